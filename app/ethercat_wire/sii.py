"""SII EEPROM image of a slave, built from its SlaveDescription (ETG.2010 layout).

Word addresses (ethercat-wire-notes.md, "SII EEPROM content"):
    0x00-0x07  ESC configuration area (PDI control, alias at 0x04, CRC-8 at 0x07)
    0x08-0x0F  vendor id, product code, revision, serial (u32 each)
    0x18-0x1C  standard mailbox: rx offset/size, tx offset/size, protocols (0x0004 = CoE)
    0x3E-0x3F  EEPROM size (KiBit - 1), version
    0x40-      categories {type u16, length in words u16, data}, ended by 0xFFFF:
               STRINGS (10), GENERAL (30), FMMU (40), SM (41), TXPDO (50), RXPDO (51)
"""

from __future__ import annotations

import struct

from app.ethercat_wire import registers as R
from app.ethercat_wire.description import Pdo, SlaveDescription, SyncManager

CAT_STRINGS = 10
CAT_GENERAL = 30
CAT_FMMU = 40
CAT_SM = 41
CAT_TXPDO = 50
CAT_RXPDO = 51
CAT_END = 0xFFFF
FIRST_CATEGORY_WORD = 0x40
ALIAS_BYTE, CRC_BYTE = 0x04 * 2, 0x07 * 2  # word 4 configured station alias, word 7 CRC-8
MBX_COE = 0x0004
PORT_MII = 0x1  # GENERAL physical port nibble

# SM type byte of category 41 (what a configurator shows as MBoxOut/MBoxIn/Outputs/Inputs)
SM_TYPE_MBX_OUT, SM_TYPE_MBX_IN, SM_TYPE_OUTPUTS, SM_TYPE_INPUTS = 1, 2, 3, 4
# FMMU category: what each FMMU is for
FMMU_OUTPUTS, FMMU_INPUTS, FMMU_MBX_STATE, FMMU_UNUSED = 0x01, 0x02, 0x03, 0xFF


def crc8(data: bytes) -> int:
    """CRC-8 of the configuration area (polynomial x^8+x^2+x+1, seed 0xFF; ETG.2010 §2.2)."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def sm_type(sm: SyncManager) -> int:
    if sm.length == 0 and sm.start == 0:
        return 0  # unused
    mailbox = (sm.control & 0x03) == R.SM_MODE_MAILBOX
    writes = (sm.control & 0x0C) == R.SM_DIR_WRITE
    if mailbox:
        return SM_TYPE_MBX_OUT if writes else SM_TYPE_MBX_IN
    return SM_TYPE_OUTPUTS if writes else SM_TYPE_INPUTS


# ETG.1000.6 data type codes of the ETG.2000 names a description gives
DATA_TYPE_CODES = {"BOOL": 0x01, "SINT": 0x02, "INT": 0x03, "DINT": 0x04, "USINT": 0x05,
                   "UINT": 0x06, "UDINT": 0x07, "ULINT": 0x1B}


def data_type(bits: int, name: str = "") -> int:
    """ETG data type code of an entry: its type's (``name``), else unsigned by its length."""
    if name in DATA_TYPE_CODES:
        return DATA_TYPE_CODES[name]
    return {1: 0x01, 8: 0x05, 16: 0x06, 32: 0x07, 64: 0x1B}.get(bits, 0x30 + bits - 1
                                                                   if bits < 8 else 0x00)


_DASHES = str.maketrans({"\u2010": "-", "\u2011": "-", "\u2012": "-", "\u2013": "-",
                         "\u2014": "-", "\u2212": "-"})


class _Strings:
    def __init__(self) -> None:
        self.items: list[str] = []

    def index(self, text: str) -> int:
        if not text:
            return 0
        if text not in self.items:
            if len(self.items) == 255:
                return 0
            self.items.append(text)
        return self.items.index(text) + 1

    def encode(self) -> bytes:
        out = bytearray([len(self.items)])
        for s in self.items:
            # Latin-1 has no typographic dashes (Tab. 27's "Module xx – TxPDO"): a hyphen
            raw = s.translate(_DASHES).encode("latin-1", "replace")[:255]
            out += bytes([len(raw)]) + raw
        return bytes(out)


def _category(kind: int, data: bytes) -> bytes:
    if len(data) % 2:
        data += b"\0"
    return struct.pack("<HH", kind, len(data) // 2) + data


def _pdo_category(pdos: tuple[Pdo, ...], sm_index: int, strings: _Strings) -> bytes:
    out = bytearray()
    for pdo in pdos:
        out += struct.pack("<HBBBBH", pdo.index, len(pdo.entries), sm_index, 0,
                           strings.index(pdo.name), 0)
        for e in pdo.entries:
            out += struct.pack("<HBBBBH", e.index, e.sub, strings.index(e.name),
                               data_type(e.bits, e.data_type) if e.index else 0, e.bits, 0)
    return bytes(out)


def _sm_index(desc: SlaveDescription, kind: int, default: int) -> int:
    for n, sm in enumerate(desc.sync_managers):
        if sm_type(sm) == kind:
            return n
    return default


def set_alias(image: bytearray, alias: int) -> None:
    """Word 4, the configured station alias, and the CRC-8 of words 0-6 after it."""
    struct.pack_into("<H", image, ALIAS_BYTE, alias & 0xFFFF)
    image[CRC_BYTE] = crc8(bytes(image[:CRC_BYTE]))


def build(desc: SlaveDescription, alias: int = 0) -> bytes:
    """The whole EEPROM image, padded with 0xFF to its declared size."""
    words = bytearray(FIRST_CATEGORY_WORD * 2)
    struct.pack_into("<H", words, 0, R.PDI_SPI)
    set_alias(words, alias)
    struct.pack_into("<IIII", words, 0x08 * 2, desc.vendor_id, desc.product_code,
                     desc.revision, desc.serial)
    if desc.mailbox is not None:
        struct.pack_into("<HHHHH", words, 0x18 * 2, *desc.mailbox, MBX_COE)

    strings = _Strings()
    strings.index(desc.name)  # string 1: the name a master shows
    group, order = strings.index(desc.group), strings.index(desc.order_code)
    general = bytearray(32)
    general[0], general[2], general[3] = group, order, 1
    general[5] = desc.coe_details
    general[14] = group
    struct.pack_into("<H", general, 16, PORT_MII | PORT_MII << 4)

    fmmus = [FMMU_OUTPUTS, FMMU_INPUTS, FMMU_MBX_STATE if desc.mailbox else FMMU_UNUSED]
    fmmus = (fmmus + [FMMU_UNUSED] * desc.fmmu_count)[:desc.fmmu_count]
    sms = b"".join(struct.pack("<HHBBBB", sm.start, sm.length, sm.control, 0, sm.enable,
                               sm_type(sm)) for sm in desc.sync_managers)
    txpdo = _pdo_category(desc.tx_pdos, _sm_index(desc, SM_TYPE_INPUTS, 3), strings)
    rxpdo = _pdo_category(desc.rx_pdos, _sm_index(desc, SM_TYPE_OUTPUTS, 2), strings)

    body = _category(CAT_STRINGS, strings.encode()) + _category(CAT_GENERAL, bytes(general))
    body += _category(CAT_FMMU, bytes(fmmus))
    if sms:
        body += _category(CAT_SM, sms)
    if txpdo:
        body += _category(CAT_TXPDO, txpdo)
    if rxpdo:
        body += _category(CAT_RXPDO, rxpdo)
    body += struct.pack("<H", CAT_END)

    kbit = 2
    while kbit * 128 < len(words) + len(body):
        kbit *= 2
    struct.pack_into("<HH", words, 0x3E * 2, kbit - 1, 1)
    return bytes(words + body).ljust(kbit * 128, b"\xff")


def categories(image: bytes) -> dict[int, list[bytes]]:
    """Category data by type (a reader for tests and for the ESI export)."""
    out: dict[int, list[bytes]] = {}
    pos = FIRST_CATEGORY_WORD * 2
    while pos + 2 <= len(image):
        (kind,) = struct.unpack_from("<H", image, pos)
        if kind == CAT_END:
            break
        (words,) = struct.unpack_from("<H", image, pos + 2)
        out.setdefault(kind, []).append(bytes(image[pos + 4:pos + 4 + words * 2]))
        pos += 4 + words * 2
    return out


def strings(image: bytes) -> list[str]:
    """STRINGS category as a list; index 0 of the list is string 1."""
    data = categories(image).get(CAT_STRINGS, [b"\0"])[0]
    out, pos = [], 1
    for _ in range(data[0]):
        n = data[pos]
        out.append(data[pos + 1:pos + 1 + n].decode("latin-1"))
        pos += 1 + n
    return out
