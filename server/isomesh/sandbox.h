/* sandbox.h — the seccomp sandbox an `isomesh --worker` enters once it is started and before
 * it takes its first request: from then on the process can read its request pipe, write its
 * result pipe and stderr, allocate memory, run threads and keep time — and nothing else. No
 * file can be opened, no socket made, no program executed, no process forked, no memory made
 * executable.
 *
 * A refused system call kills the worker with SIGSYS after one line on stderr naming the call
 * ("isomesh worker: the sandbox refused system call 41 (socket)"), so the daemon logs "killed by
 * signal 31 (Bad system call)" and answers the job 500; a library quietly failing on EPERM would
 * surface as a misleading error much later (an mmap refusal reads as "out of memory"). Two
 * exceptions answer an error instead: opening a file fails with EACCES, because glibc probes
 * /proc and /sys on its own now and then and copes without them (nothing is opened either way),
 * and clone3 answers ENOSYS, so glibc falls back to clone, whose flags the filter can check
 * (threads only). PR_SET_NO_NEW_PRIVS is set first; the core size limit is 0 (a worker's memory
 * holds other users' requests). */
#ifndef ISM_SANDBOX_H
#define ISM_SANDBOX_H

#include <stdbool.h>
#include <stddef.h>

/* Does the start-up work that needs files (libsodium and jansson read /dev/urandom once), then
 * installs the filter for a worker reading in_fd and writing out_fd (plus stdout and stderr).
 * The process must still be single-threaded. False with a reason in err when the kernel or
 * libseccomp refuses: the worker must then not run (fail closed). */
bool ism_sandbox_enter(int in_fd, int out_fd, char *err, size_t cap);

/* True once ism_sandbox_enter succeeded in this process. */
bool ism_sandbox_active(void);

/* `isomesh --worker --sandbox-selftest WHAT`: enters the very same sandbox as a worker, then
 * tries WHAT and reports on stdout: open (read an existing file), create (a new file in /tmp),
 * socket, exec, fork, exec-memory (map memory executable), write-fd (write to a descriptor
 * other than the worker's own), or allowed (threads, a large allocation, the clock, a write to
 * stdout: what the pipeline needs). Prints "refused: <errno text>" and exits 0 when WHAT
 * failed (open, create: EACCES), exits 0 after "allowed" works, exits 1 when a forbidden WHAT
 * succeeded; the other forbidden checks never return (SIGSYS). */
int ism_sandbox_selftest(const char *what);

#endif
