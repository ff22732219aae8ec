"""EtherCAT frames and datagrams (ETG.1000.4 §5): parse in place, build for tests and benches.

Frame layout on the wire (EtherType 0x88A4, little endian):
    Ethernet header (14 bytes) | EtherCAT header u16: length (11 bits), type (4 bits, 1 = datagrams)
    datagram: cmd u8, idx u8, ADP u16, ADO u16, len|R|C|M u16, IRQ u16, data[len], WKC u16
The "more" bit (0x8000 of the length word) says another datagram follows. The slave side
answers with the same frame: same length, `idx` unchanged, data and WKC updated in place
(`ethercat-wire-notes.md`, "Frames and datagrams").

Hand-written on purpose: no maintained Python library plays the slave side of EtherCAT, and
scapy's EtherCAT layer (a packet-crafting toolkit, several MB) is built for dissecting, not for
rewriting a datagram in place 10,000 times a second (docs/ethercat-wire.md).
"""

from __future__ import annotations

import enum
import struct
from dataclasses import dataclass

ETHERTYPE = 0x88A4
ETH_HEADER = 14
ECAT_HEADER = 2
DG_HEADER = 10
WKC_SIZE = 2
FRAME_TYPE_DATAGRAMS = 1
MORE = 0x8000
LEN_MASK = 0x07FF
MIN_FRAME = 60  # Ethernet minimum without FCS: short frames are padded with zeros

_ECAT = struct.Struct("<H")
_DG = struct.Struct("<BBHHHH")  # cmd, idx, adp, ado, len|flags, irq
_U16 = struct.Struct("<H")


class Cmd(enum.IntEnum):
    """Datagram commands (ETG.1000.4 Table 8)."""

    NOP = 0
    APRD = 1
    APWR = 2
    APRW = 3
    FPRD = 4
    FPWR = 5
    FPRW = 6
    BRD = 7
    BWR = 8
    BRW = 9
    LRD = 10
    LWR = 11
    LRW = 12
    ARMW = 13
    FRMW = 14


# Command classes by addressing mode and access, as sets of raw command bytes for the hot path.
AUTO_INC = frozenset({Cmd.APRD, Cmd.APWR, Cmd.APRW, Cmd.ARMW})
CONFIGURED = frozenset({Cmd.FPRD, Cmd.FPWR, Cmd.FPRW, Cmd.FRMW})
BROADCAST = frozenset({Cmd.BRD, Cmd.BWR, Cmd.BRW})
LOGICAL = frozenset({Cmd.LRD, Cmd.LWR, Cmd.LRW})
READS = frozenset({Cmd.APRD, Cmd.FPRD, Cmd.BRD, Cmd.LRD})
WRITES = frozenset({Cmd.APWR, Cmd.FPWR, Cmd.BWR, Cmd.LWR})
READ_WRITES = frozenset({Cmd.APRW, Cmd.FPRW, Cmd.BRW, Cmd.LRW})


class FrameError(ValueError):
    """A frame that is not a well-formed EtherCAT datagram frame."""


@dataclass(slots=True)
class Datagram:
    """One datagram of a frame: header fields plus where its data and WKC sit in the frame."""

    cmd: int
    idx: int
    adp: int
    ado: int
    length: int
    irq: int
    offset: int  # start of data in the frame buffer
    more: bool

    @property
    def wkc_offset(self) -> int:
        return self.offset + self.length

    @property
    def logical_address(self) -> int:
        """ADP and ADO together: the 32-bit logical address of LRD/LWR/LRW."""
        return self.adp | (self.ado << 16)


def is_ethercat(frame: bytes | bytearray | memoryview) -> bool:
    return len(frame) >= ETH_HEADER + ECAT_HEADER and frame[12] == 0x88 and frame[13] == 0xA4


def parse(frame: bytearray | memoryview) -> list[Datagram]:
    """The datagrams of a frame (raises FrameError when the chain overruns the frame)."""
    if not is_ethercat(frame):
        raise FrameError("not an EtherCAT frame (EtherType 0x88A4)")
    (header,) = _ECAT.unpack_from(frame, ETH_HEADER)
    if header >> 12 != FRAME_TYPE_DATAGRAMS:
        raise FrameError(f"EtherCAT frame type {header >> 12} is not 1 (datagrams)")
    end = ETH_HEADER + ECAT_HEADER + (header & LEN_MASK)
    if end > len(frame):
        raise FrameError(
            f"EtherCAT length {header & LEN_MASK} overruns the {len(frame)}-byte frame")
    out: list[Datagram] = []
    pos = ETH_HEADER + ECAT_HEADER
    while True:
        if pos + DG_HEADER + WKC_SIZE > end:
            raise FrameError(f"datagram header at byte {pos} overruns the EtherCAT length")
        cmd, idx, adp, ado, lenw, irq = _DG.unpack_from(frame, pos)
        length = lenw & LEN_MASK
        data = pos + DG_HEADER
        if data + length + WKC_SIZE > end:
            raise FrameError(f"datagram at byte {pos} with {length} data bytes overruns the frame")
        more = bool(lenw & MORE)
        out.append(Datagram(cmd, idx, adp, ado, length, irq, data, more))
        pos = data + length + WKC_SIZE
        if not more:
            return out


def set_adp(frame: bytearray, dg: Datagram, adp: int) -> None:
    """Write back the ADP a chain of slaves leaves behind (auto-increment / broadcast)."""
    _U16.pack_into(frame, dg.offset - 8, adp & 0xFFFF)


def get_wkc(frame: bytes | bytearray | memoryview, dg: Datagram) -> int:
    return _U16.unpack_from(frame, dg.offset + dg.length)[0]


def set_wkc(frame: bytearray, dg: Datagram, wkc: int) -> None:
    _U16.pack_into(frame, dg.offset + dg.length, wkc & 0xFFFF)


@dataclass(frozen=True)
class Request:
    """A datagram a master sends (tests and benches build frames from these)."""

    cmd: int
    adp: int
    ado: int
    data: bytes
    idx: int = 0
    irq: int = 0
    wkc: int = 0

    @classmethod
    def logical(cls, cmd: int, address: int, data: bytes, idx: int = 0) -> Request:
        return cls(cmd, address & 0xFFFF, (address >> 16) & 0xFFFF, data, idx)


def build(requests: list[Request], src: bytes = b"\x01\x01\x01\x01\x01\x01",
          dst: bytes = b"\xff\xff\xff\xff\xff\xff") -> bytearray:
    """A frame carrying `requests` in order, chained by the more bit, padded to 60 bytes."""
    body = bytearray()
    for i, rq in enumerate(requests):
        lenw = len(rq.data) | (MORE if i < len(requests) - 1 else 0)
        body += _DG.pack(rq.cmd, rq.idx, rq.adp & 0xFFFF, rq.ado & 0xFFFF, lenw, rq.irq)
        body += rq.data + _U16.pack(rq.wkc)
    frame = bytearray(dst + src + b"\x88\xa4")
    frame += _ECAT.pack(len(body) | FRAME_TYPE_DATAGRAMS << 12) + body
    if len(frame) < MIN_FRAME:
        frame += bytes(MIN_FRAME - len(frame))
    return frame


@dataclass(frozen=True)
class Reply:
    """A datagram as it came back: what a master reads from the answered frame."""

    cmd: int
    idx: int
    adp: int
    ado: int
    data: bytes
    wkc: int


def replies(frame: bytes | bytearray) -> list[Reply]:
    buf = frame if isinstance(frame, bytearray) else bytearray(frame)
    return [
        Reply(d.cmd, d.idx, d.adp, d.ado, bytes(buf[d.offset:d.offset + d.length]),
              get_wkc(buf, d))
        for d in parse(buf)
    ]
