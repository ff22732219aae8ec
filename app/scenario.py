"""Scenarios: TOML files of steps at simulated times, checked before they run.

A step is one of
- ``caption = "text"`` — narration shown to the audience;
- ``checkpoint = "name"`` — a named instant (screenshots are taken there);
- ``focus = "trscat"`` or ``"fastcat:2"`` — the dashboard's camera moves to that device; the
  device must be in the rig, and the module one it holds at that step;
- ``target = "fastcat/2"`` + ``action = "unplug"`` + the action's arguments as further keys.

``[[on]]`` tables react to the EtherCAT master's events (its ECAT_Notify hook, seed 003):
``event = "resync"`` (or ``slave_state``, ``comm_error``, ``coe_emergency``,
``network_recovery``, ``dc_state`` - the DC unit's state changes, optional ``to =
"NOT_SYNCHRONIZED"``), optional ``slave = "trscat"`` (only events about that slave; a
``network_recovery`` is about each of its ``positions``), optional ``once = true``, and a
command (``target``, ``action``, arguments) applied at the end of the master's step in which
the event happened.

Each step has ``at = <seconds>`` (absolute simulated time) or ``after = <seconds>`` (relative to
the previous step); ``expect_error = true`` marks a command that must be refused (e.g. writing a
read-only object, for training). See docs/scenarios.md.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.rig import Rig
from app.rig_config import DEVICE_KEYS, RigConfigError, not_toml, not_utf8, one_line
from app.targets import parse_target
from devices.device import UNKNOWN_MODULE, CommandError, UnknownArgument
from devices.events import Caption, Checkpoint, Event, Focus, LogLine, ValueRead
from devices.master.dc import DcState
from devices.master.master import DC_MACHINE
from devices.names import closest_slip, did_you_mean
from devices.od import SdoAbort

US = 1_000_000
# The example library: ``scenario list`` and the dashboard's scenario picker show it.
EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "static" / "scenarios"
_STEP_KEYS = {"at", "after", "target", "action", "caption", "checkpoint", "expect_error"}
# The keys a step may have, in the order a message lists them (a command step's other keys are
# its action's arguments, checked against the rig's device by check_against).
_STEP_KEYS_SHOWN = ("at", "after", "caption", "checkpoint", "focus", "target", "action",
                    "expect_error")
_REACTION_KEYS_SHOWN = ("event", "slave", "to", "once", "target", "action")
_TABLES = ("scenario", "step", "on")
_HEAD_KEYS = ("name", "label", "description", "rig", "duration_s")


class ScenarioError(ValueError):
    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))  # a key may hold a line break: one line


def step_label(number: int) -> str:
    """``step[0]`` for the file's first [[step]]: messages count from 0, as the rig files'
    (``fastcat[0]``) and ``on[0]`` do, so one number finds the table in every message."""
    return f"step[{number - 1}]"


def _unknown_key(raw: Mapping[str, Any], known: tuple[str, ...], key: str,
                 fail: Callable[[str, str], ScenarioError],
                 meant: tuple[str, ...] | None = None) -> ScenarioError | None:
    """A table that says what it is by none of its keys: name a key that is not a known one
    (``acton`` for ``action``), as the rig files do: the closest slip of a known key (not an
    argument that sorts before it: ``active``), else the first. ``meant``: only a slip of one
    of these keys is named (None when there is none): the table lacks them, and its other
    keys are arguments."""
    unknown = sorted(set(raw) - set(known))
    name = closest_slip(unknown, known if meant is None else meant)
    if name is None and meant is None and unknown:
        name = unknown[0]
    if name is None:
        return None
    return fail(f"{key}.{name}", f"unknown key (known here: {', '.join(known)})"
                                 f"{did_you_mean(name, known)}")


@dataclass(frozen=True)
class Step:
    number: int  # 1-based, in file order
    t_us: int
    kind: str  # "command", "caption", "checkpoint", "focus"
    target: str = ""
    action: str = ""
    args: dict[str, Any] = field(default_factory=dict)
    text: str = ""
    expect_error: bool = False


REACTION_EVENTS = ("slave_state", "comm_error", "coe_emergency", "resync",
                   "network_recovery", "dc_state")
DC_STATE_NAMES = tuple(s.value for s in DcState)
_REACTION_KEYS = {"event", "slave", "target", "action", "once", "to"}


def reaction_event(event: Event) -> str:
    """The ``[[on]] event`` name of a master event: its kind, ``dc_state`` for the DC
    unit's state changes (a ``state`` event with ``machine: "dc"``)."""
    if event.kind == "state" and getattr(event, "machine", "") == DC_MACHINE:
        return "dc_state"
    return event.kind


@dataclass(frozen=True)
class Reaction:
    """``[[on]]``: a command run when the master raises an event (seed 003 ECAT_Notify)."""

    number: int  # 1-based, in file order
    event: str
    slave: str  # device id of the slave the event must be about; "" = any
    target: str
    action: str
    args: dict[str, Any] = field(default_factory=dict)
    once: bool = False
    to: str = ""  # dc_state: the DC state entered; "" = any


@dataclass(frozen=True)
class Scenario:
    source: str
    name: str
    description: str
    rig: str | None  # rig file path, resolved; None = the default rig
    steps: tuple[Step, ...]
    end_us: int
    reactions: tuple[Reaction, ...] = ()
    label: str = ""  # the picker's short name ([scenario] label); "" = the name

    def __post_init__(self) -> None:
        if not self.label:
            object.__setattr__(self, "label", self.name)


def read_scenario_text(path: str | Path, cannot: str = "cannot read scenario") -> str:
    """The text of a scenario or exercise file; a ScenarioError naming the file when it cannot
    be read (``cannot`` starts the message) or is not UTF-8."""
    source = str(path)
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ScenarioError(f"{source}: {cannot}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{source}: {not_utf8(exc)}") from None


def load_scenario(path: str | Path) -> Scenario:
    source = str(path)
    text = read_scenario_text(path)
    scenario = parse_scenario(text, source, base_dir=Path(path).resolve().parent)
    # A file is a whole scenario: without its [scenario] table (an empty file, a step list
    # saved without its head) or without a step it is a wrong file, which CI must see as
    # exit 2, not as a run that passed. parse_scenario itself also reads fragments (an
    # exercise file once its [exercise] table is cut out, tests).
    if "scenario" not in tomllib.loads(text):
        raise ScenarioError(f"{source}: no [scenario] table (a scenario file starts with "
                            f"[scenario] and name = \"...\")")
    if not scenario.steps:
        raise ScenarioError(f"{source}: no steps (add [[step]] tables: at = ..., then "
                            f"caption, checkpoint, focus or target + action)")
    return scenario


def parse_scenario(text: str, source: str = "<scenario>",
                   base_dir: Path | None = None) -> Scenario:
    def fail(key: str, reason: str) -> ScenarioError:
        return ScenarioError(f"{source}: {key}: {reason}" if key else f"{source}: {reason}")

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise fail("", not_toml(exc, text)) from None
    unknown = sorted(set(data) - set(_TABLES))
    if "exercise" in unknown:  # not a broken scenario: a classroom file (docs/classroom.md)
        raise fail("[exercise]", "an exercise file, played with its hidden fault by the "
                                 "instructor's Play file and start (Classroom folder, python "
                                 "-m app --exercises DIR), not as a scenario")
    if unknown and not set(_TABLES) & set(data) and all(
            key in DEVICE_KEYS and isinstance(data[key], (Mapping, list)) for key in unknown):
        raise fail("", "a rig file, not a scenario (a scenario has [scenario], [[step]] and "
                       "[[on]] tables: docs/scenarios.md); give it with --rig")
    if unknown:
        raise fail(unknown[0], "unknown key (a scenario has [scenario], [[step]] and [[on]] "
                               f"tables){did_you_mean(unknown[0], _TABLES)}")
    head = data.get("scenario", {})
    if not isinstance(head, Mapping):
        raise fail("scenario", "must be a table")
    bad = sorted(set(head) - set(_HEAD_KEYS))
    if bad:
        raise fail(f"scenario.{bad[0]}", f"unknown key (known: {', '.join(_HEAD_KEYS)})"
                                         f"{did_you_mean(bad[0], _HEAD_KEYS)}")
    name = _typed(head, "name", str, Path(source).stem, fail, "scenario.name")
    label = _typed(head, "label", str, name, fail, "scenario.label")
    if not label.strip():
        raise fail("scenario.label", "must not be empty (leave it out: the picker shows the "
                                     "name)")
    description = _typed(head, "description", str, "", fail, "scenario.description")
    rig = _typed(head, "rig", str, None, fail, "scenario.rig")
    if rig is not None and base_dir is not None:
        given = rig
        rig = rig if Path(rig).is_absolute() else str((base_dir / rig).resolve())
        if not Path(rig).is_file():  # else only the rig's path was named, not this file
            raise fail("scenario.rig", f"{given!r}: no such rig file ({rig}; a path relative "
                                       "to the scenario's folder)")
    duration = _typed(head, "duration_s", float, None, fail, "scenario.duration_s")
    raw_steps = data.get("step", [])
    if not isinstance(raw_steps, list):
        raise fail("step", "must be an array of tables: write [[step]]")
    steps = list(_steps(raw_steps, fail))
    last = max((s.t_us for s in steps), default=0)
    end = round(duration * US) if duration is not None else last + US
    if end < last:
        raise fail("scenario.duration_s", f"ends at {end / US} s, before the last step at "
                                          f"{last / US} s")
    ordered = tuple(sorted(steps, key=lambda s: (s.t_us, s.number)))
    raw_on = data.get("on", [])
    if not isinstance(raw_on, list):
        raise fail("on", "must be an array of tables: write [[on]]")
    reactions = tuple(_reaction(i, raw, fail) for i, raw in enumerate(raw_on))
    return Scenario(source, name, description, rig, ordered, end, reactions, label)


MAX_SECONDS = 10 * 24 * 3600.0  # ten simulated days: far beyond any scenario


def _typed(table: Mapping[str, Any], key: str, kind: type, default: Any,
           fail: Callable[[str, str], ScenarioError], path: str) -> Any:
    if key not in table:
        return default
    value = table[key]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or (kind is not bool and isinstance(value, bool)):
        raise fail(path, f"must be {kind.__name__}, got {table[key]!r}")
    if kind is float and not -MAX_SECONDS <= value <= MAX_SECONDS:  # also refuses nan
        raise fail(path, f"{value!r} is not a time within {MAX_SECONDS:g} s")
    return value


def _steps(raw_steps: list[Any], fail: Callable[[str, str], ScenarioError]) -> Iterator[Step]:
    t_us = 0
    for i, raw in enumerate(raw_steps):
        key = f"step[{i}]"
        if not isinstance(raw, Mapping):
            raise fail(key, "must be a table")
        if "at" in raw and "after" in raw:
            raise fail(key, "give 'at' or 'after', not both")
        if "at" in raw:
            at = _typed(raw, "at", float, 0.0, fail, f"{key}.at")
            if at < 0:
                raise fail(f"{key}.at", "must not be negative")
            if i and round(at * US) < t_us:
                # A slip (0.2 for 2.0, a pasted step), not an order to sort: the ``after``
                # steps below it would count from the earlier time, and the run fail far
                # from the typo.
                raise fail(f"{key}.at", f"{at:g} s is before step[{i - 1}] at {t_us / US:g} s "
                                        "(steps are in time order, top to bottom: 'after' "
                                        "counts from the step above)")
            t_us = round(at * US)
        else:
            after = _typed(raw, "after", float, 0.0, fail, f"{key}.after")
            if after < 0:
                raise fail(f"{key}.after", "must not be negative")
            t_us += round(after * US)
        expect_error = _typed(raw, "expect_error", bool, False, fail, f"{key}.expect_error")
        kinds = [k for k in ("caption", "checkpoint", "focus", "action") if k in raw]
        if not kinds:
            typo = _unknown_key(raw, _STEP_KEYS_SHOWN, key, fail)
            if typo is not None:
                raise typo
        if len(kinds) != 1:
            raise fail(key, "needs exactly one of caption, checkpoint, action (or focus)")
        if kinds[0] == "focus":
            extra = sorted(set(raw) - {"at", "after", "focus"})
            if extra:
                raise fail(f"{key}.{extra[0]}", "unknown key for a focus step"
                                                f"{did_you_mean(extra[0], _STEP_KEYS_SHOWN)}")
            focus = _typed(raw, "focus", str, "", fail, f"{key}.focus")
            where = _focus_target(focus, fail, f"{key}.focus")
            yield Step(i + 1, t_us, "focus", target=where, text=where)
            continue
        if kinds[0] in ("caption", "checkpoint"):
            extra = sorted(set(raw) - {"at", "after", kinds[0]})
            if extra:
                raise fail(f"{key}.{extra[0]}", f"unknown key for a {kinds[0]} step"
                                                f"{did_you_mean(extra[0], _STEP_KEYS_SHOWN)}")
            text = _typed(raw, kinds[0], str, "", fail, f"{key}.{kinds[0]}")
            if not text:
                raise fail(f"{key}.{kinds[0]}", "must not be empty")
            yield Step(i + 1, t_us, kinds[0], text=text)
            continue
        target = _typed(raw, "target", str, None, fail, f"{key}.target")
        if target is None:
            # A slip of the key (targt) landed among the action's arguments.
            typo = _unknown_key(raw, _STEP_KEYS_SHOWN, key, fail, meant=("target",))
            if typo is not None:
                raise typo
            raise fail(key, "a command step needs target = \"device\" or \"device/N\"")
        action = _typed(raw, "action", str, "", fail, f"{key}.action")
        args = {k: v for k, v in raw.items() if k not in _STEP_KEYS}
        yield Step(i + 1, t_us, "command", target=target, action=action, args=args,
                   expect_error=expect_error)


def _reaction(i: int, raw: Any, fail: Callable[[str, str], ScenarioError]) -> Reaction:
    key = f"on[{i}]"
    if not isinstance(raw, Mapping):
        raise fail(key, "must be a table")
    event = _typed(raw, "event", str, "", fail, f"{key}.event")
    if event not in REACTION_EVENTS:
        raise fail(f"{key}.event", f"{event!r} is not a master event "
                                   f"({', '.join(REACTION_EVENTS)})"
                                   f"{did_you_mean(event, REACTION_EVENTS)}")
    target = _typed(raw, "target", str, None, fail, f"{key}.target")
    action = _typed(raw, "action", str, None, fail, f"{key}.action")
    if target is None or action is None:
        typo = _unknown_key(raw, _REACTION_KEYS_SHOWN, key, fail)
        if typo is not None:
            raise typo
        raise fail(key, "needs target = \"device\" and action = \"...\"")
    args = {k: v for k, v in raw.items() if k not in _REACTION_KEYS}
    slave = _typed(raw, "slave", str, "", fail, f"{key}.slave")
    to = _typed(raw, "to", str, "", fail, f"{key}.to")
    if event == "dc_state":
        if slave:
            raise fail(f"{key}.slave", "a dc_state event is about the master's distributed "
                                       "clock, not a slave")
        if to and to not in DC_STATE_NAMES:
            raise fail(f"{key}.to", f"{to!r} is not a DC state ({', '.join(DC_STATE_NAMES)})"
                                    f"{did_you_mean(to, DC_STATE_NAMES)}")
    elif "to" in raw:
        raise fail(f"{key}.to", "only for event = \"dc_state\" (the DC state entered)")
    return Reaction(i + 1, event, slave, target, action, args,
                    _typed(raw, "once", bool, False, fail, f"{key}.once"), to)


def _focus_target(text: str, fail: Callable[[str, str], ScenarioError], path: str) -> str:
    """``device`` or ``device:N`` (``device/N`` is accepted, as command targets write it)."""
    try:
        device, module = parse_target(text.replace(":", "/", 1))
    except CommandError as exc:
        raise fail(path, f"{exc} (focus: 'device' or 'device:N')") from None
    return device if module is None else f"{device}:{module}"


def check_against(scenario: Scenario, rig: Rig) -> dict[str, dict[int, Any]]:
    """Refuse a scenario whose commands the rig would not take, before anything runs; the
    modules each device holds after the steps (for a command that comes after them).

    Arguments are checked against the devices' declared actions (types, ranges, choices and
    the models' own tables, Param.parse); a module target against the modules its device holds
    at that step: the rig as built, changed by the earlier steps in time order
    (DeviceModel.module_layout / check_module). A position an ``[[on]]`` command may change
    is left to the run, and so is what depends on the state the run reaches (an object's
    access rights in the current state, a drive's power).
    """
    layouts = _module_layouts(scenario, rig)
    for step in scenario.steps:
        if step.kind not in ("command", "focus"):
            continue
        try:
            if step.kind == "focus":
                _check_focus(step.target, rig, layouts)
                continue
            args = rig.check(step.target, step.action, step.args)
            device_id, module = parse_target(step.target)
            device = rig.device(device_id)
            layout = layouts.setdefault(device_id, device.module_layout())
            if step.expect_error:
                # refused as the author expects, or not: the run tells; what it may change
                # on the rail is unknown from here on
                _unknown_after(layout, device, step.action, args, module)
            else:
                device.check_module(step.action, args, module, layout)
        except CommandError as exc:
            if isinstance(exc, UnknownArgument):  # maybe a slip of a step key (expect_error)
                exc = exc.among(_STEP_KEYS_SHOWN)
            raise ScenarioError(f"{scenario.source}: {step_label(step.number)} (at "
                                f"{step.t_us / US:g} s): {exc}") from None
    if scenario.reactions and "master" not in rig.devices:
        raise ScenarioError(f"{scenario.source}: [[on]] needs an EtherCAT master in the rig")
    for reaction in scenario.reactions:
        try:
            rig.check(reaction.target, reaction.action, reaction.args)
            if reaction.slave:
                rig.device(reaction.slave)
        except CommandError as exc:
            if isinstance(exc, UnknownArgument):  # maybe a slip of an [[on]] key (slave)
                exc = exc.among(_REACTION_KEYS_SHOWN)
            raise ScenarioError(f"{scenario.source}: on[{reaction.number - 1}]: {exc}") \
                from None
        if reaction.slave:
            _check_line_slave(scenario, reaction, rig)
    return layouts


def _check_focus(target: str, rig: Rig, layouts: dict[str, dict[int, Any]]) -> None:
    """A focus names the device, or one of the modules it holds at that step (the rig as
    built, changed by the earlier steps): ``fastcat:30`` or ``drive:1`` ran as a focus on the
    device, a typo nobody was told of."""
    device_id, _, number = target.partition(":")
    device = rig.device(device_id)
    if not number:
        return
    layout = layouts.setdefault(device_id, device.module_layout())
    module = int(number)
    if module in layout:  # also a position an [[on]] command may change (UNKNOWN_MODULE)
        return
    if not layout and not device.module_layout():
        raise CommandError(f"focus: {device_id} has no modules: focus = \"{device_id}\"")
    held = ", ".join(f"{n}={getattr(kind, 'name', kind)}" for n, kind in sorted(layout.items())
                     if n > 0)  # a TRS-CAT's 0 is its integrated I/O, no focus target
    raise CommandError(f"focus: {device_id} has no module {module} (modules: {held}); "
                       f"focus = \"{device_id}\" is the device")


def _check_line_slave(scenario: Scenario, reaction: Reaction, rig: Rig) -> None:
    """``slave`` must be on the master's line, or the reaction never fires (a drive is there
    as its CoE side, ``<drive>-ecat``, the id the rig file's line and the events' ``slave``
    give it; its own id, which its events carry, is not)."""
    line = [str(link.slave.device_id) for link in rig.devices["master"].links]
    if reaction.slave in line:
        return
    side = f"{reaction.slave}-ecat"
    hint = (f"; the EtherCAT side of {reaction.slave} is {side!r}" if side in line else "")
    raise ScenarioError(f"{scenario.source}: on[{reaction.number - 1}].slave: "
                        f"{reaction.slave!r} is not a slave of the EtherCAT line (its slaves: "
                        f"{', '.join(line)}{hint})")


def _module_layouts(scenario: Scenario, rig: Rig) -> dict[str, dict[int, Any]]:
    """Each device's modules as built, with the positions an ``[[on]]`` command may change
    marked unknown: it runs whenever its event comes, before or after any step."""
    layouts: dict[str, dict[int, Any]] = {}
    for reaction in scenario.reactions:
        try:
            args = rig.check(reaction.target, reaction.action, reaction.args)
            device_id, module = parse_target(reaction.target)
        except CommandError:
            continue  # check_against names it
        device = rig.device(device_id)
        layout = layouts.setdefault(device_id, device.module_layout())
        _unknown_after(layout, device, reaction.action, args, module)
    return layouts


def _unknown_after(layout: dict[int, Any], device: Any, action: str, args: dict[str, Any],
                   module: int | None) -> None:
    """Mark the positions this command may change as holding anything (UNKNOWN_MODULE)."""
    for position in device.changes_modules(action, args, module):
        layout[position] = UNKNOWN_MODULE


def install_reactions(scenario: Scenario, rig: Rig, failures: list[str]) -> None:
    """Register the scenario's ``[[on]]`` tables on the master's ECAT_Notify hook."""
    if not scenario.reactions:
        return
    master: Any = rig.devices["master"]
    fired: set[int] = set()

    def about(event: Event) -> tuple[str, ...]:
        """The device ids of the slaves ``event`` is about: its ``position``, or every one
        of a network_recovery's ``positions``."""
        positions = getattr(event, "positions", None)
        if positions is None:
            positions = (getattr(event, "position", -1),)
        return tuple(str(master.links[p].slave.device_id) for p in positions
                     if p is not None and 0 <= p < len(master.links))

    def react(event: Event) -> None:
        name = reaction_event(event)
        for r in scenario.reactions:
            if r.event != name or (r.once and r.number in fired):
                continue
            if r.slave and r.slave not in about(event):
                continue
            if r.to and getattr(event, "to_state", "") != r.to:
                continue
            fired.add(r.number)
            now = rig.clock.now_us
            rig.pending.append(LogLine(now, "scenario", text=f"on[{r.number - 1}] "
                                       f"{name}: {r.target} {r.action}"))
            try:
                rig.apply(r.target, r.action, r.args)
            except (CommandError, SdoAbort) as exc:
                failures.append(f"on[{r.number - 1}] (at {now / US:g} s): {exc}")
                rig.pending.append(LogLine(now, "scenario", text=f"on[{r.number - 1}] "
                                           f"failed: {exc}"))

    master.on_notify(react)


@dataclass
class ScenarioRun:
    events: list[Event]
    failures: list[str]


Tick = Callable[[Rig, list[Event]], None]


def run_scenario(scenario: Scenario, rig: Rig,
                 on_step: Callable[[Step, Rig], None] | None = None,
                 on_tick: Tick | None = None) -> ScenarioRun:
    """Run headless, as fast as possible.

    ``on_step`` sees each scenario step after it was applied; ``on_tick`` sees the rig after
    every simulation step (and after each applied step) with the events it produced.
    """
    check_against(scenario, rig)
    rig.scenario = scenario.name
    failures: list[str] = []
    install_reactions(scenario, rig, failures)
    # What the rig emitted when built (devices its file powers) comes first, at t = 0: left
    # to the first step it came after that step's events at 1 ms of the devices before, and
    # a served runtime (the player, --screenshots) takes it at its first queued work anyway.
    events = rig.take_events()
    if on_tick is not None and events:
        on_tick(rig, events)
    for step in scenario.steps:
        events.extend(_run_until(rig, step.t_us, on_tick))
        applied = apply_step(step, rig, failures)
        if on_tick is not None:
            on_tick(rig, applied)
        events.extend(applied)
        if on_step is not None:
            on_step(step, rig)
    events.extend(_run_until(rig, scenario.end_us, on_tick))
    return ScenarioRun(events, failures)


def _run_until(rig: Rig, t_us: int, on_tick: Tick | None) -> list[Event]:
    if on_tick is None:
        return rig.run_until(t_us)
    events: list[Event] = []
    while rig.clock.now_us + rig.clock.step_us <= t_us:
        step_events = rig.step()
        on_tick(rig, step_events)
        events.extend(step_events)
    return events


def apply_step(step: Step, rig: Rig, failures: list[str]) -> list[Event]:
    now = rig.clock.now_us
    if step.kind == "caption":
        return [Caption(now, "scenario", text=step.text)]
    if step.kind == "checkpoint":
        return [Checkpoint(now, "scenario", name=step.text)]
    if step.kind == "focus":
        return [Focus(now, "scenario", target=step.target)]
    out: list[Event] = []
    try:
        result = rig.apply(step.target, step.action, step.args)
    except (CommandError, SdoAbort) as exc:
        out.extend(rig.take_events())
        if step.expect_error:
            out.append(LogLine(now, "scenario", text=f"{step_label(step.number)}: refused as "
                                                      f"expected: {exc}"))
        else:
            failures.append(f"{step_label(step.number)} (at {now / US:g} s): {exc}")
            out.append(LogLine(now, "scenario", text=f"{step_label(step.number)} failed: "
                                                      f"{exc}"))
        return out
    out.extend(rig.take_events())
    if step.expect_error:
        failures.append(f"{step_label(step.number)} (at {now / US:g} s): expected an error, "
                        f"the command was accepted")
    if step.action.startswith("read"):
        out.append(ValueRead(now, step.target, address=_address(step.args), value=result))
    return out


def _address(args: Mapping[str, Any]) -> str:
    """``0x5400:0`` for an object, the register or parameter as written otherwise."""
    parts = []
    for key in ("index", "sub", "register", "parameter", "address"):
        if key in args:
            value = args[key]
            parts.append(f"0x{value:04X}" if key == "index" and isinstance(value, int)
                         else str(value))
    return ":".join(parts)


def scenario_rig_path(scenario: Scenario, override: str | None) -> str | None:
    return override if override is not None else scenario.rig


__all__ = ["RigConfigError", "Scenario", "ScenarioError", "Step", "load_scenario",
           "parse_scenario", "run_scenario"]
