"""The TRS modules: the integrated slot and the TRS-nn-E expansions, their idents and limits.

Seed 001 §5 (how many expansions fit), §9.3.2 (the 32-bit idents of 0xF030 / 0xF050, which
are the ASCII of the short names) and §9.3.5 (how each kind's outputs behave on an error).
The seed gives no process image for the expansions: the channel counts below other than the
integrated module's 16 lines (§3) are FieldRig's choice, written down in docs/trscat.md.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

from devices.names import did_you_mean
from devices.od import DataType


class ErrorRule(enum.Enum):
    """How a slot's outputs use 0xF700 / 0xF701 on a communication error (§9.3.5)."""

    PER_BIT = "per_bit"  # integrated, TRS-IO-E: each ErrorMode bit picks hold / ErrorVal bit
    WHOLE_MODULE = "whole_module"  # TRS-AN-E, generic standard: ErrorMode 0xFFFF -> ErrorVal
    HOLD = "hold"  # TRS-AC-E, generic smart: the objects are ignored, always hold


class IoShape(enum.Enum):
    """What the slot's channels are (drives the operator actions and the PDO entries)."""

    DIGITAL = "digital"  # bidirectional PNP lines: output n and input n are the same terminal
    ANALOG = "analog"  # INT16 inputs (volts from the field) and INT16 outputs
    WORDS = "words"  # UINT16 data words in both directions


@dataclass(frozen=True)
class ModuleKind:
    name: str  # product name as §9.3.2 prints it
    short: str  # the four ASCII characters of the ident
    ident: int  # §9.3.2, reported in 0xF050.n and expected in 0xF030.n
    smart: bool  # §5: a smart expansion uses more of the TRS bus
    integrated: bool
    rule: ErrorRule
    shape: IoShape
    inputs: int  # channels in the TxPDO (0x6nn0)
    outputs: int  # channels in the RxPDO (0x7nn0)

    @property
    def input_type(self) -> DataType:
        return _TYPES[self.shape]

    @property
    def output_type(self) -> DataType:
        return _TYPES[self.shape]


_TYPES = {IoShape.DIGITAL: DataType.BOOLEAN, IoShape.ANALOG: DataType.INTEGER16,
          IoShape.WORDS: DataType.UNSIGNED16}


def ascii_ident(short: str) -> int:
    """§9.3.2: the ident is the short name in ASCII, first character in the high byte."""
    return int.from_bytes(short.encode("ascii"), "big")


# §9.3.2 idents (printed values; tests check they are the ASCII of the short names).
INTEGRATED = ModuleKind("TRS-CAT integrated", "IO-B", 0x494F2D42, smart=False, integrated=True,
                        rule=ErrorRule.PER_BIT, shape=IoShape.DIGITAL, inputs=16, outputs=16)
EXPANSIONS: dict[str, ModuleKind] = {k.name: k for k in (
    ModuleKind("TRS-IO-E", "IO-E", 0x494F2D45, smart=False, integrated=False,
               rule=ErrorRule.PER_BIT, shape=IoShape.DIGITAL, inputs=16, outputs=16),
    ModuleKind("TRS-AN-E", "AN-E", 0x414E2D45, smart=False, integrated=False,
               rule=ErrorRule.WHOLE_MODULE, shape=IoShape.ANALOG, inputs=4, outputs=2),
    ModuleKind("TRS-AC-E", "AC-E", 0x41432D45, smart=True, integrated=False,
               rule=ErrorRule.HOLD, shape=IoShape.WORDS, inputs=4, outputs=4),
    ModuleKind("TRS-XX-E", "XX-E", 0x58582D45, smart=False, integrated=False,
               rule=ErrorRule.WHOLE_MODULE, shape=IoShape.WORDS, inputs=1, outputs=1),
    ModuleKind("TRS-KK-E", "KK-E", 0x4B4B2D45, smart=True, integrated=False,
               rule=ErrorRule.HOLD, shape=IoShape.WORDS, inputs=4, outputs=4),
)}
BY_IDENT: dict[int, ModuleKind] = {k.ident: k for k in (INTEGRATED, *EXPANSIONS.values())}

MAX_SLOTS = 8  # §5 / §9.3.5: "numero massimo di slot possibile in TRS-CAT"
MAX_EXPANSIONS = MAX_SLOTS - 1


@dataclass(frozen=True)
class SlotLimit:
    """One row of the §5 table."""

    internal: int
    standard: int  # max standard expansions
    smart: int  # max smart expansions
    slots: int  # slots occupied


# §5 "espandibilità massima" (internal, max standard, max smart, slots occupied).
SLOT_LIMITS: tuple[SlotLimit, ...] = (
    SlotLimit(1, 7, 0, 8),
    SlotLimit(1, 5, 1, 7),
    SlotLimit(1, 3, 2, 6),
    SlotLimit(1, 1, 3, 5),
)


def expansion_kind(name: str) -> ModuleKind:
    """``TRS-IO-E``, ``IO-E`` or ``io-e``; KeyError naming the known kinds otherwise."""
    wanted = str(name).strip().upper()
    for kind in EXPANSIONS.values():
        if wanted in (kind.name, kind.short):
            return kind
    raise KeyError(f"unknown TRS expansion {name!r} (known: "
                   f"{', '.join(EXPANSIONS)}; seed 001 §9.3.2){did_you_mean(name, EXPANSIONS)}")


def limit_violation(kinds: Sequence[ModuleKind]) -> str | None:
    """Why a list of expansions (integrated excluded) does not fit §5, or None when it fits."""
    smart = sum(1 for k in kinds if k.smart)
    standard = len(kinds) - smart
    if any(standard <= row.standard and smart <= row.smart for row in SLOT_LIMITS):
        return None
    allowed = "; ".join(f"{row.standard} standard + {row.smart} smart" for row in SLOT_LIMITS)
    return (f"{standard} standard + {smart} smart expansions do not fit a TRS-CAT (seed 001 §5 "
            f"allows at most: {allowed})")


def ident_allowed_at(sub: int, ident: int) -> bool:
    """Whether 0xF030 / 0xF050 sub ``sub`` (1..8) may hold ``ident`` (§9.3.2 tables).

    Sub 1 is the integrated module only; subs 2..7 any expansion; sub 8 (expansion 7) no smart
    expansion, which is also what §5 implies (a smart expansion leaves at most 6 expansions).
    """
    kind = BY_IDENT.get(ident)
    if kind is None:
        return False
    if sub == 1:
        return kind.integrated
    if 2 <= sub <= 7:
        return not kind.integrated
    return sub == 8 and not kind.integrated and not kind.smart


def expansion_list(names: Sequence[str], what: str) -> list[ModuleKind]:
    """The expansions a list of names gives (integrated excluded); ValueError naming ``what``
    when a name is unknown or the list does not fit §5."""
    if isinstance(names, str):
        raise ValueError(f"{what}s: give a list of names, not {names!r}")
    if len(names) > MAX_EXPANSIONS:
        raise ValueError(f"{len(names)} {what}s: a TRS-CAT takes at most {MAX_EXPANSIONS} "
                         f"(seed 001 §5)")
    kinds = []
    for n, name in enumerate(names, start=1):
        try:
            kinds.append(expansion_kind(name))
        except KeyError as exc:
            raise ValueError(f"{what} {n}: {exc.args[0]}") from None
    violation = limit_violation(kinds)
    if violation is not None:
        raise ValueError(f"{what}s: {violation}")
    return kinds
