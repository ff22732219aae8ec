"""The CANopen tab's frame log line of an SDO upload of 0x1001 decodes as the error register
of the node's device, the drive (seed 004 ch. 4, DS 301's bit table as the seed prints it).

The frame log writes the expedited bytes in hex, byte 0 first (devices/canopen/decode.py):
"upload 0x1001:00 = 21" is 0x21, Generic Error and Device Profile Specific (alarm 16's
0x8611). Before, the line read "no code and no alarm name", and "0x1001:00 = 21" cut from it
read as the decimal 21 (0x15: Generic Error, Voltage, Communication Error) in the words of
every device with a 0x1001, the CPX-E-EC's and the TRS-CAT's too, none of which is on CAN.
"""

from __future__ import annotations

import pytest

from app.decoder import SERVO, DecodeError, decode
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec


def test_the_upload_line_reads_hex_in_the_drives_words() -> None:
    found = decode("node 2 ->: upload 0x1001:00 = 85")
    assert [m.family for m in found] == [SERVO]
    assert found[0].title == "0x1001:0 Error register = 0x85 (SDO upload, CANopen node)"
    assert found[0].text == "Generic Error, Voltage, Manufacturer Specific.", found[0].text
    assert found[0].source.startswith("seed 004 ch. 4")


def test_the_last_sdo_row_reads_the_same() -> None:
    """The CANopen tab's Last SDO row (app/ui/drive/canopen_panel.py sdo_sentence)."""
    found = decode("Upload (read) 0x1001:00 from node 2: value 85.")
    assert [m.title for m in found] == \
        ["0x1001:0 Error register = 0x85 (SDO upload, CANopen node)"]


def test_the_request_line_lists_the_drives_bits() -> None:
    found = decode("-> node 2: upload 0x1001:00")
    assert [m.family for m in found] == [SERVO]
    assert "bit 5 Device Profile Specific" in found[0].text, found[0].text


def test_a_row_copied_from_the_models_frame_log() -> None:
    """The node answers alarm 16's register; the row as a browser copies the table's cells."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.run_until(3_000_000)
    rig.apply("drive_co", "inject_alarm", {"code": "FOLLOWING_ERROR"})
    rig.run_until(3_200_000)
    rig.apply("drive_co-can", "frame", {"cob_id": 0x602, "data": "40 01 10 00 00 00 00 00"})
    rig.run_until(3_300_000)
    frame = rig.device("drive_co-can").snapshot()["frames"][-1]
    row = "\t".join(str(frame[k]) for k in ("t", "dir", "id", "kind", "data", "text"))
    assert row.endswith("upload 0x1001:00 = 21"), row
    found = decode(row)
    assert [m.title for m in found] == \
        ["0x1001:0 Error register = 0x21 (SDO upload, CANopen node)"]
    assert found[0].text.startswith("Generic Error, Device Profile Specific"), found[0].text


@pytest.mark.parametrize(("line", "hint"), [
    ("upload 0x1001:00 = 21 00", "one byte"),
    ("upload 0x1001:01 = 21", "sub 0"),
    ("upload 0x10F3:05 = 11 00", "no 0x10F3"),
])
def test_a_line_the_node_cannot_have_sent(line: str, hint: str) -> None:
    with pytest.raises(DecodeError, match=hint):
        decode(line)
