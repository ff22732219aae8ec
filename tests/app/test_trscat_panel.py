"""The TRS-CAT's slave panel and plates agree with the node's power and what is fitted.

The UI audit, TRS-CAT powered off by the master and expansion 2 (AN-E) unplugged (the way a
technician swaps it, seed 001 §7: never under power): "not seen" stood under plate 1, whose
IO-E is still fitted, and not under plate 2, which is empty; the I/O table's slot 2 read
"None"; the panel said "Field supply 24.0 V ok" while the +24V LED was off; "Sync DC-SYNC ·
free_run" did not say which part is the mode (0x1C32:1, from Sync Control 0x0980 at PREOP ->
SAFEOP, docs/trscat.md) and which the sync unit's state.
"""

from __future__ import annotations

import random
import re
from typing import Any

import pytest

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.line.io_bodies import expansion_note
from app.ui.line.slave_panel import slave_html
from devices.trscat.device import TrsCat

BOOT_STEPS = 8000  # 8 s of 1 ms steps: every slave in OP


def rows(html: str) -> dict[str, str]:
    """The state table's rows as text: {"Field supply": "24.0 V ok", ...}."""
    table = html.split('id="fr-slave-state">', 1)[1].split("</table>", 1)[0]
    return {re.sub("<[^>]+>", "", k): " ".join(re.sub("<[^>]+>", " ", v).split())
            for k, v in re.findall(r"<tr[^>]*><th>(.*?)</th><td>(.*?)</td></tr>", table)}


def io_rows(html: str) -> list[str]:
    table = html.split('id="fr-slave-io">', 1)[1].split("</table>", 1)[0]
    body = table.split("<tbody>", 1)[1]
    return [" ".join(re.sub("<[^>]+>", " ", r).split()) for r in body.split("</tr>") if r]


@pytest.fixture(scope="module")
def booted() -> Any:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    return rig


@pytest.fixture(scope="module")
def off(booted: Any) -> dict[str, Any]:
    """Powered off from the master, then expansion 2 unplugged."""
    booted.apply("master", "power_slave", {"position": 1, "on": False})
    for _ in range(200):
        booted.step()
    booted.apply("trscat/2", "unplug", {})
    booted.step()
    snap = booted.devices["trscat"].snapshot()
    assert not snap["powered"] and snap["leds"]["+24V"] == "off"
    assert snap["slots"][2]["type"] is None
    return snap


def test_not_seen_sits_under_the_empty_plate(off: dict[str, Any]) -> None:
    assert expansion_note(off, 1) == ""  # the IO-E is fitted; the node is off (header says)
    assert expansion_note(off, 2) == "not seen"


def test_empty_slot_reads_as_such(off: dict[str, Any]) -> None:
    """Powered off, the node holds no 0xF030 (RAM, §9.3.2's default at the next power-up):
    the row names no configured module (it named the rig's, which the model no longer
    reads; docs/trscat.md "Who writes 0xF030")."""
    html = slave_html("trscat", off)
    assert "None" not in html
    slot2 = io_rows(html)[2]
    assert slot2.startswith("2 ") and "not seen" in slot2 and "configured" not in slot2, slot2


def test_empty_slot_names_what_the_masters_list_configures_there() -> None:
    """Powered on again, the master writes its 0xF030 list at PS (seed 001 §9.2), refused
    (0x0070): the empty position names the module that list puts there."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    rig.apply("master", "power_slave", {"position": 1, "on": False})
    for _ in range(200):
        rig.step()
    rig.apply("trscat/2", "unplug", {})
    rig.apply("master", "power_slave", {"position": 1, "on": True})
    for _ in range(3000):
        rig.step()
    snap = rig.devices["trscat"].snapshot()
    assert snap["al_status_code"] == 0x0070
    slot2 = io_rows(slave_html("trscat", snap))[2]
    assert "not seen" in slot2 and "(configured TRS-AN-E)" in slot2, slot2


def test_field_supply_agrees_with_the_powered_off_node(off: dict[str, Any]) -> None:
    state = rows(slave_html("trscat", off))
    assert "ok" not in state["Field supply"].split(), state["Field supply"]
    assert "node off" in state["Field supply"], state["Field supply"]
    assert state["Logic supply"].startswith("off"), state["Logic supply"]


def test_sync_mode_and_state_are_labelled(booted: Any, off: dict[str, Any]) -> None:
    state = rows(slave_html("trscat", off))
    assert "Sync" not in state
    assert state["Sync mode"].startswith("DC-SYNC (0x1C32:1)"), state["Sync mode"]
    assert "0x0980" in state["Sync mode"]
    assert state["Sync state"].startswith("free-running local cycle"), state["Sync state"]
    assert "SM events missed 0" in state["Sync state"]


def test_a_powered_node_in_op_reads_as_before() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    snap = rig.devices["trscat"].snapshot()
    state = rows(slave_html("trscat", snap))
    assert state["Logic supply"] == "on"
    assert state["Field supply"] == "24.0 V ok"
    assert state["Sync state"].startswith("on SYNC0 (DC running)"), state["Sync state"]
    assert expansion_note(snap, 1) == expansion_note(snap, 2) == ""
    assert all("not seen" not in r for r in io_rows(slave_html("trscat", snap)))


def test_an_injected_sm_fault_is_named_in_the_injected_row(booted: Any) -> None:
    """The instructor's SM fault (docs/trscat.md ESM) is an injected cause like the others:
    without it in the row, a refused PREOP -> SAFEOP read 'Injected: none'."""
    snap = {**booted.devices["trscat"].snapshot(),
            "injected_sm": [{"fault": "sm_invalid_size", "sm": 2}]}
    row = slave_html("trscat", snap).split("<th>Injected</th>", 1)[1].split("</tr>", 1)[0]
    assert "sm_invalid_size" in row


@pytest.mark.parametrize(("injected", "injected_sm", "text"), [
    ([{"fault": "TRS_OVERCURRENT", "slot": None}], [], "TRS_OVERCURRENT"),
    ([{"fault": "CONFIG_ERROR", "slot": 2}], [{"fault": "sm_invalid_size", "sm": 2}],
     "CONFIG_ERROR on slot 2, sm_invalid_size on SM2"),
    ([], [], "none"),
])
def test_the_injected_row_reads_as_the_fastcat_s(booted: Any, injected: list[Any],
                                                 injected_sm: list[Any], text: str) -> None:
    """The review (20_trscat_fault.png): the row showed the raw Python dict "{'fault':
    'TRS_OVERCURRENT', 'slot': None}"; it is written as the FastCAT's State tab writes its
    injected causes (app/ui/panels/state.py injected_text)."""
    snap = {**booted.devices["trscat"].snapshot(), "injected": injected,
            "injected_sm": injected_sm}
    assert rows(slave_html("trscat", snap))["Injected"] == text


def test_the_cpx_injected_row_names_its_faults() -> None:
    """The CPX-E-EC's entries are {fault, module, channel, sm} (they were its labels, which
    the exercise scoring could not match), written as the other slaves' are."""
    snap = {"kind": "cpx_e_ec", "esm": "OP",
            "injected": [{"fault": "module_ident_mismatch", "module": 1, "channel": None,
                          "sm": None},
                         {"fault": "short_circuit", "module": 2, "channel": 3, "sm": None},
                         {"fault": "sm_invalid_size", "module": None, "channel": None,
                          "sm": 2}]}
    assert rows(slave_html("cpx", snap))["Injected"] == (
        "module_ident_mismatch on module 1, short_circuit on module 2 channel 3, "
        "sm_invalid_size on SM2")
    assert rows(slave_html("cpx", {**snap, "injected": []}))["Injected"] == "none"


def test_a_latched_bus_shutdown_says_what_to_do() -> None:
    """The review (20_ / 21_trscat_cleared.png): after clear_fault TRS_OVERCURRENT the panel
    read "TRS bus shutdown" and "Outputs normal", nothing telling the trainee that only the
    logic supply off and on brings the bus back (docs/trscat.md, §8.2 "irreversibile") nor
    that every slot's outputs are off."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    for _ in range(BOOT_STEPS):
        rig.step()
    assert rows(slave_html("trscat", rig.devices["trscat"].snapshot()))["Outputs"] == "normal"
    rig.apply("trscat", "inject_fault", {"fault": "TRS_OVERCURRENT"})
    for _ in range(10):
        rig.step()
    rig.apply("trscat", "clear_fault", {"fault": "TRS_OVERCURRENT"})
    for _ in range(10):
        rig.step()
    state = rows(slave_html("trscat", rig.devices["trscat"].snapshot()))
    assert state["TRS bus"] == "shutdown (latched: switch the logic supply off and on)"
    assert state["Outputs"] == "off (bus down)"
    rig.apply("master", "power_slave", {"position": 1, "on": False})
    for _ in range(200):
        rig.step()
    rig.apply("master", "power_slave", {"position": 1, "on": True})
    for _ in range(BOOT_STEPS):
        rig.step()
    state = rows(slave_html("trscat", rig.devices["trscat"].snapshot()))
    assert state["TRS bus"] == "running" and state["Outputs"] == "normal"


def test_analog_and_word_channels_read_as_numbers() -> None:
    """The I/O table wrote a TRS-AN-E's four INT16 inputs at 0, 1, 0, 0 counts as "0100",
    the way it writes four digital lines, and its two outputs at 0 as "00": a trainee read
    analog channels as switched lines. Only the bidirectional lines (§3) are bits; analog
    and data words (docs/trscat.md, the kind table) are one number per channel."""
    trs = TrsCat("trscat", random.Random(1), ["TRS-IO-E", "TRS-AN-E", "TRS-XX-E"])
    trs.apply("set_input", {"channel": 2, "on": True})
    trs.apply("set_analog_input", {"channel": 2, "volts": 0.0003}, module=2)  # 1 count
    for t_us in range(1_000, 600_000, 1_000):
        trs.step(t_us)
    assert trs.snapshot()["slots"][2]["inputs"] == [0, 1, 0, 0]
    slots = io_rows(slave_html("trscat", trs.snapshot()))
    assert slots[0] == "0 TRS-CAT integrated IO-B 01000000 00000000 00000000 00000000", slots
    assert slots[1].startswith("1 TRS-IO-E IO-E 00000000 00000000 "), slots
    assert slots[2] == "2 TRS-AN-E AN-E 0 1 0 0 0 0", slots
    assert slots[3] == "3 TRS-XX-E XX-E 0 0", slots


def test_lit_io_leds_read_as_channel_numbers() -> None:
    """The LED table's "I/O 1-16" row named the lit channels as a Python list, "on: [1, 3]"
    (trscat_outputs_fallback's error outputs); a technician reads "on: 1, 3"."""
    leds = {"I/O 1": "on", "I/O 3": "on"}
    html = slave_html("trscat", {"kind": "trscat", "leds": leds})
    table = html.split('id="fr-slave-leds">', 1)[1].split("</table>", 1)[0]
    assert "<td>I/O 1-16</td><td>yellow</td><td>on: 1, 3</td>" in table
    assert "[" not in table
