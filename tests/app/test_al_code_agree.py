"""One FastCAT AL status code, one meaning on every tab (seed 000 §7.7).

0x80XX: byte 1 the module number, byte 0 the coupler code (§7.5). Only a coupler alarm reaches
the AL status code ("allarmi gravi generati dal coupler"); a module alarm (§7.6) keeps the ESM
in OP with code 0x0000 (docs/fastcat-coupler.md "Module alarms keep OP"). Before, a module
alarm on module 4 dropped the coupler to PREOP with 0x8400, which every tab had to read.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from app.decoder import FASTCAT, decode
from app.testing import RigSession, rig_session
from app.ui.line.master_panel import al_cell
from app.ui.panels.state import al_code_text
from devices.fastcat.alarms import decode_al_status


@pytest.fixture
def rig() -> Iterator[RigSession]:
    with rig_session() as rig:
        rig.command("fastcat", "power", on=True)
        rig.advance(4.0)
        yield rig


def _fastcat_row(rig: RigSession) -> dict:
    slaves = rig.snapshot("master")["slaves"]
    return next(s for s in slaves if s["device"] == "fastcat")


def test_the_decoder_reads_coupler_codes_only() -> None:
    coupler = decode_al_status(0x8204)
    assert coupler is not None and coupler.module == 2
    assert coupler.text == "module 2: coupler code 0x04 MISSING_NODE_ANSWER"
    # byte 0 = 0 names no coupler code: no FastCAT code (a module alarm has none)
    assert decode_al_status(0x8400) is None
    assert decode_al_status(0x8000) is None and decode_al_status(0x0052) is None
    assert al_code_text(0x8400) == "Manufacturer specific"
    assert not [m for m in decode("0x8400") if m.family == FASTCAT]


def test_a_module_alarm_leaves_op_and_code_0_on_every_tab(rig: RigSession) -> None:
    rig.command("fastcat/4", "inject_fault", fault="module:0x0B")  # §7.6 TARATURA
    rig.advance(1.0)
    fastcat = rig.snapshot("fastcat")
    assert fastcat["alarm"]["code"] == 0x0B and fastcat["fault_active"]
    assert (fastcat["esm"], fastcat["al_status"], fastcat["al_status_code"]) == ("OP", 0x08, 0)
    row = _fastcat_row(rig)
    assert (row["al_status_code"], row["al_status_text"]) == (0, "No error")
    assert "0x0000 No error" in al_cell(row) and "fr-line-bad" not in al_cell(row)
    rig.command("fastcat/4", "clear_fault", fault="module:0x0B")
    rig.command("fastcat", "set_reset_fault", on=True)
    rig.advance(0.2)
    rig.command("fastcat", "set_reset_fault", on=False)
    rig.advance(0.2)
    assert rig.snapshot("fastcat")["alarm"] is None


def test_every_tab_reads_a_coupler_alarms_0x8204_alike(rig: RigSession) -> None:
    rig.command("fastcat/2", "unplug")  # §7.7 example: module 2 does not answer
    rig.advance(0.1)
    fastcat = rig.snapshot("fastcat")
    assert (fastcat["esm"], fastcat["al_status_code"]) == ("PREOP", 0x8204)
    state_text = al_code_text(0x8204)
    assert state_text == "module 2: coupler code 0x04 MISSING_NODE_ANSWER"
    row = _fastcat_row(rig)
    assert row["al_status_code"] == 0x8204
    assert row["al_status_text"] == state_text  # the Line tab's slave table
    # <wbr> (a break allowed after an underscore) is no text a trainee reads
    assert f"0x8204 {state_text}" in al_cell(row).replace("<wbr>", "")
    codes_tab = [m.text for m in decode("0x8204") if m.family == FASTCAT]
    assert codes_tab and "module 2, coupler code 0x04 MISSING_NODE_ANSWER" in codes_tab[0]
