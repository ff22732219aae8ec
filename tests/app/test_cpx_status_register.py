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


def test_the_0x1001_row_reads_tab_22s_words() -> None:
    """0x1001 next to 0x1002 in the same way: its set bits in seed 002 Tab. 22's names.
    Before, the row showed "0x83" only and a trainee had to look the bits up."""
    html = cpx_html({"diagnosis": {"error_register": 0x83, "status_bits": 0x24}})
    assert "0x83 Generic Error, Current, Manufacturer specific" in html, html
    assert "0x00 no error" in cpx_html({"diagnosis": {"error_register": 0, "status_bits": 0}})
    # a bit Tab. 22 leaves "-" says so rather than borrowing DS 301's name
    assert "0x09 Generic Error, bit 3 (&quot;-&quot; in Tab. 22)" in \
        cpx_html({"diagnosis": {"error_register": 0x09, "status_bits": 0}})


def test_the_0x1001_row_reads_the_models_register() -> None:
    """The 8DO short of the test above: Tab. 22 bits 0 (every error) and 1 (KZA)."""
    cpx = CpxEEc("cpx", random.Random(1), ["CPX-E-8DO"], dil1=True)
    cpx.apply("power", {"on": True}, None)
    cpx.apply("short_circuit", {"on": True, "channel": 2}, 1)
    cpx.apply("force", {"channel": 2, "value": 1}, 1)
    for t in range(1, 400):
        cpx.step(t * 1000)
    assert "0x03 Generic Error, Current" in cpx_html(cpx.snapshot())
