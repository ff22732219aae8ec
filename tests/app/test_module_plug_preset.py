"""Plug offers the module that belongs in an empty slot (seed 000 §2: a module pulled and put
back). Before, after Unplug the Plug type box still said DB16 (the catalog's first type)
whatever the slot held (/tmp/s14/ui/09_unplugged.png); the type comes from flash, else from the
last scan (the model's rail entry ``expected``)."""

from __future__ import annotations

import random

from app.ui.panels.modules import plug_preset
from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash

CATALOG = ("DB16", "DI16", "DO16", "AI8D", "AX2")


def _coupler(flash: bytes | None) -> FastCat:
    store = MemoryFlash()
    if flash is not None:
        store.save(flash)
    fc = FastCat("fastcat", random.Random(1), [(m, {}) for m in ("DB16", "DI16", "DO16",
                                                                 "AI8D")], flash=store)
    now = 0
    while not (fc.booted and fc.scan is None):
        now += 1_000
        fc.step(now)
    return fc


def test_an_empty_slot_offers_the_flash_module() -> None:
    fc = _coupler(b'["DB16", "DI16", "DO16", "AI8D"]')
    fc.apply("unplug", {}, 3)
    entry = fc.snapshot()["rail"][2]
    assert entry["type"] is None and entry["expected"] == "DO16"
    assert plug_preset(entry, CATALOG) == "DO16"


def test_two_empty_slots_offer_their_own_modules() -> None:
    """The flash counts modules, not slots: slot 3 is module 3 with slot 2 empty too."""
    fc = _coupler(b'["DB16", "DI16", "DO16", "AI8D"]')
    fc.apply("unplug", {}, 2)
    fc.apply("unplug", {}, 3)
    rail = fc.snapshot()["rail"]
    assert [plug_preset(rail[k], CATALOG) for k in (1, 2)] == ["DI16", "DO16"]


def test_without_flash_the_last_scan_decides() -> None:
    fc = _coupler(None)
    fc.apply("unplug", {}, 3)
    entry = fc.snapshot()["rail"][2]
    assert entry["expected"] == "DO16" and entry["expected_from"] == "last scan"


def test_a_taken_slot_or_an_unknown_type_presets_nothing() -> None:
    assert plug_preset({"slot": 1, "type": "DB16"}, CATALOG) is None
    assert plug_preset({"slot": 1, "type": None, "expected": None}, CATALOG) is None
    assert plug_preset({"slot": 1, "type": None, "expected": "AI8TC"}, CATALOG) is None
