"""The scenario player and the code decoder in headless Chromium, on the default rig.

static/scenarios/module_lost_in_op.toml (seed 000 §7.1, §7.7: module 2 stops answering in OP,
emergency FF00 / 81 / 02 00 00 04 00, AL status code 0x8204) picked, played at 10x, paused,
stepped and restarted from the Scenario tab; the decoder's Codes tab decodes a pasted code and
a code the rig reported.
"""

from __future__ import annotations

from typing import Any

import pytest
from helpers import LiveDashboard, choose, open_dashboard, text_input, wait_until

from app.player import Status
from devices.events import Caption

pytestmark = pytest.mark.browser

SCENARIO = "Module 2 lost in OP"  # the picker shows the file's label
OP_CAPTION = ("The line powers up and reaches OP: the FastCAT's RUN LED on, its modules' "
              "yellow LEDs blinking.")
CAPTION = "Module 2 (DI16) is pulled off the rail while the line is in OP."


def player_text(page) -> str:
    return str(page.locator("#fr-player").inner_text())


def player_data(page, key: str) -> str:
    return str(page.locator("#fr-player").get_attribute(f"data-{key}"))


def test_pick_play_caption_pause_step_restart(live: LiveDashboard, page) -> None:
    player = live.dashboard.scenario_player.player
    open_dashboard(page, live)
    page.get_by_role("tab", name="Scenario", exact=True).click()
    assert "No scenario loaded" in player_text(page)
    choose(page, "Scenario", SCENARIO)
    # 1x leaves ten wall seconds between the caption (6 s) and the end (16 s) for the Pause
    # click: at 10x a loaded machine let the scenario finish first ("finished", not "paused").
    choose(page, "Speed", "2x")
    wait_until(lambda: live.runtime.speed == 2.0, what="speed 2x")
    choose(page, "Speed", "1x")
    wait_until(lambda: live.runtime.speed == 1.0, what="speed 1x")

    page.get_by_role("button", name="Play", exact=True).click()
    wait_until(lambda: player.view().status is Status.PLAYING, what="playing")
    # The caption at 6 s: in the panel, and above the rail (the dashboard's label).
    wait_until(lambda: CAPTION in player_text(page), timeout=60, what="the caption")
    wait_until(lambda: live.dashboard.caption == CAPTION, what="the caption above the rail")
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: live.runtime.paused, what="the pause")
    wait_until(lambda: player_data(page, "status") == "paused", what="'paused' shown")
    # The pause is a flag the simulation thread reads between steps: a step under way when it
    # came ends first. After a round trip the clock holds.
    live.runtime.submit(lambda: None).result(timeout=10)
    held = live.runtime.rig.clock.now_us
    live.runtime.submit(lambda: None).result(timeout=10)
    assert live.runtime.rig.clock.now_us == held
    # Where the pause lands depends on the machine: each caption due by then, at its time.
    # (The next caption is at 8 s; a loaded CI machine paused after it, one run in three.)
    scenario = player.view().scenario
    assert scenario is not None
    due = [(s.t_us, s.text) for s in scenario.steps if s.kind == "caption" and s.t_us <= held]
    captions = [e for e in live.runtime.events_since(0)[1] if isinstance(e, Caption)]
    assert [(c.t_us, c.text) for c in captions] == due
    assert due[:2] == [(500_000, OP_CAPTION), (6_000_000, CAPTION)]

    # Step: to the next step's instant, paused there.
    before = player.view()
    assert before.next_step is not None
    page.get_by_role("button", name="Step", exact=True).click()
    wait_until(lambda: player.view().applied > before.applied, what="the step")
    assert live.runtime.rig.clock.now_us == before.next_step.t_us
    assert live.runtime.paused

    # Restart: factory-fresh rig at t = 0, narration cleared.
    page.get_by_role("button", name="Restart", exact=True).click()
    wait_until(lambda: player.view().generation == before.generation + 1, what="the restart")
    assert live.runtime.rig.clock.now_us == 0 and player.view().status is Status.READY
    wait_until(lambda: player_data(page, "t-us") == "0", what="t = 0 shown")
    assert "ready" in player_text(page) and live.dashboard.caption == ""


def decode_typed(page: Any, code: str, meaning: str, what: str) -> None:
    """Type ``code`` in the Codes tab, see ``meaning``, then press Decode and see it again.

    The box decodes as it is typed into; the answer is awaited before the click because
    viser's page sends the latest change of any control per 50 ms window (docs/dashboard.md
    "Fast clicks and viser's client"): a Decode click inside the window the previous click
    opened took the place of the typed text, and the server decoded the old code (a CI run
    timed out on the Pegaso line that way)."""
    result = page.locator("#fr-decoded")
    text_input(page, "Code").fill(code)
    wait_until(lambda: meaning in result.inner_text(), what=what)
    page.get_by_role("button", name="Decode").click()
    wait_until(lambda: meaning in result.inner_text(), what=f"{what} after Decode")


def test_decoder_tab(live: LiveDashboard, page) -> None:
    open_dashboard(page, live)
    page.get_by_role("tab", name="Codes", exact=True).click()
    result = page.locator("#fr-decoded")
    decode_typed(page, "0x8204", "MISSING_NODE_ANSWER", what="the meaning")
    assert "module 2" in result.inner_text()

    # §7.3 as printed, pasted into the box (which drops the line breaks): data high byte first
    decode_typed(page, "ERR CODE\t[0xFF00]ERR REG\tByte 2 [0x81] Byte 0"
                 "ERR DATA\t[0x00 00 0B 00 02] basso", "TARATURA on module 2",
                 what="the Pegaso line")

    # §7.7: module 2 stops answering in OP; its emergency shows up under "Reported".
    live.advance(4.0)
    live.command("fastcat/2", "unplug")
    live.advance(1.0)
    choose(page, "Reported", "emergency FF00 81 02 00 00 04 00")
    wait_until(lambda: "FF00 81 02 00 00 04 00" in result.inner_text(), what="the pick")
    text = result.inner_text()
    assert "Coupler alarm 0x04 MISSING_NODE_ANSWER on module 2" in text
