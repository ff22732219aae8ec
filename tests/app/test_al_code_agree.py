"""One FastCAT AL status code, one meaning on every tab (seed 000 §7.7).

0x80XX: byte 1 the module number, byte 0 the coupler code; a module alarm has no coupler code
(its module code is byte 2 of the emergency and of 0x5400). Before, a module alarm on module 4
(0x8400) read "module 4: coupler code 0x00" on the State tab (§7.5 has no code 0x00),
"Manufacturer specific" in the Line tab's slave table, and right only on the Codes tab.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from app.decoder import FASTCAT, decode
from app.testing import RigSession, rig_session
from app.ui.line.master_panel import al_cell
from app.ui.panels.state import al_code_text
from devices.fastcat.alarms import decode_al_status


@pytest.fixture(scope="module")
def module_4_uncalibrated() -> Iterator[RigSession]:
    """The default rig in OP, then module 4 raising 0x0B TARATURA (§7.6)."""
    with rig_session() as rig:
        rig.command("fastcat", "power", on=True)
        rig.advance(4.0)
        rig.command("fastcat/4", "inject_fault", fault="module:0x0B")
        rig.advance(1.0)
        yield rig


def test_the_decoder_reads_a_module_alarm_without_a_coupler_code() -> None:
    found = decode_al_status(0x8400)
    assert found is not None and found.module == 4 and found.coupler is None
    assert found.text == "module 4: module alarm, its code in byte 2 of 0x5400"
    known = decode_al_status(0x8400, word=0x000B0004)  # 0x5400: module 4, module code 0x0B
    assert known is not None and known.text == "module 4: module code 0x0B TARATURA"
    # 0x5400 of another alarm (module 2) does not name module 4's code.
    assert decode_al_status(0x8400, word=0x000B0002) == found
    coupler = decode_al_status(0x8204)
    assert coupler is not None
    assert coupler.text == "module 2: coupler code 0x04 MISSING_NODE_ANSWER"
    assert decode_al_status(0x8000) is None and decode_al_status(0x0052) is None


def test_state_tab_names_no_coupler_code_for_a_module_alarm() -> None:
    assert al_code_text(0x8400) == "module 4: module alarm, its code in byte 2 of 0x5400"
    assert al_code_text(0x8400, 0x000B0004) == "module 4: module code 0x0B TARATURA"
    assert al_code_text(0x8204) == "module 2: coupler code 0x04 MISSING_NODE_ANSWER"


def test_every_tab_reads_the_rigs_0x8400_alike(module_4_uncalibrated: RigSession) -> None:
    fastcat = module_4_uncalibrated.snapshot("fastcat")
    assert fastcat["al_status_code"] == 0x8400
    word = int(fastcat["emergency_data"])
    state_text = al_code_text(0x8400, word)
    assert state_text == "module 4: module code 0x0B TARATURA"
    slaves = module_4_uncalibrated.snapshot("master")["slaves"]
    row = next(s for s in slaves if s["device"] == "fastcat")
    assert row["al_status_code"] == 0x8400
    assert row["al_status_text"] == state_text  # the Line tab's slave table
    assert f"0x8400 {state_text}" in al_cell(row)
    codes_tab = [m.text for m in decode("0x8400") if m.family == FASTCAT]
    assert codes_tab and "module alarm on module 4" in codes_tab[0]
