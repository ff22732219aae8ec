"""``python -m app --scenarios DIR`` (docs/scenarios.md "Your own scenarios"): the picker lists
the scenarios of DIR first, then the shipped ones of ``static/scenarios/``. Before, the picker
listed only the shipped ones and a sales engineer's own scenarios could not be played in the
dashboard at all. A folder that cannot serve (missing, not a folder, unreadable, no *.toml, a
file that does not load or that its rig would refuse) is one error line at start, exit 2."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import viser

from app.cli import main
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.panels import classroom_rig
from app.ui.panels.scenario_player import CHOOSE, PLAY, ScenarioPlayerPanel, library

OWN = """[scenario]
name = "{name}"
duration_s = 1

[[step]]
at = 0.0
target = "fastcat"
action = "power"
on = true
"""


def own_dir(tmp_path: Path, **files: str) -> Path:
    folder = tmp_path / "my"
    folder.mkdir()
    for stem, name in files.items():
        (folder / f"{stem}.toml").write_text(OWN.format(name=name), encoding="utf-8")
    return folder


def refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], folder: Path) -> str:
    rc = main(["--scenarios", str(folder), "--state-dir", str(tmp_path / "s"), "--no-record",
               "--run-for", "0", "--port", str(free_port())])
    captured = capsys.readouterr()
    err = captured.err.splitlines()
    assert rc == 2, (captured.out, err)
    assert len(err) == 1 and err[0].startswith("fieldrig: error: "), err
    assert "serving" not in captured.out
    return err[0]


@pytest.fixture
def panel_on(tmp_path: Path) -> Iterator[Any]:
    servers: list[viser.ViserServer] = []
    runtimes: list[Runtime] = []

    def make(folder: Path) -> ScenarioPlayerPanel:
        runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
        runtime.set_paused(True)
        runtime.start()
        runtimes.append(runtime)
        servers.append(viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False))
        return ScenarioPlayerPanel(servers[-1], runtime, own=folder)

    try:
        yield make
    finally:
        for runtime in runtimes:
            runtime.stop()
        for server in servers:
            server.stop()


def test_the_picker_lists_the_own_scenarios_first_then_the_shipped_ones(tmp_path: Path,
                                                                         panel_on) -> None:
    folder = own_dir(tmp_path, demo="Sales demo: my flow", b_other="Another of mine")
    panel = panel_on(folder)
    options = list(panel._pick.options)
    assert options[:3] == [CHOOSE, "Another of mine", "Sales demo: my flow"], options
    shipped = [e.label for e in library()]
    assert all(any(o.endswith(label) for o in options) for label in shipped)
    assert len(options) == 3 + len(shipped)
    client = _Client()
    panel._pick.set_all("Sales demo: my flow")
    panel._run(client, PLAY)
    assert client.notes == []
    view = panel.player.view()
    assert view.scenario is not None and view.scenario.name == "Sales demo: my flow"


def test_an_own_scenario_named_as_a_shipped_one_is_told_apart(tmp_path: Path,
                                                               panel_on) -> None:
    shipped = library()[0]
    folder = own_dir(tmp_path, **{shipped.path.stem: shipped.scenario.name})
    options = list(panel_on(folder)._pick.options)
    mine = [o for o in options if o.endswith(f"({folder.name}/{shipped.path.stem})")]
    theirs = [o for o in options if o.endswith(f"({shipped.path.stem})") and o not in mine]
    assert len(mine) == 1 and len(theirs) == 1, options


def test_serve_passes_the_folder_to_the_picker(tmp_path: Path, monkeypatch) -> None:
    folder = own_dir(tmp_path, demo="Sales demo: my flow")
    seen: list[Any] = []
    real = classroom_rig.serve_rig

    def spy(*args: Any, **kwargs: Any) -> Any:
        served = real(*args, **kwargs)
        seen.append(list(served.dashboard.scenario_player._pick.options))
        return served

    monkeypatch.setattr(classroom_rig, "serve_rig", spy)
    assert main(["--scenarios", str(folder), "--state-dir", str(tmp_path / "s"),
                 "--no-record", "--run-for", "0", "--port", str(free_port()),
                 "--modbus-port", str(free_port())]) == 0
    assert seen and seen[0][1] == "Sales demo: my flow", seen


def test_a_missing_folder_is_one_error_at_start(tmp_path: Path, capsys) -> None:
    line = refused(tmp_path, capsys, tmp_path / "nope")
    assert line == f"fieldrig: error: --scenarios: {tmp_path / 'nope'}: no such folder"


def test_a_file_is_not_a_folder(tmp_path: Path, capsys) -> None:
    (tmp_path / "one.toml").write_text(OWN.format(name="x"), encoding="utf-8")
    line = refused(tmp_path, capsys, tmp_path / "one.toml")
    assert line.endswith("one.toml: not a folder (give the folder that holds the *.toml "
                         "files)"), line


def test_an_unreadable_folder_is_one_error_at_start(tmp_path: Path, capsys,
                                                    monkeypatch) -> None:
    folder = own_dir(tmp_path, demo="x")

    def denied(self: Path) -> Iterator[Path]:
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "iterdir", denied)  # root reads any folder: chmod 000 is moot
    line = refused(tmp_path, capsys, folder)
    assert line == f"fieldrig: error: --scenarios: {folder}: cannot read it (Permission denied)"


def test_a_folder_without_scenarios_is_one_error_at_start(tmp_path: Path, capsys) -> None:
    folder = own_dir(tmp_path)
    line = refused(tmp_path, capsys, folder)
    assert line == f"fieldrig: error: --scenarios: {folder}: no *.toml in it"


def test_a_broken_own_scenario_is_one_error_at_start(tmp_path: Path, capsys) -> None:
    folder = own_dir(tmp_path, demo="x")
    (folder / "bad.toml").write_text("[scenario]\nname = \"bad\"\n[[step]]\nat = 0.0\n"
                                     "target = \"fastcat\"\naction = \"powr\"\n",
                                     encoding="utf-8")
    line = refused(tmp_path, capsys, folder)
    assert "bad.toml: step[0]" in line and "powr" in line, line


class _Client:
    client_id = 1

    def __init__(self) -> None:
        self.notes: list[tuple[str, str]] = []

    def add_notification(self, title: str, body: str, color: str = "",
                         auto_close_seconds: Any = None) -> None:
        self.notes.append((title, body))
