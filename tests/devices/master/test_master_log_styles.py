"""The master log's styles against the seed's displays, byte for byte (seed 000 §7.1-§7.4)."""

from __future__ import annotations

import datetime as dt
import random
from pathlib import Path

import pytest

from devices.master import EtherCatMaster
from devices.master.log_styles import STYLES, Entry, render

SEED = Path("/work/shared/seeds/000_2ef4aa04068c5f92.txt")
COUPLER = bytes.fromhex("0200000400")  # §7.2 / §7.3 first example: coupler error 04, node 2
MODULE = bytes.fromhex("02000B0000")  # second example: module 2 reports 0B


def seed_lines() -> list[str]:
    if not SEED.exists():
        pytest.skip("seed 000 not available on this machine")
    return SEED.read_text(encoding="utf-8").splitlines()


def block(first: str, n: int, nth: int = 0) -> str:
    """``n`` lines of the seed from the ``nth`` line equal to ``first``."""
    lines = seed_lines()
    starts = [i for i, line in enumerate(lines) if line == first]
    return "\n".join(lines[starts[nth]: starts[nth] + n])


def emergency(data: bytes, t_us: int = 0, position: int = 1) -> Entry:
    return Entry(t_us, "emergency", {"code": 0xFF00, "register": 0x81, "data": data},
                 slave="Box 1 (FastCAT)", address=1001, position=position)


@pytest.mark.parametrize(("data", "nth"), [(COUPLER, 0), (MODULE, 1)])
def test_sirio_display(data: bytes, nth: int) -> None:
    """§7.2: header names byte 0 and the significant byte (3 coupler, 2 module)."""
    header = "Emergency\tReset\tByte 0 basso\tByte 3 alto" if nth == 0 else \
        "Emergency\tReset\tByte 0\tByte 2"
    assert render("sirio", emergency(data)) == block(header, 3)


@pytest.mark.parametrize(("data", "nth"), [(COUPLER, 0), (MODULE, 1)])
def test_pegaso_display(data: bytes, nth: int) -> None:
    """§7.3: data high byte first."""
    assert render("pegaso", emergency(data)) == block("ERR CODE\t[0xFF00]", 3, nth)


def test_aitraceprint_lines() -> None:
    """§7.4: the state change pair (state and AL status code numeric, 33540 = 0x8304 has no
    table text: Unknown) and the emergency line, slave 11."""
    lines = seed_lines()
    abnormal = Entry(380_808_000, "abnormal", {"from_state": "OP", "to_state": "PREOP",
                                               "code": 0x8304, "target": "OP"},
                     slave="x", address=1012, position=11)
    want = [line for line in lines if line.startswith("380808 - 00000001 - ") and
            "ErrorControl" not in line]
    assert render("aitraceprint", abnormal).split("\n") == want
    got = render("aitraceprint", emergency(bytes.fromhex("0300002400"), 380_856_000, 11))
    assert got in lines


def test_twincat_emergency_is_the_7_1_line() -> None:
    """§7.1 / §7.7: the TwinCAT message after the port and timestamp columns."""
    text = render("twincat", emergency(COUPLER))
    assert text == "'Box 1 (FastCAT)' (1001): CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00')."
    assert f"(65535)\t12/11/2019 14.51.30 280 ms\t{text}" in seed_lines()


def test_set_log_style_re_renders_the_log() -> None:
    master = EtherCatMaster("master", random.Random(1), slaves=[],
                            epoch=dt.datetime(2019, 11, 12, 14, 51, 30))
    master.entries.append(emergency(MODULE, 5_000))
    master.cmd_set_log_style("twincat")
    twincat = master.snapshot()["log"][0]["text"]
    for style in STYLES:
        master.apply("set_log_style", {"style": style})
        snap = master.snapshot()
        assert snap["log_style"] == style
        assert snap["log"][0]["text"] == render(style, master.entries[0])
        assert snap["log"][0]["timestamp"] == "12/11/2019 14.51.30 005 ms"
    master.apply("set_log_style", {"style": "twincat"})
    assert master.snapshot()["log"][0]["text"] == twincat


def test_non_emergency_lines_keep_the_twincat_text_on_emergency_displays() -> None:
    entry = Entry(0, "lost", {"silent": "no answer from position 2 on"}, slave="Box 3 (CPX-E-EC)",
                  address=1003, position=2)
    assert render("sirio", entry) == render("pegaso", entry) == render("twincat", entry)
    assert render("aitraceprint", entry) == "0 - 00000001 - ECAT: " + render("twincat", entry)
