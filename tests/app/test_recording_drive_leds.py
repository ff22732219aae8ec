"""Every servo drive's network LEDs are in a recording, one entity per LED (docs/recording.md).

The dashboard draws L/A IN, Status, L/A OUT and Error on every drive (seed 004 ch. 5
"Connessioni e Leds Drive EtherCAT"; `app/ui/drive/axis_scene.py`): driven by the CoE slave on
EtherCAT, dark on Modbus and CANopen. Their LedChanged events carry the drive's id, so the
lane (events) and the lit / dark samples (snapshot) must meet under ``rig/<drive>/led/<led>``,
and nothing of them under the CoE slave's own id.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from test_recording import Chunks, Run, load, rows, value_at

from app.recording.signals import device_path
from devices.events import LedChanged
from devices.leds import LedPattern, is_lit

S = 1_000_000
DRIVES = ("drive", "drive_co", "drive_ec")
LEDS = ("L/A IN", "Status", "L/A OUT", "Error")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "leds.rrd")
    r.run_until(4 * S)  # the master walks the line, drive_ec-ecat included, to OP
    r.recorder.close()
    return r


@pytest.fixture(scope="module")
def chunks(run: Run) -> Chunks:
    return load(run.path)


def entity(drive: str, led: str) -> str:
    return device_path(drive, "led", led)


@pytest.mark.parametrize("drive", DRIVES)
@pytest.mark.parametrize("led", LEDS)
def test_every_drive_led_has_a_lane_and_lit_samples(chunks: Chunks, drive: str,
                                                     led: str) -> None:
    lane = rows(chunks, entity(drive, led), "StateChange:state")
    lit = rows(chunks, entity(drive, led), "Scalars:scalars")
    assert lane and lit, f"{drive} {led}: lane {len(lane)} rows, lit {len(lit)} rows"
    for t, value in lit:
        assert value == float(is_lit(LedPattern(value_at(lane, t)), t)), (drive, led, t)


def test_ethercat_drive_lane_follows_its_led_events(run: Run, chunks: Chunks) -> None:
    """drive_ec's Status walks with the ESM (ETG.1300 RUN); its lane holds every change."""
    changes = [(e.t_us, e.pattern) for e in run.events
               if isinstance(e, LedChanged) and e.device == "drive_ec" and e.led == "Status"]
    assert len(changes) >= 2  # blinking in PREOP, ... on in OP
    lane = rows(chunks, entity("drive_ec", "Status"), "StateChange:state")
    assert [c for c in lane if c[0] > 0] == [c for c in changes if c[0] > 0]
    assert value_at(lane, 4 * S) == "on"


def test_modbus_and_canopen_drive_leds_stay_dark(chunks: Chunks) -> None:
    for drive in ("drive", "drive_co"):
        for led in LEDS:
            assert {v for _, v in rows(chunks, entity(drive, led), "StateChange:state")} == {
                "off"}
            assert {v for _, v in rows(chunks, entity(drive, led), "Scalars:scalars")} == {0.0}


def test_no_led_entity_under_a_companion_id(chunks: Chunks) -> None:
    """The CoE slave (drive_ec-ecat) and the CANopen nodes (*-can) own no LED: the drive does."""
    strays = [p for p in chunks if "/led/" in p and p.split("/")[1].endswith(("-ecat", "-can"))]
    assert strays == []


def test_recording_verifies(run: Run) -> None:
    from test_recording import rerun_cli

    result = rerun_cli("rrd", "verify", str(Path(run.path)))
    assert result.returncode == 0, result.stderr
