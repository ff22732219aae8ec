"""``python -m app`` stopped with SIGTERM (what systemd, docker and a CI job's timeout send)
shuts down as Ctrl-C does: the session's recording is closed with its footer, so ``rerun rrd
verify`` accepts it with the footer check on, and the process exits 0."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

from tests.app.test_classroom_cli import _free_ports

PY = sys.executable


def test_sigterm_closes_the_recording(tmp_path: Path) -> None:
    port, modbus = _free_ports(1, 24000), _free_ports(1, 34000)
    record = tmp_path / "session.rrd"
    proc = subprocess.Popen(
        [PY, "-m", "app", "--port", str(port), "--modbus-port", str(modbus),
         "--state-dir", str(tmp_path / "state"), "--record", str(record), "--run-for", "120"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
            if "serving" in line:
                break
        assert any("serving" in line for line in lines), "".join(lines)
        time.sleep(1.0)  # a second of the rig in the file
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=30)
    assert proc.returncode == 0, "".join(lines) + out
    verify = subprocess.run([PY, "-m", "rerun", "rrd", "verify", str(record)],
                            capture_output=True, text=True, timeout=120)
    assert verify.returncode == 0, verify.stdout + verify.stderr
