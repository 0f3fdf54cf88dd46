#!/usr/bin/env python3
"""fuzz_summary.py RUNDIR TARGET... — the table `make fuzz` ends with: per target the
executions, executions per second, coverage (libFuzzer's final cov: and ft:), new corpus
units, and crashes (crash-, leak-, timeout- and oom- files in RUNDIR/TARGET/artifacts/).
Exits 1 when a target crashed or left no statistics (it did not run)."""
import os
import re
import sys

STATUS = re.compile(rb"^#(\d+)\s+\w+\s+cov: (\d+) ft: (\d+)", re.M)
STAT = re.compile(rb"^stat::(\w+):\s+(\d+)", re.M)
KINDS = ("crash-", "leak-", "timeout-", "oom-")


def summarise(run_dir, target):
    d = os.path.join(run_dir, target)
    try:
        with open(os.path.join(d, "log"), "rb") as f:
            log = f.read()
    except OSError:
        return None
    stats = {k.decode(): int(v) for k, v in STAT.findall(log)}
    lines = STATUS.findall(log)
    execs = stats.get("number_of_executed_units", int(lines[-1][0]) if lines else 0)
    cov, ft = (int(lines[-1][1]), int(lines[-1][2])) if lines else (0, 0)
    art = os.path.join(d, "artifacts")
    found = sorted(f for f in os.listdir(art) if f.startswith(KINDS)) if os.path.isdir(art) else []
    return {"target": target, "execs": execs, "rate": stats.get("average_exec_per_sec", 0),
            "cov": cov, "ft": ft, "new": stats.get("new_units_added", 0),
            "crashes": len(found), "files": [os.path.join(art, f) for f in found],
            "ran": bool(stats or lines)}


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    run_dir, targets = argv[1], argv[2:]
    rows = [summarise(run_dir, t) or {"target": t, "ran": False} for t in targets]
    head = f"{'target':<12} {'executions':>11} {'exec/s':>8} {'cov':>6} {'ft':>7} {'new':>6} {'crashes':>8}"
    print(head)
    print("-" * len(head))
    bad = False
    for r in rows:
        if not r["ran"]:
            print(f"{r['target']:<12} {'did not run (see its log)':>51}")
            bad = True
            continue
        print(f"{r['target']:<12} {r['execs']:>11} {r['rate']:>8} {r['cov']:>6} {r['ft']:>7} "
              f"{r['new']:>6} {r['crashes']:>8}")
        bad = bad or r["crashes"] > 0
    for r in rows:
        for f in r.get("files", []):
            print(f"  {r['target']}: {f} (reproduce: build/fuzz/fuzz_{r['target']} {f})")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
