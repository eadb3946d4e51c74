#!/usr/bin/env python3
"""Where a run loses time against the bound, cycle by cycle, by cause.

  loss_by_cause.py PROGRAM --cncore BIN --bound BIN [--accdec TYPE] [--machine M.toml]
                   [--traj T.csv] [--per-block B.tsv]

Every cycle k of the run moves the tool from path position s_{k-1} to s_k; the bound needs
t_b(s_k) - t_b(s_{k-1}) for that stretch (t_b: the bound's time to reach s, rebuilt per block
from `cncore-bound --per-block`: accelerate-cruise-decelerate between v_in and v_out at the
block's cap, with the constant acceleration that gives the block's time_s). The cycle's loss is
tau minus that; the losses add up to run - bound (up to the bound's dwell time and the run's
trailing samples). Each cycle is classified by what shapes the bound's profile at the middle of
its step:
  a-hold  the step crosses a capped corner (join_cap < 0.999 x the larger cap of both blocks)
          or is one of its two neighbours: the 3-cycle hold (cause a);
  a-ramp  the bound is on a ramp out of / into a capped corner: the ramps the hold shifts;
  arc     the step lies on an arc (cause b: the arc's r fixed for its top speed, its cap);
  zone    within [j - 2v, j + v] of a gentle joint (turn > 0.05 deg, not capped) where the bound
          changes speed (cause c: the joint zone's lowered r);
  stop    on a ramp out of / into a stop (program start/end, exact stop, dwell);
  cap     on a ramp between two block caps (feed or speed limit changes);
  cruise  the bound runs at the block's cap.
"""
import argparse
import collections
import csv
import math
import os

import per_block


def profile(L, v0, v1, cap, a):
    """(xa, xd, xm) of the accelerate-cruise-decelerate profile: cruise on [xa, xd] when
    xa <= xd, else a peak at xm."""
    xa = (cap * cap - v0 * v0) / (2 * a)
    xd = L - (cap * cap - v1 * v1) / (2 * a)
    xm = min(L, max(0.0, (v1 * v1 - v0 * v0 + 2 * a * L) / (4 * a)))
    return xa, xd, xm


def t_of(L, v0, v1, cap, a, x):
    """Time from the block's start to x, and the phase at x: +1 accelerating, 0 cruise, -1
    decelerating."""
    xa, xd, xm = profile(L, v0, v1, cap, a)
    up_end = xa if xa <= xd else xm
    dn_start = xd if xa <= xd else xm
    vup = lambda y: math.sqrt(max(0.0, v0 * v0 + 2 * a * y))
    vdn = lambda y: math.sqrt(max(0.0, v1 * v1 + 2 * a * (L - y)))
    if x <= up_end:
        return (vup(x) - v0) / a, 1
    t = (vup(up_end) - v0) / a
    if x <= dn_start:
        return t + (x - up_end) / cap, 0
    t += (dn_start - up_end) / cap if dn_start > up_end else 0
    return t + (vdn(dn_start) - vdn(x)) / a, -1


def fit_a(L, v0, v1, cap, time):
    if L <= 0 or time <= 0:
        return 1e9
    lo, hi = 1e-3, 1e9
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        if t_of(L, v0, v1, cap, mid, L)[0] > time:
            lo = mid
        else:
            hi = mid
    return hi


def main():
    ap = argparse.ArgumentParser()
    per_block.add_run_options(ap)
    ap.add_argument("--top", type=int, default=0)
    ap.add_argument("--cycles", help="write one row per cycle: t s step loss cause line")
    a = ap.parse_args()
    traj, per = per_block.run_and_bound(a, "lossbc")
    B = per_block.read_blocks(per)
    n = len(B)
    S = [0.0]
    T = [0.0]
    for b in B:
        b["a"] = fit_a(b["L"], b["v0"], b["v1"], b["cap"], b["time"])
        b["u"] = per_block.unit(b)
        S.append(S[-1] + b["L"])
        T.append(T[-1] + b["time"])

    def contiguous(i):  # block i-1 ends where block i starts
        return i > 0 and max(abs(B[i - 1]["p1"][k] - B[i]["p0"][k]) for k in range(3)) < 1e-6

    # Boundary i (start of block i): what the bound's speed there is set by.
    def btype(i):
        if i == 0 or i == n:
            return "stop"
        v = B[i]["v0"]
        if v <= 1e-9 or not contiguous(i):
            return "stop"
        hi = max(B[i - 1]["cap"], B[i]["cap"])
        if B[i - 1]["J"] < 0.999 * hi and v <= B[i - 1]["J"] * 1.0001:
            return "corner"
        return "cap"

    # Origin of the ramp through each block: accelerating at its start means the ramp began at
    # an earlier boundary (forward pass); decelerating at its end, a later one.
    up_origin = [0] * n
    for i in range(n):
        b = B[i]
        up_origin[i] = i
        if i > 0 and contiguous(i) and B[i - 1]["v1"] > 1e-9:
            p = B[i - 1]
            xa, xd, xm = profile(p["L"], p["v0"], p["v1"], p["cap"], p["a"])
            ends_up = (xa > xd and xm >= p["L"] * (1 - 1e-9)) or (xa <= xd and xa >= p["L"])
            if ends_up and btype(i) == "cap" and p["v1"] < 0.999 * min(p["cap"], b["cap"]):
                up_origin[i] = up_origin[i - 1]
    dn_origin = [0] * n
    for i in reversed(range(n)):
        b = B[i]
        dn_origin[i] = i + 1
        if i + 1 < n and contiguous(i + 1) and b["v1"] > 1e-9:
            q = B[i + 1]
            xa, xd, xm = profile(q["L"], q["v0"], q["v1"], q["cap"], q["a"])
            starts_dn = (xa > xd and xm <= 0) or (xa <= xd and xd <= 0)
            if starts_dn and btype(i + 1) == "cap" and b["v1"] < 0.999 * min(b["cap"], q["cap"]):
                dn_origin[i] = dn_origin[i + 1]

    # Gentle joints: turn > 0.05 deg, not capped; capped ones (for the hold around them).
    gentle = []
    capped = [S[i] for i in range(1, n) if btype(i) == "corner"]
    for i in range(1, n):
        if not contiguous(i) or btype(i) != "cap":
            continue
        c = sum(B[i - 1]["u"][k] * B[i]["u"][k] for k in range(3))
        if B[i - 1]["kind"] == "arc" or B[i]["kind"] == "arc" or c < math.cos(math.radians(0.05)):
            gentle.append(S[i])

    def tb(i, s):
        b = B[i]
        t, ph = t_of(b["L"], b["v0"], b["v1"], b["cap"], b["a"], min(b["L"], max(0.0, s - S[i])))
        return T[i] + t, ph

    # The run's path position per sample.
    loss = collections.Counter()
    count = collections.Counter()
    worst = collections.Counter()
    tau = None
    with open(traj) as f:
        r = csv.reader(f)
        next(r)
        rows = [(float(x[0]), int(x[1]), float(x[2]), float(x[3]), float(x[4])) for x in r]
    tau = rows[1][0] - rows[0][0]
    dump = open(a.cycles, "w") if a.cycles else None
    bi = 0
    s_prev = 0.0
    last_xyz = rows[0][2:]
    i_prev = 0
    gi = 0
    ci = 0
    run_total = 0.0
    for k in range(1, len(rows)):
        t, line, x, y, z = rows[k]
        # The block holding the sample: the first block from bi on with this line whose span
        # contains the projection (blocks in path order).
        j = bi
        while j < n and B[j]["line"] != line:
            j += 1
        if j == n:
            j = bi  # an event line: stay
        else:
            bi = j
        b = B[j]
        if b["kind"] == "arc":
            if j == i_prev:
                s = s_prev + math.dist(last_xyz, (x, y, z))
            else:
                s = S[j] + math.dist(b["p0"], (x, y, z))
        else:
            s = S[j] + sum((v - b["p0"][q]) * b["u"][q] for q, v in enumerate((x, y, z)))
        s = min(max(s, S[j]), S[j + 1])
        s = max(s, s_prev)
        t0, _ = tb(i_prev, s_prev)
        t1, _ = tb(j, s)
        l = tau - (t1 - t0)
        run_total += tau
        # Classify at the middle of the step.
        mid = 0.5 * (s_prev + s)
        m = i_prev
        while m + 1 < n and S[m + 1] <= mid:
            m += 1
        _, ph = tb(m, mid)
        step = s - s_prev
        while gi < len(gentle) and gentle[gi] < mid - step - 1e-12:
            gi += 1
        near_gentle = gi < len(gentle) and gentle[gi] <= mid + 2 * max(step, 1e-9)
        while ci < len(capped) and capped[ci] < s_prev - 1.01 * step - 1e-12:
            ci += 1
        # The hold: the step across a capped corner and both neighbours.
        near_capped = ci < len(capped) and capped[ci] <= s + 1.01 * step + 1e-12
        if B[m]["kind"] == "arc":
            cause = "b-arc"
        elif ph == 0:
            cause = "d-cruise"
        else:
            o = btype(up_origin[m]) if ph > 0 else btype(dn_origin[m])
            if near_gentle:
                cause = "c-zone"
            elif o == "corner":
                cause = "a-hold" if near_capped else "a-ramp"
            else:
                cause = "d-" + o
        if ph == 0 and near_gentle:
            cause = "c-zone"
        if near_capped and B[m]["kind"] != "arc":
            cause = "a-hold"
        loss[cause] += l
        count[cause] += 1
        worst[(cause, B[m]["line"])] += l
        if dump:
            dump.write(f"{t:.6f}\t{s:.9f}\t{step:.9f}\t{l:.9f}\t{ph}\t{cause}\t{B[m]['line']}\n")
        s_prev, last_xyz, i_prev = s, (x, y, z), j
    bound_total = T[-1]
    tot = sum(loss.values())
    print(f"{os.path.basename(a.program)}: run {run_total:.3f} s (cycles), bound {bound_total:.3f} s, "
          f"excess {run_total - bound_total:.3f} s (sum of cycle losses {tot:.3f})")
    for c in sorted(loss):
        print(f"  {c:10s} cycles {count[c]:8d}  loss {loss[c]:8.3f} s  "
              f"{100 * loss[c] / tot if tot else 0:5.1f}%")
    if a.top:
        for (c, ln), l in worst.most_common(a.top):
            print(f"    line {ln:6d} {c:10s} {l:.4f}")


if __name__ == "__main__":
    main()
