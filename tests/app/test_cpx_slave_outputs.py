"""The Slave tab's CPX-E-EC module table says which outputs the module holds off against the
PLC's output image (docs/cpx-e-ec.md choice 40, seed 002 §2.5).

In the cpx_short_circuit example's pictures the caption said output 3 was switched off, and
the table's "Outputs" still read 00010000: the PLC's image (the RxPDO, 0x7002), which keeps
the PLC's value. A trainee read it as "output 3 on".
"""

from __future__ import annotations

import re
from typing import Any

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.line.slave_panel import slave_html

BOOT_STEPS = 8000  # 8 s of 1 ms steps: every slave in OP


def io_table(html: str) -> tuple[list[str], dict[str, str]]:
    """The module table's header cells, and its rows as text by module number."""
    table = html.split('id="fr-slave-io">', 1)[1].split("</table>", 1)[0]
    head = [" ".join(re.sub("<[^>]+>", " ", h).split())
            for h in re.findall(r"<th[^>]*>(.*?)</th>", table)]
    body = table.split("<tbody>", 1)[1]
    rows = {}
    for row in body.split("</tr>"):
        cells = [" ".join(re.sub("<[^>]+>", " ", c).split())
                 for c in re.findall(r"<td[^>]*>(.*?)</td>", row)]
        if cells:
            rows[cells[0]] = cells
    return head, rows


def outputs_cell(rig: Any, module: str) -> str:
    head, rows = io_table(slave_html("cpx", rig.devices["cpx"].snapshot()))
    return rows[module][head.index("PLC out")]


@pytest.fixture()
def rig() -> Any:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    rig.apply("cpx", "write_object", {"index": 0x7002, "sub": 4, "value": 1})  # output 3 on
    for _ in range(100):
        rig.step()
    return rig


def test_the_outputs_column_says_it_is_the_plc_image(rig: Any) -> None:
    head, _ = io_table(slave_html("cpx", rig.devices["cpx"].snapshot()))
    assert "PLC out" in head
    assert outputs_cell(rig, "2") == "00010000"


def test_a_shorted_output_is_marked_held_off_by_the_short(rig: Any) -> None:
    rig.apply("cpx/2", "short_circuit", {"channel": 3, "on": True})
    for _ in range(100):
        rig.step()
    assert outputs_cell(rig, "2") == "00010000 held off: 3 (short)"
    rig.apply("cpx/2", "short_circuit", {"channel": 3, "on": False})
    for _ in range(100):
        rig.step()
    assert outputs_cell(rig, "2") == "00010000"


def test_u_out_too_low_marks_every_driven_output(rig: Any) -> None:
    rig.apply("cpx", "write_object", {"index": 0x7002, "sub": 2, "value": 1})  # output 1 on
    rig.apply("cpx", "supply", {"out": 16.0})
    for _ in range(500):
        rig.step()
    assert outputs_cell(rig, "2") == "01010000 held off: 1,3 (U_OUT low)"


def test_analog_channels_read_as_numbers_even_at_zero(rig: Any) -> None:
    """The table wrote every module through ``bits``: the 4AI-U-I's four inputs and the
    4AO-U-I's four outputs at 0 read "0000", the way four digital lines read, so a trainee
    took the analog modules for switched channels. An analog module (one with measuring
    ranges, seed 002 §2.4) shows one number per channel, whatever the values."""
    head, rows = io_table(slave_html("cpx", rig.devices["cpx"].snapshot()))
    assert rows["3"][head.index("Inputs")] == "0 0 0 0"
    assert rows["4"][head.index("PLC out")] == "0 0 0 0"
    assert rows["1"][head.index("Inputs")] == "00000000 00000000"
