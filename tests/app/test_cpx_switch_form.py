"""The CPX-E-EC's switches in the Line tab (seed 002 §2.1.7, Tab. 5 / Tab. 6).

Before, the set_dil form opened with dil1 / dil2 unticked (the factory setting) while the
default rig's CPX-E-EC sits at DIL 1 ON / DIL 2 OFF, and after a change the Slave tab's
Switches row read "rotary 000, status bits [restart to apply]": the mode still running (I/O
diagnostic interface) was no longer shown. Now the form starts from the switches' positions
and the row shows the active mode and the one set.
"""

from __future__ import annotations

from typing import Any

from served_dashboard import drawn, served_default_rig

from app.ui.line.slave_panel import cpx_html, switches_text


def _pick(form: Any, action: str) -> dict[str, Any]:
    """Pick ``action`` in the form (as a page does) and read its parameter widgets."""
    other = next(n for n in form.options() if n != action)
    for name in (other, action):
        form.choice.value = name
        form.rebuild()
    return form.values()


def test_set_dil_and_set_rotary_start_from_the_switches() -> None:
    with served_default_rig(1.0) as live:
        assert live.dashboard.line is not None
        form = live.dashboard.line.controls.all_forms()["cpx"][0]
        assert _pick(form, "set_dil") == {"dil1": True, "dil2": False}  # default.toml
        live.command("cpx", "set_dil", {"dil1": False, "dil2": True})
        live.command("cpx", "set_rotary", {"value": 0x0A1})
        drawn(live)
        assert _pick(form, "set_dil") == {"dil1": False, "dil2": True}
        assert _pick(form, "set_rotary") == {"value": "0A1"}  # hex, as Tab. 5 writes it


def test_switches_show_the_active_mode_and_the_one_set() -> None:
    switches = {"rotary": 0, "rotary_hex": "000", "dil1": False, "dil2": True,
                "mode": "status bits", "active_rotary": 0,
                "active_mode": "I/O diagnostic interface", "pending": True}
    assert switches_text(switches) == (
        "active: rotary 000, I/O diagnostic interface; set: rotary 000, status bits")
    html = cpx_html({"switches": switches})
    assert "I/O diagnostic interface; set: rotary 000, status bits" in html
    assert "restart to apply" in html
    moved = {**switches, "rotary": 0xA1, "rotary_hex": "0A1", "mode": "I/O diagnostic interface"}
    assert switches_text(moved) == (
        "active: rotary 000, I/O diagnostic interface; set: rotary 0A1, I/O diagnostic interface")
    steady = {**switches, "mode": "I/O diagnostic interface", "pending": False}
    assert switches_text(steady) == "rotary 000, I/O diagnostic interface"


def test_the_panel_says_when_the_wire_shows_the_explicit_device_id() -> None:
    """The panel's AL status rows are the ESM's (the model's al_status / al_status_code); while
    a wire master's ID request is answered the wire shows 0x0020 and the ID at 0x0134 instead,
    so the panel names the ID and says it is loaded (seed 002 Tab. 5, docs/cpx-e-ec.md 35)."""
    snap = {"al_status": 0x02, "al_status_code": 0, "explicit_device_id": 0x11,
            "id_loaded": True, "switches": {"rotary_hex": "011", "mode": "status bits"}}
    html = cpx_html(snap)
    assert "0x0002" in html and "ID loaded" in html
    assert "0x0022" in html and "0x0011" in html  # what 0x0130 / 0x0134 show
    assert "ID loaded" not in cpx_html({**snap, "id_loaded": False})
