"""docs/rig-file.md "Keys" lists every key the rig file parser takes, and only those, with
defaults and ranges that are the code's: a key added to app/rig_config.py (or to DriveConfig, a
TRS-CAT or CPX-E-EC keyword) without a row fails here, and so does a row the parser refuses, a
default in backticks that is not what a left-out key gives, or a ``LOW .. HIGH`` range whose
ends are refused or whose neighbours outside are taken.

The keys the parser takes are read from its own refusal of an unknown key (``known here:
...``), so nothing here repeats the parser's lists."""

from __future__ import annotations

import dataclasses
import inspect
import re
from pathlib import Path
from typing import Any

import pytest

from app.rig_config import RigConfigError, RigSpec, build_rig, parse_rig_spec
from devices.cpx.device import CpxEEc
from devices.servo.config import DriveConfig
from devices.trscat.device import TrsCat

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "rig-file.md"
# The lines a table needs to load at all, unless the key under test is one of them.
BASE = {"[[fastcat]]": {"modules": "[]"}}
HEADING = re.compile(r"^### `(\[\[?(\w+)\]?\])`$", re.M)
ROW = re.compile(r"^\| `(\w+)` \| ([^|]*) \| ([^|]*) \|$", re.M)
TICKED = re.compile(r"`([^`]+)`")
RANGE = re.compile(r"^(-?[0-9][0-9.xA-Fa-f]*) \.\. (-?[0-9][0-9.xA-Fa-f]*)(?![0-9^])")


def doc_tables() -> dict[str, dict[str, tuple[str, str]]]:
    """``{"[rig]": {"seed": (default cell, values cell), ...}, ...}`` of the Keys section."""
    text = DOC.read_text(encoding="utf-8")
    if "\n## Keys\n" not in text:
        return {}
    text = text.split("\n## Keys\n", 1)[1].split("\n## ", 1)[0]
    parts = HEADING.split(text)
    tables = {}
    for header, _name, body in zip(parts[1::3], parts[2::3], parts[3::3], strict=True):
        tables[header] = {k: (d.strip(), v.strip()) for k, d, v in ROW.findall(body)}
    return tables


def table_text(header: str, key: str | None = None, value: str | None = None) -> str:
    lines = {**BASE.get(header, {})}
    if key is not None:
        lines[key] = str(value)
    return "\n".join([header, *(f"{k} = {v}" for k, v in lines.items())]) + "\n"


def known_keys(header: str | None) -> set[str]:
    text = "zz_unknown = 1\n" if header is None else table_text(header, "zz_unknown", "1")
    with pytest.raises(RigConfigError) as refused:
        parse_rig_spec(text)
    return set(re.search(r"known here: ([^)]*)\)", str(refused.value))[1].split(", "))


def effective(spec: RigSpec) -> tuple[Any, ...]:
    """What a spec means once every left-out key takes the default of the code that reads it:
    the parser's own, DriveConfig's, or the TRS-CAT's / CPX-E-EC's constructor's."""
    def with_defaults(kind: str, settings: dict[str, Any]) -> dict[str, Any]:
        signature = inspect.signature(TrsCat if kind == "trscat" else CpxEEc)
        given = {k: p.default for k, p in signature.parameters.items()
                 if p.default is not inspect.Parameter.empty} | settings
        return {k: list(v) if isinstance(v, tuple) else v for k, v in given.items()}

    return (dataclasses.replace(spec, servos=(), slaves=()),
            [(s.id, s.flash, DriveConfig(**s.settings)) for s in spec.servos],
            [(s.kind, s.id, with_defaults(s.kind, s.settings)) for s in spec.slaves])


def loads(text: str) -> bool:
    try:
        build_rig(parse_rig_spec(text))
    except RigConfigError:
        return False
    return True


def test_the_keys_section_has_every_table_of_a_rig_file() -> None:
    assert {name for _header, name in HEADING.findall(DOC.read_text(encoding="utf-8"))} \
        == known_keys(None)


@pytest.mark.parametrize("header", list(doc_tables()))
def test_every_key_the_parser_takes_has_a_row_and_no_other(header: str) -> None:
    assert set(doc_tables()[header]) == known_keys(header)


def documented(kind: str) -> list[tuple[str, str, str]]:
    """(table, key, cell) for each default (kind "default") or values cell (kind "values")."""
    column = 0 if kind == "default" else 1
    return [(header, key, cells[column]) for header, rows in doc_tables().items()
            for key, cells in rows.items()]


@pytest.mark.parametrize(("header", "key", "cell"),
                         [d for d in documented("default") if TICKED.fullmatch(d[2])])
def test_a_default_in_backticks_is_what_a_left_out_key_gives(header: str, key: str,
                                                            cell: str) -> None:
    value = TICKED.fullmatch(cell)[1]  # type: ignore[index]
    left_out = parse_rig_spec(table_text(header))
    assert effective(parse_rig_spec(table_text(header, key, value))) == effective(left_out)


def bounds(cell: str) -> tuple[float, float] | None:
    found = RANGE.match(cell.replace("`", ""))
    if found is None:
        return None
    return tuple(float(int(b, 0)) if "x" in b else float(b) for b in found.groups())  # type: ignore[return-value]


@pytest.mark.parametrize(("header", "key", "cell"),
                         [d for d in documented("values") if bounds(d[2])])
def test_a_range_takes_its_ends_and_refuses_past_them(header: str, key: str, cell: str) -> None:
    low, high = bounds(cell)  # type: ignore[misc]
    whole = not any("." in b for b in RANGE.match(cell.replace("`", "")).groups())  # type: ignore[union-attr]
    past = 1.0 if whole else 1e-6 * max(1.0, abs(low), abs(high))

    def toml(v: float) -> str:
        return str(int(v)) if whole else repr(v)

    assert loads(table_text(header, key, toml(low))), f"{key} = {toml(low)}"
    assert loads(table_text(header, key, toml(high))), f"{key} = {toml(high)}"
    assert not loads(table_text(header, key, toml(low - past))), f"{key} = {toml(low - past)}"
    assert not loads(table_text(header, key, toml(high + past))), f"{key} = {toml(high + past)}"


def test_the_checks_see_a_stale_row() -> None:
    """The helpers flag what they are for: a wrong default and a range one past the code's."""
    rig = "[rig]"
    assert effective(parse_rig_spec(table_text(rig, "seed", "1"))) \
        != effective(parse_rig_spec(table_text(rig)))
    assert effective(parse_rig_spec(table_text("[[trscat]]", "field_supply_v", "23.0"))) \
        != effective(parse_rig_spec(table_text("[[trscat]]")))
    assert bounds("`0.1 .. 100`") == (0.1, 100.0) and bounds("1 .. `0x3FFFF`") == (1, 0x3FFFF)
    assert not loads(table_text("[[fastcat]]", "rotary_switch", "16"))
    assert known_keys("[[cpx]]") >= {"dil1", "history_flags"}
