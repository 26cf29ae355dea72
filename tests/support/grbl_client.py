#!/usr/bin/env python3
"""A Grbl 1.1 sender for the tests of `curvestep grbl` (tests/cli/test_grbl.sh).

Implements the two streaming methods the grbl wiki documents ("Interface", streaming
protocols): send-response (one line, then wait for its ok / error:N) and character counting
(keep the sum of the unacknowledged lines' lengths, newline included, at most 127 of Grbl's
128-byte receive buffer). Written from that description, not from Grbl's stream.py.

usage: grbl_client.py PTY|HOST:PORT COMMAND ...
  stream FILE [--method simple|counting|burst] [--hold-after N] [--status-every N]
        streams FILE (burst: character counting with the lines that fit written together, so
        the front end never sees a pause between them); prints one line per error ("error: line L: error:N"), the first status
        seen while running ("running: <...>"), with --hold-after N sends ! after N lines,
        reports "held: <...>" once the state is Hold:0 and the position has stopped, then ~;
        at the end waits for Idle and prints "final: <...>" and "acks: OK ERR".
  cmd LINE...     sends each line (send-response) and prints every reply line; a LINE
                  "@waitfor STATE" is not sent: it waits as waitfor does
  jogcancel LINE  sends the $J= LINE, waits for the Jog state, sends 0x85 and prints
                  "jogging: <...>" and "final: <...>" once Idle
  reset LINE      sends LINE, waits for Run with the position moved, sends Ctrl-X and prints
                  "moving: <...>" and "final: <...>" once Idle
  idle            (no soft reset first) waits for Idle, prints "final: <...>"
  waitfor STATE   (no soft reset first) waits for the state STATE (Alarm, Idle...), prints
                  the pushed lines seen meanwhile (ALARM:N...) and "state: <...>"
  override FILE BYTE X F  prints $120 ("accel: A"), writes FILE's lines (< 128 bytes: a
                  straight cut along +X at F mm/min) at once, sends the real-time BYTE (hex)
                  once a report in Run is at X >= X mm, prints the median FS: feed before and
                  after it ("before: F", "after: F", "after-reports: N" taken in Run), the Ov
                  field, "final: <...>", and of the reports before the byte past the ramp
                  "steady: N from X0" and "off: X:F ..." (those not within 2 % of F)
  raw BYTE...     sends real-time bytes (hex, e.g. 18 for Ctrl-X) and prints what comes back
                  (the first line within the deadline, then lines until 1 s without one)
Every command but idle starts with a soft reset (Ctrl-X) and the welcome line.
Every wait has a deadline (--deadline S, default 60); a missed one exits 3.
"""
import os
import re
import select
import socket
import sys
import termios
import time
import tty

RX_SIZE = 128
STATUS_RE = re.compile(r"^<([A-Za-z]+(?::\d)?)\|(MPos|WPos):(-?\d+\.\d{3}),(-?\d+\.\d{3}),(-?\d+\.\d{3})"
                       r"(\|Bf:\d+,\d+)?\|FS:\d+,\d+(\|Pn:[XYZPDHRS]+)?(\|WCO:-?\d+\.\d{3},-?\d+\.\d{3},-?\d+\.\d{3})?"
                       r"(\|Ov:\d+,\d+,\d+)?>$")


class Grbl:
    def __init__(self, where, deadline):
        self.deadline = deadline
        self.buf = b""
        if re.match(r"^[\d.]+:\d+$", where):
            host, port = where.rsplit(":", 1)
            self.sock = socket.create_connection((host, int(port)), timeout=deadline)
            self.fd = self.sock.fileno()
        else:
            self.sock = None
            # a fresh pty's /dev/pts entry can be missing on and off for its first ~60 ms
            # (host/cs_serial.c open_tty): retried until the deadline
            end = time.monotonic() + deadline
            while True:
                try:
                    self.fd = os.open(where, os.O_RDWR | os.O_NOCTTY)
                    break
                except FileNotFoundError:
                    if time.monotonic() > end:
                        raise
                    time.sleep(0.005)
            tty.setraw(self.fd)
            termios.tcflush(self.fd, termios.TCIOFLUSH)

    def write(self, data):
        if self.sock:
            self.sock.sendall(data)
        else:
            os.write(self.fd, data)

    def readline(self, timeout=None):
        """One line (without \\r\\n), or None when nothing came in timeout seconds."""
        end = time.monotonic() + (self.deadline if timeout is None else timeout)
        while b"\n" not in self.buf:
            left = end - time.monotonic()
            if left <= 0:
                return None
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                chunk = self.sock.recv(4096) if self.sock else os.read(self.fd, 4096)
                if not chunk:
                    return None
                self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return line.decode().rstrip("\r")

    def need(self, timeout=None):
        line = self.readline(timeout)
        if line is None:
            print("deadline: no answer", flush=True)
            sys.exit(3)
        return line

    def status(self):
        """Sends ? and returns the status report (other lines are kept in self.pushed)."""
        self.write(b"?")
        while True:
            line = self.need()
            if line.startswith("<"):
                if not STATUS_RE.match(line):
                    print("malformed: " + line, flush=True)
                return line
            self.pushed.append(line)

    pushed = []


def wait_welcome(g):
    """Soft reset, then the welcome line: a known state to start from."""
    g.write(b"\x18")
    while True:
        line = g.need()
        if line.startswith("Grbl 1.1"):
            print("welcome: " + line, flush=True)
            return


def is_ack(line):
    return line == "ok" or line.startswith("error:")


def program(path):
    out = []
    for raw in open(path):
        line = raw.strip()
        if line:
            out.append(line)
    return out


def wait_idle(g):
    end = time.monotonic() + g.deadline
    while time.monotonic() < end:
        st = g.status()
        if st.startswith("<Idle"):
            return st
        time.sleep(0.05)
    print("deadline: never idle", flush=True)
    sys.exit(3)


def wait_for(g, state):
    """Polls ? until the state is state; prints the pushed lines seen meanwhile (ALARM:N...) and
    "state: <...>". 0, or 3 at the deadline."""
    end = time.monotonic() + g.deadline
    while time.monotonic() < end:
        st = g.status()
        for line in g.pushed:
            print(line, flush=True)
        g.pushed.clear()
        if st.startswith("<" + state):
            print("state: " + st, flush=True)
            return 0
        time.sleep(0.05)
    print("deadline: never " + state, flush=True)
    return 3


def hold_and_resume(g):
    end = time.monotonic() + g.deadline
    last = None
    while time.monotonic() < end:  # hold while the machine moves
        pos = g.status().split("|")[1]
        if last is not None and pos != last:
            break
        last = pos
        time.sleep(0.05)
    g.write(b"!")
    last = None
    while time.monotonic() < end:
        st = g.status()
        pos = st.split("|")[1]
        if st.startswith("<Hold:0") and pos == last:
            print("held: " + st, flush=True)
            break
        last = pos
        time.sleep(0.3)
    else:
        print("deadline: never held", flush=True)
        sys.exit(3)
    time.sleep(0.3)
    st = g.status()
    print("still-held: " + st, flush=True)
    g.write(b"~")


def stream(g, lines, method, hold_after, status_every):
    acks = {"ok": 0, "err": 0}
    sent = []  # (line number, length) not yet acknowledged
    seen_run = False

    def take(line):
        nonlocal seen_run
        if line.startswith("<"):
            if not seen_run and line.startswith("<Run"):
                print("running: " + line, flush=True)
                seen_run = True
            return
        if not is_ack(line):
            return
        num, _ = sent.pop(0)
        if line == "ok":
            acks["ok"] += 1
        else:
            acks["err"] += 1
            print("error: line %d: %s" % (num, line), flush=True)

    burst = b""
    for k, line in enumerate(lines, 1):
        data = (line + "\n").encode()
        if method in ("counting", "burst"):
            while sent and sum(n for _, n in sent) + len(data) > RX_SIZE - 1:
                if burst:
                    g.write(burst)
                    burst = b""
                take(g.need())
        sent.append((k, len(data)))
        if method == "burst":
            burst += data
            continue
        g.write(data)
        if method == "simple":
            while sent:
                take(g.need())
        if status_every and k % status_every == 0:
            g.write(b"?")
        if hold_after and k == hold_after:
            while sent:
                take(g.need())
            hold_and_resume(g)
    if burst:
        g.write(burst)
    while sent:
        take(g.need())
    if not seen_run:
        print("running: (job ended before a report)", flush=True)
    print("final: " + wait_idle(g), flush=True)
    print("acks: %d %d" % (acks["ok"], acks["err"]), flush=True)


def feed_of(st):
    """The FS: feed of a status report (mm/min), or None."""
    for f in st.strip("<>").split("|"):
        if f.startswith("FS:"):
            return float(f[3:].split(",")[0])
    return None


def setting(g, n):
    """Grbl's $N from $$ (send-response), as a float."""
    g.write(b"$$\n")
    val = None
    while True:
        line = g.need()
        if is_ack(line):
            return val
        if line.startswith("$%d=" % n):
            val = float(line.split("=", 1)[1])


def x_of(st):
    """The first coordinate of a status report's position (mm)."""
    return float(st.split("|")[1].split(":")[1].split(",")[0])


# The front end's FS window over device time (host/cs_feedrate.h CS_FEEDRATE_WINDOW_DEV_S), s,
# and how long it may have seen no STATUS on a loaded machine (its window then starts earlier).
FS_WINDOW_S, FS_STALL_S = 0.2, 0.3


def override_mid_job(g, lines, byte, at_x, feed):
    """Prints the acceleration $120 ("accel: A", mm/s^2), streams lines (a straight cut along +X
    at feed mm/min) by character counting, then polls ? every 0.1 s: once a report in Run shows
    X >= at_x, sends the override byte; prints "before: F" and "after: F" (medians, mm/min;
    after: the reports from 0.6 s after the byte while still in Run), "after-reports: N", the
    Ov field seen after the byte, the final report, and the reports in Run before the byte past
    the ramp: "steady: N from X" (X = v^2 / 2a + v (FS_WINDOW_S + FS_STALL_S)) and "off: X:F..."
    for those whose feed is not within 2 % of feed."""
    accel = setting(g, 120)
    print("accel: %g" % accel, flush=True)
    v = feed / 60.0
    past = v * v / (2 * accel) + v * (FS_WINDOW_S + FS_STALL_S)
    steady, off = 0, []
    data = b"".join((line + "\n").encode() for line in lines)
    g.write(data)
    end = time.monotonic() + g.deadline
    before, after, ov, t_byte = [], [], None, None
    while time.monotonic() < end:
        st = g.status()
        f = feed_of(st)
        now = time.monotonic()
        if st.startswith("<Run") and f:
            if t_byte is None:
                before.append(f)
                if x_of(st) >= past:
                    steady += 1
                    if abs(f / feed - 1) > 0.02:
                        off.append("%.3f:%g" % (x_of(st), f))
                if x_of(st) >= at_x:
                    g.write(bytes([byte]))
                    t_byte = now
            elif now - t_byte >= 0.6:
                after.append(f)
        if t_byte is not None and "|Ov:" in st:
            ov = st.split("|Ov:")[1].rstrip(">")
        if st.startswith("<Idle") and t_byte is not None:
            break
        time.sleep(0.1)
    med = lambda v: sorted(v)[len(v) // 2] if v else 0.0
    print("before: %.1f" % med(before[2:]), flush=True)
    print("after: %.1f" % med(after), flush=True)
    print("after-reports: %d" % len(after), flush=True)
    print("ov: %s" % ov, flush=True)
    print("final: " + wait_idle(g), flush=True)
    print("steady: %d from %.3f" % (steady, past), flush=True)
    print("off:" + "".join(" " + o for o in off), flush=True)


def main(argv):
    deadline = 60.0
    if "--deadline" in argv:
        i = argv.index("--deadline")
        deadline = float(argv[i + 1])
        del argv[i:i + 2]
    g = Grbl(argv[1], deadline)
    cmd = argv[2]
    if cmd == "idle":  # no reset: waits for what runs to end
        print("final: " + wait_idle(g), flush=True)
        return 0
    if cmd == "waitfor":  # no reset: waits for a state, prints the pushed lines seen meanwhile
        return wait_for(g, argv[3])
    wait_welcome(g)
    if cmd == "stream":
        method, hold_after, every = "simple", 0, 0
        args = argv[4:]
        for i in range(0, len(args) - 1, 2):
            if args[i] == "--method":
                method = args[i + 1]
            elif args[i] == "--hold-after":
                hold_after = int(args[i + 1])
            elif args[i] == "--status-every":
                every = int(args[i + 1])
        stream(g, program(argv[3]), method, hold_after, every)
    elif cmd == "cmd":
        for line in argv[3:]:
            if line.startswith("@waitfor "):  # not sent: waits for a state (as waitfor)
                if wait_for(g, line.split(" ", 1)[1]) != 0:
                    return 3
                continue
            g.write((line + "\n").encode())
            while True:
                reply = g.need()
                print(reply, flush=True)
                if is_ack(reply):
                    break
    elif cmd == "reset":  # Ctrl-X mid-move: the machine stops, the rest is dropped
        g.write((argv[3] + "\n").encode())
        print("reply: " + g.need(), flush=True)
        first = None
        end = time.monotonic() + deadline
        while time.monotonic() < end:
            st = g.status()
            pos = st.split("|")[1]
            first = first or pos
            if st.startswith("<Run") and pos != first:
                print("moving: " + st, flush=True)
                break
            time.sleep(0.05)
        g.write(b"\x18")
        print("final: " + wait_idle(g), flush=True)
    elif cmd == "jogcancel":
        g.write((argv[3] + "\n").encode())
        print("reply: " + g.need(), flush=True)
        end = time.monotonic() + deadline
        while time.monotonic() < end:
            st = g.status()
            if st.startswith("<Jog") and not st.split("|")[1].endswith(":0.000,0.000,0.000"):
                print("jogging: " + st, flush=True)
                break
            time.sleep(0.05)
        g.write(b"\x85")
        print("final: " + wait_idle(g), flush=True)
    elif cmd == "override":  # override FILE BYTE X F: the byte (hex) at X mm; FS against F
        override_mid_job(g, program(argv[3]), int(argv[4], 16), float(argv[5]), float(argv[6]))
    elif cmd == "raw":
        for b in argv[3:]:
            g.write(bytes([int(b, 16)]))
        # the first answer within the deadline (a loaded machine is slow), then whatever else
        # comes within 1 s of the last line
        wait = None
        while True:
            line = g.readline(wait)
            if line is None:
                break
            print(line, flush=True)
            wait = 1.0
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
