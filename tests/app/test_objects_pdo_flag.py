"""The Objects tab's access column marks a PDO-mappable entry with "P", as seed 002 Tab. 27
(and Tab. 14) prints it: "RO P" for 0x10F3:4 New Message Available and the module inputs
0x60xx, "RW P" for the module outputs 0x70xx; plain "RO" / "RW" for the rest."""

from __future__ import annotations

import random

from app.ui.panels.object_dictionary import read_rows, render
from devices.cpx.device import CpxEEc


def _access() -> dict[tuple[int, int], str]:
    cpx = CpxEEc("cpx", random.Random(1), ["CPX-E-16DI", "CPX-E-8DO"], dil2=True)
    return {(r.index, r.sub): r.access for r in read_rows(cpx)}


def test_pdo_mappable_entries_carry_p() -> None:
    access = _access()
    assert access[(0x10F3, 4)] == "ro P"  # Tab. 14 / Tab. 27 "RO P"
    assert access[(0x6001, 1)] == "ro P"  # 0x60xx Input yy "RO P"
    assert access[(0x7002, 1)] == "rw P"  # 0x70xx Output yy "RW P"


def test_other_entries_stay_plain() -> None:
    access = _access()
    assert access[(0x10F3, 5)] == "rw"  # Flags, RW
    assert access[(0x10F3, 1)] == "ro"  # Maximum Messages, RO
    assert access[(0x6001, 0)] == "ro"  # the count of the module's inputs, RO
    assert access[(0x7002, 0)] == "ro"


def test_the_table_shows_the_flag() -> None:
    cpx = CpxEEc("cpx", random.Random(1), ["CPX-E-16DI"], dil2=True)
    html = render(read_rows(cpx), "0x10F3:4")
    assert "<td>ro P</td>" in html
