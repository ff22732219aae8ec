"""A rig, scenario, exercise or network file that is not UTF-8 (saved as Latin-1 or UTF-16 by
an editor) is one clear error naming the file, the first bad byte and its offset, exit 2; it
ended in a UnicodeDecodeError traceback (issue 7 "Hardening": never a traceback)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from app.cli import main
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec

ROOT = Path(__file__).resolve().parents[2]
UTF16 = b"\xff\xfe[scenario]\n"  # an editor's "Unicode" save: a byte order mark first
SCENARIO = '[scenario]\nname = "x"\n[[step]]\nat = 1.0\ncaption = "café"\n'
LATIN1 = SCENARIO.encode("latin-1")  # the é is 0xe9, alone
LATIN1_AT = LATIN1.index(b"\xe9")
EXERCISE = LATIN1 + b'[exercise]\nfault = "fastcat:inject:coupler:0x04"\n'


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("fieldrig: error: "), err
    return err[0]


@pytest.mark.parametrize(("data", "byte", "offset"), [(UTF16, "0xff", 0),
                                                      (LATIN1, "0xe9", LATIN1_AT)],
                         ids=["utf16", "latin1"])
def test_a_scenario_file(tmp_path: Path, capsys: pytest.CaptureFixture[str], data: bytes,
                         byte: str, offset: int) -> None:
    path = tmp_path / "bin.toml"
    path.write_bytes(data)
    line = _run(["scenario", "run", str(path), "--out", str(tmp_path / "o"), "--quiet"], capsys)
    assert line == f"fieldrig: error: {path}: not UTF-8 text: byte {byte} at offset {offset}"
    assert not (tmp_path / "o").exists()  # refused before anything is written


def test_a_rig_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "rig.toml"
    path.write_bytes(b'[rig]\nname = "Pr\xfcfstand"\n')
    line = _run(["--rig", str(path), "--state-dir", str(tmp_path / "s"), "--no-record",
                 "--run-for", "0"], capsys)
    assert line == f"fieldrig: error: {path}: not UTF-8 text: byte 0xfc at offset 16"


def test_the_rig_a_scenario_names(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "rig.toml").write_bytes(UTF16)
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO.replace('name = "x"', 'name = "x"\nrig = "rig.toml"'),
                    encoding="utf-8")
    line = _run(["scenario", "run", str(path), "--quiet"], capsys)
    assert line.endswith("rig.toml: not UTF-8 text: byte 0xff at offset 0"), line


def test_an_exercise_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "ex").mkdir()
    path = tmp_path / "ex" / "e.toml"
    path.write_bytes(EXERCISE)
    line = _run(["--exercises", str(tmp_path / "ex"), "--state-dir", str(tmp_path / "s"),
                 "--no-record", "--run-for", "0"], capsys)
    assert line == f"fieldrig: error: {path}: not UTF-8 text: byte 0xe9 at offset {LATIN1_AT}"


def test_a_network_description(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The rig's ENI file (seed 003) is read as UTF-8 too; it said only "not UTF-8 text"."""
    eni = tmp_path / "bad.eni.xml"
    eni.write_bytes(b"<EtherCATConfig>\xff</EtherCATConfig>")
    rig = DEFAULT_RIG.read_text(encoding="utf-8")
    rig = re.sub(r'(?m)^eni = ".*"$', f'eni = "{eni}"', rig)
    rig = re.sub(r'(?m)^mapping = ".*"$',
                 f'mapping = "{(DEFAULT_RIG.parent / "../networks/default.mapping.xml")}"', rig)
    (tmp_path / "rig.toml").write_text(rig, encoding="utf-8")
    line = _run(["--rig", str(tmp_path / "rig.toml"), "--state-dir", str(tmp_path / "s"),
                 "--no-record", "--run-for", "0"], capsys)
    assert line == f"fieldrig: error: {eni}: not UTF-8 text: byte 0xff at offset 16"


def _rig_with_eni(tmp_path: Path, eni: Path) -> Path:
    rig = DEFAULT_RIG.read_text(encoding="utf-8")
    rig = re.sub(r'(?m)^eni = ".*"$', f'eni = "{eni}"', rig)
    rig = re.sub(r'(?m)^mapping = ".*"$',
                 f'mapping = "{(DEFAULT_RIG.parent / "../networks/default.mapping.xml")}"', rig)
    (tmp_path / "rig.toml").write_text(rig, encoding="utf-8")
    return tmp_path / "rig.toml"


@pytest.mark.parametrize("encoding", ["ISO-8859-1", "windows-1252", "UTF-16"])
def test_a_network_description_in_the_encoding_it_declares(tmp_path: Path,
                                                           encoding: str) -> None:
    """XML 1.0 §4.3.3: a file says its encoding in its declaration, and configurators write
    ENI files as ISO-8859-1 (a German device name with an umlaut). It was read as UTF-8 and
    refused as "not UTF-8 text"; it is now read as declared, and the rig builds."""
    shipped = (DEFAULT_RIG.parent / "../networks/default.eni.xml").read_text(encoding="utf-8")
    text = shipped.replace('encoding="utf-8"', f'encoding="{encoding}"', 1)
    text = text.replace("<!-- Generated", "<!-- Gerät, generated", 1)
    assert "Gerät" in text and encoding in text
    eni = tmp_path / "latin.eni.xml"
    eni.write_bytes(text.encode(encoding))
    rig = build_rig(load_rig_spec(_rig_with_eni(tmp_path, eni)), state_dir=None)
    assert "master" in rig.devices


def test_a_network_description_not_in_its_declared_encoding(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    eni = tmp_path / "bad.eni.xml"
    eni.write_bytes(b'<?xml version="1.0" encoding="ascii"?><EtherCATConfig>\xe9'
                    b"</EtherCATConfig>")
    line = _run(["--rig", str(_rig_with_eni(tmp_path, eni)), "--state-dir",
                 str(tmp_path / "s"), "--no-record", "--run-for", "0"], capsys)
    assert line == (f"fieldrig: error: {eni}: not ascii text as it declares: byte 0xe9 at "
                    "offset 54")


def test_the_real_cli(tmp_path: Path) -> None:
    """As a process: the traceback went to stderr with exit 1."""
    path = tmp_path / "bin.toml"
    path.write_bytes(UTF16)
    proc = subprocess.run([sys.executable, "-m", "app", "scenario", "run", str(path), "--quiet"],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == f"fieldrig: error: {path}: not UTF-8 text: byte 0xff at offset 0\n"
