#!/usr/bin/env python3
"""Where adaptive feed gains or loses time: compare the trajectories of a run with and without it.

    cncore run PROG --machine M.toml --accdec TYPE --trajectory off.csv
    cncore run PROG --machine M.toml --accdec TYPE --adaptive on --trajectory on.csv
    tools/adaptive_time_split.py --off off.csv --on on.csv --feed 6000 --target 40

Every cycle of the adaptive run moves the tool from path position s to s + ds in one period; the
run without adaptive feed covered the same stretch in t_off(s + ds) - t_off(s) (interpolated
between its samples). The difference is summed per class of the adaptive run's cycle: override
above / at / below 100 %, and the tool at the feed limit F·OR (speed >= 0.99·F·OR: the override
is what limits it) or below it (acceleration, a corner or a ramp limits it). The classes add up to
the difference of the cycle times. Also prints, for the run without adaptive feed, how long the
cutting tool (load >= --threshold) ran at F and below it, by load band around the target.
Plain Python (csv), no third-party modules; a 700 000-row trajectory takes a few seconds.
"""

import argparse
import bisect
import csv
import math
import sys
from collections import defaultdict


def read(path):
    """Rows (feed, override, load) and the cumulative path length of the XYZ set-points."""
    s = [0.0]
    rows = []
    with open(path, newline="") as f:
        r = csv.reader(f)
        head = next(r)
        try:
            ix, iy, iz = head.index("x"), head.index("y"), head.index("z")
            ifeed, iov, iload = head.index("feed"), head.index("override"), head.index("load")
        except ValueError as e:
            sys.exit(f"{path}: needs the columns x, y, z, feed, override, load ({e})")
        prev = None
        for row in r:
            p = (float(row[ix]), float(row[iy]), float(row[iz]))
            if prev is not None:
                s.append(s[-1] + math.dist(p, prev))
            prev = p
            rows.append((float(row[ifeed]), float(row[iov]), float(row[iload])))
    return s, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--off", required=True, help="trajectory CSV without adaptive feed")
    ap.add_argument("--on", required=True, help="trajectory CSV with adaptive feed")
    ap.add_argument("--feed", type=float, required=True, help="programmed feed F, mm/min")
    ap.add_argument("--target", type=float, default=60, help="target load, %% (load bands)")
    ap.add_argument("--threshold", type=float, default=10, help="lm: cutting when load >= lm, %%")
    ap.add_argument("--period", type=float, default=0.001, help="interpolation period, s")
    a = ap.parse_args()

    s_off, rows_off = read(a.off)
    s_on, rows_on = read(a.on)

    def t_off(x):
        i = bisect.bisect_left(s_off, x)
        if i == 0:
            return 0.0
        if i >= len(s_off):
            return (len(s_off) - 1) * a.period
        lo, hi = s_off[i - 1], s_off[i]
        return (i - 1 + ((x - lo) / (hi - lo) if hi > lo else 1.0)) * a.period

    # class -> [cycles, on - off (s), sum of load, sum of override]
    split = defaultdict(lambda: [0, 0.0, 0.0, 0.0])
    prev_t = 0.0
    for k in range(1, len(s_on)):
        feed, ov, load = rows_on[k]
        t = t_off(s_on[k])
        at_limit = feed >= 0.99 * a.feed * ov / 100
        name = ("override > 100 %" if ov > 101 else "override < 100 %" if ov < 99 else
                "override 100 %") + (", at F·OR" if at_limit else ", below F·OR")
        c = split[name]
        c[0] += 1
        c[1] += a.period - (t - prev_t)
        c[2] += load if math.isfinite(load) else 0.0
        c[3] += ov
        prev_t = t
    print("adaptive run, by its cycles' class (on - off over the same stretch of path):")
    total = 0.0
    for name in sorted(split):
        n, d, ld, ov = split[name]
        total += d
        print(f"  {name:32s} {n * a.period:9.3f} s  mean override {ov / n:6.1f} %  "
              f"mean load {ld / n:6.1f} %  on - off {d:+8.3f} s")
    print(f"  {'total':32s} {'':9s}    {'':30s}   on - off {total:+8.3f} s")

    bands = (a.target * 2 / 3, a.target, a.target * 1.5)  # 1.5: the default upper_pct
    names = (f"< {bands[0]:.0f} %", f"{bands[0]:.0f}-{bands[1]:.0f} %",
             f"{bands[1]:.0f}-{bands[2]:.0f} %", f">= {bands[2]:.0f} %")
    hist = defaultdict(float)
    for feed, _, load in rows_off:
        if not (load >= a.threshold):
            continue
        band = names[bisect.bisect_right(bands, load)]
        hist[("at F" if feed >= 0.99 * a.feed else "below F", band)] += a.period
    print(f"run without adaptive feed, cutting (load >= {a.threshold:g} %), by load band:")
    for where in ("at F", "below F"):
        cells = "  ".join(f"{b}: {hist[(where, b)]:8.3f} s" for b in names)
        print(f"  {where:8s} {cells}")


if __name__ == "__main__":
    main()
