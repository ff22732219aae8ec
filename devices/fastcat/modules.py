"""One FastCAT I/O module on the coupler's rail (seed 000 §2, §5, §6, §7.6).

The coupler owns the object dictionary, the PDO mapping objects and the alarm logic; a module
adds its per-module objects (live getters/setters into its own state), says what it maps in
its RxPDO 0x1600+(N-1) / TxPDO 0x1A00+(N-1), advances its process in ``step`` and reports
module alarm codes (§7.6): edge-detected ones (AX2 count and zero-cycle alarms) through
``take_raised_alarms``, level ones (a short, a lost signal, ...) through ``physical_alarms``.

Operator actions on a module are declared in ``ACTIONS``; the coupler exposes them as
``fastcat/N`` targets and forwards them to :meth:`IoModule.apply`.
"""

from __future__ import annotations

import logging
import random
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

from devices.device import Action, CommandError, Param
from devices.fastcat.analog import AnalogInputs, AnalogOutputs
from devices.fastcat.catalog import ModuleType, a_module
from devices.fastcat.digital import DigitalIo
from devices.fastcat.encoder import FAULTS, PPR_DEFAULT, RPM_LIMIT, Ax2, EncoderInput
from devices.names import did_you_mean
from devices.od import ObjectDictionary

logger = logging.getLogger(__name__)

CODE_NOT_CALIBRATED = 0x0B  # §7.6 CO_E_TARATURA

Fits = Callable[[ModuleType], bool]


def _has_di(t: ModuleType) -> bool:
    return t.digital_inputs > 0


def _has_do(t: ModuleType) -> bool:
    return t.digital_outputs > 0


def _has_ai(t: ModuleType) -> bool:
    return t.ai > 0


def _has_ao(t: ModuleType) -> bool:
    return t.ao > 0


def _has_enc(t: ModuleType) -> bool:
    return t.encoders > 0


def _analog(t: ModuleType) -> bool:
    return t.group == "analog"


def _pot(t: ModuleType) -> bool:
    return t.pot_inputs


def _tc(t: ModuleType) -> bool:
    return t.thermocouple


def _any(_t: ModuleType) -> bool:
    return True


_CH = Param("channel", int, low=1, high=16, doc="channel number as printed on the module, 1..")
_ENC = Param("encoder", int, low=1, high=2, doc="encoder input 1 or 2")
_ACTIVE = Param("active", bool, doc="True = the fault is there, False = repaired")

# name -> (action, which module types take it, what the type needs, for the error message)
_ACTION_TABLE: tuple[tuple[Action, Fits, str], ...] = (
    (Action("set_input", "Drive a digital input terminal from the field",
            (_CH, Param("value", bool)), module="required"), _has_di, "digital inputs"),
    (Action("set_analog", "Put a value on an analog input, in the channel's unit "
            "(V, mA, % of potentiometer travel, °C)",
            (_CH, Param("value", float)), module="required"), _has_ai, "analog inputs"),
    (Action("set_shaft_speed", "Turn an encoder's shaft at this speed (negative = reverse)",
            (_ENC, Param("rpm", float, low=-RPM_LIMIT, high=RPM_LIMIT)), module="required"),
     _has_enc, "encoder inputs"),
    (Action("encoder_fault", "Break or repair an encoder: lost signal, noisy pulses, or no "
            "zero mark", (_ENC, Param("fault", str, choices=FAULTS), _ACTIVE),
            module="required"), _has_enc, "encoder inputs"),
    (Action("set_encoder_ppr", "Fit an encoder with this many pulses per revolution",
            (_ENC, Param("ppr", int, low=1, high=0xFFFF)), module="required"),
     _has_enc, "encoder inputs"),
    (Action("output_short", "Short-circuit a digital output terminal (read-back fault 0x02 "
            "while the output is on)", (_CH, _ACTIVE), module="required"),
     _has_do, "digital outputs"),
    (Action("pot_supply_short", "Short the potentiometer supply (alarm 0x03)", (_ACTIVE,),
            module="required"), _pot, "potentiometer inputs"),
    (Action("ao_overload", "Overload the analog outputs (protection, alarm 0x04)", (_ACTIVE,),
            module="required"), _has_ao, "analog outputs"),
    (Action("calibrated", "Whether the module holds its factory calibration (0x0B if not)",
            (Param("value", bool),), module="required"), _analog, "analog channels"),
    (Action("wire_thermocouple", "Connect a J or K thermocouple to a channel",
            (_CH, Param("type", str, choices=("J", "K"))), module="required"),
     _tc, "thermocouple inputs"),
    (Action("module_failure", "The module's electronics stop (or resume) answering on the Tbus",
            (_ACTIVE,), module="required"), _any, ""),
)


def _digital_channels(t: ModuleType) -> int:
    return t.di + t.do + t.dio  # DigitalIo numbers inputs, outputs and both in one row


def _analog_channels(t: ModuleType) -> int:
    return t.ai


# The actions that name a channel: how many the type has, what they are (for the message).
_CHANNELS: dict[str, tuple[Callable[[ModuleType], int], str]] = {
    "set_input": (_digital_channels, "digital"),
    "output_short": (_digital_channels, "digital"),
    "set_analog": (_analog_channels, "analog input"),
    "wire_thermocouple": (_analog_channels, "thermocouple"),
}


def _check_channel(mtype: ModuleType, channel: int, count: int, what: str) -> None:
    if not 1 <= channel <= count:
        raise CommandError(f"{mtype.name} has {what} channels 1..{count}, not {channel}")


# Rig-file options per module: name -> (which types take it, what the type needs).
_OPTIONS: dict[str, tuple[Fits, str]] = {
    "calibrated": (_analog, "analog channels"),
    "inputs": (_has_di, "digital inputs"),
    "analog": (_has_ai, "analog inputs"),
    "thermocouple": (_tc, "thermocouple inputs"),
    "cold_junction_c": (_tc, "thermocouple inputs"),
    "encoder_ppr": (_has_enc, "encoder inputs"),
    "shaft_rpm": (_has_enc, "encoder inputs"),
}


class IoModule:
    ACTIONS: ClassVar[dict[str, Action]] = {a.name: a for a, _f, _n in _ACTION_TABLE}
    _FITS: ClassVar[dict[str, tuple[Fits, str]]] = {a.name: (f, n) for a, f, n in _ACTION_TABLE}

    def __init__(self, mtype: ModuleType, rng: random.Random,
                 options: Mapping[str, Any] | None = None) -> None:
        self.mtype = mtype
        self.rng = rng
        self.plugged = True
        self.powered = True
        self.in_alarm = False  # set by the coupler (§7: a coupler alarm puts all modules in alarm)
        self.failed = False  # electronics dead: does not answer on the Tbus
        self.calibrated = True
        self._outputs_enabled = False
        self.still = False  # the last step changed nothing and a repeat would change nothing
        self._raised: list[int] = []
        has_digital = mtype.digital_inputs or mtype.digital_outputs
        self.digital = DigitalIo(mtype) if has_digital else None
        self.ai = AnalogInputs(mtype) if mtype.ai else None
        self.ao = AnalogOutputs(mtype) if mtype.ao else None
        self.ax2 = Ax2((PPR_DEFAULT, PPR_DEFAULT), lambda: self.in_alarm) \
            if mtype.encoders else None
        self._part_list = tuple(p for p in (self.digital, self.ai, self.ao, self.ax2)
                                if p is not None)
        self._apply_options(dict(options or {}))

    # --- options ---------------------------------------------------------------------------
    def _apply_options(self, options: dict[str, Any]) -> None:
        name = self.mtype.name
        for key, value in options.items():
            if key not in _OPTIONS:
                raise ValueError(f"{name}: unknown module option {key!r} (known: "
                                 f"{', '.join(sorted(_OPTIONS))}){did_you_mean(key, _OPTIONS)}")
            fits, needs = _OPTIONS[key]
            if not fits(self.mtype):
                raise ValueError(f"{name}: option {key!r} needs a module with {needs}")
            try:
                getattr(self, f"_option_{key}")(value)
            except CommandError as exc:
                raise ValueError(f"{name}: option {key!r}: {exc}") from None
        if self.ai is not None:
            self.ai.reset()  # settle the filters on the configured field values

    def _option_calibrated(self, value: Any) -> None:
        self.cmd_calibrated(_option_bool("calibrated", value))

    def _option_inputs(self, value: Any) -> None:
        for ch, v in enumerate(_option_list("inputs", value, self._dig().channels)):
            self.cmd_set_input(ch + 1, _option_bool("inputs", v))

    def _option_analog(self, value: Any) -> None:
        for ch, v in enumerate(_option_list("analog", value, self.mtype.ai)):
            self.cmd_set_analog(ch + 1, _option_float("analog", v))

    def _option_thermocouple(self, value: Any) -> None:
        for ch, v in enumerate(_option_list("thermocouple", value, self.mtype.ai, True)):
            self.apply("wire_thermocouple", {"channel": ch + 1, "type": v})

    def _option_cold_junction_c(self, value: Any) -> None:
        self._ai().cold_junction_c = _option_float("cold_junction_c", value)

    def _option_encoder_ppr(self, value: Any) -> None:
        for k, v in enumerate(_option_list("encoder_ppr", value, 2, True)):
            self.apply("set_encoder_ppr", {"encoder": k + 1, "ppr": v})

    def _option_shaft_rpm(self, value: Any) -> None:
        for k, v in enumerate(_option_list("shaft_rpm", value, 2, True)):
            self.apply("set_shaft_speed", {"encoder": k + 1, "rpm": v})

    # --- what the coupler uses -------------------------------------------------------------
    def responds(self) -> bool:
        return self.plugged and self.powered and not self.failed

    def _parts(self) -> tuple[Any, ...]:
        """The module's channel blocks, in PDO order: digital, analog in, analog out, encoders."""
        return self._part_list

    def add_objects(self, od: ObjectDictionary, n: int) -> None:
        for part in self._parts():
            part.add_objects(od, n)

    def rx_entries(self, n: int) -> list[tuple[int, int, int]]:
        """Outputs mapped in RxPDO 0x1600 + (n - 1) (§5, §6.28-§6.30)."""
        return [e for part in self._parts() for e in part.rx_entries(n)]

    def tx_entries(self, n: int) -> list[tuple[int, int, int]]:
        """Inputs mapped in TxPDO 0x1A00 + (n - 1) (§5, §6.24-§6.27)."""
        return [e for part in self._parts() for e in part.tx_entries(n)]

    def step(self, dt_us: int, outputs_enabled: bool) -> None:
        if dt_us < 0:
            raise ValueError(f"{self.mtype.name}: negative time step {dt_us} us")
        self._outputs_enabled = outputs_enabled
        still = True
        if self.digital is not None:
            self.digital.step(outputs_enabled)
            still = self.digital.still
        if self.ai is not None:
            self.ai.step(dt_us)
            still = still and self.ai.still
        if self.ao is not None:
            self.ao.step(dt_us, outputs_enabled)
            still = still and self.ao.still
        if self.ax2 is not None:
            raised = self.ax2.step(dt_us, self.rng)
            if raised:
                self._raised += raised
            still = still and self.ax2.still
        self.still = still

    def take_raised_alarms(self) -> list[int]:
        """Edge alarms (AX2 count 0x10/0x11, zero cycle 0x14/0x15) since the last call."""
        if not self._raised:
            return []
        raised = list(dict.fromkeys(self._raised))
        self._raised = []
        return raised

    def physical_alarms(self) -> set[int]:
        """Module codes whose physical cause is present now (level alarms)."""
        codes: set[int] = set()
        for part in self._parts():
            codes |= part.physical_alarms()
        if not self.calibrated:
            codes.add(CODE_NOT_CALIBRATED)
        return codes

    def physical_alarm_codes(self) -> tuple[int, ...]:
        """``sorted(physical_alarms())``; answered at once in the usual case where no part
        has any of the conditions its level alarms need (the coupler asks every step)."""
        dig, ai, ao, ax2 = self.digital, self.ai, self.ao, self.ax2
        if (self.calibrated and (dig is None or not dig.readback_fault)
                and (ai is None or not ai.pot_supply_short) and (ao is None or not ao.overload)
                and (ax2 is None or not (ax2.inputs[0].faults or ax2.inputs[1].faults))):
            return ()
        return tuple(sorted(self.physical_alarms()))

    def cause_present(self, code: int) -> bool:
        if code in self.physical_alarms():
            return True
        return self.ax2 is not None and self.ax2.cause_present(code)

    def reset(self) -> None:
        """CNF / power-up reset: outputs off, settings at their defaults, counters cleared."""
        for part in self._parts():
            part.reset()
        self._raised = []
        self._outputs_enabled = False
        self.still = False

    # --- operator actions ------------------------------------------------------------------
    def available_actions(self) -> list[str]:
        return [name for name, (fits, _n) in self._FITS.items() if fits(self.mtype)]

    def apply(self, action: str, args: Mapping[str, Any]) -> Any:
        spec = self.ACTIONS.get(action)
        if spec is None:
            has = self.available_actions()
            raise CommandError(f"{a_module(self.mtype.name)} module has no action '{action}' "
                               f"(it has: {', '.join(has)}){did_you_mean(action, has)}")
        return self.run(action, spec.check_args(args))

    def run(self, action: str, kwargs: Mapping[str, Any]) -> Any:
        """``action`` with arguments already checked against ``ACTIONS[action]`` (the
        coupler's command check: rail.py MODULE_ACTIONS carry the same parameters), so they
        are not checked twice; what this module's type cannot take is refused here."""
        self.check_kind(self.mtype, action, kwargs)
        return getattr(self, f"cmd_{action}")(**kwargs)

    @classmethod
    def check_kind(cls, mtype: ModuleType, action: str, args: Mapping[str, Any]) -> None:
        """Refuse what a module of this type cannot take whatever its state: an action it
        has nothing for, a channel it does not have (also a scenario check before the run:
        the type a rail position holds at that step)."""
        fits, needs = cls._FITS[action]
        if not fits(mtype):
            raise CommandError(f"action '{action}' needs a module with {needs}; "
                               f"{mtype.name} is '{mtype.description}'")
        counted = _CHANNELS.get(action)
        if counted is not None:
            count, what = counted
            _check_channel(mtype, args["channel"], count(mtype), what)

    def cmd_set_input(self, channel: int, value: bool) -> None:
        dig = self._dig()
        dig.field[self._channel(channel, dig.channels, "digital")] = value

    def cmd_set_analog(self, channel: int, value: float) -> None:
        ai = self._ai()
        ch = self._channel(channel, ai.count, "analog input")
        kind = ai.kind(ch)
        if not kind.field_low <= value <= kind.field_high:
            raise CommandError(f"{self.mtype.name} channel {channel} ({kind.name}) takes "
                               f"{kind.field_low:g}..{kind.field_high:g} {kind.unit}, "
                               f"got {value:g}")
        ai.field[ch] = value

    def cmd_set_shaft_speed(self, encoder: int, rpm: float) -> None:
        self._enc(encoder).set_rpm(rpm)

    def cmd_encoder_fault(self, encoder: int, fault: str, active: bool) -> None:
        self._enc(encoder).set_fault(fault, active)

    def cmd_set_encoder_ppr(self, encoder: int, ppr: int) -> None:
        self._enc(encoder).set_real_ppr(ppr)

    def cmd_output_short(self, channel: int, active: bool) -> None:
        dig = self._dig()
        dig.shorted[self._channel(channel, dig.channels, "digital")] = active

    def cmd_pot_supply_short(self, active: bool) -> None:
        self._ai().pot_supply_short = active

    def cmd_ao_overload(self, active: bool) -> None:
        if self.ao is None:
            raise CommandError(f"{self.mtype.name} has no analog outputs")
        self.ao.overload = active

    def cmd_calibrated(self, value: bool) -> None:
        self.calibrated = value

    def cmd_wire_thermocouple(self, channel: int, type: str) -> None:
        ai = self._ai()
        ai.wired[self._channel(channel, ai.count, "thermocouple")] = type

    def cmd_module_failure(self, active: bool) -> None:
        self.failed = active

    def _channel(self, channel: int, count: int, what: str) -> int:
        _check_channel(self.mtype, channel, count, what)
        return channel - 1

    def _dig(self) -> DigitalIo:
        if self.digital is None:
            raise CommandError(f"{self.mtype.name} has no digital channels")
        return self.digital

    def _ai(self) -> AnalogInputs:
        if self.ai is None:
            raise CommandError(f"{self.mtype.name} has no analog inputs")
        return self.ai

    def _enc(self, encoder: int) -> EncoderInput:
        if self.ax2 is None:
            raise CommandError(f"{self.mtype.name} has no encoder inputs")
        if encoder not in (1, 2):
            raise CommandError(f"encoder must be 1 or 2, not {encoder}")
        return self.ax2.inputs[encoder - 1]

    # --- view ------------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        snap: dict[str, Any] = {"type": self.mtype.name, "plugged": self.plugged,
                                "powered": self.powered, "in_alarm": self.in_alarm,
                                "responds": self.responds(), "failed": self.failed,
                                "alarms": sorted(self.physical_alarms())}
        field: dict[str, Any] = {}
        if self.mtype.group == "analog":
            snap["calibrated"] = self.calibrated
        if self.digital is not None:
            snap.update(self.digital.snapshot())
            if self.digital.inputs_n:
                field["inputs"] = list(self.digital.field)
            if self.digital.outputs_n:
                field["output_short"] = list(self.digital.shorted)
        if self.ai is not None:
            snap.update(self.ai.snapshot())
            field["analog"] = list(self.ai.field)
            if self.mtype.pot_inputs:
                field["pot_supply_short"] = self.ai.pot_supply_short
            if self.mtype.thermocouple:
                field["thermocouple"] = list(self.ai.wired)
                field["cold_junction_c"] = self.ai.cold_junction_c
        if self.ao is not None:
            snap.update(self.ao.snapshot())
            field["ao_overload"] = self.ao.overload
        if self.ax2 is not None:
            snap["encoders"] = self.ax2.snapshot()
            snap["status"] = self.ax2.status
            snap["command"] = self.ax2.command
        if field:
            snap["field"] = field
        return snap


def _option_list(key: str, value: Any, count: int, scalar_ok: bool = False) -> list[Any]:
    if scalar_ok and not isinstance(value, list | tuple):
        return [value] * count
    if not isinstance(value, list | tuple) or len(value) != count:
        raise ValueError(f"option {key!r} must be a list of {count} values, got {value!r}")
    return list(value)


def _option_bool(key: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"option {key!r} takes true/false, got {value!r}")
    return value


def _option_float(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"option {key!r} takes a number, got {value!r}")
    return float(value)

