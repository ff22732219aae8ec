"""Hidden faults an exercise can inject, and the candidate causes a trainee picks from.

Both come from the devices' own code tables, so a code added to a table is a new cause and a
new fault without touching this file: the FastCAT coupler and module codes (seed 000 §7.5,
§7.6, ``devices.fastcat.alarms.CODE_TABLES``) and the servo drive's alarms (its manual's alarm
table, ``devices.servo.alarms.alarm_table``). A few faults are physical rather than injected
codes (a pulled cable, a low Tbus supply, a jammed load): their cause is the code the device
reports for them, and their repair is the opposite action.

The TRS-CAT's application errors (seed 001 §9.3.7) and the CPX-E-EC's named faults
(``devices.cpx.faults``) are causes too.

A cause is named by an id: ``<device>:coupler:0x13``, ``<device>:module:0x0B`` (FastCAT),
``<device>:alarm:16`` (servo drive), ``<device>:fault:FIELD_SUPPLY`` (TRS-CAT, CPX-E-EC).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Command:
    target: str
    action: str
    args: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Cause:
    id: str
    label: str
    device: str


@dataclass(frozen=True)
class HiddenFault:
    """``inject`` makes the fault, ``repair`` removes its cause (an alarm may stay latched
    until the trainee resets it). ``gone``: snapshot values of ``device`` that say the fault
    is gone, besides the device showing no alarm."""

    id: str
    label: str
    device: str
    cause: str
    inject: tuple[Command, ...]
    repair: tuple[Command, ...]
    gone: Mapping[str, Any] = field(default_factory=dict)
    module: bool = False  # the instructor picks a module (target device/N)
    channel: bool = False  # a channel of that module may be named (a CPX-E-EC output short)

    def at(self, module: int | None, channel: int | None = None) -> HiddenFault:
        """This fault on module ``module`` (module codes), and on its channel ``channel``
        when given (the fault's commands carry it); itself otherwise."""
        if not self.module or module is None:
            return self
        if channel is not None and not self.channel:
            raise ValueError(f"{self.id} takes no channel")
        target = f"{self.device}/{module}"
        extra = {} if channel is None else {"channel": channel}

        def moved(commands: tuple[Command, ...]) -> tuple[Command, ...]:
            return tuple(Command(target, c.action, {**c.args, **extra}) for c in commands)

        place, where = (f"{module}", f"module {module}") if channel is None else \
            (f"{module}.{channel}", f"module {module}, channel {channel}")
        return HiddenFault(f"{self.id}@{place}", f"{self.label} ({where})", self.device,
                           self.cause, moved(self.inject), moved(self.repair), self.gone, True,
                           self.channel)


# Faults that are not a code injection: (device kind, id suffix, label, cause code key,
# inject (action, args), repair (action, args), snapshot values once repaired).
PHYSICAL: tuple[tuple[str, str, str, str, tuple[str, dict[str, Any]],
                      tuple[str, dict[str, Any]], dict[str, Any]], ...] = (
    ("fastcat", "cable", "EtherCAT cable pulled", "coupler:0x13",
     ("link", {"connected": False}), ("link", {"connected": True}), {"link": True}),
    ("fastcat", "tbus_low", "Tbus supply low", "module:0x0C",
     ("tbus_voltage", {"low": True}), ("tbus_voltage", {"low": False}), {"tbus_low": False}),
    ("servo", "jam", "Load jammed (shows when the axis moves)", "alarm:16",
     ("jam_load", {"active": True}), ("jam_load", {"active": False}), {"jammed": False}),
)


def _fastcat(device: str) -> Iterator[tuple[Cause, HiddenFault | None]]:
    from devices.fastcat.alarms import CODE_TABLES, MODULE

    for table in CODE_TABLES.values():
        for row in table.values():
            key = row.label  # coupler:0x04
            where = "§7.5" if row.table != MODULE else "§7.6"
            cause = Cause(f"{device}:{key}", f"{device} {row.table} 0x{row.code:02X} "
                          f"{row.symbol} — {row.description} ({where})", device)
            fault = HiddenFault(f"{device}:inject:{key}", f"{device}: inject {row.table} "
                                f"0x{row.code:02X} {row.symbol}", device, cause.id,
                                (Command(device, "inject_fault", {"fault": key}),),
                                (Command(device, "clear_fault", {"fault": key}),),
                                module=row.table == MODULE)
            yield cause, fault


def _servo(device: str, snapshot: Mapping[str, Any]) -> Iterator[tuple[Cause, HiddenFault | None]]:
    from devices.servo.alarms import alarm_table

    for spec in alarm_table(str(snapshot.get("fieldbus") or "modbus")).values():
        key = f"alarm:{spec.code}"
        cause = Cause(f"{device}:{key}", f"{device} alarm {spec.code} {spec.name} — "
                      f"{spec.description}", device)
        fault = HiddenFault(f"{device}:inject:{key}", f"{device}: inject alarm {spec.code} "
                            f"{spec.name}", device, cause.id,
                            (Command(device, "inject_alarm", {"code": str(spec.code)}),),
                            (Command(device, "clear_alarm", {"code": str(spec.code)}),))
        yield cause, fault


def _trscat(device: str) -> Iterator[tuple[Cause, HiddenFault | None]]:
    """Seed 001 §9.3.7 application errors. Causes that shut the TRS bus down until a power
    cycle are causes but no exercise: switching the supply off is the instructor's."""
    from devices.trscat.diagnostics import FAULTS, Target

    for spec in FAULTS.values():
        key = f"fault:{spec.name}"
        cause = Cause(f"{device}:{key}", f"{device} 0x{spec.code:04X} {spec.name} — "
                      f"{spec.text} (§9.3.7)", device)
        fault = None
        if not (spec.bus_shutdown or spec.deadlock):
            fault = HiddenFault(f"{device}:inject:{key}", f"{device}: inject {spec.name}",
                                device, cause.id,
                                (Command(device, "inject_fault", {"fault": spec.name}),),
                                (Command(device, "clear_fault", {"fault": spec.name}),),
                                module=spec.target is Target.ANALOG)
        yield cause, fault


def _cpx(device: str) -> Iterator[tuple[Cause, HiddenFault | None]]:
    """The CPX-E-EC's named faults (devices/cpx/faults.py, with their seed sections); those
    that need a channel or a sync manager are causes only."""
    from devices.cpx.faults import FAULTS, Target

    for spec in FAULTS.values():
        key = f"fault:{spec.name}"
        cause = Cause(f"{device}:{key}", f"{device} {spec.name} — {spec.doc} ({spec.seed})",
                      device)
        fault = None
        if spec.target in (Target.DEVICE, Target.MODULE):
            fault = HiddenFault(f"{device}:inject:{key}", f"{device}: inject {spec.name}",
                                device, cause.id,
                                (Command(device, "inject_fault", {"fault": spec.name}),),
                                (Command(device, "clear_fault", {"fault": spec.name}),),
                                module=spec.target is Target.MODULE, channel=spec.channel)
        yield cause, fault


SOURCES = {"fastcat": lambda d, s: _fastcat(d), "servo": _servo,
           "trscat": lambda d, s: _trscat(d), "cpx_e_ec": lambda d, s: _cpx(d)}


@dataclass(frozen=True)
class Catalog:
    causes: tuple[Cause, ...]
    faults: tuple[HiddenFault, ...]

    def cause(self, cause_id: str) -> Cause | None:
        return next((c for c in self.causes if c.id == cause_id), None)

    def fault(self, fault_id: str) -> HiddenFault:
        base, _, place = fault_id.partition("@")  # @module or @module.channel
        found = next((f for f in self.faults if f.id == base), None)
        if found is None:
            raise KeyError(f"no hidden fault {fault_id!r}")
        if not place:
            return found
        module, _, channel = place.partition(".")
        return found.at(int(module), int(channel) if channel else None)


def catalog(described: Mapping[str, Mapping[str, Any]],
            snapshot: Mapping[str, Any]) -> Catalog:
    """Causes and faults of a rig: ``described`` is :meth:`app.rig.Rig.describe`,
    ``snapshot`` :meth:`app.rig.Rig.snapshot` (a drive's alarms depend on its fieldbus)."""
    devices = snapshot.get("devices") or {}
    causes: list[Cause] = []
    faults: list[HiddenFault] = []
    for device, info in described.items():
        source = SOURCES.get(str(info["kind"]))
        if source is None:
            continue
        for cause, fault in source(device, devices.get(device) or {}):
            causes.append(cause)
            if fault is not None:
                faults.append(fault)
        for kind, suffix, label, code, (i_act, i_args), (r_act, r_args), gone in PHYSICAL:
            if kind == info["kind"]:
                faults.append(HiddenFault(f"{device}:{suffix}", f"{device}: {label}", device,
                                          f"{device}:{code}", (Command(device, i_act, i_args),),
                                          (Command(device, r_act, r_args),), gone))
    return Catalog(tuple(causes), tuple(faults))


ALARM_KEYS = ("alarm", "alarms")  # snapshot keys that hold a device's active alarm(s)
INJECTED_KEY = "injected"  # the snapshot key of a device's injected causes
NAME_KEYS = ("name", "fault", "cause")  # how an alarm or injected entry names its code


def _code(cause: str) -> tuple[str, int | str]:
    """(form, value) of a cause id: ``fastcat:coupler:0x04`` -> ("coupler", 4),
    ``drive:alarm:16`` -> ("alarm", 16), ``trscat:fault:CONFIG_ERROR`` -> ("fault", ...)."""
    _, form, value = cause.split(":", 2)
    return form, value if form == "fault" else int(value, 0)


def _module(fault: HiddenFault) -> int | None:
    """The module a module fault was put on (its target ``device/N``)."""
    target = fault.inject[0].target if fault.inject else fault.device
    _, _, module = target.partition("/")
    return int(module) if module.isdigit() else None


def _is_own(entry: Any, fault: HiddenFault) -> bool:
    """Whether an alarm or injected entry of the device's snapshot is ``fault``'s code: the
    FastCAT's {table, code, module} (an injected one has no table: module None is the coupler
    table), the drive's {code} or bare code, the slaves' {name} / {fault} at the fault's module
    or slot (and channel): the TRS-CAT's {fault, slot}, the CPX-E-EC's {fault, module, ...}."""
    form, value = _code(fault.cause)
    if form == "fault":
        if not isinstance(entry, Mapping):
            return False
        names = {str(entry[k]).casefold() for k in NAME_KEYS if entry.get(k)}
        return str(value).casefold() in names and _same_place(entry, fault)
    if not isinstance(entry, Mapping):
        return isinstance(entry, int) and form == "alarm" and entry == value
    if entry.get("code") != value:
        return False
    if form == "alarm":
        return True
    table = entry.get("table") or ("coupler" if entry.get("module") is None else "module")
    module = _module(fault)
    return table == form and (module is None or entry.get("module") in (module, None))


# Where a slave's entry sits: a CPX-E-EC module, a TRS-CAT slot (the target's N either way).
PLACE_KEYS = ("module", "slot")
# How other_faults names where another fault sits ("cpx module_ident_mismatch module 3").
PLACE_WORDS = (("module", "module {}"), ("slot", "slot {}"), ("channel", "channel {}"),
               ("sm", "SM{}"))


def _same_place(entry: Mapping[str, Any], fault: HiddenFault) -> bool:
    """A named fault put on module / slot N (and channel C) is not the same fault elsewhere;
    one put on no module in particular is its name anywhere."""
    module = _module(fault)
    if module is None:
        return True
    place = next((entry[k] for k in PLACE_KEYS if entry.get(k) is not None), None)
    channel = fault.inject[0].args.get("channel") if fault.inject else None
    return place == module and entry.get("channel") == channel


def _entries(snap: Mapping[str, Any], keys: tuple[str, ...]) -> list[Any]:
    found: list[Any] = []
    for key in keys:
        value = snap.get(key)
        found.extend(value if isinstance(value, list) else [value] if value else [])
    return found


def fault_gone(fault: HiddenFault, snapshot: Mapping[str, Any]) -> bool:
    """Whether the rig no longer shows ``fault``: its cause is removed (not injected any more,
    the physical repair holds) and its device shows its code no more (``snapshot``: the
    rig's). Another fault on the device does not count here (:func:`other_faults`)."""
    snap = (snapshot.get("devices") or {}).get(fault.device) or {}
    if any(_is_own(e, fault) for e in _entries(snap, (*ALARM_KEYS, INJECTED_KEY))):
        return False
    return all(snap.get(key) == value for key, value in fault.gone.items())


def other_faults(fault: HiddenFault, snapshot: Mapping[str, Any]) -> list[str]:
    """The other alarms and injected causes ``fault``'s device still has ("fastcat
    LINK_LOSS"): the result names them, the score does not count them."""
    snap = (snapshot.get("devices") or {}).get(fault.device) or {}
    others = [e for e in _entries(snap, (*ALARM_KEYS, INJECTED_KEY)) if not _is_own(e, fault)]
    named = {e.get("code") for e in others if isinstance(e, Mapping)}
    named_faults = _code(fault.cause)[0] == "fault"  # a TRS-CAT's or CPX-E-EC's
    labels: list[str] = []
    for entry in others:
        if isinstance(entry, Mapping):
            name = next((entry[k] for k in NAME_KEYS if entry.get(k)), entry.get("code"))
            if named_faults:  # a slave's: where it sits, the alarm and its cause alike
                name = " ".join([str(name), *(word.format(entry[k]) for k, word in PLACE_WORDS
                                              if entry.get(k) is not None)])
        elif isinstance(entry, int) and entry in named:
            continue  # a drive's bare code next to its {code, name}
        else:
            name = f"alarm {entry}" if isinstance(entry, int) else entry
        label = f"{fault.device} {name}"
        if label not in labels:
            labels.append(label)
    return labels
