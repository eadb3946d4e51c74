#!/usr/bin/env python3
"""The token rule of `cncore serve --http`: a non-loopback address without a token is refused at
start; with a token, every control needs it (403 without or with a wrong one, no effect on the
machine) while viewers read the page, the status stream and the program without it.
  token_test.py CNCORE"""
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

CNCORE = sys.argv[1]
TOKEN = "s3cret-token"


def fail(why):
    print("FAIL:", why)
    sys.exit(1)


def request(url, body=None, token=None, method=None, headers=None):
    h = dict(headers or {})
    if body is not None:
        h.setdefault("Content-Type", "application/json")
    if token is not None:
        h["Authorization"] = "Bearer " + token
    req = urllib.request.Request(url, data=None if body is None else body.encode(), headers=h,
                                 method=method or ("POST" if body is not None else "GET"))
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, r.read(200000).decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


def serve(*args):
    p = subprocess.Popen([CNCORE, "serve", "--no-state", "--no-realtime", *args],
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True)
    line = ""
    deadline = time.time() + 20
    while time.time() < deadline:
        line = p.stdout.readline()
        m = re.search(r"web page on (http://\S+)", line)
        if m:
            return p, m.group(1)
        if not line and p.poll() is not None:
            break
    p.kill()
    fail("no web page address printed; last line: " + line)
    return None, None


def first_event(url):
    with urllib.request.urlopen(url + "api/events", timeout=10) as r:
        line = r.readline().decode()
        if not line.startswith("data: "):
            fail("not an event: " + line)
        return json.loads(line[6:])["status"]


# 1. Not loopback, no token: refused at start, exit 2, a message that says why.
r = subprocess.run([CNCORE, "serve", "--no-state", "--no-realtime", "--http", "0.0.0.0:0"],
                   stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=30)
if r.returncode != 2 or "token" not in r.stderr:
    fail(f"0.0.0.0 without a token: exit {r.returncode}, stderr {r.stderr!r}")
print("non-loopback without a token refused:", r.stderr.strip().splitlines()[0])

# 2. With a token (from a file): viewers read, controls need the token.
with tempfile.TemporaryDirectory() as tmp:
    token_file = os.path.join(tmp, "token")
    with open(token_file, "w") as f:
        f.write(TOKEN + "\n")
    proc, url = serve("--http", "127.0.0.1:0", "--http-token-file", token_file)
    try:
        for path in ["", "app.js", "api/machine", "api/program"]:
            code, _ = request(url + path)
            if code != 200:
                fail(f"GET /{path} without the token: {code}")
        if first_event(url)["state"] != "Idle":
            fail("the status stream without the token")
        code, text = request(url + "api/session")
        if json.loads(text) != {"token_required": True, "authorized": False}:
            fail("session without the token: " + text)
        code, text = request(url + "api/session", token=TOKEN)
        if not json.loads(text)["authorized"]:
            fail("session with the token: " + text)
        jog = json.dumps({"mode": "inc", "axes": {"x": 5}})
        for token in [None, "wrong", TOKEN[:-1]]:
            for name, body in [("jog", jog), ("estop", "{}"), ("mdi", '{"line":"G0 X1"}')]:
                code, text = request(url + "api/" + name, body, token=token)
                if code != 403:
                    fail(f"POST {name} with token {token!r}: {code} {text}")
            code, _ = request(url + "api/program?name=a.ngc", "G0 X1\n", token=token,
                              headers={"Content-Type": "text/plain"})
            if code != 403:
                fail(f"upload with token {token!r}: {code}")
        time.sleep(0.3)
        s = first_event(url)
        if s["state"] != "Idle" or s["machine"]["x"] != 0 or s["program_loaded"]:
            fail("a refused control had an effect: " + json.dumps(s))
        print("controls without the right token: 403, no effect")
        # A control from another site's page (its Origin) is refused even with the token.
        code, _ = request(url + "api/estop", "{}", token=TOKEN,
                          headers={"Origin": "http://example.invalid"})
        if code != 403:
            fail(f"a control with another Origin: {code}")
        code, text = request(url + "api/jog", jog, token=TOKEN)
        if code != 200:
            fail(f"jog with the token: {code} {text}")
        deadline = time.time() + 10
        while time.time() < deadline:
            s = first_event(url)
            if s["state"] == "Idle" and abs(s["machine"]["x"] - 5) < 1e-9:
                break
            time.sleep(0.05)
        else:
            fail("the jog with the token did not end at X5: " + json.dumps(s))
        code, text = request(url + "api/override", '{"feed_pct": 900}', token=TOKEN)
        if code != 409 or "between" not in text:
            fail(f"a refused override: {code} {text}")
        code, text = request(url + "api/frobnicate", "{}", token=TOKEN)
        if code != 404:
            fail(f"unknown control: {code} {text}")
        print("controls with the token act; refusals carry the controller's reason")
    finally:
        proc.terminate()
        if proc.wait(timeout=30) != 0:
            fail("cncore serve did not exit 0 on SIGTERM")
print("hmi token test: passed")
