"""The drive's own cable action at its OUT port (seed 004 ch. 5 "Connessioni e Leds Drive
EtherCAT": an RJ45 IN and an RJ45 OUT, each with its L/A LED). With the drive in the middle of
the line, a trainee pulls the cable out of its OUT port: the slaves behind it are lost, the
drive stays, and its L/A OUT goes off (ETG.1300 L/A: off without link); plugged back, they
are found again. Before, the drive's ``link`` pulled the IN plug only."""

from __future__ import annotations

from app.rig import Rig
from app.rig_config import build_rig, parse_rig_spec

US = 1_000_000
RIG = ('[rig]\nname = "drive first"\nseed = 1\nstep_ms = 1\n'
       '[master]\nline = ["drive_ec-ecat", "fastcat"]\n'
       '[[servo]]\nid = "drive_ec"\nfieldbus = "ethercat"\nnode_id = 3\n'
       '[[fastcat]]\nid = "fastcat"\nmodules = ["DI16"]\n')


def _present(rig: Rig) -> list[bool]:
    return [bool(s.get("present")) for s in rig.snapshot()["devices"]["master"]["slaves"]]


def _leds(rig: Rig) -> dict[str, str]:
    leds = rig.snapshot()["devices"]["drive_ec"]["leds"]
    return {name: led if isinstance(led, str) else led["pattern"] for name, led in leds.items()}


def test_pulling_the_drive_s_out_plug_cuts_the_line_behind_it() -> None:
    rig = build_rig(parse_rig_spec(RIG))
    rig.run_until(6 * US)
    assert _present(rig) == [True, True]
    assert _leds(rig)["L/A OUT"] == "flickering"
    rig.apply("drive_ec-ecat", "link", {"connected": False, "port": "out"})
    rig.run_until(6 * US + 300_000)
    assert _present(rig) == [True, False]
    assert _leds(rig)["L/A OUT"] == "off" and _leds(rig)["L/A IN"] == "flickering"
    snap = rig.snapshot()["devices"]
    assert (snap["drive_ec-ecat"]["link"], snap["drive_ec-ecat"]["link_out"]) == (True, False)
    causes = [c["cause"] for c in snap["master"]["injected"]["lost"]]
    assert causes == ["no link on the OUT port of the slave at position 0"]
    rig.apply("drive_ec-ecat", "link", {"connected": True, "port": "out"})
    rig.run_until(14 * US)
    assert _present(rig) == [True, True]
    assert _leds(rig)["L/A OUT"] == "flickering"


def test_the_in_plug_is_still_the_default_and_keeps_the_out_plug() -> None:
    """``link`` without a port is the IN plug, as before (scenarios, exercises); pulling and
    plugging IN leaves a pulled OUT pulled."""
    rig = build_rig(parse_rig_spec(RIG))
    rig.run_until(6 * US)
    rig.apply("drive_ec-ecat", "link", {"connected": False, "port": "out"})
    rig.apply("drive_ec-ecat", "link", {"connected": False})
    rig.run_until(6 * US + 300_000)
    assert _present(rig) == [False, False]
    rig.apply("drive_ec-ecat", "link", {"connected": True})
    rig.run_until(14 * US)
    assert _present(rig) == [True, False]
    assert rig.device("drive_ec-ecat").plugs == (True, False)
