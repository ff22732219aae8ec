"""``python -m app`` stopped with SIGTERM (what systemd, docker and a CI job's timeout send)
shuts down as Ctrl-C does: the session's recording is closed with its footer, so ``rerun rrd
verify`` accepts it with the footer check on, and the process exits 0."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

from served_process import PY, free_ports, start_serving


def test_sigterm_closes_the_recording(tmp_path: Path) -> None:
    port, modbus = free_ports(1, 24000), free_ports(1, 34000)
    record = tmp_path / "session.rrd"
    proc, text = start_serving(
        "--port", str(port), "--modbus-port", str(modbus), "--state-dir",
        str(tmp_path / "state"), "--record", str(record), "--run-for", "120")
    try:
        assert "serving" in text, text
        time.sleep(1.0)  # a second of the rig in the file
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=30)
    assert proc.returncode == 0, text + out
    verify = subprocess.run([PY, "-m", "rerun", "rrd", "verify", str(record)],
                            capture_output=True, text=True, timeout=120)
    assert verify.returncode == 0, verify.stdout + verify.stderr
