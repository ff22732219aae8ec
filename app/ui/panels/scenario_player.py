"""The scenario player panel: pick a scenario of ``static/scenarios/`` (and of ``--scenarios
DIR``, listed first), play, pause, step, restart, speed 0.25x..10x, and what is on now (step,
caption, failures).

The callbacks run in viser's thread pool and only call :class:`app.player.Player`, which hands
the work to the simulation thread. Captions reach the 3D view as Caption events of the
runtime's journal (the dashboard shows them above the rail); this panel repeats the current one
with the step it belongs to. The status block carries ``data-frame`` (the runtime frame the
dashboard wrote with it), ``data-t-us``, ``data-applied`` and ``data-generation``: headless
screenshot tooling waits on them to know that the browser has received a given frame
(app/screenshots.py).

On an open rig the picker is each page's own (a ClientPick), with its hint and the "Picked:"
line under the controls: Play, Step and Restart load the clicking page's pick. The loaded
scenario is the rig's, as the player is: a load names it in every page's picker
(docs/dashboard.md "Several browsers").
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import viser

from app.classroom.roles import Operation
from app.player import Player, PlayerView, RigMismatch, Status, describe_step, shown_path
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec
from app.runtime import Frame, Runtime
from app.scenario import EXAMPLES_DIR, Scenario, ScenarioError, check_against, load_scenario
from app.ui.commands import CommandSender, notify
from app.ui.panels.client_pick import ClientHtml, ClientPick
from app.ui.panels.page_prop import PageProp
from app.ui.panels.per_client import instructor_for
from app.ui.panels.widgets import DetailHint, from_user
from app.ui.style import esc

logger = logging.getLogger(__name__)

SCENARIO_DIR = EXAMPLES_DIR
CHOOSE = "(choose a scenario)"
SPEEDS = (0.25, 0.5, 1.0, 2.0, 5.0, 10.0)
PLAY, PAUSE, STEP, RESTART = "Play", "Pause", "Step", "Restart"
STATUS_ID = "fr-player"
PLAYER_FOLDER = "Scenario player"  # the folder's title (screenshots scroll to it)


@dataclass(frozen=True)
class Entry:
    label: str  # what the picker shows: the scenario's label (its name unless the file
    # gives a shorter one: the closed box holds ~30 characters)
    path: Path
    scenario: Scenario  # as the picker read it (Play reads the file again)
    other_rig: Path | None = None  # the rig file it is written for, when not the served one


def entry_detail(entry: Entry) -> str:
    """``name (file.toml): the description's first sentence`` for the picker's hint: the
    whole name, also where the box shows a label."""
    text = " ".join(entry.scenario.description.split())
    first = text.split(". ", 1)[0].rstrip(".")
    mark = f"[rig {entry.other_rig.stem}] " if entry.other_rig is not None else ""
    return (f"{mark}{entry.scenario.name} ({entry.path.name})"
            + (f": {first}." if first else ""))


def scenario_files(directory: Path) -> list[Path]:
    """The ``*.toml`` files of ``directory``, sorted; OSError when it cannot be listed (a
    glob would hide an unreadable folder as an empty one)."""
    return sorted(p for p in directory.iterdir() if p.suffix == ".toml" and p.is_file())


def library(*directories: Path) -> list[Entry]:
    """The scenarios of ``directories`` (default: the shipped ones), folder by folder, by name.
    Two that share a label are told apart by the file stem, and an own one that also shares
    the stem of a shipped one by its folder too; a file that does not load is left out with a
    warning, not shown broken."""
    found: list[tuple[Scenario, Path]] = []
    seen: set[Path] = set()
    for directory in directories or (SCENARIO_DIR,):
        if directory.resolve() in seen:  # --scenarios static/scenarios: listed once
            continue
        seen.add(directory.resolve())
        for path in scenario_files(directory):
            try:
                found.append((load_scenario(path), path))
            except ScenarioError as exc:
                logger.warning("scenario left out of the picker: %s", exc)
    labels = [s.label for s, _ in found]
    stems = [(s.label, p.stem) for s, p in found]

    def label(scenario: Scenario, path: Path) -> str:
        if labels.count(scenario.label) == 1:
            return scenario.label
        if stems.count((scenario.label, path.stem)) == 1 \
                or path.parent.resolve() == SCENARIO_DIR.resolve():
            return f"{scenario.label} ({path.stem})"
        return f"{scenario.label} ({path.parent.name}/{path.stem})"

    return [Entry(label(s, p), p, s) for s, p in found]


def own_scenarios(directory: str | Path, default_rig: Path = DEFAULT_RIG) -> Path:
    """``--scenarios DIR`` checked before anything serves, as ``scenario run`` checks a file:
    a folder that can be listed, with ``*.toml`` files that load and that their rig (the
    default rig when they name none, as Play builds it) takes. Raises RigConfigError (the
    folder) or ScenarioError (a file: its own message): one line and exit 2 at start, not a
    scenario missing from the picker in front of a customer."""
    folder = Path(directory)
    if not folder.exists():
        raise RigConfigError("--scenarios", "", f"{folder}: no such folder")
    if not folder.is_dir():
        raise RigConfigError("--scenarios", "", f"{folder}: not a folder (give the folder "
                                                "that holds the *.toml files)")
    try:
        files = scenario_files(folder)
    except OSError as exc:
        raise RigConfigError("--scenarios", "", f"{folder}: cannot read it "
                                                f"({exc.strerror or exc})") from None
    if not files:
        raise RigConfigError("--scenarios", "", f"{folder}: no *.toml in it")
    rigs: dict[Path, Rig] = {}
    for path in files:
        scenario = load_scenario(path)
        rig_file = Path(scenario.rig).resolve() if scenario.rig else default_rig.resolve()
        if rig_file not in rigs:
            rigs[rig_file] = build_rig(load_rig_spec(rig_file), state_dir=None)
        check_against(scenario, rigs[rig_file])
    return folder


def marked(entries: list[Entry], player: Player) -> tuple[list[Entry], list[Path]]:
    """The picker's entries: those that play on the running rig first, as they are; then those
    written for another rig file, labelled ``[rig STEM] name`` (the mark first: a long name is
    cut at the right in the dropdown) so that a trainee sees which rig to serve before Play.
    Also the other rig files, in order."""
    here: list[Entry] = []
    other: list[Entry] = []
    rigs: list[Path] = []
    for entry in entries:
        why = player.mismatch(entry.scenario)
        if why is None:
            here.append(entry)
            continue
        other.append(Entry(f"[rig {why.rig_file.stem}] {entry.label}", entry.path,
                           entry.scenario, why.rig_file))
        if why.rig_file not in rigs:
            rigs.append(why.rig_file)
    return here + other, rigs


def other_rig_hint(rigs: list[Path]) -> str:
    """How to play the scenarios marked for another rig: the command for each rig file."""
    if not rigs:
        return ""
    return ("Scenarios marked [rig NAME] are written for another rig; serve it to play them: "
            + "; ".join(f"python -m app --rig {shown_path(r)}" for r in rigs) + ".")


def picked_text(entry: Entry) -> str:
    """The picked scenario's whole name and file (the closed box cuts a long name: "[rig
    ethercat_line] CPX-E-EC: short circ"), and the command that serves its rig when it is
    written for another: what a trainee reads before Play, without hovering."""
    text = f"Picked: <b>{esc(entry.scenario.name)}</b> ({esc(entry.path.name)})"
    if entry.other_rig is None:
        return text + ": Play loads it."
    rig = shown_path(entry.other_rig)
    return text + esc(f", written for {rig}: serve it with python -m app --rig {rig}.")


def speed_label(speed: float) -> str:
    return f"{speed:g}x"


def status_html(view: PlayerView, frame: Frame, text: str) -> str:
    """The status block: ``text`` (:func:`status_text`, :func:`trainee_text`) in its marker."""
    marker = (f'id="{STATUS_ID}" data-frame="{frame.seq}" data-t-us="{frame.t_us}" '
              f'data-applied="{view.applied}" data-generation="{view.generation}" '
              f'data-status="{view.status.name.lower()}"')
    return f'<div {marker} style="font-size:0.85em">{text}</div>'


def status_text(view: PlayerView, t_us: int, hint: str = "") -> str:
    """What the status block says (inside the marker): the scenario, its state and time, the
    step, the caption, the checkpoint and the failures; ``hint`` follows the "no scenario"
    text (how to play the scenarios marked for another rig). The block is every page's: a
    page's picked scenario is named under its own controls (``page_picked``)."""
    scenario = view.scenario
    if scenario is None:
        return ('<span class="fr-muted">No scenario loaded. Pick one and press Play: the rig '
                "restarts factory-fresh and the scenario drives it."
                + (f" {esc(hint)}" if hint else "") + "</span>")
    lines = [_headline(view, scenario, scenario.name, t_us),
             f"step {view.applied} of {len(scenario.steps)}" + _next(view)]
    if view.caption:
        lines.append(_caption(view))
    lines.extend(_author_lines(view))
    return "<br>".join(lines)


def trainee_text(view: PlayerView, t_us: int, title: str | None) -> str:
    """What the status block says on a rig with a token, where every browser gets it: no
    picker to point to, and while an exercise runs (``title``, "Exercise 2") neither the
    scenario's name nor its steps, checkpoints and failures, which an exercise file's author
    writes for the instructor ("CPX short", "next cpx short_circuit"); the captions are the
    narration, everyone's."""
    scenario = view.scenario
    if scenario is None:
        return '<span class="fr-muted">No scenario loaded.</span>'
    if title is None:
        return status_text(view, t_us)
    lines = [_headline(view, scenario, title, t_us),
             f"step {view.applied} of {len(scenario.steps)}"]
    if view.caption:
        lines.append(_caption(view))
    return "<br>".join(lines)


def instructor_text(view: PlayerView, title: str | None, loaded: str, hint: str,
                    picked: str) -> str:
    """What an instructor's page gets under its own controls, beyond :func:`trainee_text`:
    how to play one, the real scenario while the trainees read ``title``, its own pick."""
    scenario = view.scenario
    lines = []
    if scenario is None:
        lines.append('<span class="fr-muted">Pick a scenario and press Play: the rig '
                     "restarts factory-fresh and the scenario drives it."
                     + (f" {esc(hint)}" if hint else "") + "</span>")
    elif title is not None:
        lines.append(f"Trainees read <b>{esc(title)}</b>; loaded: <b>{esc(scenario.name)}</b>"
                     + (f" ({esc(loaded)})" if loaded else "") + _next(view))
        lines.extend(_author_lines(view))
    if picked:
        lines.append(picked)
    return (f'<div class="fr-player-note" style="font-size:0.85em">{"<br>".join(lines)}</div>'
            if lines else "")


def _headline(view: PlayerView, scenario: Scenario, title: str, t_us: int) -> str:
    # The time is one unit: the panel's width broke "t = 7.0 s of 16 s" after "7.0 s".
    return (f"<b>{esc(title)}</b> &middot; {esc(view.status.value)} &middot; "
            f'<span style="white-space:nowrap">t = {t_us / 1e6:.1f} s of '
            f"{scenario.end_us / 1e6:g} s</span>")


def _next(view: PlayerView) -> str:
    if view.next_step is None:
        return ""
    return f" &middot; next {esc(describe_step(view.next_step))}"


def _caption(view: PlayerView) -> str:
    return f'<span style="font-style:italic">&raquo; {esc(view.caption)}</span>'


def _author_lines(view: PlayerView) -> list[str]:
    lines = []
    if view.checkpoint:
        lines.append(f'<span class="fr-muted">checkpoint {esc(view.checkpoint)}</span>')
    lines.extend(f'<span style="color:#a11616">{esc(f)}</span>' for f in view.failures)
    return lines


@dataclass(frozen=True)
class _Pages:
    """What each page of an open rig gets for its own pick: the picker's hint and the
    "Picked:" line under the controls."""

    hint: PageProp
    picked: ClientHtml


@dataclass
class _Controls:
    """The player's controls one connection got (or every browser, on an open rig, whose
    ``pick`` is a ClientPick and ``pages`` what each page gets for it)."""

    pick: Any
    buttons: Any
    speed: Any
    own: Any = None  # the instructor's own status lines (with a token): None when shared
    pages: _Pages | None = None


def _value(pick: Any, client_id: int | None) -> str:
    """What ``pick`` holds on ``client_id``'s page (an open rig's ClientPick: its own)."""
    return pick.value_for(client_id) if isinstance(pick, ClientPick) else str(pick.value)


class ScenarioPlayerPanel:
    """Build inside the container it belongs to (a tab or the control panel).

    Play, Pause, Step, Restart, Speed and the picker are the instructor's: with a token they
    are built per instructor connection (app/ui/panels/per_client.py), so a trainee is not
    offered controls whose every press is refused (and cost points in an exercise); the
    status block with the caption stays everyone's (docs/classroom.md)."""

    def __init__(self, server: viser.ViserServer, runtime: Runtime,
                 directory: Path = SCENARIO_DIR, default_rig: Path = DEFAULT_RIG,
                 own: Path | None = None) -> None:
        """``own``: the folder of ``--scenarios DIR``, listed before ``directory``."""
        self.player = Player(runtime, default_rig)
        self._runtime = runtime
        folders = (own, directory) if own is not None else (directory,)
        entries, rigs = marked(library(*folders), self.player)
        self._entries = {e.label: e for e in entries}
        self.hint = other_rig_hint(rigs)
        self._loaded: Path | None = None
        self._exercise_file: Path | None = None  # the loaded file, when an exercise file
        self._busy = threading.Lock()  # one playback command at a time, in click order
        # The title trainees see instead of the loaded scenario's while an exercise runs
        # (None: the real one); the Classroom folder sets it (app/ui/panels/classroom.py).
        self.trainee_title: Callable[[], str | None] = lambda: None
        instructor = instructor_for(server)
        self._shared = instructor.shared
        self._server = server
        gui = server.gui
        with gui.add_folder(PLAYER_FOLDER):
            self._controls = instructor.part(self._build_controls)
            view = self.player.view()
            self._status = gui.add_html(status_html(
                view, runtime.frame, status_text(view, runtime.frame.t_us, self.hint)
                if self._shared else trainee_text(view, runtime.frame.t_us, None)))
        self._last = ""
        self._said: tuple[Any, ...] = ()

    def _build_controls(self, gui: Any) -> _Controls:
        loaded = self._loaded_label()
        pick = gui.add_dropdown("Scenario", (CHOOSE, *self._entries),
                                initial_value=loaded or CHOOSE)
        # The box cuts a long name ("CPX-E-EC: short circuit at a digital outp"): the
        # picked one's whole name, file and first sentence are its hint.
        if self._shared:
            # Each page's own: one page's pick went to every page, and another page's Play
            # loaded it. A new page's hint is the server's; each page's own goes to it.
            pick.hint = self._details().get(str(pick.value))
            hint = PageProp(self._server, pick, "hint")
            pick = ClientPick(self._server, pick)
        else:
            DetailHint(pick, self._details)
        buttons = gui.add_button_group("Playback", (PLAY, PAUSE, STEP, RESTART))
        speed = gui.add_dropdown("Speed", tuple(speed_label(s) for s in SPEEDS),
                                 initial_value=speed_label(self._nearest_speed()))
        controls = _Controls(pick, buttons, speed, None if self._shared else gui.add_html(""))
        if self._shared:
            controls.pages = _Pages(hint, ClientHtml(self._server, gui.add_html("")))
            pick.on_pick(lambda _client, _label: self._show_pages(controls))
        buttons.on_click(lambda event: self._on_button(event, controls))
        speed.on_update(lambda event: self._on_speed(event, controls))
        return controls

    def _nearest_speed(self) -> float:
        return min(SPEEDS, key=lambda s: abs(s - self._runtime.speed))

    # ---- callbacks (viser's threads) -------------------------------------------------------
    def _on_button(self, event: viser.GuiEvent, controls: _Controls) -> None:
        if not from_user(event) or not self._may_control(event):
            return
        choice = str(event.target.value)
        with self._busy:
            self._run(event.client, choice, _value(controls.pick, event.client_id))

    def _run(self, client: viser.ClientHandle | None, choice: str,
             picked: str | None = None) -> None:
        """``picked``: the label the pressing page's picker shows (None: on an open rig the
        shared picker's for ``client``'s page, else the loaded scenario)."""
        if picked is None and self._shared:
            picked = self._pick.value_for(getattr(client, "client_id", None))
        try:
            if choice == PLAY:
                self._play(picked)
            elif choice == PAUSE:
                self.player.pause()
            elif choice == STEP:
                self._ensure_loaded(picked)
                self.player.step()
            elif choice == RESTART:  # the picked file, read again (docs/scenarios.md)
                path = self._picked_path(picked)
                scenario = load_scenario(path)
                self.player.restart(scenario)
                self._note_loaded(scenario, path)
        except RigMismatch as exc:  # the fix first and short; the device lists to the log
            logger.warning("%s", exc)
            notify(client, f"Scenario: {choice} refused", exc.fix, error=True)
        except (ScenarioError, RigConfigError, ValueError) as exc:
            notify(client, f"Scenario: {choice} refused", str(exc), error=True)

    def _may_control(self, event: viser.GuiEvent) -> bool:
        """Scenario control is the instructor's (app/classroom/roles.py): checked, logged and
        notified by the runtime's CommandSender, whatever a page sends."""
        return CommandSender(self._runtime).allow(event.client, Operation.SCENARIO,
                                                  "scenario player")

    def _on_speed(self, event: viser.GuiEvent, controls: _Controls) -> None:
        if not from_user(event) or not self._may_control(event):
            return
        label = str(controls.speed.value)
        try:
            self.player.set_speed(float(label.rstrip("x")))
        except ValueError as exc:
            notify(event.client, "Speed refused", str(exc), error=True)
            return
        for other in self._controls.each():  # every instructor's box says the rig's speed
            if other.speed.value != label:
                other.speed.value = label

    def _play(self, picked: str | None = None) -> None:
        self._ensure_loaded(picked, restart_finished=True)
        self.player.play()

    def _picked_path(self, picked: str | None = None) -> Path:
        """The picked scenario's file, else the loaded one's."""
        entry = self._entries.get(picked or "")
        if entry is not None:
            return entry.path
        if self._loaded is None:
            raise ScenarioError("pick a scenario first")
        return self._loaded

    def _ensure_loaded(self, picked: str | None = None, restart_finished: bool = False) -> None:
        """Load the picked scenario when it is not the one loaded (or when asked to)."""
        path = self._picked_path(picked)
        finished = self.player.view().status is Status.FINISHED
        if restart_finished and path == self._exercise_file:
            return  # Play goes on: the rig runs on after an exercise file (Player.play)
        if path != self._loaded or (restart_finished and finished):
            self.load(load_scenario(path), path)

    def load(self, scenario: Scenario, path: Path | None = None, fresh: Rig | None = None,
             run_on: bool = False) -> None:
        """Load ``scenario`` (on ``fresh``; ``run_on``: see :meth:`app.player.Player.load`)."""
        self.player.load(scenario, fresh, run_on)
        self._note_loaded(scenario, path)
        # run_on: an exercise file (the Classroom's Play file and start); reading it again as
        # a scenario is refused (app.scenario.parse_scenario says how it is played)
        self._exercise_file = self._loaded if run_on else None

    def _note_loaded(self, scenario: Scenario, path: Path | None = None) -> None:
        self._loaded = path if path is not None else Path(scenario.source)
        self._exercise_file = None
        self._show_picked(scenario, self._loaded)

    def _details(self) -> dict[str, str]:
        return {label: entry_detail(entry) for label, entry in self._entries.items()}

    def _loaded_label(self) -> str | None:
        loaded = self._loaded
        if loaded is None:
            return None
        return next((e.label for e in self._entries.values()
                     if e.path.resolve() == loaded.resolve()), None)

    def _show_picked(self, scenario: Scenario, path: Path) -> None:
        """Every picker names the loaded scenario, also one loaded from elsewhere (the CLI,
        an exercise file: in the instructor's pickers only, with a token)."""
        label = self._loaded_label()
        added = label is None
        if label is None:
            label = scenario.label if scenario.label not in self._entries else f"{path}"
            self._entries[label] = Entry(label, path, scenario)
        for controls in self._controls.each():
            if isinstance(controls.pick, ClientPick):  # every page's, as the player is
                if added:
                    controls.pick.set_options((CHOOSE, *self._entries))
                controls.pick.set_all(label)
                continue
            if added:
                controls.pick.options = (CHOOSE, *self._entries)
            if controls.pick.value != label:
                controls.pick.value = label

    def _picked(self, controls: _Controls, client_id: int | None = None) -> str:
        """:func:`picked_text` of the picked entry (on ``client_id``'s page, an open rig's),
        "" when none or when it is the loaded one."""
        entry = self._entries.get(_value(controls.pick, client_id))
        loaded = self._loaded
        if entry is None or (loaded is not None and entry.path.resolve() == loaded.resolve()):
            return ""
        return picked_text(entry)

    def shown_title(self) -> str:
        """The loaded scenario's name as every browser gets it ("" before any): the trainee
        title while an exercise runs (the event log's new-run row)."""
        scenario = self.player.view().scenario
        if scenario is None:
            return ""
        return self.trainee_title() or scenario.name

    @property
    def _pick(self) -> Any:
        """The shared picker of an open rig, a ClientPick (tests)."""
        return self._controls.each()[0].pick

    def page_picked(self, client_id: int | None) -> str:
        """The "Picked:" line under an open rig's controls on ``client_id``'s page."""
        text = self._picked(self._controls.each()[0], client_id)
        return f'<div class="fr-player-note" style="font-size:0.85em">{text}</div>' if text else ""

    def _show_pages(self, controls: _Controls) -> None:
        """Each page of an open rig its own pick's hint and "Picked:" line."""
        if controls.pages is not None:
            details = self._details()
            controls.pages.hint.show(lambda c: details.get(controls.pick.value_for(c)))
            controls.pages.picked.show(self.page_picked)

    # ---- the dashboard's update thread -----------------------------------------------------
    def update(self, frame: Frame) -> None:
        """``frame``: the one the dashboard is writing (the marker names it).

        The marker's ``data-frame`` and ``data-t-us`` move with every frame (30 a second even
        in an idle rig). A running rig's block is rewritten when what it says changes (text,
        step, generation, status), with the frame of that change. A paused rig's block names
        every frame written, as the screenshot tooling needs: it steps a paused rig and waits
        until ``data-frame`` reaches the runtime's frame (app/screenshots.py ``sync``).

        With a token the block is what a trainee may read (:func:`trainee_text`) and each
        instructor's copy of the controls gets the rest under them (:func:`instructor_text`)."""
        view = self.player.view()
        copies = self._controls.each()
        if self._shared:
            for controls in copies:
                self._show_pages(controls)
            text = status_text(view, frame.t_us, self.hint)
        else:
            title = self.trainee_title() if view.scenario is not None else None
            text = trainee_text(view, frame.t_us, title)
            loaded = self._loaded.name if self._loaded is not None else ""
            for controls in copies:
                own = instructor_text(view, title, loaded, self.hint, self._picked(controls))
                if controls.own.content != own:
                    controls.own.content = own
        said = (view.applied, view.generation, view.status, text)
        if said == self._said and not self._runtime.paused:
            return
        self._said = said
        content = status_html(view, frame, text)
        if content != self._last:
            self._status.content = content
            self._last = content
