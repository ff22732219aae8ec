"""Outputs on a communication error in OP: 0xF700 / 0xF701 per slot kind, 0xF710 SysOK.

Seed 001 §9.3.5 and §9.3.6. The handled errors are ETG.1020 communication errors in OP that
send the device to SAFE-OP(-Error) on its own (sync error, SM watchdog). 0 in every field
(the reset default) keeps the behaviour of firmware before 01.20: outputs hold their last
value. Pure functions; the device calls :func:`outputs_on_error` once, when it falls.
"""

from __future__ import annotations

from collections.abc import Sequence

from devices.trscat.catalog import ErrorRule, IoShape, ModuleKind

ALL_OUTPUTS = 0xFFFF  # §9.3.5: AN-E / generic standard switch to ErrorVal only with 0xFFFF
U16 = 0xFFFF


def as_output_value(kind: ModuleKind, raw: int) -> int:
    """ErrorValN is a U16; an AN-E output is INT16, so 0x8000.. are negative counts (for the
    digital kinds it is a bit mask, for the word kinds the word itself)."""
    raw &= U16
    if kind.shape is IoShape.ANALOG and raw & 0x8000:
        return raw - 0x1_0000
    return raw


def outputs_on_error(kind: ModuleKind, held: Sequence[int], error_mode: int, error_value: int,
                     sysok_mask: int = 0) -> list[int]:
    """The outputs of one slot after a communication error in OP.

    ``held``: the master's last outputs (the "ultimo valore noto"); ``error_mode`` /
    ``error_value``: 0xF701 / 0xF700 of this slot; ``sysok_mask``: 0xF710:1, used only for
    the integrated module, where a 1 bit forces the output to 0 whatever 0xF700/0xF701 say.
    """
    error_mode &= U16
    value = as_output_value(kind, error_value)
    rule = kind.rule
    if rule is ErrorRule.PER_BIT:
        out = [(value >> i) & 1 if (error_mode >> i) & 1 else held[i] for i in range(len(held))]
    elif rule is ErrorRule.WHOLE_MODULE:
        out = [value] * len(held) if error_mode == ALL_OUTPUTS else list(held)
    else:  # ErrorRule.HOLD: §9.3.5 "I valori degli oggetti sono ignorati"
        out = list(held)
    if kind.integrated:
        out = [0 if (sysok_mask >> i) & 1 else v for i, v in enumerate(out)]  # §9.3.6
    return out
