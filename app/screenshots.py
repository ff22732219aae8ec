"""Headless screenshots of a scenario, for CI (docs/scenarios.md "Screenshots for CI").

``python -m app scenario run FILE --out DIR --screenshots`` serves the dashboard on a free
loopback port with the simulation *paused*, opens it in headless Chromium (Debian's, driven by
Playwright; never a Playwright browser download), plays the scenario step by step with the
dashboard's own scenario player, and at each checkpoint writes ``DIR/<NN>-<name>.png``; it
returns the events, which the CLI writes to ``DIR/events.jsonl`` as for every run (the same
lines ``scenario run`` prints; the CLI owns ``--out``: app/cli.py).

What makes two runs give the same pictures: a fixed 1280x720 viewport at device pixel ratio 1
(and viser's ``fixedDpr``, so slow software WebGL does not lower the resolution), the camera
the dashboard sets, the mouse parked on the title bar, the "Software WebGL" notice closed, the
3D canvas on whole pixels (app/whole_pixels.py, as the browser tests' baselines), and the
simulation standing still at the checkpoint's simulated instant, so LEDs are caught at the
same phase of their blinking. A picture is taken once the browser shows the frame of that
instant (the player panel's ``data-frame`` marker) and has painted it.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import socket
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import viser

from app.out_paths import image_name
from app.player import Status
from app.rig import Rig
from app.runtime import Runtime
from app.scenario import Scenario, Step, check_against
from app.ui.dashboard import Dashboard
from app.ui.glyphs import glyph_order
from app.ui.panels.scenario_player import PLAYER_FOLDER, STATUS_ID
from app.ui.tab_switch import SNIPPET_ID
from app.whole_pixels import pin_3d_canvas
from devices.events import Event

logger = logging.getLogger(__name__)

CHROMIUM = "/usr/bin/chromium"
LAUNCH_ARGS = (
    "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
    "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    # Crashpad kept its database in ~/.config/chromium/Crash Reports even when nothing crashed
    "--disable-crash-reporter",
    # The same bytes every run (tests/browser/test_screenshot_bytes.py): a tile re-rastered
    # over part of an earlier frame's kept that frame's anti-aliasing on rounded corners and
    # icons, and the GPU (SwiftShader) canvas of a plot could reach the capture a frame late.
    "--disable-partial-raster", "--disable-gpu-rasterization", "--disable-accelerated-2d-canvas",
)
VIEWPORT = {"width": 1280, "height": 720}
WALL_TIMEOUT_S = 60.0
PAINT_PAUSE_MS = 300  # after the frame arrived: labels and HTML settle, then the canvas paints
POINTER_PARK = (640, 12)  # on the title bar: no hover outline, no tooltip
# A rig without tabs has the "Scenario player" folder after the others in the control panel,
# below the fold of a 720 px page: the panel is scrolled to put its title at the top, the
# status lines (which grow with a caption or failures) below it.
TITLE_TO_TOP_JS = "el => el.scrollIntoView({block: 'start', inline: 'nearest'})"
# uPlot lays out a chart's axes (ticks, grid) when its size or scales change, and the order in
# which a chart's creation, width and data reach it varies with the load: the Drive tab's
# "Following error" chart, the one with the time axis, was left without its time grid in
# about one run in eight. Every chart laid out again from what it holds now, before a
# picture (viser 1.1.1 registers each inline chart under window.__viserTestpoints.uplots).
RELAYOUT_PLOTS_JS = ("() => { for (const p of Object.values("
                     "(window.__viserTestpoints || {}).uplots || {}))"
                     " p.chart.redraw(true, true); }")


class ScreenshotError(OSError):
    """The browser side failed (no Chromium, a page that never connects, Chromium dying): the
    machine failed the run, not its input. An OSError, as a file that cannot be written is:
    one line and exit 3 for the CLI (docs/scenarios.md "Exit codes")."""


@contextlib.contextmanager
def _browser_failures() -> Iterator[None]:
    """Playwright's errors (TargetClosedError when Chromium dies, its TimeoutError) as
    :class:`ScreenshotError`, with the first line of their message (the rest is the
    browser's log)."""
    from playwright.sync_api import Error as PlaywrightError

    try:
        yield
    except PlaywrightError as exc:
        first = (exc.message or type(exc).__name__).splitlines()[0]
        raise ScreenshotError(f"the browser failed: {first}") from exc


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_until(predicate: Callable[[], Any], what: str,
               timeout: float = WALL_TIMEOUT_S) -> Any:
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise ScreenshotError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(0.02)


@dataclass
class ServedRig:
    """A rig in a paused runtime behind a dashboard on a free loopback port."""

    runtime: Runtime
    server: viser.ViserServer
    dashboard: Dashboard
    url: str
    quiet: bool = False

    @classmethod
    def start(cls, rig: Rig, quiet: bool = False,
              before_start: Callable[[Runtime], object] | None = None,
              texts: Iterable[str] = ()) -> ServedRig:
        """``quiet``: nothing of viser's on the output (``scenario run --quiet``).
        ``before_start(runtime)``: attach listeners that must see every event: the first work
        the dashboard queues already journals the events a rig emits when built (its devices
        powered by the rig file). ``texts``: what labels will show besides the dashboard's
        own (a scenario's captions), for the glyph order of app/ui/glyphs.py."""
        runtime = Runtime(rig)
        runtime.set_paused(True)
        if before_start is not None:
            before_start(runtime)
        port = free_port()
        with _viser_output(quiet):
            server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
        # Every frame drawn, browser or not: advance() waits on rendered_seq before a page
        # is open, and tests read the views.
        dashboard = Dashboard(server, runtime, draw_unwatched=True,
                              glyphs=glyph_order(texts))
        runtime.start()
        dashboard.start()
        # viser binds the next port when ``port`` was taken since free_port() closed it (a
        # parallel run): the URL is the port bound, or Chromium opens the other dashboard.
        return cls(runtime, server, dashboard, f"http://127.0.0.1:{server.get_port()}", quiet)

    def advance(self, seconds: float) -> None:
        """Step the paused rig by exactly ``seconds`` of simulated time."""
        self.runtime.advance(round(seconds * 1_000_000)).result(timeout=WALL_TIMEOUT_S)

    def drawn(self) -> None:
        """Wait until the dashboard has drawn the runtime's current frame."""
        seq = self.runtime.frame.seq
        wait_until(lambda: self.dashboard.rendered_seq >= seq, "the dashboard update")

    def command(self, target: str, action: str, args: dict[str, Any] | None = None) -> Any:
        return self.runtime.command(target, action, args).result(timeout=WALL_TIMEOUT_S)

    def settle(self) -> None:
        """Wait until a frame published after now has been drawn. The frame a step publishes
        is drawn a moment after the step returns, and the step's events are journalled after
        it: a frame published later is one the dashboard draws with every event before it."""
        seq = self.runtime.frame.seq
        wait_until(lambda: self.runtime.frame.seq > seq, "a new frame")
        seq = self.runtime.frame.seq
        wait_until(lambda: self.dashboard.rendered_seq >= seq, "the dashboard update")

    def stop(self) -> None:
        self.dashboard.stop()
        self.runtime.stop()
        with _viser_output(self.quiet):  # "(viser) Server stopped"
            self.server.stop()


def _viser_output(quiet: bool) -> contextlib.AbstractContextManager[Any]:
    """Where viser's prints go: its banner (a boxed URL table) and "Server stopped" are
    rich.print calls that ``verbose=False`` does not silence (viser 1.1: verbose only covers
    the connection messages) and rich.print writes to ``sys.stdout`` of the moment. stdout is
    for the event lines, so stderr; with ``quiet``, nowhere."""
    return contextlib.redirect_stdout(io.StringIO() if quiet else sys.stderr)


def private_home(home: str) -> dict[str, str]:
    """The environment Chromium runs in: this process's, with ``home`` as its HOME and XDG
    config, cache and data dirs. A CI job's ``--screenshots`` run left
    ``~/.config/chromium/Crash Reports`` and ``~/.cache/dconf`` (GLib's settings cache) in the
    user's home; Playwright's temporary profile covers only Chromium's user data dir."""
    return {**os.environ, "HOME": home, "XDG_CONFIG_HOME": os.path.join(home, ".config"),
            "XDG_CACHE_HOME": os.path.join(home, ".cache"),
            "XDG_DATA_HOME": os.path.join(home, ".local", "share")}


def launch(playwright: Any, executable: str = CHROMIUM) -> tuple[Any, Callable[[], None]]:
    """Headless Chromium with :data:`LAUNCH_ARGS` in a home of its own (:func:`private_home`);
    the browser, and what to call after closing it (removes that home). The browser tests
    launch theirs with it too."""
    home = tempfile.TemporaryDirectory(prefix="fieldrig-chromium-", ignore_cleanup_errors=True)
    try:
        browser = playwright.chromium.launch(executable_path=executable, args=list(LAUNCH_ARGS),
                                             env=private_home(home.name))
    except Exception:
        home.cleanup()
        raise
    return browser, home.cleanup


class Chromium:
    """Headless Chromium through Playwright (:func:`launch`); a context manager."""

    def __init__(self, executable: str = CHROMIUM) -> None:
        if not Path(executable).exists():
            raise ScreenshotError(f"{executable} is missing: install Debian's chromium "
                                  "(apt-get install -y chromium)")
        from playwright.sync_api import sync_playwright

        self._playwright = sync_playwright().start()
        try:
            self.browser, self._remove_home = launch(self._playwright, executable)
        except Exception:
            self._playwright.stop()
            raise

    def open(self, served: ServedRig, show_player: bool = False) -> DashboardPage:
        context = self.browser.new_context(viewport=VIEWPORT, device_scale_factor=1)
        page = DashboardPage(context.new_page(), served)
        page.load(show_player)
        return page

    def close(self) -> None:
        try:
            self.browser.close()
            self._playwright.stop()
        finally:
            self._remove_home()

    def __enter__(self) -> Chromium:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass
class DashboardPage:
    page: Any  # playwright Page
    served: ServedRig
    # No tabs and the player wanted in the picture: scroll to it before each screenshot
    scroll_to_player: bool = False

    def load(self, show_player: bool = False) -> None:
        """Open the dashboard; ``show_player``: leave the control panel on the Scenario tab
        (the narration, the step and the time in the picture)."""
        clients = len(self.served.server.get_clients())
        # viser lowers the canvas resolution when software WebGL is slow; fixedDpr pins it.
        self.page.goto(f"{self.served.url}/?fixedDpr=1")
        # Connected = the 3D canvas runs and has sent its first camera message (viser).
        wait_until(lambda: len(self.served.server.get_clients()) > clients,
                   "the browser to connect")
        toast = self.page.locator(".mantine-Notification-root", has_text="Software WebGL")
        try:
            toast.first.wait_for(timeout=15_000)
        except Exception:  # a machine with a GPU shows no such notice
            logger.info("no software-WebGL notice to close")
        else:
            toast.first.locator("button").click()
            toast.first.wait_for(state="detached", timeout=15_000)
        # Pinned at once, not first at a picture: the event log's header came 1 px higher in
        # a page pinned at its first picture than in one pinned at an earlier sync, the rest
        # the same (tests/browser/test_screenshot_bytes.py); the same moment for every page.
        pin_3d_canvas(self.page, WALL_TIMEOUT_S)
        self._mount_player(stay=show_player)
        self.page.mouse.move(*POINTER_PARK)

    def _mount_player(self, stay: bool) -> None:
        """The browser builds a tab's content when the tab is first shown: show the Scenario
        tab (its status block is the frame marker :meth:`sync` reads), then go back unless
        ``stay``."""
        tab = self.page.get_by_role("tab", name="Scenario", exact=True)
        if not tab.count():  # no tabs: the player is the control panel's last folder
            self.scroll_to_player = stay
            return
        tabs = tab.locator("xpath=ancestor::*[@role='tablist'][1]")
        selected = tabs.locator("[role=tab][aria-selected=true]").first.inner_text().strip()
        tab.click()
        self.page.locator(f"#{STATUS_ID}").wait_for(state="attached",
                                                    timeout=WALL_TIMEOUT_S * 1000)
        if not stay:
            tabs.get_by_role("tab", name=selected, exact=True).click()

    def sync(self) -> None:
        """Wait until the page shows the runtime's current frame, with the 3D canvas on whole
        pixels (:func:`pin_3d_canvas`), then until it painted it."""
        seq = self.served.runtime.frame.seq
        wait_until(lambda: self.served.dashboard.rendered_seq >= seq, "the dashboard update")
        self.page.wait_for_function(
            "a => { const m = document.getElementById(a.id);"
            " return m !== null && Number(m.dataset.frame) >= a.seq; }",
            arg={"id": STATUS_ID, "seq": seq}, timeout=WALL_TIMEOUT_S * 1000)
        # A focus step's tab switch (app/ui/tab_switch.py) has clicked its tab.
        self.page.wait_for_function(f"() => !document.querySelector('#{SNIPPET_ID}"
                                    ":not([data-done])')", timeout=WALL_TIMEOUT_S * 1000)
        if self.scroll_to_player:  # each time: the folders above may have grown since
            self.page.get_by_text(PLAYER_FOLDER, exact=True).first.evaluate(TITLE_TO_TOP_JS)
        pin_3d_canvas(self.page, WALL_TIMEOUT_S)
        self.page.evaluate(RELAYOUT_PLOTS_JS)
        self.page.evaluate("() => new Promise(r => requestAnimationFrame("
                           "() => requestAnimationFrame(r)))")
        self.page.mouse.move(*POINTER_PARK)
        self.page.wait_for_timeout(PAINT_PAUSE_MS)

    def screenshot(self, path: Path) -> Path:
        self.sync()
        path.parent.mkdir(parents=True, exist_ok=True)
        self.page.screenshot(path=str(path))
        return path

    def close(self) -> None:
        self.page.context.close()


@dataclass
class ScreenshotRun:
    """Like :class:`app.scenario.ScenarioRun`, plus the pictures written."""

    events: list[Event]
    failures: list[str]
    images: list[Path] = field(default_factory=list)


def run_with_screenshots(scenario: Scenario, rig: Rig, out_dir: str | Path, *,
                         record: str | None = None, chromium: str = CHROMIUM,
                         quiet: bool = False) -> ScreenshotRun:
    """Play ``scenario`` on the untouched ``rig`` in a served dashboard; one PNG per checkpoint
    into ``out_dir``, and the events returned (``events.jsonl`` is the caller's: the CLI
    writes it last, for every run alike). ``quiet``: viser prints nothing.

    The scenario is checked against the rig and the browser looked for first, so a wrong file
    or a missing Chromium is one error line and no server starts."""
    check_against(scenario, rig)
    if not Path(chromium).exists():
        raise ScreenshotError(f"{chromium} is missing: install Debian's chromium "
                              "(apt-get install -y chromium)")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    images: list[Path] = []
    rig.scenario = scenario.name  # a --record recording is named after it from its start
    captions = [step.text for step in scenario.steps if step.kind == "caption"]
    with _browser_failures(), \
            served_run(rig, record=record, quiet=quiet, texts=captions) as (served, events), \
            Chromium(chromium) as browser:
        page = browser.open(served, show_player=True)
        failures = play(served, scenario, rig,
                        lambda step: images.append(_shoot(page, out, len(images) + 1, step)))
        page.close()
    return ScreenshotRun(events, failures, images)


@contextlib.contextmanager
def served_run(rig: Rig, *, record: str | None = None, quiet: bool = False,
               texts: Iterable[str] = ()) -> Iterator[tuple[ServedRig, list[Event]]]:
    """``rig`` served paused, with the list its events go to (and ``record``: a recording of
    it); stopped (and the recording closed) at the end."""
    events: list[Event] = []
    recorder = None
    if record:
        from app.recording import RigRecorder

        recorder = RigRecorder(record, start_time=False)  # a scenario run's: no wall clock

    def attach(runtime: Runtime) -> None:
        runtime.add_listener(events.extend)  # every journalled batch, in order
        if recorder is not None:
            from app.recording import attach_to_runtime

            attach_to_runtime(runtime, recorder)

    try:
        served = ServedRig.start(rig, quiet=quiet, before_start=attach, texts=texts)
        try:
            yield served, events
        finally:
            served.stop()
    finally:
        if recorder is not None:
            recorder.close()


def play(served: ServedRig, scenario: Scenario, rig: Rig,
         at_checkpoint: Callable[[Step], object]) -> list[str]:
    """Play ``scenario`` on the served, untouched ``rig`` step by step with the dashboard's
    player; ``at_checkpoint(step)`` once the rig stands at each checkpoint. The failures."""
    panel = served.dashboard.scenario_player
    panel.load(scenario, fresh=rig)
    player = panel.player
    done = 0
    while True:
        view = player.view()
        for step in scenario.steps[done:view.applied]:
            if step.kind == "checkpoint":
                at_checkpoint(step)
        done = view.applied
        if view.status is Status.FINISHED:
            return list(view.failures)
        # The page must be sent the same whatever the machine's load: each step drawn whole
        # (a focus step's event comes after the frame of its instant) and none left out.
        with served.dashboard.held():
            player.step()
        served.drawn()


def _shoot(page: DashboardPage, out: Path, number: int, step: Step) -> Path:
    path = page.screenshot(out / image_name(number, step.text))
    logger.info("checkpoint '%s' at %.3f s -> %s", step.text, step.t_us / 1e6, path)
    return path
