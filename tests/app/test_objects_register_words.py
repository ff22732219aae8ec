"""The Objects tab says 0x1001:0 and 0x10F3:5 in the device's own words, next to the number,
through the dictionary entry's ``explain`` (as 0x1003:1 names its alarm): the CPX-E-EC's
0x1001 in seed 002 Tab. 22's names, the TRS-CAT's and the drive's in DS 301's (seed 001
names no bits; seed 004 ch. 4 prints DS 301's table), 0x10F3:5 in seed 001 §9.3.7's and seed
002 Tab. 18 / 19's. Before, both rows showed a bare number ("3", "17 (0x0011)"), and the
Codes tab was the only place that read them. A row copied with its words still decodes."""

from __future__ import annotations

import random
from collections.abc import Iterator

import pytest

from app.decoder import CPX, TRSCAT, decode
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.panels.object_dictionary import OdRow, read_rows, render
from devices.cpx.device import CpxEEc


def _row(device: object, index: int, sub: int) -> OdRow:
    rows = [r for r in read_rows(device) if (r.index, r.sub) == (index, sub)]
    assert len(rows) == 1, rows
    return rows[0]


def _copied(row: OdRow) -> str:
    """The row as a browser copies it: the cells tab-separated."""
    return "\t".join((row.address, row.name, row.shown_type, row.access, row.said))


@pytest.fixture(scope="module")
def rig() -> Iterator[Rig]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.apply("fastcat", "power", {"on": True})
    rig.run_until(4_000_000)
    yield rig


@pytest.fixture(scope="module")
def shorted() -> CpxEEc:
    """A short on an output of the 8DO: Tab. 22 bits 0 (every error) and 1 (KZA)."""
    cpx = CpxEEc("cpx", random.Random(1), ["CPX-E-8DO"], dil1=True)
    cpx.apply("power", {"on": True}, None)
    cpx.apply("short_circuit", {"on": True, "channel": 2}, 1)
    cpx.apply("force", {"channel": 2, "value": 1}, 1)
    for t in range(1, 400):
        cpx.step(t * 1000)
    return cpx


def test_the_cpx_error_register_in_tab_22s_words(shorted: CpxEEc) -> None:
    row = _row(shorted, 0x1001, 0)
    assert row.value == 0x03
    assert row.said == "0x03 = Generic Error, Current"
    assert "<td>0x03 = Generic Error, Current</td>" in render([row], "")


def test_the_cpx_flags_in_tab_18_and_19s_words(shorted: CpxEEc) -> None:
    row = _row(shorted, 0x10F3, 5)
    assert row.said.startswith(f"0x{row.value:04X} = bit 0 = "), row.said
    assert "bit 4 = 0: Overwrite mode (Tab. 18)" in row.said, row.said
    shorted.od.write(0x10F3, 5, 0x0011)
    said = _row(shorted, 0x10F3, 5).said
    assert "bit 0 = 1: Emergency Message activated (Tab. 19)" in said, said
    assert "bit 4 = 1: Acknowledge mode (Tab. 18)" in said, said


def test_the_trscat_rows(rig: Rig) -> None:
    trscat = rig.device("trscat")
    assert _row(trscat, 0x1001, 0).said == "0x00 = no error"
    assert trscat.od.entry(0x1001, 0).explain(0x03) == "0x03 = Generic Error, Current"
    flags = _row(trscat, 0x10F3, 5).said
    assert "bit 1 = 0: info messages enabled" in flags, flags
    assert "bit 3 = 0: error messages enabled" in flags, flags


def test_the_drives_coe_error_register(rig: Rig) -> None:
    slave = rig.device("drive_ec-ecat")
    assert _row(slave, 0x1001, 0).said == "0x00 = no error"
    assert slave.od.entry(0x1001, 0).explain(0x21) == \
        "0x21 = Generic Error, Device Profile Specific"  # seed 004 ch. 4 (DS 301's table)


def test_the_drives_canopen_error_register(rig: Rig) -> None:
    node = rig.device("drive_co-can")
    assert node.dictionary.entry(0x1001, 0).explain(0x81) == \
        "0x81 = Generic Error, Manufacturer Specific"


def test_a_copied_row_with_its_words_decodes(shorted: CpxEEc) -> None:
    """The Codes tab takes the row as the tab now shows it: the number, then its words."""
    found = decode(_copied(_row(shorted, 0x1001, 0)))
    cpx = [m for m in found if m.family == CPX]
    assert [m.title for m in cpx] == ["0x1001:0 Error register = 0x03"]
    shorted.od.write(0x10F3, 5, 0x000A)
    trs = [m for m in decode(_copied(_row(shorted, 0x10F3, 5))) if m.family == TRSCAT]
    assert [m.title for m in trs] == ["0x10F3:5 Flags = 0x000A"]
