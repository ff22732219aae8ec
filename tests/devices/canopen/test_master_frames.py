"""The dashboard master's frames, built from the SDO server's and the CiA 402 tables."""

from __future__ import annotations

import pytest

from devices.canopen import master_frames as mf
from devices.servo import ds402


@pytest.mark.parametrize(("size", "command"), [(1, 0x2F), (2, 0x2B), (3, 0x27), (4, 0x23)])
def test_expedited_download_command_by_size(size: int, command: int) -> None:
    # DS 301 initiate download: ccs 1, n = 4 - size, e = 1, s = 1.
    assert mf.download_command(size) == command
    frame = mf.sdo_download(2, 0x6040, 0, 0x0F, size)
    assert frame.can_id == 0x602
    assert frame.data[0] == command and frame.data[1:4] == bytes((0x40, 0x60, 0x00))
    assert len(frame.data) == 8


@pytest.mark.parametrize("size", [0, 5])
def test_no_expedited_download_outside_one_to_four_bytes(size: int) -> None:
    with pytest.raises(ValueError, match=r"1\.\.4 bytes"):
        mf.sdo_download(2, 0x6040, 0, 0, size)


def test_negative_value_in_twos_complement() -> None:
    assert mf.sdo_download(1, 0x607A, 0, -1, 4).data[4:] == b"\xff\xff\xff\xff"


def test_upload_and_nmt() -> None:
    assert mf.sdo_upload(3, 0x1018, 1).data == bytes((0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0))
    assert mf.nmt(0x01, 0x85) == mf.Frame(0x000, bytes((0x01, 0x05)))


@pytest.mark.parametrize("command", [c for c in ds402.COMMAND_WORDS
                                     if c is not ds402.Command.FAULT_RESET])
def test_each_command_word_decodes_to_its_command(command: ds402.Command) -> None:
    assert ds402.decode(ds402.COMMAND_WORDS[command]) is command
