"""The CPX-E-EC's rotary switches in the Line tab's slave form, as seed 002 Tab. 5 writes
them: three hex digits, "0 ... 4095 (1h ... FFFh)", and the Slave tab's Switches row shows
them so ("rotary 07B"). Before, the form's box took a decimal number: a trainee told to set
"07B" had to type 123. Now the box takes the hex digits ("07B", "7B", "0x07B", "7Bh"); every
digit string is hex, as on the switches, so "123" is 0x123; anything else is refused in words
before a command goes (docs/cpx-e-ec.md choice 41). The model's set_rotary keeps its integer.
"""

from __future__ import annotations

import time
from typing import Any

import pytest
from form_page import fill, page_on, press, uuid
from served_dashboard import drawn, served_default_rig
from viser_page import Page, wait

from app.screenshots import ServedRig
from app.ui.line.rotary_entry import rotary_from_text
from app.ui.panels.client_action_form import ClientActionForm
from devices.device import CommandError


def _rotary_form(live: ServedRig, page: Page) -> tuple[ClientActionForm, int]:
    """The CPX-E-EC's operating form with set_rotary picked by ``page``, and the page's id."""
    form = live.dashboard.line.controls.all_forms()["cpx"][0]  # type: ignore[union-attr]
    drawn(live)
    (page_id,) = live.server.get_clients()
    other = next(n for n in form.options(page_id) if n != "set_rotary")
    for name in (other, "set_rotary"):
        page.set(uuid(form.choice), name)
        time.sleep(0.2)
    wait(lambda: form.picked(page_id) == "set_rotary")
    time.sleep(0.2)  # the pick's callback (viser's thread pool) fills the boxes
    return form, page_id


def _typed(form: ClientActionForm, page_id: int) -> str:
    return str(form.field("set_rotary", "value").value_for(page_id))


def _rotary(live: ServedRig) -> int:
    cpx = live.runtime.rig.device("cpx")
    return int(live.runtime.submit(lambda: cpx.switches.rotary).result(timeout=10))


@pytest.mark.parametrize(("text", "value"), [
    ("07B", 0x07B), ("7b", 0x07B), ("0x07B", 0x07B), ("0X7b", 0x07B), ("7Bh", 0x07B),
    (" 0A1 ", 0x0A1), ("000", 0), ("0", 0), ("FFF", 0xFFF), ("fffh", 0xFFF),
    ("123", 0x123),  # hex, as the switches read it: not decimal 123
])
def test_the_switches_hex_digits(text: str, value: int) -> None:
    assert rotary_from_text(text) == value


@pytest.mark.parametrize(("text", "said"), [
    ("", "three hex digits"), ("XYZ", "three hex digits"), ("-1", "three hex digits"),
    ("0x", "three hex digits"), ("1.5", "three hex digits"),
    ("1000", "0x1000 is above FFF"), ("4095", "0x4095 is above FFF"),
])
def test_a_wrong_entry_says_what_the_switches_take(text: str, said: str) -> None:
    with pytest.raises(CommandError, match=said) as refused:
        rotary_from_text(text)
    assert "000 ... FFF" in str(refused.value)


def test_the_form_takes_the_address_as_tab5_writes_it() -> None:
    with served_default_rig(1.0) as live, page_on(live) as page:
        form, page_id = _rotary_form(live, page)
        assert _typed(form, page_id) == "000"  # as the Switches row shows it
        fill(page, form, "set_rotary", value="07B")
        press(page, form)
        wait(lambda: _rotary(live) == 0x07B)
        form, page_id = _rotary_form(live, page)  # picked again: from the switches' digits
        assert _typed(form, page_id) == "07B"
        fill(page, form, "set_rotary", value="0x0A1")
        press(page, form)
        wait(lambda: _rotary(live) == 0x0A1)


def test_a_wrong_entry_is_refused_on_the_page_and_sends_nothing() -> None:
    with served_default_rig(1.0) as live, page_on(live) as page:
        form, _ = _rotary_form(live, page)
        fill(page, form, "set_rotary", value="1000")
        press(page, form)

        def refusal() -> dict[str, Any] | None:
            return next((m for m in page.received()
                         if m.get("type") == "NotificationShowMessage"), None)
        shown = wait(refusal)
        drawn(live)
        assert _rotary(live) == 0  # default.toml's, untouched
        props = shown["props"]
        assert props["title"] == "set_rotary refused" and props["color"] == "red"
        assert "0x1000 is above FFF" in props["body"] and "000 ... FFF" in props["body"]
