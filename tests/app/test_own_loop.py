"""Tests that run an event loop of their own pass in a pytest process where a browser test
ran before them (tests/app/own_loop.py). Playwright's sync API leaves its loop marked running
in the main thread; :func:`loop_running_here` leaves the same mark without a browser."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from own_loop import complete, run

ROOT = Path(__file__).resolve().parents[2]

# Every tests/app file that runs a loop of its own, directly or through the helpers it shares
# (fake_viser.py, test_widgets_synced*.py's ``turn``). test_modbus_server.py runs its client
# through own_loop.run too; left out here for its minute of sockets per framing.
OWN_LOOPS = ["test_drive_panel_access.py", "test_drive_panel_hints.py",
             "test_client_pick_gone.py", "test_client_synced.py", "test_widgets_synced.py",
             "test_widgets_synced_panels.py", "test_modbus_rtu_stall_clock.py",
             "test_modbus_drive_bits.py"]


@contextmanager
def loop_running_here() -> Iterator[None]:
    """This thread marked as running a loop, as a browser test leaves the main thread."""
    other = asyncio.new_event_loop()
    asyncio._set_running_loop(other)
    try:
        yield
    finally:
        asyncio._set_running_loop(None)
        other.close()


async def _answer() -> int:
    await asyncio.sleep(0)
    return 42


async def _fail() -> None:
    await asyncio.sleep(0)
    raise KeyError("from the coroutine")


def test_the_mark_stops_a_loop_in_this_thread() -> None:
    """What the helpers are for: without them the same calls fail here."""
    loop = asyncio.new_event_loop()
    try:
        with loop_running_here():
            for call in (asyncio.run, loop.run_until_complete):
                coro = _answer()
                with pytest.raises(RuntimeError, match=r"running event loop|another loop is"):
                    call(coro)
                coro.close()
    finally:
        loop.close()


def test_run_and_complete_with_a_loop_running_in_this_thread() -> None:
    loop = asyncio.new_event_loop()
    try:
        with loop_running_here():
            assert run(_answer()) == 42
            assert complete(loop, _answer()) == 42
            task = loop.create_task(_answer())  # made here, run by the next turn
            complete(loop, asyncio.sleep(0))
            assert task.result() == 42
            with pytest.raises(KeyError, match="from the coroutine"):
                run(_fail())
    finally:
        loop.close()


def test_the_loop_owning_tests_pass_with_a_loop_running_in_the_main_thread(
        tmp_path: Path) -> None:
    """Each file in a pytest process of its own whose main thread is marked as a browser test
    leaves it (a plugin sets the mark at session start)."""
    plugin = tmp_path / "loop_running_plugin.py"
    plugin.write_text(
        "import asyncio\n\n\n"
        "def pytest_sessionstart(session):\n"
        "    asyncio._set_running_loop(asyncio.new_event_loop())\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(tmp_path), *filter(None, [os.environ.get("PYTHONPATH")])])}
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "loop_running_plugin",
         "-p", "no:cacheprovider", *[f"tests/app/{name}" for name in OWN_LOOPS]],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert " passed" in out.stdout and "another loop is running" not in out.stdout
