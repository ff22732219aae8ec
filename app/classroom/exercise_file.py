"""Exercise files: a scenario that sets the stage, plus an ``[exercise]`` table.

::

    [scenario]
    name = "Lost node on a running line"
    [[step]]
    at = 0.0
    target = "fastcat"
    action = "power"
    on = true

    [exercise]
    fault = "fastcat:inject:coupler:0x04"   # a hidden fault id (app/classroom/faults.py)
    module = 3                              # module codes (§7.6): the module number, required
    # channel = 3                           # an output short (cpx short_circuit): its channel
    at_s = 5.0                              # inject at this simulated time (default: the end)

The ``[exercise]`` table is cut out and the rest is read as a scenario
(:func:`app.scenario.parse_scenario`, which knows only ``[scenario]`` and ``[[step]]``). The
cut works on the text: from the ``[exercise]`` header line to the next table header.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from app.classroom.faults import Catalog, HiddenFault
from app.rig import Rig
from app.rig_config import not_toml
from app.scenario import (
    Scenario,
    ScenarioError,
    check_against,
    parse_scenario,
    read_scenario_text,
)
from app.targets import parse_target
from devices.device import CommandError
from devices.names import close_names, did_you_mean

_HEADER = re.compile(r"^\s*\[\s*exercise\s*\]\s*(#.*)?$")
_ANY_HEADER = re.compile(r"^\s*\[")
_KEYS = {"fault", "module", "channel", "at_s"}


@dataclass(frozen=True)
class ExerciseSpec:
    fault: str
    module: int | None = None
    at_s: float | None = None  # None: when the scenario ends
    channel: int | None = None  # the module's channel (a CPX-E-EC output short, KZA)


def split_exercise(text: str, source: str = "<exercise>") -> tuple[str, Mapping[str, Any] | None]:
    """(the text without its ``[exercise]`` table, that table or None)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{source}: {not_toml(exc, text)}") from None
    table = data.get("exercise")
    if table is None:
        return text, None
    if not isinstance(table, Mapping):
        raise ScenarioError(f"{source}: exercise: must be a table ([exercise])")
    kept: list[str] = []
    inside = False
    for line in text.splitlines(keepends=True):
        if _HEADER.match(line):
            inside = True
            continue
        if inside and _ANY_HEADER.match(line):
            inside = False
        if not inside:
            kept.append(line)
    rest = "".join(kept)
    left = tomllib.loads(rest)
    if "exercise" in left or left != {k: v for k, v in data.items() if k != "exercise"}:
        raise ScenarioError(f"{source}: exercise: write it as one [exercise] table")
    return rest, table


def parse_spec(table: Mapping[str, Any], source: str = "<exercise>") -> ExerciseSpec:
    def fail(key: str, why: str) -> ScenarioError:
        return ScenarioError(f"{source}: exercise.{key}: {why}")

    unknown = sorted(set(table) - _KEYS)
    if unknown:
        raise fail(unknown[0], f"unknown key (known: {', '.join(sorted(_KEYS))})"
                               f"{did_you_mean(unknown[0], _KEYS)}")
    fault = table.get("fault")
    if not isinstance(fault, str) or not fault:
        raise fail("fault", "a hidden fault id, e.g. \"fastcat:inject:coupler:0x04\"")
    module = table.get("module")
    if module is not None and (isinstance(module, bool) or not isinstance(module, int)
                               or module < 1):
        raise fail("module", "a module number from 1")
    channel = table.get("channel")
    if channel is not None:
        if isinstance(channel, bool) or not isinstance(channel, int) or channel < 0:
            raise fail("channel", "a channel number from 0, as the device counts them")
        if module is None:
            raise fail("channel", "give its module too: module = N")
    at_s = table.get("at_s")
    if at_s is not None and (isinstance(at_s, bool) or not isinstance(at_s, (int, float))
                             or at_s < 0):
        raise fail("at_s", "simulated seconds, 0 or more")
    return ExerciseSpec(fault, module, None if at_s is None else float(at_s), channel)


def load_exercise(path: str | Path) -> tuple[Scenario, ExerciseSpec]:
    """The scenario and the exercise of an exercise file; ScenarioError when it has none."""
    source = str(path)
    text = read_scenario_text(path, "cannot read")
    rest, table = split_exercise(text, source)
    if table is None:
        raise ScenarioError(f"{source}: no [exercise] table")
    spec = parse_spec(table, source)
    scenario = parse_scenario(rest, source, base_dir=Path(path).resolve().parent)
    return scenario, spec


def start_us(scenario: Scenario, spec: ExerciseSpec) -> int:
    """When the hidden fault goes in, in simulated microseconds."""
    return scenario.end_us if spec.at_s is None else round(spec.at_s * 1_000_000)


def check_exercise(scenario: Scenario, spec: ExerciseSpec, rig: Rig,
                   faults: Catalog) -> HiddenFault:
    """The hidden fault ``spec`` names, as it will be injected on ``rig``; ScenarioError (one
    line, the file named once) when the rig would refuse a step (:func:`check_against`), has
    no such fault or its device would refuse the injection. The injection is checked by the
    device's own check_command (a FastCAT module code, §7.6, needs a ``fastcat/N`` target:
    ``module = N`` here), as a scenario's commands are before a run."""
    # its errors name scenario.source, the file, already; the modules after the file's steps
    layouts = check_against(scenario, rig)
    source = scenario.source
    try:
        base = faults.fault(spec.fault)
    except (KeyError, ValueError) as exc:
        raise ScenarioError(f"{source}: [exercise] fault: {exc.args[0] if exc.args else exc}"
                            f" on this rig ({known_ids(spec.fault, faults)}; "
                            "docs/classroom.md)") from None
    if spec.channel is not None and not base.channel:
        raise ScenarioError(f"{source}: exercise.channel: {spec.fault!r} takes no channel "
                            "(only a channel fault does: cpx short_circuit on an output)")
    if spec.module is not None and not base.module:
        # at() would drop it: the rig would show the fault with no module named
        raise ScenarioError(f"{source}: exercise.module: {spec.fault!r} is put on no module "
                            "(only a module fault is: a FastCAT §7.6 module code, a slave's "
                            "module or slot fault); remove module = N")
    fault = base.at(spec.module, spec.channel)
    # where the fault goes, so that a refusal of the module's type names the key to change
    where = " ".join(f"{key} {value}" for key, value in
                     (("module", spec.module), ("channel", spec.channel)) if value is not None)
    for command in fault.inject:
        try:
            args = rig.check(command.target, command.action, dict(command.args))
            device_id, module = parse_target(command.target)
            device = rig.device(device_id)
            # a module the device does not hold then: refused here, not at the injection
            device.check_module(command.action, args, module,
                                layouts.setdefault(device_id, device.module_layout()))
        except CommandError as exc:
            hint = "; give its module: module = N" if fault.module and spec.module is None \
                else "; give it: channel = N" if fault.channel and spec.channel is None \
                and spec.module is not None else ""
            on = f" on {where}" if where else ""
            raise ScenarioError(f"{source}: [exercise] fault {spec.fault!r}{on}: {exc}{hint}") \
                from None
    return fault


def known_ids(fault_id: str, faults: Catalog) -> str:
    """What to write instead of an unknown ``fault_id``: the hidden faults of the device it
    names, ids that share a prefix folded (``fastcat:inject:coupler:{0x01,0x02}``), or the
    closest ids of the rig when it names no device that has any."""
    device = fault_id.partition("@")[0].split(":", 1)[0]
    ids = [f.id for f in faults.faults if f.device == device]
    if not ids:
        everything = [f.id for f in faults.faults]
        closest = close_names(fault_id, everything, n=5, cutoff=0.5)
        if closest:
            return f"closest: {', '.join(closest)}"
        return f"devices with hidden faults: {', '.join(sorted({f.device for f in faults.faults}))}"
    groups: dict[str, list[str]] = {}  # id head -> code tails; a physical fault: itself, []
    for one in ids:
        head, _, tail = one.rpartition(":")
        if head == device:
            groups[one] = []
        else:
            groups.setdefault(head, []).append(tail)
    shown = [head if not tails else f"{head}:{tails[0]}" if len(tails) == 1
             else f"{head}:{{{','.join(tails)}}}" for head, tails in groups.items()]
    return f"{device}'s hidden faults: {', '.join(shown)}"
