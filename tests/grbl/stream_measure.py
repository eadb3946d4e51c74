"""Streams a G-code file to `cncore serve --grbl-tcp` with the sender of sender.py (character
counting, `?` at 10 Hz) and compares the motion time of the served trajectory with `cncore run`
on the same file. Used by grbl_stream_test.py and tools/grbl-stream-time.py."""
import csv
import math
import os
import subprocess

from grbl_client import Client, Server
from sender import Sender


def read_trajectory(path):
    """Rows of a trajectory CSV as (t_s, x, y, z)."""
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.append((float(r["t"]), float(r["x"]), float(r["y"]), float(r["z"])))
    return rows


def motion_time(rows):
    """Seconds from the first cycle that moves to the last one (position changes between rows)."""
    moving = [i for i in range(1, len(rows)) if rows[i][1:] != rows[i - 1][1:]]
    if not moving:
        return 0.0
    return rows[moving[-1]][0] - rows[moving[0] - 1][0]


def max_speed_mm_min(rows):
    """Highest path speed by finite differences of consecutive set-points."""
    best = 0.0
    for a, b in zip(rows, rows[1:]):
        dt = b[0] - a[0]
        if dt > 0:
            best = max(best, math.dist(a[1:], b[1:]) / dt * 60)
    return best


def run_time(cncore, program, workdir):
    """`cncore run` on the program: its motion time and final position."""
    traj = os.path.join(workdir, "run.csv")
    subprocess.run([cncore, "run", program, "--trajectory", traj], check=True,
                   stdout=subprocess.DEVNULL)
    rows = read_trajectory(traj)
    return motion_time(rows), rows[-1][1:]


def stream_file(cncore, program, workdir, actions=None, machine=None):
    """Streams the program over TCP; returns (sender, served trajectory rows)."""
    traj = os.path.join(workdir, "served.csv")
    server = Server(cncore, workdir, machine=machine, extra=["--trajectory", traj])
    try:
        c = Client.tcp(server.port)
        s = Sender(c)
        s.handshake()
        with open(program) as f:
            lines = [ln for ln in (x.strip() for x in f) if ln]
        s.stream(lines, actions=actions)
        c.close()
    finally:
        server.stop()
    return s, read_trajectory(traj)
