"""Rigs in your own tests: start one, command it, step it, screenshot its dashboard.

    from app.testing import rig_session

    def test_module_2_lost(tmp_path):
        with rig_session("static/rigs/default.toml") as rig:   # paused at t = 0
            rig.command("fastcat", "power", on=True)
            rig.advance(4.0)                                    # exactly 4 simulated seconds
            rig.command("fastcat/2", "unplug")
            rig.advance(1.0)
            assert rig.snapshot("fastcat")["fault_active"]
            rig.screenshot(tmp_path / "alarm.png")              # headless Chromium

The rig runs in a real runtime behind a real dashboard, but *paused*: it moves only when the
test calls :meth:`RigSession.advance` (or plays a scenario), so a test sees the same states,
events and pictures on every run. Flash lives in memory unless ``state_dir`` is given. The
browser starts at the first :meth:`RigSession.screenshot` (Debian's ``/usr/bin/chromium``).

As a pytest plugin (``pytest_plugins = ["app.testing"]`` in a conftest.py) it also gives the
``fieldrig`` fixture: ``fieldrig(rig_file=None)`` returns a started :class:`RigSession`,
stopped after the test. Needs the test extra (``pip install -e '.[test]'``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from app.player import Status
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.scenario import Scenario, load_scenario
from app.screenshots import CHROMIUM, WALL_TIMEOUT_S, Chromium, DashboardPage, ServedRig
from devices.events import Event


class RigSession:
    """A served, paused rig and (once asked for) a browser showing its dashboard."""

    def __init__(self, served: ServedRig, chromium: str = CHROMIUM) -> None:
        self.served = served
        self._chromium_path = chromium
        self._chromium: Chromium | None = None
        self._page: DashboardPage | None = None
        self._events: list[Event] = []
        served.runtime.add_listener(self._events.extend)

    @property
    def rig(self) -> Rig:
        """The models; read them only while the rig stands still (between calls)."""
        return self.served.runtime.rig

    @property
    def url(self) -> str:
        return self.served.url

    @property
    def t(self) -> float:
        """Simulated seconds since the rig started."""
        return self.served.runtime.frame.t_us / 1e6

    def command(self, target: str, action: str, **args: Any) -> Any:
        """A device action (``"fastcat"``, ``"fastcat/2"``, ...); returns its result, raises
        its CommandError / SdoAbort. The dashboard shows its effect when it returns."""
        try:
            return self.served.command(target, action, args)
        finally:
            self.served.settle()

    def advance(self, seconds: float) -> None:
        """Step the rig by exactly ``seconds`` of simulated time; the dashboard shows the rig
        as it stands then (its views and logs may be read at once)."""
        self.served.advance(seconds)
        self.served.settle()

    def snapshot(self, device: str | None = None) -> dict[str, Any]:
        """The rig's snapshot, or one device's, as of the last step."""
        snap = self.served.runtime.frame.snapshot
        return dict(snap["devices"][device]) if device is not None else dict(snap)

    def events(self, kind: str | None = None) -> list[Event]:
        """Events so far (``kind``: "emergency", "al_status", "caption", ...)."""
        self.served.runtime.submit(lambda: None).result(timeout=WALL_TIMEOUT_S)
        return [e for e in self._events if kind is None or e.kind == kind]

    def play(self, scenario: str | Path | Scenario) -> list[str]:
        """Play a scenario to its end, from a factory-fresh rig, with the dashboard's player;
        returns the failed steps (empty when all went as written)."""
        if not isinstance(scenario, Scenario):
            scenario = load_scenario(scenario)
        player = self.served.dashboard.scenario_player.player
        self.served.dashboard.scenario_player.load(scenario)
        while player.view().status is not Status.FINISHED:
            player.step()
        return list(player.view().failures)

    def screenshot(self, path: str | Path) -> Path:
        """A PNG of the dashboard as the rig stands now (1280x720, stable pixels)."""
        if self._page is None:
            self._chromium = Chromium(self._chromium_path)
            self._page = self._chromium.open(self.served)
        return self._page.screenshot(Path(path))

    def close(self) -> None:
        if self._page is not None:
            self._page.close()
        if self._chromium is not None:
            self._chromium.close()
        self.served.stop()


@contextmanager
def rig_session(rig: str | Path | Rig = DEFAULT_RIG, *, state_dir: str | Path | None = None,
                chromium: str = CHROMIUM) -> Iterator[RigSession]:
    """A :class:`RigSession` on ``rig`` (a rig file or a built Rig), stopped on exit."""
    if not isinstance(rig, Rig):
        rig = build_rig(load_rig_spec(rig), state_dir=state_dir)
    session = RigSession(ServedRig.start(rig), chromium)
    try:
        yield session
    finally:
        session.close()


@pytest.fixture
def fieldrig() -> Iterator[Callable[..., RigSession]]:
    """``fieldrig(rig_file=None, state_dir=None)``: a started session, stopped after the
    test (plugin: ``pytest_plugins = ["app.testing"]``)."""
    sessions: list[RigSession] = []

    def start(rig: str | Path | Rig | None = None,
              state_dir: str | Path | None = None) -> RigSession:
        if not isinstance(rig, Rig):
            rig = build_rig(load_rig_spec(rig or DEFAULT_RIG), state_dir=state_dir)
        session = RigSession(ServedRig.start(rig))
        sessions.append(session)
        return session

    yield start
    for session in sessions:
        session.close()
