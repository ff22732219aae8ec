"""Security defaults: every listener on loopback unless asked otherwise; rig and scenario files
are parsed as TOML and never executed.

Issue 7 "Hardening". The listeners are read from the kernel while a real ``python -m app`` runs
(its sockets from /proc/PID/fd, their addresses from /proc/PID/net, multicast memberships from
/proc/net/igmp), first with the defaults (only the ports chosen, so that parallel runs do not
collide), then with the CAN bus on ``udp_multicast``.
"""

from __future__ import annotations

import inspect
import ipaddress
import os
import random
import socket
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from app.canopen_bus import CanBusError, open_bus
from app.modbus.server import DriveModbusServer
from app.rig_config import RigConfigError, build_rig, parse_rig_spec
from app.scenario import ScenarioError, check_against, parse_scenario

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT_S = 120.0
TCP_LISTEN, UDP_UNCONNECTED = "0A", "07"


@dataclass
class Listeners:
    tcp: list[tuple[str, int]]  # LISTEN sockets
    udp: list[tuple[str, int]]
    igmp_devices: list[str]  # interfaces that joined the CAN multicast group


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _address(hex_address: str) -> tuple[str, int]:
    """/proc/net/{tcp,udp}[6] ``ADDR:PORT`` (address in the kernel's byte order) -> text."""
    host, port = hex_address.split(":")
    raw = bytes.fromhex(host)
    if len(raw) == 4:
        text = str(ipaddress.IPv4Address(raw[::-1]))
    else:  # four 32-bit words, each in host (little-endian) order
        text = str(ipaddress.IPv6Address(b"".join(raw[i:i + 4][::-1] for i in range(0, 16, 4))))
    return text, int(port, 16)


def _sockets(pid: int) -> dict[str, list[tuple[str, int]]]:
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    found: dict[str, list[tuple[str, int]]] = {"tcp": [], "udp": []}
    for proto in ("tcp", "tcp6", "udp", "udp6"):
        table = Path(f"/proc/{pid}/net/{proto}")
        if not table.exists():
            continue
        for line in table.read_text().splitlines()[1:]:
            cols = line.split()
            if cols[9] not in inodes:
                continue
            if proto.startswith("tcp") and cols[3] == TCP_LISTEN:
                found["tcp"].append(_address(cols[1]))
            elif proto.startswith("udp"):
                found["udp"].append(_address(cols[1]))
    return found


def _igmp_devices(group: str) -> list[str]:
    """Interfaces on which ``group`` is joined (/proc/net/igmp: group in host byte order)."""
    wanted = ipaddress.IPv4Address(group).packed[::-1].hex().upper()
    devices, device = [], ""
    for line in Path("/proc/net/igmp").read_text().splitlines()[1:]:
        if not line.startswith(("\t", " ")):
            device = line.split()[1]
        elif line.split()[0].upper() == wanted:
            devices.append(device)
    return devices


def _serve(tmp: Path, *flags: str) -> Listeners:
    """Start ``python -m app`` with ``flags``, read its listeners from the kernel, stop it."""
    port, modbus_port = _free_port(), _free_port()
    log = tmp / "stderr.txt"
    with log.open("w") as stderr:  # a file, not a pipe nobody reads while it runs
        proc = subprocess.Popen(
            [sys.executable, "-m", "app", "--port", str(port), "--modbus-port",
             str(modbus_port), "--state-dir", str(tmp / "state"), "--run-for",
             str(START_TIMEOUT_S), *flags], cwd=ROOT, stdout=subprocess.PIPE, stderr=stderr,
            text=True)
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:  # the dashboard line is printed once every listener is up
            line = proc.stdout.readline()
            assert line, f"python -m app ended: {log.read_text()}"
            if line.startswith("FieldRig: rig"):
                break
            assert time.monotonic() < deadline
        found = _sockets(proc.pid)
        group = next((f.split("=", 1)[1].split(":")[0] for f in flags
                      if f.startswith("--can-channel=")), None)
        igmp = _igmp_devices(group) if group else []
    finally:
        proc.terminate()
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    assert {port, modbus_port} <= {p for _a, p in found["tcp"]}, found
    return Listeners(found["tcp"], found["udp"], igmp)


def _loopback(address: str) -> bool:
    return ipaddress.ip_address(address).is_loopback


@pytest.fixture(scope="module")
def default_listeners(tmp_path_factory: pytest.TempPathFactory) -> Listeners:
    return _serve(tmp_path_factory.mktemp("defaults"))


@pytest.fixture(scope="module")
def udp_listeners(tmp_path_factory: pytest.TempPathFactory) -> Listeners:
    rng = random.Random()
    channel = f"239.74.{rng.randrange(200, 250)}.{rng.randrange(1, 250)}:" \
              f"{rng.randrange(46000, 49000)}"
    return _serve(tmp_path_factory.mktemp("udp"), "--can-interface", "udp_multicast",
                  f"--can-channel={channel}")


def test_web_and_modbus_listen_on_loopback_by_default(default_listeners: Listeners) -> None:
    """--host defaults to 127.0.0.1; the dashboard and the Modbus line both bind to it."""
    assert default_listeners.tcp
    assert all(_loopback(a) for a, _p in default_listeners.tcp), default_listeners.tcp


def test_the_default_can_bus_opens_no_socket(default_listeners: Listeners) -> None:
    """--can-interface defaults to python-can's in-process virtual bus: nothing on the network."""
    assert default_listeners.udp == []


def test_tcp_listeners_stay_on_loopback_with_can_over_udp(udp_listeners: Listeners) -> None:
    assert all(_loopback(a) for a, _p in udp_listeners.tcp), udp_listeners.tcp


def test_can_over_udp_stays_on_this_machine(udp_listeners: Listeners) -> None:
    """The UDP socket takes nothing addressed to this host from outside: it is bound to the
    loopback or the multicast group (not 0.0.0.0), and the group is joined on ``lo`` only
    (app/canopen_bus.py: loopback unless ``--can-channel GROUP:PORT@ADDRESS`` asks otherwise)."""
    assert udp_listeners.udp
    for address, _port in udp_listeners.udp:
        ip = ipaddress.ip_address(address)
        assert ip.is_loopback or ip.is_multicast, udp_listeners.udp
    assert udp_listeners.igmp_devices and set(udp_listeners.igmp_devices) == {"lo"}, \
        udp_listeners.igmp_devices


@pytest.mark.parametrize(("suffix", "bound"), [("", "239.74.251.7"), ("@127.0.0.1", "239.74.251.7"),
                                               ("@any", "0.0.0.0")])
def test_can_over_udp_binds_where_the_channel_says(suffix: str, bound: str) -> None:
    """Loopback and the group address by default; ``@any`` is python-can's own socket (what a
    user asks for explicitly to reach another host)."""
    port = 46000 + random.randrange(3000)
    try:
        bus = open_bus("udp_multicast", f"239.74.251.7:{port}{suffix}")
    except CanBusError as exc:
        pytest.skip(f"udp_multicast cannot bind here: {exc}")
    try:
        address, got_port = socket.socket(fileno=os.dup(bus.fileno())).getsockname()
        assert (address, got_port) == (bound, port)
    finally:
        bus.shutdown()


@pytest.mark.parametrize("channel", ["239.74.1.1:x", "ff02::1", "239.74.1.1@eth0", "nowhere"])
def test_a_bad_can_channel_is_one_clear_error(channel: str) -> None:
    with pytest.raises(CanBusError, match="GROUP\\[:PORT\\]\\[@ADDRESS\\]"):
        open_bus("udp_multicast", channel)


@pytest.mark.parametrize(("channel", "why"), [
    ("239.1.1.1:99999", "port 99999 is not a UDP port"),  # was OverflowError from bind()
    ("239.1.1.1:70000@any", "port 70000 is not a UDP port"),
    ("239.1.1.1:0", "port 0 is not a UDP port"),  # was bound to a port the kernel picked
    ("999.1.1.1:43113", "999.1.1.1 is not an IPv4 multicast group"),
    ("10.1.1.1:43113@any", "10.1.1.1 is not an IPv4 multicast group"),
    ("239.1.1.1:43113@999.1.1.1", "999.1.1.1 is not an IPv4 address"),
])
def test_a_can_channel_out_of_range_is_one_clear_error(channel: str, why: str) -> None:
    with pytest.raises(CanBusError, match=f"channel {channel}: {why}"):
        open_bus("udp_multicast", channel).shutdown()


def test_the_cli_refuses_a_bad_can_channel_before_serving(tmp_path: Path) -> None:
    """One line and exit 2, before the dashboard or the Modbus line listens (it was a
    traceback after both had started)."""
    port, modbus = _free_port(), _free_port()
    proc = subprocess.run(
        [sys.executable, "-m", "app", "--can-interface", "udp_multicast", "--can-channel",
         "239.1.1.1:99999", "--port", str(port), "--modbus-port", str(modbus), "--no-record",
         "--state-dir", str(tmp_path), "--run-for", "0"],
        cwd=ROOT, capture_output=True, text=True, timeout=START_TIMEOUT_S)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == ("fieldrig: error: --can-channel: cannot open CAN interface "
                           "udp_multicast channel 239.1.1.1:99999: port 99999 is not a UDP "
                           "port (1..65535)\n")
    assert "FieldRig:" not in proc.stdout, proc.stdout  # nothing was served


def test_modbus_server_defaults_to_loopback() -> None:
    host = inspect.signature(DriveModbusServer).parameters["host"].default
    assert _loopback(host)


# ---- files are data, never code ----------------------------------------------------------------
PAYLOAD = "__import__('pathlib').Path({marker!r}).write_text('ran')"


def test_a_rig_file_holding_python_is_a_parse_error(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    code = f"import pathlib\n{PAYLOAD.format(marker=str(marker))}\n"
    with pytest.raises(RigConfigError, match="not valid TOML"):
        parse_rig_spec(code, "evil.toml")
    assert not marker.exists()


def _literal(text: str) -> str:
    """A TOML multi-line literal string: taken as written, quotes included."""
    return f"'''{text}'''"


def test_python_in_a_rig_value_stays_a_string(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    payload = PAYLOAD.format(marker=str(marker))
    text = f"[rig]\nname = {_literal(payload)}\n[[fastcat]]\nmodules = [\"DI16\"]\n"
    rig = build_rig(parse_rig_spec(text, "evil.toml"), state_dir=None)
    assert rig.name == payload
    assert not marker.exists()


def test_python_in_a_scenario_is_refused_not_run(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    payload = PAYLOAD.format(marker=str(marker))
    with pytest.raises(ScenarioError, match="not valid TOML"):
        parse_scenario(f"exec({payload!r})\n", "evil.toml")
    scenario = parse_scenario(f"[[step]]\nat = 1\ntarget = \"fastcat\"\n"
                              f"action = {_literal(payload)}\n", "evil.toml")
    assert scenario.steps[0].action == payload
    rig = build_rig(parse_rig_spec("[[fastcat]]\nmodules = [\"DI16\"]\n"), state_dir=None)
    with pytest.raises(ScenarioError):
        check_against(scenario, rig)
    assert not marker.exists()


def test_the_cli_does_not_run_a_python_file_given_as_scenario_or_rig(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    evil = tmp_path / "evil.py"
    evil.write_text(f"{PAYLOAD.format(marker=str(marker))}\n", encoding="utf-8")
    for args in (["scenario", "run", str(evil)],
                 ["--rig", str(evil), "--state-dir", str(tmp_path), "--run-for", "0"]):
        proc = subprocess.run([sys.executable, "-m", "app", *args], cwd=ROOT,
                              capture_output=True, text=True, timeout=START_TIMEOUT_S)
        assert proc.returncode == 2 and "not valid TOML" in proc.stderr, proc.stderr
    assert not marker.exists()
