/* fd_io.c — whole writes to a file descriptor (see fd_io.h). */
#include "server/common/fd_io.h"

#include <errno.h>
#include <unistd.h>

bool ism_write_all(int fd, const void *p, size_t n)
{
    const unsigned char *b = p;
    while (n) {
        ssize_t w = write(fd, b, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return false;
        b += w;
        n -= (size_t)w;
    }
    return true;
}
