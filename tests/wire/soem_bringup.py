"""The SOEM line test's session (tests/wire/test_soem_line.py) and how far the line is brought
up on it, so that each test asks for the state it needs and any test passes alone or in any
order. Before, the tests ran in "bring-up order" on one session: `-k map_and_bring` alone
failed with "map: TypeError('NoneType' object is not subscriptable)" (SOEM had no slaves: no
config_init), and a failure early failed every test after it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

from devices.ethercat import AlState

SLAVES = 4
EXPECTED_WKC = 3 * SLAVES  # every slave has outputs and inputs: LRW +2 +1 each
# The TRS-CAT's 0xF030 (position 1: the integrated module, the line's TRS-IO-E), which the
# master's start-up writes in PRE-OP (seed 001 §9.2 PS, §9.3.2): the slave powers up with
# the integrated module alone there, and the rig file's `configured` is the built-in
# master's list, not SOEM's (docs/trscat.md "Who writes 0xF030").
TRSCAT_STARTUP = ((1, 0xF030, 0, b"\x02"), (1, 0xF030, 1, (0x494F2D42).to_bytes(4, "little")),
                  (1, 0xF030, 2, (0x494F2D45).to_bytes(4, "little")))
STATE_TIMEOUT_S = 10.0


class Stage(IntEnum):
    """How far the session's master has brought the line, each stage implying the ones before.
    MAPPED says the process data is set up but the slaves may have left OP since (a fault, a
    damaged cable): a test that needs OP then brings the line up again from a scan."""
    NONE = 0
    SCANNED = 1  # config_init: every slave found, in PRE-OP, no process data (SM2 / SM3) set up
    MAPPED = 2  # config_map
    OP = 3  # every slave in OP


@dataclass
class SoemLine:
    """What the module's tests share: the runtime, the bridge, the SOEM master process, and
    the stage the line is at (a test that takes it elsewhere says so: :meth:`left`)."""
    runtime: Any
    bridge: Any
    master: Callable[..., Any]
    stage: Stage = Stage.NONE
    map_errors: list[str] = field(default_factory=list)  # what the last config_map reported

    def left(self, stage: Stage) -> None:
        """A test takes the line down to at most ``stage`` (said before it does: a test that
        fails halfway leaves the next one a line it brings up again, not a broken one)."""
        self.stage = min(self.stage, stage)

    def init(self) -> tuple[int, list[tuple[str, int, int, int]]]:
        """config_init (SOEM's scan): the slaves found, back in PRE-OP with nothing mapped."""
        self.stage = Stage.NONE
        n, slaves = self.master("init")
        assert n == SLAVES, slaves
        self.stage = Stage.SCANNED
        return n, slaves

    def scanned(self) -> SoemLine:
        """A line just scanned, its process data not set up (a mapped one is scanned again:
        config_init clears the sync managers and FMMUs)."""
        if self.stage != Stage.SCANNED:
            self.init()
        return self

    def at_least(self, stage: Stage) -> SoemLine:
        """The line at ``stage`` or further, brought up only as far as it is not yet."""
        if self.stage >= stage:
            return self
        if stage >= Stage.MAPPED:
            self.scanned().map_to_op()
        else:
            self.init()
        return self

    def map_to_op(self) -> None:
        """The start-up writes and config_map (SYNC0 on the DC slaves first), then SAFE-OP and
        OP for every slave."""
        assert self.stage == Stage.SCANNED, self.stage
        expected, errors = self.master("map", [i for i, d in enumerate(self.bridge.descriptions)
                                               if d.dc_supported], TRSCAT_STARTUP)
        self.map_errors = errors
        self.stage = Stage.MAPPED
        assert expected == EXPECTED_WKC
        for target in (AlState.SAFEOP, AlState.OP):
            states = self.master("state", target, STATE_TIMEOUT_S)
            assert [s & 0x1F for s, _ in states] == [target] * SLAVES, states
        self.stage = Stage.OP
