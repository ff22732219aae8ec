"""Issue 7 "send only what changed" (benchmarks 2 and 3): what the dashboard queues for the
browsers while the default rig stands idle in OP.

Any scene message makes every browser redraw its 3D canvas, and a GUI message that repeats
what the browser shows is bandwidth for nothing. Checked on the messages viser queues (the
server's own send path, patched to record), frame by frame:

- no node property and no GUI property is written twice in one frame, or twice in a row with
  the same value (the master's header went "1 · ... · running" then "target OP" every frame);
- idle, the 3D scene only carries LED colours (the flickering LINK / L/A LEDs, ETG.1300);
- the Drive tab's state table is not resent while only the simulated time moves (its title,
  with the time, is its own handle); with several drives each page gets the tab of the drive
  it picked, so a connected page's own messages are recorded too;
- the master panel: its status table (phase, target, link) and its slave table are not resent
  while the time, the frame counter and the DC deviation move (each in its own handle, tested
  block by block in test_send_only_changes_panels.py); the drive plots' unchanged x range is
  not resent with their data, and a still drive's charts get the ends of their flat lines,
  not every sample of the window;
- the scenario player's ``fr-player`` block (app/screenshots.py waits on its ``data-frame``):
  a running rig's block is rewritten only when what it says changes; a paused rig's names
  every frame written, byte for byte what ``status_html`` gives.
"""

from __future__ import annotations

import collections
import dataclasses
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
import viser

from app.player import PlayerView, Status
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Frame, Runtime
from app.scenario import load_scenario
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.drive.plots import SEND_PERIOD_S, SIGNALS
from app.ui.panels.scenario_player import (
    STATUS_ID,
    ScenarioPlayerPanel,
    library,
    status_html,
    status_text,
)
from tests.app.test_classroom_leak import Page, _wait

FRAME_US = 33_000  # one dashboard frame of simulated time (the runtime publishes at 30 Hz)
IDLE_FRAMES = 90  # three seconds
# The drive plots are written on wall time (SEND_PERIOD_S); frames here come faster than real
# time, so every PLOT_FRAMES-th frame also writes them, as 30 frames a second would.
PLOT_FRAMES = round(SEND_PERIOD_S * 1e6 / FRAME_US)
BOOT_LIMIT_US = 30_000_000
TIMEOUT_S = 60


@dataclass
class Tape:
    """The messages viser queued, one list per dashboard tick."""

    ticks: list[list[Any]] = field(default_factory=list)
    recording: bool = False

    def record(self, message: Any) -> None:
        if self.recording and self.ticks:
            self.ticks[-1].append(message)


def writes(message: Any) -> Iterator[tuple[tuple[str, str], Any]]:
    """((node or GUI id, property), value) for each property a message sets."""
    kind = type(message).__name__
    if kind == "SceneNodeUpdateMessage" or kind == "GuiUpdateMessage":
        key = getattr(message, "name", None) or getattr(message, "uuid", "")
        for prop, value in message.updates.items():
            yield (key, prop), value
    elif kind.startswith("Set") and hasattr(message, "name"):
        fields = [f.name for f in dataclasses.fields(message) if f.name not in ("name", "owner")]
        yield (message.name, kind), tuple(getattr(message, f) for f in fields)


def in_op(snapshot: dict[str, Any]) -> bool:
    devices = snapshot.get("devices") or {}
    master = devices.get("master") or {}
    slaves = master.get("slaves") or []
    return (devices.get("fastcat", {}).get("esm") == "OP" and bool(slaves)
            and all(s.get("state") == "OP" for s in slaves))


@pytest.fixture(scope="module")
def idle() -> Iterator[tuple[Dashboard, Tape]]:
    """The default rig booted to OP behind a dashboard; then IDLE_FRAMES frames recorded."""
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    runtime.set_paused(True)  # frames only when the test advances (the drive's time too)
    port = free_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    dashboard = Dashboard(server, runtime)  # ticked by the test, not by its own thread
    runtime.start()
    tape = Tape()
    queue = server._websock_server.queue_message

    def recorded(message: Any) -> None:
        tape.record(message)
        queue(message)
    server._websock_server.queue_message = recorded  # type: ignore[method-assign]
    # A page: what goes to it alone (the Drive tab of the drive it picked) is recorded too
    page = Page(port)
    try:
        _wait(lambda: server.get_clients())
        [client] = server.get_clients().values()
        to_page = client.gui._websock_interface.queue_message

        def recorded_for_page(message: Any) -> None:
            tape.record(message)
            to_page(message)
        client.gui._websock_interface.queue_message = recorded_for_page  # type: ignore
        while not in_op(runtime.frame.snapshot):
            assert runtime.rig.clock.now_us < BOOT_LIMIT_US, "the default rig did not reach OP"
            runtime.advance(500_000).result(timeout=TIMEOUT_S)
            dashboard.tick()
        runtime.advance(1_000_000).result(timeout=TIMEOUT_S)
        dashboard.tick()
        tape.recording = True
        for n in range(IDLE_FRAMES):
            runtime.advance(FRAME_US).result(timeout=TIMEOUT_S)
            tape.ticks.append([])
            dashboard.tick()
            if dashboard.drives is not None and n % PLOT_FRAMES == PLOT_FRAMES - 1:
                dashboard.drives.plots.update(time.monotonic(), runtime.frame.t_us, force=True)
        tape.recording = False
        yield dashboard, tape
    finally:
        page.close()
        runtime.stop()
        server.stop()


def test_nothing_written_twice_in_a_frame(idle: tuple[Dashboard, Tape]) -> None:
    _, tape = idle
    for n, messages in enumerate(tape.ticks):
        counts = collections.Counter(key for m in messages for key, _ in writes(m))
        assert [k for k, c in counts.items() if c > 1] == [], f"frame {n}"


def test_nothing_rewritten_with_the_value_it_has(idle: tuple[Dashboard, Tape]) -> None:
    """Scene nodes, HTML blocks and the drive plots' uPlot scales (their x range stands at
    0..20 s until the window fills: app/ui/drive/plots.py)."""
    _, tape = idle
    last: dict[tuple[str, str], Any] = {}
    for n, messages in enumerate(tape.ticks):
        for message in messages:
            for key, value in writes(message):
                if not key[0].startswith("/") and key[1] not in ("content", "scales"):
                    continue
                assert last.get(key, object()) != value, f"frame {n}: {key} resent"
                last[key] = value


def test_idle_scene_carries_led_colours_only(idle: tuple[Dashboard, Tape]) -> None:
    """The master's header: "target OP" once, not once a frame (benchmark 2)."""
    dashboard, tape = idle
    scene = [key for messages in tape.ticks for m in messages for key, _ in writes(m)
             if key[0].startswith("/")]
    assert scene, "no LED flipped in three seconds: the LINK LEDs flicker in OP"
    assert {prop for _, prop in scene} == {"color"}
    assert all("/led_" in name for name, _ in scene), sorted({n for n, _ in scene})
    assert dashboard.line is not None
    assert dashboard.line.scene.text("master", "header") == "target OP"


def test_drive_table_not_resent_for_the_time(idle: tuple[Dashboard, Tape]) -> None:
    """The title moves with the time (tenths, 30 in three seconds); the table stands."""
    _, tape = idle
    contents = [str(v) for messages in tape.ticks for m in messages
                for (_, prop), v in writes(m) if prop == "content"]
    assert not [c for c in contents if 'id="fr-drive"' in c]
    titles = [c for c in contents if c.startswith('<p class="fr-title"><b>drive</b>')]
    assert IDLE_FRAMES * FRAME_US // 100_000 - 1 <= len(titles) <= IDLE_FRAMES


def test_master_summary_not_resent_for_the_time(idle: tuple[Dashboard, Tape]) -> None:
    """The master's status table and slave table stand; its title moves with the tenths, its
    DC and Frames rows with every frame (the counter, the deviation drawn each cycle)."""
    dashboard, tape = idle
    contents = [str(v) for messages in tape.ticks for m in messages
                for (_, prop), v in writes(m) if prop == "content"]
    assert not [c for c in contents if 'id="fr-line-master-status"' in c]
    assert not [c for c in contents if 'id="fr-line-slaves"' in c]
    titles = [c for c in contents if "<b>EtherCAT master</b>" in c]
    tenths = IDLE_FRAMES * FRAME_US // 100_000
    assert tenths - 1 <= len(titles) <= tenths + 1
    assert all('id="fr-line-master' not in c for c in titles)
    live = [c for c in contents if 'id="fr-line-master"' in c]
    assert live and all("Phase" not in c for c in live)
    assert dashboard.line is not None
    assert "running" in dashboard.line.master.text("status")


def test_idle_plots_send_the_ends_of_flat_lines(idle: tuple[Dashboard, Tape]) -> None:
    """The drive stands still: a chart's data is its flat line's two ends (app/ui/drive/plots.py;
    every sample of the window before, up to 1000 float64 t and value pairs a chart)."""
    _, tape = idle
    data = [v for messages in tape.ticks for m in messages for (_, prop), v in writes(m)
            if prop == "data"]
    assert len(data) >= len(SIGNALS) * (IDLE_FRAMES // PLOT_FRAMES)
    assert all(len(t) == len(values) == 2 for t, values in data), [len(t) for t, _ in data]


# ---- the scenario player's marker -------------------------------------------------------------
class _Recorder:
    """Stands in for the marker's HTML handle: keeps what is written to it."""

    def __init__(self) -> None:
        self.writes: list[str] = []

    @property
    def content(self) -> str:
        return self.writes[-1] if self.writes else ""

    @content.setter
    def content(self, value: str) -> None:
        self.writes.append(value)


@pytest.fixture
def player() -> Iterator[tuple[ScenarioPlayerPanel, Runtime, list[str]]]:
    """The panel on a runtime that is never started: the test hands it frames and views."""
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        panel = ScenarioPlayerPanel(server, runtime)
        recorder = _Recorder()
        panel._status = recorder  # type: ignore[assignment]
        sent = recorder.writes
        yield panel, runtime, sent
    finally:
        server.stop()


def frames(start: int, count: int) -> list[Frame]:
    return [Frame(seq, seq * FRAME_US, {}) for seq in range(start, start + count)]


def test_running_idle_marker_written_once(player: Any) -> None:
    panel, runtime, sent = player
    runtime.set_paused(False)
    for frame in frames(1, 30):
        panel.update(frame)
    assert len(sent) == 1 and f'id="{STATUS_ID}" data-frame="1"' in sent[0]


def test_paused_marker_names_every_frame(player: Any) -> None:
    """app/screenshots.py steps a paused rig and waits for data-frame >= the runtime's."""
    panel, runtime, sent = player
    runtime.set_paused(True)
    shown = frames(1, 5)
    for frame in shown:
        panel.update(frame)
    view = panel.player.view()
    assert sent == [_html(view, f, panel.hint) for f in shown]


def _html(view: PlayerView, frame: Frame, hint: str = "") -> str:
    """What an open rig's status block shows (its text is the shared status_text)."""
    return status_html(view, frame, status_text(view, frame.t_us, hint))


def _view(**changes: Any) -> PlayerView:
    scenario = load_scenario(library()[0].path)
    base = PlayerView(scenario, Status.PLAYING, 1, scenario.steps[1], "", "", (), 1)
    return dataclasses.replace(base, **changes)


@pytest.mark.parametrize("change", [
    {"status": Status.PAUSED}, {"applied": 2}, {"generation": 2}, {"caption": "a caption"},
    {"checkpoint": "in_alarm"}, {"failures": ("expected OP",)}, {"next_step": None},
])
def test_running_marker_follows_what_it_says(player: Any, change: dict[str, Any]) -> None:
    panel, runtime, sent = player
    runtime.set_paused(False)
    before, after = _view(), _view(**change)
    first, second, third = Frame(1, 1_000_000, {}), Frame(2, 1_033_000, {}), \
        Frame(3, 1_066_000, {})
    panel.player.view = lambda: before  # type: ignore[method-assign]
    panel.update(first)
    panel.update(second)  # same tenth of a second, same words: nothing
    panel.player.view = lambda: after  # type: ignore[method-assign]
    panel.update(third)
    assert sent == [_html(before, first), _html(after, third)]


def test_running_marker_follows_the_shown_time(player: Any) -> None:
    """A loaded scenario shows "t = 1.0 s": a new tenth is a new text, a new frame is not."""
    panel, runtime, sent = player
    runtime.set_paused(False)
    view = _view()
    panel.player.view = lambda: view  # type: ignore[method-assign]
    shown = [Frame(1, 1_000_000, {}), Frame(2, 1_020_000, {}), Frame(3, 1_060_000, {})]
    for frame in shown:
        panel.update(frame)
    assert sent == [_html(view, shown[0]), _html(view, shown[2])]
