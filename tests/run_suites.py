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
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PY_DIRS = ["cli", "http", "deploy", "reliability"]
# Also run against the --asan build (isomeshd and isomesh with ASan+UBSan, LeakSanitizer at exit;
# the command line's runs are where the pipeline's own leaks show: workers end with _exit).
SAN_PY_DIRS = ["cli", "http", "reliability"]


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


def run(name, cmd, counter, env, timeout, report_dir=None):
    print(f"\n=== {name}: {' '.join(cmd)}", flush=True)
    t0 = time.time()
    try:
        proc = subprocess.run(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, errors="replace",
                              timeout=timeout)
        out, rc = proc.stdout, proc.returncode
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode("utf-8", "replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        out += f"\n{name}: timed out after {timeout} s\n"
        rc = -1
    sys.stdout.write(out)
    counts = counter(out)
    if counts is None:
        counts = (1, 0) if rc == 0 else (0, 1)
    passed, failed = counts
    if rc != 0 and failed == 0:
        failed = 1  # the suite failed outside any single test (crash, build, leak report)
    reports = sanitizer_reports(report_dir)
    if reports:  # a daemon or worker of the suite reported a leak or an error
        print(f"{name}: sanitizer reports:\n{reports}")
        failed += 1
    print(f"=== {name}: {passed} passed, {failed} failed ({time.time() - t0:.1f} s)", flush=True)
    return passed, failed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--release", default="build/release")
    ap.add_argument("--asan", default="")
    ap.add_argument("--only", default="", help="run only suites whose name contains this")
    args = ap.parse_args()

    env = dict(os.environ)
    env["ISOMESH_BUILD"] = os.path.join(ROOT, args.release)
    env.setdefault("PYTHONDONTWRITEBYTECODE", "1")

    suites = []
    for build, tag in ((args.release, ""), (args.asan, " [asan+ubsan]")):
        if not build:
            continue
        d = os.path.join(ROOT, build, "tests")
        for b in sorted(os.listdir(d)) if os.path.isdir(d) else []:
            if b.startswith("unit_"):
                senv = dict(env)
                if tag:
                    senv["ASAN_OPTIONS"] = "detect_leaks=1:abort_on_error=0:strict_string_checks=1"
                    senv["UBSAN_OPTIONS"] = "print_stacktrace=1:halt_on_error=1"
                    senv["ISOMESH_TEST_QUICK"] = "1"
                suites.append((b + tag, [os.path.join(d, b), "--jobs=2"], count_criterion, senv, 900))
    for sub in PY_DIRS:
        d = os.path.join(ROOT, "tests", sub)
        for f in sorted(os.listdir(d)) if os.path.isdir(d) else []:
            if f.startswith("test_") and f.endswith(".py"):
                suites.append((f"{sub}/{f}", [sys.executable, "-m", "unittest", "-v",
                                              os.path.join("tests", sub, f)],
                               count_unittest, env, 900))
    if args.asan:
        report_dir = os.path.join(ROOT, args.asan, "sanitizer-reports")
        os.makedirs(report_dir, exist_ok=True)
        sanitizer_reports(report_dir)  # left over from an interrupted run
        senv = dict(env)
        senv["ISOMESH_BUILD"] = os.path.join(ROOT, args.asan)
        senv["ISOMESH_TEST_QUICK"] = "1"
        senv["ASAN_OPTIONS"] = ("detect_leaks=1:abort_on_error=0:strict_string_checks=1:"
                                "log_path=" + os.path.join(report_dir, "asan"))
        senv["UBSAN_OPTIONS"] = ("print_stacktrace=1:halt_on_error=1:"
                                 "log_path=" + os.path.join(report_dir, "ubsan"))
        for sub in SAN_PY_DIRS:
            d = os.path.join(ROOT, "tests", sub)
            for f in sorted(os.listdir(d)) if os.path.isdir(d) else []:
                if f.startswith("test_") and f.endswith(".py"):
                    suites.append((f"{sub}/{f} [asan+ubsan]",
                                   [sys.executable, "-m", "unittest", "-v",
                                    os.path.join("tests", sub, f)],
                                   count_unittest, senv, 900, report_dir))
    d = os.path.join(ROOT, "tests", "browser")
    for f in sorted(os.listdir(d)) if os.path.isdir(d) else []:
        if f.endswith(".test.mjs"):
            suites.append((f"browser/{f}", ["node", "--test", os.path.join("tests", "browser", f)],
                           count_node, env, 900))

    if args.only:
        suites = [s for s in suites if args.only in s[0]]
    total_p = total_f = 0
    failed_suites = []
    for name, cmd, counter, senv, timeout, *report_dir in suites:
        p, f = run(name, cmd, counter, senv, timeout, *report_dir)
        total_p += p
        total_f += f
        if f:
            failed_suites.append(name)
    print()
    if failed_suites:
        print("failed suites: " + ", ".join(failed_suites))
    print(f"{total_p} passed, {total_f} failed")
    return 0 if total_f == 0 and suites else 1


if __name__ == "__main__":
    sys.exit(main())
