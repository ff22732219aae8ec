"""Seed 000 §6.17: 0x5200:1 Reset fault is in the FastCAT snapshot, so a view can show it.

The dashboard's Reset fault checkbox mirrors the snapshot's ``reset_fault``; it must be the
object's value whichever way it was written (object write, the coupler action, the mapped
0x16FF bit), and the object's default (False) after a power cycle.
"""

from __future__ import annotations

import pytest
from fastcat_bench import Bench

from devices.device import CommandError
from devices.ethercat import AlState
from devices.fastcat.objects import COUPLER_RXPDO

RESET_FAULT = (0x5200, 1)  # §6.17

# (how the bit is written, the levels written one after the other)
WRITES = [
    ("write_object", (1,)),
    ("write_object", (1, 0)),
    ("write_object", (1, 1, 0, 1)),
    ("set_reset_fault", (True,)),
    ("set_reset_fault", (True, False)),
]


def _write(bench: Bench, how: str, level: int | bool) -> None:
    if how == "write_object":
        bench.write(*RESET_FAULT, int(level))
    else:
        bench.apply("set_reset_fault", on=bool(level))


@pytest.mark.parametrize(("how", "levels"), WRITES)
def test_snapshot_shows_the_last_level_written(how: str, levels: tuple[int | bool, ...]) -> None:
    """§6.17: the snapshot's reset_fault is 0x5200:1 after every write."""
    bench = Bench()
    bench.to_state(AlState.OP)
    assert bench.fc.snapshot()["reset_fault"] is False  # §6.17 default: False
    for level in levels:
        _write(bench, how, level)
        assert bench.fc.snapshot()["reset_fault"] is bool(level)
        assert bench.read(*RESET_FAULT) == int(bool(level))


def test_snapshot_follows_a_write_through_the_mapped_coupler_rxpdo() -> None:
    """§5 / §6.17: 0x16FF maps 0x5200:1; the object is the one the snapshot shows."""
    bench = Bench()
    bench.to_state(AlState.OP)
    od = bench.fc.od
    assert od is not None
    mapped = [od.read(COUPLER_RXPDO, sub) for sub in range(1, od.read(COUPLER_RXPDO, 0) + 1)]
    assert 0x5200_01_01 in mapped  # index 0x5200, sub 1, one bit
    od.write(*RESET_FAULT, 1)
    assert bench.fc.snapshot()["reset_fault"] is True


def test_power_cycle_brings_back_the_default() -> None:
    """§6.17 default False: the bit does not outlive the supply, and with the coupler off
    there is no object to write."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.write(*RESET_FAULT, 1)
    bench.apply("power", on=False)
    assert bench.fc.snapshot()["reset_fault"] is False
    with pytest.raises(CommandError):
        bench.apply("set_reset_fault", on=True)
    assert bench.fc.snapshot()["reset_fault"] is False
    bench.apply("power", on=True)
    bench.settle()
    assert bench.fc.snapshot()["reset_fault"] is False
    assert bench.read(*RESET_FAULT) == 0
