/* fd_io.h — whole writes to a file descriptor (a loop over write(2) that survives short
 * writes and EINTR), whole reads of a small file and safe replacement of a whole file, shared
 * by every program that writes files or pipes or reads its configuration. */
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

/* Replaces the file at path by data (len bytes) so that a reader sees the old file or the
 * new one, never part of one: the bytes go to tmp, already created and open as fd (in path's
 * directory), which is fsync'd, given the permission bits mode, closed and renamed over path;
 * then the directory is fsync'd (best effort). fd is closed, and tmp removed on failure.
 * Returns false with the reason in err (the file named first). */
bool ism_replace_file_via(int fd, const char *tmp, const char *path, const void *data, size_t len,
                          unsigned mode, char *err, size_t cap);

/* ism_replace_file_via through a new temporary file path.XXXXXX (mkstemp). */
bool ism_replace_file(const char *path, const void *data, size_t len, unsigned mode, char *err,
                      size_t cap);

#endif
