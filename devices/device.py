"""What every device model is: clock-driven, commanded by named actions, observed by snapshot.

A model never reads the wall clock, sleeps, opens sockets or starts threads. The runtime calls
``step(now_us)`` with the simulated time (integer microseconds since the rig started), applies
commands between steps with :meth:`DeviceModel.apply`, reads :meth:`snapshot` for views and
drains the events the model emitted.

Actions are declared as data (:class:`Action`, :class:`Param`) so that the scenario loader can
check a scenario before running it, and the UI can list what a device accepts, without either
knowing device logic. ``apply("press_cnf", {...})`` calls the model's ``cmd_press_cnf``.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

from devices.events import Event, EventQueue
from devices.names import did_you_mean
from devices.od import IEC_NAMES, TypeNames


class CommandError(ValueError):
    """A command the device cannot take: unknown action, bad argument, value out of range."""


class UnknownArgument(CommandError):
    """Arguments an action does not take. A scenario's table holds keys of its own beside
    them (a step's ``expect_error``, an ``[[on]]``'s ``slave``), so a slip of one of those
    lands here: :meth:`among` offers them too."""

    def __init__(self, action: str, names: Sequence[str], takes: Sequence[str],
                 also: Sequence[str] = ()) -> None:
        self.action, self.names, self.takes = action, tuple(names), tuple(takes)
        hints = (did_you_mean(name, (*takes, *also)) for name in self.names)
        super().__init__(f"action '{action}' takes no argument {', '.join(self.names)} "
                         f"(it takes: {', '.join(self.takes) or 'nothing'})"
                         f"{next((h for h in hints if h), '')}")

    def among(self, keys: Sequence[str]) -> UnknownArgument:
        """The same refusal, its hint also looking at the table's own ``keys``."""
        return UnknownArgument(self.action, self.names, self.takes, keys)


# A module position of a scenario check's layout whose module no check before the run can
# know (an [[on]] command may plug or unplug there at any instant): anything may be there.
UNKNOWN_MODULE: Any = object()


@dataclass(frozen=True)
class Param:
    name: str
    type: type  # int, float, bool or str
    required: bool = True
    default: Any = None
    low: float | None = None
    high: float | None = None
    choices: tuple[Any, ...] | None = None
    doc: str = ""
    # The model's own reading of a value that no choices list covers (a fault symbol or
    # ``coupler:0x04``, a parameter name or address): called with the typed value, raises
    # CommandError for a value the model refuses whatever its state, so a scenario file is
    # refused before it runs and not at the step (app.scenario.check_against).
    parse: Callable[[Any], object] | None = None
    # Where the device's snapshot holds the value this parameter has now, as a dotted key
    # ("switches.dil1"): a form starts from it rather than from ``default`` (a switch that is
    # ON shows ticked; the dashboard reads it, the model never does).
    current: str = ""

    def check(self, value: Any) -> Any:
        if self.type is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if self.type is int and isinstance(value, str):
            value = _parse_int(self.name, value)
        if not isinstance(value, self.type) or (self.type is int and isinstance(value, bool)):
            raise CommandError(f"'{self.name}' must be {self.type.__name__}, got {value!r}")
        if self.low is not None and value < self.low:
            raise CommandError(f"'{self.name}' = {value!r} is below {self.low}")
        if self.high is not None and value > self.high:
            raise CommandError(f"'{self.name}' = {value!r} is above {self.high}")
        if self.choices is not None and value not in self.choices:
            allowed = ", ".join(repr(c) for c in self.choices)
            hint = did_you_mean(value, map(str, self.choices)) if isinstance(value, str) else ""
            raise CommandError(f"'{self.name}' = {value!r} is not one of {allowed}{hint}")
        if self.parse is not None:
            self.parse(value)
        return value


def _parse_int(name: str, text: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise CommandError(f"'{name}' must be an integer, got {text!r}") from None


def bool_value_as_int(action: str, args: Mapping[str, Any]) -> Mapping[str, Any]:
    """A write_object's TOML ``value = true`` / ``false`` as 1 / 0, for a BOOL object: what the
    FastCAT, the TRS-CAT and the CPX-E-EC take before their action table checks the value."""
    if action == "write_object" and isinstance(args.get("value"), bool):
        return {**args, "value": int(args["value"])}
    return args


@dataclass(frozen=True)
class Action:
    name: str
    doc: str
    params: tuple[Param, ...] = ()
    module: str = "none"  # "none", "optional" or "required": may the target name a module?

    def check_args(self, args: Mapping[str, Any]) -> dict[str, Any]:
        known = {p.name: p for p in self.params}
        unknown = sorted(set(args) - set(known))
        if unknown:
            raise UnknownArgument(self.name, unknown, tuple(known))
        out: dict[str, Any] = {}
        for p in self.params:
            if p.name in args:
                out[p.name] = p.check(args[p.name])
            elif p.required:
                raise CommandError(f"action '{self.name}' needs '{p.name}'")
            else:
                out[p.name] = p.default
        return out


@dataclass
class DeviceModel:
    """Base of the device models: identity, simulated time, seeded randomness, event queue."""

    device_id: str
    rng: random.Random = field(default_factory=lambda: random.Random(0))
    now_us: int = 0
    events: EventQueue = field(default_factory=EventQueue)

    ACTIONS: ClassVar[Mapping[str, Action]] = {}
    KIND: ClassVar[str] = "device"
    # True: quiet steps leave this model's snapshot as it was (it shows no counter they move),
    # so a snapshot taken before them still stands (app.rig.Rig.snapshot's ``since``).
    QUIET_SNAPSHOT: ClassVar[bool] = False
    # The data types of the model's ``od`` in its manual's words (the Objects tab): seed 000's
    # IEC names unless the manual prints others (the CPX-E-EC's U8 / BYTE[23], seed 002).
    TYPE_NAMES: ClassVar[TypeNames] = IEC_NAMES

    def step(self, now_us: int) -> None:
        """Advance to simulated time ``now_us`` (never backwards)."""
        if now_us < self.now_us:
            raise ValueError(f"{self.device_id}: time went backwards ({now_us} < {self.now_us})")
        self.now_us = now_us

    # ---- quiet spans (docs/performance.md "Quiet spans") --------------------------------------
    def quiet_until(self, step_us: int) -> int:
        """How far this model's coming steps are *quiet*: the latest time T (``now_us`` plus a
        whole number of steps; ``now_us`` itself for none) such that stepping it at each of
        ``now_us + step_us`` .. T, with no command in between, would emit no event and
        change nothing (its rng's state included) that :meth:`skip_to` does not set exactly
        as those steps would. No side effect.

        For an EtherCAT slave the promise holds whether or not the master's frames arrive in
        the span (the master reports its own frames: :meth:`frames_quiet`). The default: no
        quiet step, the rig steps this model one step at a time.
        """
        return self.now_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        """Leave the model as its quiet steps up to ``t_us``, ``step_us`` apart, would (``t_us``
        no later than :meth:`quiet_until` gave, asked just before with no command since)."""
        if t_us != self.now_us:
            raise NotImplementedError(f"{self.device_id}: no quiet steps to skip")

    def snapshot(self) -> dict[str, Any]:
        raise NotImplementedError  # abstract: every model reports its own state

    def emit(self, event: Event) -> None:
        self.events.put(event)

    def drain_events(self) -> list[Event]:
        return self.events.drain()

    def check_command(self, action: str, args: Mapping[str, Any],
                      module: int | None = None) -> dict[str, Any]:
        spec = self.ACTIONS.get(action)
        if spec is None:
            raise CommandError(f"{self.KIND} '{self.device_id}' has no action '{action}' "
                               f"(it has: {', '.join(sorted(self.ACTIONS))})"
                               f"{did_you_mean(action, self.ACTIONS)}")
        if module is not None and spec.module == "none":
            raise CommandError(f"action '{action}' takes the device, not a module: "
                               f"write '{self.device_id}'")
        if module is None and spec.module == "required":
            raise CommandError(f"action '{action}' needs a module: write "
                               f"'{self.device_id}/N'")
        return spec.check_args(args)

    def target_actions(self, module: int | None = None) -> list[str]:
        """The actions target ``device`` (``module`` None) or ``device/N`` takes, by the action
        table's ``module``; a model whose modules have types narrows a module's list by what
        its type takes (as check_command and the handlers would refuse the rest)."""
        wanted = ("none", "optional") if module is None else ("required", "optional")
        return [name for name, spec in self.ACTIONS.items() if spec.module in wanted]

    def part_of(self) -> str:
        """What this model is a side of, for a list of targets (``the CANopen node of
        drive``); empty for a device of its own."""
        return ""

    # ---- what a scenario check may know of module targets (app.scenario.check_against) ----
    def module_layout(self) -> dict[int, Any]:
        """The modules as built, by the N of ``device/N``: each one's kind, as this model's
        :meth:`check_module` reads it. Empty for a device without module targets."""
        return {}

    def check_module(self, action: str, args: Mapping[str, Any], module: int | None,
                     layout: dict[int, Any]) -> None:
        """Refuse ``action`` (``args`` as :meth:`check_command` returned them) on
        ``device/module`` when the modules ``layout`` holds at that step (the rig as built,
        changed by earlier commands) cannot take it; then change ``layout`` as the command
        would (a plug, an unplug, a swap). A position set to :data:`UNKNOWN_MODULE` may hold
        anything: nothing is refused there. Default: no module is checked."""

    def changes_modules(self, action: str, args: Mapping[str, Any],
                        module: int | None) -> tuple[int, ...]:
        """The positions this command may put a module on, take one off or change the kind
        of (a plug, an unplug, a swap): an ``[[on]]`` command does so at an instant no check
        before the run knows."""
        return ()

    def apply(self, action: str, args: Mapping[str, Any], module: int | None = None) -> Any:
        """Run a named action now; raises CommandError for anything the device refuses."""
        kwargs = self.check_command(action, args, module)
        handler = getattr(self, f"cmd_{action}")
        if self.ACTIONS[action].module != "none":
            kwargs["module"] = module
        return handler(**kwargs)
