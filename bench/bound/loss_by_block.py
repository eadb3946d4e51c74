#!/usr/bin/env python3
"""Where a run loses time against the bound, per source line.

  loss_by_block.py PROGRAM --cncore BIN --bound BIN [--accdec TYPE] [--machine M.toml] [--top N]
                   [--model MODEL] [--out FILE.tsv]

Runs `cncore run PROGRAM --mode lookahead --accdec TYPE --trajectory T.csv` and
`cncore-bound PROGRAM --per-block B.tsv`, then counts the run's cycles per source line (the CSV's
`line` column: the block the sample lies in) against the bound's time of the same line's
segments. Prints the totals, the loss grouped by the kind of stretch (see `kind_of`), and the
worst lines. Times in s.
"""
import argparse
import collections
import csv
import os

import per_block


def kind_of(seg, prev):
    """A coarse class of a segment by what limits it in the bound."""
    if seg["kind"] == "arc":
        return "arc"
    v_top = max(seg["v_in"], seg["v_out"])
    cap = seg["cap"]
    # Reaching the cap: a cruise segment (long); else ramps only.
    reaches = abs(seg["peak"] - cap) < 1e-6 * max(cap, 1)
    if seg["v_out"] == 0 and seg["join_cap"] == 0:
        tag = "stop"
    elif reaches:
        tag = "cruise"
    else:
        tag = "ramp"
    # Short: the segment is shorter than one cycle at its peak speed.
    return tag + ("/short<1cycle" if seg["length"] < seg["peak"] * seg["tau"] else "")


def main():
    ap = argparse.ArgumentParser()
    per_block.add_run_options(ap, reuse=False)
    ap.add_argument("--model")
    ap.add_argument("--top", type=int, default=8)
    ap.add_argument("--out")
    a = ap.parse_args()
    traj, per = per_block.run_and_bound(a, "lossbb", ["--model", a.model] if a.model else [])
    run_t = collections.Counter()
    tau = None
    last_t = 0.0
    n = 0
    with open(traj) as f:
        r = csv.reader(f)
        next(r)
        prev_t = None
        for row in r:
            t = float(row[0])
            if prev_t is not None and tau is None:
                tau = t - prev_t
            prev_t = t
            if n > 0:
                run_t[int(row[1])] += 1  # the cycle that ends in this line
            n += 1
            last_t = t
    tau = tau or 0.001
    for k in run_t:
        run_t[k] *= tau
    segs = []
    with open(per) as f:
        r = csv.DictReader(f, delimiter="\t")
        for row in r:
            s = dict(line=int(row["line"]), kind=row["kind"], length=float(row["length_mm"]),
                     cap=float(row["cap_mm_s"]), v_in=float(row["v_in_mm_s"]),
                     v_out=float(row["v_out_mm_s"]), join_cap=float(row["join_cap_mm_s"]),
                     time=float(row["time_s"]), tau=tau)
            # Peak speed of the accelerate-cruise-decelerate profile (A from the time is not
            # known here; use the cap when the segment averages close to it).
            s["peak"] = s["cap"] if s["time"] > 0 and s["length"] / s["time"] > 0.999 * s["cap"] else \
                max(s["v_in"], s["v_out"], 2 * s["length"] / s["time"] - min(s["v_in"], s["v_out"]) if s["time"] > 0 else 0)
            segs.append(s)
    bound_t = collections.Counter()
    kind_line = {}
    for i, s in enumerate(segs):
        bound_t[s["line"]] += s["time"]
        kind_line.setdefault(s["line"], kind_of(s, segs[i - 1] if i else None))
    lines = sorted(set(run_t) | set(bound_t))
    total_run = sum(run_t.values())
    total_bound = sum(bound_t.values())
    by_kind = collections.defaultdict(lambda: [0, 0.0, 0.0])
    rows = []
    for ln in lines:
        k = kind_line.get(ln, "no-motion")
        by_kind[k][0] += 1
        by_kind[k][1] += run_t[ln]
        by_kind[k][2] += bound_t[ln]
        rows.append((run_t[ln] - bound_t[ln], ln, k, run_t[ln], bound_t[ln]))
    print(f"{os.path.basename(a.program)}: run {total_run:.3f} s, bound {total_bound:.3f} s, "
          f"ratio {total_run / total_bound:.3f}, loss {total_run - total_bound:.3f} s")
    print("  kind                    lines   run_s    bound_s  loss_s  share")
    loss = total_run - total_bound
    for k, (c, rt, bt) in sorted(by_kind.items(), key=lambda kv: -(kv[1][1] - kv[1][2])):
        print(f"  {k:22s} {c:6d} {rt:9.3f} {bt:9.3f} {rt - bt:7.3f} {100 * (rt - bt) / loss if loss else 0:5.1f}%")
    rows.sort(reverse=True)
    print("  worst lines: line kind run_s bound_s")
    for d, ln, k, rt, bt in rows[: a.top]:
        print(f"    {ln:6d} {k:20s} {rt:.4f} {bt:.4f} (+{d:.4f})")
    if a.out:
        with open(a.out, "w") as f:
            f.write("line\tkind\trun_s\tbound_s\n")
            for ln in lines:
                f.write(f"{ln}\t{kind_line.get(ln, 'no-motion')}\t{run_t[ln]:.6f}\t{bound_t[ln]:.9f}\n")


if __name__ == "__main__":
    main()
