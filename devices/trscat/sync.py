"""DC-SYNC and FREE-RUN: when the local cycle runs, SM events, SYNC0, sync errors.

Seed 001 §9.1.1 (DC-SYNC on SYNC0, 1:1 with the master cycle, ESC 0x980 = 0x0300; FREE-RUN,
fixed 500 us local cycle, 0x980 = 0x0000; the SM2 frame must not invade the calc+copy time),
§9.3.1 (0x1C32 / 0x1C33 values) and §9.3.7 (0x10F1:2, limit 3 consecutive sync errors).

Model (docs/trscat.md): the mode is the ESC's Sync Control register as the master wrote it
(§9.1.1 "Il modo di sincronizzazione può essere cambiato mediante il Sync Control Register del
ESC (registri 0x980 e 0x981)"): at PREOP -> SAFEOP the word 0x0980 = 0x0300 (0x0981 = 0x03,
cyclic operation + SYNC0) is DC-SYNC, 0x0000 FREE-RUN, anything else refused; 0x1C32:1 /
0x1C33:1 then report it. A master frame is one SM2 event. In DC-SYNC the SYNC0 pulses come
from the ESC's DC registers the master writes (0x0981 activation, 0x09A0 SYNC0 cycle, 0x0990
start time; §9.2 IP "il master inizializza il DC clock sync"): they run from PREOP -> SAFEOP
on, one per configured cycle, however irregularly the frames come. At every SYNC0 the frames
that arrived at least the calc+copy time (100 us) earlier are taken; none is an "SM event
missed" and the counter 0x1C32:11 counts them consecutively (a good event resets it). At the
limit of 0x10F1:2 the sync error 0x1C32:32 is TRUE. Frames that arrive while SYNC0 is lost
count the other way round (SM events without SYNC0); at the same limit that is a fatal sync
error.
"""

from __future__ import annotations

import enum
import random
from collections.abc import Sequence
from dataclasses import dataclass, field

from devices.ethercat import sync_error_reached

FREE_RUN_CYCLE_US = 500  # §9.1.1 "tempo di ciclo locale fisso pari a 500 us"
MIN_CYCLE_NS = 500_000  # §9.3.1 0x1C32:5 / 0x1C33:5
CALC_COPY_NS = 100_000  # §9.3.1 0x1C32:6 / 0x1C33:6
DELAY_NS = 150_000  # §9.3.1 0x1C32:9 / 0x1C33:9
SYNC_MODES_SUPPORTED = 0x0005  # §9.3.1 0x1C32:4: FREE-RUN and DC-SYNC only
SYNC_ERROR_LIMIT = 3  # §9.3.7 0x10F1:2
NS_PER_US = 1_000
CALC_COPY_US = CALC_COPY_NS // NS_PER_US
# ESC register 0x0981 (DC activation, ETG.1000.4): bit 0 cyclic operation, bit 1 SYNC0, bit 2
# SYNC1. It is the high byte of the 16-bit Sync Control word 0x0980 the seed names (§9.1.1);
# the low byte, 0x0980 (cyclic unit control), is not modelled: 0, as SOEM and TwinCAT write it.
DC_CYCLIC, DC_SYNC0 = 0x01, 0x02
SYNC0_ACTIVE = DC_CYCLIC | DC_SYNC0


class SyncMode(enum.IntEnum):
    """0x1C32:1 / 0x1C33:1 values (§9.3.1)."""

    FREE_RUN = 0x0000
    DC_SYNC = 0x0002

    @property
    def label(self) -> str:
        return "DC-SYNC" if self is SyncMode.DC_SYNC else "FREE-RUN"


# §9.1.1: "Il registro 0x980 deve assumere valore 0x0300" (DC-SYNC) / "0x0000" (FREE-RUN).
SYNC_CONTROL: dict[SyncMode, int] = {SyncMode.FREE_RUN: 0x0000, SyncMode.DC_SYNC: 0x0300}
MODE_BY_SYNC_CONTROL: dict[int, SyncMode] = {word: mode for mode, word in SYNC_CONTROL.items()}
MODE_BY_NAME: dict[str, SyncMode] = {"dc": SyncMode.DC_SYNC, "dc-sync": SyncMode.DC_SYNC,
                                     "free_run": SyncMode.FREE_RUN,
                                     "free-run": SyncMode.FREE_RUN}


class DcRefusal(enum.Enum):
    """Why PREOP -> SAFEOP refuses the sync configuration (transitions.py gives the codes)."""

    SYNC_CONTROL = "sync_control"  # 0x0980 neither 0x0300 nor 0x0000
    MODE_MISMATCH = "mode_mismatch"  # 0x1C32:1 written by the master, 0x0980 says otherwise
    NO_CYCLE = "no_cycle"  # SYNC0 activated, 0x09A0 = 0
    CYCLE_TOO_SMALL = "cycle_too_small"  # 0x09A0 below 0x1C32:5


class SyncState(enum.Enum):
    """StateChanged machine "sync"."""

    FREE_RUN = "free_run"  # FREE-RUN mode, or DC mode before the master started SYNC0
    DC_RUNNING = "dc_running"
    SYNC_ERROR = "sync_error"  # SM events missed up to the limit
    SYNC0_LOST = "sync0_lost"  # SM events without SYNC0 up to the limit (fatal sync error)


@dataclass
class SyncUnit:
    mode: SyncMode = SyncMode.DC_SYNC  # 0x1C32:1: DC-SYNC "quella di default" until a PS
    requested: SyncMode | None = None  # 0x1C32:1 / 0x1C33:1 as written by the master
    taken: SyncMode = SyncMode.DC_SYNC  # the mode the last PS took (the default before one)
    running: bool = False  # DC-SYNC started at PREOP -> SAFEOP (SAFEOP, OP)
    # The master's DC registers (0 at power-up, as the ESC's): 0x0981, 0x09A0, 0x0990.
    dc_activation: int = 0
    dc_cycle_ns: int = 0
    dc_start_ns: int = 0  # the wire's DC system time: kept and shown, not a simulated time
    next_sync0_us: int = 0
    next_free_us: int = 0  # next FREE-RUN local cycle
    arrivals: list[int] = field(default_factory=list)  # SM2 frames waiting for a SYNC0
    sm_missed: int = 0  # 0x1C32:11 / 0x1C33:11
    without_sync0: int = 0  # SM events since the last SYNC0
    sync0_seen: bool = True
    last_frame_us: int | None = None
    # Injected faults.
    drop_frames: int = 0  # the next N frames never reach SM2 (lost / CRC error)
    sync0_lost: bool = False  # the SYNC0 pulses stop
    jitter_us: int = 0  # each frame arrives up to this much late

    def __post_init__(self) -> None:
        self.period_us = self.cycle_us  # cycle_us, kept: configure() alone changes it

    # ---- state ------------------------------------------------------------------------------
    @property
    def sync0_configured(self) -> bool:
        """0x0981 has cyclic operation and SYNC0 on, with a SYNC0 cycle in 0x09A0."""
        return self.dc_activation & SYNC0_ACTIVE == SYNC0_ACTIVE and self.dc_cycle_ns > 0

    @property
    def sync_control(self) -> int:
        """The 16-bit Sync Control word 0x0980 (§9.1.1): 0x0981 as the master wrote it, high."""
        return self.dc_activation << 8

    @property
    def register_mode(self) -> SyncMode | None:
        """The mode 0x0980 selects, None for a word that is neither (§9.1.1)."""
        return MODE_BY_SYNC_CONTROL.get(self.sync_control)

    @property
    def cycle_us(self) -> int:
        """The SYNC0 cycle on the simulated microsecond clock (0 without one)."""
        return _cycle_us(self.dc_cycle_ns) if self.sync0_configured else 0

    @property
    def sync_error(self) -> bool:
        """0x1C32:32 / 0x1C33:32."""
        return self.running and sync_error_reached(self.sm_missed, SYNC_ERROR_LIMIT)

    @property
    def fatal(self) -> bool:
        return self.running and sync_error_reached(self.without_sync0, SYNC_ERROR_LIMIT)

    @property
    def state(self) -> SyncState:
        # ``fatal`` and ``sync_error`` (sync_error_reached) written out: read twice per step.
        if not self.running:
            return SyncState.FREE_RUN
        if self.without_sync0 >= SYNC_ERROR_LIMIT:
            return SyncState.SYNC0_LOST
        return SyncState.SYNC_ERROR if self.sm_missed >= SYNC_ERROR_LIMIT else \
            SyncState.DC_RUNNING

    @property
    def cycle_ns(self) -> int:
        """0x1C32:2 / 0x1C33:2: the local cycle in ns (0 before DC-SYNC is started)."""
        if self.mode is SyncMode.FREE_RUN:
            return FREE_RUN_CYCLE_US * NS_PER_US
        return self.dc_cycle_ns if self.running and self.sync0_configured else 0

    # ---- the master's side ------------------------------------------------------------------
    def configure(self, activation: int, sync0_cycle_ns: int, start_time_ns: int,
                  now_us: int) -> None:
        """The master wrote the DC registers. While DC-SYNC runs, SYNC0 follows at once: off
        without activation (SOEM writes 0x0981 = 0 before it reprograms), else the new cycle."""
        self.dc_activation = int(activation) & 0xFF
        self.dc_cycle_ns = int(sync0_cycle_ns) & 0xFFFFFFFF
        self.dc_start_ns = int(start_time_ns) & 0xFFFFFFFFFFFFFFFF
        self.period_us = self.cycle_us
        if self.running and self.sync0_configured:
            self._first_sync0(now_us)

    def _first_sync0(self, now_us: int) -> None:
        """SYNC0's phase: the wire's start time is on the DC system clock, which the simulated
        clock does not share, so the pulses keep the frames' phase: one cycle after the last
        frame (a master sending at the start of its cycle, SYNC0 shift 0; docs/trscat.md)."""
        period = self.cycle_us
        anchor = self.last_frame_us if self.last_frame_us is not None else now_us
        self.next_sync0_us = anchor + period
        if self.next_sync0_us <= now_us:
            self.next_sync0_us += (now_us - self.next_sync0_us) // period * period + period

    def frame(self, now_us: int, rng: random.Random) -> bool:
        """A frame passed; True when it is an SM2 event now (FREE-RUN / not running).

        In DC-SYNC while running the event is taken at the next SYNC0 instead (``arrivals``).
        """
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

    def start_refusal(self) -> DcRefusal | None:
        """Why PREOP -> SAFEOP cannot take the mode of the Sync Control register, or None. A
        mode the master wrote to 0x1C32:1 must be the register's (ETG.1020: the ETG slave stack
        answers a disagreement with 0x0030 too)."""
        mode = self.register_mode
        if mode is None:
            return DcRefusal.SYNC_CONTROL
        if self.requested is not None and self.requested is not mode:
            return DcRefusal.MODE_MISMATCH
        if mode is SyncMode.DC_SYNC:
            if self.dc_cycle_ns == 0:
                return DcRefusal.NO_CYCLE
            if self.dc_cycle_ns < MIN_CYCLE_NS:
                return DcRefusal.CYCLE_TOO_SMALL
        return None

    def start(self, now_us: int) -> None:
        """PREOP -> SAFEOP accepted: the register's mode; in DC-SYNC, SYNC0 runs on the
        configured cycle."""
        mode = self.register_mode
        if mode is None or self.start_refusal() is not None:
            return
        self.mode = self.taken = mode
        if mode is not SyncMode.DC_SYNC:
            return
        self.running = True
        self._first_sync0(now_us)
        self.arrivals, self.sm_missed, self.without_sync0, self.sync0_seen = [], 0, 0, True

    def request(self, mode: SyncMode) -> None:
        """0x1C32:1 / 0x1C33:1 written in PRE-OP: reported at once, checked at the next PS."""
        self.mode = self.requested = mode

    def forget_request(self) -> None:
        """INIT: the master's written mode goes; 0x1C32:1 reports the mode last taken again."""
        self.requested = None
        self.mode = self.taken

    def stop(self) -> None:
        self.running = False
        self.arrivals, self.sm_missed, self.without_sync0, self.sync0_seen = [], 0, 0, True

    # ---- the local cycles -------------------------------------------------------------------
    def cycles_until(self, now_us: int) -> Sequence[tuple[int, bool]]:
        """Local cycles in (last call, now]: (time, an SM2 event taken at this SYNC0).

        FREE-RUN (or DC-SYNC not started): every 500 us, never an event (the SM2 event was
        handled when the frame came). DC-SYNC: one per SYNC0, none while SYNC0 is lost or the
        master switched it off (0x0981).
        """
        if not self.running:
            out: list[tuple[int, bool]] = []
            while self.next_free_us <= now_us:
                out.append((self.next_free_us, False))
                self.next_free_us += FREE_RUN_CYCLE_US
            return out
        t = self.next_sync0_us
        period = self.period_us  # 0: SYNC0 not configured (0x0981 / 0x09A0)
        if t > now_us or not period:
            return ()
        out = []
        while t <= now_us:
            self.next_sync0_us = t + period
            deadline = t - CALC_COPY_US
            arrivals = self.arrivals
            if not arrivals:
                taken = False
            elif max(arrivals) <= deadline:  # the usual case: every frame in time
                taken, self.arrivals = True, []
            else:
                taken = any(a <= deadline for a in arrivals)
                self.arrivals = [a for a in arrivals if a > deadline]
            if not self.sync0_lost:  # no SYNC0: the frames that came are overwritten
                self.sync0_seen = True
                self.sm_missed = 0 if taken else self.sm_missed + 1
                out.append((t, taken))
            t = self.next_sync0_us
        return out

    def take_one_sync0(self, now_us: int) -> int | None:
        """The steady case of :meth:`cycles_until`, without building its list: exactly one
        SYNC0 in (last call, now], SYNC0 not lost and the one frame waiting for it in time.
        Then the same as ``cycles_until`` (that SYNC0 takes the frame) and its time; else
        None and nothing changed (``cycles_until`` is for the rest)."""
        t = self.next_sync0_us
        arrivals = self.arrivals
        if not (t <= now_us < t + self.period_us and self.running and len(arrivals) == 1
                and arrivals[0] <= t - CALC_COPY_US) or self.sync0_lost:
            return None
        self.next_sync0_us = t + self.period_us
        self.arrivals = []
        self.sync0_seen = True
        self.sm_missed = 0
        return t

    def restart_free_run(self, now_us: int) -> None:
        self.next_free_us = now_us + FREE_RUN_CYCLE_US


def _cycle_us(cycle_ns: int) -> int:
    return max(1, round(cycle_ns / NS_PER_US))
