#!/usr/bin/env python3
"""The web page's travel follows what a Grbl sender writes: `cncore serve --http --grbl-tcp`,
a sender writes $130=250 (X travel) over TCP; the page's status stream then carries a new
machine_serial and GET /api/machine (what the page fetches on it) has the new X travel.
  travel_test.py CNCORE"""
import json
import os
import re
import subprocess
import sys
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "grbl"))
from grbl_client import Client, _free_port  # noqa: E402

CNCORE = sys.argv[1]


def fail(why):
    print("FAIL:", why)
    sys.exit(1)


def x_travel(url):
    with urllib.request.urlopen(url + "api/machine", timeout=10) as r:
        axes = json.loads(r.read())["axes"]
    x = next(a for a in axes if a["name"] == "X")
    return x["max_mm"] - x["min_mm"]


def machine_serials(url, until, seconds=10):
    """The machine_serial of each status event, until `until(serial)` or the time is up."""
    seen = []
    end = time.time() + seconds
    with urllib.request.urlopen(url + "api/events", timeout=10) as r:
        while time.time() < end:
            line = r.readline().decode()
            if not line.startswith("data: "):
                continue
            seen.append(json.loads(line[6:])["machine_serial"])
            if until(seen[-1]):
                break
    return seen


port = _free_port()
proc = subprocess.Popen([CNCORE, "serve", "--no-state", "--no-realtime", "--http", "127.0.0.1:0",
                         "--grbl-tcp", f"127.0.0.1:{port}"],
                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                        text=True)
try:
    url = None
    deadline = time.time() + 20
    while url is None and time.time() < deadline:
        m = re.search(r"web page on (http://\S+)", proc.stdout.readline())
        url = m.group(1) if m else None
    if url is None:
        fail("no web page address printed")
    before = x_travel(url)
    first = machine_serials(url, lambda s: True)
    if first != [0]:
        fail(f"machine_serial before any write: {first}")
    c = Client.tcp(port)
    c.until("Grbl 1.1h")
    got = c.command("$130=250")
    if got[-1] != "ok":
        fail(f"$130=250 -> {got}")
    serials = machine_serials(url, lambda s: s >= 1)
    if not serials or serials[-1] != 1:
        fail(f"no new machine_serial after $130=250: {serials}")
    after = x_travel(url)
    if abs(after - 250) > 1e-9:
        fail(f"/api/machine X travel {after} mm after $130=250 (was {before})")
    print(f"ok: X travel {before:.1f} -> {after:.1f} mm; machine_serial 0 -> 1 in the status stream")
    c.close()
finally:
    proc.terminate()
    proc.wait(timeout=20)
