"""Where the dashboard and the Modbus line listen is checked before anything serves: a ``--host``
that does not resolve or is no address of this machine, or a port in use, is one error line
and exit 2. The host ones hung for ever (viser's server thread tries 1,000 ports, then gives up
without telling ``ViserServer()``, which waits); a busy ``--port`` moved the dashboard to the
next port without a word; a busy ``--modbus-port`` ended in a traceback."""

from __future__ import annotations

import socket
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from served_process import free_ports

from app.cli import main

ROOT = Path(__file__).resolve().parents[2]
HANG_S = 60  # far more than a refusal takes (imports and a rig: ~3 s)


@pytest.mark.parametrize(("host", "why"), [
    ("10.9.9.9", "cannot listen on 10.9.9.9:{port}: Cannot assign requested address"),
    ("nosuchhost.invalid", "cannot resolve nosuchhost.invalid:"),
    ("999.1.1.1", "cannot resolve 999.1.1.1:"),
])
def test_a_host_that_cannot_be_bound(tmp_path: Path, host: str, why: str) -> None:
    port = free_ports(2, 24000)
    proc = subprocess.run(
        [sys.executable, "-m", "app", "--host", host, "--port", str(port), "--modbus-port",
         str(port + 1), "--no-record", "--state-dir", str(tmp_path), "--run-for", "0"],
        cwd=ROOT, capture_output=True, text=True, timeout=HANG_S)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"fieldrig: error: --host: "
                                                   f"{why.format(port=port)}"), proc.stderr
    assert "FieldRig:" not in proc.stdout, proc.stdout


@contextmanager
def _listening(port: int) -> Iterator[None]:
    """Another program listening on 127.0.0.1:port."""
    with socket.socket() as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(("127.0.0.1", port))
        sock.listen()
        yield


def _refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], *args: str) -> str:
    code = main([*args, "--no-record", "--state-dir", str(tmp_path), "--run-for", "0"])
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    assert "FieldRig:" not in out, out  # refused before any rig served
    lines = err.splitlines()
    assert len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize("host", ["bad..host", "a" * 64 + ".example", ".lead"])
def test_a_host_that_is_no_name_says_so(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                        host: str) -> None:
    """``--host bad..host`` said ``encoding with 'idna' codec failed (UnicodeError: label
    empty or too long)``: Python's words, not the user's. One line names the flag and the
    value."""
    port = free_ports(2, 24500)
    line = _refused(tmp_path, capsys, "--host", host, "--port", str(port), "--modbus-port",
                    str(port + 1))
    assert line == f"fieldrig: error: --host: {host!r} is not a host name or address"


def test_a_busy_port(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    port = free_ports(2, 25000)
    with _listening(port):
        line = _refused(tmp_path, capsys, "--port", str(port), "--modbus-port", str(port + 1))
    assert line == (f"fieldrig: error: --port: cannot listen on 127.0.0.1:{port}: "
                    "Address already in use")


def test_a_busy_modbus_port(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    port = free_ports(2, 26000)
    with _listening(port + 1):
        line = _refused(tmp_path, capsys, "--port", str(port), "--modbus-port", str(port + 1))
    assert line == (f"fieldrig: error: --modbus-port: cannot listen on 127.0.0.1:{port + 1}: "
                    "Address already in use")


def test_the_modbus_port_on_the_dashboards(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    port = free_ports(1, 27000)
    line = _refused(tmp_path, capsys, "--port", str(port), "--modbus-port", str(port))
    assert line == (f"fieldrig: error: --modbus-port: {port} is also a dashboard port "
                    f"(--port {port}, one port per rig from there)")


def test_the_third_rig_of_a_classroom(tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """Every rig's ports are checked before the first serves (the third one's trainee was
    sent to a port the README does not name)."""
    port, modbus = free_ports(3, 28000), free_ports(3, 29000)
    with _listening(port + 2):
        line = _refused(tmp_path, capsys, "--rigs", "3", "--port", str(port),
                        "--modbus-port", str(modbus))
    assert line == (f"fieldrig: error: --port: cannot listen on 127.0.0.1:{port + 2}: "
                    "Address already in use")


def test_the_ports_are_free_again_after_the_check(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    port, modbus = free_ports(2, 30000), free_ports(2, 31000)
    assert main(["--rigs", "2", "--port", str(port), "--modbus-port", str(modbus),
                 "--no-record", "--state-dir", str(tmp_path), "--run-for", "0"]) == 0
    out = capsys.readouterr().out
    assert f"at http://127.0.0.1:{port}/" in out and f"at http://127.0.0.1:{port + 1}/" in out
    assert f"Modbus (socket) on 127.0.0.1:{modbus + 1}" in out
