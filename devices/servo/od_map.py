"""The drive's CiA 402 and manufacturer objects, as views on the same state as the registers.

Seed 004 ch. 4 "Oggetti implementati" (index, access, mappability, size) and the object
descriptions; ch. 5 adds 0x603F (error code) and 0x2007 (save). The CANopen and CoE adapters
serve this dictionary as it is; nothing here knows a bus. Objects backed by a register read and
write that register, so a value written by SDO is the value Modbus reads and vice versa.
Deviations from the printed table are listed in docs/servo-drive.md §Object dictionary.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from devices.device import CommandError
from devices.od import AbortCode, Access, DataType, ObjectDictionary, OdEntry, SdoAbort
from devices.servo import flashsave
from devices.servo.errors import AccessError
from devices.servo.parameters import parameter_spec
from devices.servo.registers import REGISTER_BASE, R, register_spec

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

# 0x2000's parameter writes (ch. 4: "sfrutta l'oggetto 0x2000 ... Ogni modifica è attiva dopo
# un intervallo di tempo di circa 20 ms"); 0x2006 writes parameters in HANDSHAKE_US (ch. 5:
# "Affinché la scrittura sia effettiva occorre aspettare almeno 3ms", docs/servo-drive.md).
PARAMETER_APPLY_US = 20_000
HANDSHAKE_US = 3_000  # "occorre aspettare almeno 3 ms tra la scrittura dell'indirizzo e la lettura"
# The modes 0x6060 takes and their 0x6502 bits: ch. 4 lists 1, 3, 6, 7, -1, -2, -127
# (l. 3131-3145). DSP 402 bits 0 pp, 2 pv, 5 hm, 6 ip; bits 16.. manufacturer: -1, -2, -127 in
# order. -50 (save / load) is the Modbus chapter's R01 mode, not an object dictionary one.
OD_MODE_BITS: dict[int, int] = {1: 0, 3: 2, 6: 5, 7: 6, -1: 16, -2: 17, -127: 18}
SUPPORTED_DRIVE_MODES = sum(1 << bit for bit in OD_MODE_BITS.values())  # 0x00070065

D = DataType
RO, RW, WO = Access.RO, Access.RW, Access.WO
_ABORT_BY_KIND = {"value": AbortCode.VALUE_RANGE, "readonly": AbortCode.READ_ONLY,
                  "address": AbortCode.VALUE_RANGE}


def _guard(index: int, sub: int, action: Callable[[], None]) -> None:
    """Run a model write; refusals become the SDO abort a master sees (state unchanged)."""
    try:
        action()
    except AccessError as exc:
        raise SdoAbort(_ABORT_BY_KIND[exc.kind], index, sub) from exc
    except CommandError as exc:  # powered off, saving
        raise SdoAbort(AbortCode.CANNOT_STORE_STATE, index, sub) from exc


def _set_od_mode(drive: ServoDrive, mode: int) -> None:
    """0x6060: a mode 0x6502 lists (a value range abort for any other, -50 included)."""
    if mode not in OD_MODE_BITS:
        raise AccessError("value", f"mode {mode} is not one of 0x6502's "
                                   f"{', '.join(str(m) for m in OD_MODE_BITS)}")
    drive.set_mode(mode)


def _fit(dtype: DataType, value: int) -> int:
    """A register value in an object's type (a 16-bit view shows the low 16 bits)."""
    bits = {D.INTEGER8: 8, D.UNSIGNED8: 8, D.INTEGER16: 16, D.UNSIGNED16: 16,
            D.INTEGER32: 32, D.UNSIGNED32: 32}[dtype]
    value &= (1 << bits) - 1
    if dtype in (D.INTEGER8, D.INTEGER16, D.INTEGER32) and value >> (bits - 1):
        value -= 1 << bits
    return value


class IndirectAccess:
    """0x2000 (parameters), 0x2005 / 0x2006 (parameters and registers by address).

    Writing the address starts the operation; the address reads back as it was written until
    the drive is done, then 0 (ch. 4 "Procedura per la lettura e la scrittura dei parametri").
    """

    def __init__(self, drive: ServoDrive) -> None:
        self.drive = drive
        self.values: dict[str, int] = dict.fromkeys(
            ("param_write_address", "param_write_value", "param_read_address",
             "param_read_value", "var_read_address", "var_read_value", "var_write_address",
             "var_write_value"), 0)
        self._jobs: list[tuple[int, str, Callable[[], None]]] = []

    def step(self, now_us: int) -> None:
        due = [job for job in self._jobs if job[0] <= now_us]
        self._jobs = [job for job in self._jobs if job[0] > now_us]
        for _, address_key, run in due:
            try:
                run()
            except CommandError as exc:  # the target changed meanwhile (e.g. saving)
                self.drive.log(f"indirect access failed: {exc}")
            self.values[address_key] = 0

    def _schedule(self, delay_us: int, address_key: str, address: int,
                  run: Callable[[], None]) -> None:
        self.values[address_key] = address
        self._jobs.append((self.drive.now_us + delay_us, address_key, run))

    @staticmethod
    def _target(address: int) -> tuple[str, int]:
        if 0x8000 <= address <= 0x8FFF:
            register_spec(address - REGISTER_BASE)
            return "register", address - REGISTER_BASE
        parameter_spec(address)
        return "parameter", address

    def write_parameter(self, address: int) -> None:
        if address == 0:
            return
        value = self.values["param_write_value"]
        spec = parameter_spec(address)
        self.drive.check_parameter(spec, value)
        self._schedule(PARAMETER_APPLY_US, "param_write_address", address,
                       lambda: self.drive.write_parameter(address, value))

    def read_parameter(self, address: int) -> None:
        if address == 0:
            return
        parameter_spec(address)
        self._schedule(HANDSHAKE_US, "param_read_address", address,
                       lambda: self._store("param_read_value",
                                           self.drive.read_parameter(address)))

    def read_variable(self, address: int) -> None:
        if address == 0:
            return
        kind, n = self._target(address)
        read = self.drive.read_register if kind == "register" else self.drive.read_parameter
        self._schedule(HANDSHAKE_US, "var_read_address", address,
                       lambda: self._store("var_read_value", read(n)))

    def write_variable(self, address: int) -> None:
        if address == 0:
            return
        kind, n = self._target(address)
        value = self.values["var_write_value"]
        if kind == "register":
            spec = register_spec(n)
            if not spec.writable:
                raise AccessError("readonly", f"R{n:02d} {spec.name} is read-only")
            spec.check(value)
            self._schedule(HANDSHAKE_US, "var_write_address", address,
                           lambda: self.drive.write_register(n, value))
        else:
            pspec = parameter_spec(n)
            self.drive.check_parameter(pspec, value)
            self._schedule(HANDSHAKE_US, "var_write_address", address,
                           lambda: self.drive.write_parameter(n, value))

    def _store(self, key: str, value: int) -> None:
        self.values[key] = value


def build_object_dictionary(drive: ServoDrive) -> ObjectDictionary:
    od = ObjectDictionary()

    def add(index: int, sub: int, name: str, dtype: DataType, access: Access,
            get: Callable[[], Any] | None = None, put: Callable[[Any], None] | None = None,
            default: Any = 0, mappable: bool = True) -> None:
        setter = None
        if put is not None:
            def setter(value: Any, put: Callable[[Any], None] = put) -> None:
                drive.touch()  # the drive's next step runs in full (stillness.py)
                _guard(index, sub, lambda: put(value))
        od.add(OdEntry(index, sub, name, dtype, access, default, pdo_mappable=mappable,
                       getter=get, setter=setter))

    def reg(index: int, sub: int, name: str, dtype: DataType, access: Access, n: int,
            mappable: bool = True) -> None:
        put = (lambda v: drive.write_register(n, v)) if access.writable else None
        add(index, sub, name, dtype, access, lambda: _fit(dtype, drive.read_register(n)), put,
            mappable=mappable)

    def const(index: int, sub: int, name: str, dtype: DataType, value: int) -> None:
        add(index, sub, name, dtype, RO, lambda: value, mappable=False)

    ia = drive.indirect
    # ---- save (DS 301 0x1010, ch. 4; 0x2007, ch. 5) -------------------------------------------
    const(0x1010, 0, "Store parameters", D.UNSIGNED8, 1)
    add(0x1010, 1, "Save all parameters", D.UNSIGNED32, RW, lambda: 1,
        lambda v: _save_on_signature(drive, v), mappable=False)
    add(0x2007, 0, "Save parameters", D.UNSIGNED8, WO, None,
        lambda v: _save_on_value(drive, v), mappable=False)
    # ---- manufacturer objects (ch. 4 "Oggetti manufacturer specific") ----------------------
    const(0x2000, 0, "Drive parameters settings", D.UNSIGNED8, 4)
    add(0x2000, 1, "Parameter write address", D.UNSIGNED8, RW,
        lambda: ia.values["param_write_address"], ia.write_parameter, mappable=False)
    add(0x2000, 2, "Parameter write value", D.UNSIGNED16, WO, None,
        lambda v: ia.values.__setitem__("param_write_value", v), mappable=False)
    add(0x2000, 3, "Parameter read address", D.UNSIGNED8, RW,
        lambda: ia.values["param_read_address"], ia.read_parameter, mappable=False)
    add(0x2000, 4, "Parameter read value", D.UNSIGNED16, RO,
        lambda: ia.values["param_read_value"], mappable=False)
    reg(0x2001, 0, "Latched user position", D.INTEGER32, RW, R.LATCHED_POSITION)
    add(0x2002, 0, "IP set point 16", D.INTEGER16, WO, None, drive.set_ip_set_point_16)
    add(0x2003, 0, "Position actual value 16", D.INTEGER16, RO,
        lambda: _fit(D.INTEGER16, drive.position_user))
    add(0x2004, 0, "Latched user position 16", D.INTEGER16, RW,
        lambda: _fit(D.INTEGER16, drive.read_register(R.LATCHED_POSITION)),
        lambda v: drive.write_register(R.LATCHED_POSITION, v))
    const(0x2005, 0, "Drive variable read", D.UNSIGNED8, 2)
    add(0x2005, 1, "Variable read address", D.UNSIGNED16, RW,
        lambda: ia.values["var_read_address"], ia.read_variable)
    add(0x2005, 2, "Variable read value", D.INTEGER32, RO,
        lambda: _fit(D.INTEGER32, ia.values["var_read_value"]))
    const(0x2006, 0, "Drive variable write", D.UNSIGNED8, 2)
    add(0x2006, 1, "Variable write address", D.UNSIGNED16, RW,
        lambda: ia.values["var_write_address"], ia.write_variable)
    add(0x2006, 2, "Variable write value", D.INTEGER32, RW,
        lambda: ia.values["var_write_value"],
        lambda v: ia.values.__setitem__("var_write_value", v))
    reg(0x3000, 0, "Master encoder increments", D.UNSIGNED16, RW, R.MASTER_ENCODER_INCREMENTS,
        mappable=False)
    for index, n in ((0x3001, 25), (0x3002, 26), (0x3100, 28), (0x3101, 29)):
        reg(index, 0, register_spec(n).name, D.UNSIGNED8, RW, n)
    for index, n, dtype, access in (
            (0x3201, 30, D.INTEGER32, RW), (0x3202, 31, D.INTEGER32, RW),
            (0x3301, 32, D.INTEGER32, RO), (0x3302, 33, D.INTEGER32, RO),
            (0x3401, 34, D.INTEGER16, RW), (0x3402, 35, D.INTEGER16, RW),
            (0x3501, 36, D.INTEGER16, RO), (0x3502, 37, D.INTEGER16, RO),
            *((0x3601 + i, 38 + i, D.INTEGER32, RW) for i in range(4)),
            *((0x3701 + i, 42 + i, D.INTEGER16, RW) for i in range(4))):
        reg(index, 0, register_spec(n).name, dtype, access, n)
    # ---- device profile (DSP 402) -------------------------------------------------------------
    add(0x603F, 0, "Error code", D.UNSIGNED16, RO, drive.error_code)
    add(0x6040, 0, "Controlword", D.UNSIGNED16, RW, lambda: drive.cw, drive.write_controlword)
    add(0x6041, 0, "Statusword", D.UNSIGNED16, RO, lambda: drive.statusword)
    add(0x6060, 0, "Modes of operation", D.INTEGER8, WO, lambda: drive.mode,
        lambda mode: _set_od_mode(drive, mode))
    add(0x6061, 0, "Modes of operation display", D.INTEGER8, RO, lambda: drive.mode)
    reg(0x6064, 0, "Position actual value", D.INTEGER32, RO, R.POSITION_ACTUAL_VALUE)
    reg(0x6065, 0, "Following error window", D.UNSIGNED32, RW, R.FOLLOWING_ERROR_WINDOW)
    reg(0x6066, 0, "Following error time out", D.UNSIGNED16, RW, R.FOLLOWING_ERROR_TIMEOUT)
    add(0x6069, 0, "Velocity sensor actual value", D.INTEGER32, RO, drive.velocity_sensor)
    add(0x606B, 0, "Velocity demand value", D.INTEGER32, RO,
        lambda: _fit(D.INTEGER32, round(drive.trajectory.velocity * drive.feed)))
    reg(0x606C, 0, "Velocity actual value", D.INTEGER32, RO, R.VELOCITY_ACTUAL_VALUE)
    for index, n in ((0x606D, 14), (0x606E, 15), (0x606F, 16), (0x6070, 17)):
        reg(index, 0, register_spec(n).name, D.UNSIGNED16, RW, n)
    reg(0x607A, 0, "Target position", D.INTEGER32, RW, R.TARGET_POSITION)
    reg(0x607C, 0, "Home offset", D.INTEGER32, RW, R.HOME_OFFSET)
    reg(0x6081, 0, "Profile velocity", D.UNSIGNED32, RW, R.PROFILE_VELOCITY)
    reg(0x6083, 0, "Profile acceleration", D.UNSIGNED32, RW, R.PROFILE_ACCELERATION)
    reg(0x6084, 0, "Profile deceleration", D.UNSIGNED32, RW, R.PROFILE_DECELERATION)
    reg(0x6086, 0, "Motion profile type", D.INTEGER16, RW, R.MOTION_PROFILE_TYPE)
    const(0x6092, 0, "Feed constant", D.UNSIGNED8, 2)
    reg(0x6092, 1, "Feed", D.UNSIGNED32, RW, R.FEED_CONSTANT, mappable=False)
    const(0x6092, 2, "Shaft revolutions", D.UNSIGNED32, 1)
    reg(0x6098, 0, "Homing method", D.UNSIGNED8, RW, R.HOMING_METHOD)
    const(0x6099, 0, "Homing speeds", D.UNSIGNED8, 2)
    reg(0x6099, 1, "Fast homing speed", D.UNSIGNED32, RW, R.HOMING_FAST_SPEED)
    reg(0x6099, 2, "Slow homing speed", D.UNSIGNED32, RW, R.HOMING_SLOW_SPEED)
    reg(0x609A, 0, "Homing acceleration", D.UNSIGNED32, RW, R.HOMING_ACCELERATION)
    const(0x60C1, 0, "Interpolation data record", D.UNSIGNED8, 1)
    add(0x60C1, 1, "Position set-point", D.INTEGER32, WO, lambda: drive.ip_set_point,
        drive.set_ip_set_point)
    const(0x60C2, 0, "Interpolation time period", D.UNSIGNED8, 2)
    reg(0x60C2, 1, "Time period", D.UNSIGNED8, RW, R.IP_TIME_UNITS, mappable=False)
    add(0x60C2, 2, "Time index", D.INTEGER8, RO, lambda: -3, mappable=False)  # 10^-3 s
    add(0x60F8, 0, "Max slippage", D.INTEGER32, RW, lambda: drive.max_slippage,
        lambda v: setattr(drive, "max_slippage", v))
    reg(0x60FD, 0, "Digital inputs", D.UNSIGNED32, RO, R.DIGITAL_INPUTS)
    const(0x60FE, 0, "Digital outputs", D.UNSIGNED8, 2)
    reg(0x60FE, 1, "Physical outputs", D.UNSIGNED32, RW, R.DIGITAL_OUTPUTS)
    reg(0x60FE, 2, "Bitmask", D.UNSIGNED32, RW, R.DIGITAL_OUT_MASK)
    reg(0x60FF, 0, "Target velocity", D.INTEGER32, RW, R.TARGET_VELOCITY)
    const(0x6502, 0, "Supported drive modes", D.UNSIGNED32, SUPPORTED_DRIVE_MODES)
    return od


def _save_on_signature(drive: ServoDrive, value: int) -> None:
    if value != flashsave.SAVE_SIGNATURE:
        raise SdoAbort(AbortCode.CANNOT_STORE, 0x1010, 1)
    drive.request_save("0x1010:1 = 0x65766173")


def _save_on_value(drive: ServoDrive, value: int) -> None:
    if value != flashsave.COE_SAVE_VALUE:
        raise SdoAbort(AbortCode.VALUE_RANGE, 0x2007, 0)
    drive.request_save("0x2007 = 0x11")

