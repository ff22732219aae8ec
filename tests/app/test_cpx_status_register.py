"""The Slave tab shows the CPX-E-EC's 0x1002 Manufacturer Status Register next to 0x1001,
its bits in seed 002 Tab. 23's words (bits 0-3 the module type, 4-7 the error type). Before,
the tab showed 0x1001 only, though the snapshot has both (``diagnosis.status_bits``) and the
emergency carries 0x1002 as byte 3 (Tab. 20)."""

from __future__ import annotations

import random

from app.ui.line.slave_panel import cpx_html, status_register_text
from devices.cpx.device import CpxEEc


def test_the_bits_in_tab_23s_words() -> None:
    assert status_register_text(0x24) == "0x24 Error at input, Short circuit/overload"
    assert status_register_text(0x12) == "0x12 Error at output, Undervoltage"
    assert status_register_text(0x81) == "0x81 Error at valve terminal, Other error"
    assert status_register_text(0x00) == "0x00 no error"


def test_the_row_next_to_0x1001() -> None:
    html = cpx_html({"diagnosis": {"error_register": 0x03, "status_bits": 0x24}})
    assert "0x1001" in html and "0x1002" in html
    assert html.index("0x1001") < html.index("0x1002")
    assert "0x24 Error at input, Short circuit/overload" in html


def test_the_row_reads_the_models_register() -> None:
    """A short on an output of the 8DO (Tab. 23: bit 1 output, bit 5 short circuit), as the
    model's snapshot carries it."""
    cpx = CpxEEc("cpx", random.Random(1), ["CPX-E-8DO"], dil1=True)
    cpx.apply("power", {"on": True}, None)
    cpx.apply("short_circuit", {"on": True, "channel": 2}, 1)
    cpx.apply("force", {"channel": 2, "value": 1}, 1)
    for t in range(1, 400):
        cpx.step(t * 1000)
    snap = cpx.snapshot()
    assert snap["diagnosis"]["status_bits"] == 0x22
    assert "0x22 Error at output, Short circuit/overload" in cpx_html(snap)
