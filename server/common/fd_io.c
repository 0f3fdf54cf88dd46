/* fd_io.c — whole writes to a file descriptor, whole reads of small files and safe
 * replacement of whole files (fd_io.h). */
#include "server/common/fd_io.h"

#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
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

/* Reads exactly n bytes from fd into buf; the reason when it cannot, else NULL. */
static const char *read_exactly(int fd, char *buf, size_t n)
{
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, buf + got, n - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0)
            return strerror(errno);
        if (r == 0)
            return "the file shrank while being read";
        got += (size_t)r;
    }
    return NULL;
}

int ism_read_file(const char *path, size_t max, char **data, size_t *len, unsigned *mode,
                  char *err, size_t cap)
{
    *data = NULL;
    *len = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
        if (errno == ENOENT)
            return 0;
        snprintf(err, cap, "%s: %s", path, strerror(errno));
        return -1;
    }
    struct stat st;
    const char *why = NULL;
    char toobig[64];
    if (fstat(fd, &st) != 0)
        why = strerror(errno);
    else if (!S_ISREG(st.st_mode))
        why = "not a regular file (a FIFO, device or directory is refused)";
    else if ((unsigned long long)st.st_size > max) {
        snprintf(toobig, sizeof toobig, "larger than %zu bytes", max);
        why = toobig;
    }
    char *buf = why ? NULL : malloc((size_t)st.st_size + 1);
    if (!why && !buf)
        why = "out of memory";
    if (!why)
        why = read_exactly(fd, buf, (size_t)st.st_size);
    close(fd);
    if (why) {
        free(buf);
        snprintf(err, cap, "%s: %s", path, why);
        return -1;
    }
    buf[st.st_size] = 0;
    *data = buf;
    *len = (size_t)st.st_size;
    if (mode)
        *mode = (unsigned)(st.st_mode & 07777);
    return 1;
}

/* fsync of the directory holding path, so that a rename into it survives a crash (best
 * effort: some file systems refuse to sync a directory, and the file is replaced anyway). */
static void fsync_dir_of(const char *path)
{
    char *copy = strdup(path);
    if (!copy)
        return;
    int dfd = open(dirname(copy), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    free(copy);
    if (dfd >= 0) {
        (void)fsync(dfd);
        close(dfd);
    }
}

bool ism_replace_file_via(int fd, const char *tmp, const char *path, const void *data, size_t len,
                          unsigned mode, char *err, size_t cap)
{
    const char *what = NULL;
    if (!ism_write_all(fd, data, len) || fsync(fd) != 0)
        what = "writing";
    else if (fchmod(fd, (mode_t)mode) != 0)
        what = "setting the permissions of";
    int e = errno;
    if (close(fd) != 0 && !what)
        what = "writing", e = errno;
    if (!what && rename(tmp, path) != 0)
        what = "renaming over", e = errno;
    if (what) {
        snprintf(err, cap, "%s: %s %s: %s", path, what, tmp, strerror(e));
        unlink(tmp);
        return false;
    }
    fsync_dir_of(path);
    return true;
}

bool ism_replace_file(const char *path, const void *data, size_t len, unsigned mode, char *err,
                      size_t cap)
{
    size_t n = strlen(path) + 8;
    char *tmp = malloc(n);
    if (!tmp) {
        snprintf(err, cap, "%s: out of memory", path);
        return false;
    }
    snprintf(tmp, n, "%s.XXXXXX", path);
    int fd = mkstemp(tmp);
    bool ok = false;
    if (fd < 0)
        snprintf(err, cap, "%s: cannot create %s: %s", path, tmp, strerror(errno));
    else
        ok = ism_replace_file_via(fd, tmp, path, data, len, mode, err, cap);
    free(tmp);
    return ok;
}
