"""The event log after a scenario Play (docs/dashboard.md "Event log"): loading a scenario
restarts the simulated clock at 0 on a factory-fresh rig, so the previous session's rows,
stamped later, sorted above the new run's and the top of the newest-first log showed stale
events (the trainee-eyes review, 39_scenario_later.png). Now the log starts afresh at a load:
the previous rows go, a row "scenario '...' started" is at the bottom, the new run above it.
"""

from __future__ import annotations

import html
import re
from collections.abc import Iterator

import pytest
import viser

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import EXAMPLES_DIR, load_scenario
from app.screenshots import free_port
from app.ui.dashboard import Dashboard

TIMEOUT_S = 60


def log_rows(dashboard: Dashboard) -> list[tuple[str, str, str]]:
    """(server, timestamp, message) of each row of the event log, newest first."""
    assert dashboard._panels is not None
    content = str(dashboard._panels.log._html.content)
    return [(html.unescape(s), html.unescape(t.replace("<br>", " ")), html.unescape(m))
            for s, t, m in re.findall(
                r'<td class="fr-srv">(.*?)</td><td class="fr-ts">(.*?)</td><td>(.*?)</td>',
                content)]


@pytest.fixture
def dashboard() -> Iterator[Dashboard]:
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    runtime.set_paused(True)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    dashboard = Dashboard(server, runtime)  # ticked by the test
    runtime.start()
    try:
        yield dashboard
    finally:
        runtime.stop()
        server.stop()


def test_a_scenario_load_starts_the_log_afresh(dashboard: Dashboard) -> None:
    runtime = dashboard.runtime
    # A session before the scenario: the line powered and a module pulled at 20 s.
    runtime.command("fastcat", "power", {"on": True}).result(timeout=TIMEOUT_S)
    runtime.advance(20_000_000).result(timeout=TIMEOUT_S)
    runtime.command("fastcat/2", "unplug", {}).result(timeout=TIMEOUT_S)
    runtime.advance(1_000_000).result(timeout=TIMEOUT_S)
    dashboard.tick()
    assert any("14.51.5" in ts for _, ts, _ in log_rows(dashboard))  # 14.51.30 + 21 s
    scenario = load_scenario(EXAMPLES_DIR / "cnf_scan.toml")
    dashboard.scenario_player.load(scenario)
    runtime.advance(2_000_000).result(timeout=TIMEOUT_S)
    dashboard.tick()
    rows = log_rows(dashboard)
    assert rows, "the new run logged nothing"
    # Nothing of the session before: every row is of the new run (epoch 14.51.30 + 2 s).
    stale = [r for r in rows if not re.search(r"14\.51\.3[0-2] ", r[1])]
    assert not stale, stale
    assert rows[-1][0] == "scenario" and rows[-1][2] == (
        f"» scenario '{scenario.name}' started: the rig is factory-fresh, the clock at 0 s")
    assert rows[-1][1] == "12/11/2019 14.51.30 000 ms"


def test_a_load_at_0_s_starts_the_log_afresh_too(dashboard: Dashboard) -> None:
    """A load while the clock is still at 0 s (another scenario picked before Play) puts no
    clock back: the log used to keep the first scenario's rows and never said the second
    one started. The load itself starts the run (the Player's generation)."""
    first = load_scenario(EXAMPLES_DIR / "cnf_scan.toml")
    dashboard.scenario_player.load(first)
    dashboard.tick()
    assert any(first.name in m for _, _, m in log_rows(dashboard))
    second = load_scenario(EXAMPLES_DIR / "module_lost_in_op.toml")
    dashboard.scenario_player.load(second)
    dashboard.tick()
    rows = log_rows(dashboard)
    assert rows[-1] == ("scenario", "12/11/2019 14.51.30 000 ms",
                        f"» scenario '{second.name}' started: the rig is factory-fresh, "
                        "the clock at 0 s")
    assert not [r for r in rows if first.name in r[2]], rows
    # The first scenario's caption ("The rig is switched on. The coupler scans ...") is gone.
    assert not [r for r in rows if "coupler scans its internal bus" in r[2]], rows


def test_restart_before_play_gives_no_repeated_rows(dashboard: Dashboard) -> None:
    """Restart before Play (the same scenario loaded twice at 0 s): the run's rows once each,
    not "x2" rows of both loads collapsed into one."""
    scenario = load_scenario(EXAMPLES_DIR / "cnf_scan.toml")
    dashboard.scenario_player.load(scenario)
    dashboard.tick()
    once = log_rows(dashboard)
    dashboard.scenario_player.player.restart()
    dashboard.tick()
    rows = log_rows(dashboard)
    assert not [r for r in rows if " x2, last " in r[2]], rows
    assert rows == once


def test_events_of_the_old_run_in_the_same_batch_stay_out(dashboard: Dashboard) -> None:
    """Events of the session before and of the new run taken in one tick: the load splits
    the batch where it happened (the journal's sequence number at the load), so the old
    run's rows never land under the new run's "started" row."""
    runtime = dashboard.runtime
    dashboard.tick()
    runtime.command("fastcat", "power", {"on": True}).result(timeout=TIMEOUT_S)
    runtime.command("fastcat/2", "unplug", {}).result(timeout=TIMEOUT_S)
    scenario = load_scenario(EXAMPLES_DIR / "cnf_scan.toml")
    dashboard.scenario_player.load(scenario)
    dashboard.tick()
    rows = log_rows(dashboard)
    assert rows[-1][2].startswith(f"» scenario '{scenario.name}' started"), rows
    assert not [r for r in rows if "module 2" in r[2] or "unplug" in r[2]], rows


def test_a_load_clears_every_drives_log(dashboard: Dashboard) -> None:
    """The Drive tab's log (app/ui/drive/drive_state.py DriveLog) had no caller of its clear:
    a drive's rows of the session before stayed under the new run, whichever drive the tab
    showed."""
    from devices.events import LogLine

    assert dashboard.drives is not None
    runtime = dashboard.runtime
    runtime.journal([LogLine(0, "drive", text="old run: homing started"),
                     LogLine(0, "drive_ec", text="old run: mode change")])
    runtime.submit(lambda: None).result(timeout=TIMEOUT_S)  # journalled
    dashboard.tick()
    log = dashboard.drives.words.log
    assert "old run: homing started" in log.html("drive")
    dashboard.scenario_player.load(load_scenario(EXAMPLES_DIR / "cnf_scan.toml"))
    dashboard.tick()
    assert "old run" not in log.html("drive") + log.html("drive_ec")


def test_a_load_starts_the_drive_plots_afresh(dashboard: Dashboard) -> None:
    """The drive plots (app/ui/drive/plots.py) took a new run from the clock going back at
    the next simulation step: a scenario loaded and left paused at 0 s (and one loaded right
    after another) kept the old run's curve, to be joined by the new run's samples. The load
    itself (Rig.loads) starts them afresh."""
    import numpy as np

    assert dashboard.drives is not None
    sampler, plots = dashboard.drives.sampler, dashboard.drives.plots
    run = [1]  # which run a sample is of: the plots' position

    sampler._snapshot = lambda: {"position_counts": run[0], "velocity": 0.0,
                                 "following_error": 0.0}
    runtime = dashboard.runtime
    runtime.advance(50_000).result(timeout=TIMEOUT_S)
    assert list(sampler.columns()[1]) == [1, 1]  # at 20 and 40 ms
    scenario = load_scenario(EXAMPLES_DIR / "cnf_scan.toml")
    for run[0] in (2, 3):  # the second load right after the first, 30 ms of run 2 between
        dashboard.scenario_player.load(scenario)
        dashboard.tick()
        assert len(sampler.columns()[0]) == 0, run
        plots.update(0.0, 0, force=True)  # unless the tick sent them
        assert not [v for chart in plots._charts for v in np.asarray(chart.data[1]) if v], run
        runtime.advance(30_000).result(timeout=TIMEOUT_S)
        dashboard.tick()
        t, position = sampler.columns()[:2]
        assert list(t) == [0.02] and list(position) == [run[0]], (t, position)


def test_a_load_clears_the_caption(dashboard: Dashboard) -> None:
    """The caption label above the rig (a sales engineer's narration) kept the previous
    scenario's last caption over a new one with none at 0 s: the player's panel hid it before
    the load, but a caption of the old run the dashboard had not taken yet (it ticks ~30 times
    a second; the old scenario plays on while the new rig is built) came in one batch with
    the load and was shown again. The load itself (the dashboard's split of its batch) hides
    it; a caption of the new run shows."""
    from devices.events import Caption

    runtime = dashboard.runtime
    quiet_start = load_scenario(EXAMPLES_DIR / "ax2_homing.toml")  # first caption 4.5 s
    assert not [s for s in quiet_start.steps if s.kind == "caption" and s.t_us == 0]
    runtime.journal([Caption(0, "scenario", text="old run: the cable is pulled")])
    runtime.submit(lambda: None).result(timeout=TIMEOUT_S)  # journalled, not yet taken
    dashboard.scenario_player.load(quiet_start)
    dashboard.tick()
    assert dashboard.caption == ""
    # Shown and taken before the load, then a load that is not the panel's (Player.restart).
    runtime.journal([Caption(0, "scenario", text="old run: shown")])
    runtime.submit(lambda: None).result(timeout=TIMEOUT_S)
    dashboard.tick()
    assert dashboard.caption == "old run: shown"
    dashboard.scenario_player.player.restart()
    dashboard.tick()
    assert dashboard.caption == ""
    # A scenario with a caption at 0 s shows it at the load.
    dashboard.scenario_player.load(load_scenario(EXAMPLES_DIR / "cnf_scan.toml"))
    dashboard.tick()
    assert dashboard.caption.startswith("The rig is switched on."), dashboard.caption
