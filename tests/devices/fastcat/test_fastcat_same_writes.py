"""A process image written every cycle (docs/fastcat-coupler.md, "Step cost").

A master writes the coupler's outputs every cycle (Reset fault 0x5200:1 in RxPDO 0x16FF, the
digital outputs 0x7000, the analog outputs 0x7400), nearly always the values they already hold.
Such a write is not announced to the coupler, so its next step may stay a still one. The
differential: a twin that announces every write (``SKIP_SAME_WRITES = False``, the plain path)
must give the same events, snapshots and object values, step for step, while the image changes
now and then (outputs on and off, a Reset-fault edge with an alarm latched, faults injected).
"""

from __future__ import annotations

import json
import random

import pytest

from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash
from devices.master import EtherCatMaster
from devices.od import SdoAbort

DEFAULT = ("DB16", "DI16", "DO16", "AI8D", "AO4", "AI8TC", "AX2")  # static/rigs/default.toml
STEP_US = 1_000
DO16, AO4 = 0x7000 + 0x10 * 2, 0x7400 + 0x10 * 4  # modules 3 and 5


class Twin:
    """A coupler and its master at 1 ms, the master writing the image before each cycle."""

    def __init__(self, plain: bool) -> None:
        self.fc = FastCat("fastcat", random.Random(5), [(m, {}) for m in DEFAULT],
                          flash=MemoryFlash())
        if plain:
            self.fc.SKIP_SAME_WRITES = False
        self.master = EtherCatMaster("master", random.Random(6), slaves=[self.fc])
        self.now = 0
        self.events: list[str] = []
        self.full_steps = 0

    def step(self, image: dict[tuple[int, int], int]) -> list[str]:
        od = self.fc.od
        refused = []
        if od is not None:
            for (index, sub), value in image.items():
                try:
                    od.write(index, sub, value)
                except SdoAbort as abort:  # before the scan bound the modules
                    refused.append(str(abort))
        self.full_steps += self.fc._touched
        self.now += STEP_US
        for device in (self.fc, self.master):
            device.step(self.now)
            self.events += [json.dumps(e.to_record(), sort_keys=True)
                            for e in device.drain_events()]
        return refused

    def view(self) -> str:
        od = self.fc.od
        values = [] if od is None else [od.read(DO16, ch) for ch in range(1, 17)] + [
            od.read(AO4, ch) for ch in range(1, 5)] + [od.read(0x5200, 1)]
        return json.dumps([self.fc.snapshot(), self.master.snapshot(), values],
                          sort_keys=True, default=str)


def image_changes(rng: random.Random, image: dict[tuple[int, int], int], i: int,
                  twins: tuple[Twin, Twin]) -> None:
    """Now and then an output, the Reset-fault bit or a fault: the rest of the time the image
    is written unchanged."""
    if rng.random() < 0.02:
        sub = rng.randint(1, 16)
        image[(DO16, sub)] = 1 - image[(DO16, sub)]
    if rng.random() < 0.01:
        image[(AO4, rng.randint(1, 4))] = rng.choice((0, 500, -2000, 32767))
    if rng.random() < 0.01:
        image[(0x5200, 1)] = 1 - image[(0x5200, 1)]
    if i % 1500 == 650:
        image[(DO16, 3)] = 1  # on, so that the short below is seen
    if i % 1500 == 700:  # a latched alarm for the Reset-fault edge to clear (§6.17)
        for t in twins:
            t.fc.apply("output_short", {"channel": 3, "active": True}, 3)
    if i % 1500 == 900:
        for t in twins:
            t.fc.apply("output_short", {"channel": 3, "active": False}, 3)


@pytest.mark.parametrize("seed", [1, 2])
def test_unchanged_image_writes_match_the_plain_path(seed: int) -> None:
    rng = random.Random(seed)
    fast, plain = Twin(plain=False), Twin(plain=True)
    image = {(0x5200, 1): 0} | {(DO16, ch): 0 for ch in range(1, 17)} | {
        (AO4, ch): 0 for ch in range(1, 5)}
    for i in range(8000):
        image_changes(rng, image, i, (fast, plain))
        assert fast.step(image) == plain.step(image), i
        if i % 50 == 0:
            assert fast.view() == plain.view(), i
    assert fast.events == plain.events
    assert fast.view() == plain.view()
    kinds = {json.loads(e)["event"] for e in fast.events}
    assert {"alarm", "led"} <= kinds  # the image did reach the model
    # The plain twin is told of every write from the scan's end (~3 s) on, the fast one only
    # of the changes.
    assert plain.full_steps > 4500 and fast.full_steps < plain.full_steps // 10


def test_a_changed_value_still_touches_the_coupler() -> None:
    twin = Twin(plain=False)
    image = {(DO16, 1): 0}
    for _ in range(4000):  # booted, scanned, in OP, settled
        twin.step(image)
    assert twin.fc.od is not None
    twin.fc.od.write(DO16, 1, 0)
    assert not twin.fc._touched
    twin.fc.od.write(DO16, 1, 1)
    assert twin.fc._touched
