"""A Grbl 1.1 test client for cncore serve's endpoints (TCP and pseudo-terminal), standard
library only: connect, send lines and real-time bytes, read replies with time-outs."""
import os
import re
import select
import socket
import subprocess
import termios
import time
import tty


class Client:
    def __init__(self, fd, close):
        self.fd = fd
        self._close = close
        self.buf = b""

    @staticmethod
    def tcp(port, timeout=5.0):
        end = time.time() + timeout
        while True:
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=1)
                break
            except OSError:
                if time.time() > end:
                    raise
                time.sleep(0.05)
        s.setblocking(False)
        return Client(s.fileno(), s.close)

    @staticmethod
    def pty(path, timeout=5.0):
        end = time.time() + timeout
        while not os.path.exists(path):
            if time.time() > end:
                raise RuntimeError(f"no pty at {path}")
            time.sleep(0.05)
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(fd)
        attrs = termios.tcgetattr(fd)
        attrs[3] &= ~termios.ECHO
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        return Client(fd, lambda: os.close(fd))

    def close(self):
        self._close()

    def send(self, data):
        if isinstance(data, str):
            data = data.encode()
        while data:
            select.select([], [self.fd], [], 5)
            n = os.write(self.fd, data)
            data = data[n:]

    def line(self, timeout=5.0):
        """The next reply line (without \\r\\n), or None after the time-out."""
        end = time.time() + timeout
        while b"\n" not in self.buf:
            left = end - time.time()
            if left <= 0:
                return None
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                try:
                    chunk = os.read(self.fd, 4096)
                except OSError:
                    return None
                if not chunk:
                    return None
                self.buf += chunk
        raw, self.buf = self.buf.split(b"\n", 1)
        return raw.decode(errors="replace").rstrip("\r")

    def until(self, pattern, timeout=5.0):
        """Lines up to and including the first that matches; raises when none does in time."""
        seen = []
        end = time.time() + timeout
        while True:
            line = self.line(max(0.0, end - time.time()))
            if line is None:
                raise AssertionError(f"no line matching {pattern!r}; got {seen}")
            seen.append(line)
            if re.search(pattern, line):
                return seen

    def command(self, text, timeout=5.0):
        """Sends one line; returns the lines up to its ok / error:N (the last of the list)."""
        self.send(text + "\n")
        return self.until(r"^(ok|error:\d+)$", timeout)

    def status(self):
        self.send(b"?")
        return self.until(r"^<.*>$")[-1]

    def wait_state(self, state, timeout=20.0):
        end = time.time() + timeout
        last = ""
        while time.time() < end:
            last = self.status()
            if last.startswith("<" + state):
                return last
            time.sleep(0.02)
        raise AssertionError(f"still {last}, expected {state}")


def field(report, name):
    m = re.search(r"[<|]" + name + r":([^|>]*)", report)
    return m.group(1) if m else None


def position(report):
    v = field(report, "MPos") or field(report, "WPos")
    return [float(x) for x in v.split(",")]


class Server:
    """cncore serve with both Grbl endpoints; its console (stdin) stays open for the test."""

    def __init__(self, cncore, workdir, machine=None, extra=()):
        self.port = _free_port()
        self.pty_path = os.path.join(workdir, "ttyGRBL")
        args = [cncore, "serve", "--no-realtime", "--state-dir", os.path.join(workdir, "state"),
                "--grbl-tcp", f"127.0.0.1:{self.port}", "--grbl-pty", self.pty_path, *extra]
        if machine:
            args += ["--machine", machine]
        self.log = open(os.path.join(workdir, "serve.log"), "w")
        self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=self.log,
                                     stderr=subprocess.STDOUT)

    def console(self, line):
        self.proc.stdin.write((line + "\n").encode())
        self.proc.stdin.flush()

    def stop(self):
        self.proc.terminate()
        rc = self.proc.wait(30)
        self.log.close()
        return rc


def _free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port
