"""The rig file tables the docs show (docs/rig-file.md, docs/trscat.md, docs/cpx-e-ec.md, ...)
load and build as written: a key a doc offers is a key the rig file takes.

A block made of rig tables only is checked; a ``[master]`` with a ``line`` names slaves of a
whole rig file, so that block is left to the rig files in static/rigs (their own tests)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

from app.rig_config import build_rig, parse_rig_spec

ROOT = Path(__file__).resolve().parents[2]
RIG_TABLES = {"rig", "master", "fastcat", "servo", "trscat", "cpx"}
BLOCK = re.compile(r"^```toml\n(.*?)^```", re.M | re.S)


def rig_blocks() -> list[tuple[str, str]]:
    found = []
    for doc in sorted((ROOT / "docs").glob("*.md")):
        text = doc.read_text(encoding="utf-8")
        for m in BLOCK.finditer(text):
            tables = tomllib.loads(m.group(1))
            if not set(tables) <= RIG_TABLES or "line" in tables.get("master", {}):
                continue
            found.append((f"{doc.name}:{text[:m.start()].count(chr(10)) + 1}", m.group(1)))
    return found


def test_the_docs_show_rig_tables() -> None:
    names = {where.split(":")[0] for where, _ in rig_blocks()}
    assert {"rig-file.md", "trscat.md", "cpx-e-ec.md"} <= names


@pytest.mark.parametrize(("where", "text"), rig_blocks(), ids=[w for w, _ in rig_blocks()])
def test_a_doc_rig_table_loads_and_builds(where: str, text: str) -> None:
    # Relative paths in a doc's table are relative to a rig file in static/rigs.
    spec = parse_rig_spec(text, str(ROOT / "static" / "rigs" / "from_the_doc.toml"))
    assert build_rig(spec).devices
