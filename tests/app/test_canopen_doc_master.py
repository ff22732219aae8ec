"""docs/canopen.md "Connecting an external master": its Python block, run as written in another
process against ``python -m app --can-interface udp_multicast`` (the default rig, so the
CANopen drive ``drive_co`` at node 2), brings the drive to Operation enabled.

Only the default channel in the block is swapped for a unique one, so runs beside other tests
do not meet."""

from __future__ import annotations

import os
import random
import re
import subprocess
from pathlib import Path

from served_process import PY, free_ports, start_serving

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "canopen.md"
DEFAULT_GROUP, DEFAULT_PORT = "239.74.163.2", "43113"


def doc_master_code() -> str:
    section = DOC.read_text(encoding="utf-8").split("## Connecting an external master", 1)[1]
    found = re.search(r"^```python\n(.*?)^```", section, re.M | re.S)
    assert found, "no Python block under 'Connecting an external master'"
    return found.group(1)


def test_the_external_master_of_the_doc_enables_the_drive(tmp_path: Path) -> None:
    code = doc_master_code()
    assert DEFAULT_GROUP in code and DEFAULT_PORT in code, code  # what the test swaps
    rng = random.Random()
    group, port = f"239.74.{rng.randrange(1, 255)}.{rng.randrange(1, 255)}", \
        str(rng.randrange(40_000, 60_000))
    script = tmp_path / "master.py"
    script.write_text(code.replace(DEFAULT_GROUP, group).replace(DEFAULT_PORT, port)
                      + "print('state', node.state)\nnetwork.disconnect()\n")
    web, modbus = free_ports(1, 24300), free_ports(1, 34300)
    proc, text = start_serving(
        "--can-interface", "udp_multicast", "--can-channel", f"{group}:{port}",
        "--port", str(web), "--modbus-port", str(modbus), "--state-dir",
        str(tmp_path / "state"), "--no-record", "--run-for", "120")
    try:
        assert "serving" in text, text
        # As the doc's reader runs it: from the checkout, so ``app`` is this one.
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        master = subprocess.run([PY, str(script)], cwd=ROOT, env=env, capture_output=True,
                                text=True, timeout=90)
    finally:
        proc.terminate()
        proc.wait(timeout=60)
    assert master.returncode == 0, master.stdout + master.stderr
    assert "state OPERATION ENABLED" in master.stdout, master.stdout + master.stderr
