"""The master's frames cross a drive whose c9 was not 11 at its power-up: the drive does not
answer, its ESC passes the frames on (docs/ethercat-master.md "What the master knows"), and its
L/A LEDs show the link and that traffic (ETG.1300 L/A is the ESC's; seed 004 ch. 5 "L/A Verde
Link Active rete ethernet"). Status and Error belong to the EtherCAT application the drive
does not run then: dark (docs/ethercat-coe.md "LEDs of a drive with c9 != 11"). Before, the
drive's four LEDs stayed dark while the line behind it ran.
"""

from __future__ import annotations

from line_bench import US
from test_master_port_link import _drive_first, _drive_leds


def test_frames_crossing_a_silent_drive_flicker_both_its_l_a() -> None:
    rig = _drive_first(c9=3)  # master -> drive (c9 = 3) -> FastCAT
    rig.run_until(4 * US)
    view = rig.snapshot()["devices"]["master"]
    assert [s["present"] for s in view["slaves"]] == [False, True]  # the FastCAT answers
    assert _drive_leds(rig) == {
        "L/A IN": "flickering", "Status": "off", "L/A OUT": "flickering", "Error": "off"}


def test_a_silent_drive_alone_flickers_its_in_port_only() -> None:
    rig = _drive_first(c9=3, fastcat=False)
    rig.run_until(2 * US)
    assert _drive_leds(rig) == {
        "L/A IN": "flickering", "Status": "off", "L/A OUT": "off", "Error": "off"}


def test_the_cables_of_a_silent_drive_move_its_l_a() -> None:
    rig = _drive_first(c9=3)
    rig.run_until(4 * US)
    rig.apply("master", "pull_cable", {"cable": 1})  # drive -> FastCAT
    rig.run_until(4 * US + 10_000)
    assert (_drive_leds(rig)["L/A IN"], _drive_leds(rig)["L/A OUT"]) == ("flickering", "off")
    rig.apply("master", "plug_cable", {"cable": 1})
    rig.apply("master", "pull_cable", {"cable": 0})  # master -> drive: no frame comes in
    rig.run_until(4 * US + 100_000)  # past the 50 ms activity window
    # the OUT port keeps its link to the powered FastCAT, with no traffic: on (ETG.1300)
    assert (_drive_leds(rig)["L/A IN"], _drive_leds(rig)["L/A OUT"]) == ("off", "on")
    rig.apply("master", "plug_cable", {"cable": 0})
    rig.run_until(4 * US + 110_000)
    assert (_drive_leds(rig)["L/A IN"], _drive_leds(rig)["L/A OUT"]) == (
        "flickering", "flickering")


def test_a_silent_drive_switched_off_is_dark_and_passes_nothing() -> None:
    rig = _drive_first(c9=3)
    rig.run_until(4 * US)
    rig.apply("master", "power_slave", {"position": 0, "on": False})
    rig.run_until(4 * US + 10_000)
    assert set(_drive_leds(rig).values()) == {"off"}
    view = rig.snapshot()["devices"]["master"]
    assert [s["present"] for s in view["slaves"]] == [False, False]


def test_a_wire_masters_frames_cross_a_silent_drive_too() -> None:
    """External mode (docs/ethercat-wire.md): the frames come as ``external_frame`` per
    position; at a silent drive they pass its ESC (its L/A flicker) and exchange nothing.
    Until session 20 they went to exchange_frame only, which the drive ignores: L/A on."""
    rig = _drive_first(c9=3)
    master, drive = rig.devices["master"], rig.devices["drive_ec-ecat"]
    rig.run_until(4 * US)
    master.set_external(True)
    rig.run_until(4 * US + 100_000)  # the built-in master's frames past the 50 ms window
    assert (_drive_leds(rig)["L/A IN"], _drive_leds(rig)["L/A OUT"]) == ("on", "on")
    for t in range(4 * US + 101_000, 4 * US + 111_000, 1_000):
        rig.run_until(t)
        master.external_frame(0)
        master.external_frame(1)
    rig.run_until(4 * US + 112_000)
    assert _drive_leds(rig) == {
        "L/A IN": "flickering", "Status": "off", "L/A OUT": "flickering", "Error": "off"}
    assert drive.frames == 0 and drive.al_state.name == "INIT"
    rig.apply("master", "power_slave", {"position": 0, "on": False})
    rig.run_until(4 * US + 113_000)
    master.external_frame(0)  # a report on its way when it went off: nothing passes
    rig.run_until(4 * US + 114_000)
    assert set(_drive_leds(rig).values()) == {"off"}
