#!/usr/bin/env python3
"""Test helper (not a test): opens N connections to the UNIX socket SOCK and sends nothing.
holdconn.py SOCK N SECS: holds them SECS seconds, then exits 0 (silent clients).
holdconn.py SOCK 1 SECS --wait-eof: exits 0 when the server closes the connection (printing
what it sent), 1 when SECS pass first (an idle client that is never closed)."""
import socket
import sys

path, n, secs = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
conns = []
for _ in range(n):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(path)
    conns.append(s)
if len(sys.argv) > 4 and sys.argv[4] == "--wait-eof":
    conns[0].settimeout(secs)
    got = b""
    try:
        while True:
            b = conns[0].recv(4096)
            if not b:
                break
            got += b
    except socket.timeout:
        sys.exit(1)
    sys.stdout.write(got.decode(errors="replace"))
    sys.exit(0)
print("holding", flush=True)
import time
time.sleep(secs)
