"""DC-SYNC and FREE-RUN: when the local cycle runs, SM events, SYNC0, sync errors.

Seed 001 §9.1.1 (DC-SYNC on SYNC0, 1:1 with the master cycle, ESC 0x980 = 0x0300; FREE-RUN,
fixed 500 us local cycle, 0x980 = 0x0000; the SM2 frame must not invade the calc+copy time),
§9.3.1 (0x1C32 / 0x1C33 values) and §9.3.7 (0x10F1:2, limit 3 consecutive sync errors).

Model (docs/trscat.md): a master frame is one SM2 event. In DC-SYNC the SYNC0 pulses run on
the slave's own clock once the master has started them (PREOP -> SAFEOP), one per cycle; the
cycle is the master's frame period at that moment. At every SYNC0 the frames that arrived at
least the calc+copy time (100 us) earlier are taken; none is an "SM event missed" and the
counter 0x1C32:11 counts them consecutively (a good event resets it). At the limit of 0x10F1:2
the sync error 0x1C32:32 is TRUE. Frames that arrive while SYNC0 is lost count the other way
round (SM events without SYNC0); at the same limit that is a fatal sync error.
"""

from __future__ import annotations

import enum
import random
from dataclasses import dataclass, field

FREE_RUN_CYCLE_US = 500  # §9.1.1 "tempo di ciclo locale fisso pari a 500 us"
MIN_CYCLE_NS = 500_000  # §9.3.1 0x1C32:5 / 0x1C33:5
CALC_COPY_NS = 100_000  # §9.3.1 0x1C32:6 / 0x1C33:6
DELAY_NS = 150_000  # §9.3.1 0x1C32:9 / 0x1C33:9
SYNC_MODES_SUPPORTED = 0x0005  # §9.3.1 0x1C32:4: FREE-RUN and DC-SYNC only
SYNC_ERROR_LIMIT = 3  # §9.3.7 0x10F1:2
NS_PER_US = 1_000


class SyncMode(enum.IntEnum):
    """0x1C32:1 / 0x1C33:1 values (§9.3.1)."""

    FREE_RUN = 0x0000
    DC_SYNC = 0x0002

    @property
    def sync_control(self) -> int:
        """ESC register 0x980 (Sync Control) that goes with the mode (§9.1.1)."""
        return SYNC_CONTROL[self]

    @property
    def label(self) -> str:
        return "DC-SYNC" if self is SyncMode.DC_SYNC else "FREE-RUN"


SYNC_CONTROL: dict[SyncMode, int] = {SyncMode.FREE_RUN: 0x0000, SyncMode.DC_SYNC: 0x0300}
MODE_BY_NAME: dict[str, SyncMode] = {"dc": SyncMode.DC_SYNC, "dc-sync": SyncMode.DC_SYNC,
                                     "free_run": SyncMode.FREE_RUN,
                                     "free-run": SyncMode.FREE_RUN}


class SyncState(enum.Enum):
    """StateChanged machine "sync"."""

    FREE_RUN = "free_run"  # FREE-RUN mode, or DC mode before the master started SYNC0
    DC_RUNNING = "dc_running"
    SYNC_ERROR = "sync_error"  # SM events missed up to the limit
    SYNC0_LOST = "sync0_lost"  # SM events without SYNC0 up to the limit (fatal sync error)


@dataclass
class SyncUnit:
    mode: SyncMode = SyncMode.DC_SYNC
    running: bool = False  # SYNC0 pulses started by the master (SAFEOP, OP in DC-SYNC)
    cycle_us: int = 0  # SYNC0 cycle while running
    next_sync0_us: int = 0
    next_free_us: int = 0  # next FREE-RUN local cycle
    arrivals: list[int] = field(default_factory=list)  # SM2 frames waiting for a SYNC0
    sm_missed: int = 0  # 0x1C32:11 / 0x1C33:11
    without_sync0: int = 0  # SM events since the last SYNC0
    sync0_seen: bool = True
    last_frame_us: int | None = None
    frame_period_us: int | None = None
    # Injected faults.
    drop_frames: int = 0  # the next N frames never reach SM2 (lost / CRC error)
    sync0_lost: bool = False  # the SYNC0 pulses stop
    jitter_us: int = 0  # each frame arrives up to this much late

    # ---- state ------------------------------------------------------------------------------
    @property
    def sync_error(self) -> bool:
        """0x1C32:32 / 0x1C33:32."""
        return self.running and self.sm_missed >= SYNC_ERROR_LIMIT

    @property
    def fatal(self) -> bool:
        return self.running and self.without_sync0 >= SYNC_ERROR_LIMIT

    @property
    def state(self) -> SyncState:
        if not self.running:
            return SyncState.FREE_RUN
        if self.fatal:
            return SyncState.SYNC0_LOST
        return SyncState.SYNC_ERROR if self.sync_error else SyncState.DC_RUNNING

    @property
    def cycle_ns(self) -> int:
        """0x1C32:2 / 0x1C33:2: the local cycle in ns (0 before DC-SYNC is started)."""
        if self.mode is SyncMode.FREE_RUN:
            return FREE_RUN_CYCLE_US * NS_PER_US
        return self.cycle_us * NS_PER_US if self.running else 0

    # ---- the master's side ------------------------------------------------------------------
    def frame(self, now_us: int, rng: random.Random) -> bool:
        """A frame passed; True when it is an SM2 event now (FREE-RUN / not running).

        In DC-SYNC while running the event is taken at the next SYNC0 instead (``arrivals``).
        """
        if self.last_frame_us is not None and now_us > self.last_frame_us:
            self.frame_period_us = now_us - self.last_frame_us
        self.last_frame_us = now_us
        if self.drop_frames > 0:
            self.drop_frames -= 1
            return False
        if not self.running:
            return True
        if self.sync0_seen:
            self.sync0_seen = False
            self.without_sync0 = 0
        else:
            self.without_sync0 += 1
        late = rng.randint(0, self.jitter_us) if self.jitter_us > 0 else 0
        self.arrivals.append(now_us + late)
        return False

    def start_refusal(self) -> str | None:
        """Why SYNC0 cannot start (``"no_frames"``, ``"cycle_too_small"``), or None."""
        if self.mode is not SyncMode.DC_SYNC:
            return None
        if self.frame_period_us is None or self.last_frame_us is None:
            return "no_frames"
        if self.frame_period_us * NS_PER_US < MIN_CYCLE_NS:
            return "cycle_too_small"
        return None

    def start(self, now_us: int) -> None:
        """PREOP -> SAFEOP accepted: in DC-SYNC, SYNC0 starts on the master's frame period."""
        if self.mode is not SyncMode.DC_SYNC or self.start_refusal() is not None:
            return
        period = self.frame_period_us
        assert period is not None and self.last_frame_us is not None
        self.running, self.cycle_us = True, period
        self.next_sync0_us = self.last_frame_us + period
        while self.next_sync0_us <= now_us:
            self.next_sync0_us += period
        self.arrivals, self.sm_missed, self.without_sync0, self.sync0_seen = [], 0, 0, True
        return None

    def stop(self) -> None:
        self.running = False
        self.arrivals, self.sm_missed, self.without_sync0, self.sync0_seen = [], 0, 0, True

    # ---- the local cycles -------------------------------------------------------------------
    def cycles_until(self, now_us: int) -> list[tuple[int, bool]]:
        """Local cycles in (last call, now]: (time, an SM2 event taken at this SYNC0).

        FREE-RUN (or DC-SYNC not started): every 500 us, never an event (the SM2 event was
        handled when the frame came). DC-SYNC: one per SYNC0, none while SYNC0 is lost.
        """
        out: list[tuple[int, bool]] = []
        if not self.running:
            while self.next_free_us <= now_us:
                out.append((self.next_free_us, False))
                self.next_free_us += FREE_RUN_CYCLE_US
            return out
        while self.next_sync0_us <= now_us:
            t = self.next_sync0_us
            self.next_sync0_us += self.cycle_us
            deadline = t - CALC_COPY_NS // NS_PER_US
            taken = [a for a in self.arrivals if a <= deadline]
            self.arrivals = [a for a in self.arrivals if a > deadline]
            if self.sync0_lost:
                continue  # no SYNC0: the frames that came are overwritten by the next ones
            self.sync0_seen = True
            self.sm_missed = 0 if taken else self.sm_missed + 1
            out.append((t, bool(taken)))
        return out

    def restart_free_run(self, now_us: int) -> None:
        self.next_free_us = now_us + FREE_RUN_CYCLE_US
