#!/usr/bin/env python3
"""SVG figure for docs/direction-correction.md: the coefficient C against FI.

    python3 docs/plots/direction_correction_plot.py docs/plots [build/<dir>/src/app/cncore]

Lines: the default law C = 1 + 0.5*FI (both branches) and the ball-end example of the doc
(uphill: ratio of effective cutting diameters, capped at 1.5; downhill: max(0.5, 1 + 0.8*FI)).
With the cncore binary, also markers measured on real runs: for slopes at several angles the
steady path speed (finite differences of the trajectory positions, middle 60 % of the move)
divided by the programmed feed. No dependencies.
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

W, H, LEFT, RIGHT, TOP, BOTTOM = 640, 400, 60, 20, 30, 50
FI_RANGE = (-1.0, 1.0)
C_RANGE = (0.0, 2.0)


def default_law(fi):
    return 1 + 0.5 * fi


def ball_end_law(fi, d=10.0, ap=0.5):
    if fi < 0:
        return max(0.5, 1 + 0.8 * fi)
    t0 = math.acos(1 - 2 * ap / d)
    return min(1.5, math.sin(math.asin(fi) + t0) / math.sin(t0))


def x_of(fi):
    return LEFT + (fi - FI_RANGE[0]) / (FI_RANGE[1] - FI_RANGE[0]) * (W - LEFT - RIGHT)


def y_of(c):
    return TOP + (C_RANGE[1] - c) / (C_RANGE[1] - C_RANGE[0]) * (H - TOP - BOTTOM)


def polyline(f, colour, width=2, dash=""):
    pts = []
    for i in range(401):
        fi = FI_RANGE[0] + (FI_RANGE[1] - FI_RANGE[0]) * i / 400
        pts.append(f"{x_of(fi):.1f},{y_of(f(fi)):.1f}")
    d = f' stroke-dasharray="{dash}"' if dash else ""
    return (f'<polyline fill="none" stroke="{colour}" stroke-width="{width}"{d} '
            f'points="{" ".join(pts)}"/>')


def measure(cncore, angles_deg):
    """(FI, C measured) for straight moves at the given slope angles, default law, F1000."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        toml = os.path.join(tmp, "m.toml")
        with open(toml, "w") as f:
            f.write("[direction_correction]\nenabled = true\n")
        for a in angles_deg:
            dx, dz = 60 * math.cos(math.radians(a)), 60 * math.sin(math.radians(a))
            prog = os.path.join(tmp, "p.ngc")
            with open(prog, "w") as f:
                f.write(f"G21 G90\nG0 X0 Y0 Z-60\nG1 X{dx:.6f} Z{-60 + dz:.6f} F1000\nM30\n")
            csv_path = os.path.join(tmp, "t.csv")
            subprocess.run([cncore, "run", prog, "--machine", toml, "--trajectory", csv_path],
                           check=True, stdout=subprocess.DEVNULL)
            with open(csv_path, newline="") as f:
                rows = [r for r in csv.DictReader(f) if r["line"] == "3"]
            n = len(rows)
            speeds = []
            for k in range(n // 5 + 1, n - n // 5):
                p, q = rows[k - 1], rows[k]
                d = math.dist([float(p[c]) for c in "xyz"], [float(q[c]) for c in "xyz"])
                speeds.append(d / (float(q["t"]) - float(p["t"])) * 60)
            out.append((math.sin(math.radians(a)), sum(speeds) / len(speeds) / 1000))
    return out


def main():
    outdir = sys.argv[1] if len(sys.argv) > 1 else "."
    cncore = sys.argv[2] if len(sys.argv) > 2 else None
    s = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
         f'font-family="sans-serif" font-size="12">',
         f'<rect width="{W}" height="{H}" fill="white"/>']
    for c in [0, 0.5, 1, 1.5, 2]:
        s.append(f'<line x1="{LEFT}" y1="{y_of(c):.1f}" x2="{W - RIGHT}" y2="{y_of(c):.1f}" '
                 f'stroke="#ddd"/>')
        s.append(f'<text x="{LEFT - 8}" y="{y_of(c) + 4:.1f}" text-anchor="end">{c:g}</text>')
    for fi in [-1, -0.5, 0, 0.5, 1]:
        s.append(f'<line x1="{x_of(fi):.1f}" y1="{TOP}" x2="{x_of(fi):.1f}" y2="{H - BOTTOM}" '
                 f'stroke="#ddd"/>')
        s.append(f'<text x="{x_of(fi):.1f}" y="{H - BOTTOM + 16}" text-anchor="middle">{fi:g}</text>')
    s.append(f'<text x="{(LEFT + W - RIGHT) / 2}" y="{H - 12}" text-anchor="middle">'
             f'FI = direction of motion · u (−1 straight down, 0 level, +1 straight up)</text>')
    s.append(f'<text x="16" y="{(TOP + H - BOTTOM) / 2}" text-anchor="middle" '
             f'transform="rotate(-90 16 {(TOP + H - BOTTOM) / 2})">correction coefficient C</text>')
    s.append(f'<text x="{LEFT}" y="18" font-weight="bold">Feed correction by direction: '
             f'C against FI</text>')
    s.append(polyline(default_law, "#1f77b4", 2.5))
    s.append(polyline(ball_end_law, "#d62728", 2, "6 4"))
    legend = [("#1f77b4", "", "default: C = 1 + 0.5·FI (uphill and downhill)"),
              ("#d62728", "6 4", "ball-end example (D 10, ap 0.5): eff. diameter, max(0.5, 1+0.8·FI)")]
    if cncore:
        pts = measure(cncore, [-90, -60, -30, -20, -10, 0, 10, 20, 30, 60, 90])
        for fi, c in pts:
            s.append(f'<circle cx="{x_of(fi):.1f}" cy="{y_of(c):.1f}" r="4" fill="none" '
                     f'stroke="black" stroke-width="1.5"/>')
        legend.append(("black", "o", "measured: steady speed / F on cncore runs (default law)"))
        with open(os.path.join(outdir, "direction_correction_measured.csv"), "w") as f:
            f.write("fi,c_measured,c_default\n")
            for fi, c in pts:
                f.write(f"{fi:.6f},{c:.6f},{default_law(fi):.6f}\n")
    for i, (colour, dash, text) in enumerate(legend):
        y = TOP + 14 + 18 * i
        if dash == "o":
            s.append(f'<circle cx="{LEFT + 24}" cy="{y - 4}" r="4" fill="none" stroke="{colour}" '
                     f'stroke-width="1.5"/>')
        else:
            d = f' stroke-dasharray="{dash}"' if dash else ""
            s.append(f'<line x1="{LEFT + 10}" y1="{y - 4}" x2="{LEFT + 38}" y2="{y - 4}" '
                     f'stroke="{colour}" stroke-width="2"{d}/>')
        s.append(f'<text x="{LEFT + 46}" y="{y}">{text}</text>')
    s.append("</svg>")
    with open(os.path.join(outdir, "direction_correction.svg"), "w") as f:
        f.write("\n".join(s) + "\n")


if __name__ == "__main__":
    main()
