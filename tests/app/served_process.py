"""``python -m app`` as a real subprocess, read until it says it is serving. Shared by
test_classroom_cli (several rigs, their URLs) and test_serve_sigterm (a clean stop)."""

from __future__ import annotations

import socket
import subprocess
import sys
import time

PY = sys.executable


def free_ports(n: int, start: int) -> int:
    """A base port with ``n`` free ports from it (best effort: bound and released)."""
    for base in range(start, 60000, 97):
        socks: list[socket.socket] = []
        try:
            for i in range(n):
                sock = socket.socket()
                socks.append(sock)
                sock.bind(("127.0.0.1", base + i))
            return base
        except OSError:
            continue
        finally:
            for sock in socks:
                sock.close()
    raise RuntimeError("no free ports")


def start_serving(*args: str, timeout_s: float = 90) -> tuple[subprocess.Popen[str], str]:
    """``python -m app ARGS`` started, and what it printed up to its "serving" line (or up
    to its end or ``timeout_s``: the caller asserts on the text)."""
    proc = subprocess.Popen([PY, "-m", "app", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    assert proc.stdout is not None
    lines: list[str] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        if "serving" in line:
            break
    return proc, "".join(lines)
