#!/usr/bin/env python3
"""An achievable sampled trajectory close to the bound: what a planner could reach.

  reference_profile.py PER_BLOCK.tsv -o TRAJ.csv [--accel 2000] [--period 0.001]
                       [--margin 0.99] [--plateau 2] [--no-dense]

PER_BLOCK.tsv is `cncore-bound PROGRAM --per-block FILE` (lines and rapids only; a program with
arcs is refused). The trajectory is the bound's own construction with the three changes a
sampled trajectory needs, then sampled every period:
  1. every joint j is passed on a plateau: speed <= J_j on [p_j - k*J_j*tau, p_j + k*J_j*tau]
     (k = --plateau, 2): the cycle that reaches or passes the joint, and the chords on both sides
     of the turn, then all move at <= J_j, so the joint rule and the direction change
     2*v*sin(theta/2) <= A*tau hold for the cycle's chords (not only at an instant);
  2. dense corners: a chord pair at speed v spans up to 2*v*tau of path, and the angle between
     two chords is at most the total turning between them, so J_j is lowered until
     2*J_j*sin(Theta_j/2) <= A*tau, Theta_j = sum of the corner angles within k*J_j*tau of p_j
     (fixed point, iterated from above);
  3. a feed decrease at p to c applies from p - k*c*tau (the cycle that ends in the slower block
     must already be slow), stops start again at the next whole cycle, and the acceleration is
     margin*A;
  4. near a joint the tangential acceleration leaves room for the turn on every axis (the
     velocity change of the cycle that turns is dv*T + v*dT): (1 - f)*margin*A within k*c*tau,
     f = c*max|dT_i|/(A*tau) at the highest speed c there.
Whether the result really satisfies every limit is not claimed here: check it with
`cncore-trajcheck PROGRAM TRAJ.csv`. If it passes, its duration is an achievable cycle time, so
(run - reference) is time the run's planner wastes (class b), and (reference - bound) is at
most what the continuous bound allows that sampling cannot do (class a) plus this
construction's own slack.
"""
import argparse
import bisect
import heapq
import math

import per_block


def interval_min(events, bps):
    """Per interval (bps[m], bps[m+1]): the least value of the events (pos, 0 = open / 1 = close,
    value, id) open at bps[m]; inf where none is. Both lists sorted by position."""
    out = []
    heap, closed = [], set()
    ei = 0
    for m in range(len(bps) - 1):
        while ei < len(events) and events[ei][0] <= bps[m]:
            _, kind, val, idd = events[ei]
            if kind == 0:
                heapq.heappush(heap, (val, idd))
            else:
                closed.add(idd)
            ei += 1
        while heap and heap[0][1] in closed:
            heapq.heappop(heap)
        out.append(heap[0][0] if heap else math.inf)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("per_block")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--accel", type=float, default=2000.0)
    ap.add_argument("--period", type=float, default=0.001)
    ap.add_argument("--margin", type=float, default=0.99)
    ap.add_argument("--plateau", type=float, default=2.0)
    ap.add_argument("--no-dense", action="store_true")
    ap.add_argument("--no-turn-share", action="store_true")
    a = ap.parse_args()
    A, tau, k = a.accel, a.period, a.plateau
    acc = a.margin * A

    segs = per_block.read_lines(a.per_block, "reference_profile")
    n = len(segs)
    S = per_block.starts(segs)
    dirs = [per_block.unit(s) for s in segs]
    # Joints: end of segment i (i < n-1); the end of the program is a stop.
    theta = []
    for i in range(n - 1):
        c = max(-1.0, min(1.0, sum(dirs[i][j] * dirs[i + 1][j] for j in range(3))))
        theta.append(math.acos(c))
    P = [S[i + 1] for i in range(n - 1)]
    J = [segs[i]["J"] * a.margin for i in range(n - 1)]
    stops = [i for i in range(n - 1) if segs[i]["J"] == 0]
    # 2. Dense corners: fixed point of J <- min(J, A*tau/(2 sin(Theta(k*J*tau)/2))).
    if not a.no_dense and n > 1:
        pref = [0.0]
        for t in theta:
            pref.append(pref[-1] + t)
        for i in range(n - 1):
            if J[i] == 0:
                continue
            for _ in range(60):
                w = k * J[i] * tau
                lo = bisect.bisect_left(P, P[i] - w)
                hi = bisect.bisect_right(P, P[i] + w)
                Th = min(math.pi, pref[hi] - pref[lo])
                lim = a.margin * A * tau / (2 * math.sin(Th / 2)) if Th > 1e-12 else math.inf
                if lim >= J[i] * (1 - 1e-12):
                    break
                J[i] = lim
    # Caps over the path: events (position, +/-, value) swept with a lazy-deletion heap.
    events = []  # (pos, kind 0=open 1=close, value, id)
    eid = 0
    for i, s in enumerate(segs):
        events.append((S[i], 0, s["cap"], eid))
        events.append((S[i + 1], 1, s["cap"], eid))
        eid += 1
    for i in range(n - 1):
        if J[i] == 0:
            continue
        w = k * J[i] * tau
        events.append((max(0.0, P[i] - w), 0, J[i], eid))
        events.append((min(S[-1], P[i] + w), 1, J[i], eid))
        eid += 1
        # 3. A slower next block: its cap from k*c*tau before the joint.
        c2 = segs[i + 1]["cap"]
        if c2 < segs[i]["cap"]:
            events.append((max(0.0, P[i] - k * c2 * tau), 0, c2, eid))
            events.append((P[i], 1, c2, eid))
            eid += 1
    # 4. A turn that the corner cap does not bind still uses part of every axis's acceleration
    # in the cycles that straddle it: w_{k+1} - w_k = dv*T + v*dT per axis. Around joint j
    # (within k*c*tau, c the larger neighbouring cap) the tangential acceleration is held to
    # (1 - f)*margin*A, f = c*max_i|dT_i|/(A*tau) (the turn's share at the highest speed there).
    aevents = []
    if not a.no_turn_share:
        for i in range(n - 1):
            if J[i] == 0:
                continue
            dT = max(abs(dirs[i + 1][j] - dirs[i][j]) for j in range(3))
            c = min(max(segs[i]["cap"], segs[i + 1]["cap"]), J[i] / a.margin)
            f = c * dT / (A * tau)
            if f <= 1e-9:
                continue
            ai = max(0.02 * A, (1 - f) * acc)
            w = k * c * tau
            aevents.append((max(0.0, P[i] - w), 0, ai, eid))
            aevents.append((min(S[-1], P[i] + w), 1, ai, eid))
            eid += 1
    events.sort()
    aevents.sort()
    bps = sorted(set([e[0] for e in events] + [e[0] for e in aevents]))
    caps = interval_min(events, bps)  # cap of (bps[m], bps[m+1])
    accs = [min(acc, x) for x in interval_min(aevents, bps)]  # acceleration of the same
    # Node caps: 0 at stops and the ends; else the smaller neighbouring interval cap.
    stop_pos = set(P[i] for i in stops)
    nb = len(bps)
    u = [0.0] * nb
    for m in range(nb):
        if m == 0 or m == nb - 1 or bps[m] in stop_pos:
            u[m] = 0.0
        else:
            u[m] = min(caps[m - 1], caps[m])
    for m in range(nb - 1):
        u[m + 1] = min(u[m + 1], math.sqrt(u[m] ** 2 + 2 * accs[m] * (bps[m + 1] - bps[m])))
    for m in range(nb - 2, -1, -1):
        u[m] = min(u[m], math.sqrt(u[m + 1] ** 2 + 2 * accs[m] * (bps[m + 1] - bps[m])))

    # Per interval: accelerate-cruise-decelerate; a function local time -> distance.
    def phases(L, v0, v1, vc, acc):
        vc = max(vc, v0, v1)
        vp = min(vc, math.sqrt((2 * acc * L + v0 * v0 + v1 * v1) / 2))
        ta = (vp - v0) / acc
        da = (vp * vp - v0 * v0) / (2 * acc)
        dd = (vp * vp - v1 * v1) / (2 * acc)
        cr = max(0.0, L - da - dd)
        tc = cr / vp if vp > 0 else 0.0
        td = (vp - v1) / acc
        return (v0, vp, ta, da, tc, cr, td, acc)

    def dist_at(ph, t):
        v0, vp, ta, da, tc, cr, td, acc = ph
        if t <= ta:
            return v0 * t + 0.5 * acc * t * t
        t -= ta
        if t <= tc:
            return da + vp * t
        t = min(t - tc, td)
        return da + cr + vp * t - 0.5 * acc * t * t

    # Sample: pieces between stops restart at the next whole cycle.
    out = per_block.TrajectoryCsv(a.out)
    path = per_block.PathPoints(segs)
    T0 = 0.0  # absolute time of the current piece's start (a multiple of tau)
    kcyc = 0
    out.row(0.0, *path.at(0.0))
    m = 0
    while m < nb - 1:
        # One piece: intervals m .. m2-1, ending at a node with u = 0 (a stop or the end).
        m2 = m + 1
        while m2 < nb - 1 and u[m2] > 0:
            m2 += 1
        ph = []
        tstart = [0.0]
        for q in range(m, m2):
            p = phases(bps[q + 1] - bps[q], u[q], u[q + 1], caps[q], accs[q])
            ph.append(p)
            tstart.append(tstart[-1] + p[2] + p[4] + p[6])
        Tp = tstart[-1]
        ncyc = max(1, math.ceil(Tp / tau - 1e-9))
        q = 0
        for c in range(1, ncyc + 1):
            t = c * tau
            if c == ncyc:
                sv = bps[m2]
            else:
                while q + 1 < len(ph) and tstart[q + 1] <= t:
                    q += 1
                sv = bps[m + q] + dist_at(ph[q], t - tstart[q])
                sv = min(sv, bps[m2])
            kcyc += 1
            out.row(kcyc * tau, *path.at(sv))
        m = m2
    out.close()
    print("reference_s=%.6f cycles=%d joints=%d stops=%d" % (kcyc * tau, kcyc, n - 1, len(stops) + 1))


if __name__ == "__main__":
    main()
