#!/usr/bin/env python3
"""SVG plots of docs/lookahead.md: path speed and tangential acceleration against time, look-ahead
and stop mode on the same axes, from two trajectory CSVs of `cncore run --trajectory`.

    cncore run examples/seed-line-arc-line.ngc --mode lookahead --trajectory /tmp/look.csv
    cncore run examples/seed-line-arc-line.ngc --mode stop --trajectory /tmp/stop.csv
    python3 tools/plot_lookahead.py /tmp/look.csv /tmp/stop.csv docs/plots

Writes OUT/lookahead_speed.svg and OUT/lookahead_accel.svg. Everything is measured from the
positions by finite differences (not from the kernel's feed column), like the trajectory checker:
  speed v[k] = |P[k] - P[k-1]| / tau        (chord over X Y Z; on the R 5 arc at 133 mm/s the
                                             chord is shorter than the arc by 1e-5 relative)
  tangential acceleration a[k] = (v[k+1] - v[k]) / tau
Positions are printed with 6 decimals (+-5e-7 mm), so v carries up to +-1e-3 mm/s and a up to
+-2 mm/s^2 of rounding. Optional reference lines (--ref-speed, --ref-accel) are drawn dashed.
No third-party packages.
"""
import argparse
import csv
import math
import os

W, H = 720, 330
LEFT, RIGHT, TOP, BOTTOM = 70, 16, 34, 46
COLOURS = {"look-ahead": "#1f5fbf", "stop": "#c03020", "moving average": "#1f5fbf",
           "acceleration": "#c03020", "search": "#2a9a40"}


def read_positions(path):
    """(t_s, [(x, y, z)], line) rows of a trajectory CSV; missing axes count as 0."""
    ts, ps, lines = [], [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            ts.append(float(row["t"]))
            ps.append(tuple(float(row.get(a) or 0.0) for a in ("x", "y", "z")))
            lines.append(int(row["line"]))
    return ts, ps, lines


def speed_accel(ts, ps):
    tau = ts[1] - ts[0] if len(ts) > 1 else 0.001
    v = [0.0] + [math.dist(ps[k], ps[k - 1]) / tau for k in range(1, len(ps))]
    a = [(v[k + 1] - v[k]) / tau for k in range(len(v) - 1)] + [0.0]
    return tau, v, a


def nice_step(span):
    raw = span / 6.0
    step = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 2.5, 5, 10):
        if m * step >= raw:
            return m * step
    return 10 * step


def fmt(v):
    return ("%.3f" % v).rstrip("0").rstrip(".") if abs(v) < 1e6 else "%g" % v


def plot(path, title, y_label, series, x_max, y_min, y_max, refs):
    """series: [(name, xs, ys)]; refs: [(y, label)] dashed horizontal lines."""
    pw, ph = W - LEFT - RIGHT, H - TOP - BOTTOM
    x_of = lambda x: LEFT + pw * x / x_max
    y_of = lambda y: TOP + ph * (y_max - y) / (y_max - y_min)
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
           'viewBox="0 0 %d %d" font-family="sans-serif" font-size="11">' % (W, H, W, H),
           '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="18" font-size="13">%s</text>' % (LEFT, title)]
    # Grid and ticks.
    xs = nice_step(x_max)
    k = 0
    while k * xs <= x_max + 1e-9:
        x = x_of(k * xs)
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#e4e4e4"/>' % (x, TOP, x, TOP + ph))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (x, TOP + ph + 15, fmt(k * xs)))
        k += 1
    ys = nice_step(y_max - y_min)
    k = math.ceil(y_min / ys)
    while k * ys <= y_max + 1e-9:
        y = y_of(k * ys)
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="%s"/>' % (
            LEFT, y, LEFT + pw, y, "#999" if k == 0 else "#e4e4e4"))
        out.append('<text x="%d" y="%.1f" text-anchor="end">%s</text>' % (LEFT - 5, y + 4, fmt(k * ys)))
        k += 1
    out.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#444"/>' % (LEFT, TOP, pw, ph))
    out.append('<text x="%.1f" y="%d" text-anchor="middle">time [s]</text>' % (LEFT + pw / 2, H - 10))
    out.append('<text transform="translate(16,%.1f) rotate(-90)" text-anchor="middle">%s</text>' % (
        TOP + ph / 2, y_label))
    for y, label in refs:
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#555" stroke-dasharray="5 4"/>' % (
            LEFT, y_of(y), LEFT + pw, y_of(y)))
        out.append('<text x="%d" y="%.1f" text-anchor="end" fill="#555">%s</text>' % (
            LEFT + pw - 4, y_of(y) - 4, label))
    # Curves (points that fall on the same pixel are dropped).
    for i, (name, xv, yv) in enumerate(series):
        pts, last = [], None
        for x, y in zip(xv, yv):
            p = (round(x_of(x), 1), round(y_of(y), 1))
            if p != last:
                pts.append("%g,%g" % p)
                last = p
        out.append('<polyline fill="none" stroke="%s" stroke-width="1.3" points="%s"/>' % (
            COLOURS.get(name, "#000"), " ".join(pts)))
        lx, ly = LEFT + 10, TOP + 16 + 15 * i
        out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"/>' % (
            lx, ly - 4, lx + 22, ly - 4, COLOURS.get(name, "#000")))
        out.append('<text x="%d" y="%d">%s</text>' % (lx + 28, ly, name))
    out.append("</svg>\n")
    with open(path, "w") as f:
        f.write("\n".join(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("lookahead_csv")
    ap.add_argument("stop_csv")
    ap.add_argument("out_dir")
    ap.add_argument("--title", default="seed example (line, R 5 arc, line; F8000)")
    ap.add_argument("--ref-speed", action="append", default=[], metavar="MM_S:LABEL",
                    help="dashed reference line on the speed plot")
    ap.add_argument("--ref-accel", action="append", default=[], metavar="MM_S2:LABEL",
                    help="dashed reference line on the acceleration plot")
    ap.add_argument("--labels", default="look-ahead,stop", metavar="A,B",
                    help="names of the two runs (e.g. 'moving average,acceleration')")
    ap.add_argument("--prefix", default="lookahead", help="file names PREFIX_speed/_accel.svg")
    ap.add_argument("--extra", action="append", default=[], metavar="CSV:LABEL",
                    help="a further run on the same plots (e.g. 'search.csv:search')")
    args = ap.parse_args()
    label_a, _, label_b = args.labels.partition(",")

    runs = []
    inputs = [(label_a, args.lookahead_csv), (label_b, args.stop_csv)]
    for item in args.extra:
        path, _, name = item.rpartition(":")
        inputs.append((name, path))
    for name, path in inputs:
        ts, ps, _ = read_positions(path)
        _, v, a = speed_accel(ts, ps)
        runs.append((name, ts, v, a))
        print("%s: cycle time %.3f s (%d samples), max speed %.2f mm/s, |a| max %.1f mm/s^2" % (
            name, ts[-1], len(ts), max(v), max(abs(x) for x in a)))

    def refs(items):
        out = []
        for item in items:
            value, _, label = item.partition(":")
            out.append((float(value), label))
        return out

    x_max = max(r[1][-1] for r in runs)
    v_max = max(max(r[2]) for r in runs)
    a_abs = max(max(abs(x) for x in r[3]) for r in runs)
    rs, ra = refs(args.ref_speed), refs(args.ref_accel)
    v_top = max([v_max] + [y for y, _ in rs]) * 1.1
    a_top = max([a_abs] + [abs(y) for y, _ in ra]) * 1.12
    os.makedirs(args.out_dir, exist_ok=True)
    times = ", ".join("%s %.3f s" % (r[0], r[1][-1]) for r in runs)
    plot(os.path.join(args.out_dir, args.prefix + "_speed.svg"),
         "Path speed, %s: %s" % (args.title, times), "path speed [mm/s]",
         [(r[0], r[1], r[2]) for r in runs], x_max, 0, v_top, rs)
    plot(os.path.join(args.out_dir, args.prefix + "_accel.svg"),
         "Tangential acceleration, %s" % args.title, "tangential acceleration [mm/s²]",
         [(r[0], r[1], r[3]) for r in runs], x_max, -a_top, a_top, ra)


if __name__ == "__main__":
    main()
