"""What a scenario check before the run knows of ``cpx/N`` targets (app.scenario.check_against).

The CPX-E-EC's modules are fixed by the rig file; ``replace_module`` changes a module's type,
nothing plugs or unplugs one. The check follows the types through the scenario's steps and
refuses a module number the terminal does not have, as the handlers would at the step.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from devices.cpx.catalog import ModuleType, module_type
from devices.cpx.faults import check_target, fault_spec
from devices.device import UNKNOWN_MODULE, CommandError

if TYPE_CHECKING:
    from devices.cpx.modules import CpxModule

_FAULT_ACTIONS = ("inject_fault", "clear_fault")


def module_listing(device_id: str, module: int | None, layout: Mapping[int, Any]) -> str:
    """The refusal of a module number the terminal does not have, with its modules."""
    listing = ", ".join(f"{n}={'?' if k is UNKNOWN_MODULE else k.short}"
                        for n, k in sorted(layout.items()))
    return f"{device_id}: no module {module} (modules: {listing or 'none'})"


def modules_layout(modules: list[CpxModule]) -> dict[int, ModuleType]:
    return {m.number: m.mtype for m in modules}


class ModuleChecks:
    """The scenario-check hooks of :class:`~devices.cpx.device.CpxEEc`."""

    device_id: str
    modules: list[CpxModule]

    def module_layout(self) -> dict[int, Any]:
        return dict(modules_layout(self.modules))

    def check_module(self, action: str, args: Mapping[str, Any], module: int | None,
                     layout: dict[int, Any]) -> None:
        if action in _FAULT_ACTIONS:  # the handler's order: the fault's target first
            check_target(fault_spec(args["fault"]), module, args["channel"], args["sm"])
        if module is None:
            return
        if module not in layout:
            raise CommandError(module_listing(self.device_id, module, layout))
        if action == "replace_module":
            try:
                layout[module] = module_type(args["type"])
            except KeyError as exc:
                raise CommandError(exc.args[0]) from None

    def changes_modules(self, action: str, args: Mapping[str, Any],
                        module: int | None) -> tuple[int, ...]:
        return (module,) if action == "replace_module" and module is not None else ()
