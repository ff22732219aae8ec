"""A servo drive's words and digital I/O are recorded beside its motion signals.

The drive's snapshot carries the CiA 402 controlword / statusword (0x6040 / 0x6041), the
register-mode control and status registers (R00 / R05, seed 004 ch. 2) and the CN2 inputs and
outputs (seed 004: start, limits, home, TEN, IEN; end of job, brake, ...). An audit of the
example scenarios' recordings found only position, velocity and following error: a support
engineer replaying drive_jammed_load could not see which controlword the master sent, nor
when the brake output dropped or a limit switch closed. They are now under
``rig/<drive>/drive/<word>`` and ``rig/<drive>/io/inputs`` / ``outputs`` (one series a pin).
"""

from __future__ import annotations

import pytest
from test_recording import Run, load, rows, value_at

S = 1_000_000
WORDS = ("controlword", "statusword", "control_register", "status_register")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "drive_io.rrd")
    r.hook(r.rig, r.rig.take_events())  # t = 0, as run_scenario starts
    r.run_until(1 * S)
    r.do("drive", "set_input", name="pos_limit", value=True)
    r.do("drive_co", "controlword", value=0x0006)  # Shutdown: Ready to switch on
    r.do("drive", "enable", on=True)
    r.run_until(1_500_000)
    r.recorder.close()
    return r


@pytest.mark.parametrize("drive", ["drive", "drive_co", "drive_ec"])
def test_words_and_pins_follow_the_snapshot(run: Run, drive: str) -> None:
    chunks = load(run.path)
    snap = run.rig.snapshot()["devices"][drive]
    now = run.rig.clock.now_us
    for word in WORDS:
        lane = rows(chunks, f"rig/{drive}/drive/{word}", "Scalars:scalars")
        assert lane and lane[0][0] == 0, (drive, word)
        assert value_at(lane, now) == float(snap[word]), (drive, word)
    for side in ("inputs", "outputs"):
        lane = rows(chunks, f"rig/{drive}/io/{side}", "Scalars:scalars")
        assert lane and lane[0][0] == 0, (drive, side)
        assert value_at(lane, now) == [float(v) for v in snap[side].values()], (drive, side)


def test_the_commands_show(run: Run) -> None:
    chunks = load(run.path)
    names = next(n for b in chunks["rig/drive/io/inputs"]
                 if "SeriesLines:names" in b.schema.names
                 for n in b.column("SeriesLines:names").to_pylist())
    pins = value_at(rows(chunks, "rig/drive/io/inputs", "Scalars:scalars"), 1_100_000)
    assert pins[names.index("pos_limit")] == 1.0
    words = rows(chunks, "rig/drive_co/drive/controlword", "Scalars:scalars")
    assert value_at(words, 1_100_000) == 6.0
