/* worker_spawn.c — worker processes of worker_spawn.h: pipes, fork, the child's set-up
 * between fork and exec (signal mask, parent-death signal, memory limit, descriptors), and
 * exit statuses in words. */
#include "server/isomeshd/worker_spawn.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#define RESULT_PIPE_SIZE (1 << 20) /* a worker's answer pipe: fewer wake-ups for big results */

/* In the child between fork and exec: async-signal-safe calls only. */
static void child_exec(const char *path, size_t job_memory, pid_t parent, int in_fd,
                       int out_fd)
{
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, NULL);
    struct sigaction dfl = {.sa_handler = SIG_DFL};
    sigaction(SIGPIPE, &dfl, NULL);
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent)
        _exit(126);
    if (job_memory && !ISMD_SANITIZER_BUILD) {
        struct rlimit rl = {job_memory, job_memory};
        if (setrlimit(RLIMIT_AS, &rl) != 0)
            _exit(126);
    }
    if (dup2(in_fd, STDIN_FILENO) < 0 || dup2(out_fd, STDOUT_FILENO) < 0)
        _exit(126);
    syscall(SYS_close_range, 3u, ~0u, 0); /* everything else is O_CLOEXEC anyway */
    char *const argv[] = {"isomesh", "--worker", NULL};
    execv(path, argv);
    _exit(127);
}

static void set_nonblock(int fd)
{
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0)
        fcntl(fd, F_SETFL, fl | O_NONBLOCK);
}

void ismd_worker_describe_exit(int status, char *buf, size_t cap)
{
    if (WIFSIGNALED(status))
        snprintf(buf, cap, "killed by signal %d (%s)", WTERMSIG(status), strsignal(WTERMSIG(status)));
    else if (WIFEXITED(status))
        snprintf(buf, cap, "exited with status %d", WEXITSTATUS(status));
    else
        snprintf(buf, cap, "ended");
}


bool ismd_worker_spawn(const char *path, size_t job_memory, ismd_worker_proc *out)
{
    int req[2], res[2];
    if (pipe2(req, O_CLOEXEC) != 0)
        return false;
    if (pipe2(res, O_CLOEXEC) != 0) {
        close(req[0]);
        close(req[1]);
        return false;
    }
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid == 0)
        child_exec(path, job_memory, parent, req[0], res[1]);
    close(req[0]);
    close(res[1]);
    if (pid < 0) {
        close(req[1]);
        close(res[0]);
        return false;
    }
    fcntl(res[0], F_SETPIPE_SZ, RESULT_PIPE_SIZE);
    set_nonblock(req[1]);
    set_nonblock(res[0]);
    out->pid = pid;
    out->to_fd = req[1];
    out->from_fd = res[0];
    return true;
}
