"""Where a run writes: ``--out DIR``, ``--record FILE`` and ``--state-dir DIR`` checked before
anything runs.

A path that cannot take the output is a user's mistake like a wrong scenario file: one
``fieldrig: error:`` line and exit 2 before the run, not a traceback after it (with a recording
that looked complete). ``--out`` gets this run's files only: the files a previous run wrote
there (``events.jsonl``, ``NN-name.png``) go first; no other file is touched
(docs/scenarios.md "Output folder").
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from collections.abc import Iterable
from pathlib import Path

from app.rig_config import RigConfigError
from devices.events import Event

# What a run writes into --out (image_name, app/cli.py): nothing else is ever removed.
EVENTS_FILE = "events.jsonl"
RUN_FILE = re.compile(r"(events\.jsonl|\d{2,}-[A-Za-z0-9_.-]+\.png)")


def image_name(number: int, checkpoint: str) -> str:
    """``03-in_alarm.png``: numbered in scenario order, the name made file-safe."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", checkpoint).strip("_.") or "checkpoint"
    return f"{number:02d}-{safe}.png"


def _writable_parent(path: Path, flag: str, writable: bool = True) -> None:
    """The nearest existing ancestor of ``path`` must be a directory this process may write
    in (the missing ones are created at the start); with ``writable`` False, a directory."""
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise RigConfigError(flag, "", f"{path}: {parent} is not a directory")
    if writable:
        _can_make_files(parent, flag, f"{path}: cannot write in {parent}")


def _can_make_files(directory: Path, flag: str, refused: str) -> None:
    """A file can be made in ``directory``. access() answers yes to root for any directory,
    /proc and /sys included, where no file can be made: a trial file (removed at once) is
    the answer that holds for every user."""
    if not os.access(directory, os.W_OK | os.X_OK):
        raise RigConfigError(flag, "", refused)
    try:
        fd, trial = tempfile.mkstemp(prefix=".fieldrig-check-", dir=directory)
    except OSError as exc:
        raise RigConfigError(flag, "", f"{refused}: {exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(trial)


def check_record(path: str | Path, flag: str = "--record") -> Path:
    """A file a recording can be written to (created or replaced); nothing is created."""
    target = Path(path)
    if target.is_dir():
        raise RigConfigError(flag, "", f"{target} is a directory; give a file name, e.g. "
                                       f"{target / 'run.rrd'}")
    if target.exists():
        try:  # open for appending writes nothing; it fails where access() may say yes (root)
            with open(target, "ab"):
                pass
        except OSError as exc:
            raise RigConfigError(flag, "", f"{target}: cannot write to it: "
                                           f"{exc.strerror or exc}") from None
    _writable_parent(target, flag)
    return target


def check_out(path: str | Path, names: Iterable[str] = (EVENTS_FILE,)) -> Path:
    """A directory ``--out`` may be (existing or to be created), where each of ``names`` (the
    files this run will write) is free or a file of an earlier run; nothing is created."""
    out = Path(path)
    if out.exists():
        if not out.is_dir():
            raise RigConfigError("--out", "", f"{out} is a file, not a directory")
        _can_make_files(out, "--out", f"{out}: cannot write in it")
        for name in names:
            # Not removed before the run (not a file a run wrote): the run failed on it at
            # the end (events.jsonl) or mid-run (a screenshot), after all the work.
            taken = out / name
            if taken.is_symlink() or (taken.exists() and not taken.is_file()):
                raise RigConfigError("--out", "", f"{taken} is in the way (not a file); this "
                                                  "run writes its file there")
    else:
        _writable_parent(out, "--out")
    return out


def check_state_dir(path: str | Path, writable: bool = True) -> Path:
    """A directory ``--state-dir`` may keep flash files in (existing or to be created);
    nothing is created. A scenario run whose flash write fails gives another result than the
    one asked for (a SAVE_FLASH alarm): that is a bad flag, said before the run. Serving
    (``writable`` False) refuses only what cannot be a directory at all (a file, a path under
    a file): a directory that cannot be written is the devices' simulated flash failure
    there (docs/rig-file.md "Where the flash lives")."""
    state = Path(path)
    if state.exists():
        if not state.is_dir():
            raise RigConfigError("--state-dir", "", f"{state} is a file, not a directory")
        if writable:
            _can_make_files(state, "--state-dir", f"{state}: cannot write flash files in it")
    else:
        _writable_parent(state, "--state-dir", writable)
    return state


def check_recordings_dir(recordings: Path) -> None:
    """A served session records into ``STATE_DIR/recordings`` unless told otherwise: a state
    directory that serves (its flash failing as the devices' simulated failure) but where no
    file can be made cannot take the recording, and the recorder's own error named no flag."""
    state = recordings.parent
    way_out = "give --record PATH or --no-record"
    try:
        if recordings.is_dir():
            _can_make_files(recordings, "--state-dir", f"{recordings}: cannot write in it")
        else:
            _writable_parent(recordings, "--state-dir")
    except RigConfigError as exc:
        raise RigConfigError("--state-dir", "", f"{state}: the session's recording cannot "
                                                f"go there ({exc.reason}); {way_out}") from None


def prepare_out(out: Path) -> list[Path]:
    """Create ``out`` and remove what an earlier run wrote there; the files removed."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RigConfigError("--out", "", f"{out}: {exc.strerror or exc}") from None
    removed = []
    for entry in sorted(out.iterdir()):
        if RUN_FILE.fullmatch(entry.name) and entry.is_file() and not entry.is_symlink():
            try:
                entry.unlink()
            except OSError as exc:
                raise RigConfigError("--out", "", f"{entry}: cannot remove the earlier "
                                                  f"run's file: {exc.strerror or exc}") from None
            removed.append(entry)
    return removed


def _umask() -> int:
    """The process's umask, read where Linux shows it: setting it to read it back would
    change it for a moment under the threads still running (viser's, the recorder's)."""
    try:
        for line in Path("/proc/self/status").read_text(encoding="ascii").splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_events(out: Path, text: str) -> Path:
    """``out/events.jsonl``, the last file of a run, whole or not at all: written to a
    temporary file in ``out`` and renamed over (atomic on POSIX), so a reader never sees half
    a file and a folder without it is a run that did not finish (docs/scenarios.md "Output
    folder"). The temporary file goes if the write fails or is interrupted. Its mode is
    what open() gives the pictures beside it (0666 less the umask), not mkstemp's 0600: a CI
    job's artifact store or web server, another user, reads the folder."""
    fd, tmp = tempfile.mkstemp(prefix=f".{EVENTS_FILE}.", dir=out)
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, out / EVENTS_FILE)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out / EVENTS_FILE


def event_lines(events: Iterable[Event]) -> str:
    """The JSON lines of ``scenario run``: stdout and ``events.jsonl`` (docs/scenarios.md)."""
    return "".join(json.dumps(e.to_record(), default=str) + "\n" for e in events)
