"""A drive and its CANopen node on one simulated clock, and a master's view of the wire.

The bench steps drive then node (as the rig does), 1 ms per step, offers the master's frames
to the node and collects what the node sends, each frame with the simulated time it left the
bus. Nothing here sleeps or touches a socket.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass, field

from devices.canopen.bus_timing import CanFrame
from devices.canopen.node import CanOpenNode
from devices.events import Event
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

MS = 1_000
h = bytes.fromhex
CANOPEN_ENABLE = (0x0000, 0x0080, 0x0000, 0x0006, 0x0007, 0x000F)  # seed 004 ch. 4 examples


def hexs(data: bytes) -> str:
    return data.hex(" ").upper()


@dataclass
class Bench:
    drive: ServoDrive
    node: CanOpenNode
    flash: MemoryFlash
    t_us: int = 0
    sent: list[CanFrame] = field(default_factory=list)  # by the node, in order, all of them
    events: list[Event] = field(default_factory=list)
    mark: int = 0  # where take() continues

    def step(self) -> None:
        self.t_us += MS
        self.drive.step(self.t_us)
        self.node.step(self.t_us)
        self.sent += self.node.take_frames()
        self.events += self.drive.drain_events() + self.node.drain_events()

    def run(self, ms: float) -> None:
        end = self.t_us + round(ms * MS)
        while self.t_us < end:
            self.step()

    def run_until(self, condition: Callable[[], bool], timeout_ms: float) -> float:
        start = self.t_us
        while not condition():
            if self.t_us - start > timeout_ms * MS:
                raise AssertionError(f"condition not met within {timeout_ms} ms")
            self.step()
        return (self.t_us - start) / MS

    # ---- the master's side ---------------------------------------------------------------
    def send(self, can_id: int, data: bytes = b"", rtr: bool = False, dlc: int | None = None
             ) -> None:
        self.node.receive(can_id, data, rtr, dlc)

    def take(self) -> list[CanFrame]:
        """The frames sent since the previous take()."""
        out, self.mark = self.sent[self.mark:], len(self.sent)
        return out

    def request(self, can_id: int, data: bytes, answer_id: int | None = None,
                timeout_ms: float = 100) -> CanFrame | None:
        """Send one frame, step until a frame with ``answer_id`` comes (None: timeout)."""
        seen = len(self.sent)
        self.send(can_id, data)
        start = self.t_us
        while self.t_us - start < timeout_ms * MS:
            self.step()
            for frame in self.sent[seen:]:
                if answer_id is None or frame.can_id == answer_id:
                    return frame
        return None

    def sdo(self, request_hex: str) -> str:
        """One SDO request (hex, 8 bytes) -> the response bytes (hex, upper case)."""
        node = self.node.node_id
        answer = self.request(0x600 + node, h(request_hex), 0x580 + node)
        assert answer is not None, f"no SDO answer to {request_hex}"
        return hexs(answer.data)

    def write(self, index: int, sub: int, value: int, size: int) -> str:
        cmd = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
        data = bytes((cmd,)) + index.to_bytes(2, "little") + bytes((sub,)) \
            + (value & (1 << 8 * size) - 1).to_bytes(size, "little").ljust(4, b"\0")
        return self.sdo(hexs(data))

    def ok(self, index: int, sub: int, value: int, size: int) -> None:
        answer = self.write(index, sub, value, size)
        assert answer.startswith("60"), f"0x{index:04X}:{sub} = {value}: {answer}"

    def read(self, index: int, sub: int = 0) -> int:
        answer = h(self.sdo(hexs(bytes((0x40,)) + index.to_bytes(2, "little")
                                 + bytes((sub, 0, 0, 0, 0)))))
        assert answer[0] & 0xE3 == 0x43, f"0x{index:04X}:{sub}: {hexs(answer)}"
        size = 4 - (answer[0] >> 2 & 3)
        return int.from_bytes(answer[4:4 + size], "little")

    def nmt(self, command: int, node: int | None = None) -> None:
        self.send(0x000, bytes((command, self.node.node_id if node is None else node)))
        self.run(2)

    def kinds(self, kind: str) -> list[dict]:
        return [e.to_record() for e in self.events if e.kind == kind]


def make_bench(n1: int = 6, node_id: int = 1, fieldbus: str = "canopen", boot: bool = True,
               device_name: str | None = None, flash: MemoryFlash | None = None) -> Bench:
    flash = flash if flash is not None else MemoryFlash()
    config = DriveConfig(node_id=node_id, fieldbus=fieldbus, parameters={"n1": n1})
    drive = ServoDrive("servo", random.Random(7), config, flash)
    kwargs = {"device_name": device_name} if device_name is not None else {}
    node = CanOpenNode("servo-can", drive, **kwargs)
    bench = Bench(drive, node, flash)
    if boot:
        bench.run(60)  # drive self test and node Initialisation: boot-up sent
    return bench
