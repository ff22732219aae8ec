"""SII EEPROM image built from a SlaveDescription (ETG.2010 layout; notes "SII EEPROM content").

Checked at byte level the way SOEM reads it: identity words 0x08-0x0E, mailbox words
0x18-0x1C, categories from word 0x40 ended by 0xFFFF, string 1 = the name, GENERAL byte 5 =
CoE details, SM category (without it SM2/SM3 would start at 0), PDO categories.
"""

from __future__ import annotations

import struct

import pytest
from test_esc import description

from app.ethercat_wire import sii
from app.ethercat_wire.description import Pdo, PdoEntry


@pytest.fixture
def image() -> bytes:
    return sii.build(description(2), alias=0x0203)


def word(image: bytes, address: int) -> int:
    return struct.unpack_from("<H", image, address * 2)[0]


def dword(image: bytes, address: int) -> int:
    return struct.unpack_from("<I", image, address * 2)[0]


def test_identity_words(image):
    d = description(2)
    assert [dword(image, a) for a in (0x08, 0x0A, 0x0C, 0x0E)] == [
        d.vendor_id, d.product_code, d.revision, d.serial]


def test_configuration_area_alias_and_checksum(image):
    assert word(image, 0x04) == 0x0203
    assert sii.crc8(image[:14]) == image[14]
    assert sii.crc8(image[:15]) == 0  # a CRC without final XOR leaves no residue


def test_standard_mailbox_words(image):
    assert [word(image, a) for a in range(0x18, 0x1D)] == [0x1000, 128, 0x1080, 128, 0x0004]


def test_no_mailbox_means_zero_mailbox_words():
    from dataclasses import replace
    img = sii.build(replace(description(0), mailbox=None))
    assert [word(img, a) for a in range(0x18, 0x1D)] == [0] * 5


def test_categories_end_with_0xffff_and_the_size_word_covers_the_image(image):
    cats = sii.categories(image)
    assert set(cats) == {sii.CAT_STRINGS, sii.CAT_GENERAL, sii.CAT_FMMU, sii.CAT_SM,
                         sii.CAT_TXPDO, sii.CAT_RXPDO}
    assert len(image) == (word(image, 0x3E) + 1) * 128


def test_string_1_is_the_name_and_general_points_at_it(image):
    names = sii.strings(image)
    assert names[0] == "Slave 2"
    general = sii.categories(image)[sii.CAT_GENERAL][0]
    assert len(general) == 32
    assert names[general[3] - 1] == "Slave 2"
    assert names[general[0] - 1] == "Test" and names[general[2] - 1] == "T-2"
    assert general[5] == description(2).coe_details


def test_general_byte_5_where_soem_reads_it(image):
    """SOEM: siifind returns the byte address of the category's length word; CoE details at
    +7 (2 bytes of length word + byte 5)."""
    pos = 0x80
    while word(image, pos // 2) != sii.CAT_GENERAL:
        pos += 4 + word(image, pos // 2 + 1) * 2
    assert image[pos + 2 + 7] == description(2).coe_details


def test_sm_category_entries(image):
    sm = sii.categories(image)[sii.CAT_SM][0]
    rows = [struct.unpack_from("<HHBBBB", sm, 8 * n) for n in range(len(sm) // 8)]
    assert rows == [(0x1000, 128, 0x26, 0, 1, 1), (0x1080, 128, 0x22, 0, 1, 2),
                    (0x1100, 2, 0x64, 0, 1, 3), (0x1180, 4, 0x20, 0, 1, 4)]


def test_fmmu_category(image):
    assert sii.categories(image)[sii.CAT_FMMU][0][:3] == bytes([1, 2, 3])


@pytest.mark.parametrize(("cat", "index", "sm", "entry"), [
    (sii.CAT_RXPDO, 0x1600, 2, (0x7000, 1, 0x06, 16)),
    (sii.CAT_TXPDO, 0x1A00, 3, (0x6000, 1, 0x07, 32)),
])
def test_pdo_categories(image, cat, index, sm, entry):
    data = sii.categories(image)[cat][0]
    pdo_index, n, sm_index, _sync, name, _flags = struct.unpack_from("<HBBBBH", data)
    assert (pdo_index, n, sm_index) == (index, 1, sm)
    e_index, e_sub, _e_name, e_type, e_bits, _ = struct.unpack_from("<HBBBBH", data, 8)
    assert (e_index, e_sub, e_type, e_bits) == entry
    assert name > 0


@pytest.mark.parametrize(("bits", "code"), [(1, 0x01), (2, 0x31), (8, 0x05), (16, 0x06),
                                            (32, 0x07), (64, 0x1B), (12, 0x00)])
def test_entry_data_types(bits, code):
    assert sii.data_type(bits) == code


def test_padding_entries_have_no_type():
    from dataclasses import replace
    pad = Pdo(0x1A01, "In", (PdoEntry(0, 0, 8, ""), PdoEntry(0x6001, 1, 8, "x")))
    img = sii.build(replace(description(0), tx_pdos=(pad,)))
    data = sii.categories(img)[sii.CAT_TXPDO][0]
    assert struct.unpack_from("<HBBBBH", data, 8)[:5] == (0, 0, 0, 0, 8)
