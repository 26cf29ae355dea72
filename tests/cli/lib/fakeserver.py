#!/usr/bin/env python3
"""Test helper (not a test): a fake daemon on the UNIX socket SOCK that answers every request
"OK job 1 queued" and writes what it received to LOG (another user's squatting socket)."""
import os
import socket
import sys

path, log = sys.argv[1], sys.argv[2]
s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
s.bind(path)
os.chmod(path, 0o666)
s.listen(4)
print("ready", flush=True)
while True:
    c, _ = s.accept()
    c.settimeout(5)
    try:
        data = c.recv(4096)
    except socket.timeout:
        data = b""
    with open(log, "ab") as f:
        f.write(data)
    c.sendall(b"OK job 1 queued\n")
    c.close()
