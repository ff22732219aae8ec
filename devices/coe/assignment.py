"""The drive's PDOs on EtherCAT: the eight default PDOs, 0x1C12 / 0x1C13, the slots.

Seed 004 ch. 5 "PDO": "Attivi in totale 8 PDO di cui 4 in trasmissione e 4 in ricezione"
(0x1600..0x1603, 0x1A00..0x1A03 with the contents below); "come default, attraverso gli
oggetti 0x1C12 e 0x1C13, sono selezionati gli oggetti 0x1600 e 0x1A02 per l'interpolazione in
posizione (modes of operation = 7)". "Mappatura dinamica PDO": 0x1C12 (RxPDO assign) and
0x1C13 (TxPDO assign) select "una qualunque configurazione possibile fra i pdo di default";
other contents are made by editing 0x1600..0x1603 / 0x1A00..0x1A03 first, then 0x1C12 /
0x1C13. "Utilizzo degli Slots": Position / Interpolated / Velocity Mode, and 0x6060 = 8 CSP.

The PDO records and their mapping rules are the CANopen node's (:class:`devices.canopen.pdo.Pdo`,
ch. 4, which ch. 5 refers to: "Riferirsi alle caratteristiche del livello applicativo CANOpen");
their default contents are the ch. 5 table, which the CANopen node uses too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from devices.canopen.pdo import (
    DEFAULT_RPDO_MAPS,
    DEFAULT_TPDO_MAPS,
    MAX_ENTRIES,
    Pdo,
)
from devices.pdo_assign import PdoAssignment

RX_ASSIGN, TX_ASSIGN = 0x1C12, 0x1C13
RX_MAP_FIRST, TX_MAP_FIRST = 0x1600, 0x1A00
PDOS_PER_DIRECTION = 4
DEFAULT_RX = (0x1600,)  # ch. 5 "Nota importante": 0x1600 + 0x1A02, interpolated (mode 7)
DEFAULT_TX = (0x1A02,)


@dataclass(frozen=True)
class Slot:
    """A TwinCAT slot of the ESI file (ch. 5 "Utilizzo degli Slots")."""

    name: str
    description: str  # as TwinCAT's Module Description column prints it
    mode: int  # 0x6060 for it
    rx: int
    tx: int
    module: str = ""  # as TwinCAT's Module column prints it ("" : not in the .xml)


# Ch. 5 "Utilizzo degli Slots". CSP (0x6060 = 8) has no slot of its own in the seed; it takes
# the Position Mode PDOs (controlword + 0x607A target position, statusword + 0x6064): the
# target position is what a CSP master sends every cycle (docs/ethercat-coe.md §CSP).
SLOTS: dict[str, Slot] = {s.name: s for s in (
    Slot("position", "Position Mode", 1, 0x1602, 0x1A02, "Position Mode"),
    Slot("interpolated", "Profile Interpolated Mode", 7, 0x1600, 0x1A02, "Interpolated Mode"),
    Slot("velocity", "Profile Velocity Mode", 3, 0x1603, 0x1A03, "Velocity Mode"),
    Slot("csp", "Cyclic Synchronous Position Mode", 8, 0x1602, 0x1A02),
)}
DEFAULT_SLOT = "interpolated"  # "Di default sarà impostata la modalità Interpolated Mode"
# The slots the drive's .xml offers: the three of ch. 5's Slots tab ("sono disponibili i
# seguenti slot mutualmente selezionabili"); CSP is the Position Mode slot + 0x6060 = 8.
XML_SLOTS = tuple(s for s in SLOTS.values() if s.module)


def pdo_name(index: int) -> str:
    """A PDO's name in the drive's .xml, as ch. 5's TwinCAT "Process Data" screen prints it
    ("0x1A02 ... TxPDO 3", "0x1600 ... RxPDO 1"): 'RxPDO n' / 'TxPDO n', n = (index & 0xFF) + 1.
    """
    kind = "RxPDO" if index < TX_MAP_FIRST else "TxPDO"
    return f"{kind} {(index & 0xFF) + 1}"


# The mapped objects' names in the drive's .xml: those ch. 5's TwinCAT screens print (PDO
# Content of 0x1A02: "Status Word", "Position Actual Value"; the tree's Velocity Mode module:
# "Control Word", "Target Velocity", "Actual Velocity"), the others as ch. 5 "PDO" lists them.
# The dictionary keeps its DS402 names (SDO Information shows those).
ESI_ENTRY_NAMES: dict[tuple[int, int], str] = {
    (0x6040, 0): "Control Word", (0x6041, 0): "Status Word",
    (0x60C1, 1): "Set-Point Position", (0x6060, 0): "Modes of Operation",
    (0x6061, 0): "Modes of Operation Display", (0x607A, 0): "Target Position",
    (0x6064, 0): "Position Actual Value", (0x60FF, 0): "Target Velocity",
    (0x606C, 0): "Actual Velocity",
}


def pdo_entry_name(index: int, sub: int, name: str) -> str:
    """The .xml name of mapped object ``index:sub`` (``name``: its dictionary name, kept for an
    object ch. 5 maps in no default PDO)."""
    return ESI_ENTRY_NAMES.get((index, sub), name)


def default_pdos(receive: bool) -> list[Pdo]:
    """The four PDOs of one direction with the ch. 5 contents (no COB-IDs on EtherCAT)."""
    maps = DEFAULT_RPDO_MAPS if receive else DEFAULT_TPDO_MAPS
    return [Pdo(n + 1, receive, cob_id=0, entries=[*m, *[0] * (MAX_ENTRIES - len(m))], count=len(m))
            for n, m in enumerate(maps)]


class Assignment(PdoAssignment):
    """0x1C12 or 0x1C13 of the drive: sub 0 = count, subs 1..4 = the assigned PDO indices, in
    order; only the four default PDOs of the direction exist (devices/pdo_assign.py has the
    rules; the PREOP guard is devices/coe/objects.py's, as for the mapping objects)."""

    def __init__(self, index: int, first: int) -> None:
        super().__init__(index, range(first, first + PDOS_PER_DIRECTION), PDOS_PER_DIRECTION)
        self.first = first  # 0x1600 or 0x1A00

    @classmethod
    def default(cls, receive: bool) -> Assignment:
        index, first, pdos = (RX_ASSIGN, RX_MAP_FIRST, DEFAULT_RX) if receive else \
            (TX_ASSIGN, TX_MAP_FIRST, DEFAULT_TX)
        out = cls(index, first)
        out.assign(pdos)
        return out


def assigned_pdos(assignment: Assignment, pdos: Sequence[Pdo]) -> list[Pdo]:
    return [pdos[i - assignment.first] for i in assignment.assigned]


def mapping_problem(assignment: Assignment, pdos: Sequence[Pdo]) -> str | None:
    """Why an assignment cannot be used for process data, or None (checked at PREOP -> SAFEOP).

    An assigned PDO must map something. An object may repeat: ch. 5 allows "una qualunque
    configurazione possibile fra i pdo di default", and every default RxPDO carries the
    controlword, so 0x1601 "ulteriormente" mapped next to a slot's RxPDO repeats 0x6040; the
    outputs image then writes each object once, with its last value in image order
    (process_image.last_writes, docs/ethercat-coe.md §PDO assignment).
    """
    for pdo in assigned_pdos(assignment, pdos):
        if pdo.count == 0:
            return f"0x{pdo.map_index:04X} is assigned but maps nothing"
    return None


def slot_of(rx: Assignment, tx: Assignment, mode: int) -> str | None:
    """The slot whose PDOs are assigned (Position and CSP share theirs: the mode decides)."""
    found = [s for s in SLOTS.values() if rx.assigned == (s.rx,) and tx.assigned == (s.tx,)]
    for slot in found:
        if slot.mode == mode:
            return slot.name
    return found[0].name if found else None
