#!/usr/bin/env python3
"""run_suites.py — runs every test suite of isomesh in turn and ends with one summary line,
"N passed, N failed", counted over individual tests (not suites).

Suites, found by location so that adding a test file needs no edit here:
  <release>/tests/unit_*        Criterion binaries (core, proto, server)
  <asan>/tests/unit_*           the same built with AddressSanitizer + UndefinedBehaviorSanitizer
  tests/{cli,http,deploy,reliability}/test_*.py   Python unittest files (real programs, real sockets)
  tests/{cli,http,reliability}/test_*.py [asan+ubsan]  the same against the --asan build: any
                                report a sanitized daemon or worker writes (a leak at exit, an
                                error) fails the suite
  tests/browser/*.test.mjs      node:test files driving headless Chromium

Each suite's own output is shown as it runs. Exit status is 0 only when nothing failed.
"""
import argparse
import os
import re
import subprocess
import sys
import threading
import time
import traceback

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PY_DIRS = ["cli", "http", "deploy", "reliability"]
# Also run against the --asan build (isomeshd and isomesh with ASan+UBSan, LeakSanitizer at exit;
# the command line's runs are where the pipeline's own leaks show: workers end with _exit).
SAN_PY_DIRS = ["cli", "http", "reliability"]
TOP_COSTS = 20  # suites listed in the closing table of costs
SUITE_TIMEOUT = 900  # s: a suite that runs longer has hung
BUILD_TIMEOUT = 1800  # s: the sanitizer build, from scratch on a loaded machine
# Started first, the longest first (measured CPU and wall seconds): with several lanes, a long
# suite started last would leave the other lanes idle at the end. Suites not named follow in the
# order they are found.
HEAVY_FIRST = [
    "build [asan+ubsan]",
    "unit_core [asan+ubsan]",
    "browser/viewer.test.mjs",
    "reliability/test_sandbox.py",
    "http/test_gallery.py",
    "unit_core",
    "http/test_fairness.py [asan+ubsan]",
    "cli/test_singular.py [asan+ubsan]",
    "http/test_gallery.py [asan+ubsan]",
    "http/test_fairness.py",
    "browser/live.test.mjs",
    "deploy/test_cluster.py",
    "reliability/test_faults.py",
    "browser/explore.test.mjs",
    "reliability/test_faults.py [asan+ubsan]",
    "reliability/test_sandbox.py [asan+ubsan]",
    "browser/jobs.test.mjs",
    "browser/auth.test.mjs",
]


def count_criterion(out):
    m = re.findall(r"Synthesis: Tested: (\d+) \| Passing: (\d+) \| Failing: (\d+) \| Crashing: (\d+)", out)
    if not m:
        return None
    _, passing, failing, crashing = map(int, m[-1])
    return passing, failing + crashing


def count_unittest(out):
    ran = re.findall(r"^Ran (\d+) tests?", out, re.M)
    if not ran:
        return None
    total = int(ran[-1])
    failed = 0
    m = re.search(r"^FAILED \((.*)\)", out, re.M)
    if m:
        for part in m.group(1).split(","):
            k, _, v = part.strip().partition("=")
            if k in ("failures", "errors", "unexpected successes"):
                failed += int(v)
    skipped = 0
    m = re.search(r"skipped=(\d+)", out)
    if m:
        skipped = int(m.group(1))
    return total - failed - skipped, failed


def count_node(out):
    p = re.findall(r"^# pass (\d+)", out, re.M)
    f = re.findall(r"^# fail (\d+)", out, re.M)
    if not p:
        return None
    return int(p[-1]), int(f[-1]) if f else 0


def sanitizer_reports(report_dir):
    """Text of the reports sanitized programs wrote into report_dir (log_path), then removed."""
    out = []
    for f in sorted(os.listdir(report_dir)) if report_dir and os.path.isdir(report_dir) else []:
        path = os.path.join(report_dir, f)
        with open(path, errors="replace") as fh:
            out.append(f"--- {f}\n" + fh.read())
        os.remove(path)
    return "\n".join(out)


def run_measured(cmd, env, timeout):
    """Runs cmd (stdout and stderr together) -> (output, exit status, CPU seconds). The CPU time
    is the user+system time of cmd and of every process below it that was waited for (its
    daemons, their workers): a figure that, unlike wall time, barely moves with the load that
    other programs put on the machine."""
    try:
        proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    except OSError as e:  # no such program (a build that did not make it)
        return f"{cmd[0]}: {e}\n", 127, 0.0
    chunks = []
    reader = threading.Thread(target=lambda: chunks.extend(iter(lambda: proc.stdout.read(65536), b"")),
                              daemon=True)
    reader.start()
    reader.join(timeout)
    timed_out = reader.is_alive()
    if timed_out:
        proc.kill()
        reader.join(30)  # its own children may still hold the pipe: bounded
    _, status, ru = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    out = b"".join(chunks).decode("utf-8", "replace")
    if timed_out:
        out += f"\ntimed out after {timeout} s\n"
        return out, -1, ru.ru_utime + ru.ru_stime
    return out, proc.returncode, ru.ru_utime + ru.ru_stime


def run(name, cmd, counter, env, timeout, report_dir=None):
    """Runs one suite -> (passed, failed, wall seconds, CPU seconds, its output with a last
    line of counts)."""
    head = f"\n=== {name}: {' '.join(cmd)}\n"
    t0 = time.time()
    out, rc, cpu = run_measured(cmd, env, timeout)
    wall = time.time() - t0
    counts = counter(out)
    if counts is None:
        counts = (1, 0) if rc == 0 else (0, 1)
    passed, failed = counts
    if rc != 0 and failed == 0:
        failed = 1  # the suite failed outside any single test (crash, build, leak report)
    reports = sanitizer_reports(report_dir)
    if reports:  # a daemon or worker of the suite reported a leak or an error
        out += f"{name}: sanitizer reports:\n{reports}\n"
        failed += 1
    out += f"=== {name}: {passed} passed, {failed} failed ({wall:.1f} s, {cpu:.1f} s CPU)\n"
    return passed, failed, wall, cpu, head + out


class Suite:
    """One suite to run: name, command, output counter, environment, time bound, where its
    sanitized programs write their reports, and whether it needs the sanitizer build."""

    def __init__(self, name, cmd, counter, env, timeout=SUITE_TIMEOUT, report_dir=None,
                 needs_asan=False):
        self.name, self.cmd, self.counter, self.env = name, cmd, counter, env
        self.timeout, self.report_dir, self.needs_asan = timeout, report_dir, needs_asan


def count_build(out):
    return None  # the exit status decides


def slug(name):
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_")


def find_suites(args, env):
    """Every suite, in the order they are started: see HEAVY_FIRST."""
    suites = []
    unit_dirs = sorted(d for d in os.listdir(os.path.join(ROOT, "tests", "unit"))
                       if os.path.isdir(os.path.join(ROOT, "tests", "unit", d)))
    for build, tag in ((args.release, ""), (args.asan, " [asan+ubsan]")):
        if not build:
            continue
        for u in unit_dirs:
            b = "unit_" + u
            senv = dict(env)
            if tag:
                senv["ASAN_OPTIONS"] = "detect_leaks=1:abort_on_error=0:strict_string_checks=1"
                senv["UBSAN_OPTIONS"] = "print_stacktrace=1:halt_on_error=1"
                senv["ISOMESH_TEST_QUICK"] = "1"
            suites.append(Suite(b + tag, [os.path.join(ROOT, build, "tests", b), "--jobs=2"],
                                count_criterion, senv, needs_asan=bool(tag)))
    for sub in PY_DIRS:
        for f in python_suites(sub):
            suites.append(Suite(f"{sub}/{f}", [sys.executable, "-m", "unittest", "-v",
                                               os.path.join("tests", sub, f)], count_unittest, env))
    if args.asan:
        reports = os.path.join(ROOT, args.asan, "sanitizer-reports")
        for sub in SAN_PY_DIRS:
            for f in python_suites(sub):
                name = f"{sub}/{f} [asan+ubsan]"
                report_dir = os.path.join(reports, slug(name))  # its own: suites run at once
                os.makedirs(report_dir, exist_ok=True)
                sanitizer_reports(report_dir)  # left over from an interrupted run
                senv = dict(env)
                senv["ISOMESH_BUILD"] = os.path.join(ROOT, args.asan)
                senv["ISOMESH_TEST_QUICK"] = "1"
                senv["ASAN_OPTIONS"] = ("detect_leaks=1:abort_on_error=0:strict_string_checks=1:"
                                        "log_path=" + os.path.join(report_dir, "asan"))
                senv["UBSAN_OPTIONS"] = ("print_stacktrace=1:halt_on_error=1:"
                                         "log_path=" + os.path.join(report_dir, "ubsan"))
                suites.append(Suite(name, [sys.executable, "-m", "unittest", "-v",
                                           os.path.join("tests", sub, f)],
                                    count_unittest, senv, report_dir=report_dir, needs_asan=True))
    d = os.path.join(ROOT, "tests", "browser")
    for f in sorted(os.listdir(d)) if os.path.isdir(d) else []:
        if f.endswith(".test.mjs"):
            suites.append(Suite(f"browser/{f}", ["node", "--test", os.path.join("tests", "browser", f)],
                                count_node, env))
    if args.only:
        suites = [s for s in suites if args.only in s.name]
    if args.asan_build and any(s.needs_asan for s in suites):
        suites.insert(0, Suite("build [asan+ubsan]", ["/bin/sh", "-c", args.asan_build],
                               count_build, env, timeout=BUILD_TIMEOUT))
    rank = {name: i for i, name in enumerate(HEAVY_FIRST)}
    return sorted(suites, key=lambda s: rank.get(s.name, len(rank)))  # stable: found order


def python_suites(sub):
    d = os.path.join(ROOT, "tests", sub)
    return [f for f in sorted(os.listdir(d)) if f.startswith("test_") and f.endswith(".py")] \
        if os.path.isdir(d) else []


def waits_mostly(suite):
    """Suites that mostly wait: a headless browser on a page waiting for its daemon, its
    decoder and its renders (the viewer suite: 148 s wall for 43 s CPU in the clean run at
    59122b6). They run on one lane of their own beside the --jobs lanes, so that their waits
    do not leave a core idle."""
    return suite.name.startswith("browser/")


def group(suite):
    """Suites of one group never run at the same time. The deploy suites: each starts Redis,
    two or three daemons and nginx (on free ports: tests/deploy/stack.py), many processes for
    little CPU; one at a time keeps the machine's load bounded. (Two failures once blamed on
    running them together were races in the tests, fixed in 98ad6b7 and 3207255.) None: no
    group."""
    return "deploy" if suite.name.startswith("deploy/") else None


class Lanes:
    """Runs suites on `jobs` lanes at once, each lane taking the next suite that can start:
    one that needs the sanitizer build waits until it is built (and fails unrun if the build
    failed). With more than one lane, one more lane runs only the suites that mostly wait
    (waits_mostly); the other lanes take those too once nothing else is left. Each suite's
    output is printed whole when it ends."""

    def __init__(self, suites, jobs):
        self.pending = list(suites)
        self.jobs = max(1, jobs)
        self.cv = threading.Condition()
        self.asan_state = "building" if any(s.name.startswith("build ") for s in suites) else "built"
        self.results = []   # (suite, passed, failed, wall, cpu)
        self.busy = set()   # groups of the suites running now (see group())

    def next_suite(self, waiting_lane):
        with self.cv:
            while self.pending:
                others_left = any(not waits_mostly(s) for s in self.pending)
                for i, s in enumerate(self.pending):
                    if waiting_lane != waits_mostly(s) and (waiting_lane or others_left):
                        continue
                    if (not s.needs_asan or self.asan_state != "building") and \
                            group(s) not in self.busy:
                        if group(s):
                            self.busy.add(group(s))
                        return self.pending.pop(i)
                if waiting_lane and not any(waits_mostly(s) for s in self.pending):
                    return None
                self.cv.wait()
            return None

    def lane(self, waiting_lane=False):
        while True:
            s = self.next_suite(waiting_lane)
            if s is None:
                return
            if s.needs_asan and self.asan_state == "failed":
                out = f"\n=== {s.name}: not run, the sanitizer build failed\n"
                p, f, wall, cpu = 0, 1, 0.0, 0.0
            else:
                try:
                    p, f, wall, cpu, out = run(s.name, s.cmd, s.counter, s.env, s.timeout,
                                               s.report_dir)
                except Exception:  # a fault of this runner: the suite counts as failed
                    p, f, wall, cpu = 0, 1, 0.0, 0.0
                    out = f"\n=== {s.name}: the runner failed:\n{traceback.format_exc()}"
            with self.cv:
                self.busy.discard(group(s))
                if s.name.startswith("build "):
                    self.asan_state = "failed" if f else "built"
                self.results.append((s, p, f, wall, cpu))
                sys.stdout.write(out)
                sys.stdout.flush()
                self.cv.notify_all()

    def run(self):
        threads = [threading.Thread(target=self.lane) for _ in range(self.jobs)]
        if self.jobs > 1 and any(waits_mostly(s) for s in self.pending):
            threads.append(threading.Thread(target=self.lane, args=(True,)))
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        return self.results


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--release", default="build/release")
    ap.add_argument("--asan", default="")
    ap.add_argument("--asan-build", default="",
                    help="a shell command that builds --asan, run on a lane of its own while "
                         "release suites run; suites against --asan wait for it")
    ap.add_argument("--jobs", type=int, default=1, help="suites run at once")
    ap.add_argument("--only", default="", help="run only suites whose name contains this")
    args = ap.parse_args()

    env = dict(os.environ)
    env["ISOMESH_BUILD"] = os.path.join(ROOT, args.release)
    env.setdefault("PYTHONDONTWRITEBYTECODE", "1")

    suites = find_suites(args, env)
    t0 = time.time()
    results = Lanes(suites, args.jobs).run()
    total_p = sum(r[1] for r in results)
    total_f = sum(r[2] for r in results)
    failed_suites = [r[0].name for r in results if r[2]]
    extra = " and one lane for the suites that mostly wait" \
        if args.jobs > 1 and any(waits_mostly(r[0]) for r in results) else ""
    print(f"\nsuites by CPU time ({args.jobs} at once{extra}; s CPU, s wall):")
    for s, _, _, wall, cpu in sorted(results, key=lambda r: -r[4])[:TOP_COSTS]:
        print(f"  {cpu:7.1f} {wall:7.1f}  {s.name}")
    print(f"  {sum(r[4] for r in results):7.1f} {time.time() - t0:7.1f}  all {len(results)} suites")
    print()
    if failed_suites:
        print("failed suites: " + ", ".join(failed_suites))
    print(f"{total_p} passed, {total_f} failed")
    return 0 if total_f == 0 and suites else 1


if __name__ == "__main__":
    sys.exit(main())
