/* spawn_for_tests.c — posix_spawnp with a pipe for stdout, a poll loop bounded by a
 * deadline, and a kill of the child when the deadline passes. */
#include "tests/unit/proto/spawn_for_tests.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "core/util/clock.h"

extern char **environ;

int test_run(char *const argv[], int timeout_s, char **out, size_t *len)
{
    int fds[2];
    if (pipe(fds) != 0)
        return -1;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    pid_t pid;
    int rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    close(fds[1]);
    if (rc != 0) {
        close(fds[0]);
        return -1;
    }
    size_t n = 0, cap = 4096;
    char *buf = malloc(cap);
    double deadline = ism_now_s() + timeout_s;
    bool killed = false;
    for (;;) {
        double left = deadline - ism_now_s();
        if (left <= 0) {
            kill(pid, SIGKILL);
            killed = true;
            break;
        }
        struct pollfd p = {fds[0], POLLIN, 0};
        int r = poll(&p, 1, (int)(left * 1000) + 1);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            continue;
        if (n + 1024 > cap)
            buf = realloc(buf, cap *= 2);
        ssize_t k = read(fds[0], buf + n, cap - n - 1);
        if (k <= 0)
            break;
        n += (size_t)k;
    }
    close(fds[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    buf[n] = '\0';
    if (out) {
        *out = buf;
        if (len)
            *len = n;
    } else {
        free(buf);
    }
    if (killed || !WIFEXITED(status))
        return -1;
    return WEXITSTATUS(status);
}

char *test_write_temp(const void *data, size_t len, const char *suffix)
{
    char *path = malloc(256);
    snprintf(path, 256, "/tmp/isomesh-test-XXXXXX%s", suffix);
    int fd = mkstemps(path, (int)strlen(suffix));
    if (fd < 0) {
        free(path);
        return NULL;
    }
    const char *p = data;
    while (len) {
        ssize_t k = write(fd, p, len);
        if (k <= 0)
            break;
        p += k;
        len -= (size_t)k;
    }
    close(fd);
    return path;
}
