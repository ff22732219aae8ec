"""The TRS-CAT object dictionary against the tables of seed 001 §9.3 (index, sub, type,
access, PDO mapping), and the per-slot process-data objects of §9.3.3."""

from __future__ import annotations

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.od import Access, DataType

U8, U16, U32, BOOL, I16 = (DataType.UNSIGNED8, DataType.UNSIGNED16, DataType.UNSIGNED32,
                           DataType.BOOLEAN, DataType.INTEGER16)
RO, RW, RWPS = Access.RO, Access.RW, Access.RW_PREOP

# (index, sub, type, access, PDO mappable): the seed's tables. 0xF030 prints "R-WPS": read
# always, written in PRE-OP only (the refusal elsewhere: test_trscat_esm.py).
SEED_TABLE = [
    *[(i, 1, U16, RW, False) for i in (0x1C32, 0x1C33)],  # §9.3.1
    *[(i, s, U32, RO, False) for i in (0x1C32, 0x1C33) for s in (2, 5, 6, 9, 11)],
    *[(i, 4, U16, RO, False) for i in (0x1C32, 0x1C33)],
    *[(i, 32, BOOL, RO, False) for i in (0x1C32, 0x1C33)],
    (0xF030, 0, U8, RWPS, False), *[(0xF030, s, U32, RWPS, False) for s in range(1, 9)],  # §9.3.2
    (0xF050, 0, U8, RO, False), *[(0xF050, s, U32, RO, False) for s in range(1, 9)],
    (0xF100, 0, U8, RO, False), (0xF100, 1, U8, RO, True),  # §9.3.4
    *[(0xF100, s, BOOL, RO, True) for s in (2, 3, 4)],
    (0xF700, 0, U8, RO, False), *[(0xF700, s, U16, RW, False) for s in range(1, 9)],  # §9.3.5
    (0xF701, 0, U8, RO, False), *[(0xF701, s, U16, RW, False) for s in range(1, 9)],
    (0xF710, 0, U8, RO, False), (0xF710, 1, U16, RW, False),  # §9.3.6
    (0x10F1, 2, U32, RO, False),  # §9.3.7
    (0x10F3, 2, U8, RO, False), (0x10F3, 3, U8, RW, False), (0x10F3, 4, BOOL, RO, True),
    (0x10F3, 5, U16, RW, False),
]


@pytest.fixture(scope="module")
def od():
    bench = Bench(["IO-E", "AN-E", "KK-E"])
    bench.to_state(AlState.PREOP)
    # The master's list (its PS init commands, written in PRE-OP): the PDO mappings follow it.
    for sub, ident in enumerate((4, 0x494F2D42, 0x494F2D45, 0x414E2D45, 0x4B4B2D45)):
        bench.write(0xF030, sub, ident)
    return bench.trs.od


@pytest.mark.parametrize(("index", "sub", "dtype", "access", "pdo"), SEED_TABLE,
                         ids=[f"{r[0]:04X}:{r[1]}" for r in SEED_TABLE])
def test_seed_tables(od, index: int, sub: int, dtype: DataType, access: Access,
                     pdo: bool) -> None:
    entry = od.entry(index, sub)
    assert (entry.dtype, entry.access, entry.pdo_mappable) == (dtype, access, pdo)


@pytest.mark.parametrize(("index", "sub", "value"), [
    (0xF700, 0, 8), (0xF701, 0, 8),  # "Vale 8 pari al numero massimo di slot"
    (0xF710, 0, 1),  # "Vale 1"
    (0x10F3, 1, 20),  # acknowledge mode, 20 messages
    (0x10F1, 2, 3),
    (0xF000, 1, 0x10), (0xF000, 2, 8),
    (0x1008, 0, "TRS-CAT"),
    (0x1000, 0, 0x1389),
])
def test_fixed_values(od, index: int, sub: int, value: object) -> None:
    assert od.read(index, sub) == value


@pytest.mark.parametrize(("index", "sub"), [
    (0xF700, s) for s in range(1, 9)] + [(0xF701, s) for s in range(1, 9)] + [(0xF710, 1)])
def test_error_objects_reset_to_zero(od, index: int, sub: int) -> None:
    """§9.3.5 / §9.3.6: 0 is the value at reset (hold the last value)."""
    assert od.read(index, sub) == 0


@pytest.mark.parametrize(("slot", "inputs", "outputs", "dtype"), [
    (0, 16, 16, BOOL),  # §9.3.3: 0x6000 / 0x7000, 16 lines
    (1, 16, 16, BOOL), (2, 4, 2, I16), (3, 4, 4, U16),  # FieldRig (docs/trscat.md)
])
def test_slot_objects(od, slot: int, inputs: int, outputs: int, dtype: DataType) -> None:
    """ETG.5001 MDP: slot s at 0x6000 / 0x7000 + 0x10 * s; RxPDO 0x1600 + s, TxPDO
    0x1A00 + s, entries index << 16 | sub << 8 | bits."""
    i_index, o_index = 0x6000 + 0x10 * slot, 0x7000 + 0x10 * slot
    assert od.read(i_index, 0) == inputs and od.read(o_index, 0) == outputs
    assert od.entry(i_index, 1).dtype is dtype and od.entry(o_index, 1).access is RW
    bits = 1 if dtype is BOOL else 16
    assert od.read(0x1A00 + slot, 0) == inputs
    assert od.read(0x1A00 + slot, 1) == i_index << 16 | 1 << 8 | bits
    assert od.read(0x1600 + slot, outputs) == o_index << 16 | outputs << 8 | bits


def test_mapping_objects_are_read_only(od) -> None:
    """§9.3.3: the device maps its PDOs itself."""
    for index in (0x1600, 0x1A00, 0x1AFF, 0x1C12, 0x1C13):
        assert od.entry(index, 0).access is RO


def test_no_object_for_an_absent_slot(od) -> None:
    assert not od.has_index(0x6040) and not od.has_index(0x1604)
