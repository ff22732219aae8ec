"""The drive's "cause removed" log line names the reset of the drive's own fieldbus.

Before, every drive read "(reset with control word bit 3)": bit 3 is Alm_rst of the Modbus R00
register (seed 004 ch. 1 / ch. 2); a CANopen or EtherCAT (CoE) master resets by writing 0x80
to 0x6040, bit 7 (ch. 4 examples "0x0080"; ch. 5 "Reset allarmi": "scrittura 0x80 su oggetto
0x6040"). Profinet: "L'allarme può essere resettato scrivendo il codice 0x08 nella Control
Word" (ch. 6 l. 5297), the Control Word being R00 (the worked example, l. 5244-5271,
"Registro 0 control_word ... valore: 0x0008"); it used to say "Control Word = 0x80 (bit 7)",
the CiA 402 bit.
"""

from __future__ import annotations

import pytest
from servo_helpers import make_sim

from devices.servo.drive import DriveConfig


@pytest.mark.parametrize(("fieldbus", "hint"), [
    ("modbus", "R00 bit 3"),
    ("canopen", "0x6040 = 0x80 (bit 7)"),
    ("ethercat", "0x6040 = 0x80 (bit 7)"),
    ("profinet", "Control Word = 0x08 (R00 bit 3)"),
])
def test_clear_alarm_names_the_reset_of_the_fieldbus(fieldbus: str, hint: str) -> None:
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    sim.drive.apply("inject_alarm", {"code": 16})
    sim.run(5)
    sim.drive.apply("clear_alarm", {"code": 16})
    sim.run(1)
    texts = [e["text"] for e in sim.kinds("log") if "removed" in e.get("text", "")]
    assert texts == [f"cause of alarm 16 removed (reset with {hint})"], texts


def test_a_profinet_master_resets_with_0x08_in_the_control_word_as_the_hint_says() -> None:
    """R00 = 0x08 resets alarm 34 (the one Profinet alarm ch. 6 marks resettable); 0x80 there is
    Inc_mod (R00 bit 7), not a reset."""
    sim = make_sim(DriveConfig(fieldbus="profinet"))
    sim.drive.apply("inject_alarm", {"code": 34})
    sim.run(300)
    sim.drive.apply("clear_alarm", {"code": 34})
    sim.run(1)
    for value in (0x80, 0x00):
        sim.w(0, value)
    assert sim.drive.read_register(46) == 34
    for value in (0x08, 0x00):
        sim.w(0, value)
    assert sim.drive.read_register(46) == 0


@pytest.mark.parametrize(("fieldbus", "code"), [("ethercat", 35), ("profinet", 30),
                                                 ("profinet", 33)])
def test_an_alarm_no_reset_bit_clears_names_the_power_cycle(fieldbus: str, code: int) -> None:
    """EtherCAT 35 (the slave sits in INIT: no mailbox, no process data, so no 0x6040 write
    reaches the drive, docs/ethercat-coe.md) and Profinet 30-33 ("Resettabile" NO, ch. 6):
    the hint names the only way out, a power cycle, not a reset bit."""
    sim = make_sim(DriveConfig(fieldbus=fieldbus))
    sim.drive.apply("inject_alarm", {"code": code})
    sim.run(300)
    sim.drive.apply("clear_alarm", {"code": code})
    sim.run(1)
    texts = [e["text"] for e in sim.kinds("log") if "removed" in e.get("text", "")]
    assert texts == [f"cause of alarm {code} removed (reset with a power cycle: switch the "
                     "drive off and on)"], texts
