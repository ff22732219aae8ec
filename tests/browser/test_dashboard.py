"""The dashboard in headless Chromium, on the default rig: CNF, a fault, Reset fault.

Seed 000 §2 (CNF held >= 3 s: reset, scan, configuration stored), §7 / §7.1 / §7.7 (module 2
stops answering: emergency FF00 / 81 / 02 00 00 04 00, 0x5400 = 0x04000002, AL status code
0x8204, OP -> PREOP), §6.17 (Reset fault: the rising edge of 0x5200:1 resets the alarm once
its cause is gone). The simulation is paused and advanced by the test, so the screenshots are
taken at the same simulated instants every run.
"""

from __future__ import annotations

import pytest
from helpers import (
    LiveDashboard,
    choose,
    compare_screenshot,
    log_text,
    open_dashboard,
    state_value,
    text_input,
    wait_for_text,
    wait_until,
)

from app.ui.rail_scene import LIT

pytestmark = pytest.mark.browser

BOOT_S = 4.0  # power-up scan of 7 modules and INIT -> OP take ~3.2 s (docs/fastcat-coupler.md)


def _reset_bit(live: LiveDashboard) -> int:
    return int(live.command("fastcat", "read_object", {"index": 0x5200, "sub": 1}))


def _expect_state(page, row: str, text: str) -> None:
    wait_until(lambda: text in state_value(page, row), what=f"{row} to show {text!r}")


def test_cnf_fault_and_reset(live: LiveDashboard, page) -> None:
    open_dashboard(page, live)
    live.advance(BOOT_S)
    _expect_state(page, "ESM state", "OP")
    _expect_state(page, "Configuration", "none stored")

    # §2: hold CNF for more than three seconds, then release it.
    page.get_by_label("Hold CNF", exact=True).check()
    live.wait_for_state(lambda s: s["cnf"]["pressed"], "CNF pressed")
    live.advance(3.2)
    _expect_state(page, "CNF", "pressed 3.2 s")
    page.get_by_label("Hold CNF", exact=True).uncheck()
    live.wait_for_state(lambda s: s["cnf"]["phase"] == "resetting", "the CNF procedure")
    # Reset 0.5 s, bus set-up 1 s, then one module every 0.25 s (devices/fastcat/cnf.py).
    live.advance(2.6)
    snap = live.snapshot()
    assert snap["cnf"]["phase"] == "scanning" and snap["scan"]["done"] == 4
    _expect_state(page, "CNF", "scanning, scan 4/7")
    compare_screenshot(page, "cnf_scanning")  # red LEDs of modules 1..4 steady
    live.advance(1.8)  # scan over, configuration stored, back to OP (yellow LEDs lit)
    _expect_state(page, "Configuration", "matches flash")
    _expect_state(page, "ESM state", "OP")
    assert "DB16" in live.snapshot()["stored_config"]
    compare_screenshot(page, "after_scan")

    # §7.7: module 2 stops answering in OP.
    choose(page, "Fault", "0x04 MISSING_NODE_ANSWER")
    choose(page, "Target", "2 DI16")
    page.get_by_role("button", name="Inject").click()
    live.wait_for_state(lambda s: s["injected"], "the injected cause")
    live.advance(0.8)  # the master's failed retry comes 141 ms later (§7.7)
    _expect_state(page, "Fault active", "TRUE")
    assert state_value(page, "0x5400") == "0x04000002"
    assert state_value(page, "AL status code").startswith("0x8204 module 2")
    assert "PREOP" in state_value(page, "ESM state")
    log = log_text(page)
    assert "CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00')." in log
    assert "abnormal state change (from 'OP' to 'PREOP') with code 0x8204" in log
    assert "AL Status Code '0x8204'" in log
    compare_screenshot(page, "in_alarm")

    # §7: Reset fault does nothing while the cause is still there ...
    reset = page.get_by_label("Reset fault", exact=True)
    reset.check()
    wait_until(lambda: _reset_bit(live) == 1, what="0x5200:1 = 1")
    live.advance(0.1)
    assert live.snapshot()["fault_active"]
    # The box mirrors the bit and stays ticked: the note under it says why (the UI audit).
    note = page.locator("#fr-reset-note")
    wait_until(lambda: "rising edge (0 → 1)" in note.inner_text(), what="the Reset fault note")
    reset.uncheck()
    wait_until(lambda: _reset_bit(live) == 0, what="0x5200:1 = 0")
    live.advance(0.1)
    # ... and resets the alarm on its rising edge once the cause is gone (§6.17).
    page.get_by_role("button", name="Clear").click()
    live.wait_for_state(lambda s: not s["injected"], "the cause cleared")
    assert live.snapshot()["fault_active"], "clearing a cause must not reset the latch (§7)"
    reset.check()
    live.wait_for_state(lambda s: not s["fault_active"], "the reset")
    reset.uncheck()
    live.advance(2.7)  # the master retries every 2 s and brings the coupler back to OP
    _expect_state(page, "Fault active", "FALSE")
    _expect_state(page, "ESM state", "OP")
    assert state_value(page, "0x5400") == "0x00000000"
    assert state_value(page, "AL status code").startswith("0x0000")
    compare_screenshot(page, "after_reset")


def test_two_browsers_see_the_same_rig(live: LiveDashboard, browser) -> None:
    """A press in one browser shows in the other; a refusal only for whoever clicked."""
    pages = []
    for _ in range(2):
        context = browser.new_context(viewport={"width": 1280, "height": 720})
        pages.append(context.new_page())
    first, second = pages
    try:
        for p in pages:
            open_dashboard(p, live)
        live.advance(BOOT_S)
        for p in pages:
            _expect_state(p, "ESM state", "OP")
        first.get_by_label("Power", exact=True).uncheck()
        live.wait_for_state(lambda s: not s["powered"], "power off")
        _expect_state(second, "ESM state", "power off")
        wait_until(lambda: not second.get_by_label("Power", exact=True).is_checked(),
                   what="the Power checkbox to follow in the second browser")
        second.get_by_label("Power", exact=True).check()
        live.wait_for_state(lambda s: s["powered"], "power on")
        live.advance(BOOT_S)
        _expect_state(first, "ESM state", "OP")

        # A write to a read-only object is refused (SDO abort 0x06010002) for whoever clicked.
        # (The FastCAT's fault form no longer offers a target its code refuses, §7.5 / §7.6.)
        second.get_by_role("tab", name="Objects").click()
        text_input(second, "Object").fill("0x5400:0")
        text_input(second, "Value").fill("1")
        second.get_by_role("button", name="Write").click()
        wait_for_text(second, "Attempt to write a read only object")
        first.wait_for_timeout(500)
        assert first.get_by_text("Attempt to write a read only object").count() == 0
        assert not live.snapshot()["fault_active"]
    finally:
        for p in pages:
            p.context.close()


def test_object_dictionary_view(live: LiveDashboard, page) -> None:
    """§6: the dictionary of the detected modules, filtered; a read-only object refuses."""
    open_dashboard(page, live)
    live.advance(BOOT_S)
    page.get_by_role("tab", name="Objects").click()
    text_input(page, "Filter").fill("5400")
    wait_for_text(page, "Emergency data")
    table = page.locator("#fr-od")
    wait_until(lambda: "0x5400:0" in table.inner_text(), what="0x5400 in the table")
    assert "0x1008" not in table.inner_text()

    text_input(page, "Filter").fill("0x2104")  # AI8D (module 4) filter: 4000
    wait_until(lambda: "0x2134:0" in table.inner_text(), what="module 4's filter object")

    text_input(page, "Object").fill("0x5400:0")
    text_input(page, "Value").fill("1")
    page.get_by_role("button", name="Write").click()
    wait_for_text(page, "Attempt to write a read only object")


def _slot(live: LiveDashboard, slot: int) -> dict:
    return live.snapshot()["rail"][slot - 1]


def test_module_and_encoder_controls(live: LiveDashboard, page) -> None:
    """§6.30 / §6.27: the zero cycle of an AX2 encoder; §7.7: a module unplugged in OP."""
    open_dashboard(page, live)
    live.advance(BOOT_S)
    choose(page, "Module", "7 AX2")
    wait_for_text(page, "Shaft speed (rpm)")
    page.get_by_label("Shaft speed (rpm)", exact=True).fill("600")
    page.get_by_role("button", name="Set shaft speed").click()
    live.wait_for_state(lambda s: s["rail"][6]["encoders"][0]["rpm"] == 600.0, "600 rpm")
    page.get_by_label("Zero-cycle command enc 1", exact=True).check()
    live.wait_for_state(lambda s: s["rail"][6]["command"] & 0x1000, "0x7660 bit 12")
    live.advance(0.3)  # 600 rpm: a zero mark every 100 ms
    assert _slot(live, 7)["encoders"][0]["homed"]
    assert _slot(live, 7)["status"] & 0x1000  # 0x6660 bit 12: zero cycle done
    wait_for_text(page, "homed")

    choose(page, "Module", "2 DI16")
    page.get_by_role("button", name="Unplug").click()
    live.wait_for_state(lambda s: s["rail"][1]["type"] is None, "module 2 off the rail")
    live.advance(0.3)
    _expect_state(page, "Fault active", "TRUE")
    assert state_value(page, "0x5400") == "0x04000002"  # MISSING_NODE_ANSWER, module 2
    assert live.dashboard.scene_slots()[2] is None  # drawn as an empty slot
    # §7: a coupler alarm puts every module in alarm: all red LEDs steady.
    assert all(live.dashboard.scene_colors()[f"{n}.red"] == LIT["red"] for n in (1, 3, 7))
    choose(page, "Plug type", "DI16")
    page.get_by_role("button", name="Plug", exact=True).click()
    live.wait_for_state(lambda s: s["rail"][1]["type"] == "DI16", "module 2 back")
