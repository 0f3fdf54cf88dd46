/* sandbox.c — the worker's seccomp allow-list (sandbox.h): what the pipeline needs was found by
 * tracing workers (strace -f) through every preset in every format, in release and
 * AddressSanitizer builds; tests/reliability/test_sandbox.py runs the same under the filter. */
#include "server/isomesh/sandbox.h"

#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <sched.h>
#include <seccomp.h>
#include <signal.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

/* Names of system calls for the SIGSYS message, resolved before the filter is installed (the
 * handler may not allocate). */
#define NAMED_SYSCALLS 512
static char syscall_names[NAMED_SYSCALLS][24];
static pid_t sandbox_pid;
static volatile sig_atomic_t sandbox_on;

bool ism_sandbox_active(void)
{
    return sandbox_on != 0;
}

/* ---- the SIGSYS report --------------------------------------------------------------- */

static size_t put_str(char *buf, size_t at, size_t cap, const char *s)
{
    while (*s && at + 1 < cap)
        buf[at++] = *s++;
    return at;
}

static size_t put_uint(char *buf, size_t at, size_t cap, unsigned long v)
{
    char digits[24];
    size_t n = 0;
    do {
        digits[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v && n < sizeof digits);
    while (n && at + 1 < cap)
        buf[at++] = digits[--n];
    return at;
}

/* Async-signal-safe: one line on stderr, then death by SIGSYS (the disposition was reset to
 * the default on entry, SA_RESETHAND, and SIGSYS is not blocked here, SA_NODEFER). */
static void on_sigsys(int sig, siginfo_t *si, void *uctx)
{
    (void)uctx;
    char msg[160];
    size_t n = put_str(msg, 0, sizeof msg, "isomesh worker: the sandbox refused system call ");
    int nr = si->si_syscall;
    n = put_uint(msg, n, sizeof msg, (unsigned long)(nr < 0 ? 0 : nr));
    if (nr >= 0 && nr < NAMED_SYSCALLS && syscall_names[nr][0]) {
        n = put_str(msg, n, sizeof msg, " (");
        n = put_str(msg, n, sizeof msg, syscall_names[nr]);
        n = put_str(msg, n, sizeof msg, ")");
    }
    n = put_str(msg, n, sizeof msg, "; stopping\n");
    ssize_t w = write(STDERR_FILENO, msg, n);
    (void)w;
    syscall(SYS_tgkill, sandbox_pid, (pid_t)syscall(SYS_gettid), sig);
    _exit(128 + sig); /* not reached */
}

static bool install_sigsys_handler(void)
{
    for (int nr = 0; nr < NAMED_SYSCALLS; nr++) {
        char *name = seccomp_syscall_resolve_num_arch(SCMP_ARCH_NATIVE, nr);
        if (name) {
            snprintf(syscall_names[nr], sizeof syscall_names[nr], "%s", name);
            free(name);
        }
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_sigsys;
    sa.sa_flags = SA_SIGINFO | SA_RESETHAND | SA_NODEFER;
    sigemptyset(&sa.sa_mask);
    return sigaction(SIGSYS, &sa, NULL) == 0;
}

/* ---- the filter ---------------------------------------------------------------------- */

/* Calls allowed whatever their arguments. */
static const char *const ALLOWED[] = {
    /* memory (mmap and mprotect: below, never executable) */
    "brk", "munmap", "mremap", "madvise",
    /* threads of the polygoniser (clone: below, threads only) */
    "futex", "set_robust_list", "rseq", "sched_yield", "sched_getaffinity", "exit",
    "exit_group", "gettid", "getpid", "sigaltstack",
    /* signals: masks around thread creation, returning from a handler, abort() */
    "rt_sigprocmask", "rt_sigreturn", "rt_sigaction",
    /* time */
    "clock_gettime", "clock_getres", "gettimeofday", "time", "nanosleep", "clock_nanosleep",
    /* glibc's qsort asks the size of memory (sysconf(_SC_PHYS_PAGES)) once */
    "sysinfo",
    /* closing a descriptor grants nothing */
    "close",
};

typedef struct rule_ctx {
    scmp_filter_ctx ctx;
    const char *failed;
    int err;
} rule_ctx;

static void add(rule_ctx *r, uint32_t action, const char *name, unsigned n,
                const struct scmp_arg_cmp *cmp)
{
    if (r->failed)
        return;
    int nr = seccomp_syscall_resolve_name(name);
    if (nr == __NR_SCMP_ERROR)
        return; /* not a system call on this architecture */
    int rc = seccomp_rule_add_array(r->ctx, action, nr, n, cmp);
    if (rc < 0) {
        r->failed = name;
        r->err = -rc;
    }
}

static void allow_fds(rule_ctx *r, const char *name, const int *fds, size_t nfds)
{
    for (size_t i = 0; i < nfds; i++) {
        bool seen = false;
        for (size_t j = 0; j < i; j++)
            seen = seen || fds[j] == fds[i];
        if (seen)
            continue;
        struct scmp_arg_cmp eq = SCMP_A0(SCMP_CMP_EQ, (scmp_datum_t)fds[i]);
        add(r, SCMP_ACT_ALLOW, name, 1, &eq);
    }
}

static void build_rules(rule_ctx *r, int in_fd, int out_fd)
{
    for (size_t i = 0; i < sizeof ALLOWED / sizeof ALLOWED[0]; i++)
        add(r, SCMP_ACT_ALLOW, ALLOWED[i], 0, NULL);

    int in[] = {in_fd};
    allow_fds(r, "read", in, 1);
    int out[] = {out_fd, STDOUT_FILENO, STDERR_FILENO};
    allow_fds(r, "write", out, 3);
    allow_fds(r, "writev", out, 3);

    struct scmp_arg_cmp no_exec = SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC, 0);
    add(r, SCMP_ACT_ALLOW, "mmap", 1, &no_exec);
    add(r, SCMP_ACT_ALLOW, "mprotect", 1, &no_exec);

    struct scmp_arg_cmp thread = SCMP_A0(SCMP_CMP_MASKED_EQ, CLONE_THREAD, CLONE_THREAD);
    add(r, SCMP_ACT_ALLOW, "clone", 1, &thread);
    /* clone3 passes its flags in memory the filter cannot read: glibc retries with clone */
    add(r, SCMP_ACT_ERRNO(ENOSYS), "clone3", 0, NULL);

    /* signals to this process only (raise, abort, the SIGSYS handler) */
    struct scmp_arg_cmp self = SCMP_A0(SCMP_CMP_EQ, (scmp_datum_t)sandbox_pid);
    add(r, SCMP_ACT_ALLOW, "tgkill", 1, &self);

    /* Opening a file fails with EACCES rather than killing: glibc itself probes files now and
     * then and copes without them (malloc reads /proc/sys/vm/overcommit_memory the first time
     * it shrinks a thread's heap; counting cores reads /sys). Nothing is opened either way. */
    add(r, SCMP_ACT_ERRNO(EACCES), "open", 0, NULL);
    add(r, SCMP_ACT_ERRNO(EACCES), "openat", 0, NULL);
    add(r, SCMP_ACT_ERRNO(EACCES), "creat", 0, NULL);
    add(r, SCMP_ACT_ERRNO(ENOSYS), "openat2", 0, NULL);

#if defined(__SANITIZE_ADDRESS__)
    /* AddressSanitizer probes whether memory is readable by writing it into a pipe; refused
     * with an error it takes the memory as unreadable. Creating a pipe grants no access. */
    add(r, SCMP_ACT_ERRNO(EPERM), "pipe2", 0, NULL);
    add(r, SCMP_ACT_ERRNO(EPERM), "pipe", 0, NULL);
#endif
}

/* Start-up work that needs files or randomness, done while both are still allowed. */
static bool prepare(char *err, size_t cap)
{
    if (sodium_init() < 0) {
        snprintf(err, cap, "libsodium did not initialise");
        return false;
    }
    json_object_seed(0);
    struct rlimit no_core = {0, 0};
    setrlimit(RLIMIT_CORE, &no_core);
    sandbox_pid = getpid();
    if (!install_sigsys_handler()) {
        snprintf(err, cap, "installing the SIGSYS handler: %s", strerror(errno));
        return false;
    }
    return true;
}

bool ism_sandbox_enter(int in_fd, int out_fd, char *err, size_t cap)
{
    if (!prepare(err, cap))
        return false;
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) {
        snprintf(err, cap, "PR_SET_NO_NEW_PRIVS: %s", strerror(errno));
        return false;
    }
    rule_ctx r = {.ctx = seccomp_init(SCMP_ACT_TRAP)};
    if (!r.ctx) {
        snprintf(err, cap, "seccomp_init failed");
        return false;
    }
    build_rules(&r, in_fd, out_fd);
    int rc = 0;
    if (!r.failed && (rc = seccomp_attr_set(r.ctx, SCMP_FLTATR_CTL_TSYNC, 1)) == 0)
        rc = seccomp_load(r.ctx);
    seccomp_release(r.ctx);
    if (r.failed) {
        snprintf(err, cap, "seccomp rule for %s: %s", r.failed, strerror(r.err));
        return false;
    }
    if (rc < 0) {
        snprintf(err, cap, "loading the seccomp filter: %s", strerror(-rc));
        return false;
    }
    sandbox_on = 1;
    return true;
}
