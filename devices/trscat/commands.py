"""Operator and scenario actions of the TRS-CAT, declared as data, and their handlers.

Targets: ``trscat`` is the TRS-CAT itself (slot 0, its 16 integrated lines); ``trscat/N`` is
expansion N (slot N, 1..7), as 0xF030 / 0xF050 number them (§9.3.2). Field actions act on the
terminals (what a sensor, a load or a supply does), never on the device's logic; the PLC side
is ``set_output`` / ``write_object``, which write what the master sends.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from devices.device import Action, CommandError, Param, bool_value_as_int
from devices.ethercat import AlState
from devices.od import AbortCode, ObjectDictionary, SdoAbort
from devices.sync_managers import SM_FAULTS
from devices.trscat.alarms import FaultKey, TrsBus
from devices.trscat.catalog import (
    EXPANSIONS,
    expansion_kind,
)
from devices.trscat.diagnostics import FAULTS, parse_fault
from devices.trscat.io import SlotIo
from devices.trscat.module_checks import (
    FAULT_ACTIONS,
    channel_index,
    check_fault_target,
    check_output,
    check_plug,
    check_slot_fault,
    device_fault,
    no_expansion,
    plug_position,
)
from devices.trscat.objects import refuse_in_state
from devices.trscat.sync import MODE_BY_NAME, SyncMode, SyncUnit

if TYPE_CHECKING:
    from devices.trscat.catalog import ModuleKind
    from devices.trscat.diagnostics import DiagHistory
    from devices.trscat.esm import Esm

_CHANNEL = Param("channel", int, low=1, high=16, doc="channel, from 1")
_FAULT = Param("fault", str, parse=parse_fault,
               doc="a seed 001 §9.3.7 code (0x3220) or name (FIELD_SUPPLY)")
_SM_FAULT = (Param("fault", str, choices=tuple(SM_FAULTS)),
             Param("sm", int, low=0, high=3, doc="0 / 1 mailbox, 2 outputs, 3 inputs"))
SENSOR_ON_V = 24.0  # set_input(on=True): a PNP sensor puts the field voltage on the terminal

ACTIONS: dict[str, Action] = {a.name: a for a in (
    Action("power", "Switch the logic supply Vdd (§10.2); off clears every volatile state",
           (Param("on", bool),)),
    Action("field_supply", "Voltage on the +24Vdc field terminals (§10.3); outside 18..30 V "
                           "the +24V LED is off and 0x3220 is raised (§6.2, §8.4)",
           (Param("volts", float, low=0.0, high=40.0),)),
    Action("link", "Plug or unplug the EtherCAT cable on port in or out",
           (Param("port", str, choices=("in", "out")), Param("connected", bool))),
    Action("set_input", "A sensor drives the line to 24 V (on) or 0 V (off) (§3, §4)",
           (_CHANNEL, Param("on", bool)), module="optional"),
    Action("set_input_voltage", "Voltage a sensor puts on the line: <= 10 V is 0, >= 14 V "
                                "is 1, in between the level does not change (§4)",
           (_CHANNEL, Param("volts", float, low=0.0, high=40.0)), module="optional"),
    Action("set_load", "Current the load on the line draws when the output is on; above "
                       "0.5 A the output protection switches it off (§4)",
           (_CHANNEL, Param("amps", float, low=0.0, high=100.0)), module="optional"),
    Action("set_analog_input", "Voltage on a TRS-AN-E input (+-10 V)",
           (_CHANNEL, Param("volts", float, low=-12.0, high=12.0)), module="required"),
    Action("set_input_word", "Value of a data word of a TRS-XX-E / AC-E / KK-E",
           (_CHANNEL, Param("value", int, low=0, high=0xFFFF)), module="required"),
    Action("set_output", "What the PLC writes to an output (the RxPDO image, 0x7ss0:channel)",
           (_CHANNEL, Param("value", int, low=-0x8000, high=0xFFFF)), module="optional"),
    Action("unplug", "Take expansion N off the TRS bus (with power on: forbidden by §7, "
                     "a TRS bus communication error)", module="required"),
    Action("plug", "Put an expansion at position N (seen at the next power-up, §9.2)",
           (Param("type", str, choices=tuple(EXPANSIONS)),), module="required"),
    Action("inject_fault", "Make an application error cause present (§9.3.7); the slot is "
                           "the target module (none = the TRS-CAT)", (_FAULT,),
           module="optional"),
    Action("clear_fault", "Remove an injected cause (the TRS bus stays down after 0x7100, "
                          "0x7500, 0x6100 until power-off)", (_FAULT,), module="optional"),
    Action("inject_sm_fault", "The master sets up sync manager sm wrong: SM0 / SM1 refuse "
                              "INIT -> PREOP (0x0016), SM2 / SM3 PREOP -> SAFEOP "
                              "(0x001D / 0x001E) (§9.2)", _SM_FAULT),
    Action("clear_sm_fault", "The master sets sync manager sm up right again", _SM_FAULT),
    Action("drop_frames", "The next N master frames never reach SM2 (lost / CRC error)",
           (Param("count", int, low=0, high=1_000_000),)),
    Action("lose_sync0", "Stop or restore the SYNC0 pulses (§9.1.1)", (Param("lost", bool),)),
    Action("frame_jitter", "Frames arrive up to this many us late; one that invades the "
                           "calc+copy time misses its SYNC0 (§9.1.1)",
           (Param("us", int, low=0, high=100_000),)),
    Action("set_sync_mode", "Write 0x1C32:1 / 0x1C33:1 in PRE-OP: dc or free_run, the mode "
                            "the master asks for; PS refuses it (0x0030) unless the Sync "
                            "Control register says the same (§9.1.1)",
           (Param("mode", str, choices=tuple(MODE_BY_NAME)),)),
    Action("acknowledge_messages", "Write 0x10F3:3 = 0x10F3:2, as a master acknowledging "
                                   "every diagnosis message (§9.3.7)"),
    Action("write_object", "Write an object (access rights enforced, §9.3)",
           (Param("index", int, low=0, high=0xFFFF), Param("sub", int, low=0, high=0xFF),
            Param("value", int))),
    Action("read_object", "Read an object (§9.3)",
           (Param("index", int, low=0, high=0xFFFF), Param("sub", int, low=0, high=0xFF))),
)}


class CommandsMixin:
    """Operator commands of :class:`~devices.trscat.device.TrsCat`."""

    # Provided by TrsCat (declared for type checkers).
    device_id: str
    powered: bool
    field_v: float
    link_in: bool
    link_out: bool
    plugs: tuple[bool, bool]
    bus: TrsBus
    rail: list[SlotIo | None]
    detected: list[ModuleKind]
    injected: list[FaultKey]
    sync: SyncUnit
    diag: DiagHistory
    esm: Esm
    od: ObjectDictionary | None
    _plc_written: bool

    if TYPE_CHECKING:  # defined by TrsCat
        def cmd_power(self, on: bool) -> None: ...
        def write_object(self, index: int, sub: int, value: Any) -> None: ...
        def read_object(self, index: int, sub: int) -> Any: ...
        def _log(self, text: str) -> None: ...
        def module_layout(self) -> dict[int, Any]: ...

    def check_command(self, action: str, args: Mapping[str, Any],
                      module: int | None = None) -> dict[str, Any]:
        args = bool_value_as_int(action, args)
        kwargs: dict[str, Any] = super().check_command(action, args, module)  # type: ignore[misc]
        # Here, not only in the handlers: the checks before a run (a scenario's [[on]]
        # commands, an exercise file's fault) call this only. What depends on the expansions
        # a step finds is check_module's.
        if action in FAULT_ACTIONS:
            check_fault_target(self.device_id, kwargs["fault"], module)
        elif action in ("plug", "unplug") and module is not None:
            plug_position(module)
        return kwargs

    # ---- slots and channels -------------------------------------------------------------------
    def slot_io(self, module: int | None) -> SlotIo:
        slot = module or 0
        io = self.rail[slot] if slot < len(self.rail) else None
        if io is None:
            raise CommandError(no_expansion(self.device_id, slot, self.module_layout(),
                                            len(self.rail) - 1))
        return io

    # ---- field side ---------------------------------------------------------------------------
    def cmd_field_supply(self, volts: float) -> None:
        self.field_v = volts

    def cmd_link(self, port: str, connected: bool) -> None:
        inp, out = self.plugs
        self.plugs = (connected, out) if port == "in" else (inp, connected)
        self._ports()

    def cmd_set_input(self, channel: int, on: bool, module: int | None) -> None:
        self.cmd_set_input_voltage(channel, SENSOR_ON_V if on else 0.0, module)

    def cmd_set_input_voltage(self, channel: int, volts: float, module: int | None) -> None:
        io = self.slot_io(module)
        ch = channel_index(io.kind, "set_input_voltage", channel)
        assert io.lines is not None
        io.lines.set_external(ch, volts)

    def cmd_set_load(self, channel: int, amps: float, module: int | None) -> None:
        io = self.slot_io(module)
        ch = channel_index(io.kind, "set_load", channel)
        assert io.lines is not None
        io.lines.set_load(ch, amps)

    def cmd_set_analog_input(self, channel: int, volts: float, module: int) -> None:
        io = self.slot_io(module)
        io.analog_in_v[channel_index(io.kind, "set_analog_input", channel)] = volts

    def cmd_set_input_word(self, channel: int, value: int, module: int) -> None:
        io = self.slot_io(module)
        io.words_in[channel_index(io.kind, "set_input_word", channel)] = value

    def cmd_set_output(self, channel: int, value: int, module: int | None) -> None:
        io = self.slot_io(module)
        ch = channel_index(io.kind, "set_output", channel)
        self.od_set_output(module or 0, ch, value)

    def od_set_output(self, slot: int, channel: int, value: int) -> None:
        io = self.rail[slot]
        assert io is not None
        check_output(io.kind, channel, value)
        io.plc[channel] = value
        self._plc_written = True  # the next SM2 event latches it (stepping.py)

    def cmd_unplug(self, module: int) -> None:
        self.slot_io(module)
        self.rail[module] = None
        if self.powered:
            self._log(f"expansion {module} unplugged with power on (not allowed, §7)")

    def cmd_plug(self, module: int, type: str) -> None:
        kind = expansion_kind(type)
        check_plug(self.device_id, module, kind, self.module_layout())
        self.rail.extend([None] * (module + 1 - len(self.rail)))
        self.rail[module] = SlotIo.new(kind)
        if self.powered:
            self._log(f"expansion {module} plugged with power on (not allowed, §7): "
                      f"detected at the next power-up")

    # ---- faults -------------------------------------------------------------------------------
    def _fault_key(self, text: str, module: int | None) -> FaultKey:
        fault = parse_fault(text)
        if device_fault(self.device_id, text, module):
            return fault.name, None
        check_slot_fault(text, self.slot_io(module).kind, module or 0)
        return fault.name, module or 0

    def cmd_inject_fault(self, fault: str, module: int | None) -> None:
        key = self._fault_key(fault, module)
        if key not in self.injected:
            self.injected.append(key)

    def cmd_clear_fault(self, fault: str, module: int | None) -> None:
        key = self._fault_key(fault, module)
        if key not in self.injected:
            now = ", ".join(f"{n}@{s}" if s is not None else n for n, s in self.injected)
            raise CommandError(f"{FAULTS[key[0]].name} is not injected there "
                               f"(injected: {now or 'none'})")
        self.injected.remove(key)

    def cmd_drop_frames(self, count: int) -> None:
        self.sync.drop_frames = count

    def cmd_lose_sync0(self, lost: bool) -> None:
        self.sync.sync0_lost = lost

    def cmd_frame_jitter(self, us: int) -> None:
        self.sync.jitter_us = us

    # ---- the master's side, as actions ----------------------------------------------------------
    def cmd_set_sync_mode(self, mode: str) -> None:
        self.cmd_write_object(0x1C32, 1, int(MODE_BY_NAME[mode]))

    def cmd_acknowledge_messages(self) -> None:
        self.cmd_write_object(0x10F3, 3, self.diag.newest)

    def cmd_write_object(self, index: int, sub: int, value: int) -> None:
        self.write_object(index, sub, value)

    def cmd_read_object(self, index: int, sub: int) -> Any:
        return self.read_object(index, sub)

    def require_od(self) -> ObjectDictionary:
        if not self.powered:
            raise CommandError(f"{self.device_id} is not powered")
        if self.od is None:
            raise CommandError(f"{self.device_id}: the object dictionary exists once the "
                               f"power-up detection of the TRS bus is over (§9.2 INIT)")
        return self.od

    def od_set_sync_mode(self, index: int, value: int) -> None:
        """0x1C32:1 or 0x1C33:1 (``index``) written: one mode for both, shown at once and
        checked at PS against the Sync Control register (§9.1.1); kept until INIT. An abort
        names the object the master wrote."""
        if self.esm.state is not AlState.PREOP:
            raise refuse_in_state(index, 1)
        try:
            mode = SyncMode(value)
        except ValueError:
            raise SdoAbort(AbortCode.VALUE_RANGE, index, 1) from None
        self.sync.request(mode)

