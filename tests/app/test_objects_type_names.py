"""The Objects tab's Type column in each device's own manual's words. Before, every device's
types were seed 000's (USINT, UDINT, ARRAY OF BYTE ...), while seed 002 Tab. 14 / Tab. 27
print the CPX-E-EC's as U8, U16, U32, BOOL, STRING, BYTE[23] and seed 001 §9.3 the
TRS-CAT's as U8, U16, U32, Bool. The FastCAT keeps seed 000's; the drive's CoE side the IEC
names seed 004 §5.5's TwinCAT Process Data list prints (UINT Status Word, DINT Position
Actual Value). Each table is the device's data (devices/); the view only reads it."""

from __future__ import annotations

import random
from collections.abc import Iterator
from typing import Any

import pytest

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.panels.object_dictionary import read_rows, render
from devices.cpx.device import CpxEEc
from devices.od import DataType


def _types(device: Any) -> dict[tuple[int, int], str]:
    return {(r.index, r.sub): r.type_name for r in read_rows(device)}


@pytest.fixture(scope="module")
def rig() -> Iterator[Rig]:
    """The default rig with the line in OP: the FastCAT has scanned (its dictionary)."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.apply("fastcat", "power", {"on": True})
    rig.run_until(4_000_000)
    yield rig


def test_the_cpx_e_ec_in_seed_002s_words() -> None:
    cpx = CpxEEc("cpx", random.Random(1), ["CPX-E-16DI", "CPX-E-4AI-U-I"], dil1=True)
    types = _types(cpx)
    assert types[(0x1000, 0)] == "U32"  # Tab. 27 Device Type U32
    assert types[(0x1001, 0)] == "U8"  # Error Register U8
    assert types[(0x1008, 0)] == "STRING"  # Device Name STRING
    assert types[(0x10F3, 4)] == "BOOL"  # New Message Available BOOL
    assert types[(0x10F3, 5)] == "U16"  # Flags U16
    assert types[(0x10F3, 6)] == "BYTE[23]"  # Tab. 14 / 27 "BYTE[23]"
    assert types[(0xF000, 2)] == "U16"  # Maximum Number Of Modules U16
    assert types[(0x6002, 1)] == "I16"  # an analog input: seed 002 prints none (choice 42)
    html = render(read_rows(cpx), "0x1000")
    assert "<td>U32</td>" in html and "UDINT" not in html
    assert "(0x04561389)" in html  # still shown in hex too, as a 32-bit unsigned


def test_the_trscat_in_seed_001s_words(rig: Rig) -> None:
    types = _types(rig.device("trscat"))
    assert types[(0x1C32, 1)] == "U16"  # §9.3 Sync Mode U16
    assert types[(0x1C32, 2)] == "U32"  # Cycle Time U32
    assert types[(0x10F3, 2)] == "U8"  # Newest message U8
    assert types[(0x10F3, 4)] == "Bool"  # New message available Bool
    assert types[(0xF030, 1)] == "U32"


def test_the_fastcat_keeps_seed_000s_words(rig: Rig) -> None:
    types = _types(rig.device("fastcat"))
    assert types[(0x5400, 0)] == "UDINT"
    assert types[(0x1008, 0)] == "STRING"
    assert "USINT" in types.values() and "U8" not in types.values()


def test_the_drive_in_seed_004s_twincat_words(rig: Rig) -> None:
    types = _types(rig.device("drive_ec-ecat"))
    assert types[(0x6041, 0)] == "UINT"  # §5.5: 604100 Status Word UINT
    assert types[(0x6064, 0)] == "DINT"  # 606400 Position Actual Value DINT


@pytest.mark.parametrize("device", ["fastcat", "trscat", "cpx", "drive_ec-ecat", "drive"])
def test_every_type_a_device_has_is_named_by_its_table(rig: Rig, device: str) -> None:
    """A table names every DataType: one device's column never mixes two manuals' words."""
    model = rig.device(device)
    assert set(model.TYPE_NAMES.names) == set(DataType)
    assert all(r.type_name for r in read_rows(model))
