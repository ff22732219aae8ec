"""Several rigs in one process (issue 6: "a trainee can be given a rig of their own"):
``python -m app --rigs 2`` serves each copy at its own URL with its own state directory and
recording, and prints the URLs and the instructor token."""

from __future__ import annotations

import re
import socket
import urllib.request
from pathlib import Path
from types import SimpleNamespace

import pytest
from served_process import free_ports, start_serving

from app.cli import main
from app.ui.panels.classroom_rig import ServedRig


def test_two_rigs_two_urls(tmp_path: Path) -> None:
    port, modbus = free_ports(2, 23000), free_ports(2, 33000)
    proc, text = start_serving(
        "--rigs", "2", "--port", str(port), "--modbus-port", str(modbus),
        "--state-dir", str(tmp_path / "state"), "--instructor-token", "tok-1",
        "--run-for", "60")
    try:
        urls = re.findall(r"rig (\d) '[^']+' at (http://\S+)", text)
        assert [u for _, u in urls] == [f"http://127.0.0.1:{port}/",
                                        f"http://127.0.0.1:{port + 1}/"], text
        assert "instructor token tok-1" in text and "?token=tok-1" in text
        for _, url in urls:
            with urllib.request.urlopen(url, timeout=10) as page:
                assert page.status == 200 and b"<html" in page.read().lower()
        for i in (1, 2):
            recordings = list((tmp_path / "state" / f"rig{i}" / "recordings").glob("*.rrd"))
            assert len(recordings) == 1, i
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def test_bad_multi_rig_flags(capsys: object, tmp_path: Path) -> None:
    assert main(["--rigs", "0", "--state-dir", str(tmp_path), "--run-for", "0"]) == 2
    assert main(["--rigs", "2", "--can-interface", "udp_multicast", "--state-dir",
                 str(tmp_path), "--run-for", "0"]) == 2
    assert main(["--instructor-token", " ", "--state-dir", str(tmp_path), "--run-for", "0"]) \
        == 2


def test_broken_exercise_file_exits_2(tmp_path: Path, capsys: object) -> None:
    (tmp_path / "bad.toml").write_text('[exercise]\nfault = ""\n')
    assert main(["--exercises", str(tmp_path), "--state-dir", str(tmp_path / "s"),
                 "--run-for", "0"]) == 2
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["--exercises", str(empty), "--state-dir", str(tmp_path / "s"),
                 "--run-for", "0"]) == 2


EXERCISE = """[scenario]
name = "x"
[[step]]
at = 0.0
target = "{target}"
action = "power"
on = true
[exercise]
fault = "{fault}"
"""


@pytest.mark.parametrize(("target", "fault", "said"), [
    ("drive", "no:such:fault", "no hidden fault 'no:such:fault' on this rig"),
    ("drive", "fastcat:inject:coupler:0x99", "no hidden fault"),
    ("nosuchdevice", "fastcat:inject:coupler:0x04", "nosuchdevice"),
    # a module code (§7.6) without `module =`: the FastCAT model's own check_command rule
    ("fastcat", "fastcat:inject:module:0x0B", "module alarm (§7.6)"),
    # the CPX-E-EC's and the TRS-CAT's module faults: their check_command rules too
    ("cpx", "cpx:inject:fault:module_failure", "module_failure needs a module: target 'cpx/N'"
     "; give its module: module = N"),
    ("trscat", "trscat:inject:fault:AN_PLUS_12V", "AN_PLUS_12V (0x5114) is a TRS-AN-E fault"),
])
def test_an_exercise_the_rig_cannot_play_exits_2_before_serving(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], target: str, fault: str,
        said: str) -> None:
    """docs/classroom.md: every file is checked at start. A fault id the rig does not have,
    or a step the rig would refuse, passed the start and failed only at *Play file and
    start* (a KeyError in the instructor's page)."""
    (tmp_path / "ex.toml").write_text(EXERCISE.format(target=target, fault=fault))
    assert main(["--exercises", str(tmp_path), "--state-dir", str(tmp_path / "s"),
                 "--run-for", "0", "--no-record"]) == 2
    err = capsys.readouterr().err
    assert "ex.toml" in err and said in err and "Traceback" not in err


def test_a_wildcard_host_is_shown_by_the_machine_name() -> None:
    """Served on 0.0.0.0 the server printed http://0.0.0.0:8190/, which no trainee's browser
    can open; the machine's name stands in (README: http://THIS-MACHINE:8081/)."""
    token = SimpleNamespace(access=SimpleNamespace(token="tok"))
    one = ServedRig(None, None, None, None, token, None, "0.0.0.0", 8081)  # type: ignore[arg-type]
    name = socket.gethostname()
    assert one.url == "http://0.0.0.0:8081/"
    assert one.shown_url == f"http://{name}:8081/"
    assert one.instructor_url == f"http://{name}:8081/?token=tok"
    loopback = ServedRig(None, None, None, None, token, None, "127.0.0.1", 8080)  # type: ignore[arg-type]
    assert loopback.shown_url == loopback.url == "http://127.0.0.1:8080/"


def test_an_ipv6_host_is_shown_in_brackets() -> None:
    """--host ::1 printed http://::1:8192/, which no browser opens (RFC 3986 §3.2.2)."""
    token = SimpleNamespace(access=SimpleNamespace(token="tok"))
    six = ServedRig(None, None, None, None, token, None, "::1", 8192)  # type: ignore[arg-type]
    assert six.url == six.shown_url == "http://[::1]:8192/"
    assert six.instructor_url == "http://[::1]:8192/?token=tok"


def test_a_module_fault_with_its_module_passes_the_start_check(tmp_path: Path) -> None:
    """The module check asks for `module =`, and takes a file that gives it."""
    from app.classroom.exercise_file import check_exercise, load_exercise
    from app.classroom.faults import catalog
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec

    path = tmp_path / "ex.toml"
    path.write_text(EXERCISE.format(target="fastcat", fault="fastcat:inject:module:0x0B")
                    + "module = 2\n")
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    scenario, spec = load_exercise(path)
    fault = check_exercise(scenario, spec, rig, catalog(rig.describe(), rig.snapshot()))
    assert fault.inject[0].target == "fastcat/2"


@pytest.mark.parametrize(("fault", "module", "said"), [
    # the default rig's CPX-E-EC holds modules 1..4, its TRS-CAT one TRS-AN-E at 2
    ("cpx:inject:fault:module_failure", 9, "cpx: no module 9 (modules: 1=16DI"),
    ("trscat:inject:fault:AN_PLUS_12V", 5, "trscat: no expansion at position 5"),
    # the FastCAT's seven modules: a §7.6 code on an empty rail position
    ("fastcat:inject:module:0x0B", 9, "fastcat: TARATURA is a module alarm (§7.6): there is "
     "no module 9, rail position 9 is empty (modules: 1=DB16, 2=DI16, 3=DO16, 4=AI8D, 5=AO4, "
     "6=AI8TC, 7=AX2)"),
])
def test_an_exercise_module_the_device_does_not_hold_exits_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], fault: str, module: int,
        said: str) -> None:
    """`module = 9` on a four-module CPX-E-EC passed the start check (check_command knows
    no modules) and failed only at the injection, in the instructor's background thread. The
    modules the device holds after the file's steps are checked as a scenario's are
    (check_module)."""
    device = fault.split(":", 1)[0]
    (tmp_path / "ex.toml").write_text(EXERCISE.format(target=device, fault=fault)
                                      + f"module = {module}\n")
    assert main(["--exercises", str(tmp_path), "--state-dir", str(tmp_path / "s"),
                 "--run-for", "0", "--no-record"]) == 2
    err = capsys.readouterr().err
    assert "ex.toml" in err and said in err and "Traceback" not in err, err


@pytest.mark.parametrize(("target", "fault", "said"), [
    # the ids of the device named, on the one line
    ("fastcat", "fastcat:inject:coupler:0x99",
     "fastcat's hidden faults: fastcat:inject:coupler:{0x01,0x02,"),
    ("fastcat", "fastcat:inject:coupler:0x99", ", fastcat:cable, fastcat:tbus_low"),
    # a device the rig does not have: the closest ids
    ("fastcat", "fastcatt:cable", "closest: fastcat:cable"),
    # a bad step: the file named once
    ("fastcatt", "fastcat:cable", "ex.toml: step[0] (at 0 s): no device 'fastcatt'"),
])
def test_an_exercise_error_is_one_line_that_helps(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], target: str, fault: str,
        said: str) -> None:
    """An unknown id listed only prefixes ("ids start cpx:..., drive:..."), and a bad step
    named the file twice ("x.toml: x.toml: step[0] ...")."""
    path = tmp_path / "ex.toml"
    path.write_text(EXERCISE.format(target=target, fault=fault))
    assert main(["--exercises", str(tmp_path), "--state-dir", str(tmp_path / "s"),
                 "--run-for", "0", "--no-record"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.count(str(path)) == 1, err
    assert said in err, err


def test_an_exercises_folder_that_is_missing_or_a_file(tmp_path: Path, capsys) -> None:
    """``--exercises lost_node.toml`` (the file, not its folder) and a folder name with a typo
    both said "no *.toml in ...", as if the folder were empty; ``--scenarios`` names the
    mistake (docs/scenarios.md), and so does ``--exercises`` now."""
    exercise = tmp_path / "lost_node.toml"
    exercise.write_text(EXERCISE, encoding="utf-8")
    for given, why in ((tmp_path / "nope", f"{tmp_path / 'nope'}: no such folder"),
                       (exercise, f"{exercise}: not a folder (give the folder that holds the "
                                  "*.toml files)")):
        assert main(["--exercises", str(given), "--state-dir", str(tmp_path / "s"),
                     "--run-for", "0"]) == 2
        assert capsys.readouterr().err == f"fieldrig: error: --exercises: {why}\n"
