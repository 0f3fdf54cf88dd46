/* sandbox_selftest.c — `isomesh --worker --sandbox-selftest WHAT` (sandbox.h): enters the same
 * sandbox a worker enters, through the same function, then tries one thing and says what
 * happened. Tests use it to prove what a worker can and cannot do; it changes nothing in the
 * sandbox itself. */
#include "server/isomesh/sandbox.h"

#include <errno.h>
#include <stdbool.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static int report(const char *what, long rc, int err)
{
    if (rc < 0) {
        printf("selftest %s: refused: %s\n", what, strerror(err));
        fflush(stdout);
        return 0;
    }
    printf("selftest %s: SUCCEEDED (returned %ld): the sandbox let it through\n", what, rc);
    fflush(stdout);
    return 1;
}

static void *thread_main(void *arg)
{
    size_t n = 64u << 20;
    unsigned char *p = malloc(n); /* large: mmap */
    if (!p)
        return NULL;
    memset(p, 1, n);
    unsigned char *q = realloc(p, 2 * n); /* mremap */
    if (!q) {
        free(p);
        return NULL;
    }
    *(int *)arg = q[n - 1];
    free(q);
    return arg;
}

/* What the pipeline needs: threads, large allocations, the clock, stdout. */
static int try_allowed(void)
{
    pthread_t t[2];
    int v[2] = {0, 0};
    for (int i = 0; i < 2; i++)
        if (pthread_create(&t[i], NULL, thread_main, &v[i]) != 0) {
            printf("selftest allowed: pthread_create failed\n");
            return 1;
        }
    for (int i = 0; i < 2; i++)
        pthread_join(t[i], NULL);
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    if (v[0] != 1 || v[1] != 1) {
        printf("selftest allowed: the threads' allocations failed\n");
        return 1;
    }
    printf("selftest allowed: threads, 128 MiB allocations, clock and stdout work\n");
    fflush(stdout);
    return 0;
}

static const char *const CHECKS[] = {"open", "create", "socket", "exec", "fork",
                                     "exec-memory", "write-fd", "allowed"};

int ism_sandbox_selftest(const char *what)
{
    bool known = false;
    for (size_t i = 0; i < sizeof CHECKS / sizeof CHECKS[0]; i++)
        known = known || !strcmp(what, CHECKS[i]);
    if (!known) {
        fprintf(stderr, "isomesh: --sandbox-selftest: unknown check '%s'\n", what);
        return 2;
    }
    char err[256];
    setvbuf(stdout, NULL, _IONBF, 0);
    /* write-fd: a descriptor the daemon did not hand over, made before the sandbox */
    int spare[2] = {-1, -1};
    if (!strcmp(what, "write-fd") && pipe(spare) != 0) {
        perror("isomesh: pipe");
        return 2;
    }
    if (!ism_sandbox_enter(STDIN_FILENO, STDOUT_FILENO, err, sizeof err)) {
        fprintf(stderr, "isomesh worker: sandbox: %s\n", err);
        return 2;
    }
    printf("selftest %s: sandbox entered\n", what);
    long rc = -1;
    if (!strcmp(what, "allowed"))
        _exit(try_allowed()); /* exit handlers may need more than the sandbox allows */
    if (!strcmp(what, "open")) {
        rc = open("/proc/self/status", O_RDONLY | O_CLOEXEC);
    } else if (!strcmp(what, "create")) {
        char path[64];
        snprintf(path, sizeof path, "/tmp/isomesh-sandbox-selftest.%ld", (long)getpid());
        rc = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (rc >= 0)
            unlink(path);
    } else if (!strcmp(what, "socket")) {
        rc = socket(AF_INET, SOCK_STREAM, 0);
    } else if (!strcmp(what, "exec")) {
        char *const argv[] = {"true", NULL};
        rc = execv("/bin/true", argv);
    } else if (!strcmp(what, "fork")) {
        rc = fork();
        if (rc == 0)
            _exit(0);
    } else if (!strcmp(what, "exec-memory")) {
        void *p = mmap(NULL, 4096, PROT_READ | PROT_WRITE | PROT_EXEC,
                       MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        rc = p == MAP_FAILED ? -1 : 0;
    } else if (!strcmp(what, "write-fd")) {
        rc = write(spare[1], "x", 1);
    }
    _exit(report(what, rc, errno)); /* exit handlers may need more than the sandbox allows */
}
