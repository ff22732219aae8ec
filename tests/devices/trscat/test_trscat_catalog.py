"""TRS modules: idents of seed 001 §9.3.2, slot limits of §5, output rules of §9.3.5."""

from __future__ import annotations

import itertools

import pytest

from devices.trscat.catalog import (
    BY_IDENT,
    EXPANSIONS,
    INTEGRATED,
    SLOT_LIMITS,
    ErrorRule,
    ascii_ident,
    expansion_kind,
    ident_allowed_at,
    limit_violation,
)

# §9.3.2, as printed: (name, ident, ASCII).
SEED_IDENTS = [
    ("TRS-CAT integrated", 0x494F2D42, "IO-B"),
    ("TRS-IO-E", 0x494F2D45, "IO-E"),
    ("TRS-AN-E", 0x414E2D45, "AN-E"),
    ("TRS-AC-E", 0x41432D45, "AC-E"),
    ("TRS-XX-E", 0x58582D45, "XX-E"),
    ("TRS-KK-E", 0x4B4B2D45, "KK-E"),
]


@pytest.mark.parametrize(("name", "ident", "text"), SEED_IDENTS)
def test_idents_are_the_printed_ascii(name: str, ident: int, text: str) -> None:
    """§9.3.2: each ident is the quoted ASCII text, first character in the high byte."""
    kind = BY_IDENT[ident]
    assert kind.name == name and kind.short == text
    assert ascii_ident(text) == ident


def test_catalog_holds_exactly_the_seed_modules() -> None:
    assert sorted(BY_IDENT) == sorted(i for _n, i, _t in SEED_IDENTS)
    assert INTEGRATED.integrated and INTEGRATED.inputs == INTEGRATED.outputs == 16  # §3


@pytest.mark.parametrize(("name", "smart", "rule"), [
    ("TRS-IO-E", False, ErrorRule.PER_BIT),
    ("TRS-AN-E", False, ErrorRule.WHOLE_MODULE),
    ("TRS-XX-E", False, ErrorRule.WHOLE_MODULE),  # "generica espansione standard"
    ("TRS-AC-E", True, ErrorRule.HOLD),
    ("TRS-KK-E", True, ErrorRule.HOLD),  # "generica espansione smart"
])
def test_kinds(name: str, smart: bool, rule: ErrorRule) -> None:
    """§9.3.2 (standard / smart) and §9.3.5 (which output rule each kind follows)."""
    kind = EXPANSIONS[name]
    assert (kind.smart, kind.rule) == (smart, rule)


@pytest.mark.parametrize("text", ["TRS-IO-E", "IO-E", "io-e", " trs-io-e "])
def test_names_accepted(text: str) -> None:
    assert expansion_kind(text) is EXPANSIONS["TRS-IO-E"]


def test_unknown_name() -> None:
    with pytest.raises(KeyError, match="unknown TRS expansion 'TRS-ZZ-E'"):
        expansion_kind("TRS-ZZ-E")


@pytest.mark.parametrize("row", SLOT_LIMITS, ids=lambda r: f"{r.standard}std+{r.smart}smart")
def test_each_row_of_the_slot_table_fits(row) -> None:
    """§5: every printed row fits, and occupies internal + standard + smart slots."""
    kinds = [EXPANSIONS["TRS-IO-E"]] * row.standard + [EXPANSIONS["TRS-KK-E"]] * row.smart
    assert limit_violation(kinds) is None
    assert row.internal + row.standard + row.smart == row.slots


@pytest.mark.parametrize(("standard", "smart"), [
    (8, 0), (6, 1), (4, 2), (2, 3), (0, 4), (1, 4),
])
def test_one_more_does_not_fit(standard: int, smart: int) -> None:
    """§5: one expansion past a row of the table is refused."""
    kinds = [EXPANSIONS["TRS-XX-E"]] * standard + [EXPANSIONS["TRS-AC-E"]] * smart
    message = limit_violation(kinds)
    assert message is not None and "seed 001 §5" in message


def test_limits_are_the_table_and_nothing_else() -> None:
    """§5: (standard, smart) fits exactly when some row allows it."""
    for standard, smart in itertools.product(range(9), range(5)):
        fits = any(standard <= r.standard and smart <= r.smart for r in SLOT_LIMITS)
        kinds = [EXPANSIONS["TRS-AN-E"]] * standard + [EXPANSIONS["TRS-KK-E"]] * smart
        assert (limit_violation(kinds) is None) == fits, (standard, smart)


@pytest.mark.parametrize(("sub", "name", "allowed"), [
    (1, "IO-B", True), (1, "IO-E", False),  # "ammesso solo 0x494F2D42"
    *[(s, n, True) for s in range(2, 8) for n in ("IO-E", "AN-E", "AC-E", "XX-E", "KK-E")],
    *[(s, "IO-B", False) for s in range(2, 9)],
    (8, "IO-E", True), (8, "AN-E", True), (8, "XX-E", True),  # expansion 7
    (8, "AC-E", False), (8, "KK-E", False),  # no smart expansion at expansion 7
])
def test_idents_allowed_per_sub(sub: int, name: str, allowed: bool) -> None:
    """§9.3.2 tables of 0xF030 / 0xF050: which ident each sub may hold."""
    ident = ascii_ident(name)
    assert ident_allowed_at(sub, ident) is allowed


def test_unknown_ident_never_allowed() -> None:
    assert not ident_allowed_at(2, 0x12345678)
