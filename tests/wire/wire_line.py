"""What the wire tests share: the line they put on the wire and the veth pair they put it on."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
from collections.abc import Iterator

import pytest

LINE = ("fastcat", "trscat", "cpx", "drive_ecat-ecat")


def line_spec(name: str = "wire", seed: int = 3, cpx_dil: tuple[bool, bool] = (False, True),
              cpx_rotary: int = 0, fastcat_rotary: int = 1) -> str:
    """A rig file with the master and the four slaves of the default line, one expansion and
    four CPX modules: every slave has outputs and inputs (SOEM's expected WKC 3 per slave).
    The CPX-E-EC runs with status bits unless ``cpx_dil`` (DIL 1, DIL 2; Tab. 6) says else,
    its rotary switches (Explicit Device ID, Tab. 5) at ``cpx_rotary``; the FastCAT's rotary
    switch (seed 000 §6.19) at ``fastcat_rotary``, the built-in master's address for it at 1."""
    dil1, dil2 = (str(d).lower() for d in cpx_dil)
    return f"""
[rig]
name = "{name}"
seed = {seed}
step_ms = 1
[master]
line = {list(LINE)!r}
[[fastcat]]
id = "fastcat"
rotary_switch = {fastcat_rotary}
master_address = 1
modules = ["DI16", "DO16", "AI8D"]
[[trscat]]
id = "trscat"
expansions = ["TRS-IO-E"]
configured = ["TRS-IO-E"]
[[cpx]]
id = "cpx"
dil1 = {dil1}
dil2 = {dil2}
rotary_switch = {cpx_rotary}
modules = ["CPX-E-16DI", "CPX-E-8DO", "CPX-E-4AI-U-I", "CPX-E-4AO-U-I"]
[[servo]]
id = "drive_ecat"
fieldbus = "ethercat"
node_id = 2
"""


def _make_veth(tag: str) -> tuple[str, str]:
    if os.geteuid() != 0:
        pytest.skip("a veth pair and a raw socket need root")
    if shutil.which("ip") is None:
        pytest.skip("no `ip` command (iproute2)")
    a, b = f"fr{tag}m{os.getpid() % 10000}", f"fr{tag}s{os.getpid() % 10000}"
    subprocess.run(["ip", "link", "del", a], capture_output=True)  # left by a killed run
    made = subprocess.run(["ip", "link", "add", a, "type", "veth", "peer", "name", b],
                          capture_output=True, text=True)
    if made.returncode:
        pytest.skip(f"`ip link add ... type veth` refused here: {made.stderr.strip()}")
    for name in (a, b):
        subprocess.run(["ip", "link", "set", name, "up"], check=True)
    return a, b


@contextlib.contextmanager
def veth_pair(tag: str) -> Iterator[tuple[str, str]]:
    """(master end, slave end), deleted afterwards; the test is skipped with the reason where
    the machine cannot make one. `tag` keeps pairs of tests running together apart."""
    a, b = _make_veth(tag)
    try:
        yield a, b
    finally:
        subprocess.run(["ip", "link", "del", a], capture_output=True)
