/* fd_io.h — whole writes to a file descriptor (a loop over write(2) that survives short
 * writes and EINTR) and whole reads of a small file, shared by every program that writes
 * files or pipes or reads its configuration. */
#ifndef ISM_FD_IO_H
#define ISM_FD_IO_H

#include <stdbool.h>
#include <stddef.h>

/* Writes all n bytes of p to fd; false (errno set) when a write fails or writes nothing. */
bool ism_write_all(int fd, const void *p, size_t n);

/* Reads the whole regular file at path, at most max bytes, into a malloc'd buffer with a NUL
 * after the last byte (*data, *len; *mode gets the permission bits when mode is not NULL).
 * The file is opened without blocking and without becoming a controlling terminal, and
 * checked on the open descriptor (a FIFO, a device or a directory is refused). Returns 1 when
 * read, 0 when there is no such file, -1 otherwise with the reason in err (path first). */
int ism_read_file(const char *path, size_t max, char **data, size_t *len, unsigned *mode,
                  char *err, size_t cap);

#endif
