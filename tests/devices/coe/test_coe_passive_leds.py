"""The drive's LEDs on the EtherCAT line with c9 != 11 at its power-up (a *passive* slave).

Seed 004 ch. 5 "Connessioni e Leds Drive EtherCAT": "L/A Verde Link Active rete ethernet";
"Status ... stato ethercat", "Error ... warning/allarmi in ethercat", both "riferirsi alla
documentazione ufficiale ETG-1300". ETG.1300 puts L/A on the ESC (the port's link and the
frames crossing it); RUN and ERR on the application. Without c9 = 11 the drive runs no
EtherCAT application, but its ESC, powered with it, passes the frames on
(docs/ethercat-coe.md "How it runs"): its L/A show link and traffic, Status and Error stay
dark (docs/ethercat-coe.md "LEDs of a drive with c9 != 11").
"""

from __future__ import annotations

from coe_bench import Bench, make_bench

from devices.leds import LedPattern

DARK = {"L/A IN": "off", "Status": "off", "L/A OUT": "off", "Error": "off"}


def _passive(out_link: bool = False) -> Bench:
    bench = make_bench(fieldbus="modbus", boot=False)
    bench.cycling = False  # a silent slave gets no process-data frame: only passed frames
    bench.slave.set_link(out_link, "out")
    bench.run(60)
    return bench


def _pass_frames(bench: Bench, ms: int) -> None:
    for _ in range(ms):
        bench.step()
        bench.slave.frame_passed(bench.t_us)


def test_frames_passing_a_drive_off_ethercat_flicker_its_l_a() -> None:
    bench = _passive(out_link=True)
    assert not bench.slave.on_line and not bench.slave.reachable()
    assert bench.slave.leds.snapshot() == {
        "L/A IN": "on", "Status": "off", "L/A OUT": "on", "Error": "off"}  # link, no traffic
    _pass_frames(bench, 5)
    assert bench.slave.leds.snapshot() == {
        "L/A IN": "flickering", "Status": "off", "L/A OUT": "flickering", "Error": "off"}
    bench.run(60)  # no frame for longer than the activity window: link without traffic
    assert bench.slave.leds.snapshot()["L/A IN"] == "on"


def test_a_passive_drive_last_on_the_line_has_no_out_link() -> None:
    bench = _passive(out_link=False)
    _pass_frames(bench, 5)
    assert bench.slave.leds.snapshot() == {
        "L/A IN": "flickering", "Status": "off", "L/A OUT": "off", "Error": "off"}


def test_a_passed_frame_is_no_exchange() -> None:
    """The application takes nothing from a frame it does not answer: no SM event counted,
    no inputs, the ESM left in INIT."""
    bench = _passive()
    _pass_frames(bench, 5)
    snap = bench.slave.snapshot()
    assert (snap["frames"], snap["inputs"], snap["esm"]) == (0, None, "Off")


def test_no_link_on_the_in_port_keeps_l_a_in_dark() -> None:
    bench = _passive()
    bench.slave.set_link(False, "in")
    bench.run(2)
    assert bench.slave.leds.snapshot()["L/A IN"] == "off"


def test_a_drive_alarm_off_ethercat_leaves_status_and_error_dark() -> None:
    """Alarm 7 "Processore DSP in fault" lights Error on EtherCAT (an application controller
    failure); with c9 = 3 the drive's EtherCAT application does not run: the alarm is on the
    display, not on the EtherCAT LEDs."""
    bench = _passive()
    bench.drive.apply("inject_alarm", {"code": "7"})
    _pass_frames(bench, 5)
    leds = bench.slave.leds.snapshot()
    assert (leds["Status"], leds["Error"]) == ("off", "off")
    assert leds["L/A IN"] == LedPattern.FLICKERING.value


def test_a_passive_drive_switched_off_goes_dark() -> None:
    bench = _passive(out_link=True)
    _pass_frames(bench, 5)
    bench.drive.apply("power", {"on": False})
    bench.run(2)
    assert bench.slave.leds.snapshot() == DARK
