#!/usr/bin/env python3
"""Protocol tests of cncore serve's Grbl 1.1 endpoints, over TCP and over the pseudo-terminal:
every command, real-time byte, error and alarm code the endpoint implements (docs/senders.md).
    grbl_protocol_test.py CNCORE
Measured outcomes: positions, states and override values come from status reports after the
machine moved; settings from $$ after writes and from the state folder after a restart."""
import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from grbl_client import Client, Server, field, position  # noqa: E402

WELCOME = "Grbl 1.1h ['$' for help]"
FAILS = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        FAILS.append(what)


def expect_reply(c, line, reply, what=None):
    got = c.command(line)
    check(got[-1] == reply, f"{what or line!r} -> {reply} (got {got})")
    return got


MACHINE = """
[servo]
home_search_mm_min = 9000
home_latch_mm_min = 600

[probe]
boxes = [[-50, -50, -30, 50, 50, -2]]
"""


def connect_checks(c, how):
    c.until("^" + __import__("re").escape(WELCOME) + "$")
    check(True, f"{how}: welcome line on connect")
    got = expect_reply(c, "$I", "ok", f"{how}: $I")
    check(any(x.startswith("[VER:1.1h") for x in got), f"{how}: [VER:…]")
    check("[OPT:V,64,128]" in got, f"{how}: [OPT:V,64,128] (64 lines of stream queue)")
    got = expect_reply(c, "$", "ok", f"{how}: $ help")
    check(any(x.startswith("[HLP:") for x in got), f"{how}: [HLP:…]")
    rep = c.status()
    check(rep.startswith("<Idle|MPos:"), f"{how}: ? gives an Idle status report ({rep})")


def rapid_top_speed(c):
    """The highest FS: feed seen while `G0 X100` runs (then back to X0)."""
    expect_reply(c, "G0 X100", "ok")
    top = 0.0
    rep = c.wait_state("Run")
    end = time.time() + 10
    while not rep.startswith("<Idle") and time.time() < end:
        top = max(top, float(field(rep, "FS").split(",")[0]))
        rep = c.status()
    expect_reply(c, "G0 X0", "ok")
    c.wait_state("Idle")
    return top


def test_settings(c, workdir):
    got = expect_reply(c, "$$", "ok")
    d = dict(x[1:].split("=", 1) for x in got[:-1])
    check(d.get("110") == "15000" and d.get("120") == "2000",
          f"$$ maps $110/$120 to the machine (got {d.get('110')}, {d.get('120')})")
    check(d.get("130") == "600" and d.get("11") == "0.010", "$130 travel, $11 contour tolerance")
    expect_reply(c, "$110=5000", "ok")
    # The write changes the running machine at once: a rapid along X runs at 5000 mm/min.
    top = rapid_top_speed(c)
    check(4900 < top <= 5000.5, f"after $110=5000 the X rapid runs at 5000 mm/min ({top})")
    expect_reply(c, "$100=80", "ok", "$100 steps/mm accepted")
    expect_reply(c, "$110=-1", "error:4")
    expect_reply(c, "$20=0", "error:3", "$20=0 (soft limits always on)")
    expect_reply(c, "$999=1", "error:3")
    expect_reply(c, "$110=abc", "error:2")
    expect_reply(c, "$Q", "error:3")
    got = expect_reply(c, "$$", "ok")
    check("$110=5000" in got and "$100=80" in got, "$$ shows the written values")
    saved = json.load(open(os.path.join(workdir, "state", "grbl.json")))
    check(saved["settings"]["110"] == 5000, "the write persists in the state folder")
    got = expect_reply(c, "$G", "ok")
    check(got[0].startswith("[GC:"), "$G -> [GC:…]")
    got = expect_reply(c, "$#", "ok")
    check(got[0].startswith("[G54:") and any(x.startswith("[PRB:") for x in got), "$# offsets")
    expect_reply(c, "$N0=G21 G90", "ok")
    got = expect_reply(c, "$N", "ok")
    check("$N0=G21 G90" in got, "$N lists the startup line")
    c.send(b"\x18")
    got = c.until(r"^>G21 G90:")
    check(WELCOME in got and got[-1] == ">G21 G90:ok", "soft reset: welcome, then the startup line")
    expect_reply(c, "$N0=", "ok")
    expect_reply(c, "$10=2", "ok")
    rep = c.status()
    check(field(rep, "WPos") is not None and field(rep, "Bf") == "64,128",
          f"$10=2: WPos and Bf:64,128 ({rep})")
    expect_reply(c, "$10=1", "ok")


def test_gcode(c):
    expect_reply(c, "G21 G90 G0 X10 Y5", "ok")
    rep = c.wait_state("Idle")
    check(position(rep)[:2] == [10.0, 5.0], f"G0 X10 Y5 ends there ({rep})")
    expect_reply(c, "G1 X20 F0", "error:22")
    expect_reply(c, "G5 X1", "error:20")
    expect_reply(c, "G0 X1000", "error:33", "a target beyond the travel")
    c.send("x" * 300 + "\n")
    check(c.until(r"^(ok|error:\d+)$")[-1] == "error:11", "an overlong line -> error:11")
    c.send(b"G1 X30 F600\n")
    c.until("^ok$")
    rep = c.wait_state("Run")
    end = time.time() + 2
    while field(rep, "Ln") is None and rep.startswith("<Run") and time.time() < end:
        rep = c.status()
    check(field(rep, "Ln") is not None, f"Ln: while running ({rep})")
    # feed hold, then resume
    c.send(b"!")
    check(c.wait_state("Hold:").startswith("<Hold:"), "! -> Hold")
    rep = c.wait_state("Hold:0")
    x0 = position(rep)[0]
    time.sleep(0.3)
    check(position(c.status())[0] == x0, "Hold:0: the tool stands still")
    c.send(b"~")
    c.wait_state("Run")
    time.sleep(0.2)
    check(position(c.status())[0] > x0, "~ resumes the move")
    # overrides: feed +10 %, rapid 50 %, spindle +10 %, measured as the path speed
    f0 = float(field(c.status(), "FS").split(",")[0])
    c.send(b"\x91\x96\x9a")
    time.sleep(0.4)
    rep = c.status()
    f1 = float(field(rep, "FS").split(",")[0])
    check(abs(f0 - 600) < 1 and abs(f1 - 660) < 1, f"0x91: feed 600 -> 660 mm/min ({f0}, {f1})")
    ov = None
    for _ in range(12):
        ov = field(c.status(), "Ov") or ov
    check(ov == "110,50,110", f"Ov: after 0x91 0x96 0x9A ({ov})")
    c.send(b"\x90\x95\x99")
    # the safety door: stops like a hold, Door:0 once stopped, ~ resumes
    c.send(b"\x84")
    rep = c.wait_state("Door:0")
    x0 = position(rep)[0]
    time.sleep(0.2)
    check(position(c.status())[0] == x0, "Door:0: stopped")
    c.send(b"~")
    c.wait_state("Run")
    # soft reset during motion: a controlled stop, the welcome line, Idle
    c.send(b"\x18")
    c.until("^" + WELCOME.replace("[", r"\[").replace("$", r"\$") + "$")
    rep = c.wait_state("Idle")
    check(10 < position(rep)[0] < 30, f"0x18 stops the move on its way ({rep})")


def test_probe(c):
    """G38.2 onto the [probe] box (top at machine Z -2): [PRB:…:1] and ok once the move ended, where
    the tool stands; G38.3 beside it: [PRB:…:0] at the target; $# shows the last one."""
    expect_reply(c, "G21 G90 G0 X10 Y10 Z5", "ok")
    c.wait_state("Idle")
    sent = time.time()
    got = expect_reply(c, "G38.2 Z-10 F300", "ok", "G38.2 onto the box")
    took = time.time() - sent
    prb = [x for x in got if x.startswith("[PRB:")]
    rep = c.status()
    check(len(prb) == 1 and prb[0].endswith(":1]"), f"G38.2: one [PRB:…:1] before its ok ({got})")
    z = float(prb[0][5:].split(":")[0].split(",")[2]) if prb else None
    check(z is not None and abs(z + 2) < 1e-3, f"G38.2: the probe tripped at Z-2 ({prb})")
    # 7 mm at 300 mm/min take 1.4 s: the ok came after the move, and the tool stands there.
    check(took > 1.3 and rep.startswith("<Idle") and position(rep)[2] == z,
          f"G38.2: ok after the move ({took:.2f} s), the tool at the trip point ({rep})")
    expect_reply(c, "G0 Z5", "ok")
    expect_reply(c, "G0 X70", "ok")
    got = expect_reply(c, "G38.3 Z-5 F600", "ok", "G38.3 beside the box")
    prb3 = [x for x in got if x.startswith("[PRB:")]
    check(len(prb3) == 1 and prb3[0].endswith(",-5.000:0]"), f"G38.3: no contact, [PRB:…:0] ({got})")
    got = expect_reply(c, "$#", "ok")
    check(prb3 and prb3[0] in got, f"$#: the last probe ({got})")
    expect_reply(c, "G0 Z5", "ok")
    expect_reply(c, "G0 X0 Y0", "ok")
    c.wait_state("Idle")


def gc_words(c):
    got = expect_reply(c, "$G", "ok")
    return got[0][len("[GC:"):-1].split() if got[0].startswith("[GC:") else []


def test_modes(c):
    """$G shows the parser's modes after the lines sent, and the machine's spindle and coolant;
    the status report's FS: and A: show the spindle and coolant once reached."""
    c.wait_state("Idle")
    time.sleep(0.3)
    words = gc_words(c)
    # The soft reset abandoned the streamed G1 X30 F600: its modes are not carried.
    check(words == ["G80", "G54", "G17", "G21", "G90", "G94", "M5", "M9", "T0", "F0", "S0"],
          f"$G after a soft reset: the start modes ({words})")
    for line in ("G18 G91 G20", "G55", "F100", "S1200 M4", "M8", "M7"):
        expect_reply(c, line, "ok")
    rep = c.wait_state("Idle")
    time.sleep(0.3)
    words = gc_words(c)
    want = ["G80", "G55", "G18", "G20", "G91", "G94", "M4", "M7", "M8", "T0", "F100", "S1200"]
    check(words == want, f"$G after G18 G91 G20, G55, F100 (in/min), S1200 M4, M8, M7 ({words})")
    fs = None
    acc = None
    for _ in range(25):
        rep = c.status()
        fs = field(rep, "FS") or fs
        acc = field(rep, "A") or acc
    check(fs == "0,1200", f"FS: shows the spindle speed ({fs})")
    check(acc == "CFM", f"A: spindle CCW, flood, mist ({acc})")
    for line in ("M9 M5", "G17 G90 G21 G54"):
        expect_reply(c, line, "ok")
    c.wait_state("Idle")
    time.sleep(0.3)
    words = gc_words(c)
    check(words[1:6] == ["G54", "G17", "G21", "G90", "G94"] and "M5" in words and "M9" in words
          and words[-2] == "F2540", f"$G after M9 M5 G17 G90 G21 G54 ({words})")


def test_jog(c):
    expect_reply(c, "$J=G91 X5 F3000", "ok")
    rep = c.wait_state("Idle")
    x = position(rep)[0]
    expect_reply(c, "$J=G91 X-5", "error:22", "$J without F")
    expect_reply(c, "$J=G91 X5000 F100", "error:15")
    expect_reply(c, "$J=G1 X5 F100", "error:16")
    expect_reply(c, "$J=G91 X50 F300", "ok")
    c.wait_state("Jog")
    time.sleep(0.3)
    c.send(b"\x85")
    rep = c.wait_state("Idle")
    check(x + 0.5 < position(rep)[0] < x + 5, f"0x85 cancels the jog (from X{x}: {rep})")
    expect_reply(c, "$J=G53 X0 F6000", "ok")
    check(position(c.wait_state("Idle"))[0] == 0.0, "$J=G53 X0: machine X0")


def test_check_mode(c):
    got = expect_reply(c, "$C", "ok")
    check("[MSG:Enabled]" in got, "$C enables check mode")
    check(c.status().startswith("<Check"), "state Check")
    x = position(c.status())[0]
    expect_reply(c, "G0 X77", "ok", "a line in check mode")
    expect_reply(c, "G5", "error:20", "an error in check mode")
    check(position(c.status())[0] == x, "check mode moves nothing")
    got = c.command("$C")
    check("[MSG:Disabled]" in got, "$C disables check mode")
    c.until("Grbl 1.1h")
    c.wait_state("Idle")


def test_alarm(c, server):
    server.console("estop")
    got = c.until(r"^ALARM:")
    check(got[-1] == "ALARM:10", f"E-stop -> ALARM:10 ({got})")
    c.wait_state("Alarm")
    expect_reply(c, "G0 X1", "error:9", "G-code in Alarm")
    got = expect_reply(c, "$X", "ok")
    check("[MSG:Caution: Unlocked]" in got, "$X unlocks")
    c.wait_state("Idle")
    got = c.command("$H", timeout=60)
    check(got[-1] == "ok", f"$H answers ok when homing ended ({got})")
    rep = c.status()
    check(rep.startswith("<Idle"), f"Idle after homing ({rep})")
    expect_reply(c, "$SLP", "ok")
    check(c.status().startswith("<Sleep"), "$SLP -> Sleep")
    c.send(b"\x18")
    c.until("Grbl 1.1h")
    c.wait_state("Idle")
    expect_reply(c, "$RST=$", "ok")
    check("$110=15000" in c.command("$$"), "$RST=$ restores the settings")
    expect_reply(c, "G10 L2 P1 X5", "ok")
    c.wait_state("Idle")
    expect_reply(c, "$RST=#", "ok")
    c.wait_state("Idle")
    c.command("$10=0")
    rep = c.status()
    c.command("$10=1")
    check(position(rep)[0] == position(c.status())[0], "$RST=# clears the work offsets")


def test_streaming(c, how, lines=60):
    """Character counting: up to 128 bytes unanswered; then a sender that ignores the buffer."""
    prog = [f"G1 X{1 + (i % 7)} Y{1 + (i % 5)} F6000" for i in range(lines)]
    prog[-1] = "G0 X3 Y4"
    pending = []
    oks = 0
    i = 0
    while oks < len(prog):
        while i < len(prog) and sum(pending) + len(prog[i]) + 1 <= 128:
            c.send(prog[i] + "\n")
            pending.append(len(prog[i]) + 1)
            i += 1
        reply = c.line(10)
        if reply in ("ok",) or (reply or "").startswith("error"):
            if reply != "ok":
                check(False, f"{how}: streamed line {oks + 1}: {reply} {c.buf[:200]!r}")
            pending.pop(0)
            oks += 1
        elif reply is None:
            break
    check(oks == len(prog), f"{how}: character counting: {oks}/{len(prog)} lines answered")
    check(position(c.wait_state("Idle"))[:2] == [3.0, 4.0], f"{how}: ends at X3 Y4")
    # An overfilling sender: everything at once; every line still answered in order.
    blast = "".join(f"G0 X{i % 9} Y{i % 4}\n" for i in range(40)) + "G0 X2 Y2\n"
    c.send(blast)
    got = [c.line(20) for _ in range(41)]
    check(all(x == "ok" for x in got), f"{how}: an overfilled buffer answers 41 ok")
    check(position(c.wait_state("Idle"))[:2] == [2.0, 2.0], f"{how}: and ends at X2 Y2")


def test_second_client(port):
    first = Client.tcp(port)
    first.until("Grbl 1.1h")
    second = Client.tcp(port)
    line = second.line(3)
    check(line is not None and "another sender" in line, f"a second TCP client is told ({line})")
    check(second.line(1) is None, "and closed")
    second.close()
    first.close()
    time.sleep(0.3)  # the endpoint notices the hang-up at its next poll


def main():
    cncore = sys.argv[1]
    with tempfile.TemporaryDirectory() as workdir:
        machine = os.path.join(workdir, "mill.toml")
        with open(machine, "w") as f:
            f.write(MACHINE)
        server = Server(cncore, workdir, machine)
        try:
            tcp = Client.tcp(server.port)
            connect_checks(tcp, "tcp")
            test_settings(tcp, workdir)
            test_gcode(tcp)
            test_modes(tcp)
            test_jog(tcp)
            test_check_mode(tcp)
            test_alarm(tcp, server)
            test_probe(tcp)
            test_streaming(tcp, "tcp")
            tcp.close()
            time.sleep(0.3)
            test_second_client(server.port)
            pty = Client.pty(server.pty_path)
            connect_checks(pty, "pty")
            test_streaming(pty, "pty", 30)
            expect_reply(pty, "G1 X40 F600", "ok")
            pty.wait_state("Run")
            pty.send(b"!")
            pty.wait_state("Hold:0")
            pty.send(b"~")
            pty.wait_state("Run")
            pty.send(b"\x18")
            pty.until("Grbl 1.1h")
            pty.wait_state("Idle")
            check(True, "pty: hold, resume, soft reset")
            pty.close()
        finally:
            rc = server.stop()
            check(rc == 0, f"cncore serve exits 0 on SIGTERM ({rc})")
        # Settings written by a sender are in the machine after a restart.
        server = Server(cncore, workdir, machine)
        try:
            tcp = Client.tcp(server.port)
            tcp.until("Grbl 1.1h")
            got = tcp.command("$$")
            check("$110=15000" in got, "restart: the restored settings are kept")
            expect_reply(tcp, "$110=5000", "ok")
            tcp.close()
        finally:
            server.stop()
        # $RST=$ restores the configuration file's values, not those persisted at the start,
        # and the running machine takes them at once.
        server = Server(cncore, workdir, machine)
        try:
            tcp = Client.tcp(server.port)
            tcp.until("Grbl 1.1h")
            check("$110=5000" in tcp.command("$$"), "restart: the write of the last run is kept")
            expect_reply(tcp, "$RST=$", "ok")
            check("$110=15000" in tcp.command("$$"), "$RST=$: the configuration's $110 again")
            top = rapid_top_speed(tcp)
            check(top > 5100, f"$RST=$: the X rapid is faster than 5000 mm/min again ({top})")
            tcp.close()
        finally:
            server.stop()
    print(f"{len(FAILS)} failed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
