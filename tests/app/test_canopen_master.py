"""A real CANopen master against the running drive: the seed's worked sequences end to end.

Seed 004 ch. 4 "Esempi CANopen" (homing method 34 with offset -1000, profile position
incremental then absolute, velocity at 1000 rpm, save, interpolator with its Sync + PDO loop),
"Device Configuration via SDOs" (the 1017 / 1018 frames, aborts), "Emergency Message".

The master is the python ``canopen`` library (BaseNode402 built from static/eds) in a separate
process (this file run as a script) on python-can's ``udp_multicast`` interface, a unique
group and port per run; the drive runs in a :class:`~app.runtime.Runtime` in the test process
with the CANopen adapter. The two talk over stdin/stdout JSON lines where the test must act
on the drive's side (power on, inject and clear an alarm).
A second, in-process test checks a RemoteNode built from the EDS over the virtual interface.
"""

from __future__ import annotations

import argparse
import json
import queue
import random
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
EDS = ROOT / "static" / "eds" / "servo_drive.eds"
NODE = 1
SPEED = 3.0  # simulated seconds per wall second (the model steps at about 5x real time)
WALL_LIMIT_S = 90.0


# ======================================================================================
# The master process
# ======================================================================================
class Master:
    def __init__(self, channel: str, port: int) -> None:
        import can
        import canopen

        self.can = can
        self.frames: list[tuple[float, int, bytes, bool]] = []
        self.lock = threading.Lock()
        self.network = canopen.Network()
        self.network.listeners.append(_Recorder(self))
        self.node = canopen.BaseNode402(NODE, str(EDS))
        self.node.sdo.RESPONSE_TIMEOUT = 2.0
        self.network.add_node(self.node)
        self.network.connect(interface="udp_multicast", channel=channel, port=port, fd=False)

    # ---- talking to the test -------------------------------------------------------------
    @staticmethod
    def say(**fields: Any) -> None:
        print(json.dumps(fields), flush=True)

    def ask(self, what: str, **fields: Any) -> None:
        """Let the test act on the drive's side, wait for its "go"."""
        self.say(wait=what, **fields)
        line = sys.stdin.readline().strip()
        if line != "go":
            raise RuntimeError(f"test answered {line!r} to {what}")

    # ---- helpers ---------------------------------------------------------------------------
    def sdo(self, index: int, sub: int | None = None) -> Any:
        obj = self.node.sdo[index]
        return obj[sub] if sub is not None else obj

    def write(self, index: int, sub: int, value: int) -> None:
        target = self.node.sdo[index]
        if sub or not isinstance(target, type(self.node.sdo[0x6040])):
            target = target[sub]
        target.raw = value

    def read(self, index: int, sub: int = 0) -> int:
        target = self.node.sdo[index]
        if sub or not isinstance(target, type(self.node.sdo[0x6040])):
            target = target[sub]
        return target.raw

    def until(self, what: str, condition: Callable[[], bool], timeout_s: float = 20) -> None:
        end = time.monotonic() + timeout_s
        while not condition():
            if time.monotonic() > end:
                raise AssertionError(f"timed out waiting for {what}")
            time.sleep(0.005)

    def seen(self, since: float, can_id: int) -> list[bytes]:
        with self.lock:
            return [data for t, cid, data, rtr in self.frames
                    if t >= since and cid == can_id and not rtr]

    def abort_code(self, call: Callable[[], Any]) -> int:
        from canopen.sdo.exceptions import SdoAbortedError

        try:
            call()
        except SdoAbortedError as exc:
            return exc.code
        return 0

    # ---- the seed's sequences --------------------------------------------------------------
    def run(self) -> None:
        steps = [self.boot_and_identity, self.heartbeat, self.nmt_start_and_402,
                 self.homing, self.profile_position, self.velocity, self.alarm_emcy,
                 self.aborts, self.interpolated, self.save]
        for step in steps:
            started = time.monotonic()
            result = step() or {}
            self.say(step=step.__name__, ok=True, wall_s=round(time.monotonic() - started, 3),
                     **result)
        self.say(done=True)

    def boot_and_identity(self) -> dict:
        t0 = time.monotonic()
        self.ask("power_on")
        self.until("the boot-up message", lambda: b"\0" in self.seen(t0, 0x700 + NODE), 10)
        vendor = self.read(0x1018, 1)
        responses = self.seen(t0, 0x580 + NODE)
        assert vendor == 0x078F, hex(vendor)
        assert responses[-1].hex(" ").upper() == "43 18 10 01 8F 07 00 00", responses
        return {"vendor": vendor, "boot_up": [d.hex() for d in self.seen(t0, 0x700 + NODE)]}

    def heartbeat(self) -> dict:
        t0 = time.monotonic()
        self.write(0x1017, 0, 4000)  # the seed's 4 s
        assert self.seen(t0, 0x580 + NODE)[-1].hex(" ").upper() == "60 17 10 00 00 00 00 00"
        self.until("two heartbeats", lambda: len(self.seen(t0, 0x700 + NODE)) >= 2,
                   3 * 4.0 / SPEED + 2)
        with self.lock:
            beats = [(t, d) for t, cid, d, rtr in self.frames
                     if t >= t0 and cid == 0x700 + NODE and not rtr]
        gap = beats[1][0] - beats[0][0]
        assert all(d == b"\x7f" for _, d in beats), beats
        return {"heartbeat_wall_gap_s": round(gap, 3)}

    def nmt_start_and_402(self) -> dict:
        # BaseNode402 takes a TPDO it received twice for a periodic one and then waits for
        # the next: TPDO1 (statusword) gets an event timer of 20 ms, as a real master would.
        self.write(0x1800, 5, 20)
        self.node.setup_402_state_machine()  # reads the PDO configuration in Pre-operational
        # udp_multicast hands the master its own frames back; an RPDO it hears twice looks
        # periodic to canopen and is no longer sent on a change: it must not listen to them.
        for rpdo in self.node.rpdo.map.values():
            if rpdo.enabled:
                self.network.unsubscribe(rpdo.cob_id, rpdo.on_message)
        t0 = time.monotonic()
        self.node.nmt.state = "OPERATIONAL"
        self.until("a TPDO with the statusword",
                   lambda: bool(self.seen(t0, 0x180 + NODE)), 5)
        self.until("an Operational heartbeat",
                   lambda: b"\x05" in self.seen(t0, 0x700 + NODE), 4.0 / SPEED * 2 + 2)
        self.node.state = "OPERATION ENABLED"
        sw = self.read(0x6041)
        assert sw & 0x006F == 0x0027, hex(sw)
        return {"statusword": sw}

    def homing(self) -> dict:
        for index, sub, value in ((0x6092, 1, 6000), (0x6098, 0, 34), (0x607C, 0, -1000),
                                  (0x6099, 2, 1000), (0x6060, 0, 6)):
            self.write(index, sub, value)
        self.write(0x6040, 0, 0x000F)
        self.write(0x6040, 0, 0x001F)
        self.until("homing bit 12 or 13", lambda: self.read(0x6041) & 0x3000, 30)
        sw, position = self.read(0x6041), self.read(0x6064)
        assert sw & 0x3000 == 0x1000, hex(sw)
        assert position == 1000, position
        self.write(0x6040, 0, 0x000F)
        return {"statusword": sw, "position": position}

    def profile_position(self) -> dict:
        for index, value in ((0x6081, 20000), (0x6083, 200), (0x6084, 200), (0x6060, 1)):
            self.write(index, 0, value)
        reached = []
        for target, commands, expected in ((60000, (0x004F, 0x005F), 61000),
                                           (30000, (0x000F, 0x001F), 30000)):
            self.write(0x607A, 0, target)
            for cw in commands:
                self.write(0x6040, 0, cw)
            self.until(f"position {expected}", lambda e=expected: abs(self.read(0x6064) - e)
                       <= 1 and self.read(0x6041) & 0x0400, 30)
            reached.append(self.read(0x6064))
        return {"positions": reached}

    def velocity(self) -> dict:
        for index, sub, value in ((0x6092, 1, 60), (0x6083, 0, 5), (0x6084, 0, 5),
                                  (0x6060, 0, 3), (0x60FF, 0, 1000)):
            self.write(index, sub, value)
        self.until("1000 rpm", lambda: abs(self.read(0x606C) - 1000) <= 10, 10)
        rpm = self.read(0x606C)
        self.write(0x60FF, 0, 0)
        self.until("standstill", lambda: abs(self.read(0x606C)) <= 1, 10)
        self.write(0x6092, 1, 6000)
        return {"rpm": rpm}

    def alarm_emcy(self) -> dict:
        t0 = time.monotonic()
        self.ask("inject_alarm", code=16)
        self.until("an EMCY", lambda: bool(self.seen(t0, 0x80 + NODE)), 5)
        frame = self.seen(t0, 0x80 + NODE)[0]
        code, register = struct.unpack_from("<HB", frame)
        assert (code, register, frame[3]) == (0x8611, 0x21, 16), frame.hex()
        assert self.read(0x1001) == 0x21
        assert self.read(0x1003, 1) == 0x0010_8611
        t1 = time.monotonic()
        self.ask("clear_alarm", code=16)
        self.write(0x6040, 0, 0x0000)
        self.write(0x6040, 0, 0x0080)  # the seed's enable sequence starts with the reset
        self.until("the error reset EMCY", lambda: bool(self.seen(t1, 0x80 + NODE)), 5)
        reset = self.seen(t1, 0x80 + NODE)[0]
        assert reset[:3] == b"\0\0\0", reset.hex()
        return {"emcy": frame.hex(" "), "reset": reset.hex(" ")}

    def aborts(self) -> dict:
        sdo = self.node.sdo
        codes = {
            "missing object 0x2007": self.abort_code(lambda: sdo.upload(0x2007, 0)),
            "missing sub 0x1018:5": self.abort_code(lambda: sdo.upload(0x1018, 5)),
            "read-only 0x1018:1": self.abort_code(
                lambda: sdo.download(0x1018, 1, b"\1\0\0\0")),
            "write-only 0x60C1:1": self.abort_code(lambda: sdo.upload(0x60C1, 1)),
            "wrong length 0x1017": self.abort_code(
                lambda: sdo.download(0x1017, 0, b"\xa0\x0f\0\0")),
            "out of range 0x6060": self.abort_code(lambda: sdo.download(0x6060, 0, b"\5")),
            "mapping too long 0x1A01": self._mapping_too_long(),
        }
        expected = {"missing object 0x2007": 0x06020000, "missing sub 0x1018:5": 0x06090011,
                    "read-only 0x1018:1": 0x06010002, "write-only 0x60C1:1": 0x06010001,
                    "wrong length 0x1017": 0x06070012, "out of range 0x6060": 0x06090030,
                    "mapping too long 0x1A01": 0x06040042}
        assert codes == expected, {k: hex(v) for k, v in codes.items()}
        return {"aborts": {k: f"0x{v:08X}" for k, v in codes.items()}}

    def _mapping_too_long(self) -> int:
        self.write(0x1A01, 0, 0)
        for sub, entry in ((1, 0x60640020), (2, 0x606C0020), (3, 0x60690020)):
            self.write(0x1A01, sub, entry)
        return self.abort_code(lambda: self.write(0x1A01, 0, 3))

    def interpolated(self) -> dict:
        """Ch. 4 "Modo interpolatore", PDOs configured in Pre-operational, then the loop."""
        self.node.nmt.state = "PRE-OPERATIONAL"
        for index, sub, value in (
                (0x6092, 1, 6000), (0x60C2, 1, 1), (0x6060, 0, 7),
                (0x1400, 2, 1), (0x1600, 0, 0), (0x1600, 1, 0x60C10120),
                (0x1600, 2, 0x60400010), (0x1600, 0, 2),
                (0x1800, 2, 1), (0x1A00, 0, 0), (0x1A00, 1, 0x60640020),
                (0x1A00, 2, 0x60410010), (0x1A00, 0, 2)):  # sub 2: printed "sub 1" twice
            self.write(index, sub, value)
        self.node.nmt.state = "OPERATIONAL"
        for cw in (0x0000, 0x0080, 0x0000, 0x0006, 0x0007, 0x000F):
            self.write(0x6040, 0, cw)
        start = self.read(0x6064)
        self.write(0x60C1, 1, start)  # the set-point where the axis stands, then 0x1F
        self.write(0x6040, 0, 0x001F)
        t0 = time.monotonic()
        set_point = start
        cycles = 300
        for _ in range(cycles):
            self.network.sync.transmit()
            set_point += 20
            self.network.send_message(0x200 + NODE, struct.pack("<iH", set_point, 0x001F))
            time.sleep(0.002)
        count = -1
        while count != len(self.seen(t0, 0x180 + NODE)):  # the simulation may lag a little
            count = len(self.seen(t0, 0x180 + NODE))
            time.sleep(0.3)
        feedback = [struct.unpack("<iH", d) for d in self.seen(t0, 0x180 + NODE)]
        positions = [p for p, _ in feedback]
        final = self.read(0x6064)
        self.write(0x6040, 0, 0x000F)  # "Fermata normale": interpolator off
        assert len(feedback) >= cycles * 0.9, len(feedback)
        assert positions == sorted(positions)
        assert abs(final - (set_point - 20)) <= 40, (final, set_point)
        assert feedback[-1][1] & 0x106F == 0x1027, hex(feedback[-1][1])
        return {"tpdos": len(feedback), "start": start, "final": final}

    def save(self) -> dict:
        self.write(0x6040, 0, 0x0002)  # "Disabilitazione dell'asse"
        wrong = self.abort_code(lambda: self.write(0x1010, 1, 0x12345678))
        assert wrong == 0x08000020, hex(wrong)
        self.write(0x1010, 1, 0x65766173)
        self.write(0x6040, 0, 0x0006)
        took = time.monotonic()
        self.until("Ready to switch on after the save", lambda: self.read(0x6041) & 1, 15)
        return {"save_wall_s": round(time.monotonic() - took, 3)}

    def close(self) -> None:
        self.network.disconnect()


class _Recorder:
    """A python-can listener that keeps every frame (wall time, id, data, rtr)."""

    def __init__(self, master: Master) -> None:
        self.master = master

    def on_message_received(self, msg: Any) -> None:
        with self.master.lock:
            self.master.frames.append((time.monotonic(), msg.arbitration_id, bytes(msg.data),
                                       msg.is_remote_frame))

    def __call__(self, msg: Any) -> None:
        self.on_message_received(msg)

    def stop(self) -> None:
        pass

    def on_error(self, exc: Exception) -> None:
        pass


def master_main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--channel", required=True)
    parser.add_argument("--port", type=int, required=True)
    args = parser.parse_args(argv)
    master = Master(args.channel, args.port)
    try:
        master.run()
    except Exception as exc:
        Master.say(error=f"{type(exc).__name__}: {exc}")
        return 1
    finally:
        master.close()
    return 0


# ======================================================================================
# The tests (the drive's side)
# ======================================================================================
if __name__ != "__main__":
    import pytest

    from app.canopen_bus import CanBusError, CanOpenBus, open_bus
    from app.rig import Rig
    from app.runtime import Runtime
    from devices.canopen.node import CanOpenNode
    from devices.events import Event
    from devices.flash import MemoryFlash
    from devices.servo.drive import DriveConfig, ServoDrive

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
        import canopen

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
                remote.sdo[0x1017].raw = 50
                assert remote.nmt.wait_for_heartbeat(2) == "PRE-OPERATIONAL"
                remote.nmt.state = "OPERATIONAL"
                assert remote.nmt.wait_for_heartbeat(2) == "OPERATIONAL"
            finally:
                network.disconnect()
            kinds = {entry["kind"] for entry in node.frame_log}
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
                [sys.executable, __file__, "--channel", group, "--port", str(port)],
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


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(master_main(sys.argv[1:]))
