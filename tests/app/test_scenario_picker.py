"""The Scenario tab on the default dashboard (``python -m app``): the library lists every
scenario of ``static/scenarios/``, also those written for another rig file (nine analog
modules). Those are marked in the picker with the rig they need, listed after the ones that
play here, and Play on one is refused with a short notice that gives the command to serve its
rig first; the two device lists go to the server log, not into the notice (a notice of ~1,200
characters was clipped, title and fix cut off). The EtherCAT line's scenarios run on the
default rig, which is that line: they play here, unmarked (before, they named
ethercat_line.toml, whose drive was then drive_ecat, and Play refused them)."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import load_scenario
from app.screenshots import free_port
from app.ui.panels.scenario_player import CHOOSE, PLAY, ScenarioPlayerPanel, library

NINE_RIG = Path("static/rigs/nine_analog.toml")
LINE_SCENARIOS = ("cable_pulled", "cpx_short_circuit", "dc_sync_lost",
                  "trscat_expansion_mismatch", "trscat_outputs_fallback",
                  "fastcat_sm_watchdog", "fastcat_address_check")
# Rig files with the default rig's devices, which a load installs in place (app/player.py
# compatible): fastcat_switch_3.toml is the default rig with the FastCAT's switch at 3.
PLAY_HERE = {DEFAULT_RIG.resolve(), (DEFAULT_RIG.parent / "fastcat_switch_3.toml").resolve()}


class _Client:
    client_id = 1

    def __init__(self) -> None:
        self.notes: list[tuple[str, str, str]] = []

    def add_notification(self, title: str, body: str, color: str = "",
                         auto_close_seconds: Any = None) -> None:
        self.notes.append((title, body, color))


@pytest.fixture
def panel() -> Iterator[ScenarioPlayerPanel]:
    """The panel on the default rig's runtime, never started (a refused load touches nothing)."""
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        yield ScenarioPlayerPanel(server, runtime)
    finally:
        server.stop()


def _rig_of(path: Path) -> Path:
    rig = load_scenario(path).rig
    return Path(rig).resolve() if rig is not None else DEFAULT_RIG.resolve()


def test_scenarios_for_another_rig_are_marked_and_listed_last(
        panel: ScenarioPlayerPanel) -> None:
    options = list(panel._pick.options)
    assert options[0] == CHOOSE
    entries = library()
    assert len(options) == 1 + len(entries)  # nothing left out
    here = [e for e in entries if _rig_of(e.path) in PLAY_HERE]
    other = [e for e in entries if e not in here]
    assert here and other  # the library has both kinds
    # The ones that play here keep their plain name, first.
    assert options[1:1 + len(here)] == [e.label for e in here]
    for label, entry in zip(options[1 + len(here):], other, strict=True):
        stem = _rig_of(entry.path).stem
        assert label == f"[rig {stem}] {entry.label}"
    assert "[rig nine_analog] Max 8 analog" in options  # too_many_analog.toml's label
    # The empty status tells how to play the marked ones.
    status = str(panel._status.content)
    assert "[rig NAME]" in status
    assert "python -m app --rig static/rigs/nine_analog.toml" in status
    assert "ethercat_line" not in status


@pytest.mark.parametrize("stem", LINE_SCENARIOS)
def test_the_line_scenarios_play_on_the_default_rig(panel: ScenarioPlayerPanel,
                                                     stem: str) -> None:
    """The default rig is the EtherCAT line: its scenarios are listed plainly, Play takes them
    (fastcat_address_check with its own rig file, whose devices are the default rig's)."""
    scenario = load_scenario(Path("static/scenarios") / f"{stem}.toml")
    assert panel.player.mismatch(scenario) is None
    assert scenario.label in panel._pick.options


def test_play_on_another_rig_is_refused_short_fix_first(
        panel: ScenarioPlayerPanel, caplog: pytest.LogCaptureFixture) -> None:
    client = _Client()
    panel._pick.set_all(next(o for o in panel._pick.options if "Max 8 analog" in o))
    with caplog.at_level(logging.WARNING):
        panel._run(client, PLAY)  # type: ignore[arg-type]
    [(title, body, color)] = client.notes
    assert (title, color) == ("Scenario: Play refused", "red")
    assert len(body) <= 250, body  # fits the notice without clipping
    assert body.startswith(f"Serve its rig: python -m app --rig {NINE_RIG}"), body
    assert "drive_co" not in body and "drive_ec (" not in body  # no device lists
    # The device lists are in the log, for whoever wants the detail.
    assert any("drive_co (servo)" in r.getMessage() for r in caplog.records)
    assert panel.player.view().scenario is None  # nothing loaded


def _hint(panel: ScenarioPlayerPanel) -> str | None:
    """The hint a page gets for its pick (a new page's here: each page's own on an open rig,
    tests/app/test_scenario_pick_per_page.py)."""
    return panel._details().get(panel._pick.value_for(None))


def test_the_picked_scenario_is_whole_in_the_hint(panel: ScenarioPlayerPanel) -> None:
    """The box cuts a long name; its hint gives the name, the file and the first sentence."""
    assert panel._pick.handle.hint is None and _hint(panel) is None  # nothing picked yet
    entry = next(e for e in library() if e.path.name == "cpx_short_circuit.toml")
    panel._pick.set_all(entry.label)  # "CPX-E-EC: short circuit", the file's label
    assert _hint(panel) == (f"{entry.scenario.name} (cpx_short_circuit.toml): Seed 002 "
                            "§2.5: an output of the CPX-E-8DO (module 2) is shorted while "
                            "it is on.")


def test_the_picked_scenario_is_named_whole_in_the_status(panel: ScenarioPlayerPanel) -> None:
    """The closed box cuts a long name ("[rig ethercat_line] CPX-E-EC: short circ"): the
    line under the controls (each page's own on an open rig) names the picked scenario whole
    before Play, and for one marked for another rig the command that serves it, so nobody
    needs to hover or press Play to read it."""
    entry = next(e for e in library() if e.path.name == "cpx_short_circuit.toml")
    panel._pick.set_all(entry.label)
    status = panel.page_picked(None)
    assert f"Picked: <b>{entry.scenario.name}</b> (cpx_short_circuit.toml)" in status, status
    assert "Serve its rig" not in status
    marked = next(o for o in panel._pick.options if o.startswith("[rig nine_analog]"))
    panel._pick.set_all(marked)
    status = panel.page_picked(None)
    assert "Picked: <b>Too many analog modules</b> (too_many_analog.toml)" in status, status
    assert "written for static/rigs/nine_analog.toml: serve it with python -m app --rig " \
        "static/rigs/nine_analog.toml" in status, status


# The closed box holds about 170 px of text at 1280x720, some 30 characters of its font
# (tests/browser/test_picker_text.py measures each option in Chromium).
LABEL_CHARS = 30


def test_every_shipped_scenario_fits_the_closed_box(panel: ScenarioPlayerPanel) -> None:
    """A long name has a short ``label`` in its file (the box cut "CANopen drive: motor
    overtemperatu"); the mark of another rig counts too."""
    long = [o for o in panel._pick.options if len(o) > LABEL_CHARS]
    assert long == []


def test_a_label_keeps_the_whole_name_in_the_hint_and_the_status(
        panel: ScenarioPlayerPanel) -> None:
    entry = next(e for e in library() if e.path.name == "canopen_drive_alarm_reset.toml")
    name = "CANopen drive: motor overtemperature, EMCY and fault reset"
    assert entry.scenario.name == name and entry.label == entry.scenario.label != name
    panel._pick.set_all(entry.label)
    assert str(_hint(panel)).startswith(f"{name} (canopen_drive_alarm_reset.toml): ")
    assert f"Picked: <b>{name}</b>" in panel.page_picked(None)
