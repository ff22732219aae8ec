"""What a scenario check before the run knows of ``trscat/N`` targets
(app.scenario.check_against): the expansions each position holds at that step, from the rig
as built and the earlier plug / unplug steps, refused as the handlers would refuse them: a
position with no expansion, a channel its kind does not have (:func:`check_kind`, which the
handlers call too), a TRS-AN-E fault elsewhere."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from devices.device import UNKNOWN_MODULE, CommandError
from devices.trscat.catalog import (
    EXPANSIONS,
    INTEGRATED,
    MAX_EXPANSIONS,
    IoShape,
    ModuleKind,
    expansion_kind,
    limit_violation,
)
from devices.trscat.diagnostics import Target, parse_fault

if TYPE_CHECKING:
    from devices.trscat.io import SlotIo

FAULT_ACTIONS = ("inject_fault", "clear_fault")
_DIGITAL = ((IoShape.DIGITAL,), False)
# The channels each action names: of which shapes, and whether outputs are counted.
_CHANNELS: dict[str, tuple[tuple[IoShape, ...], bool]] = {
    "set_input": _DIGITAL, "set_input_voltage": _DIGITAL, "set_load": _DIGITAL,
    "set_analog_input": ((IoShape.ANALOG,), False), "set_input_word": ((IoShape.WORDS,), False),
    "set_output": (tuple(IoShape), True),
}
# What the PLC may write to an output of each shape (the RxPDO entry's type).
OUTPUT_RANGE = {IoShape.DIGITAL: (0, 1), IoShape.ANALOG: (-0x8000, 0x7FFF),
                IoShape.WORDS: (0, 0xFFFF)}


def channel_index(kind: ModuleKind, action: str, channel: int) -> int:
    """The 0-based index of ``channel`` (from 1) of an action on a slot of this kind."""
    shapes, outputs = _CHANNELS[action]
    if kind.shape not in shapes:
        raise CommandError(f"{kind.name} has no {' / '.join(s.value for s in shapes)} "
                           f"channels")
    count = kind.outputs if outputs else kind.inputs
    if not 1 <= channel <= count:
        raise CommandError(f"{kind.name}: channel {channel} outside 1..{count}")
    return channel - 1


def _has_channels(kind: ModuleKind, action: str) -> bool:
    try:
        channel_index(kind, action, 1)
    except CommandError:
        return False
    return True


def check_output(kind: ModuleKind, index: int, value: int) -> None:
    low, high = OUTPUT_RANGE[kind.shape]
    if not low <= value <= high:
        raise CommandError(f"{kind.name} output {index + 1}: {value} outside {low}..{high}")


def check_slot_fault(fault: str, kind: ModuleKind, slot: int) -> None:
    found = parse_fault(fault)
    if found.target is Target.ANALOG and kind is not EXPANSIONS["TRS-AN-E"]:
        raise CommandError(f"{found.name} (0x{found.code:04X}) is a TRS-AN-E fault; "
                           f"position {slot} is a {kind.name}")


def check_kind(kind: ModuleKind, slot: int, action: str, args: Mapping[str, Any]) -> None:
    """Refuse what slot ``slot`` holding ``kind`` cannot take whatever its state."""
    if action in FAULT_ACTIONS:
        check_slot_fault(args["fault"], kind, slot)
    elif action in _CHANNELS:
        index = channel_index(kind, action, args["channel"])
        if action == "set_output":
            check_output(kind, index, args["value"])


def rail_text(layout: Mapping[int, Any], last: int) -> str:
    """``0=IO-B, 1=IO-E, 2=-``: slots 0 .. last (``?``: an [[on]] command may change it)."""
    return ", ".join(f"{s}={_short(layout.get(s))}" for s in range(last + 1))


def _short(kind: Any) -> str:
    return "-" if kind is None else "?" if kind is UNKNOWN_MODULE else str(kind.short)


def no_expansion(device_id: str, slot: int, layout: Mapping[int, Any], last: int) -> str:
    return f"{device_id}: no expansion at position {slot} (rail: {rail_text(layout, last)})"


def plug_position(module: int) -> None:
    """Where an expansion can be plugged or unplugged: slot 0 is the integrated module, part
    of the base (§9.3.2 "quello integrato direttamente in TRS-CAT"), not a position."""
    if not 1 <= module <= MAX_EXPANSIONS:
        raise CommandError(f"a TRS-CAT has expansion positions 1..{MAX_EXPANSIONS} (§5)")


def check_plug(device_id: str, module: int, kind: ModuleKind,
               held: Mapping[int, Any]) -> None:
    """A plug of ``kind`` at ``module`` on a rail holding ``held`` (slot -> kind): a position
    1..7 that is free, and expansions that still fit §5 with it."""
    plug_position(module)
    here = held.get(module)
    if here is UNKNOWN_MODULE:
        return
    if here is not None:
        raise CommandError(f"{device_id}: position {module} holds a {here.name}: unplug it "
                           f"first")
    kinds = [k for s, k in held.items() if s > 0] + [kind]
    if UNKNOWN_MODULE in kinds:
        return
    violation = limit_violation(kinds)
    if violation is not None:
        raise CommandError(violation)


def device_fault(device_id: str, fault: str, module: int | None) -> bool:
    """Whether ``fault`` is the TRS-CAT's own; refused on an expansion target."""
    found = parse_fault(fault)
    if found.target is not Target.DEVICE:
        return False
    if module is not None:
        raise CommandError(f"{found.name} is a fault of the TRS-CAT itself: target "
                           f"'{device_id}'")
    return True


def check_fault_target(device_id: str, fault: str, module: int | None) -> None:
    """Refuse a fault whatever the expansions: one of the TRS-CAT itself on an expansion, a
    TRS-AN-E fault on the TRS-CAT (slot 0 always holds the integrated I/O)."""
    if not device_fault(device_id, fault, module) and module is None:
        check_slot_fault(fault, INTEGRATED, 0)


class ModuleChecks:
    """The scenario-check hooks of :class:`~devices.trscat.device.TrsCat`."""

    device_id: str
    rail: list[SlotIo | None]

    def module_layout(self) -> dict[int, Any]:
        return {s: io.kind for s, io in enumerate(self.rail) if io is not None}

    def check_module(self, action: str, args: Mapping[str, Any], module: int | None,
                     layout: dict[int, Any]) -> None:
        if action in FAULT_ACTIONS and device_fault(self.device_id, args["fault"], module):
            return
        if action == "plug" and module is not None:
            kind = expansion_kind(args["type"])
            check_plug(self.device_id, module, kind, layout)
            layout[module] = kind
            return
        slot = module or 0
        kind = layout.get(slot, INTEGRATED if slot == 0 else None)
        if kind is None:
            raise CommandError(no_expansion(self.device_id, slot, layout,
                                            max(layout, default=0)))
        if kind is not UNKNOWN_MODULE:
            check_kind(kind, slot, action, args)
        if action == "unplug":
            del layout[slot]

    def changes_modules(self, action: str, args: Mapping[str, Any],
                        module: int | None) -> tuple[int, ...]:
        return (module,) if action in ("plug", "unplug") and module is not None else ()

    def target_actions(self, module: int | None = None) -> list[str]:
        """As the device's; the channel actions narrowed by what the slot holds (slot 0, the
        target ``trscat``, the integrated I/O): no set_input on a TRS-AN-E."""
        names: list[str] = super().target_actions(module)  # type: ignore[misc]
        slot = module or 0
        io = self.rail[slot] if 0 <= slot < len(self.rail) else None
        if io is None:
            return []
        return [n for n in names if n not in _CHANNELS or _has_channels(io.kind, n)]
