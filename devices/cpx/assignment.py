"""The CPX-E-EC's PDO assignment 0x1C12 / 0x1C13 (seed 002 §2.5.2 l. 539-541, Tab. 27 0x1A40).

The module PDOs are assigned in the order of the addressing rules (§2.3.1: the bus module,
then analog and technology modules, then digital ones, each by module number); 0x1C12 lists
the RxPDOs read-only. «можно в качестве опции выполнить присвоение (привязку) объекта "New
Message Available" данным процесса»: 0x1A40 "Diag History – TxPDO" (0x10F3:4, 1 bit) is an
optional TxPDO, not assigned by default, which a master assigns through 0x1C13 in PREOP as
ETG.1000.6 / CiA 301 change an assignment: sub 0 = 0, the entries, sub 0 = n. Aborts: outside
PREOP 0x08000022, an entry while sub 0 is not 0 0x06010000, a PDO the device does not have
(or one twice) 0x06090030, sub 0 past the entries 0x06090031. A start (restart, power-up)
brings back the default (RAM).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from devices.cpx.addressing import GROUP_ORDER
from devices.cpx.modules import CpxModule
from devices.od import AbortCode, SdoAbort

RX_ASSIGN, TX_ASSIGN = 0x1C12, 0x1C13
RXPDO_BASE, TXPDO_BASE = 0x1600, 0x1A00
DIAG_PDO = 0x1A40  # Tab. 27 "Diag History – TxPDO"


def address_order(units: Sequence[CpxModule], receive: bool) -> tuple[int, ...]:
    """The module PDOs in the order of §2.3.1 (modules without data in that direction have
    none)."""
    base = RXPDO_BASE if receive else TXPDO_BASE
    return tuple(base + unit.number for kind in GROUP_ORDER for unit in units
                 if unit.mtype.kind is kind
                 and (unit.mtype.outputs if receive else unit.mtype.inputs))


@dataclass
class TxAssignment:
    """0x1C13: the module TxPDOs by default; 0x1A40 may be added (or anything rearranged)."""

    default: tuple[int, ...]
    may_write: Callable[[], bool]  # PREOP only
    entries: list[int] = field(default_factory=list)
    count: int = 0

    def __post_init__(self) -> None:
        self.entries = [*self.default, 0]  # room for the module PDOs and 0x1A40
        self.count = len(self.default)

    @property
    def allowed(self) -> tuple[int, ...]:
        return (*self.default, DIAG_PDO)

    @property
    def assigned(self) -> tuple[int, ...]:
        return tuple(self.entries[:self.count])

    def _check_state(self, sub: int) -> None:
        if not self.may_write():
            raise SdoAbort(AbortCode.CANNOT_STORE_STATE, TX_ASSIGN, sub)

    def set_entry(self, sub: int, value: int) -> None:
        self._check_state(sub)
        if self.count != 0:
            raise SdoAbort(AbortCode.UNSUPPORTED_ACCESS, TX_ASSIGN, sub)
        if value != 0 and value not in self.allowed:
            raise SdoAbort(AbortCode.VALUE_RANGE, TX_ASSIGN, sub)
        self.entries[sub - 1] = value

    def set_count(self, value: int) -> None:
        self._check_state(0)
        if value > len(self.entries):
            raise SdoAbort(AbortCode.VALUE_TOO_HIGH, TX_ASSIGN, 0)
        chosen = self.entries[:value]
        if 0 in chosen or len(set(chosen)) != len(chosen):
            raise SdoAbort(AbortCode.VALUE_RANGE, TX_ASSIGN, 0)
        self.count = value
