"""Byte layouts: the diagnosis message of 0x10F3 (seed 002 §2.5.2, Tab. 15/16, after ETG.1020)
and the 8-byte emergency (§2.5.3, Tab. 20). Everything little-endian, as the example shows.

Tab. 15 example, 22 bytes: ``02 00 00 E1 | 02 02 | 02 37 | 1F C5 9D 61 31 00 00 00 | 05 00 |
02 | 05 00 | 80``: Diag Code 0xE1000002 (CPX error 2), flags 0x0202 (2 parameters, type 2
error), Text-ID 0x3702, time stamp in ns, parameter 1 UNSIGNED8 = module 2, parameter 2
UNSIGNED8 = channel 0x80. The object entry is BYTE[23] (Tab. 14): shorter messages are padded
with zero bytes.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from devices.cpx.codes import (
    CPX_ERRORS,
    CPX_TEXT_ID_BASE,
    DIAG_CODE_CPX,
    DIAG_CODE_DS401,
    EMCY_CODES,
    NO_ERROR_TEXT,
    TEXT_IDS,
    DiagType,
)
from devices.od import DataType

MESSAGE_BYTES = 23  # Tab. 14 / Tab. 27: BYTE[23]
HEADER = struct.Struct("<IHHQ")  # diag code, flags, Text-ID, time stamp (ns)
PARAM_FLAGS = struct.Struct("<H")  # ETG.1020: bits 0-11 data type (DS301 code) for type 0
PARAM_FORMATS = {DataType.UNSIGNED8: "<B", DataType.UNSIGNED16: "<H", DataType.UNSIGNED32: "<I"}

# Channel parameter (Tab. 16: "channel 80h (128d)" for the example's output 0 of a CPX-E-8DO):
# bits 0-5 the channel, bits 6-7 the direction, 01 input / 10 output (docs/cpx-e-ec.md).
CHANNEL_INPUT = 0x40
CHANNEL_OUTPUT = 0x80


def channel_param(channel: int, output: bool) -> int:
    return (CHANNEL_OUTPUT if output else CHANNEL_INPUT) | (channel & 0x3F)


@dataclass(frozen=True)
class DiagMessage:
    diag_code: int
    dtype: DiagType
    text_id: int
    timestamp_ns: int
    params: tuple[tuple[DataType, int], ...] = ()

    @property
    def flags(self) -> int:
        """Tab. 16 "02 02": number of parameters in the high byte, the type in the low."""
        return len(self.params) << 8 | int(self.dtype)

    def encode(self) -> bytes:
        raw = HEADER.pack(self.diag_code, self.flags, self.text_id, self.timestamp_ns)
        for dtype, value in self.params:
            raw += PARAM_FLAGS.pack(int(dtype)) + struct.pack(PARAM_FORMATS[dtype], value)
        if len(raw) > MESSAGE_BYTES:
            raise ValueError(f"diagnosis message of {len(raw)} bytes: 0x10F3 holds "
                             f"{MESSAGE_BYTES} (seed 002 Tab. 14)")
        return raw.ljust(MESSAGE_BYTES, b"\x00")

    @classmethod
    def decode(cls, raw: bytes) -> DiagMessage:
        code, flags, text_id, stamp = HEADER.unpack_from(raw)
        offset, params = HEADER.size, []
        for _ in range(flags >> 8):
            (ptype,) = PARAM_FLAGS.unpack_from(raw, offset)
            dtype = DataType(ptype & 0x0FFF)
            fmt = PARAM_FORMATS[dtype]
            (value,) = struct.unpack_from(fmt, raw, offset + PARAM_FLAGS.size)
            params.append((dtype, value))
            offset += PARAM_FLAGS.size + struct.calcsize(fmt)
        return cls(code, DiagType(flags & 0x0F), text_id, stamp, tuple(params))

    def text(self) -> str:
        """English text as a configuration tool shows it from the ESI Text-IDs (Tab. 17)."""
        if CPX_TEXT_ID_BASE <= self.text_id <= CPX_TEXT_ID_BASE + 0xFF:
            number = self.text_id - CPX_TEXT_ID_BASE
            known = CPX_ERRORS.get(number)
            what = known.text if known else (NO_ERROR_TEXT if number == 0 else "CPX error")
            body = f"CPX error {number}: {what}"
        else:
            body = TEXT_IDS.get(self.text_id, ("", f"Text-ID 0x{self.text_id:04X}"))[1]
        values = ", ".join(f"0x{v:X}" if v > 9 else str(v) for _t, v in self.params)
        marker = self.diag_code >> 24
        origin = {DIAG_CODE_CPX: "CPX", DIAG_CODE_DS401: "DS401"}.get(marker, "ETG")
        return f"{self.dtype.name.lower()} [{origin} 0x{self.diag_code:08X}] {body}" + \
            (f" ({values})" if values else "")


EMCY_BYTES = 8


def emergency_frame(code: int, register: int, status_bits: int, module: int, cpx_error: int,
                    info: int) -> bytes:
    """Tab. 20: bytes 0-1 error code (LE), 2 error register (0x1001), 3 status bits (0x1002),
    4 CPX-E module number, 5 CPX-E error number, 6 reserved, 7 additional information."""
    if code not in EMCY_CODES:
        raise ValueError(f"emergency code 0x{code:04X} is not in seed 002 Tab. 21")
    return struct.pack("<HBBBBBB", code, register, status_bits, module, cpx_error, 0, info)


def parse_emergency(frame: bytes) -> dict[str, int]:
    code, register, status, module, number, _reserved, info = struct.unpack("<HBBBBBB", frame)
    return {"code": code, "register": register, "status_bits": status, "module": module,
            "cpx_error": number, "info": info}
