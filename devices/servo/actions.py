"""Operator and scenario actions of the servo drive (``cmd_<name>``), declared as data.

Every action goes through the same state as the fieldbus: an ``enable`` is a write of R00 = 3,
``jog`` is velocity mode with target_velocity = +-profile_velocity, ``home`` is mode 6 and the
start bit, exactly as a master would do it. Values are checked before anything changes.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from devices.device import Action, CommandError, Param
from devices.servo import control, ds402
from devices.servo.alarms import lookup, reset_hint
from devices.servo.io import INPUT_NAMES
from devices.servo.parameters import parameter_by_name_or_address
from devices.servo.registers import LAST_REGISTER, MODE_NAMES, R

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

U16 = 0xFFFF
_REG = Param("register", int, low=0, high=LAST_REGISTER, doc="register number n (R00..R133)")
_PARAM = Param("parameter", str, parse=parameter_by_name_or_address,
               doc="parameter name (d3) or Modbus address (3, 0x0003)")
_VALUE32 = Param("value", int, low=-0x8000_0000, high=0xFFFF_FFFF)
_ALARM = Param("code", str, doc="alarm code (16) or name (FOLLOWING_ERROR)")
# The simulator's words for an injected cause, put or taken away, not anything the drive
# shows (its alarm stays latched when a cause goes, seed 004 "Reset allarmi"): a dashboard
# with trainees keeps these lines off their pages (docs/classroom.md).
JAM_LOG = {True: "load jammed", False: "load free"}
CAUSE_LOG_LINES = frozenset(JAM_LOG.values())
CAUSE_REMOVED_LOG = "cause of alarm {number} removed (reset with {hint})"
_CAUSE_REMOVED_HEAD = CAUSE_REMOVED_LOG.split("{", 1)[0]


def names_a_cause(text: str) -> bool:
    """Whether a drive log line is one of the simulator's cause lines above."""
    return text in CAUSE_LOG_LINES or text.startswith(_CAUSE_REMOVED_HEAD)

ACTIONS: dict[str, Action] = {a.name: a for a in (
    Action("write_register", "write register Rn as a master would", (_REG, _VALUE32)),
    Action("read_register", "read register Rn", (_REG,)),
    Action("write_parameter", "write a parameter by name or address", (
        _PARAM, Param("value", int, low=0, high=U16))),
    Action("read_parameter", "read a parameter by name or address", (_PARAM,)),
    Action("control_register", "write the register-mode control word R00", (
        Param("value", int, low=0, high=U16),)),
    Action("controlword", "write the CiA 402 controlword 0x6040", (
        Param("value", int, low=0, high=U16),)),
    Action("write_object", "write a CiA 402 / manufacturer object", (
        Param("index", int, low=0, high=U16), Param("sub", int, False, 0, 0, 0xFF),
        Param("value", int))),
    Action("read_object", "read a CiA 402 / manufacturer object", (
        Param("index", int, low=0, high=U16), Param("sub", int, False, 0, 0, 0xFF))),
    Action("set_mode", "modes of operation (R01 / 0x6060)", (
        Param("mode", int, choices=tuple(MODE_NAMES)),)),
    Action("set_input", "drive an input: CN2 pins, TEN, IEN", (
        Param("name", str, choices=INPUT_NAMES), Param("value", bool))),
    Action("inject_alarm", "raise an alarm, its cause staying until clear_alarm", (_ALARM,)),
    Action("clear_alarm", "remove the injected cause (the alarm stays until a reset)", (_ALARM,)),
    Action("jam_load", "block the load (the motor cannot move)", (Param("active", bool),)),
    Action("power", "switch the drive's supply", (Param("on", bool),)),
    Action("enable", "torque and motion on (R00 = 3) or off (R00 = 0)", (Param("on", bool),)),
    Action("alarm_reset", "alarm reset: a 0 -> 1 -> 0 pulse of the control word's reset bit"),
    Action("start", "start in the active mode (positioning, homing, interpolation, axis)"),
    Action("stop", "stop on the deceleration ramp and hold (Stp_cmd)"),
    # "position", not "target": in a scenario step "target" names the device.
    Action("move", "positioner: go to a position (absolute, or incremental)", (
        Param("position", int, low=-0x8000_0000, high=0x7FFF_FFFF),
        Param("relative", bool, False, False))),
    Action("jog", "velocity mode at -/+ profile_velocity, 0 stops", (
        Param("direction", int, choices=(-1, 0, 1)),)),
    Action("home", "mode 6 and start homing with the configured method"),
    Action("pulses", "pulse positioner (mode -1): pulses on the pulse input", (
        Param("count", int, low=-1_000_000, high=1_000_000),)),
    Action("master_encoder", "electronic axis: the master shaft's speed", (
        Param("rpm", float, low=-10_000.0, high=10_000.0),)),
    Action("analog_input", "analog reference (mode -127), volts", (
        Param("volts", float, low=-10.0, high=10.0),)),
    Action("sync", "a fieldbus Sync: the interpolator takes its set-point now"),
    Action("save", "save parameters and registers to flash (as 0x3802 = 0x0011)"),
)}

_TOLERANT = {"parameter", "code"}  # accept 3 as well as "3"
_ALARM_ACTIONS = ("inject_alarm", "clear_alarm")


class DriveActions:
    """Mixin of :class:`~devices.servo.drive.ServoDrive`: its ``ACTIONS`` and handlers."""

    ACTIONS: ClassVar[Mapping[str, Action]] = ACTIONS

    def check_command(self, action: str, args: Mapping[str, Any],
                      module: int | None = None) -> dict[str, Any]:
        args = {k: str(v) if k in _TOLERANT and isinstance(v, int) and not isinstance(v, bool)
                else v for k, v in args.items()}
        kwargs = super().check_command(action, args, module)  # type: ignore[misc]
        if action in _ALARM_ACTIONS:
            # The alarm table of the fieldbus c9 selected at the last power-up (ch. 5 / ch. 6):
            # a scenario check before the run reads the drive's configuration as built.
            self._alarm(kwargs["code"])  # type: ignore[attr-defined]
        return kwargs

    def _powered(self: ServoDrive) -> None:
        if not self.powered:
            raise CommandError(f"servo '{self.device_id}' is powered off")
        if self.saving:
            raise CommandError(f"servo '{self.device_id}' is saving to flash and does not "
                               "answer")

    def cmd_write_register(self: ServoDrive, register: int, value: int) -> None:
        self._powered()
        self.write_register(register, value)

    def cmd_read_register(self: ServoDrive, register: int) -> int:
        self._powered()
        return self.read_register(register)

    def cmd_write_parameter(self: ServoDrive, parameter: str, value: int) -> None:
        self._powered()
        self.write_parameter(parameter_by_name_or_address(parameter).address, value)

    def cmd_read_parameter(self: ServoDrive, parameter: str) -> int:
        self._powered()
        return self.read_parameter(parameter_by_name_or_address(parameter).address)

    def cmd_control_register(self: ServoDrive, value: int) -> None:
        self.cmd_write_register(R.CONTROL_WORD, value)

    def cmd_controlword(self: ServoDrive, value: int) -> None:
        self._powered()
        self.write_controlword(value)

    def cmd_write_object(self: ServoDrive, index: int, sub: int, value: int) -> None:
        self._powered()
        self.od.write(index, sub, value)

    def cmd_read_object(self: ServoDrive, index: int, sub: int) -> Any:
        self._powered()
        return self.od.read(index, sub)

    def cmd_set_mode(self: ServoDrive, mode: int) -> None:
        self.cmd_write_register(R.MODES_OF_OPERATION, mode)

    def cmd_set_input(self: ServoDrive, name: str, value: bool) -> None:
        self.wired[name] = value
        if self.powered:
            if name == "latch":  # capture the position of this very instant
                self.latch.update(value, self.now_us, self.position_user)
            self._evaluate()

    def _alarm(self: ServoDrive, code: str) -> int:
        try:
            return lookup(self.fieldbus, code).code
        except KeyError as exc:
            raise CommandError(str(exc.args[0])) from None

    def cmd_inject_alarm(self: ServoDrive, code: str) -> None:
        number = self._alarm(code)
        self._powered()
        self.raise_alarm(number, injected=True)

    def cmd_clear_alarm(self: ServoDrive, code: str) -> None:
        number = self._alarm(code)
        self.alarms.remove_cause(number)
        hint = reset_hint(self.fieldbus, self.alarm_table[number])
        self.log(CAUSE_REMOVED_LOG.format(number=number, hint=hint))

    def cmd_jam_load(self: ServoDrive, active: bool) -> None:
        self.plant.jammed = active
        self.log(JAM_LOG[active])

    def cmd_power(self: ServoDrive, on: bool) -> None:
        if on and not self.powered:
            self._power_up()
        elif not on and self.powered:
            self._power_down()

    def cmd_enable(self: ServoDrive, on: bool) -> None:
        if on and self.ten_cmd_held_at_reset:
            # after an alarm reset with Ten_cmd held only a fresh 0 -> 1 enables (statemachine)
            self.cmd_write_register(R.CONTROL_WORD, 0)
        self.cmd_write_register(R.CONTROL_WORD, control.TEN_CMD | control.IEN_CMD if on else 0)

    def cmd_alarm_reset(self: ServoDrive) -> str | None:
        """The reset pulse; the answer says why the drive stays in Fault (the drive log says
        it too), None when the reset went through or there was nothing to reset."""
        self._powered()
        if self.cw_source == "register":
            r00 = self.regs[R.CONTROL_WORD] & ~control.ALM_RST
            self.write_register(R.CONTROL_WORD, r00 | control.ALM_RST)
            self.write_register(R.CONTROL_WORD, r00)
        else:
            cw = self.cw & ~ds402.CW_FAULT_RESET
            self.write_controlword(cw | ds402.CW_FAULT_RESET)
            self.write_controlword(cw)
        return self.reset_refusal()

    def cmd_start(self: ServoDrive) -> str | None:
        """The mode's start bit as a fresh edge; the answer says why the axis will not move
        (``motion_blocked``, as Jog's), None when it will or for a save / load."""
        self._powered()
        mode = self.mode
        bit = control.BIT6 if mode in control.HOMING | control.ELECTRONIC_AXIS else control.BIT5
        if mode in control.VELOCITY:
            raise CommandError(f"mode {mode} ({MODE_NAMES[mode]}) has no start: set the "
                               "target velocity")
        r00 = self.regs[R.CONTROL_WORD] & ~(control.STP_CMD | bit)
        self.write_register(R.CONTROL_WORD, r00)  # a fresh 0 -> 1 edge
        self.write_register(R.CONTROL_WORD, r00 | bit)
        if mode in control.SAVE_LOAD:
            self.write_register(R.CONTROL_WORD, r00)
            return None
        return self.motion_blocked()

    def cmd_stop(self: ServoDrive) -> None:
        self._powered()
        self.write_register(R.CONTROL_WORD, self.regs[R.CONTROL_WORD] | control.STP_CMD)

    def cmd_move(self: ServoDrive, position: int, relative: bool) -> str | None:
        """Target and a fresh Pos_str; the answer as :meth:`cmd_start`'s."""
        self._powered()
        if self.mode not in control.POSITIONER:
            self.set_mode(1)
        self.write_register(R.TARGET_POSITION, position)
        # Clear the mode bits 5..7 first (after homing R00 still holds bit 6, Upd_mod in mode
        # 1), so the start below is a fresh 0 -> 1 edge of Pos_str alone, as the seed's
        # example does after homing (CW = 3, then 0x23).
        r00 = self.regs[R.CONTROL_WORD] & ~(control.STP_CMD | control.BIT5 | control.BIT6
                                            | control.BIT7)
        self.write_register(R.CONTROL_WORD, r00)
        self.write_register(R.CONTROL_WORD, r00 | control.BIT5
                            | (control.BIT7 if relative else 0))
        return self.motion_blocked()

    def cmd_jog(self: ServoDrive, direction: int) -> str | None:
        """Mode 3 and R13 = direction * R12, taken in any state as a master's writes are;
        the answer says why the axis will not move (not enabled, ...), None when it will or
        for a stop."""
        self._powered()
        if self.mode != 3:
            self.set_mode(3)
        self.write_register(R.TARGET_VELOCITY, direction * self.regs[R.PROFILE_VELOCITY])
        return self.motion_blocked() if direction else None

    def cmd_home(self: ServoDrive) -> str | None:
        self._powered()
        self.set_mode(6)
        return self.cmd_start()

    def cmd_pulses(self: ServoDrive, count: int) -> None:
        self._powered()
        if self.mode != -1:
            raise CommandError("pulses drive the pulse positioner: set mode -1 first")
        self.mode_logic.pulses(self, count)  # type: ignore[attr-defined]

    def cmd_master_encoder(self: ServoDrive, rpm: float) -> None:
        self.master_rpm = rpm

    def cmd_analog_input(self: ServoDrive, volts: float) -> None:
        self.analog_volts = volts

    def cmd_sync(self: ServoDrive) -> None:
        self._powered()
        sync = getattr(self.mode_logic, "sync", None)
        if sync is not None:
            sync(self)

    def cmd_save(self: ServoDrive) -> None:
        self._powered()
        self.request_save("operator")
