"""What an operator (dashboard, scenario) can do to a CPX-E-EC, as an actions table.

Targets are ``cpx`` (the bus module) or ``cpx/N`` with N the CPX module number (1 ... 10, as
§2.3.2 numbers them; the bus module is module 0). Physical actions change the field or the
hardware (supplies, cables, switches, signals, shorts, broken wires); ``inject_fault`` makes a
named fault of devices/cpx/faults.py present, ``clear_fault`` takes it away again.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from devices.cpx.catalog import IO_MODULES, module_type
from devices.cpx.faults import FAULTS, Injected, Target, check_target, fault_spec
from devices.cpx.history import FIRST_SUB
from devices.cpx.history import INDEX as HISTORY
from devices.cpx.module_checks import (
    FAULT_ACTIONS,
    check_kind,
    module_listing,
    modules_layout,
)
from devices.cpx.modules import CpxModule
from devices.cpx.switches import ROTARY_MAX
from devices.device import Action, CommandError, Param, bool_value_as_int
from devices.od import ObjectDictionary

if TYPE_CHECKING:
    from devices.cpx.device import CpxEEc

_CHANNEL = Param("channel", int, low=0, high=15, doc="channel of the module, from 0")
_OPT_CHANNEL = Param("channel", int, required=False, low=0, high=15,
                     doc="channel of the module, from 0")
_SM = Param("sm", int, required=False, low=0, high=3, doc="sync manager 0 ... 3")
_VOLTS = (0.0, 36.0)

ACTIONS: dict[str, Action] = {a.name: a for a in (
    Action("power", "Switch U_EL/SEN on (24 V) or off; the module rides through 20 ms "
                    "(Tab. 29)", (Param("on", bool),)),
    Action("supply", "Set the supplies: U_EL/SEN at [XD] (electronics and sensors, Tab. 8) "
                     "and the load supply U_OUT (outputs, PL); 24 V +- 25 % is in tolerance "
                     "(Tab. 29)",
           (Param("el_sen", float, required=False, low=_VOLTS[0], high=_VOLTS[1]),
            Param("out", float, required=False, low=_VOLTS[0], high=_VOLTS[1]))),
    Action("cable", "Plug or pull the EtherCAT cable at [IN] or [OUT] (LA IN / LA OUT)",
           (Param("port", str, choices=("in", "out")), Param("connected", bool))),
    Action("set_rotary", "Turn the three hex rotary switches (0 = the master assigns the "
                         "address, 1 ... 4095 = Explicit Device ID); read at the next start",
           (Param("value", int, low=0, high=ROTARY_MAX, current="switches.rotary"),)),
    Action("set_dil", "Set DIL 1 / DIL 2 (Tab. 6: off/off no diagnosis, off/on status bits, "
                      "on/off I/O diagnostic interface, on/on bootloader); read at the next "
                      "start", (Param("dil1", bool, current="switches.dil1"),
                                Param("dil2", bool, current="switches.dil2"))),
    Action("restart", "Restart the bus node (switch changes take effect, §2.1.7)"),
    Action("set_input", "A sensor at a CPX-E-16DI input switches on or off",
           (_CHANNEL, Param("on", bool)), module="required"),
    Action("set_analog", "The signal at a CPX-E-4AI-U-I input, in V or mA of its range",
           (_CHANNEL, Param("value", float, low=-30.0, high=30.0)), module="required"),
    Action("set_count_rate", "Pulses per second at the CPX-E-1CI counter input",
           (Param("hz", float, low=-1e6, high=1e6),), module="required"),
    Action("short_circuit", "Short an output channel (KZA) or, without channel, the module's "
                            "sensor supply (KZS)", (Param("on", bool), _OPT_CHANNEL),
           module="required"),
    Action("wire_break", "Break or mend the wire of a channel",
           (_CHANNEL, Param("on", bool)), module="required"),
    Action("force", "Force a digital channel to 0 / 1 (M LED); without value: release it",
           (_CHANNEL, Param("value", int, required=False, low=0, high=1)),
           module="required"),
    Action("replace_module", "With the terminal switched off, replace module N by another "
                             "type (its ident changes: 0xF050)",
           (Param("type", str, doc=f"one of {', '.join(IO_MODULES)}"),), module="required"),
    Action("inject_fault", "Make a fault present: " + ", ".join(FAULTS),
           (Param("fault", str, choices=tuple(FAULTS)), _OPT_CHANNEL, _SM), module="optional"),
    Action("clear_fault", "Take an injected fault away",
           (Param("fault", str, choices=tuple(FAULTS)), _OPT_CHANNEL, _SM), module="optional"),
    Action("write_object", "Write an object (access rights and ranges enforced, Tab. 27)",
           (Param("index", int, low=0, high=0xFFFF), Param("sub", int, low=0, high=0xFF),
            Param("value", int))),
    Action("read_object", "Read an object (Tab. 27); reading the newest 0x10F3 message "
                          "clears New Message Available in Overwrite mode",
           (Param("index", int, low=0, high=0xFFFF), Param("sub", int, low=0, high=0xFF))),
)}


class OperatorMixin:
    """The ``cmd_*`` handlers of :class:`~devices.cpx.device.CpxEEc`."""

    def check_command(self, action: str, args: Mapping[str, Any],
                      module: int | None = None) -> dict[str, Any]:
        args = bool_value_as_int(action, args)
        kwargs: dict[str, Any] = super().check_command(action, args, module)  # type: ignore[misc]
        # Here, not in the handler: the checks before a run (a scenario's [[on]] commands, an
        # exercise file's fault) call this only.
        if action in FAULT_ACTIONS:
            check_target(fault_spec(kwargs["fault"]), module, kwargs["channel"], kwargs["sm"])
        return kwargs

    # ---- supplies, cables, switches -----------------------------------------------------
    def cmd_power(self: CpxEEc, on: bool) -> None:
        self.el_sen_v = 24.0 if on else 0.0
        if on:  # the electronics start at once; switching off waits out the bridging time
            self._set_powered(True)

    def cmd_supply(self: CpxEEc, el_sen: float | None, out: float | None) -> None:
        if el_sen is not None:
            self.el_sen_v = el_sen
        if out is not None:
            self.out_v = out

    def cmd_cable(self: CpxEEc, port: str, connected: bool) -> None:
        inp, out = self.plugs
        self.plugs = (connected, out) if port == "in" else (inp, connected)
        self._ports()
        self._refresh_leds()

    def cmd_set_rotary(self: CpxEEc, value: int) -> None:
        self.switches.rotary = value

    def cmd_set_dil(self: CpxEEc, dil1: bool, dil2: bool) -> None:
        self.switches.dil1, self.switches.dil2 = dil1, dil2

    def cmd_restart(self: CpxEEc) -> None:
        if not self.powered:
            raise CommandError(f"{self.device_id} is not powered")
        self._stop()
        self._start()
        self._refresh_leds()

    # ---- field --------------------------------------------------------------------------
    def unit(self: CpxEEc, module: int | None) -> CpxModule:
        if module is None or not 1 <= module <= len(self.modules):
            raise CommandError(module_listing(self.device_id, module,
                                              modules_layout(self.modules)))
        return self.modules[module - 1]

    def cmd_set_input(self: CpxEEc, module: int, channel: int, on: bool) -> None:
        target = self.unit(module)
        check_kind(target.mtype, module, "set_input", {"channel": channel})
        target.field_inputs[channel] = on

    def cmd_set_analog(self: CpxEEc, module: int, channel: int, value: float) -> None:
        target = self.unit(module)
        check_kind(target.mtype, module, "set_analog", {"channel": channel})
        target.analog_in[channel] = value

    def cmd_set_count_rate(self: CpxEEc, module: int, hz: float) -> None:
        target = self.unit(module)
        check_kind(target.mtype, module, "set_count_rate", {})
        target.count_rate_hz = hz

    def cmd_short_circuit(self: CpxEEc, module: int, on: bool, channel: int | None) -> None:
        target = self.unit(module)
        check_kind(target.mtype, module, "short_circuit", {"channel": channel})
        if channel is None:
            target.sensor_supply_short = on
            return
        (target.shorted.add if on else target.shorted.discard)(channel)

    def cmd_wire_break(self: CpxEEc, module: int, channel: int, on: bool) -> None:
        target = self.unit(module)
        check_kind(target.mtype, module, "wire_break", {"channel": channel})
        (target.wire_broken.add if on else target.wire_broken.discard)(channel)

    def cmd_force(self: CpxEEc, module: int, channel: int, value: int | None) -> None:
        target = self.unit(module)
        check_kind(target.mtype, module, "force", {"channel": channel})
        if value is None:
            target.forced.pop(channel, None)
        else:
            target.forced[channel] = value

    def cmd_replace_module(self: CpxEEc, module: int, type: str) -> None:
        self.unit(module)
        if self.powered:
            raise CommandError("CPX-E modules are changed with the terminal switched off: "
                               "power it off first")
        try:
            mtype = module_type(type)
        except KeyError as exc:
            raise CommandError(exc.args[0]) from None
        self.modules[module - 1] = CpxModule(module, mtype)
        self.default_ranges[module - 1] = list(self.modules[module - 1].ranges)

    # ---- named faults ---------------------------------------------------------------------
    def cmd_inject_fault(self: CpxEEc, fault: str, channel: int | None, sm: int | None,
                         module: int | None) -> None:
        self._apply_fault(fault, channel, sm, module, present=True)

    def cmd_clear_fault(self: CpxEEc, fault: str, channel: int | None, sm: int | None,
                        module: int | None) -> None:
        self._apply_fault(fault, channel, sm, module, present=False)

    def _apply_fault(self: CpxEEc, fault: str, channel: int | None, sm: int | None,
                     module: int | None, present: bool) -> None:
        spec = fault_spec(fault)  # its target: check_command
        if spec.name == "short_circuit":
            self.cmd_short_circuit(module, present, channel)  # type: ignore[arg-type]
            return
        if spec.name == "wire_break":
            self.cmd_wire_break(module, channel, present)  # type: ignore[arg-type]
            return
        if spec.name == "module_failure":
            self.unit(module).failed = present
            return
        if spec.target is Target.MODULE and module is not None:
            self.unit(module)
        entry = Injected(spec.name, module, channel, sm)
        if present:
            if entry not in self.injected:
                self.injected.append(entry)
                self.faults_changed()
            return
        if entry not in self.injected:
            now = ", ".join(f.label() for f in self.injected) or "none"
            raise CommandError(f"{entry.label()} is not injected (injected: {now})")
        self.injected.remove(entry)
        self.faults_changed()
        if spec.name == "ac_failure" and self.powered:
            self.cmd_restart()  # the application controller starts again

    # ---- objects --------------------------------------------------------------------------
    def _require_od(self: CpxEEc) -> ObjectDictionary:
        if not self.powered or self.od is None:
            raise CommandError(f"{self.device_id} is not powered")
        if self.has_fault("ac_failure"):
            raise CommandError(f"{self.device_id}: the application controller does not "
                               f"answer (CoE runs on it)")
        return self.od

    def cmd_write_object(self: CpxEEc, index: int, sub: int, value: int) -> None:
        # the wire's face calls this directly: the dictionary's setters touch the model
        self._require_od().write(index, sub, value)

    def cmd_read_object(self: CpxEEc, index: int, sub: int) -> Any:
        return self._read_object(self._require_od(), index, sub)

    def mailbox_read(self: CpxEEc, index: int, sub: int) -> Any:
        # the built-in master's SDO upload (CoeMailbox.sdo_upload): a read of the newest
        # message lowers New Message Available there too (docs/cpx-e-ec.md choice 21)
        assert self.od is not None  # the mailbox checked it
        return self._read_object(self.od, index, sub)

    def _read_object(self: CpxEEc, od: ObjectDictionary, index: int, sub: int) -> Any:
        if index == HISTORY and sub >= FIRST_SUB:
            self.touch()  # the wire's face and the master call this, not through apply()
            self.history.read(sub)  # NO_SUBINDEX past sub 0, New Message Available falls
        return od.read(index, sub)
