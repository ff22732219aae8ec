"""The FastCAT module catalog against seed 000 §2."""

from __future__ import annotations

import pytest

from devices.fastcat.analog import AI_KINDS
from devices.fastcat.catalog import (
    AI_KIND_NAMES,
    CATALOG,
    GROUPS,
    module_type,
    module_type_by_code,
)

# §2 as printed: (name, column, inputs, outputs) — digital column, analog column, encoders.
SEED_LIST = [
    ("DB16", "digital"), ("DI16", "digital"), ("DO82", "digital"), ("DO16", "digital"),
    ("AI8D", "analog"), ("AI8C", "analog"), ("AI8TC", "analog"), ("AI8PT100", "analog"),
    ("AI8PT1000", "analog"), ("AB4P4", "analog"), ("AB4D4", "analog"), ("AB4C4", "analog"),
    ("AI4D", "analog"), ("AI4C", "analog"), ("AO4", "analog"), ("AO4H", "analog"),
    ("AI4P", "analog"), ("AI8M", "analog"), ("AB4M4", "analog"), ("AX2", "encoder"),
]

# §2 channel counts: name -> (di, do, dio, ai, ao, encoders)
CHANNELS = {
    "DB16": (0, 0, 16, 0, 0, 0), "DI16": (16, 0, 0, 0, 0, 0), "DO82": (0, 8, 0, 0, 0, 0),
    "DO16": (0, 16, 0, 0, 0, 0), "AI8D": (0, 0, 0, 8, 0, 0), "AI8C": (0, 0, 0, 8, 0, 0),
    "AI8TC": (0, 0, 0, 8, 0, 0), "AI8PT100": (0, 0, 0, 8, 0, 0), "AI8PT1000": (0, 0, 0, 8, 0, 0),
    "AB4P4": (0, 0, 0, 4, 4, 0), "AB4D4": (0, 0, 0, 4, 4, 0), "AB4C4": (0, 0, 0, 4, 4, 0),
    "AI4D": (0, 0, 0, 4, 0, 0), "AI4C": (0, 0, 0, 4, 0, 0), "AO4": (0, 0, 0, 0, 4, 0),
    "AO4H": (0, 0, 0, 0, 4, 0), "AI4P": (0, 0, 0, 4, 0, 0), "AI8M": (0, 0, 0, 8, 0, 0),
    "AB4M4": (0, 0, 0, 8, 4, 0), "AX2": (0, 0, 0, 0, 0, 2),
}


def test_catalog_is_the_20_types_of_section_2_in_order():
    """§2: exactly these names, in the order the seed prints them."""
    assert [(t.name, t.group) for t in CATALOG.values()] == SEED_LIST
    assert list(CATALOG) == [name for name, _g in SEED_LIST]


@pytest.mark.parametrize("name", list(CHANNELS))
def test_channel_counts(name):
    """§2 descriptions: channel counts per type."""
    t = CATALOG[name]
    assert (t.di, t.do, t.dio, t.ai, t.ao, t.encoders) == CHANNELS[name]
    assert t.group in GROUPS
    assert t.description


def test_db16_groups_of_four():
    """§6.6: DB16 channels configurable in groups of 4 (one connector each)."""
    assert CATALOG["DB16"].dio_group_size == 4


@pytest.mark.parametrize(("name", "bits"), [("AO4", 12), ("AO4H", 16), ("AB4P4", 12)])
def test_analog_output_resolution(name, bits):
    """§2: AO4 12 bit, AO4H 16 bit."""
    assert CATALOG[name].ao_bits == bits


def test_ax2_is_not_counted_as_analog():
    """§2: at most 8 analog modules; AX2 sits in its own 'Moduli encoder' list."""
    analog = [t.name for t in CATALOG.values() if t.counts_as_analog]
    assert len(analog) == 15
    assert "AX2" not in analog


@pytest.mark.parametrize("t", list(CATALOG.values()), ids=list(CATALOG))
def test_ai_kind_is_known(t):
    if t.ai:
        assert t.ai_kind in AI_KIND_NAMES
        assert t.ai_kind == "configurable" or t.ai_kind in AI_KINDS
    else:
        assert t.ai_kind is None


@pytest.mark.parametrize(("name", "temperature"), [
    ("AI8TC", True), ("AI8PT100", True), ("AI8PT1000", True), ("AI8D", False), ("AI8M", False),
])
def test_temperature_modules(name, temperature):
    """§6.9: temperature modules get their own filter default."""
    assert CATALOG[name].temperature is temperature


def test_product_codes_unique_and_reversible():
    codes = [t.product_code for t in CATALOG.values()]
    assert len(set(codes)) == 20
    assert all(0 < c <= 0xFFFF_FFFF for c in codes)  # UDINT in 0xF050.n (§6.31)
    for t in CATALOG.values():
        assert module_type_by_code(t.product_code) is t
    assert module_type_by_code(0) is None
    assert module_type_by_code(0xFACA) is None  # the coupler's own product code (§6.5)


def test_product_codes_are_stable():
    """FieldRig-assigned codes are stored in flash: they must never be renumbered."""
    assert CATALOG["DB16"].product_code == 0x0000FA01
    assert CATALOG["AX2"].product_code == 0x0000FA14


def test_unknown_name_lists_valid_names():
    assert module_type("AI8TC") is CATALOG["AI8TC"]
    with pytest.raises(KeyError) as err:
        module_type("AI8X")
    assert "AI8X" in str(err.value)
    assert "DB16" in str(err.value) and "AX2" in str(err.value)
