#!/usr/bin/env python3
"""Cycles per second of whole `cncore run` commands (throughput without trajectory
output), one or more binaries alternated, best of N.

  bench/pipeline/whole_run.py BIN[,BIN2...] [N]      (N runs per binary and program, default 3)

Each run is `BIN run PROGRAM --accdec TYPE --summary TMP.json` (no trajectory; the summary is
written to a temporary file — not /dev/null: the summary is written atomically, by a rename
over the target path). Reports, per program and type, the best wall-clock time of the whole
process (start, kernel construction, interpretation, cycles, summary) and its best CPU time
(user + sys, from wait4), and cycles / time. Environment: SHARED (corpus root, default
../shared next to the repo), PROGS (paths under testdata/gcode, space-separated), TYPES
(default "acceleration moving_average"), PIN (a CPU to pin to with taskset; default none).
"""
import json
import os
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
shared = os.environ.get("SHARED", os.path.join(here, "..", "..", "..", "shared"))
gcode = os.path.join(shared, "testdata", "gcode")
progs = os.environ.get(
    "PROGS", "camotics/bear.nc ugs/stress_test.gcode camotics/botomata_bottom.nc").split()
types = os.environ.get("TYPES", "acceleration moving_average").split()
pin = os.environ.get("PIN", "")
bins = sys.argv[1].split(",")
runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3


def run_once(cmd):
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if status != 0:
        sys.exit(f"failed: {' '.join(cmd)}")
    return wall, usage.ru_utime + usage.ru_stime


with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "summary.json")
    print(f"load average {os.getloadavg()[0]:.2f}; best of {runs}")
    for prog in progs:
        for accdec in types:
            best = {b: [float("inf"), float("inf")] for b in bins}
            for _ in range(runs):
                for b in bins:  # alternated, so that both see the same machine
                    cmd = (["taskset", "-c", pin] if pin else []) + [
                        b, "run", os.path.join(gcode, prog), "--accdec", accdec, "--summary", out]
                    wall, cpu = run_once(cmd)
                    best[b][0] = min(best[b][0], wall)
                    best[b][1] = min(best[b][1], cpu)
            cycles = json.load(open(out))["cycles"]
            for b in bins:
                wall, cpu = best[b]
                print(f"{os.path.basename(prog):22s} {accdec:15s} {cycles:8d} cycles  {b}: "
                      f"wall {wall * 1e3:7.1f} ms = {cycles / wall / 1e6:5.2f} M/s, "
                      f"CPU {cpu * 1e3:7.1f} ms = {cycles / cpu / 1e6:5.2f} M/s", flush=True)
    print(f"load average {os.getloadavg()[0]:.2f}")
