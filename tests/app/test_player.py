"""The scenario player on a live runtime: play, pause, step, restart, speed, and the events.

The contract (docs/scenarios.md "Playing a scenario in the dashboard"): a scenario played live
gives the model events of ``scenario run`` at the same simulated times, captions and
checkpoints included, whatever the speed, the pauses and the steps. The rig is a small FastCAT
(seed 000 §2 power-up, §7.7 a module that stops answering) so that every test runs fast.
Waits are on the simulation thread (a queued no-op returns once the thread went round), never
fixed sleeps.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.player import MAX_SPEED, MIN_SPEED, Player, Status, reset_in_place
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import Scenario, ScenarioError, load_scenario, parse_scenario, run_scenario
from devices.events import Caption, Checkpoint, Event

RIG = """
[rig]
name = "small"
seed = 3

[[fastcat]]
id = "fastcat"
modules = ["DB16", "DI16", "AO4"]
"""

# Times off the 1 ms grid on purpose: steps land where `scenario run` puts them.
SCENARIO = """
[scenario]
name = "small: module 2 lost"
rig = "small.toml"
duration_s = 8

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true

[[step]]
at = 0.0
caption = "Power on."

[[step]]
at = 4.0005
checkpoint = "op"

[[step]]
at = 4.5
caption = "Module 2 is pulled off the rail."

[[step]]
after = 0.0
target = "fastcat/2"
action = "unplug"

[[step]]
at = 5.2345
checkpoint = "in_alarm"

[[step]]
at = 6.0
target = "fastcat/2"
action = "plug"
type = "DI16"

[[step]]
at = 6.5
target = "fastcat"
action = "write_object"
index = 0x5100
sub = 1
value = 1
expect_error = true
"""

WAIT_S = 60.0


def lines(events: list[Event]) -> list[str]:
    return [json.dumps(e.to_record(), default=str) for e in events]


@pytest.fixture
def scenario(tmp_path: Path) -> Scenario:
    (tmp_path / "small.toml").write_text(RIG, encoding="utf-8")
    return parse_scenario(SCENARIO, "small_scenario.toml", base_dir=tmp_path)


@pytest.fixture
def reference(scenario: Scenario) -> list[str]:
    assert scenario.rig is not None
    run = run_scenario(scenario, build_rig(load_rig_spec(scenario.rig)))
    assert not run.failures
    return lines(run.events)


class Live:
    """A running runtime on the scenario's rig (already powered and run for a while, as a
    served rig is), its journal, and a player."""

    def __init__(self, scenario: Scenario) -> None:
        assert scenario.rig is not None
        self.runtime = Runtime(build_rig(load_rig_spec(scenario.rig)), speed=1.0)
        self.events: list[Event] = []
        self.runtime.add_listener(self.events.extend)
        self.runtime.start()
        self.runtime.command("fastcat", "power", {"on": True}).result(timeout=WAIT_S)
        self.runtime.advance(300_000).result(timeout=WAIT_S)
        self.player = Player(self.runtime)

    def quiet(self) -> None:
        """Stop the clock and forget the events so far (what the served rig did before)."""
        self.runtime.set_paused(True)
        self.barrier()
        self.events.clear()

    def barrier(self, rounds: int = 1) -> None:
        """Let the simulation thread go round ``rounds`` times."""
        for _ in range(rounds):
            self.runtime.submit(lambda: None).result(timeout=WAIT_S)

    def wait(self, predicate, what: str) -> None:
        deadline = time.monotonic() + WAIT_S
        while not predicate():
            assert time.monotonic() < deadline, f"timed out waiting for {what}"
            self.barrier()

    def untouched(self) -> tuple[object, int, int]:
        """What a refused load must leave as it was. The rig keeps running meanwhile (a
        refusal must not pause it), so its clock only moves on, never back."""
        return self.runtime.rig, self.t_us, len(self.events)

    def assert_untouched(self, before: tuple[object, int, int]) -> None:
        rig, t_us, n_events = before
        self.barrier()
        assert self.runtime.rig is rig and not self.runtime.paused
        assert self.t_us >= t_us, "the clock went back: the rig was reset"
        assert all(e.t_us >= t_us for e in self.events[n_events:])
        assert self.player.view().status is Status.EMPTY

    @property
    def t_us(self) -> int:
        return self.runtime.rig.clock.now_us


@pytest.fixture
def live(scenario: Scenario) -> Iterator[Live]:
    rig = Live(scenario)
    yield rig
    rig.runtime.stop()


def test_play_gives_the_events_of_scenario_run(live: Live, scenario: Scenario,
                                               reference: list[str]) -> None:
    live.quiet()
    live.player.load(scenario)
    assert live.t_us == 0 and live.player.view().status is Status.READY
    live.player.set_speed(MAX_SPEED)
    live.player.play()
    assert live.player.view().status is Status.PLAYING
    live.wait(lambda: live.player.view().status is Status.FINISHED, "the end")
    assert live.runtime.paused, "the player pauses the rig at the scenario's end"
    played = [e for e in live.events if e.t_us <= scenario.end_us]
    assert lines(played) == reference


def test_step_goes_from_instant_to_instant(live: Live, scenario: Scenario,
                                           reference: list[str]) -> None:
    live.quiet()
    live.player.load(scenario)
    # Steps at 0 s are applied by the load, before the first simulation step.
    assert live.player.view().applied == 2 and live.player.view().caption == "Power on."
    instants = sorted({s.t_us for s in scenario.steps if s.t_us > 0})
    for t_us in instants:
        applied = live.player.step()
        assert applied and {s.t_us for s in applied} == {t_us}
        assert live.t_us == t_us // 1000 * 1000  # the 1 ms step at or before the time
        assert live.player.view().status is Status.PAUSED
    assert live.player.view().next_step is None
    live.player.step()  # to the scenario's end
    assert live.t_us == scenario.end_us and live.player.view().status is Status.FINISHED
    assert lines(live.events) == reference


def test_captions_and_checkpoints_at_their_simulated_time(live: Live,
                                                          scenario: Scenario) -> None:
    live.quiet()
    live.player.load(scenario)
    while live.player.view().status is not Status.FINISHED:
        live.player.step()
    marks = [(type(e).__name__, e.t_us) for e in live.events
             if isinstance(e, (Caption, Checkpoint))]
    assert marks == [("Caption", 0), ("Checkpoint", 4_000_000), ("Caption", 4_500_000),
                     ("Checkpoint", 5_234_000)]
    view = live.player.view()
    assert view.caption == "Module 2 is pulled off the rail." and view.checkpoint == "in_alarm"
    assert view.failures == ()  # the refused write was expected


def test_pause_holds_the_simulated_clock(live: Live, scenario: Scenario) -> None:
    live.player.load(scenario)
    live.player.set_speed(MAX_SPEED)
    live.player.play()
    live.wait(lambda: live.t_us > 200_000, "the clock to run")
    live.player.pause()
    live.barrier()
    held = live.t_us
    live.barrier(rounds=50)  # 50 rounds of the simulation loop (>= 50 ms): 0.5 s at 10x
    assert live.t_us == held and live.player.view().status is Status.PAUSED
    live.player.play()
    live.wait(lambda: live.t_us > held, "the clock to run again")


def test_restart_makes_the_rig_factory_fresh_in_place(live: Live, scenario: Scenario,
                                                      reference: list[str]) -> None:
    devices = dict(live.runtime.rig.devices)
    live.player.load(scenario)
    for _ in range(4):
        live.player.step()
    assert live.t_us > 4_000_000 and live.player.view().caption
    live.events.clear()
    live.player.restart()
    rig = live.runtime.rig
    assert live.t_us == 0 and live.runtime.frame.t_us == 0
    assert all(rig.devices[i] is d for i, d in devices.items()), "the objects stay the same"
    assert live.player.view().generation == 2 and live.player.view().applied == 2
    while live.player.view().status is not Status.FINISHED:
        live.player.step()
    assert lines(live.events) == reference


def fresh_snapshot(scenario: Scenario) -> dict:
    assert scenario.rig is not None
    return build_rig(load_rig_spec(scenario.rig)).devices["fastcat"].snapshot()


def test_reset_in_place_is_seen_through_old_references(scenario: Scenario) -> None:
    """A protocol server holds device objects; after the reset they show the fresh state."""
    assert scenario.rig is not None
    running = build_rig(load_rig_spec(scenario.rig))
    coupler = running.devices["fastcat"]
    running.apply("fastcat", "power", {"on": True})
    running.run_until(4_000_000)
    assert coupler.now_us == 4_000_000 and coupler.snapshot() != fresh_snapshot(scenario)
    fresh = build_rig(load_rig_spec(scenario.rig))
    reset_in_place(running, fresh)
    assert running.clock.now_us == 0 and running.pending == []
    assert coupler.now_us == 0
    assert coupler.snapshot() == fresh.devices["fastcat"].snapshot() == fresh_snapshot(scenario)
    fresh.devices["fastcat"].step(1000)  # the fresh model acts on the very same state
    assert coupler.now_us == 1000


@pytest.mark.parametrize("speed", [MIN_SPEED, 1.0, 2.5, MAX_SPEED])
def test_speed_in_range(live: Live, scenario: Scenario, speed: float) -> None:
    live.player.set_speed(speed)
    assert live.runtime.speed == speed


@pytest.mark.parametrize("speed", [0.0, 0.2, 10.5, 100.0])
def test_speed_out_of_range_is_refused(live: Live, speed: float) -> None:
    before = live.runtime.speed
    with pytest.raises(ValueError, match=r"between 0\.25x and 10x"):
        live.player.set_speed(speed)
    assert live.runtime.speed == before


def test_a_scenario_for_another_rig_is_refused_before_anything_changes(live: Live) -> None:
    other = load_scenario(Path(DEFAULT_RIG).parent.parent / "scenarios" / "cnf_scan.toml")
    before = live.untouched()
    with pytest.raises(ScenarioError, match="cannot play on this dashboard"):
        live.player.load(other)  # the default rig has a master and drives; this one not
    live.assert_untouched(before)


def test_a_broken_step_is_refused_before_anything_changes(live: Live, tmp_path: Path) -> None:
    bad = parse_scenario(SCENARIO.replace('action = "unplug"', 'action = "unplugg"'),
                         "bad.toml", base_dir=tmp_path)
    before = live.untouched()
    with pytest.raises(ScenarioError, match=r"step\[4\]"):
        live.player.load(bad)
    live.assert_untouched(before)


def test_controls_need_a_scenario(live: Live) -> None:
    for control in (live.player.play, live.player.step, live.player.restart):
        with pytest.raises(ScenarioError, match="no scenario loaded"):
            control()


def test_example_scenario_on_the_default_rig(tmp_path: Path) -> None:
    """static/scenarios/module_lost_in_op.toml (seed 000 §7.7) stepped live on the default
    rig gives the lines of `scenario run`, byte for byte."""
    scenario = load_scenario(Path(DEFAULT_RIG).parent.parent / "scenarios"
                             / "module_lost_in_op.toml")
    reference = lines(run_scenario(scenario, build_rig(load_rig_spec(DEFAULT_RIG))).events)
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG)))
    runtime.set_paused(True)
    events: list[Event] = []
    runtime.add_listener(events.extend)
    runtime.start()
    try:
        player = Player(runtime)
        player.load(scenario, fresh=runtime.rig)
        while player.view().status is not Status.FINISHED:
            player.step()
    finally:
        runtime.stop()
    assert lines(events) == reference


# Seed 003: ECAT_Notify reactions. The coupler's emergency for module 2 (seed 000 §7.1)
# triggers a re-plug from the scenario's [[on]] table, live as in `scenario run`.
REACTING = """
[scenario]
name = "small: module 2 lost, re-plugged by a reaction"
rig = "small.toml"
duration_s = 9

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true

[[step]]
at = 4.5
target = "fastcat/2"
action = "unplug"

[[on]]
event = "coe_emergency"
once = true
target = "fastcat/2"
action = "plug"
type = "DI16"
"""


def test_play_runs_the_on_reactions_as_scenario_run_does(live: Live, tmp_path: Path) -> None:
    reacting = parse_scenario(REACTING, "reacting.toml", base_dir=tmp_path)
    assert reacting.rig is not None
    run = run_scenario(reacting, build_rig(load_rig_spec(reacting.rig)))
    assert not run.failures
    expected = lines(run.events)
    assert any('"on[0] coe_emergency: fastcat/2 plug"' in line for line in expected)
    live.quiet()
    live.player.load(reacting)
    live.player.set_speed(MAX_SPEED)
    live.player.play()
    live.wait(lambda: live.player.view().status is Status.FINISHED, "the end")
    played = [e for e in live.events if e.t_us <= reacting.end_us]
    assert lines(played) == expected
    assert not live.player.view().failures


def test_next_step_shows_object_indexes_in_hex() -> None:
    """The "next" line wrote ``index=21504`` where the scenario file, the Objects tab and the
    State panel say 0x5400 (static/scenarios/module_lost_in_op.toml)."""
    from app.player import describe_step
    from app.scenario import Step

    read = Step(1, 7_500_000, "command", "fastcat", "read_object", {"index": 0x5400, "sub": 0})
    assert describe_step(read) == "7.5 s: fastcat read_object index=0x5400 sub=0"
    frame = Step(2, 1_000_000, "command", "drive_co", "send_frame",
                 {"cob_id": 0x601, "data": "40 41 60 00"})
    assert describe_step(frame) == "1 s: drive_co send_frame cob_id=0x601 data='40 41 60 00'"
    write = Step(3, 2_000_000, "command", "drive", "write_register", {"register": 12,
                                                                      "value": 6000})
    assert describe_step(write) == "2 s: drive write_register register=12 value=6000"


def test_restart_while_playing_plays_again_from_0(live: Live, scenario: Scenario) -> None:
    """A demo's Restart goes on playing (before: "ready · t = 0.0 s", waiting for Play)."""
    live.quiet()
    live.player.load(scenario)
    live.player.set_speed(MIN_SPEED)
    live.player.play()
    live.wait(lambda: live.t_us > 0, "the clock to run")
    live.player.restart()
    assert live.player.view().status is Status.PLAYING
    assert live.player.view().generation == 2
    live.wait(lambda: live.t_us > 0, "the clock to run again after the restart")


def test_restart_while_paused_stays_paused(live: Live, scenario: Scenario) -> None:
    live.quiet()
    live.player.load(scenario)
    live.player.step()
    live.player.restart()
    assert live.t_us == 0 and live.runtime.paused
    assert live.player.view().status is Status.READY


def test_the_panels_restart_keeps_playing(live: Live, tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """The Restart button goes through the panel (it loads the picked file again) to
    Player.restart: "playing on" is decided in one place (the panel had its own copy)."""
    import viser

    from app.screenshots import free_port
    from app.ui.panels.scenario_player import PAUSE, RESTART, ScenarioPlayerPanel

    path = tmp_path / "small_scenario.toml"  # beside small.toml (the scenario fixture's)
    path.write_text(SCENARIO, encoding="utf-8")
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        panel = ScenarioPlayerPanel(server, live.runtime)
        panel.load(load_scenario(path), path)
        restarts: list[Scenario | None] = []
        restart = panel.player.restart

        def counted(scenario: Scenario | None = None) -> None:
            restarts.append(scenario)
            restart(scenario)

        monkeypatch.setattr(panel.player, "restart", counted)
        panel.player.set_speed(MIN_SPEED)
        panel.player.play()
        panel._run(None, RESTART)
        assert panel.player.view().status is Status.PLAYING
        assert panel.player.view().generation == 2
        panel._run(None, PAUSE)
        panel._run(None, RESTART)
        assert panel.player.view().status is Status.READY and live.runtime.paused
        assert len(restarts) == 2
        assert all(s is not None and s.source == str(path) for s in restarts)  # read again
    finally:
        server.stop()
