"""A rig file that stands for "the default rig with one difference" stays that: a change to
static/rigs/default.toml that the copy misses would make its example play on another line
than the one its captions describe (static/scenarios/fastcat_address_check.toml)."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

RIGS = Path(__file__).resolve().parents[2] / "static" / "rigs"


def _load(name: str) -> dict[str, Any]:
    return tomllib.loads((RIGS / name).read_text(encoding="utf-8"))


def test_fastcat_switch_3_is_the_default_rig_with_the_switch_at_3() -> None:
    default, copy = _load("default.toml"), _load("fastcat_switch_3.toml")
    assert copy["fastcat"][0]["rotary_switch"] == 3 != copy["fastcat"][0]["master_address"]
    for rig in (default, copy):
        rig["rig"].pop("name")
        rig["fastcat"][0].pop("rotary_switch")
    assert copy == default
