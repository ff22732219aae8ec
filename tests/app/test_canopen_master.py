"""A real CANopen master against the running drive: the seed's worked sequences end to end.

Seed 004 ch. 4 "Esempi CANopen" (homing method 34 with offset -1000, profile position
incremental then absolute, velocity at 1000 rpm, save, interpolator with its Sync + PDO loop),
"Device Configuration via SDOs" (the 1017 / 1018 frames, aborts), "Emergency Message".

The master is the python ``canopen`` library (BaseNode402 built from static/eds) in a separate
process (tests/app/canopen_master_process.py) on python-can's ``udp_multicast`` interface, a unique
group and port per run; the drive runs in a :class:`~app.runtime.Runtime` in the test process
with the CANopen adapter. The two talk over stdin/stdout JSON lines where the test must act
on the drive's side (power on, inject and clear an alarm).
A second, in-process test checks a RemoteNode built from the EDS over the virtual interface.
"""

from __future__ import annotations

import json
import queue
import random
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import can
import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError
from canopen_master_process import EDS, NODE, SPEED

from app.canopen_bus import CanBusError, CanOpenBus, open_bus
from app.rig import Rig
from app.runtime import Runtime
from devices.canopen.node import CanOpenNode
from devices.events import Event
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

ROOT = Path(__file__).resolve().parents[2]
MASTER = Path(__file__).resolve().parent / "canopen_master_process.py"
WALL_LIMIT_S = 90.0


@contextmanager
def running_drive(interface: str, channel: str, speed: float
                  ) -> Iterator[tuple[Runtime, CanOpenNode, MemoryFlash, list[Event]]]:
    flash = MemoryFlash()
    drive = ServoDrive("servo", random.Random(3), DriveConfig(fieldbus="canopen",
                                                              node_id=NODE), flash)
    node = CanOpenNode("servo-can", drive)
    runtime = Runtime(Rig("canopen", {"servo": drive, "servo-can": node}), speed=speed)
    events: list[Event] = []
    runtime.add_listener(events.extend)
    bus = CanOpenBus([node], runtime.submit, interface, channel)
    bus.attach(runtime)
    bus.start()
    runtime.start()
    try:
        yield runtime, node, flash, events
    finally:
        runtime.stop()
        bus.stop()

def _unique_group() -> tuple[str, int]:
    rng = random.Random()
    return f"239.74.{rng.randrange(1, 255)}.{rng.randrange(1, 255)}", \
        rng.randrange(40_000, 60_000)

def test_remote_node_from_the_eds_talks_to_the_drive() -> None:
    """In-process, python-can's virtual bus: read 0x1018, set the heartbeat, hear it."""
    channel = f"fieldrig-test-{random.randrange(1 << 30)}"
    with running_drive("virtual", channel, 1.0) as (runtime, node, _flash, _events):
        network = canopen.Network()
        remote = canopen.RemoteNode(NODE, str(EDS))
        network.add_node(remote)
        network.connect(interface="virtual", channel=channel)
        try:
            runtime.command("servo", "power", {"on": False}).result(5)
            runtime.command("servo", "power", {"on": True}).result(5)
            remote.nmt.wait_for_bootup(5)
            assert remote.sdo[0x1018][1].raw == 0x078F
            assert remote.sdo[0x1008].raw == "SDrive"
            # No block transfer in the drive: canopen's block upload (pst 0) gets the abort
            # DS 301 owes it, not a plain upload answer it cannot parse
            with pytest.raises(SdoAbortedError) as aborted:
                remote.sdo[0x1008].open("rb", block_transfer=True)
            assert aborted.value.code == 0x0504_0001
            assert remote.sdo[0x1008].raw == "SDrive"  # the channel serves on
            remote.sdo[0x1017].raw = 50
            assert remote.nmt.wait_for_heartbeat(2) == "PRE-OPERATIONAL"
            remote.nmt.state = "OPERATIONAL"
            assert remote.nmt.wait_for_heartbeat(2) == "OPERATIONAL"
        finally:
            network.disconnect()
        kinds = {entry["kind"] for entry in node.monitor.frames}
        assert {"SDO", "NMT", "NMT-EC", "PDO"} <= kinds

def test_canopen_master_in_another_process() -> None:
    group, port = _unique_group()
    try:
        open_bus("udp_multicast", f"{group}:{port}").shutdown()
    except CanBusError as exc:
        pytest.skip(f"udp_multicast cannot bind here: {exc}")
    with running_drive("udp_multicast", f"{group}:{port}", SPEED) as (
            runtime, node, flash, events):
        runtime.command("servo", "power", {"on": False}).result(5)
        proc = subprocess.Popen(
            [sys.executable, str(MASTER), "--channel", group, "--port", str(port)],
            cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=lambda: [lines.put(x) for x in proc.stdout],  # type: ignore
                         daemon=True).start()
        results: dict[str, dict] = {}
        end = time.monotonic() + WALL_LIMIT_S
        try:
            while True:
                line = lines.get(timeout=max(0.1, end - time.monotonic()))
                msg = json.loads(line)
                assert "error" not in msg, f"{msg['error']} after {sorted(results)}"
                if "wait" in msg:
                    _act(runtime, msg)
                    proc.stdin.write("go\n")  # type: ignore[union-attr]
                    proc.stdin.flush()  # type: ignore[union-attr]
                elif "step" in msg:
                    results[msg["step"]] = msg
                elif msg.get("done"):
                    break
        except queue.Empty:
            pytest.fail(f"the master did not finish in {WALL_LIMIT_S} s; got "
                        f"{sorted(results)}")
        finally:
            proc.stdin.close()  # type: ignore[union-attr]
            proc.wait(10)
        assert proc.returncode == 0
        snapshot = runtime.submit(node.snapshot).result(5)
    assert snapshot["nmt"] == "Operational"
    assert snapshot["bus"]["syncs"] >= 300  # the interpolator loop's Syncs all arrived
    assert results["homing"]["position"] == 1000
    assert results["profile_position"]["positions"] == [61000, 30000]
    assert abs(results["velocity"]["rpm"] - 1000) <= 10
    assert results["alarm_emcy"]["emcy"] == "11 86 21 10 00 00 00 00"
    assert flash.load() is not None  # the save reached the flash
    nmt = [(e.from_state, e.to_state) for e in events
           if e.kind == "state" and getattr(e, "machine", "") == "nmt"]
    assert ("Pre-operational", "Operational") in nmt
    emergencies = [e.to_record() for e in events if e.kind == "emergency"]
    assert [e["code"] for e in emergencies] == ["0x8611", "0x0000"]

def _act(runtime: Runtime, msg: dict) -> None:
    what = msg["wait"]
    if what == "power_on":
        runtime.command("servo", "power", {"on": True}).result(5)
    elif what in ("inject_alarm", "clear_alarm"):
        runtime.command("servo", what, {"code": str(msg["code"])}).result(5)
    else:
        raise AssertionError(f"unknown request from the master: {msg}")


# ---- the adapter on its own ------------------------------------------------------------------
class _Now:
    """``submit`` that runs the function at once (no simulation thread needed)."""

    def __call__(self, fn):  # type: ignore[no-untyped-def]
        fn()


def _node(node_id: int) -> CanOpenNode:
    drive = ServoDrive(f"servo{node_id}", random.Random(node_id),
                       DriveConfig(fieldbus="canopen", node_id=node_id), MemoryFlash())
    return CanOpenNode(f"servo{node_id}-can", drive)


def test_udp_multicast_echoes_of_own_frames_are_dropped() -> None:
    """udp_multicast hands a sender its own datagrams back: the adapter drops exactly those."""
    node = _node(1)
    bus = CanOpenBus([node], _Now(), "udp_multicast", "239.74.1.1:45999")
    bus.bus = type("FakeBus", (), {"send": lambda self, msg, timeout=None: None})()
    node.step(1_000)
    node.step(60_000)  # boot-up sent
    bus.on_step(60_000)
    boot = can.Message(arbitration_id=0x701, data=b"\0", is_extended_id=False)
    bus._on_message(boot)  # the echo of our boot-up: dropped
    bus._on_message(boot)  # a second one is someone else's: delivered
    assert bus.received == 1 and bus.sent == 1


def test_nodes_on_one_adapter_hear_each_other() -> None:
    """PDO linking between two drives of the rig: node 2's RPDO1 listens to node 1's TPDO1."""
    first, second = _node(1), _node(2)
    bus = CanOpenBus([first, second], _Now(), "virtual", "unused")
    for t in range(1_000, 61_000, 1_000):
        for node in (first, second):
            node.drive.step(t)
            node.step(t)
        bus.on_step(t)
    heard = [f["text"] for f in second.monitor.frames if f["dir"] == "rx"]
    assert "node 1: boot-up" in heard


def test_open_bus_refuses_an_unknown_interface() -> None:
    with pytest.raises(CanBusError, match="not one of virtual, udp_multicast, socketcan"):
        open_bus("pcan")
