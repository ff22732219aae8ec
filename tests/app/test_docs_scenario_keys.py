"""docs/scenarios.md against the code that reads scenarios: every `scenario run` flag, every
key of a [scenario], [[step]] and [[on]] table, every `[[on]]` event, every example file and
the FastCAT's own actions are in the doc, and each action or argument a device paragraph names
is one the device declares. A flag, key or action added or renamed fails here, not in front of
a reader."""

from __future__ import annotations

import argparse
import re
import tomllib
from pathlib import Path

from app import scenario
from app.cli import _scenario_parser
from app.rig_config import DEFAULT_RIG, load_rig_spec
from devices.canopen.node import CanOpenNode
from devices.coe.drive_slave import DriveEcatSlave
from devices.device import DeviceModel
from devices.fastcat.coupler import FastCat
from devices.servo.drive import ServoDrive

ROOT = Path(__file__).resolve().parents[2]
TEXT = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
TOML_BLOCKS = [tomllib.loads(b) for b in re.findall(r"^```toml\n(.*?)^```", TEXT, re.M | re.S)]
TICKED = re.compile(r"`([a-z][a-z0-9_]*)`")


def paragraph(start: str, text: str = TEXT) -> str:
    return start + text.split(start, 1)[1].split("\n\n", 1)[0]


def run_options() -> set[str]:
    sub = next(a for a in _scenario_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    return {o for a in sub.choices["run"]._actions for o in a.option_strings
            if o.startswith("--") and o != "--help"}


def test_every_scenario_run_flag_is_in_the_doc() -> None:
    assert sorted(o for o in run_options() if f"`{o}" not in TEXT and f"{o} " not in TEXT) == []


def test_the_example_scenario_table_has_every_key_of_the_scenario_table() -> None:
    heads = [b["scenario"] for b in TOML_BLOCKS if "scenario" in b]
    assert len(heads) == 1 and set(heads[0]) == set(scenario._HEAD_KEYS)


def test_the_step_keys_the_doc_lists_are_the_parsers() -> None:
    listed = paragraph("A key that is none of ").split(" in a step", 1)[0]
    assert tuple(TICKED.findall(listed)) == scenario._STEP_KEYS_SHOWN


def test_the_on_tables_show_every_key_and_event() -> None:
    shown = {key for b in TOML_BLOCKS for table in b.get("on", []) for key in table}
    assert set(scenario._REACTION_KEYS_SHOWN) <= shown
    comment = re.search(r'^event = "\w+" +# (.*)$', TEXT, re.M)
    assert comment is not None and comment[1].split(", ") == list(scenario.REACTION_EVENTS)


def test_the_examples_table_names_every_example_file() -> None:
    section = TEXT.split("## Examples (`static/scenarios/`)", 1)[1].split("\n## ", 1)[0]
    rows = set(re.findall(r"^\| `(\w+\.toml)` \|", section, re.M))
    assert rows == {p.name for p in (ROOT / "static" / "scenarios").glob("*.toml")}


def names_of(model: type[DeviceModel]) -> set[str]:
    return set(model.ACTIONS) | {p.name for a in model.ACTIONS.values() for p in a.params}


def unknown_names(text: str, models: list[type[DeviceModel]]) -> list[str]:
    """The snake-case names in backticks that are neither an action or argument of ``models``
    nor a device id of the default rig (``fastcat``, ``drive_ec``: the paragraphs' targets)."""
    spec = load_rig_spec(DEFAULT_RIG)
    ids = {d.id for d in (*spec.fastcats, *spec.servos, *spec.slaves)}
    known = set().union(ids, *(names_of(m) for m in models))
    return [t for t in TICKED.findall(text) if t not in known]


def test_the_fastcat_paragraph_lists_every_action_of_the_coupler_itself() -> None:
    text = paragraph("The FastCAT's actions: ")
    own = [a.name for a in FastCat.ACTIONS.values() if a.module != "required"]
    assert [a for a in own if f"`{a}`" not in text] == []
    assert unknown_names(text, [FastCat]) == []


def test_the_drive_paragraph_names_actions_and_arguments_the_drive_declares() -> None:
    text = paragraph("A servo drive (`target = \"drive\"`) takes ")
    assert unknown_names(text, [ServoDrive, CanOpenNode, DriveEcatSlave]) == []


def test_the_checks_see_a_stale_name() -> None:
    assert unknown_names("`power`, `press_knob` (`seconds`)", [FastCat]) == ["press_knob"]
    assert "--screenshots" in run_options() and "--state-dir" in run_options()


def test_the_doc_gives_the_time_limit_of_the_parser() -> None:
    assert f"{scenario.MAX_SECONDS / 86400:g} simulated days" in TEXT
