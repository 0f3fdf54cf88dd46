/* fd_io.h — whole writes to a file descriptor: a loop over write(2) that survives short
 * writes and EINTR, shared by every program that writes files or pipes. */
#ifndef ISM_FD_IO_H
#define ISM_FD_IO_H

#include <stdbool.h>
#include <stddef.h>

/* Writes all n bytes of p to fd; false (errno set) when a write fails or writes nothing. */
bool ism_write_all(int fd, const void *p, size_t n);

#endif
