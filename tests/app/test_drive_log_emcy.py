"""The Drive log names the alarm an emergency carries, as the drive numbers it (decimal).

The drive's emergency (CANopen EMCY, CoE emergency) carries the alarm number in its first
manufacturer byte (devices/coe/emergency.py), and the frame's bytes are hex: alarm 16
FOLLOWING_ERROR reads "data 10 00 00 00 00", which a trainee with seed 004 ch. 3 open ("Codice
10: Allarme resistore frenatura") reads as alarm 10. The display and the alarm tables number the
alarms in decimal (ch. 3, ch. 5 "Codice Allarme ECO"), so the log line says which alarm it is.
"""

from __future__ import annotations

from app.decoder import decode
from app.ui.drive.drive_state import DriveLog, event_text
from devices.events import EmergencySent


def test_the_log_names_alarm_16_not_a_hex_10() -> None:
    event = EmergencySent(1_000, "drive_co", code=0x8611, register=0x21,
                          data=bytes((16, 0, 0, 0, 0)))
    text, error = event_text(event) or ("", False)
    assert text == ("EMCY 0x8611 register 0x21 data 10 00 00 00 00: "
                    "alarm 16 FOLLOWING_ERROR")
    assert error
    log = DriveLog()
    log.add([event])
    assert "alarm 16 FOLLOWING_ERROR" in log.html("drive_co")


def test_one_0x603f_code_of_several_alarms_takes_the_alarm_of_the_byte() -> None:
    # 0x7300 is the code of 8, 23, 24 and 25 (ch. 5 table): byte 0 says which one
    event = EmergencySent(1_000, "drive_ec", code=0x7300, register=0x01,
                          data=bytes((24, 0, 0, 0, 0)))
    assert (event_text(event) or ("",))[0].endswith(": alarm 24 ABS_ENCODER_COMMUNICATION")


def test_an_emergency_of_no_drive_alarm_keeps_its_bytes_alone() -> None:
    reset = EmergencySent(1_000, "drive_co", code=0x0000, register=0x00, data=bytes(5))
    assert (event_text(reset) or ("",))[0] == "EMCY 0x0000 register 0x00 data 00 00 00 00 00"
    guard = EmergencySent(1_000, "drive_co", code=0x8130, register=0x11, data=bytes(5))
    assert "alarm" not in (event_text(guard) or ("",))[0]


def test_the_codes_tab_still_reads_a_pasted_line() -> None:
    for line in ("EMCY 0x8611 register 0x21 data 10 00 00 00 00: alarm 16 FOLLOWING_ERROR",
                 "node 2: code 0x8611, register 0x21, data 10 00 00 00 00: "
                 "alarm 16 FOLLOWING_ERROR"):
        assert any("16 FOLLOWING_ERROR" in m.title + m.text for m in decode(line)), line
