"""``python -m app ethercat export-esi``: bad input is one ``fieldrig: error:`` line and exit 2
before anything is written, as for ``scenario run`` (docs/ethercat-wire.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.cli import EXIT_BAD_INPUT, main


def test_a_rig_without_an_ethercat_line(tmp_path: Path, capsys) -> None:
    """A rig of one Modbus drive ended in a ValueError traceback (exit 1)."""
    rig = tmp_path / "servo_only.toml"
    rig.write_text('[rig]\nname = "s"\n[[servo]]\nid = "d"\n', encoding="utf-8")
    out = tmp_path / "esi"
    assert main(["ethercat", "export-esi", "--rig", str(rig), "--out", str(out)]) \
        == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err == (f"fieldrig: error: {rig}: the rig has no EtherCAT line (no [[fastcat]], "
                   "[[trscat]], [[cpx]] or drive with fieldbus = \"ethercat\"): no ESI to "
                   "export\n")
    assert not out.exists()


def test_an_out_that_is_a_file(tmp_path: Path, capsys) -> None:
    """``--out`` naming a file was exit 3 "FILE: File exists" (the machine failed, it said)
    after the rig was built; it is the input's fault, said before any work."""
    out = tmp_path / "esi"
    out.write_text("mine", encoding="utf-8")
    assert main(["ethercat", "export-esi", "--out", str(out)]) == EXIT_BAD_INPUT
    assert capsys.readouterr().err == f"fieldrig: error: --out: {out} is a file, not a " \
                                      "directory\n"
    assert out.read_text(encoding="utf-8") == "mine"


def help_text(argv: list[str], capsys) -> str:
    with pytest.raises(SystemExit):
        main([*argv, "--help"])
    return " ".join(capsys.readouterr().out.split())


def test_the_help_says_where_the_files_go(capsys) -> None:
    assert "default: static/esi in the working directory" in \
        help_text(["ethercat", "export-esi"], capsys)
    # the project's own tracker number meant nothing to a user
    assert "issue 8" not in help_text(["ethercat"], capsys)
