"""The CPX-E-EC's PDO assignment 0x1C12 / 0x1C13 (seed 002 §2.5.2 l. 539-541, Tab. 27 0x1A40).

The module PDOs are assigned in the order of the addressing rules (§2.3.1: the bus module,
then analog and technology modules, then digital ones, each by module number); 0x1C12 lists
the RxPDOs read-only. «можно в качестве опции выполнить присвоение (привязку) объекта "New
Message Available" данным процесса»: 0x1A40 "Diag History – TxPDO" (0x10F3:4, 1 bit) is an
optional TxPDO, not assigned by default, which a master assigns through 0x1C13 in PREOP as
ETG.1000.6 / CiA 301 change an assignment: sub 0 = 0, the entries, sub 0 = n. Aborts: outside
PREOP 0x08000022, an entry while sub 0 is not 0 0x06010000, a PDO the device does not have
(or one twice) 0x06090030, sub 0 past the entries 0x06090031; any list but the module TxPDOs
in the §2.3.1 order, with or without 0x1A40 last, 0x06090030 (``TxAssignment``). Sub 0 left
at 0 refuses PREOP -> SAFEOP (``complete``, devices/cpx/transitions.py). A start (restart,
power-up) brings back the default (RAM).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from devices.cpx.addressing import GROUP_ORDER
from devices.cpx.modules import CpxModule
from devices.od import AbortCode, SdoAbort
from devices.pdo_assign import PdoAssignment

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
class TxAssignment(PdoAssignment):
    """0x1C13 with the device's layout rule: the module TxPDOs as §2.3.1 places them, all of
    them, and 0x1A40 only after them.

    §2.3.1 has the bus module assign the addresses itself (group, then module number) and
    Tab. 9 is the image a PLC programmer reads them from: a module TxPDO moved or left out
    would move module data off those addresses. Tab. 27 maps one bit in 0x1A40 (sub 0 = 1,
    RO: no padding entry a master could add); before a module it would move that module's
    data by a bit. Last, the bit takes a byte of its own at the end of SM3 (7 bits unused)
    and every module stays where the addressing rules put it."""

    modules: tuple[int, ...] = ()  # the module TxPDOs in the §2.3.1 order

    def check_sequence(self, chosen: Sequence[int]) -> None:
        super().check_sequence(chosen)
        if chosen and tuple(chosen) not in (self.modules, (*self.modules, DIAG_PDO)):
            raise SdoAbort(AbortCode.VALUE_RANGE, self.index, 0)

    def complete(self) -> bool:
        """Every module TxPDO assigned: not the empty list of a change in progress (sub 0 = 0,
        the first step of CiA 301's procedure) while modules have inputs."""
        return self.count > 0 or not self.modules


def tx_assignment(default: tuple[int, ...], may_write: Callable[[], bool]) -> TxAssignment:
    """0x1C13: the module TxPDOs by default (room for them and 0x1A40), written in PREOP only
    (``may_write``); the rules are devices/pdo_assign.py's."""
    out = TxAssignment(TX_ASSIGN, (*default, DIAG_PDO), len(default) + 1, may_write, default)
    out.entries[:len(default)] = default  # the start's default, not a master's write
    out.count = len(default)
    return out
