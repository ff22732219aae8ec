"""What a scenario check before the run knows of ``trscat/N`` targets
(app.scenario.check_against): the expansions each position holds at that step, from the rig
as built and the earlier plug / unplug steps, refused as the handlers would refuse them."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from devices.device import UNKNOWN_MODULE, CommandError
from devices.trscat.catalog import MAX_EXPANSIONS, expansion_kind
from devices.trscat.diagnostics import Target, parse_fault

if TYPE_CHECKING:
    from devices.trscat.io import SlotIo

_FAULT_ACTIONS = ("inject_fault", "clear_fault")


def rail_text(layout: Mapping[int, Any], last: int) -> str:
    """``0=IO-B, 1=IO-E, 2=-``: slots 0 .. last (``?``: an [[on]] command may change it)."""
    return ", ".join(f"{s}={_short(layout.get(s))}" for s in range(last + 1))


def _short(kind: Any) -> str:
    return "-" if kind is None else "?" if kind is UNKNOWN_MODULE else str(kind.short)


def no_expansion(device_id: str, slot: int, layout: Mapping[int, Any], last: int) -> str:
    return f"{device_id}: no expansion at position {slot} (rail: {rail_text(layout, last)})"


def plug_position(module: int) -> None:
    if module > MAX_EXPANSIONS:
        raise CommandError(f"a TRS-CAT has expansion positions 1..{MAX_EXPANSIONS} (§5)")


def device_fault(device_id: str, fault: str, module: int | None) -> bool:
    """Whether ``fault`` is the TRS-CAT's own; refused on an expansion target."""
    found = parse_fault(fault)
    if found.target is not Target.DEVICE:
        return False
    if module is not None:
        raise CommandError(f"{found.name} is a fault of the TRS-CAT itself: target "
                           f"'{device_id}'")
    return True


class ModuleChecks:
    """The scenario-check hooks of :class:`~devices.trscat.device.TrsCat`."""

    device_id: str
    rail: list[SlotIo | None]

    def module_layout(self) -> dict[int, Any]:
        return {s: io.kind for s, io in enumerate(self.rail) if io is not None}

    def check_module(self, action: str, args: Mapping[str, Any], module: int | None,
                     layout: dict[int, Any]) -> None:
        if action in _FAULT_ACTIONS and device_fault(self.device_id, args["fault"], module):
            return
        if module is None:
            return
        if action == "plug":
            plug_position(module)
            layout[module] = expansion_kind(args["type"])
            return
        if module not in layout:
            raise CommandError(no_expansion(self.device_id, module, layout,
                                            max(layout, default=0)))
        if action == "unplug":
            del layout[module]

    def changes_modules(self, action: str, args: Mapping[str, Any],
                        module: int | None) -> tuple[int, ...]:
        return (module,) if action in ("plug", "unplug") and module is not None else ()
