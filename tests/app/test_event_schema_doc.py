"""docs/architecture.md "Event schema" says all a CI job needs to parse the event lines: every
kind with every field and the device families that emit it, every ``machine`` value with its
families, and the shape of an alarm's ``code`` per family. The example scenarios' events
(all of them: no smaller set emits every kind, field and machine; ~5 s) must stay inside it."""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import load_scenario, run_scenario
from app.targets import parse_target
from devices import events

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "architecture.md"
SCENARIOS = sorted((ROOT / "static" / "scenarios").glob("*.toml"))
TICKED = re.compile(r"`([^`]*)`")


def section(text: str, heading: str) -> str:
    """From ``heading`` to the next heading of its level or above."""
    start = text.index(heading)
    level = len(heading) - len(heading.lstrip("#"))
    end = re.compile(rf"\n#{{1,{level}}} ").search(text, start + len(heading))
    return text[start:] if end is None else text[start:end.start()]


def table(heading: str) -> list[list[list[str]]]:
    """The rows of the table under ``heading`` in the Event schema section: each cell as the
    list of its `ticked` words."""
    schema = section(DOC.read_text(encoding="utf-8"), "## Event schema")
    rows = []
    for line in section(schema, heading).splitlines():
        cells = line.strip().strip("|").split("|")
        if not line.startswith("|") or set(cells[0].strip()) <= set("-: "):
            continue
        rows.append([TICKED.findall(cell) for cell in cells])
    return rows[1:]  # the header


def kinds_doc() -> dict[str, tuple[set[str], set[str]]]:
    """``event`` -> (fields, families), from "### Kinds"."""
    return {row[0][0]: (set(row[1]), set(row[2])) for row in table("### Kinds") if row[0]}


def machines_doc() -> dict[str, set[str]]:
    """``machine`` (``""``: the field absent) -> families, from "### `machine` values"."""
    out: dict[str, set[str]] = {}
    for row in table("### `machine` values"):
        out.setdefault((row[0] or [""])[0], set()).update(row[1])
    return out


def alarm_codes_doc() -> dict[str, str]:
    """family -> an example alarm ``code``, from "### Alarm codes"."""
    return {row[0][0]: row[1][0].strip('"') for row in table("### Alarm codes")}


def shape(code: str) -> str:
    """``"34"`` -> decimal, ``"0x04"`` -> hex2, ``"0xA000"`` -> hex4."""
    if re.fullmatch(r"[0-9]+", code):
        return "decimal"
    assert re.fullmatch(r"0x[0-9A-F]+", code), code
    return f"hex{len(code) - 2}"


@cache
def example_records() -> tuple[tuple[dict, str], ...]:
    """Every event line of the example scenarios, with the family (rig ``kind``) of its
    device: a drive's CANopen and CoE sides emit under the drive's id, so ``servo``."""
    out = []
    for path in SCENARIOS:
        scenario = load_scenario(path)
        rig = build_rig(load_rig_spec(scenario.rig or DEFAULT_RIG))
        families = {i: d["kind"] for i, d in rig.describe().items()}
        for event in run_scenario(scenario, rig).events:
            record = event.to_record()
            device = parse_target(record["device"])[0]
            out.append((record, families.get(device, device)))
    return tuple(out)


def test_every_kind_and_field_an_example_emits_is_documented() -> None:
    documented = kinds_doc()
    missing = set()
    for record, family in example_records():
        fields, families = documented.get(record["event"], (set(), set()))
        missing |= {(record["event"], f) for f in record if f not in fields | {"t", "device",
                                                                              "event"}}
        if family not in families:
            missing.add((record["event"], f"from {family}"))
    assert not missing, f"docs/architecture.md Event schema lacks {sorted(missing)}"


def test_every_machine_an_example_emits_is_documented_with_its_families() -> None:
    documented = machines_doc()
    seen = {(r.get("machine", ""), family) for r, family in example_records()
            if r["event"] == "state"}
    missing = sorted((m, f) for m, f in seen if f not in documented.get(m, set()))
    assert not missing, f"docs/architecture.md lacks these machine values/families: {missing}"
    assert documented.keys() <= {m for m, _ in seen}, "a documented machine no example emits"


def test_alarm_codes_have_the_documented_shape_per_family() -> None:
    documented = alarm_codes_doc()
    wrong = {(family, r["code"]) for r, family in example_records()
             if r["event"] == "alarm"
             and (family not in documented or shape(r["code"]) != shape(documented[family]))}
    assert not wrong, f"alarm codes not as docs/architecture.md says: {sorted(wrong)}"


def every_event_class() -> list[type[events.Event]]:
    found, todo = [], [events.Event]
    while todo:
        cls = todo.pop()
        todo.extend(cls.__subclasses__())
        if cls.kind != "event":
            found.append(cls)
    return found


@pytest.mark.parametrize("cls", every_event_class(), ids=lambda c: c.kind)
def test_every_event_class_is_documented(cls: type[events.Event]) -> None:
    """Kinds no example emits yet are documented too (their default fields at least)."""
    fields, _ = kinds_doc().get(cls.kind, (set(), set()))
    record = cls(0, "x").to_record()
    assert cls.kind in kinds_doc()
    assert set(record) - {"t", "device", "event"} <= fields
