#!/usr/bin/env python3
"""How much of a run's time beyond the bound lies between capped corners, and how much at them.

  corner_loss.py PROGRAM --cncore BIN --bound BIN [--accdec TYPE] [--machine M.toml]
                 [--traj T.csv] [--per-block B.tsv] [--accel 2000] [--period 0.001]

Lines only (the per-block TSV of `cncore-bound --per-block`; arcs are refused). A capped corner
is a joint whose cap is below 0.999 x both segments' caps; its crossing is the run's first
sample at or past it (cycle k, step v[k] <= Vg). Reports:
  - between two consecutive crossings k1 < k2: the fewest cycles any profile needs from the
    run's own state there (start step v[k1], last step <= v[k2], |dv| <= A*tau per cycle, each
    step <= the highest cap), against k2 - k1: what the speed profile between the corners wastes;
  - the same for the middles, from the step after a crossing (k1 + 1) to the step before the
    next one (k2 - 1): the ramps alone, the steps next to the corners given;
  - the crossing step against Vg, and the steps next to it (v[k-1] - v[k], v[k+1] - v[k]) in
    units of A*tau, by where the corner lies in the crossing step (beta: the part after it).
What is not wasted between corners is spent at them: the crossing and its two neighbours, which
the checker's per-axis and normal rules limit at the two samples around the turn (the
continuous bound passes a corner in no time and has no samples there).
"""
import argparse
import collections
import csv
import os
import statistics

import per_block


def projections(segs, samples):
    """Path position of every (x, y, z) sample: a cursor that only moves forward."""
    s0 = per_block.starts(segs)
    out, i = [], 0

    def proj(k, p):
        seg = segs[k]
        d = [seg["p1"][q] - seg["p0"][q] for q in range(3)]
        L = seg["L"]
        if L <= 0:
            return 0.0, sum((p[q] - seg["p0"][q]) ** 2 for q in range(3))
        t = min(L, max(0.0, sum((p[q] - seg["p0"][q]) * d[q] for q in range(3)) / L))
        e = sum((seg["p0"][q] + d[q] * t / L - p[q]) ** 2 for q in range(3))
        return t, e

    for p in samples:
        t, e = proj(i, p)
        while i + 1 < len(segs):
            t2, e2 = proj(i + 1, p)
            if e2 <= e + 1e-18 and (t >= segs[i]["L"] - 1e-12 or e2 < e):
                i, t, e = i + 1, t2, e2
            else:
                break
        out.append(s0[i] + t)
    return out


def fewest(w0, dist, w_end, step, top):
    """Fewest steps w_1..w_n (|w_i - w_(i-1)| <= step from w_0, w_n <= w_end, <= top) covering
    dist."""
    n = 0
    while True:
        n += 1
        if sum(max(0.0, min(w0 + i * step, w_end + (n - i) * step, top))
               for i in range(1, n + 1)) >= dist - 1e-12:
            return n


def main():
    ap = argparse.ArgumentParser()
    per_block.add_run_options(ap)
    ap.add_argument("--accel", type=float, default=2000.0)
    ap.add_argument("--period", type=float, default=0.001)
    a = ap.parse_args()
    traj, per = per_block.run_and_bound(a, "cornerloss")
    segs = per_block.read_lines(per, "corner_loss")
    tau, step = a.period, a.accel * a.period * a.period
    with open(traj) as f:
        rows = list(csv.DictReader(f))
    s = projections(segs, [[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    v = [0.0] + [s[k] - s[k - 1] for k in range(1, len(s))]  # mm per cycle
    top = max(seg["cap"] for seg in segs) * tau
    s0 = per_block.starts(segs)
    cross = []  # (cycle, joint position, Vg in mm per cycle)
    k = 1
    for i in range(len(segs) - 1):
        if not segs[i]["J"] < 0.999 * min(segs[i]["cap"], segs[i + 1]["cap"]):
            continue
        j = s0[i + 1]
        while k < len(s) and s[k] < j - 1e-9:
            k += 1
        if k < len(s):
            cross.append((k, j, segs[i]["J"] * tau))
    between = [0, 0]
    middle = [0, 0]
    for (k1, _, _), (k2, _, _) in zip(cross, cross[1:]):
        if k2 > k1:
            between[0] += k2 - k1
            between[1] += (k2 - k1) - fewest(v[k1], s[k2] - s[k1], v[k2], step, top)
        m1, m2 = k1 + 1, k2 - 1
        if m2 > m1:
            middle[0] += m2 - m1
            middle[1] += (m2 - m1) - fewest(v[m1], s[m2] - s[m1], v[m2], step, top)
    ratio = [v[k] / vg for k, _, vg in cross if vg > 0]
    print("%s: %d cycles, %d capped corners, %d cycles cross one"
          % (os.path.basename(a.program), len(s) - 1, len(cross), len({c[0] for c in cross})))
    print("  corner to corner: %d cycles, %d more than the fewest from the run's corner states"
          % tuple(between))
    print("  ramps between the corners' neighbours: %d cycles, %d more than the fewest"
          % tuple(middle))
    if ratio:
        ratio.sort()
        print("  crossing step / Vg: mean %.3f, median %.3f, 10th percentile %.3f"
              % (statistics.mean(ratio), ratio[len(ratio) // 2], ratio[len(ratio) // 10]))
    by_beta = collections.defaultdict(list)
    for k, j, _ in cross:
        if 0 < k < len(v) - 1 and v[k] > 0:
            beta = (s[k] - j) / v[k]
            by_beta[round(beta * 5) / 5].append(((v[k - 1] - v[k]) / step, (v[k + 1] - v[k]) / step))
    print("  steps next to the crossing, in A*tau, by the part of the crossing step past the corner:")
    for b in sorted(by_beta):
        xs = by_beta[b]
        print("    beta %.1f: %5d corners, before %+.2f, after %+.2f"
              % (b, len(xs), statistics.mean(x[0] for x in xs), statistics.mean(x[1] for x in xs)))


if __name__ == "__main__":
    main()
