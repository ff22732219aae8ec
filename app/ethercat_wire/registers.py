"""ESC register map: addresses, power-on contents, and decoders for SM and FMMU blocks.

Addresses are those of ETG.1000.4 / the ET1100 datasheet as SOEM uses them
(`ethercat-wire-notes.md`, "Registers touched"). Everything here is data or a pure function of
register bytes; the behaviour (side effects of reads and writes) lives in `esc.py` / `dc.py`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from app.ethercat_wire.description import SlaveDescription
from devices.master.esc_errors import BASE as ERROR_COUNTERS
from devices.master.esc_errors import END as ERROR_COUNTERS_END

MEMORY_SIZE = 0x10000  # 64 KiB per slave: 4 KiB registers + 60 KiB process RAM
PROCESS_RAM = 0x1000

# Information block (read-only for the master)
TYPE = 0x0000
REVISION = 0x0001
BUILD = 0x0002
FMMU_COUNT = 0x0004
SM_COUNT = 0x0005
RAM_SIZE = 0x0006
PORT_DESCRIPTOR = 0x0007
FEATURES = 0x0008
# Addressing
STATION_ADDRESS = 0x0010
STATION_ALIAS = 0x0012
# Data link layer
DL_CONTROL = 0x0100
DL_STATUS = 0x0110
# Application layer
AL_CONTROL = 0x0120
AL_STATUS = 0x0130
AL_STATUS_CODE = 0x0134
AL_STATE_MASK = 0x0F  # AL status bits 0-3: the state (bit 4 is the error flag)
AL_STATE_INIT = 0x01
PDI_CONTROL = 0x0140
# SII EEPROM interface
EEPROM_CONFIG = 0x0500
EEPROM_CONTROL = 0x0502
EEPROM_ADDRESS = 0x0504
EEPROM_DATA = 0x0508
# FMMUs and sync managers
FMMU0 = 0x0600
FMMU_SIZE = 16
FMMU_MAX = 16
SM0 = 0x0800
SM_SIZE = 8
SM_MAX = 16
# Distributed clocks
DC_RECEIVE_TIME_PORT0 = 0x0900
DC_SYSTEM_TIME = 0x0910
DC_RECEIVE_TIME_PU = 0x0918
DC_SYSTEM_OFFSET = 0x0920
DC_SYSTEM_DELAY = 0x0928
DC_SYSTEM_DIFF = 0x092C
DC_SPEED_COUNTER = 0x0930
DC_CYCLIC_UNIT_CONTROL = 0x0980
DC_ACTIVATION = 0x0981
DC_START_TIME0 = 0x0990
DC_CYCLE0 = 0x09A0

ESC_TYPE = 0x11  # what the notes saw SOEM accept; "ET1100-like"
FEATURE_DC = 0x0004  # 0x0008 bit 2: distributed clocks supported
FEATURE_DC64 = 0x0008  # bit 3: 64-bit system time
PORTS_MII_2 = 0x0F  # port 0 and 1 MII, ports 2 and 3 not implemented
PDI_SPI = 0x05

# EEPROM control/status word (0x0502): command in bits 8..10, status bits
EEPROM_CMD_MASK = 0x0700
EEPROM_CMD_READ = 0x0100
EEPROM_CMD_WRITE = 0x0200
EEPROM_CMD_RELOAD = 0x0300
EEPROM_WRITE_ENABLE = 0x0001
EEPROM_READ_8_BYTES = 0x0040  # "read bytes: 8" (SOEM's EC_ESTAT_R64)

# DL status (0x0110): bit 0 PDI operational, bits 4..7 physical link per port, bits 8..15 a
# (loop closed, communication) pair per port. SOEM's topology detection reads "open and
# communicating" as (loop, comm) == (0, 1), so the last slave shows port 1 closed.
DL_PDI_OPERATIONAL = 0x0001
DL_LINK_PORT0 = 0x0010
DL_LINK_PORT1 = 0x0020
DL_PORT0_COMM = 0x0200
DL_PORT1_CLOSED = 0x0400
DL_PORT1_COMM = 0x0800
DL_PORT2_CLOSED = 0x1000
DL_PORT3_CLOSED = 0x4000


def dl_status(last: bool) -> int:
    """DL status of a slave in a line: port 0 to the master, port 1 onwards or closed."""
    base = DL_PDI_OPERATIONAL | DL_LINK_PORT0 | DL_PORT0_COMM | DL_PORT2_CLOSED | DL_PORT3_CLOSED
    return base | (DL_PORT1_CLOSED if last else DL_LINK_PORT1 | DL_PORT1_COMM)


# Master writes to these ranges leave the register unchanged (start, end exclusive).
READ_ONLY: tuple[tuple[int, int], ...] = (
    *((SM0 + SM_SIZE * n + 5, SM0 + SM_SIZE * n + 6) for n in range(SM_MAX)),  # SM status
    *((SM0 + SM_SIZE * n + 7, SM0 + SM_SIZE * n + 8) for n in range(SM_MAX)),  # SM PDI control
    (0x0000, 0x0010),  # information block
    (STATION_ALIAS, STATION_ALIAS + 2),  # loaded from SII word 4, PDI-writable only
    (DL_STATUS, DL_STATUS + 2),
    (AL_STATUS, AL_STATUS + 6),  # AL status and status code come from the device (process A)
    (PDI_CONTROL, PDI_CONTROL + 2),
    # 0x0300-0x0313: counted by the model (devices/master/esc_errors.py); a write clears
    # blocks of them (esc.py) and stores nothing
    (ERROR_COUNTERS, ERROR_COUNTERS_END),
    (DC_RECEIVE_TIME_PORT0, DC_SYSTEM_TIME),  # port receive times: a write only latches
    (DC_RECEIVE_TIME_PU, DC_SYSTEM_OFFSET),
)


def power_on(desc: SlaveDescription, alias: int = 0) -> bytearray:
    """Register memory of a freshly powered ESC for this slave."""
    mem = bytearray(MEMORY_SIZE)
    mem[TYPE] = ESC_TYPE
    mem[REVISION] = 0x02
    struct.pack_into("<H", mem, BUILD, 0x0001)
    mem[FMMU_COUNT] = desc.fmmu_count
    mem[SM_COUNT] = max(4, len(desc.sync_managers))
    mem[RAM_SIZE] = (MEMORY_SIZE - PROCESS_RAM) // 1024
    mem[PORT_DESCRIPTOR] = PORTS_MII_2
    features = FEATURE_DC | FEATURE_DC64 if desc.dc_supported else 0
    struct.pack_into("<H", mem, FEATURES, features)
    struct.pack_into("<H", mem, STATION_ALIAS, alias)
    struct.pack_into("<H", mem, DL_STATUS, dl_status(last=False))
    struct.pack_into("<H", mem, AL_STATUS, 0x0001)  # INIT
    mem[PDI_CONTROL] = PDI_SPI
    struct.pack_into("<H", mem, EEPROM_CONTROL, EEPROM_READ_8_BYTES)
    return mem


# Sync manager control byte (offset 4): bits 0..1 mode, bits 2..3 direction.
SM_MODE_MAILBOX = 0x02
SM_DIR_WRITE = 0x04  # master writes, slave reads
SM_STATUS_MAILBOX_FULL = 0x08  # status byte (offset 5) bit 3
SM_REPEAT_REQUEST = 0x02  # activate byte (offset 6) bit 1; mirrored as ack in PDI control bit 1


@dataclass(frozen=True, slots=True)
class SmConfig:
    index: int
    start: int
    length: int
    control: int
    enabled: bool

    @property
    def mailbox(self) -> bool:
        return (self.control & 0x03) == SM_MODE_MAILBOX

    @property
    def master_writes(self) -> bool:
        return (self.control & 0x0C) == SM_DIR_WRITE

    @property
    def last(self) -> int:
        return self.start + self.length - 1

    @property
    def end(self) -> int:
        return self.start + self.length


@dataclass(frozen=True, slots=True)
class SmRoles:
    """Which enabled SM plays which part (first of each kind)."""

    mbx_out: SmConfig | None = None  # master -> slave mailbox (SM0 usually)
    mbx_in: SmConfig | None = None  # slave -> master mailbox (SM1)
    outputs: SmConfig | None = None  # process data the master writes (SM2)
    inputs: SmConfig | None = None  # process data the master reads (SM3)


def sm_registers(mem: bytearray, count: int) -> tuple[tuple[int, int, int, bool], ...]:
    """SM0.. as the master wrote them: (start, length, control, enabled)."""
    out = []
    for n in range(count):
        start, length, control, _status, activate, _pdi = struct.unpack_from(
            "<HHBBBB", mem, SM0 + SM_SIZE * n)
        out.append((start, length, control, bool(activate & 0x01)))
    return tuple(out)


def decode_sms(mem: bytearray, count: int) -> SmRoles:
    roles: dict[str, SmConfig] = {}
    for n in range(count):
        start, length, control, _status, activate, _pdi = struct.unpack_from(
            "<HHBBBB", mem, SM0 + SM_SIZE * n)
        if not (activate & 0x01) or length == 0:
            continue
        sm = SmConfig(n, start, length, control, True)
        if sm.mailbox:
            key = "mbx_out" if sm.master_writes else "mbx_in"
        else:
            key = "outputs" if sm.master_writes else "inputs"
        roles.setdefault(key, sm)
    return SmRoles(**roles)


FMMU_READ = 0x01  # type bit 0: master reads through this FMMU
FMMU_WRITE = 0x02  # type bit 1: master writes through this FMMU


@dataclass(frozen=True, slots=True)
class FmmuMap:
    """An enabled FMMU: logical [log_start, log_end) bytes onto physical memory."""

    log_start: int
    log_end: int
    phys_start: int
    kind: int  # FMMU_READ | FMMU_WRITE bits
    # bit granularity: None when the map is whole bytes (start bit 0, end bit 7, phys bit 0)
    bits: tuple[int, int, int] | None  # (logical start bit, logical end bit, physical start bit)


def decode_fmmus(mem: bytearray, count: int) -> tuple[FmmuMap, ...]:
    maps = []
    for n in range(count):
        log_start, length, sbit, ebit, phys, pbit, kind, enable = struct.unpack_from(
            "<IHBBHBBB", mem, FMMU0 + FMMU_SIZE * n)
        if not (enable & 0x01) or length == 0 or not (kind & 0x03):
            continue
        whole = sbit == 0 and ebit == 7 and pbit == 0
        maps.append(FmmuMap(log_start, log_start + length, phys, kind & 0x03,
                            None if whole else (sbit & 7, ebit & 7, pbit & 7)))
    return tuple(maps)


def copy_bits(mem: bytearray, fm: FmmuMap, may_write: bool, may_read: bool, frame: bytearray,
              base: int, lo: int, hi: int) -> tuple[bool, bool]:
    """Logical bytes [lo, hi) of a datagram whose byte 0 sits at frame[base] through a
    bit-granular FMMU (SOEM maps slaves with fewer than 8 bits this way): (read, wrote)."""
    sbit, ebit, pbit = fm.bits  # type: ignore[misc]
    first = fm.log_start * 8 + sbit
    last = (fm.log_end - 1) * 8 + ebit
    write = may_write and bool(fm.kind & FMMU_WRITE)
    read = may_read and bool(fm.kind & FMMU_READ)
    touched = False
    for lbit in range(max(first, lo * 8), min(last + 1, hi * 8)):
        touched = True
        phys = fm.phys_start * 8 + pbit + (lbit - first)
        fbyte, fmask = base + (lbit >> 3), 1 << (lbit & 7)
        pbyte, pmask = phys >> 3, 1 << (phys & 7)
        if write:
            mem[pbyte] = (mem[pbyte] | pmask) if frame[fbyte] & fmask else (mem[pbyte] & ~pmask)
        if read:
            frame[fbyte] = (frame[fbyte] | fmask) if mem[pbyte] & pmask else (frame[fbyte] & ~fmask)
    return read and touched, write and touched
