/* worker_spawn.h — starting one `isomesh --worker` process: fork + exec of the binary (argv
 * only, no shell) with PR_SET_PDEATHSIG, an RLIMIT_AS memory limit and nothing open but its
 * two pipes (requests in on stdin, answers out on stdout); and describing how one ended. */
#ifndef ISMD_WORKER_SPAWN_H
#define ISMD_WORKER_SPAWN_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

/* AddressSanitizer reserves terabytes of address space for its shadow memory, so a build
 * with it cannot run under RLIMIT_AS: such builds skip the limit (and say so at start-up). */
#if defined(__SANITIZE_ADDRESS__)
#define ISMD_SANITIZER_BUILD 1
#else
#define ISMD_SANITIZER_BUILD 0
#endif


/* A started worker: its pid and the daemon's ends of its pipes (non-blocking, close-on-exec). */
typedef struct ismd_worker_proc {
    pid_t pid;
    int to_fd;                 /* requests to the worker */
    int from_fd;               /* its answers */
} ismd_worker_proc;

/* Starts the worker binary at path with an address-space limit of job_memory bytes (0: none).
 * False (errno set, nothing left open) when it could not be started; an exec failure shows
 * as the worker's exit with status 127. */
bool ismd_worker_spawn(const char *path, size_t job_memory, ismd_worker_proc *out);

/* "killed by signal 9 (Killed)", "exited with status 1": a waitpid status in words. */
void ismd_worker_describe_exit(int status, char *buf, size_t cap);

#endif
