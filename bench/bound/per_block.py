"""Shared by the scripts of bench/bound: the `cncore-bound --per-block` TSV of a program of lines,
points along its path for the trajectory CSV they write, and running `cncore run` and
`cncore-bound` on a program."""
import csv
import math
import os
import subprocess
import sys
import tempfile


def add_run_options(ap, reuse=True):
    """The program and the tools of a script that compares a run with the bound; reuse: also
    --traj / --per-block, files of an earlier run used instead of running again."""
    ap.add_argument("program")
    ap.add_argument("--cncore", required=True)
    ap.add_argument("--bound", required=True)
    ap.add_argument("--accdec", default="acceleration")
    ap.add_argument("--machine")
    if reuse:
        ap.add_argument("--traj")
        ap.add_argument("--per-block")


def run_and_bound(a, prefix, bound_options=()):
    """(trajectory CSV, per-block TSV) of the program: `cncore run --mode lookahead` and
    `cncore-bound --per-block` into a temporary folder, unless --traj / --per-block name them."""
    tmp = tempfile.mkdtemp(prefix=prefix)
    traj = getattr(a, "traj", None) or os.path.join(tmp, "t.csv")
    per = getattr(a, "per_block", None) or os.path.join(tmp, "b.tsv")
    mach = ["--machine", a.machine] if a.machine else []
    if not getattr(a, "traj", None):
        subprocess.run([a.cncore, "run", a.program, "--mode", "lookahead", "--accdec", a.accdec,
                        "--trajectory", traj] + mach, check=True, stdout=subprocess.DEVNULL)
    if not getattr(a, "per_block", None):
        subprocess.run([a.bound, a.program, "--per-block", per] + mach + list(bound_options),
                       check=True, stdout=subprocess.DEVNULL)
    return traj, per


def read_blocks(path):
    """Every block of a per-block TSV as a dict (line, kind, L, cap, v0, v1, J, time, p0, p1)."""
    blocks = []
    with open(path) as f:
        for r in csv.DictReader(f, delimiter="\t"):
            blocks.append(dict(line=int(r["line"]), kind=r["kind"], L=float(r["length_mm"]),
                               cap=float(r["cap_mm_s"]), v0=float(r["v_in_mm_s"]),
                               v1=float(r["v_out_mm_s"]), J=float(r["join_cap_mm_s"]),
                               time=float(r["time_s"]),
                               p0=[float(r["x0"]), float(r["y0"]), float(r["z0"])],
                               p1=[float(r["x1"]), float(r["y1"]), float(r["z1"])]))
    return blocks


def read_lines(path, tool):
    """read_blocks() of a program of lines, with u = v1 (the speed out); arcs are refused."""
    segs = read_blocks(path)
    for seg in segs:
        if seg["kind"] != "line":
            sys.exit("%s: arcs are not handled (line %s)" % (tool, seg["line"]))
        seg["u"] = seg["v1"]
    return segs


def unit(seg):
    """The block's direction (0 for a zero-length block)."""
    d = [seg["p1"][i] - seg["p0"][i] for i in range(3)]
    l = math.sqrt(sum(x * x for x in d))
    return [x / l for x in d] if l > 0 else [0.0, 0.0, 0.0]


def starts(segs):
    """Path position of every block's start, and the path's length last."""
    s = [0.0]
    for seg in segs:
        s.append(s[-1] + seg["L"])
    return s


class PathPoints:
    """(line, [x, y, z]) at path position sv; a cursor, cheap for positions close together."""

    def __init__(self, segs):
        self.segs, self.s, self.i = segs, starts(segs), 0

    def at(self, sv):
        n = len(self.segs)
        while self.i + 1 < n and self.s[self.i + 1] < sv:
            self.i += 1
        while self.i > 0 and self.s[self.i] > sv:
            self.i -= 1
        seg = self.segs[self.i]
        f = 0.0 if seg["L"] <= 0 else min(1.0, max(0.0, (sv - self.s[self.i]) / seg["L"]))
        return seg["line"], [seg["p0"][j] + f * (seg["p1"][j] - seg["p0"][j]) for j in range(3)]


class TrajectoryCsv:
    """The `t,line,x,y,z` CSV cncore-trajcheck reads."""

    def __init__(self, path):
        self.f = open(path, "w")
        self.f.write("t,line,x,y,z\n")

    def row(self, t, line, xyz):
        self.f.write("%.6f,%d,%.10f,%.10f,%.10f\n" % (t, line, *xyz))

    def close(self):
        self.f.close()
