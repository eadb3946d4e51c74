#!/usr/bin/env python3
"""A sampled trajectory built cycle by cycle: one cycle centred on every corner.

  discrete_reference.py PER_BLOCK.tsv -o TRAJ.csv [--accel 2000] [--period 0.001]
                        [--margin 0.995]

PER_BLOCK.tsv is `cncore-bound PROGRAM --per-block FILE` (lines and rapids only). Every joint j
with passing speed V_j > 0 gets one cycle of length m*V_j*tau whose midpoint is the joint (so the
turn is split evenly between the two samples around it). Its neighbours may move faster by D_j,
the largest step (found by bisection on the actual vectors) for which both samples around the
corner keep every axis's |d[k+1] - d[k]| <= m*A_i*tau^2 and the normal acceleration
2*sqrt(l1*l2)*sin(angle/2) <= m*A*tau^2 with the neighbours anywhere in [V_j - D_j, V_j + D_j]. Between two joint cycles (one straight segment) the
fewest cycles that cover the distance are used: the largest lengths allowed by the steps
(<= m*A*tau^2 per cycle), the neighbours' D and the segment's cap, scaled down to the exact
distance. Stops: the path starts and ends with steps <= A*tau^2 and a sample on the point.
Joints closer than their cycles (a gap shorter than the two half joint cycles) are refused.

Check the result with `cncore-trajcheck PROGRAM TRAJ.csv`: if it passes, its duration is an
achievable cycle time on the checker's rules.
"""
import argparse
import math
import sys

import per_block


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("per_block")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--accel", type=float, default=2000.0)
    ap.add_argument("--period", type=float, default=0.001)
    ap.add_argument("--margin", type=float, default=0.995)
    a = ap.parse_args()
    A, tau, m = a.accel, a.period, a.margin
    segs = per_block.read_lines(a.per_block, "discrete_reference")
    n = len(segs)
    dirs = [per_block.unit(s) for s in segs]
    step = m * A * tau * tau  # largest change of a cycle's length (mm) from one cycle to the next

    def ok_corner(E, S, V, D):
        # Samples around a corner passed by the cycle of path length V*tau centred on it: chords
        # (V±D)*tau*E, (V*tau/2)(E + S), (V±D)*tau*S (each neighbour anywhere in [V−D, V+D]:
        # the extremes, the accelerations being linear in the neighbour's length).
        return all(ok_pair(E, S, V, da, db) for da in (D, -D) for db in (D, -D))

    def ok_pair(E, S, V, da, db):
        h = V * tau / 2
        d0 = [max(0.0, V + da) * tau * e for e in E]
        d1 = [h * (E[i] + S[i]) for i in range(3)]
        d2 = [max(0.0, V + db) * tau * s for s in S]
        for u, w in ((d0, d1), (d1, d2)):
            for i in range(3):
                if abs(w[i] - u[i]) > m * A * tau * tau + 1e-15:
                    return False
            lu = math.sqrt(sum(x * x for x in u))
            lw = math.sqrt(sum(x * x for x in w))
            if lu > 0 and lw > 0:
                c = sum(u[i] * w[i] for i in range(3)) / (lu * lw)
                ang = math.acos(max(-1.0, min(1.0, c)))
                if 2 * math.sqrt(lu * lw) * math.sin(ang / 2) > m * A * tau * tau + 1e-15:
                    return False
        return True

    # Joint cycles: speed V_j (m * the bound's joint cap) and the neighbours' extra D_j.
    V, D = [], []
    for j in range(n - 1):
        # The bound's own joint speed (its passes already brake for what follows), not only the
        # joint's cap.
        vj = m * min(segs[j]["J"], segs[j]["u"])
        if vj <= 0:
            V.append(0.0)
            D.append(0.0)
            continue
        E, S = dirs[j], dirs[j + 1]
        while not ok_corner(E, S, vj, 0.0):
            vj *= 0.98
        lo, hi = 0.0, m * A * tau
        if ok_corner(E, S, vj, hi):
            lo = hi
        else:
            for _ in range(40):
                mid = (lo + hi) / 2
                if ok_corner(E, S, vj, mid):
                    lo = mid
                else:
                    hi = mid
        V.append(vj)
        D.append(lo)

    infeasible = [0]

    def fill(dist, first, last, cap):
        # Fewest cycle lengths x_1..x_k (mm) with |x_1 - v_first*tau| <= step,
        # |x_k - v_last*tau| <= step, |x_{i+1} - x_i| <= step, x_i <= cap*tau, summing to dist:
        # between the lowest (lo) and highest (hi) such profiles, x_i = clamp(h, lo_i, hi_i) for
        # the level h that gives the exact sum (the edges keep their values as long as possible).
        # first/last = (lowest, highest) speed allowed for the cycle next to each end.
        if dist <= 1e-15:
            return []
        ctop = cap * tau * m

        def hi_lo(k):
            hi = [min(ctop, first[1] * tau + step * i, last[1] * tau + step * (k - 1 - i))
                  for i in range(k)]
            lo = [max(0.0, first[0] * tau - step * i, last[0] * tau - step * (k - 1 - i))
                  for i in range(k)]
            return hi, lo

        k = 1
        while True:
            hi, lo = hi_lo(k)
            if sum(hi) >= dist:
                break
            k += 1
        if sum(lo) > dist:
            infeasible[0] += 1  # the joint speeds do not fit in this gap: keep the lowest
            return lo
        a_, b_ = 0.0, max(hi)
        for _ in range(60):
            h = (a_ + b_) / 2
            if sum(min(hi[i], max(lo[i], h)) for i in range(k)) < dist:
                a_ = h
            else:
                b_ = h
        xs = [min(hi[i], max(lo[i], b_)) for i in range(k)]
        xs[-1] += dist - sum(xs)  # rounding
        return xs

    # Cycle lengths along the path and the sample positions s_k.
    S_start = per_block.starts(segs)
    lengths = []
    pos = 0.0  # where the next cycle starts
    rest = (0.0, step / tau)  # the cycle next to a stop: at most A*tau
    after = rest  # (lowest, highest) speed of the first cycle after pos
    for j in range(n):
        end = S_start[j + 1]
        if j < n - 1 and V[j] > 0:
            half = V[j] * tau / 2
            if end - half < pos - 1e-12:
                sys.exit("discrete_reference: joints closer than their cycles (line %d)"
                         % segs[j]["line"])
            nb = (max(0.0, V[j] - D[j]), V[j] + D[j])  # the joint cycle's neighbours
            lengths.extend(fill(end - half - pos, after, nb, segs[j]["cap"]))
            lengths.append(2 * half)
            pos = end + half
            after = nb
        else:
            # A stop or the end: the last cycle <= A*tau^2 lands on the point.
            lengths.extend(fill(end - pos, after, rest, segs[j]["cap"]))
            pos = end
            after = rest
    # Positions to samples.
    out = per_block.TrajectoryCsv(a.out)
    path = per_block.PathPoints(segs)
    out.row(0.0, *path.at(0.0))
    sv = 0.0
    for k, x in enumerate(lengths, 1):
        sv = min(S_start[-1], sv + x)
        if k == len(lengths):
            sv = S_start[-1]
        out.row(k * tau, *path.at(sv))
    out.close()
    print("reference_s=%.6f cycles=%d joints=%d infeasible_gaps=%d"
          % (len(lengths) * tau, len(lengths), n - 1, infeasible[0]))


if __name__ == "__main__":
    main()
