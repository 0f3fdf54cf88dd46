/* fd_keep.h — a bounded table of open files kept by name, so that a file sent often is opened
 * once, not once per send. A lookup lends the kept descriptor itself (no syscall), to be
 * given back (a sender that closes what it is given, libmicrohttpd, gets a duplicate made by
 * the borrower: server/common/cache_disk.c). The table's own copy stays open until the name's
 * slot is taken by another name, the name is dropped, or the table is freed, and, while lent,
 * until the last borrower gives it back. */
#ifndef ISM_FD_KEEP_H
#define ISM_FD_KEEP_H

#include <stdbool.h>

typedef struct ism_fd_keep ism_fd_keep;

/* An empty table (NULL when out of memory). Safe to use from several threads. */
ism_fd_keep *ism_fd_keep_new(void);
/* Closes every kept descriptor and frees the table (NULL: nothing). */
void ism_fd_keep_free(ism_fd_keep *k);

/* The kept descriptor of name, lent: *lease gets what ism_fd_keep_give_back takes; the
 * descriptor stays open (and its number unused by anything else) until then, whatever
 * happens to its slot meanwhile. -1 (and *lease NULL) when none is kept. The borrower must
 * not close it, nor change its file offset or flags (pread / sendfile with an offset only). */
typedef struct ism_fd_lease ism_fd_lease;
int ism_fd_keep_borrow(ism_fd_keep *k, const char *name, ism_fd_lease **lease);
/* Gives a lent descriptor back (NULL: nothing); the last reference closes it. */
void ism_fd_keep_give_back(ism_fd_lease *lease);
/* Keeps a duplicate of fd under name (fd stays the caller's); the name's slot may have held
 * another file, which is closed. No effect when the duplicate cannot be made. */
void ism_fd_keep_put(ism_fd_keep *k, const char *name, int fd);
/* Closes the file kept under name, if any. */
void ism_fd_keep_drop(ism_fd_keep *k, const char *name);

#endif
