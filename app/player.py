"""Play a scenario on a live runtime: play, pause, step, restart, speed (docs/scenarios.md).

A scenario's times are absolute simulated times on a factory-fresh rig, as ``scenario run``
plays it. So loading (and restarting) a scenario first makes the runtime's rig factory-fresh:
a new rig is built from the scenario's rig file (flash in memory, seed from the file, clock at
0) and installed *in place* in the simulation thread: every device object of the running rig
takes the fresh model's state (they share one attribute dict), the clock goes back to 0. The
objects keep their identity, so whatever holds them (protocol servers, the recorder, the
dashboard's panels) goes on working with the fresh rig.

Steps are applied by a step listener in the simulation thread, at the simulated instant
``scenario run`` applies them (after the simulation step that reaches their time), through the
same function; captions and checkpoints go to the runtime's journal. The model events of a
scenario played live are therefore those of ``scenario run``, at the same simulated times,
whatever the speed or the pauses, as long as nobody else commands the rig meanwhile.
"""

from __future__ import annotations

import enum
import logging
import threading
from dataclasses import dataclass
from pathlib import Path

from app.rig import FAR_US, Rig
from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec
from app.runtime import Runtime
from app.scenario import (
    Scenario,
    ScenarioError,
    Step,
    apply_step,
    check_against,
    install_reactions,
)
from devices.events import Event

logger = logging.getLogger(__name__)

MIN_SPEED = 0.25
MAX_SPEED = 10.0
WAIT_S = 30.0  # wall-time limit for the simulation thread to take a load or a step


class Status(enum.Enum):
    EMPTY = "no scenario"
    READY = "ready"  # loaded, paused before its first step
    PLAYING = "playing"
    PAUSED = "paused"
    FINISHED = "finished"


@dataclass(frozen=True)
class PlayerView:
    """What a view shows of the player (read from any thread)."""

    scenario: Scenario | None
    status: Status
    applied: int  # steps applied so far
    next_step: Step | None
    caption: str  # the last caption shown, "" before the first
    checkpoint: str  # the last checkpoint reached
    failures: tuple[str, ...]
    generation: int  # counts loads: a view that sees it change starts afresh


def compatible(running: Rig, fresh: Rig) -> str | None:
    """Why ``fresh`` cannot replace ``running`` in place (None when it can): the same device
    ids of the same kinds, in the same order (the order devices step in)."""
    have = [(i, d.KIND) for i, d in running.devices.items()]
    want = [(i, d.KIND) for i, d in fresh.devices.items()]
    if have == want and all(type(running.devices[i]) is type(fresh.devices[i])
                            for i in running.devices):
        return None
    return (f"rig '{fresh.name}' has devices {', '.join(f'{i} ({k})' for i, k in want)}; the "
            f"running rig '{running.name}' has {', '.join(f'{i} ({k})' for i, k in have)}")


def shown_path(path: Path) -> Path:
    """``path`` as a command typed in the working directory takes it (relative when inside)."""
    try:
        return path.resolve().relative_to(Path.cwd().resolve())
    except ValueError:
        return path


class RigMismatch(ScenarioError):
    """A scenario written for a rig with other devices than the running one.

    ``fix`` is what a trainee reads in the dashboard's notice: the command that serves the
    scenario's rig, first, in a few words; ``str()`` adds the two device lists (the log, the
    CLI), which were the whole notice before and pushed its title and the fix out of view."""

    def __init__(self, scenario: Scenario, rig_file: Path, rig_name: str, running: str,
                 why: str) -> None:
        self.rig_file = rig_file
        self.fix = (f"Serve its rig: python -m app --rig {shown_path(rig_file)} (it is "
                    f"written for the rig '{rig_name}'; this dashboard serves '{running}', "
                    f"with other devices: both lists are in the server log).")
        super().__init__(f"{scenario.source}: cannot play on this dashboard: {why}; serve its "
                         f"rig instead (python -m app --rig {shown_path(rig_file)})")


def reset_in_place(running: Rig, fresh: Rig) -> None:
    """Give ``running`` the state of the factory-fresh ``fresh``; simulation thread only.

    Each running device object takes the fresh twin's attribute dict itself (not a copy), so
    the fresh models' internal references (a master's slaves, object-dictionary callbacks bound
    to a device) and the outside references (protocol servers) see one and the same state.
    """
    for device_id, device in running.devices.items():
        device.__dict__ = fresh.devices[device_id].__dict__
    running.name, running.seed = fresh.name, fresh.seed
    running.clock.step_us = fresh.clock.step_us
    running.clock.now_us = fresh.clock.now_us
    running.pending = []
    running.loads += 1
    running.touch()


class Player:
    """Plays one scenario at a time on ``runtime`` (which must be started)."""

    def __init__(self, runtime: Runtime, default_rig: str | Path = DEFAULT_RIG) -> None:
        self.runtime = runtime
        self.default_rig = Path(default_rig)
        self._lock = threading.Lock()
        self._scenario: Scenario | None = None
        self._next = 0
        self._caption = ""
        self._checkpoint = ""
        self._failures: list[str] = []
        self._finished = False
        self._run_on = False  # the rig keeps running after the last step (an exercise file)
        self._generation = 0
        self._load_seq = 0  # Runtime.journal_seq when the last load installed its rig
        self._started = False  # a simulation step has run since the load
        # rig file -> (its rig's name, why it cannot replace the running rig) or None
        self._fits: dict[Path, tuple[str, str] | None] = {}
        runtime.add_step_listener(self._on_step, quiet_until=self._quiet_until)

    # ---- commands (any thread but the simulation thread) ---------------------------------
    def rig_path(self, scenario: Scenario) -> Path:
        return Path(scenario.rig) if scenario.rig is not None else self.default_rig

    def mismatch(self, scenario: Scenario) -> RigMismatch | None:
        """Why ``scenario`` cannot play on the running rig (None when it can, or when its
        rig file does not load: Play then says why). The devices of a running rig never
        change (a load resets them in place), so each rig file is built once."""
        path = self.rig_path(scenario).resolve()
        if path not in self._fits:
            try:
                fresh = build_rig(load_rig_spec(path), state_dir=None)
            except (RigConfigError, ValueError) as exc:
                logger.warning("rig %s of scenario '%s' does not load: %s", path,
                               scenario.name, exc)
                return None
            why = compatible(self.runtime.rig, fresh)
            self._fits[path] = None if why is None else (fresh.name, why)
        found = self._fits[path]
        if found is None:
            return None
        rig_name, why = found
        return RigMismatch(scenario, path, rig_name, self.runtime.rig.name, why)

    def fresh_rig(self, scenario: Scenario) -> Rig:
        """The factory-fresh rig :meth:`load` installs for ``scenario`` (RigConfigError when
        its rig file does not load). Flash in memory, as `scenario run` has it: a played
        scenario starts from the factory state and never writes the served rig's flash."""
        return build_rig(load_rig_spec(self.rig_path(scenario)), state_dir=None)

    def load(self, scenario: Scenario, fresh: Rig | None = None, run_on: bool = False) -> None:
        """Make the rig factory-fresh and stand before the scenario's first step, paused.

        ``fresh``: the rig to install (default: built from the scenario's rig file, or
        ``default_rig``); pass the runtime's own untouched rig to play on it as it is.
        ``run_on``: the rig is not paused at the scenario's end (an exercise file sets the
        stage and its hidden fault has to develop on a running rig afterwards). Raises
        ScenarioError / RigConfigError before anything changes when the scenario does not fit.
        """
        if fresh is None:
            fresh = self.fresh_rig(scenario)
        check_against(scenario, fresh)
        if fresh is not self.runtime.rig:
            why = compatible(self.runtime.rig, fresh)
            if why is not None:
                raise RigMismatch(scenario, self.rig_path(scenario).resolve(), fresh.name,
                                  self.runtime.rig.name, why)
        self.runtime.set_paused(True)

        def install() -> None:
            rig = self.runtime.rig
            if fresh is not rig:
                reset_in_place(rig, fresh)
            rig.scenario = scenario.name  # before the load's events: the recorder's run row
            with self._lock:
                self._scenario = scenario
                self._next = 0
                self._caption = self._checkpoint = ""
                self._failures = []
                self._finished = self._started = False
                self._run_on = run_on
                self._generation += 1
                # Where the new run starts in the journal: a view splits its batch of events
                # there (app/ui/runs.py); the clock going back does not tell a load at 0 s.
                self._load_seq = self.runtime.journal_seq
            # The [[on]] tables ride on the fresh master's ECAT_Notify hook, as in `scenario run`.
            install_reactions(scenario, rig, self._failures)
            # Steps at 0 s come before the first step, after what the fresh rig emitted when
            # built, as app.scenario.run_scenario orders them.
            self._apply_due(rig.clock.now_us, rig.take_events())
            self.runtime.set_speed(self.runtime.speed)  # rebase the wall clock on time 0

        self.runtime.submit(install).result(timeout=WAIT_S)
        self.runtime.advance(0).result(timeout=WAIT_S)  # publish the fresh rig's frame
        self._barrier()
        logger.info("scenario '%s' loaded", scenario.name)

    def restart(self, scenario: Scenario | None = None) -> None:
        """Back to the start of the loaded scenario (or of ``scenario``: the dashboard's
        picked file, read again), on a factory-fresh rig again, playing on if it was playing
        (a demo goes on from 0 s; a paused one waits at 0 s). The one place Restart's rule
        lives: the Scenario panel's button comes here."""
        scenario = scenario if scenario is not None else self._require()
        playing = self.playing()
        self.load(scenario)
        if playing:
            self.play()

    def playing(self) -> bool:
        return self.view().status is Status.PLAYING

    def play(self) -> None:
        self._require()
        if not self._finished or self._run_on:
            self.runtime.set_paused(False)

    def pause(self) -> None:
        self.runtime.set_paused(True)

    def step(self) -> list[Step]:
        """Pause, then run to the next step's instant and apply every step due there (to the
        scenario's end once all are applied). Returns the steps applied."""
        self._require()
        self.pause()

        def plan() -> tuple[int, int]:
            with self._lock:
                scenario, index = self._scenario, self._next
            assert scenario is not None
            target = (scenario.steps[index].t_us if index < len(scenario.steps)
                      else scenario.end_us)
            return index, max(0, target - self.runtime.rig.clock.now_us)

        before, delta = self.runtime.submit(plan).result(timeout=WAIT_S)
        self.runtime.advance(delta).result(timeout=WAIT_S)
        self._barrier()
        with self._lock:
            scenario, after = self._scenario, self._next
        return list(scenario.steps[before:after]) if scenario is not None else []

    def set_speed(self, speed: float) -> None:
        if not MIN_SPEED <= speed <= MAX_SPEED:
            raise ValueError(f"speed must be between {MIN_SPEED:g}x and {MAX_SPEED:g}x, "
                             f"got {speed:g}x")
        self.runtime.set_speed(speed)

    def view(self) -> PlayerView:
        with self._lock:
            scenario = self._scenario
            if scenario is None:
                status = Status.EMPTY
            elif self._finished:
                status = Status.FINISHED
            elif not self.runtime.paused:
                status = Status.PLAYING
            else:
                status = Status.PAUSED if self._started else Status.READY
            steps = scenario.steps if scenario is not None else ()
            return PlayerView(scenario, status, self._next,
                              steps[self._next] if self._next < len(steps) else None,
                              self._caption, self._checkpoint, tuple(self._failures),
                              self._generation)

    def last_load(self) -> tuple[int, int]:
        """(generation, load_seq) of the last load: what a view needs to start afresh."""
        with self._lock:
            return self._generation, self._load_seq

    def _barrier(self) -> None:
        """Wait until the work queued so far ran: the journal has the captions of the steps
        just applied (they are queued behind the advance that applied them)."""
        self.runtime.submit(lambda: None).result(timeout=WAIT_S)

    def _require(self) -> Scenario:
        with self._lock:
            if self._scenario is None:
                raise ScenarioError("no scenario loaded")
            return self._scenario

    # ---- the simulation thread -----------------------------------------------------------
    def _quiet_until(self, now_us: int, step_us: int) -> int:
        """Nothing to do while no scenario is loaded or after its end; a loaded one is played
        step by step (its steps' times and the end are checked after every step)."""
        return FAR_US if self._scenario is None or self._finished else now_us

    def _on_step(self, now_us: int) -> None:
        if self._scenario is None or self._finished:
            return
        self._started = True
        self._apply_due(now_us)

    def _apply_due(self, now_us: int, before: list[Event] | None = None) -> None:
        """Apply the steps ``scenario run`` applies at ``now_us``: those before the next
        simulation step (app.scenario._run_until stops at the last step not past them).
        ``before``: events to journal ahead of theirs."""
        rig = self.runtime.rig
        horizon = now_us + rig.clock.step_us
        events: list[Event] = list(before or ())
        with self._lock:
            scenario = self._scenario
            if scenario is None:
                return
            while self._next < len(scenario.steps) and scenario.steps[self._next].t_us < horizon:
                step = scenario.steps[self._next]
                events.extend(apply_step(step, rig, self._failures))
                self._next += 1
                if step.kind == "caption":
                    self._caption = step.text
                elif step.kind == "checkpoint":
                    self._checkpoint = step.text
            done = self._next >= len(scenario.steps) and horizon > scenario.end_us
            if done:
                self._finished = True
            pause = done and not self._run_on
        if events:
            self.runtime.journal(events)
        if pause:
            self.runtime.set_paused(True)
            logger.info("scenario '%s' finished at %.3f s", scenario.name, now_us / 1e6)


# Parameters that name an object or a frame: the seeds, the scenario files and every panel
# write them in hex (0x5400, COB-ID 0x601), so the "next" line does too; width in hex digits.
HEX_ARGS = {"index": 4, "cob_id": 3}


def _arg(name: str, value: object) -> str:
    width = HEX_ARGS.get(name)
    if width is not None and isinstance(value, int) and not isinstance(value, bool):
        return f"{name}=0x{value:0{width}X}"
    return f"{name}={value!r}"


def describe_step(step: Step) -> str:
    """One line for a view: ``6 s: fastcat/2 unplug``, ``7.5 s: fastcat read_object
    index=0x5400 sub=0``."""
    at = f"{step.t_us / 1e6:g} s"
    if step.kind == "command":
        args = " ".join(_arg(k, v) for k, v in step.args.items())
        return f"{at}: {step.target} {step.action}" + (f" {args}" if args else "")
    return f"{at}: {step.kind} \u00ab{step.text}\u00bb"

