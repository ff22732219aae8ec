"""The Encoder section's zero-cycle boxes write the 0x7600 of the module the page picked (seed
000 §6.30: 0x7600 + 0x10 * (N - 1), N the module number, §6.24: modules numbered as detected
along the bus). Before, the index was computed from the slot: behind an empty slot, after a
rescan, the box of the AX2 in slot 3 homed the AX2 in slot 4 (module 3)."""

from __future__ import annotations

import random

import pytest

from app.ui.panels.modules import command_index
from devices.device import CommandError
from devices.ethercat import AlState
from devices.fastcat.coupler import FastCat


def _settle(fc: FastCat, now: int) -> int:
    while not (fc.booted and fc.scan is None):
        now += 1_000
        fc.step(now)
    return now


def _rescanned_with_a_gap() -> FastCat:
    fc = FastCat("fastcat", random.Random(1), [(m, {}) for m in ("DB16", "DI16", "AX2", "AX2")])
    now = _settle(fc, 0)
    fc.request_state(AlState.PREOP)
    fc.apply("unplug", {}, 2)
    fc.request_state(AlState.INIT)  # §3: the coupler scans the bus again at INIT
    _settle(fc, now)
    return fc


def test_the_index_follows_the_module_number_not_the_slot() -> None:
    fc = _rescanned_with_a_gap()
    rail = fc.snapshot()["rail"]
    assert [(e["slot"], e.get("module_number")) for e in rail] == [(1, 1), (2, None), (3, 2),
                                                                     (4, 3)]
    assert command_index(rail[2]) == 0x7610  # not 0x7620, the AX2 of slot 4
    assert command_index(rail[3]) == 0x7620
    assert {0x7610, 0x7620} <= {e.index for e in fc.od or ()}


def test_a_module_the_last_scan_did_not_number_has_no_command_word() -> None:
    fc = _rescanned_with_a_gap()
    fc.apply("plug", {"type": "AX2"}, 5)
    entry = fc.snapshot()["rail"][4]
    assert entry["type"] == "AX2" and entry.get("module_number") is None
    with pytest.raises(CommandError, match="slot 5: the last scan did not number"):
        command_index(entry)
