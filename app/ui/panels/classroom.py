"""The Classroom folder: roles, exercises, scores and the recording download, per browser.

The folder itself is server-level; what is inside is built per connection (viser's client
GUI inside a server container), so each browser sees its role's part only:

- everyone: "You are the instructor / a trainee", the exercise question (name a cause, done);
- a trainee of a rig served with a token: the instructor login form;
- the instructor: the hidden-fault picker, Start / End, the hidden fault, the trainees'
  answer, actions and score, the refused commands, the scores so far, Download recording.

Hiding is for the eyes only; the server enforces the roles in
:class:`app.ui.commands.CommandSender` whatever a browser sends. The exercise logic is
:mod:`app.classroom.exercise` (docs/classroom.md).
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import viser

from app.classroom.exercise import Exercise, Phase
from app.classroom.exercise_file import check_exercise, load_exercise, start_us
from app.classroom.faults import Catalog, catalog
from app.classroom.names import ConnectionNames
from app.classroom.roles import Operation, Role
from app.rig_config import RigConfigError
from app.runtime import Runtime
from app.ui.commands import CommandSender, Sent, notify
from app.ui.panels.classroom_access import TokenForm, read_browser_token
from app.ui.panels.classroom_html import Audience, history_html, instructor_html, trainee_html
from app.ui.panels.per_client import connected, release_gone
from app.ui.panels.widgets import instructor_folders, widget_uuid
from app.ui.style import INSTRUCTOR_CLASS
from devices.device import CommandError
from devices.events import LogLine

if TYPE_CHECKING:  # rerun loads with a recorder only (app/recording/allocators.py)
    from app.recording import RigRecorder

logger = logging.getLogger(__name__)

UPDATE_S = 0.5
WAIT_S = 10.0
NO_FAULT = "(pick a hidden fault)"
NO_CAUSE = "(pick the cause)"
NO_FILE = "(pick an exercise file)"
START, END = "Start exercise", "End and score"


def trainee_css(widgets: Sequence[Any] = ()) -> str:
    """The style a trainee's page gets: no element of :data:`INSTRUCTOR_CLASS` (the injected
    causes in the state tables), no row of these server-level widgets (fault pickers, the
    boxes that follow an injected physical fault) and no folder left with none of its rows
    (:func:`instructor_folders`: no empty "Alarms and load" title). viser 1.1.1 has no
    per-client visibility for a server-level widget; its client renders a widget's uuid as
    the input's ``id`` and its label's ``for``, inside the row's two wrappers
    (components/common.tsx): the rule hides that outer wrapper, padding and all. A folder
    is its bordered wrapper, four levels above its rows (wrapper, collapse, box, container:
    components/Folder.tsx), found by one of its own rows (tests/browser/test_classroom.py)."""
    rules = [f".{INSTRUCTOR_CLASS}"]
    for uuid in map(widget_uuid, widgets):
        rules.append(f'div:has(> div > div > p > label[for="{uuid}"])')  # a labelled input
        rules.append(f'div:has(> button[id="{uuid}"])')  # a button
    for folder in instructor_folders(widgets):
        for uuid in map(widget_uuid, _rows(folder)):
            rules.append(f'div:has(> {_FOLDER_TO_ROW} > div > div > p > label[for="{uuid}"])')
            rules.append(f'div:has(> {_FOLDER_TO_ROW} > button[id="{uuid}"])')
    return f"<style>{', '.join(rules)} {{ display: none !important; }}</style>"


_FOLDER_TO_ROW = "div > div > div > div"  # collapse, box, container, the row's wrapper


def _rows(folder: Any) -> list[Any]:
    """A folder's own widgets (not its sub-folders, whose rows sit deeper)."""
    return [c for c in folder._children.values() if not isinstance(c, viser.GuiFolderHandle)]


@dataclass
class _View:
    """The handles one connection got; removed and rebuilt when its role changes."""

    role: Role
    client_id: int | None = None
    handles: list[Any] = field(default_factory=list)
    trainee: Any = None
    instructor: Any = None
    history: Any = None
    shown: dict[str, str] = field(default_factory=dict)
    form: TokenForm | None = None


class ClassroomPanel:
    def __init__(self, server: viser.ViserServer, runtime: Runtime, sender: CommandSender,
                 recorder: RigRecorder | None = None, download_name: str = "fieldrig.rrd",
                 player: Any = None, exercise_files: Sequence[Path] = (),
                 instructor_widgets: Sequence[Any] = (),
                 on_instructor: Callable[[viser.ClientHandle], None] | None = None) -> None:
        """``player``: the dashboard's ScenarioPlayerPanel, which plays an exercise file's
        scenario; ``exercise_files``: what the instructor may pick from;
        ``instructor_widgets``: the dashboard's widgets a trainee's page does not show
        (:func:`trainee_css`); ``on_instructor``: called with each connection whose role is
        (now) the instructor (the dashboard builds its instructor parts for it)."""
        self._on_instructor = on_instructor
        self._trainee_css = trainee_css(instructor_widgets)
        self._server, self._runtime, self._sender = server, runtime, sender
        self.access = sender.gate.access
        self._recorder = recorder
        self._download_name = download_name
        self._player = player
        self._file_pending = False  # an exercise file plays, its hidden fault not in yet
        if player is not None:
            player.trainee_title = self.trainee_title
        self._files = {p.stem: p for p in exercise_files}
        self.catalog: Catalog = catalog(runtime.rig.describe(), runtime.frame.snapshot)
        self._faults = {f.label: f for f in self.catalog.faults}
        self._causes = {c.label: c for c in self.catalog.causes}
        self._lock = threading.RLock()
        self._build_lock = threading.Lock()
        self.exercise: Exercise | None = None
        self.history: list[dict[str, Any]] = []
        self.refusals: collections.deque[str] = collections.deque(maxlen=20)
        self.names = ConnectionNames()  # "trainee 1", ...: the instructor's lists name them
        self._views: dict[int, _View] = {}
        self._folder = server.gui.add_folder("Classroom", expand_by_default=True)
        self._stop = threading.Event()
        sender.gate.observe(self._on_sent)
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        self._thread = threading.Thread(target=self._run, name="fieldrig-classroom",
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)

    # ---- the exercise (also called by tests and exercise files) ---------------------------
    def start_exercise(self, fault_id: str, module: int | None = None,
                       client: viser.ClientHandle | None = None,
                       channel: int | None = None) -> Exercise | None:
        if not self._sender.allow(client, Operation.EXERCISE, "start an exercise"):
            return None
        with self._lock:
            if self.exercise is not None and self.exercise.phase is not Phase.FINISHED:
                raise ValueError("an exercise is running: end it first")
            fault = self.catalog.fault(fault_id).at(module, channel)
            for command in fault.inject:
                self._apply(command.target, command.action, dict(command.args))
            self.exercise = Exercise(fault, time.monotonic())
            # The instructor's list shows this exercise's refusals (and the ones after it)
            # only: older ones mixed in could not be told apart.
            self.refusals.clear()
        self._log(f"exercise started by connection {self._id(client)} (the fault is hidden)")
        return self.exercise

    def start_from_file(self, path: Path, client: viser.ClientHandle | None = None) -> int:
        """Play an exercise file's scenario from a factory-fresh rig and inject its hidden
        fault at its time (a watcher thread), the rig running on after the file's end;
        returns that time in simulated us."""
        if not self._sender.allow(client, Operation.EXERCISE, "start an exercise"):
            raise PermissionError("exercises are for the instructor")
        if self._player is None:
            raise ValueError("this dashboard has no scenario player")
        scenario, spec = load_exercise(path)
        # The file may have changed since the server's start check: checked again, on the rig
        # it will play on, before anything changes (ScenarioError, one line).
        fresh = self._player.player.fresh_rig(scenario)
        check_exercise(scenario, spec, fresh, self.catalog)
        with self._lock:
            if self.exercise is not None and self.exercise.phase is not Phase.FINISHED:
                raise ValueError("an exercise is running: end it first")
        # Before the load: its new-run row and first status already read the trainee title.
        self._file_pending = True
        try:
            # The rig runs on after the file's last step: paused there, the hidden fault would
            # never develop (the clock stands at the injection time).
            self._player.load(scenario, path, fresh=fresh, run_on=True)
        except BaseException:
            self._file_pending = False
            raise
        generation = self._player.player.view().generation
        at = start_us(scenario, spec)
        self._player.player.play()

        def inject_when_due() -> None:
            try:
                while not self._stop.wait(0.05):
                    if self._player.player.view().generation != generation:
                        return  # another scenario was loaded meanwhile
                    if self._runtime.frame.t_us >= at:
                        try:
                            self.start_exercise(spec.fault, spec.module, channel=spec.channel)
                        except (ValueError, KeyError, CommandError) as exc:
                            logger.warning("exercise file %s: %s", path, exc)
                        return
            finally:
                self._file_pending = False

        threading.Thread(target=inject_when_due, name="fieldrig-exercise", daemon=True).start()
        self._log(f"exercise file {path.name} started by connection {self._id(client)}")
        return at

    def trainee_title(self) -> str | None:
        """The Scenario tab's title for every browser while an exercise runs (or an exercise
        file plays towards its hidden fault) on a rig with a token: "Exercise N", as the
        exercise format has no trainee-facing title and a scenario's own ("CPX short")
        can name the fault. None: the scenario's own title (no exercise, or an open rig,
        where everyone is the instructor)."""
        exercise = self.exercise
        running = exercise is not None and exercise.phase is not Phase.FINISHED
        if self.access.open or not (running or self._file_pending):
            return None
        return f"Exercise {len(self.history) + 1}"

    def name_cause(self, cause_id: str, client: viser.ClientHandle | None = None) -> bool:
        """A trainee's answer; the right cause gets its repair (True). With a token the
        instructor's page has the form too but its answer is refused: it knows the hidden
        fault, and a first answer from it would repair the fault and lock the trainees out."""
        if not self.access.open and client is not None \
                and self.access.role(client.client_id) is Role.INSTRUCTOR:
            raise PermissionError("the trainees name the cause; the instructor ends the "
                                  "exercise with End and score")
        with self._lock:
            exercise = self.exercise
            if exercise is None or exercise.phase is Phase.FINISHED:
                raise ValueError("no exercise is running")
            right = exercise.name_cause(time.monotonic(), cause_id, self._id(client))
            if right:
                for command in exercise.fault.repair:
                    self._apply(command.target, command.action, dict(command.args))
        who = self.names.name(self._id(client), self.access.role(self._id(client)))
        self._log(f"{who} (connection {self._id(client)}) named a cause")
        return right

    def finish(self, client: viser.ClientHandle | None = None,
               as_instructor: bool = False) -> dict[str, Any]:
        """Check the rig, score, and repair the fault's cause if it is still there."""
        if as_instructor and not self._sender.allow(client, Operation.EXERCISE, "end"):
            raise PermissionError("ending an exercise is for the instructor")
        with self._lock:
            exercise = self.exercise
            if exercise is None or exercise.phase is Phase.FINISHED:
                raise ValueError("no exercise is running")
            if not as_instructor and exercise.phase is not Phase.ANSWERED:
                raise ValueError("name a cause first")
            snapshot = self._runtime.submit(self._runtime.rig.snapshot).result(timeout=WAIT_S)
            exercise.finish(time.monotonic(), snapshot)
            if not exercise.cause_right:
                for command in exercise.fault.repair:
                    try:
                        self._apply(command.target, command.action, dict(command.args))
                    except CommandError:
                        logger.debug("repair after the exercise", exc_info=True)
            report = exercise.report(self.catalog)
            self.history.append(report)
        self._log(f"exercise finished: score {report['score']['total']}")
        return report

    # ---- connections ------------------------------------------------------------------------
    def _connect(self, client: viser.ClientHandle) -> None:
        if not self._build(client):
            return  # the page closed meanwhile
        if not self.access.open:  # its own thread: it waits for the page to render
            def alive() -> bool:
                return (not self._stop.is_set()
                        and client.client_id in self._server.get_clients())

            threading.Thread(target=read_browser_token, name="fieldrig-token", daemon=True,
                             args=(client, self.access, self._promoted),
                             kwargs={"alive": alive}).start()

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self._views.pop(client.client_id, None)
        self.access.forget(client.client_id)

    def _promoted(self, client: viser.ClientHandle) -> None:
        logger.info("connection %s is the instructor", client.client_id)
        notify(client, "Instructor", "You are the instructor of this rig.")
        self._build(client)

    def _build(self, client: viser.ClientHandle) -> bool:
        """Build ``client``'s part of the folder; False if its page closed meanwhile (then
        nothing of it is kept, and no traceback: viser's KeyError from a client folder it
        already released is that case)."""
        with self._build_lock:  # a connect and a login of one browser never interleave
            try:
                built = self._build_locked(client)
            except KeyError:
                if connected(self._server, client):
                    raise
                built = False
            if built and self._on_instructor is not None \
                    and self.access.role(client.client_id) is Role.INSTRUCTOR:
                self._on_instructor(client)
        if not built:
            logger.debug("connection %s closed during its build", client.client_id)
            release_gone(client)
        return built

    def _build_locked(self, client: viser.ClientHandle) -> bool:
        role = self.access.role(client.client_id)
        with self._lock:
            old = self._views.pop(client.client_id, None)
        if old is not None:
            for handle in reversed(old.handles):
                handle.remove()
        view = _View(role, client.client_id)
        gui = client.gui
        with self._folder:
            view.handles.append(gui.add_markdown(
                f"You are **{'the instructor' if role is Role.INSTRUCTOR else 'a trainee'}**"))
            if role is Role.TRAINEE:
                # What the dashboard marks as the instructor's (the injected causes, the
                # fault pickers) is not shown on a trainee's page.
                view.handles.append(gui.add_html(self._trainee_css))
                view.form = TokenForm(client, self.access, self._promoted)
                view.handles.append(view.form)
            self._answer_controls(client, view)
            if role is Role.INSTRUCTOR:
                self._instructor_controls(client, view)
        with self._lock:
            # Under the lock _disconnect takes, which runs after viser let the client go: a
            # view stored here is removed by it, one of a page already gone is not stored.
            if not connected(self._server, client):
                return False
            self._views[client.client_id] = view
        self._refresh(view)
        return True

    def _answer_controls(self, client: viser.ClientHandle, view: _View) -> None:
        gui = client.gui
        folder = gui.add_folder("Exercise")
        view.handles.append(folder)
        with folder:
            view.trainee = gui.add_html(trainee_html(None, 0.0,
                                                     audience=self._audience(view.role)))
            cause = gui.add_dropdown("Cause", (NO_CAUSE, *self._causes))
            name = gui.add_button("Name the cause", icon=viser.Icon.CHECK)
            done = gui.add_button("Done", hint="the rig runs again: check and score")

        def on_name(_event: viser.GuiEvent) -> None:
            picked = self._causes.get(str(cause.value))
            if picked is None:
                notify(client, "Exercise", "pick a cause first", error=True)
                return
            self._guarded(client, lambda: self.name_cause(picked.id, client),
                          "Answer recorded: reset what stays latched, then press Done.")

        name.on_click(on_name)
        done.on_click(lambda _e: self._guarded(client, lambda: self.finish(client),
                                               "Exercise finished: thank you."))

    def _instructor_controls(self, client: viser.ClientHandle, view: _View) -> None:
        gui = client.gui
        folder = gui.add_folder("Instructor")
        view.handles.append(folder)
        with folder:
            fault = gui.add_dropdown("Hidden fault", (NO_FAULT, *self._faults))
            module = gui.add_number("Module", 1, min=1, max=64, step=1,
                                    hint="for module codes (§7.6): the module number")
            buttons = gui.add_button_group("Exercise control", (START, END))
            if self._files and self._player is not None:
                picked_file = gui.add_dropdown("Exercise file", (NO_FILE, *self._files))
                from_file = gui.add_button("Play file and start", icon=viser.Icon.PLAYER_PLAY,
                                           hint="the file's scenario, then its hidden fault")

                def on_file(_event: viser.GuiEvent) -> None:
                    path = self._files.get(str(picked_file.value))
                    if path is None:
                        notify(client, "Exercise", "pick an exercise file first", error=True)
                        return
                    self._guarded(client, lambda: self.start_from_file(path, client),
                                  "Scenario playing; the hidden fault follows.")

                from_file.on_click(on_file)
            view.instructor = gui.add_html(instructor_html(None, 0.0))
            gui.add_markdown("**Scores**")
            view.history = gui.add_html(history_html([]))
            download = gui.add_button("Download recording", icon=viser.Icon.DOWNLOAD,
                                      disabled=self._recorder is None)

        def on_button(_event: viser.GuiEvent) -> None:
            if buttons.value == START:
                picked = self._faults.get(str(fault.value))
                if picked is None:
                    notify(client, "Exercise", "pick a hidden fault first", error=True)
                    return
                self._guarded(client, lambda: self.start_exercise(
                    picked.id, int(module.value) if picked.module else None, client),
                    "Exercise started.")
            else:
                self._guarded(client, lambda: self.finish(client, as_instructor=True),
                              "Exercise scored.")

        buttons.on_click(on_button)
        download.on_click(lambda _e: self.download(client))

    def download(self, client: viser.ClientHandle | None) -> bytes | None:
        """Flush the session's recording and send it to ``client``'s browser."""
        if not self._sender.allow(client, Operation.RECORDING, "download the recording"):
            return None
        if self._recorder is None:
            notify(client, "Recording", "this session is not recorded", error=True)
            return None
        data = self._recorder.recording_bytes()
        if client is not None:
            client.send_file_download(self._download_name, data, save_immediately=True)
        return data

    # ---- helpers --------------------------------------------------------------------------
    def _guarded(self, client: viser.ClientHandle, fn: Callable[[], Any], ok: str) -> None:
        try:
            fn()
        except (ValueError, KeyError, CommandError, PermissionError, RigConfigError) as exc:
            notify(client, "Exercise", str(exc), error=True)
            return
        notify(client, "Exercise", ok)

    def _apply(self, target: str, action: str, args: dict[str, Any]) -> Any:
        return self._runtime.command(target, action, args).result(timeout=WAIT_S)

    def _log(self, text: str) -> None:
        logger.info("%s", text)
        self._runtime.journal([LogLine(t_us=self._runtime.frame.t_us, device="classroom",
                                       text=text)])

    def _audience(self, role: Role) -> Audience:
        """Whose words the Exercise box says (classroom_html.trainee_html)."""
        if role is Role.TRAINEE:
            return "trainee"
        return "open" if self.access.open else "instructor"

    @staticmethod
    def _id(client: viser.ClientHandle | None) -> int | None:
        return None if client is None else client.client_id

    def _on_sent(self, sent: Sent) -> None:
        if sent.refused:
            who = self.names.name(sent.client_id, sent.role)
            self.refusals.append(f"{who} {sent.target}: {sent.refused}")
        exercise = self.exercise
        if sent.role is Role.INSTRUCTOR and not self.access.open:
            return  # the instructor's own commands are not the trainees' actions
        if exercise is not None and sent.client_id is not None:
            self.names.name(sent.client_id, sent.role)  # named at its first act
            args = " ".join(f"{k}={v}" for k, v in sent.args.items())
            exercise.record(time.monotonic(), sent.client_id, sent.role.value,
                            f"{sent.target}: {sent.action} {args}".strip(), sent.refused)

    # ---- the update thread ----------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.wait(UPDATE_S):
            with self._lock:
                views = list(self._views.values())
            for view in views:
                try:
                    self._refresh(view)
                except Exception:  # the browser may be gone: the next disconnect cleans up
                    logger.debug("classroom refresh failed", exc_info=True)

    def _refresh(self, view: _View) -> None:
        exercise = self.exercise
        report = exercise.report(self.catalog) if exercise is not None else None
        elapsed = 0.0
        if exercise is not None:
            end = exercise.finished_s
            elapsed = end if end is not None else time.monotonic() - exercise.started_s
        mine = report is not None and report["answered_by"] == view.client_id
        name = self.names.get(view.client_id) if view.role is Role.TRAINEE else None
        self._show(view, "trainee", view.trainee, trainee_html(
            report, elapsed, mine, audience=self._audience(view.role), name=name or ""))
        if view.instructor is not None:
            self._show(view, "instructor", view.instructor,
                       instructor_html(report, elapsed, list(self.refusals), self.names))
            self._show(view, "history", view.history, history_html(self.history))

    @staticmethod
    def _show(view: _View, key: str, handle: Any, content: str) -> None:
        if handle is not None and view.shown.get(key) != content:
            handle.content = content
            view.shown[key] = content
