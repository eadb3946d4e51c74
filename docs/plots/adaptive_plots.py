#!/usr/bin/env python3
"""SVG figures for docs/adaptive-feed.md from the CSV traces of cncore_adaptive_figures.

    build/<dir>/tests/feedcontrol/cncore_adaptive_figures /tmp/adaptive
    python3 docs/plots/adaptive_plots.py /tmp/adaptive docs/plots

One SVG per anti-wind-up policy, four panels against path distance (depth of cut, feed, load,
integral term), all three on the same scales like the seed's figures. No dependencies.
"""
import csv
import math
import os
import sys

POLICIES = ["none", "clamp", "back_calculation"]
TITLES = {
    "none": "no output limit (seed Fig. 5)",
    "clamp": "output overwritten with the limit (seed Fig. 6)",
    "back_calculation": "back-calculated integral (seed Fig. 2)",
}
UPPER_FEED = 1500  # upper_pct 150 % of F 1000 mm/min (tests/feedcontrol/scenario.hpp)
JUMP_MM = 120
W, LEFT, RIGHT, PANEL_H, GAP, TOP = 640, 70, 12, 80, 22, 28


def read(path):
    with open(path, newline="") as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def nice_max(v):
    if v <= 0:
        return 1.0
    step = 10 ** math.floor(math.log10(v))
    for m in (1, 1.5, 2, 2.5, 3, 4, 5, 6, 8, 10):
        if m * step >= v:
            return m * step
    return 10 * step


def polyline(xs, ys, x_of, y_of, colour, dash=""):
    pts, last = [], None
    for x, y in zip(xs, ys):
        p = (round(x_of(x), 1), round(y_of(y), 1))
        if p != last:
            pts.append("%g,%g" % p)
            last = p
    d = ' stroke-dasharray="4 3"' if dash else ""
    return '<polyline fill="none" stroke="%s" stroke-width="1.2"%s points="%s"/>' % (
        colour, d, " ".join(pts))


def figure(policy, rows, scales):
    s_max = scales["s"]
    x_of = lambda s: LEFT + (W - LEFT - RIGHT) * s / s_max
    panels = [
        ("depth of cut [mm]", "depth_mm", scales["depth"], 0, "#8a5a00", None),
        ("feed [mm/min]", "feed_mm_min", scales["feed"], 0, "#1f5fbf", UPPER_FEED),
        ("load [%]", "load_pct", scales["load"], 0, "#c03020", rows[0]["target_pct"]),
        ("Ki·I [% override]", "integral_term_pct", scales["iterm"], scales["iterm_min"], "#2a8a2a", None),
    ]
    h = TOP + len(panels) * (PANEL_H + GAP) + 14
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
           'font-size="10">' % (W, h),
           '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="16" font-size="12">%s: %s</text>' % (LEFT, policy, TITLES[policy])]
    xs = [r["s_mm"] for r in rows]
    for i, (label, key, vmax, vmin, colour, ref) in enumerate(panels):
        y0 = TOP + i * (PANEL_H + GAP)
        y_of = lambda v, y0=y0, vmin=vmin, vmax=vmax: y0 + PANEL_H - PANEL_H * (
            min(max(v, vmin), vmax) - vmin) / (vmax - vmin)
        out.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#999"/>' % (
            LEFT, y0, W - LEFT - RIGHT, PANEL_H))
        out.append('<text x="%d" y="%d" text-anchor="end">%g</text>' % (LEFT - 4, y0 + 8, vmax))
        out.append('<text x="%d" y="%d" text-anchor="end">%g</text>' % (LEFT - 4, y0 + PANEL_H, vmin))
        out.append('<text x="%d" y="%d">%s</text>' % (LEFT + 4, y0 - 3, label))
        jx = round(x_of(JUMP_MM), 1)
        out.append('<line x1="%g" y1="%d" x2="%g" y2="%d" stroke="#bbb" stroke-dasharray="2 2"/>' % (
            jx, y0, jx, y0 + PANEL_H))
        if ref is not None:
            out.append(polyline([0, s_max], [ref, ref], x_of, y_of, "#555", dash=True))
        out.append(polyline(xs, [r[key] for r in rows], x_of, y_of, colour))
    yb = TOP + len(panels) * (PANEL_H + GAP) - GAP + 12
    for s in range(0, int(s_max) + 1, 40):
        out.append('<text x="%g" y="%d" text-anchor="middle">%d</text>' % (x_of(s), yb, s))
    out.append('<text x="%d" y="%d" text-anchor="end">path distance [mm]</text>' % (W - RIGHT, yb + 12))
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    src, dst = sys.argv[1], sys.argv[2]
    data = {p: read(os.path.join(src, "adaptive-%s.csv" % p)) for p in POLICIES}
    allrows = [r for rows in data.values() for r in rows]
    scales = {
        "s": nice_max(max(r["s_mm"] for r in allrows)),
        "depth": nice_max(max(r["depth_mm"] for r in allrows) * 1.1),
        "feed": nice_max(max(r["feed_mm_min"] for r in allrows)),
        "load": nice_max(max(r["load_pct"] for r in allrows)),
        "iterm": nice_max(max(r["integral_term_pct"] for r in allrows)),
        "iterm_min": -nice_max(-min(min(r["integral_term_pct"] for r in allrows), 0)),
    }
    for p, rows in data.items():
        rows = rows[::3]  # every 30 ms is plenty for 640 px
        path = os.path.join(dst, "adaptive-%s.svg" % p)
        with open(path, "w") as f:
            f.write(figure(p, rows, scales))
        print("%s: %d bytes" % (path, os.path.getsize(path)))


if __name__ == "__main__":
    main()
