#!/usr/bin/env python3
"""bench_threads.py — the polygoniser on one and two threads (issue 16: two threads at least
1.8x one on the gyroid at depth 9 and on a Barth-like nodal sextic). For each surface,
build/bench/bench_threads runs ism_polygonise on 1 and 2 threads, alternating, REPEATS times;
the minimum of each figure is kept (the machine is shared). Printed per surface:

  wall and CPU (process) of each thread count, and the wall speed-up — meaningful only on an
  idle machine, so the RESULT line says NOT idle when the load average was above the cores;
  per phase (octree, breaks, polygons, weld) the CPU, the part of it the calling thread ran
  alone (serial), the critical path as the threads ran (serial + each parallel loop's
  busiest thread) and as a fair split of the same tasks would run (serial + per loop
  max(CPU / 2, longest task): on a loaded machine a thread that starts late leaves its
  tasks to the other, which the first path counts as imbalance);
  the serial fraction s of the one-thread CPU and Amdahl's bound 1 / (s + (1 - s) / 2);
  the load-independent estimate of the two-thread speed-up: one-thread CPU / two-thread
  fair critical path (it counts the serial part, the longest tasks and any work the second
  thread adds), the same with the busiest threads, and the balance of the parallel loops
  as they ran (their CPU / (2 x busiest));
  whether both thread counts made the same mesh (hash of positions, normals, triangles);
  the machine's own share of the extra CPU: two one-thread runs side by side (two processes,
  nothing shared but the hardware) against one alone — on an idle machine the second busy
  core alone slows the first (shared caches and memory, the host's clock and siblings), so
  2t/1t CPU divided by this pair/alone CPU is what the threads themselves add.

Asserts nothing; exits 0 unless a run fails.

  bench_threads.py --build build/release [--quick] [--repeats N]
"""
import argparse
import json
import os
import subprocess
import sys

GOAL = 1.8
# (surface, depth): the two; --quick runs them two levels coarser.
CASES = (("gyroid-ball", 9), ("barth-sextic", 8))
PHASES = ("octree", "breaks", "polygons", "weld")
RUN_TIMEOUT_S = 900


def run(exe, name, depth, threads):
    r = subprocess.run([exe, name, str(depth), str(threads)], capture_output=True, text=True,
                       timeout=RUN_TIMEOUT_S)
    if r.returncode != 0:
        raise RuntimeError("%s %s %d %d: %s" % (exe, name, depth, threads, r.stderr.strip()))
    return json.loads(r.stdout)


def run_pair(exe, name, depth):
    """Two one-thread runs at once, as separate processes: their mean polygoniser CPU."""
    procs = [subprocess.Popen([exe, name, str(depth), "1"], stdout=subprocess.PIPE, text=True)
             for _ in range(2)]
    cpu = []
    for p in procs:
        out, _ = p.communicate(timeout=RUN_TIMEOUT_S)
        if p.returncode != 0:
            raise RuntimeError("%s %s %d 1 (pair): failed" % (exe, name, depth))
        cpu.append(sum(json.loads(out)["cpu_ms"]))
    return sum(cpu) / 2


def minimum(runs):
    """Each figure's minimum over the runs (lists element-wise)."""
    out = dict(runs[0])
    for k, v in runs[0].items():
        if isinstance(v, float):
            out[k] = min(r[k] for r in runs)
        elif isinstance(v, list) and v and isinstance(v[0], float):
            out[k] = [min(r[k][i] for r in runs) for i in range(len(v))]
    return out


def load_line(load):
    cores = os.cpu_count()
    return "load average %.1f (max over the runs) on %d cores%s" % (
        load, cores, " — NOT idle: wall times follow the scheduler's share" if load > cores else "")


def report(name, depth, one, two, load, hashes, pair_cpu):
    s = sum(one["serial_ms"]) / sum(one["cpu_ms"])
    amdahl = 1 / (s + (1 - s) / 2)
    crit2 = sum(two["critical_ms"])
    estimate = sum(one["cpu_ms"]) / sum(two["even_ms"])
    as_ran = sum(one["cpu_ms"]) / crit2
    par_cpu = sum(c - s_ for c, s_ in zip(two["cpu_ms"], two["serial_ms"]))
    par_busy = sum(c - s_ for c, s_ in zip(two["critical_ms"], two["serial_ms"]))
    balance = par_cpu / (2 * par_busy) if par_busy > 0 else 1.0
    wall = one["wall_ms"] / two["wall_ms"]
    same = len(hashes) == 1
    print("\n%s depth %d: %d triangles, mesh %s on 1 and 2 threads" % (
        name, depth, one["triangles"], "identical" if same else "DIFFERENT"))
    print("%-9s %10s %10s %10s %10s %10s %10s %10s %10s" % (
        "phase", "cpu 1t ms", "serial 1t", "cpu 2t ms", "serial 2t", "as ran 2t", "fair 2t",
        "wall 1t", "wall 2t"))
    for i, ph in enumerate(PHASES):
        print("%-9s %10.1f %10.1f %10.1f %10.1f %10.1f %10.1f %10.1f %10.1f" % (
            ph, one["cpu_ms"][i], one["serial_ms"][i], two["cpu_ms"][i], two["serial_ms"][i],
            two["critical_ms"][i], two["even_ms"][i], one["time_ms"][i], two["time_ms"][i]))
    print("%-9s %10.1f %10.1f %10.1f %10.1f %10.1f %10.1f" % (
        "total", sum(one["cpu_ms"]), sum(one["serial_ms"]), sum(two["cpu_ms"]),
        sum(two["serial_ms"]), crit2, sum(two["even_ms"])))
    print("wall 1t %.0f ms, 2t %.0f ms (x%.2f); process CPU 1t %.0f ms, 2t %.0f ms" % (
        one["wall_ms"], two["wall_ms"], wall, one["process_cpu_ms"], two["process_cpu_ms"]))
    print("serial fraction %.3f -> Amdahl bound x%.2f; estimate from CPU x%.2f fair split, "
          "x%.2f as the threads ran (parallel loops' balance %.2f, 2t/1t CPU %.2f)" % (
              s, amdahl, estimate, as_ran, balance, sum(two["cpu_ms"]) / sum(one["cpu_ms"])))
    machine = pair_cpu / sum(one["cpu_ms"])
    print("two 1-thread processes side by side: CPU %.0f ms each, x%.3f of one alone (the "
          "machine's share); 2t/1t CPU over it x%.3f (what the threads add)" % (
              pair_cpu, machine, sum(two["cpu_ms"]) / sum(one["cpu_ms"]) / machine))
    idle = load <= os.cpu_count()
    print("RESULT threads %s d%d: 2 threads x%.2f wall (goal >= %.1f: %s), estimate x%.2f, "
          "Amdahl bound x%.2f; %s" % (
              name, depth, wall, GOAL,
              ("PASS" if wall >= GOAL else "MISS") if idle else "NOT idle, not judged",
              estimate, amdahl, load_line(load)))
    return same


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--only", default="")
    args = ap.parse_args()
    exe = os.path.join(args.build, "bench", "bench_threads")
    if not os.path.exists(exe):
        print("bench_threads.py: %s not built (make bench builds it)" % exe)
        return 1
    ok = True
    for name, depth in CASES:
        if args.only not in name:
            continue
        depth -= 2 if args.quick else 0
        runs = {1: [], 2: []}
        pairs = []
        load = os.getloadavg()[0]
        for _ in range(args.repeats):
            for t in (1, 2):
                r = run(exe, name, depth, t)
                runs[t].append(r)
                load = max(load, os.getloadavg()[0])
            pairs.append(run_pair(exe, name, depth))
        hashes = {r["hash"] for t in runs for r in runs[t]}
        ok = report(name, depth, minimum(runs[1]), minimum(runs[2]), load, hashes,
                    min(pairs)) and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
