"""The CPX-E-EC's switches in the Line tab (seed 002 §2.1.7, Tab. 5 / Tab. 6).

Before, the set_dil form opened with dil1 / dil2 unticked (the factory setting) while the
default rig's CPX-E-EC sits at DIL 1 ON / DIL 2 OFF, and after a change the Slave tab's
Switches row read "rotary 000, status bits [restart to apply]": the mode still running (I/O
diagnostic interface) was no longer shown. Now the form starts from the switches' positions
and the row shows the active mode and the one set. The form is each page's own
(app/ui/panels/client_action_form.py): a page picks the action here (tests/app/form_page.py),
and its boxes take the switches as they are when it picks.
"""

from __future__ import annotations

import time
from typing import Any

from form_page import page_on, uuid
from served_dashboard import drawn, served_default_rig
from viser_page import Page, wait

from app.ui.line.slave_panel import cpx_html, switches_text
from app.ui.panels.client_action_form import ClientActionForm


def _pick(page: Page, client_id: int, form: ClientActionForm,
          action: str) -> dict[str, Any]:
    """``page`` (``client_id``) picks ``action`` after another one and reads its boxes."""
    other = next(n for n in form.options(client_id) if n != action)
    for name in (other, action):
        page.set(uuid(form.choice), name)
        time.sleep(0.2)
    wait(lambda: form.picked(client_id) == action)
    time.sleep(0.2)  # the pick's callback (viser's thread pool) fills the boxes
    return {p.name: box.value_for(client_id) for p, box in form._fields[action]}


def test_set_dil_and_set_rotary_start_from_the_switches() -> None:
    with served_default_rig(1.0) as live, page_on(live) as page:
        assert live.dashboard.line is not None
        form = live.dashboard.line.controls.all_forms()["cpx"][0]
        drawn(live)
        (page_id,) = live.server.get_clients()
        # default.toml
        assert _pick(page, page_id, form, "set_dil") == {"dil1": True, "dil2": False}
        live.command("cpx", "set_dil", {"dil1": False, "dil2": True})
        live.command("cpx", "set_rotary", {"value": 0x0A1})
        drawn(live)
        assert _pick(page, page_id, form, "set_dil") == {"dil1": False, "dil2": True}
        assert _pick(page, page_id, form, "set_rotary") == {"value": "0A1"}  # hex, Tab. 5
        dil1 = uuid(form.field("set_dil", "dil1"))
        assert page.updates(dil1)[-1] is False  # what the page's box shows


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
