"""What a scenario check before the run knows of ``cpx/N`` targets (app.scenario.check_against).

The CPX-E-EC's modules are fixed by the rig file; ``replace_module`` changes a module's type,
nothing plugs or unplugs one. The check follows the types through the scenario's steps and
refuses a module number the terminal does not have, or an action or channel the module's type
cannot take (:func:`check_kind`, which the handlers call too), as the step would.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from devices.cpx.catalog import ModuleKind, ModuleType, module_type
from devices.cpx.faults import fault_spec
from devices.device import UNKNOWN_MODULE, CommandError

if TYPE_CHECKING:
    from devices.cpx.modules import CpxModule

FAULT_ACTIONS = ("inject_fault", "clear_fault")
_PHYSICAL_FAULTS = ("short_circuit", "wire_break")  # inject_fault runs their actions


def is_digital_input(mtype: ModuleType) -> bool:
    return mtype.kind is ModuleKind.DIGITAL and bool(mtype.inputs)


def is_counter(mtype: ModuleType) -> bool:
    return mtype.short == "1CI"


def check_channel(mtype: ModuleType, channel: int) -> int:
    if not 0 <= channel < mtype.channels:
        raise CommandError(f"{mtype.name} has channels 0 ... {mtype.channels - 1}, "
                           f"not {channel}")
    return channel


def _set_input(mtype: ModuleType, module: int, channel: int | None) -> None:
    if not is_digital_input(mtype):
        raise CommandError(f"module {module} ({mtype.name}) has no digital inputs")


def _set_analog(mtype: ModuleType, module: int, channel: int | None) -> None:
    if not (mtype.analog_ranges and mtype.inputs):
        raise CommandError(f"module {module} ({mtype.name}) has no analog inputs")


def _set_count_rate(mtype: ModuleType, module: int, channel: int | None) -> None:
    if not is_counter(mtype):
        raise CommandError(f"module {module} ({mtype.name}) is not a counter")


def _short_circuit(mtype: ModuleType, module: int, channel: int | None) -> None:
    if channel is None:
        if not mtype.inputs or is_counter(mtype):
            raise CommandError(f"{mtype.name} has no sensor supply to short: give the output "
                               f"channel")
    elif not mtype.outputs or is_counter(mtype):
        raise CommandError(f"{mtype.name} has no outputs to short; without channel the "
                           f"sensor supply is shorted")


def _wire_break(mtype: ModuleType, module: int, channel: int | None) -> None:
    if not (mtype.analog_ranges or is_counter(mtype)):
        raise CommandError(f"{mtype.name}: wire break is diagnosed on analog channels and "
                           f"the counter input")


def _force(mtype: ModuleType, module: int, channel: int | None) -> None:
    if mtype.analog_ranges or is_counter(mtype):
        raise CommandError(f"{mtype.name}: only digital channels can be forced")


# What each module action needs of the module's type (the channel is checked after it).
_KIND_CHECKS: dict[str, Callable[[ModuleType, int, int | None], None]] = {
    "set_input": _set_input, "set_analog": _set_analog, "set_count_rate": _set_count_rate,
    "short_circuit": _short_circuit, "wire_break": _wire_break, "force": _force,
}


def fits(mtype: ModuleType, module: int, action: str) -> bool:
    """Whether a module of type ``mtype`` takes ``action`` with some channel (or none: the
    sensor supply's short), as :func:`check_kind` would let it through."""
    check = _KIND_CHECKS.get(action)
    if check is None:
        return True
    for channel in (None, 0):
        try:
            check(mtype, module, channel)
        except CommandError:
            continue
        return True
    return False


def check_kind(mtype: ModuleType, module: int, action: str, args: Mapping[str, Any]) -> None:
    """Refuse what module ``module`` of type ``mtype`` cannot take whatever its state: an
    action its type has nothing for, a channel it does not have (Tab. 21-23)."""
    if action in FAULT_ACTIONS:
        action = fault_spec(args["fault"]).name
    check = _KIND_CHECKS.get(action)
    if check is None:
        return
    channel = args.get("channel")
    check(mtype, module, channel)
    if channel is not None:
        check_channel(mtype, channel)


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
        # The fault's target (a module fault without a module, ...): check_command, first.
        if module is None:
            return
        if module not in layout:
            raise CommandError(module_listing(self.device_id, module, layout))
        if layout[module] is not UNKNOWN_MODULE:
            check_kind(layout[module], module, action, args)
        if action == "replace_module":
            try:
                layout[module] = module_type(args["type"])
            except KeyError as exc:
                raise CommandError(exc.args[0]) from None

    def changes_modules(self, action: str, args: Mapping[str, Any],
                        module: int | None) -> tuple[int, ...]:
        return (module,) if action == "replace_module" and module is not None else ()

    def target_actions(self, module: int | None = None) -> list[str]:
        """As the device's, a module's narrowed by its type (:func:`fits`)."""
        names: list[str] = super().target_actions(module)  # type: ignore[misc]
        if module is None:
            return names
        mtype = next((m.mtype for m in self.modules if m.number == module), None)
        return [] if mtype is None else [n for n in names if fits(mtype, module, n)]
