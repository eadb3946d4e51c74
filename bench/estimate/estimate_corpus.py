#!/usr/bin/env python3
"""Wall time of `cncore estimate` over the whole shared G-code corpus with -j 1 and -j 2, and a
check that both give the same cycle time for every program.

  bench/estimate/estimate_corpus.py BUILD/src/app/cncore [N]   (N runs per -j, best kept; 1)

Environment: SHARED (corpus root, default ../shared next to the repository), JOBS (the -j values,
default "1 2"). Prints the load average first: on a loaded machine the speed-up is lower.
"""
import csv
import os
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
shared = os.environ.get("SHARED", os.path.join(here, "..", "..", "..", "shared"))
gcode = os.path.join(shared, "testdata", "gcode")
jobs_list = [int(j) for j in os.environ.get("JOBS", "1 2").split()]
binary = sys.argv[1]
runs = int(sys.argv[2]) if len(sys.argv) > 2 else 1
if not os.path.isdir(gcode):
    sys.exit(f"no corpus at {gcode}")

print(f"load average {os.getloadavg()[0]:.2f}; {os.cpu_count()} cores; best of {runs}")
tables = {}
best = {}
with tempfile.TemporaryDirectory() as tmp:
    for jobs in jobs_list:
        out = os.path.join(tmp, f"j{jobs}.csv")
        for _ in range(runs):
            t0 = time.perf_counter()
            p = subprocess.run([binary, "estimate", gcode, "-j", str(jobs), "--csv", out],
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
            wall = time.perf_counter() - t0
            if p.returncode not in (0, 1):
                sys.exit(f"estimate -j {jobs} failed with exit code {p.returncode}")
            best[jobs] = min(best.get(jobs, float("inf")), wall)
        with open(out, newline="") as f:
            tables[jobs] = {r["program"]: r for r in csv.DictReader(f)}

first = tables[jobs_list[0]]
ok = sum(1 for r in first.values() if r["status"] == "ok")
total = sum(float(r["cycle_time_s"]) for r in first.values() if r["status"] == "ok")
print(f"{len(first)} programs ({ok} ok, {len(first) - ok} failed), total cycle time {total:.1f} s")
for jobs in jobs_list:
    same = all(tables[jobs][p]["cycle_time_s"] == first[p]["cycle_time_s"] for p in first)
    print(f"-j {jobs}: wall {best[jobs]:7.2f} s, speed-up {best[jobs_list[0]] / best[jobs]:.2f}, "
          f"cycle times {'identical' if same else 'DIFFERENT'} to -j {jobs_list[0]}")
