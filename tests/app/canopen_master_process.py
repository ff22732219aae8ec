"""The CANopen master process of tests/app/test_canopen_master.py (run as a script).

The python ``canopen`` library as a real master — BaseNode402 built from static/eds — on
python-can's ``udp_multicast`` interface. It runs seed 004 ch. 4 "Esempi CANopen" against the
drive and prints one JSON line per step (``{"step": ..., "ok": true, ...}``, or
``{"error": ...}``); where the drive's side must act (power on, inject or clear an alarm) it
prints ``{"wait": ...}`` and reads "go" from stdin.

    python tests/app/canopen_master_process.py --channel 239.74.10.20 --port 45000
"""

from __future__ import annotations

import argparse
import json
import struct
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import canopen
from canopen.sdo import SdoVariable
from canopen.sdo.exceptions import SdoAbortedError

from app.canopen_bus import open_bus

ROOT = Path(__file__).resolve().parents[2]
EDS = ROOT / "static" / "eds" / "servo_drive.eds"
NODE = 1
SPEED = 3.0  # the simulation speed the test runs the drive at (the model steps ~5x real time)


class Master:
    def __init__(self, channel: str, port: int) -> None:
        self.frames: list[tuple[float, int, bytes, bool]] = []
        self.lock = threading.Lock()
        # The drive's side opens the bus on loopback (app/canopen_bus.py): so does the master.
        self.network = canopen.Network(open_bus("udp_multicast", f"{channel}:{port}"))
        self.network.listeners.append(_recorder(self))
        self.node = canopen.BaseNode402(NODE, str(EDS))
        self.node.sdo.RESPONSE_TIMEOUT = 2.0
        self.network.add_node(self.node)
        self.network.connect()

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
    def _variable(self, index: int, sub: int) -> Any:
        target = self.node.sdo[index]
        return target if isinstance(target, SdoVariable) else target[sub]

    def write(self, index: int, sub: int, value: int) -> None:
        self._variable(index, sub).raw = value

    def read(self, index: int, sub: int = 0) -> int:
        return self._variable(index, sub).raw

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
        # udp_multicast hands the master its own request back: both frames, byte for byte
        assert self.seen(t0, 0x600 + NODE)[-1].hex(" ").upper() == "2B 17 10 00 A0 0F 00 00"
        assert self.seen(t0, 0x580 + NODE)[-1].hex(" ").upper() == "60 17 10 00 00 00 00 00"
        self.until("two heartbeats", lambda: len(self.seen(t0, 0x700 + NODE)) >= 2,
                   2 * 4.0 + 4)  # 8 s of simulated time, even if the simulation lags
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
                   lambda: b"\x05" in self.seen(t0, 0x700 + NODE), 4.0 + 4)
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
        # Lock-step: each cycle waits for the TPDO its SYNC asks for (at most 2 s; the drive
        # answers within a 1 ms step). Sent open-loop every 2 ms, 300 cycles put 900 frames
        # on the multicast group in 0.6 s, and a reader stalled by a loaded machine lost a
        # burst of them to a full socket buffer (236 TPDOs for 300 SYNCs once in CI).
        late = []
        for cycle in range(cycles):
            answered = len(self.seen(t0, 0x180 + NODE))
            self.network.sync.transmit()
            set_point += 20
            self.network.send_message(0x200 + NODE, struct.pack("<iH", set_point, 0x001F))
            deadline = time.monotonic() + 2.0
            while len(self.seen(t0, 0x180 + NODE)) <= answered:
                if time.monotonic() > deadline:
                    late.append(cycle)
                    break
                time.sleep(0.0005)
        time.sleep(0.3)  # an answer that came after its deadline is still counted
        feedback = [struct.unpack("<iH", d) for d in self.seen(t0, 0x180 + NODE)]
        positions = [p for p, _ in feedback]
        final = self.read(0x6064)
        self.write(0x6040, 0, 0x000F)  # "Fermata normale": interpolator off
        assert len(feedback) == cycles, (len(feedback), late)
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


def _recorder(master: Master) -> Callable[[Any], None]:
    """A python-can listener that keeps every frame (wall time, id, data, rtr)."""

    def record(msg: Any) -> None:
        with master.lock:
            master.frames.append((time.monotonic(), msg.arbitration_id, bytes(msg.data),
                                  msg.is_remote_frame))
    return record


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


if __name__ == "__main__":
    sys.exit(master_main(sys.argv[1:]))
