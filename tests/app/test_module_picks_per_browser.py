"""The FastCAT tab's Module picker is each page's own, and so is what depends on its pick: the
Plug type preset, the encoder section, and the module the Rail buttons and Module I/O act on
(docs/dashboard.md "Several browsers"). Before, one trainee picking module 3 moved every
other page's Module picker and what its Unplug acted on: a classmate unplugged the wrong
module. Two websocket connections stand in for the browsers (tests/app/test_picks_per_browser.py)
on an open rig, where the Rail rows are everyone's."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from app.ui.panels.classroom_rig import ServedRig
from devices.fastcat.encoder import CMD_ZERO_CYCLE, COMMAND_INDEX
from devices.fastcat.module_od import object_index
from tests.app.form_page import fill, press
from tests.app.test_classroom_leak import Page, _wait
from tests.app.test_picks_per_browser import _ids, _settle, _widget
from tests.app.two_pages import powered, two_pages


def _powered_module_3_pulled(served: ServedRig) -> None:
    powered(served)
    served.runtime.command("fastcat/3", "unplug", {}).result(timeout=10)
    served.runtime.advance(100_000).result(timeout=30)
    served.dashboard.tick()


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages(prepare=_powered_module_3_pulled) as pages:
        yield pages


def _picked(live: ServedRig, pick: Any) -> tuple[str, str]:
    """What each page picked in one per-page picker (its ``value_for``): first's, second's."""
    one, two = _ids(live)
    return pick.value_for(one), pick.value_for(two)


def _rail(live: ServedRig) -> list[dict[str, Any]]:
    return list(live.runtime.submit(
        lambda: live.rig.device("fastcat").snapshot()["rail"]).result(timeout=10))


def _visible(page: Page, uuid: str) -> list[Any]:
    return [m["updates"]["visible"] for m in page.received()
            if m.get("type") == "GuiUpdateMessage" and m.get("uuid") == uuid
            and "visible" in (m.get("updates") or {})]


def _folder(page: Page, label: str) -> str:
    return str(_wait(lambda: next((m["uuid"] for m in page.received()
                                   if (m.get("props") or {}).get("label") == label), None)))


def test_a_module_picked_on_one_page_is_not_the_other_page_s(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    picker = _widget(first, "Module", "3 (empty)")
    assert _widget(second, "Module", "3 (empty)") == picker  # one server-level widget
    plug_type = _widget(first, "Plug type", "DO16")
    first.set(picker, "3 (empty)")
    _wait(lambda: "DO16" in first.updates(plug_type))  # seed 000 §2: what belongs there
    _settle(live)
    assert "3 (empty)" not in second.updates(picker)
    assert "DO16" not in second.updates(plug_type)
    modules = live.dashboard._panels.modules  # type: ignore[union-attr]
    assert _picked(live, modules.pick) == ("3 (empty)", "1 DB16")


def test_the_other_page_s_unplug_acts_on_its_own_pick(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    picker = _widget(first, "Module", "3 (empty)")
    first.set(picker, "3 (empty)")
    _settle(live)
    rail = _widget(second, "Rail", None)
    second.set(rail, "Unplug")  # a button group's click
    _wait(lambda: _rail(live)[0]["type"] is None)
    assert [e["type"] for e in _rail(live)[1:3]] == ["DI16", None]
    # The second page's pick follows its slot's new label; the first page keeps its own.
    live.runtime.advance(100_000).result(timeout=30)
    _settle(live)
    modules = live.dashboard._panels.modules  # type: ignore[union-attr]
    assert _picked(live, modules.pick) == ("3 (empty)", "1 (empty)")
    assert "3 (empty)" not in second.updates(picker)
    live.runtime.command("fastcat/1", "plug", {"type": "DB16"}).result(timeout=10)
    live.runtime.advance(100_000).result(timeout=30)


def test_the_encoder_section_shows_on_the_page_that_picked_the_ax2(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    picker = _widget(first, "Module", "7 AX2")
    folder = _folder(first, "Encoder (AX2)")
    first.set(picker, "7 AX2")
    _wait(lambda: True in _visible(first, folder))
    _settle(live)
    assert True not in _visible(second, folder)
    first.set(picker, "2 DI16")
    _wait(lambda: _visible(first, folder)[-1] is False)


def _pick(first: Page, second: Page, firsts: str, seconds: str) -> None:
    """``first`` picks module ``firsts``, then ``second`` ``seconds`` (one server-level
    picker, its value each page's own)."""
    picker = _widget(first, "Module", firsts)
    first.set(picker, firsts)
    second.set(picker, seconds)


def _read(live: ServedRig, index: int) -> int:
    return int(live.runtime.submit(lambda: live.rig.apply(
        "fastcat", "read_object", {"index": index, "sub": 0})).result(timeout=10))


def test_module_powered_shows_and_commands_each_page_s_module(
        served: tuple[ServedRig, Page, Page]) -> None:
    """§2: a module's supply. The box shows the page's own module's and its click commands
    that module; the other page keeps its module's."""
    live, first, second = served
    live.runtime.command("fastcat/6", "module_power", {"on": False}).result(timeout=10)
    live.runtime.advance(100_000).result(timeout=30)
    box = _widget(first, "Module powered", None)
    _pick(second, first, "2 DI16", "6 AI8TC")
    _wait(lambda: False in first.updates(box))
    _settle(live)
    assert False not in second.updates(box)
    first.set(box, True)
    _wait(lambda: _rail(live)[5]["powered"])
    assert all(e.get("powered", True) for e in _rail(live))


def test_a_zero_cycle_click_commands_the_page_s_ax2(
        served: tuple[ServedRig, Page, Page]) -> None:
    """§6.30: bit 12 of 0x7600 + 0x10 * (N - 1), of the module the clicking page picked."""
    live, first, second = served
    _pick(first, second, "7 AX2", "2 DI16")
    _settle(live)
    index = object_index(COMMAND_INDEX, 7)
    box = _widget(first, "Zero-cycle command enc 1", None)
    first.set(box, True)
    _wait(lambda: _read(live, index) & CMD_ZERO_CYCLE[0])
    live.runtime.advance(100_000).result(timeout=30)
    _settle(live)
    assert first.updates(box)[-1] is True  # the model's bit, on the page that set it
    assert True not in second.updates(box)  # its DI16 has no such bit
    first.set(box, False)
    _wait(lambda: not _read(live, index) & CMD_ZERO_CYCLE[0])


def _rpm(live: ServedRig, slot: int) -> list[float]:
    return [float(e["rpm"]) for e in _rail(live)[slot - 1]["encoders"]]


def test_set_shaft_speed_sends_the_clicking_page_s_encoder_and_speed(
        served: tuple[ServedRig, Page, Page]) -> None:
    """The encoder section is each page's (its folder, text and zero-cycle boxes), and so are
    its Encoder and Shaft speed boxes: what one page typed there was every page's, and a
    classmate's Set shaft speed turned the shaft at it."""
    live, first, second = served
    _pick(first, second, "7 AX2", "7 AX2")
    encoder, speed = _widget(first, "Encoder", "2"), _widget(first, "Shaft speed (rpm)", None)
    first.set(encoder, "2")
    first.set(speed, 120.0)
    _settle(live)
    assert "2" not in second.updates(encoder)
    assert 120.0 not in second.updates(speed)
    button = _widget(second, "Set shaft speed", None)
    second.set(button, True)  # its own boxes: encoder 1 at 60 rpm
    _wait(lambda: _rpm(live, 7)[0] == 60.0)
    first.set(button, True)
    _wait(lambda: _rpm(live, 7)[1] == 120.0)
    assert _rpm(live, 7) == [60.0, 120.0]
    for which in (1, 2):  # the shafts stand still again for the other tests
        live.runtime.command("fastcat/7", "set_shaft_speed",
                             {"encoder": which, "rpm": 0.0}).result(timeout=10)


def test_unplug_then_plug_are_commanded_in_click_order_with_the_page_s_type(
        served: tuple[ServedRig, Page, Page]) -> None:
    """§2: modules plugged and unplugged by hand; Plug puts in the type the page chose."""
    live, first, second = served
    _pick(second, first, "2 DI16", "4 AI8D")
    plug_type = _widget(second, "Plug type", "DI16")
    second.set(plug_type, "DI16")
    first.set(plug_type, "AO4")
    _settle(live)
    rail = _widget(second, "Rail", None)
    second.set(rail, "Unplug")
    second.set(rail, "Plug")
    live.runtime.advance(100_000).result(timeout=30)
    _settle(live)
    assert [e["type"] for e in _rail(live)[1:4]] == ["DI16", None, "AI8D"]


def test_a_slave_target_picked_on_one_page_is_not_the_other_page_s(
        served: tuple[ServedRig, Page, Page]) -> None:
    """The Line tab's Slave actions Target (a CPX-E-EC module): page A's pick of cpx/2 moves
    nothing on page B, and B's Apply acts on B's own pick, cpx/1 (a 16DI: set_input)."""
    live, first, second = served
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    target = _widget(first, "Target", "cpx/2")
    second.set(target, "cpx/1")
    first.set(target, "cpx/2")
    _settle(live)
    _settle(live)  # the actions both picks take, read and offered
    assert "cpx/2" not in second.updates(target)
    assert "cpx/1" not in first.updates(target)
    _folder, form = controls.forms["cpx"]
    _one, two = _ids(live)
    assert "set_input" in form.options(two)  # B's 16DI takes it
    fill(second, form, "set_input", channel=5, on=True)  # the form is each page's own too
    press(second, form)
    _wait(lambda: live.runtime.submit(
        lambda: live.rig.device("cpx").modules[0].field_inputs[5]).result(timeout=10))


def _injected(live: ServedRig) -> list[dict[str, Any]]:
    return list(live.runtime.submit(
        lambda: live.rig.device("fastcat").snapshot()["injected"]).result(timeout=10))


def test_the_fault_pickers_are_each_page_s_and_inject_sends_the_page_s_fault(
        served: tuple[ServedRig, Page, Page]) -> None:
    """An open rig's Faults form (seed 000 §7.5 / §7.6): page A's Table, Fault and Target
    move nothing on page B, whose Inject sends B's own pick (coupler code 0x01, no module)."""
    live, first, second = served
    control = live.dashboard._panels.control  # type: ignore[union-attr]
    table = _widget(first, "Table", "module codes (§7.6)")
    fault = _widget(first, "Fault", "0x02 IOFAULT")
    target = _widget(first, "Target", "coupler (no module)")
    ai8d = next(o for o in control._target.options if o.endswith("AI8D"))
    first.set(table, "module codes (§7.6)")
    _settle(live)
    first.set(fault, "0x02 IOFAULT")
    first.set(target, ai8d)
    _settle(live)
    for uuid, picked in ((table, "module codes (§7.6)"), (fault, "0x02 IOFAULT"),
                         (target, ai8d)):
        assert picked not in second.updates(uuid)
    assert _picked(live, control._fault) == ("0x02 IOFAULT", "0x01 MODULE_CHANGED")
    injection = _widget(second, "Injection", None)
    second.set(injection, "Inject")
    _wait(lambda: _injected(live))
    assert _injected(live) == [{"fault": "MODULE_CHANGED", "code": 1, "module": None}]
    second.set(injection, "Clear")
    _wait(lambda: not _injected(live))


def _cables(live: ServedRig) -> list[bool]:
    return [bool(c["master_pulled"]) for c in live.runtime.submit(
        lambda: live.rig.device("master").snapshot()["cables"]).result(timeout=10)]


def test_the_master_s_cable_picker_is_each_page_s_and_pull_pulls_the_page_s_cable(
        served: tuple[ServedRig, Page, Page]) -> None:
    """An open rig's Line tab, Cables and power (seed 003): page A's pick of cable 2 moves
    nothing on page B, whose Pull pulls B's own pick, cable 3; the pick keeps its cable when
    the list marks it pulled."""
    live, first, second = served
    cable = _widget(first, "Cable", "2 trscat -> cpx")
    second.set(cable, "3 cpx -> drive_ec-ecat")
    first.set(cable, "2 trscat -> cpx")
    _settle(live)
    assert "2 trscat -> cpx" not in second.updates(cable)
    assert "3 cpx -> drive_ec-ecat" not in first.updates(cable)
    second.set(_widget(second, "Cable plug", None), "Pull")
    _wait(lambda: _cables(live)[3])
    assert _cables(live) == [False, False, False, True]
    live.runtime.advance(100_000).result(timeout=30)
    _settle(live)
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    assert _picked(live, controls.cable) == ("2 trscat -> cpx", "3 cpx -> drive_ec-ecat (pulled)")
    second.set(_widget(second, "Cable plug", None), "Plug")
    _wait(lambda: not any(_cables(live)))
