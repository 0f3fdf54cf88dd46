/* file_memo.h — a bounded memo of files whose contents were checked, by name: the identity each
 * had when it was (device, inode, size, change time). A file whose identity is the same now
 * was not written since through the file system (a write, a truncation, a rename over it or
 * a change of its times all move its change time), so its check still stands; a different
 * identity means check again. What the disk's own decay would change without a write is not
 * seen here: the memo only saves re-reading a file nobody touched. */
#ifndef ISM_FILE_MEMO_H
#define ISM_FILE_MEMO_H

#include <stdbool.h>
#include <sys/stat.h>

typedef struct ism_file_memo ism_file_memo;

/* An empty memo (NULL when out of memory). Safe to use from several threads. */
ism_file_memo *ism_file_memo_new(void);
void ism_file_memo_free(ism_file_memo *m);

/* Whether name was checked while it had the identity st has now. */
bool ism_file_memo_holds(ism_file_memo *m, const char *name, const struct stat *st);

/* Whether a check of the file with identity st, made now, could be recorded: it last changed
 * long enough ago that no later change can share its change time (file times come from a
 * coarse clock, and some file systems keep whole seconds). */
bool ism_file_memo_settled(const struct stat *st);

/* Records that name, with identity st, was checked just now — only when st is settled (above):
 * a second change in the same tick would leave the identity as it was. Evicts another name's
 * record when its slot is taken (the memo is bounded). */
void ism_file_memo_put(ism_file_memo *m, const char *name, const struct stat *st);

#endif
