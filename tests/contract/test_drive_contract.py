"""One drive model, three fieldbuses: the same commands give the same drive (issue 4).

One contract class is re-run per transport by overriding constants, as python-can's
Back2BackTestCase does. Each transport speaks its own bus, in process, on one simulated clock
(the drive, then its bus side, 1 ms per step):

- Modbus RTU (seed 004 ch. 2): request PDUs through ``app.modbus.pdu.serve_line``, the
  register sequences of the ch. 2 examples (R00 = 8, 3, 0x43, 0x23; 32-bit FC 16 writes);
- CANopen (ch. 4): expedited SDO frames to the node's SDO server, EMCY frames from the node;
- EtherCAT CoE (ch. 5): the slave in OP with the master's frames, SDO through its mailbox,
  emergencies from its mailbox.

CANopen and CoE use the CiA 402 sequences of ch. 4 (enable 0x0000, 0x0080, 0x0000, 0x0006,
0x0007, 0x000F; homing 0x001F; positioning 0x001F; reset 0x80, ch. 5). What the bus shows is
checked against the transport's constants; the drive itself (state, position, statusword,
alarm and 0x603F code) against constants shared by every transport.
"""

from __future__ import annotations

import random
from typing import ClassVar

from app.modbus.pdu import Reply, serve_line
from devices.canopen.node import CanOpenNode
from devices.coe.drive_slave import DriveEcatSlave
from devices.ethercat import AlState
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

MS = 1_000
NODE = 1
CIA402_ENABLE = (0x0000, 0x0080, 0x0000, 0x0006, 0x0007, 0x000F)
HOMING_METHOD, HOME_OFFSET, SLOW_SPEED = 34, -1000, 1000  # ch. 4 "Modo Homing"
TARGET = 6000  # ch. 2 example: R09 = 0x1770
ALARM = 16  # following error; 0x603F = 0x8611 (ch. 5 table)


class Link:
    """A drive on one fieldbus, stepped 1 ms at a time; subclasses speak the bus."""

    FIELDBUS: ClassVar[str] = ""

    def __init__(self) -> None:
        self.drive = ServoDrive("drive", random.Random(5), DriveConfig(
            node_id=NODE, fieldbus=self.FIELDBUS), MemoryFlash())
        self.t_us = 0

    def bus_side_step(self) -> None:
        """The bus side of the drive steps after it, as in the rig."""

    def step(self) -> None:
        self.t_us += MS
        self.drive.step(self.t_us)
        self.bus_side_step()

    def run(self, ms: int) -> None:
        for _ in range(ms):
            self.step()

    def run_until(self, condition, timeout_ms: int) -> None:
        for _ in range(timeout_ms):
            if condition():
                return
            self.step()
        raise AssertionError(f"condition not met within {timeout_ms} ms")


class ModbusLink(Link):
    FIELDBUS = "modbus"

    def request(self, pdu: bytes) -> bytes:
        outcome = serve_line([self.drive], NODE, pdu)
        assert isinstance(outcome, Reply), outcome
        self.step()
        return outcome.pdu

    def write_register(self, n: int, value: int) -> None:
        raw = (value & 0xFFFF_FFFF).to_bytes(4, "big")
        self.request(bytes((0x10,)) + (0x8000 + n).to_bytes(2, "big") + b"\x00\x02\x04" + raw)

    def read_register(self, n: int) -> int:
        answer = self.request(bytes((0x03,)) + (0x8000 + n).to_bytes(2, "big") + b"\x00\x02")
        return int.from_bytes(answer[2:6], "big", signed=True)

    def read_parameter(self, address: int) -> int:
        answer = self.request(bytes((0x03,)) + address.to_bytes(2, "big") + b"\x00\x01")
        return int.from_bytes(answer[2:4], "big")

    # ---- the contract's operations (ch. 2 "Esempi") ---------------------------------------
    def identity(self) -> tuple[int, ...]:
        return self.read_parameter(20), self.read_parameter(22)  # c7 node, c9 fieldbus

    def status(self) -> dict[str, bool]:
        r05 = self.read_register(5)
        return {"torque": bool(r05 & 0x01), "alarm": bool(r05 & 0x08),
                "homed": bool(r05 & 0x40)}

    def position(self) -> int:
        return self.read_register(6)

    def alarm(self) -> int:
        return self.read_register(46)

    def enable(self) -> None:
        self.write_register(0, 0x08)
        self.write_register(0, 0x03)

    def home(self) -> None:
        for n, value in ((18, HOMING_METHOD), (19, HOME_OFFSET), (21, SLOW_SPEED), (1, 6)):
            self.write_register(n, value)
        self.write_register(0, 0x03)
        self.write_register(0, 0x43)

    def move(self, target: int) -> None:
        self.write_register(1, 1)
        self.write_register(9, target)
        self.write_register(0, 0x03)
        self.write_register(0, 0x23)

    def reset_alarm(self) -> None:
        self.write_register(0, 0x08)
        self.write_register(0, 0x00)


class Cia402Link(Link):
    """CANopen and CoE: the same objects, the same ch. 4 sequences; the bus differs."""

    def upload(self, index: int, sub: int) -> bytes:
        raise NotImplementedError

    def download(self, index: int, sub: int, data: bytes) -> None:
        raise NotImplementedError

    def emergency_codes(self) -> list[int]:
        raise NotImplementedError

    def read(self, index: int, sub: int = 0, signed: bool = False) -> int:
        return int.from_bytes(self.upload(index, sub), "little", signed=signed)

    def write(self, index: int, sub: int, value: int, size: int) -> None:
        self.download(index, sub, (value & (1 << 8 * size) - 1).to_bytes(size, "little"))

    def cw(self, *values: int) -> None:
        for value in values:
            self.write(0x6040, 0, value, 2)

    def identity(self) -> tuple[int, ...]:
        return self.read(0x1000), self.read(0x1018, 1)

    def status(self) -> dict[str, bool]:
        sw = self.read(0x6041)
        return {"torque": sw & 0x6F == 0x27, "alarm": bool(sw & 0x08),
                "homed": bool(sw & 0x1000) and self.read(0x6061, signed=True) == 6}

    def position(self) -> int:
        return self.read(0x6064, signed=True)

    def enable(self) -> None:
        self.cw(*CIA402_ENABLE)

    def home(self) -> None:
        self.write(0x6098, 0, HOMING_METHOD, 1)
        self.write(0x607C, 0, HOME_OFFSET, 4)
        self.write(0x6099, 2, SLOW_SPEED, 4)
        self.write(0x6060, 0, 6, 1)
        self.cw(0x000F, 0x001F)

    def move(self, target: int) -> None:
        """DSP 402 set-point handshake: bit 4 up, set-point acknowledge (0x6041 bit 12), bit 4
        down again (the register view's Pos_str clears by itself, ch. 2)."""
        self.write(0x6060, 0, 1, 1)
        self.write(0x607A, 0, target, 4)
        self.cw(0x000F, 0x001F)
        self.run_until(lambda: self.read(0x6041) & 0x1000, 50)
        self.cw(0x000F)

    def reset_alarm(self) -> None:
        self.cw(0x0080, 0x0000)  # ch. 5 "Reset allarmi": 0x80 on 0x6040


class CanOpenLink(Cia402Link):
    FIELDBUS = "canopen"

    def __init__(self) -> None:
        super().__init__()
        self.node = CanOpenNode("drive-can", self.drive)
        self.emcy: list[bytes] = []
        self.answers: list[bytes] = []

    def bus_side_step(self) -> None:
        self.node.step(self.t_us)
        for frame in self.node.take_frames():
            if frame.can_id == 0x580 + NODE:
                self.answers.append(frame.data)
            elif frame.can_id == 0x080 + NODE:
                self.emcy.append(frame.data)

    def _sdo(self, request: bytes) -> bytes:
        self.answers.clear()
        self.node.receive(0x600 + NODE, request)
        self.run_until(lambda: bool(self.answers), 50)
        answer = self.answers[0]
        assert answer[0] != 0x80, f"SDO abort 0x{int.from_bytes(answer[4:], 'little'):08X}"
        return answer

    def upload(self, index: int, sub: int) -> bytes:
        answer = self._sdo(b"\x40" + index.to_bytes(2, "little") + bytes((sub, 0, 0, 0, 0)))
        return answer[4:8 - (answer[0] >> 2 & 3)]

    def download(self, index: int, sub: int, data: bytes) -> None:
        command = 0x23 | (4 - len(data)) << 2
        self._sdo(bytes((command,)) + index.to_bytes(2, "little") + bytes((sub,))
                  + data.ljust(4, b"\0"))

    def emergency_codes(self) -> list[int]:
        return [int.from_bytes(frame[:2], "little") for frame in self.emcy]

    def alarm(self) -> int:
        return self.emergency_codes()[-1]


class CoeLink(Cia402Link):
    FIELDBUS = "ethercat"

    def __init__(self) -> None:
        super().__init__()
        self.slave = DriveEcatSlave("drive-ecat", self.drive)
        self.emcy: list[bytes] = []

    def bus_side_step(self) -> None:
        self.slave.step(self.t_us)
        self.slave.exchange_frame(self.t_us)  # the master's cyclic frame
        self.emcy += self.slave.take_emergencies()

    def start(self) -> None:
        for state in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
            self.slave.request_state(state)
            self.step()
        assert self.slave.al_state is AlState.OP

    def upload(self, index: int, sub: int) -> bytes:
        data = self.slave.sdo_upload(index, sub)
        self.step()
        return data

    def download(self, index: int, sub: int, data: bytes) -> None:
        self.slave.sdo_download(index, sub, data)
        self.step()

    def emergency_codes(self) -> list[int]:
        return [int.from_bytes(frame[:2], "little") for frame in self.emcy]

    def alarm(self) -> int:
        return self.read(0x603F)


class DriveContract:
    """The contract; ``Test*`` subclasses choose the transport and what its bus shows."""

    LINK: ClassVar[type[Link]]
    IDENTITY: ClassVar[tuple[int, ...]]
    ALARM_SEEN_AS: ClassVar[int]  # R46 on Modbus, the 0x603F code on CANopen / CoE
    # The drive, whichever bus drives it (statusword = 0x6041 as the model computes it).
    AFTER_ENABLE: ClassVar[dict[str, object]] = {
        "state": "Operation enabled", "statusword": 0x0637, "alarms": [], "error_code": 0}
    AFTER_HOMING: ClassVar[dict[str, object]] = {
        "state": "Operation enabled", "statusword": 0x1637, "position": 1000, "homed": True}
    AFTER_MOVE: ClassVar[dict[str, object]] = {
        "state": "Operation enabled", "statusword": 0x0637, "position": TARGET}
    AFTER_ALARM: ClassVar[dict[str, object]] = {
        "state": "Fault", "statusword": 0x0608, "alarms": [ALARM], "error_code": 0x8611}
    # Bit 15 follows TEN, IEN and Ien_cmd (ch. 4): the Modbus reset ends with R00 = 0, Ien_cmd
    # low, 0x8640 as the fresh drive's (ch. 6 example); a CiA 402 master holds Ien_cmd: 0x0640
    AFTER_RESET: ClassVar[dict[str, object]] = {
        "state": "Switch on disabled", "statusword": 0x8640, "alarms": [], "error_code": 0}
    CIA402_AFTER_RESET: ClassVar[dict[str, object]] = {**AFTER_RESET, "statusword": 0x0640}

    def setup_method(self) -> None:
        self.link = self.LINK()
        self.link.run(100)  # self test (50 ms), CANopen boot-up
        start = getattr(self.link, "start", None)
        if start is not None:
            start()
        self.drive = self.link.drive

    def model(self, *keys: str) -> dict[str, object]:
        d = self.drive
        values = {"state": d.state.label, "statusword": d.statusword,
                  "alarms": list(d.alarms.latched), "error_code": d.error_code(),
                  "position": d.position_user, "homed": d.homed}
        return {k: values[k] for k in keys}

    def _enable(self) -> None:
        self.link.enable()
        self.link.run(5)

    def _home(self) -> None:
        self._enable()
        self.link.home()
        self.link.run_until(lambda: self.drive.statusword & 0x3000, 20_000)

    def test_identity_and_state(self) -> None:
        assert self.link.identity() == self.IDENTITY
        assert self.link.status() == {"torque": False, "alarm": False, "homed": False}
        assert self.drive.state.label == "Switch on disabled"

    def test_enable(self) -> None:
        self._enable()
        assert self.model(*self.AFTER_ENABLE) == self.AFTER_ENABLE
        assert self.link.status()["torque"]

    def test_homing_method_34_offset_minus_1000(self) -> None:
        """Ch. 4 "Modo Homing": method 34, home offset -1000: "la posizione attuale varrà
        1000", statusword bit 12 (Homing ok, R05 bit 6 on Modbus)."""
        self._home()
        assert self.model(*self.AFTER_HOMING) == self.AFTER_HOMING
        assert self.link.position() == 1000
        assert self.link.status() == {"torque": True, "alarm": False, "homed": True}

    def test_profile_position_move(self) -> None:
        self._home()
        self.link.move(TARGET)
        self.link.run_until(lambda: self.drive.position_user == TARGET
                            and self.drive.statusword & 0x0400, 20_000)
        assert self.model(*self.AFTER_MOVE) == self.AFTER_MOVE
        assert self.link.position() == TARGET

    def test_injected_alarm_and_reset(self) -> None:
        self._enable()
        self.drive.apply("inject_alarm", {"code": str(ALARM)})
        self.link.run(5)
        assert self.model(*self.AFTER_ALARM) == self.AFTER_ALARM
        assert self.link.alarm() == self.ALARM_SEEN_AS
        assert self.link.status()["alarm"]
        self.drive.apply("clear_alarm", {"code": str(ALARM)})
        self.link.reset_alarm()
        self.link.run(5)
        assert self.model(*self.AFTER_RESET) == self.AFTER_RESET
        assert not self.link.status()["alarm"]


class TestModbus(DriveContract):
    LINK = ModbusLink
    IDENTITY = (NODE, 3)  # c7, c9 = 3 (ch. 2)
    ALARM_SEEN_AS = ALARM  # R46 alarm_code

    def test_alarm_code_clears_after_reset(self) -> None:
        self.test_injected_alarm_and_reset()
        assert self.link.alarm() == 0


class TestCanOpen(DriveContract):
    LINK = CanOpenLink
    IDENTITY = (0x00020192, 0x0000078F)  # 0x1000, 0x1018:1
    ALARM_SEEN_AS = 0x8611  # the EMCY's error code
    AFTER_RESET = DriveContract.CIA402_AFTER_RESET

    def test_emergencies_raise_and_reset(self) -> None:
        self.test_injected_alarm_and_reset()
        assert isinstance(self.link, Cia402Link)
        assert self.link.emergency_codes() == [0x8611, 0x0000]


class TestCoe(DriveContract):
    LINK = CoeLink
    IDENTITY = (0x00020192, 0x0000078F)
    ALARM_SEEN_AS = 0x8611  # 0x603F
    AFTER_RESET = DriveContract.CIA402_AFTER_RESET

    def test_emergencies_raise_and_reset(self) -> None:
        self.test_injected_alarm_and_reset()
        assert isinstance(self.link, Cia402Link)
        assert self.link.emergency_codes() == [0x8611, 0x0000]
