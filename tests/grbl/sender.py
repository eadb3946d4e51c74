"""A G-code sender that behaves as Universal G-code Sender and bCNC do on a Grbl 1.1 board, per
their documented protocol behaviour (Grbl wiki, "Interface": streaming), standard library only:

- on connect: wait for the welcome line, then `$$` and `$G` (UGS asks both; bCNC `$G`);
- character-counting streaming: lines go out while the bytes of the lines not yet answered stay
  within the 128-byte receive buffer less one (UGS's and bCNC's budget, 127);
- `?` polled at 10 Hz while streaming (UGS's default status interval is 100 ms, bCNC's 200 ms);
- `!`, `~` and the override bytes sent mid-stream at the moments the caller asks;
- on an `error:N` it stops sending new lines (UGS's default), on `ALARM:N` it stops and a soft
  reset (0x18) and `$X` bring the machine back.

It records every reply and status report with the time it arrived, so a test can check the
states seen, the final position and how long the machine took.
"""
import re
import time

from grbl_client import field

RX_BUDGET = 127
POLL_S = 0.1
WELCOME = re.compile(r"^Grbl 1\.1")


class Sender:
    def __init__(self, client):
        self.c = client
        self.log = []  # (time, line) of every reply
        self.states = []  # status reports in order (time, report)
        self.errors = []
        self.alarms = []
        self.settings = {}
        self.gcode_state = ""

    def _read(self, timeout):
        line = self.c.line(timeout)
        if line is None:
            return None
        self.log.append((time.time(), line))
        if line.startswith("<"):
            self.states.append((time.time(), line))
        elif line.startswith("ALARM:"):
            self.alarms.append(line)
        return line

    def _until_answer(self, timeout=10.0):
        """Lines up to the next ok / error:N (status reports and messages recorded on the way)."""
        end = time.time() + timeout
        got = []
        while True:
            line = self._read(max(0.0, end - time.time()))
            if line is None:
                raise AssertionError(f"no ok/error in {timeout} s; got {got}")
            got.append(line)
            if line == "ok" or line.startswith("error:"):
                return got

    def handshake(self, timeout=5.0):
        end = time.time() + timeout
        while True:
            line = self._read(max(0.0, end - time.time()))
            if line is None:
                raise AssertionError("no welcome line")
            if WELCOME.match(line):
                break
        self.c.send("$$\n")
        for line in self._until_answer():
            m = re.match(r"^\$(\d+)=(.*)$", line)
            if m:
                self.settings[int(m.group(1))] = m.group(2)
        self.c.send("$G\n")
        for line in self._until_answer():
            if line.startswith("[GC:"):
                self.gcode_state = line

    def stream(self, lines, actions=None, poll_s=POLL_S, finish_state="Idle", timeout=600.0,
               stop_after=None):
        """Streams `lines` by character counting, polling `?` every poll_s. `actions`: a list of
        (after_seconds, bytes) real-time bytes to send that long after the first line. Returns
        (sent, answered) line counts; stops early on an error or alarm (as UGS does), or returns
        `stop_after` seconds after the first line (the operator pressing stop)."""
        actions = sorted(actions or [], key=lambda a: a[0])
        pending = []  # byte counts of the lines sent and not yet answered
        sent = answered = 0
        start = time.time()
        next_poll = start
        end = start + timeout
        stopped = False
        last_answer = start
        while time.time() < end:
            now = time.time()
            if stop_after is not None and now - start >= stop_after:
                return sent, answered
            while actions and now - start >= actions[0][0]:
                self.c.send(actions.pop(0)[1])
            if now >= next_poll:
                self.c.send(b"?")
                next_poll = now + poll_s
            while not stopped and sent < len(lines):
                data = lines[sent].strip() + "\n"
                if sum(pending) + len(data) > RX_BUDGET:
                    break
                self.c.send(data)
                pending.append(len(data))
                sent += 1
            done = sent == len(lines) and not pending
            if stopped or done:
                t, last = self.states[-1] if self.states else (0, "")
                if done and t > last_answer and last.startswith("<" + finish_state) and not actions:
                    return sent, answered
                if stopped and not pending:
                    return sent, answered
            line = self._read(min(poll_s, max(0.0, next_poll - time.time())) + 0.001)
            if line is None:
                continue
            if line == "ok" or line.startswith("error:"):
                if pending:
                    pending.pop(0)
                    answered += 1
                last_answer = time.time()
                if line.startswith("error:"):
                    self.errors.append((sent - len(pending), line))
                    stopped = True
            elif line.startswith("ALARM:"):
                stopped = True
        raise AssertionError(f"stream did not finish in {timeout} s ({sent} sent, {answered} answered)")

    def reset_and_unlock(self):
        """Soft reset, then `$X` when the board comes back in alarm (UGS's 'Reset' + 'Unlock')."""
        self.c.send(b"\x18")
        end = time.time() + 5
        while True:
            line = self._read(max(0.0, end - time.time()))
            if line is None:
                raise AssertionError("no welcome after soft reset")
            if WELCOME.match(line):
                break
        self.c.send("$X\n")
        return self._until_answer()

    def state_names(self):
        """The distinct machine states seen, in order (Idle, Run, Hold:0 …)."""
        names = []
        for _, rep in self.states:
            name = rep[1:].split("|", 1)[0]
            if not names or names[-1] != name:
                names.append(name)
        return names

    def last_report(self):
        return self.states[-1][1] if self.states else ""

    def buffer_free(self):
        """The smallest Bf: planner figure seen (when $10 asks for it)."""
        figures = [int(field(r, "Bf").split(",")[0]) for _, r in self.states if field(r, "Bf")]
        return min(figures) if figures else None
