"""The coupler's operator actions: the actions table and the physical causes on the rail.

Targets are ``fastcat`` (the coupler) or ``fastcat/N``: N is the rail position, which is the
module number the seed counts from 1 as long as the rail has no empty slot (a module missing
in the middle shifts the bus numbering of the ones after it, as on the real internal bus).
Module-level actions of :class:`~devices.fastcat.modules.IoModule` are forwarded to the module
at rail position N. Mapping of causes to alarm codes: docs/fastcat-coupler.md.
"""

from __future__ import annotations

import random
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from devices.device import UNKNOWN_MODULE, Action, CommandError, Param, bool_value_as_int
from devices.fastcat.alarms import MODULE, parse_fault
from devices.fastcat.catalog import CATALOG, a_module, module_type
from devices.fastcat.modules import IoModule
from devices.fastcat.objects import MAX_MODULES
from devices.od import ObjectDictionary

if TYPE_CHECKING:
    from devices.flash import FlashStore

_SLOT = Param("other", int, low=1, high=MAX_MODULES, doc="the other rail position")
_FAULT = Param("fault", str, parse=parse_fault, doc="a §7.5 / §7.6 symbol or coupler:0xNN / "
                                                    "module:0xNN")
# Commands that act on the module at the rail position (the others put one there or name
# the position only, e.g. a module alarm).
_NEED_MODULE = ("unplug", "module_power")
_FAULT_ACTIONS = ("inject_fault", "clear_fault")

COUPLER_ACTIONS: dict[str, Action] = {a.name: a for a in (
    Action("power", "Switch the coupler supply on or off", (Param("on", bool),)),
    Action("press_cnf", "Press the CNF button and keep it down (§2)"),
    Action("release_cnf", "Release CNF: held for 3 s or more, it resets the modules, scans "
                          "the internal bus and stores the configuration (§2)"),
    Action("hold_cnf", "Press CNF now and release it after this many seconds (§2)",
           (Param("seconds", float, low=0.0, high=60.0),)),
    Action("inject_fault", "Make an alarm cause present: a §7.5 / §7.6 symbol (e.g. "
                           "MISSING_NODE_ANSWER, TARATURA) or coupler:0xNN / module:0xNN; "
                           "the target module is byte 0 of the emergency",
           (_FAULT,), module="optional"),
    Action("clear_fault", "Remove an injected cause (the alarm stays latched until reset)",
           (_FAULT,), module="optional"),
    Action("set_reset_fault", "Write the Reset fault bit 0x5200:1; a rising edge resets a "
                              "resettable alarm whose cause is gone (§6.17, §7)",
           (Param("on", bool),)),
    Action("write_object", "Write an object (access rights enforced, §6)",
           (Param("index", int, low=0, high=0xFFFF), Param("sub", int, low=0, high=0xFF),
            Param("value", int))),
    Action("read_object", "Read an object (§6)",
           (Param("index", int, low=0, high=0xFFFF), Param("sub", int, low=0, high=0xFF))),
    Action("set_rotary", "Turn the address rotary switch (1..15); the coupler reads it at "
                         "power-up (§6.19, §6.20)", (Param("value", int, low=1, high=15),)),
    Action("unplug", "Take the module at this rail position off the rail", module="required"),
    Action("plug", "Put a module of this type on the empty rail position",
           (Param("type", str, choices=tuple(CATALOG)),), module="required"),
    Action("swap", "Swap the modules at two rail positions", (_SLOT,), module="required"),
    Action("module_power", "Switch one module's supply", (Param("on", bool),),
           module="required"),
    Action("tbus_voltage", "Internal-bus (Tbus) supply low or normal (module code 0x0C)",
           (Param("low", bool),)),
    Action("link", "Plug or unplug the EtherCAT cable (coupler code 0x13)",
           (Param("connected", bool),)),
)}

# IoModule actions, addressed as fastcat/N; the coupler's own names win on a clash.
MODULE_ACTIONS: dict[str, Action] = {
    name: replace(action, module="required") for name, action in IoModule.ACTIONS.items()
    if name not in COUPLER_ACTIONS}
# Module commands that change only what a module's field terminals carry, which the module's
# own step compares by value (AnalogInputs.step): the module is stepped at the next cycle
# (bus.py, "woken") without a full step of the coupler. A full step would ask every module
# whether it answers, step the still ones and search every alarm cause, and find each as it
# was: a field value is an input of none of them (docs/performance.md "Session 22").
FIELD_ACTIONS = frozenset({"set_analog"})


class RailMixin:
    """Rail and operator commands of :class:`~devices.fastcat.coupler.FastCat`."""

    # Provided by FastCat (declared for type checkers).
    rail: list[IoModule | None]
    shelf: dict[int, IoModule]
    powered: bool
    rng: random.Random
    device_id: str
    tbus_low: bool
    link: bool
    line_in: bool
    plugs: tuple[bool, bool]
    rotary_switch: int
    od: ObjectDictionary | None
    flash: FlashStore
    detected: list[tuple[int, str]]
    _touched: bool
    _modules_touched: bool
    _woken: list[IoModule]  # bus.py
    _settled: tuple[int, bool] | None

    def check_command(self, action: str, args: Mapping[str, Any],
                      module: int | None = None) -> dict[str, Any]:
        args = bool_value_as_int(action, args)
        kwargs: dict[str, Any] = super().check_command(action, args, module)  # type: ignore[misc]
        # Here, not in the command itself: a scenario's check before the run calls this only.
        if action in _FAULT_ACTIONS:
            row = parse_fault(kwargs["fault"])
            if module is None and not row.on_coupler:
                raise CommandError(f"{row.symbol} is a module alarm (§7.6): target "
                                   f"'{self.device_id}/N'")
            if module is not None and not row.names_module:
                # a module here is no byte 0 the coupler could send: refused, not sent
                raise CommandError(f"{row.symbol} is an alarm of the coupler itself (§7.5: "
                                   f"byte 0 names no module): target '{self.device_id}'")
        return kwargs

    def apply(self, action: str, args: Mapping[str, Any], module: int | None = None) -> Any:
        if action in FIELD_ACTIONS:
            kwargs = self.check_command(action, args, module)
            target = self.rail_module(module)
            done = target.run(action, kwargs)  # checked: the module's own check would repeat it
            self._woken.append(target)  # stepped at the next cycle, still or not (bus.py)
            self._settled = None  # so there is a next cycle: no repeat of a settled step
            return done
        self._touched = self._modules_touched = True  # a full next step (FastCat.step)
        if action in MODULE_ACTIONS:
            kwargs = self.check_command(action, args, module)
            return self.rail_module(module).run(action, kwargs)
        return super().apply(action, args, module)  # type: ignore[misc]

    def module_layout(self) -> dict[int, Any]:
        return {n: m.mtype for n, m in enumerate(self.rail, start=1) if m is not None}

    def check_module(self, action: str, args: Mapping[str, Any], module: int | None,
                     layout: dict[int, Any]) -> None:
        if module is None:
            return
        self._on_rail(module)
        if action == "plug":
            here = layout.get(module)
            if here is not None and here is not UNKNOWN_MODULE:
                raise CommandError(_taken(self.device_id, module, here.name))
            layout[module] = module_type(args["type"])
        elif action == "swap":
            other = args["other"]
            here, there = layout.pop(module, None), layout.pop(other, None)
            if here is not None:
                layout[other] = here
            if there is not None:
                layout[module] = there
        elif action == "inject_fault":
            row = parse_fault(args["fault"])
            if row.table == MODULE and module not in layout:
                # Before the run the modules are numbered by rail position, as the rig is
                # built; a rescan's renumbering after a gap is the run's (_numbered).
                raise CommandError(_no_module(self.device_id, row.symbol, module, module,
                                              layout))
        elif action in MODULE_ACTIONS or action in _NEED_MODULE:
            if module not in layout:
                raise CommandError(f"{self.device_id}: no module at rail position {module} "
                                   f"(rail: {_layout_text(layout)}) and no earlier step plugs "
                                   f"one there")
            if action == "unplug":
                del layout[module]
            elif action in MODULE_ACTIONS and layout[module] is not UNKNOWN_MODULE:
                IoModule.check_kind(layout[module], action, args)

    def changes_modules(self, action: str, args: Mapping[str, Any],
                        module: int | None) -> tuple[int, ...]:
        if module is None:
            return ()
        if action in ("plug", "unplug"):
            return (module,)
        if action == "swap":
            return (module, int(args.get("other", module)))
        return ()

    def _numbered(self) -> dict[int, int]:
        """Rail position per module number: the last scan's numbering (byte 0 of the
        emergency, §7), or the rail positions while no scan has numbered any module."""
        if self.detected:
            return {n: slot for n, (slot, _name) in enumerate(self.detected, start=1)}
        return {n: n for n in range(1, len(self.rail) + 1)}

    def check_module_fault(self, symbol: str, module: int) -> None:
        """A §7.6 alarm is raised by the module itself: module ``module`` must be on the
        rail, in the position the coupler numbered it in. Refused with the modules there are."""
        numbered, rail = self._numbered(), self.rail
        held = {n: m for n, slot in numbered.items()
                if slot <= len(rail) and (m := rail[slot - 1]) is not None}
        if module in held:
            return
        listing = {n: m.mtype for n, m in held.items()}
        slot = numbered.get(module, module)
        if slot <= len(rail) and rail[slot - 1] is not None:  # a module the scan did not number
            raise CommandError(f"{self.device_id}: {symbol} is a module alarm (§7.6): there "
                               f"is no module {module}: the last scan numbered "
                               f"{len(numbered)} (modules: {_listing(listing)})")
        raise CommandError(_no_module(self.device_id, symbol, module, slot, listing))

    def rail_module(self, slot: int | None) -> IoModule:
        if slot is None or not 1 <= slot <= len(self.rail) or self.rail[slot - 1] is None:
            raise CommandError(f"{self.device_id}: no module at rail position {slot} "
                               f"(rail: {self._rail_text()})")
        module = self.rail[slot - 1]
        assert module is not None
        return module

    def _rail_text(self) -> str:
        return _layout_text(self.module_layout(), last=len(self.rail))

    def cmd_unplug(self, module: int) -> None:
        taken = self.rail_module(module)
        taken.plugged = False
        taken.in_alarm = False
        self.shelf[module] = taken
        self.rail[module - 1] = None

    def _on_rail(self, module: int) -> None:
        if not 1 <= module <= MAX_MODULES:
            raise CommandError(f"{self.device_id}: no rail position {module}: a FastCAT takes "
                               f"at most {MAX_MODULES} modules (§2)")

    def cmd_plug(self, module: int, type: str) -> None:
        self._on_rail(module)
        taken = self.rail[module - 1] if module <= len(self.rail) else None
        if taken is not None:
            raise CommandError(_taken(self.device_id, module, taken.mtype.name))
        mtype = module_type(type)
        back = self.shelf.get(module)
        if back is not None and back.mtype is mtype:  # the same module put back
            new = self.shelf.pop(module)
        else:
            new = IoModule(mtype, random.Random(self.rng.getrandbits(64)))
        new.plugged = True
        if self.powered:
            new.reset()  # it powers up from the Tbus
        self.rail.extend([None] * (module - len(self.rail)))
        self.rail[module - 1] = new

    def cmd_swap(self, module: int, other: int) -> None:
        self._on_rail(module)
        if module == other:
            raise CommandError(f"swap: rail position {module} with itself")
        top = max(module, other)
        self.rail.extend([None] * (top - len(self.rail)))
        a, b = self.rail[module - 1], self.rail[other - 1]
        if a is None and b is None:
            raise CommandError(f"swap: rail positions {module} and {other} are both empty")
        self.rail[module - 1], self.rail[other - 1] = b, a

    def cmd_module_power(self, module: int, on: bool) -> None:
        target = self.rail_module(module)
        if on and not target.powered and self.powered:
            target.reset()
        target.powered = on

    def cmd_tbus_voltage(self, low: bool) -> None:
        self.tbus_low = low

    def cmd_link(self, connected: bool) -> None:
        self.plugs = (connected, True)  # the operator's own plug at IN (the only port)
        self.link = self.line_in and connected

    # ---- the line, as the EtherCAT master drives it (devices/master) ------------------------
    def set_link(self, connected: bool, port: str = "in") -> None:
        """The cable on the IN port (the coupler's only port): no link raises 0x13."""
        if port == "in":
            self._touched = True
            self.line_in = connected
            self.link = connected and self.plugs[0]

    def set_power(self, on: bool) -> None:
        self._touched = True
        self.cmd_power(on)  # type: ignore[attr-defined]

    def mailbox_write(self, index: int, sub: int, value: Any) -> None:
        self._touched = True  # a master's SDO download (CoeMailbox): the next step is full
        super().mailbox_write(index, sub, value)  # type: ignore[misc]

    def cmd_set_rotary(self, value: int) -> None:
        self.rotary_switch = value  # read at the next power-up, like the real switch

    def cmd_write_object(self, index: int, sub: int, value: int) -> None:
        self._require_od().write(index, sub, value)

    def cmd_read_object(self, index: int, sub: int) -> Any:
        return self._require_od().read(index, sub)

    def cmd_set_reset_fault(self, on: bool) -> None:
        self._require_od().write(0x5200, 1, int(on))

    def _require_od(self) -> ObjectDictionary:
        if not self.powered:
            raise CommandError(f"{self.device_id} is not powered")
        if self.od is None:
            raise CommandError(f"{self.device_id}: the object dictionary is generated at the "
                               f"end of the first internal-bus scan (§5); wait for it")
        return self.od


def _layout_text(layout: Mapping[int, Any], last: int | None = None) -> str:
    """``1=DB16, 2=-, 3=?``: positions 1 .. ``last`` (default: the last one held) of a rail
    or a scenario check's layout (``?`` = an [[on]] command may change it)."""
    last = max(layout, default=0) if last is None else last
    return ", ".join(f"{n}={_kind_name(layout.get(n))}" for n in range(1, last + 1)) or "empty"


def _listing(kinds: Mapping[int, Any]) -> str:
    return ", ".join(f"{n}={_kind_name(k)}" for n, k in sorted(kinds.items())) or "none"


def _no_module(device_id: str, symbol: str, module: int, slot: int,
               kinds: Mapping[int, Any]) -> str:
    """The refusal of a §7.6 fault on module ``module``, whose rail position ``slot`` is
    empty; ``kinds``: the module numbers there are and their kinds."""
    return (f"{device_id}: {symbol} is a module alarm (§7.6): there is no module {module}, "
            f"rail position {slot} is empty (modules: {_listing(kinds)})")


def _kind_name(kind: Any) -> str:
    return "-" if kind is None else "?" if kind is UNKNOWN_MODULE else str(kind.name)


def _taken(device_id: str, module: int, name: str) -> str:
    return f"{device_id}: rail position {module} is taken by {a_module(name)}: unplug it first"
