#!/usr/bin/env python3
"""Streams G-code files to `cncore serve --grbl-tcp` as a character-counting sender does
(tests/grbl/sender.py: 127-byte budget, `?` at 10 Hz) and compares the served motion time with
`cncore run` on the same file (both from their trajectories: first to last cycle that moves).

    tools/grbl-stream-time.py CNCORE [FILE.ngc ...]

Without files it writes and streams the r 50 mm F3000 circles of 1 000 and 36 000 chords that
docs/senders.md quotes."""
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "grbl"))
from stream_measure import motion_time, run_time, stream_file  # noqa: E402


def circle(path, chords):
    with open(path, "w") as f:
        f.write("G21 G90 G17\nG0 X50 Y0\nG1 F3000\n")
        for i in range(1, chords + 1):
            a = 2 * math.pi * i / chords
            f.write(f"X{50 * math.cos(a):.4f} Y{50 * math.sin(a):.4f}\n")
        f.write("M2\n")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    cncore = os.path.abspath(sys.argv[1])
    with tempfile.TemporaryDirectory() as tmp:
        files = sys.argv[2:]
        if not files:
            for n in (1000, 36000):
                files.append(os.path.join(tmp, f"circle{n}.ngc"))
                circle(files[-1], n)
        print(f"{'program':<16} {'run s':>8} {'streamed s':>11} {'ratio':>6}  final position")
        for path in files:
            work = tempfile.mkdtemp(dir=tmp)
            t_run, end_run = run_time(cncore, path, work)
            sender, rows = stream_file(cncore, path, work)
            t_served = motion_time(rows)
            same = all(abs(a - b) < 1e-6 for a, b in zip(rows[-1][1:], end_run))
            print(f"{os.path.basename(path):<16} {t_run:8.3f} {t_served:11.3f} "
                  f"{t_served / t_run:6.3f}  {'same as run' if same else 'DIFFERS'}"
                  + (f"  errors {sender.errors}" if sender.errors else ""))


if __name__ == "__main__":
    main()
