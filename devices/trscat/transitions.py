"""How the TRS-CAT moves through the EtherCAT states (seed 001 §9.2) and leaves OP on an error.

The checks of each transition are listed in devices/trscat/esm.py (``TRANSITION_CHECKS``) and
defined here: SM / DC configuration (the mode is the Sync Control register's, §9.1.1; DC-SYNC
needs a SYNC0 cycle of at least 500 us, §9.3.1),
0xF030 = 0xF050 at PREOP -> SAFEOP (§9.2, §9.3.2), no sync error and valid outputs for OP.
A communication error in OP (ETG.1020: sync error, SM watchdog) sends the device to SAFE-OP
with the error flag; the outputs then follow 0xF700 / 0xF701 / 0xF710 (§9.3.5, §9.3.6).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from typing import TYPE_CHECKING

from devices import mdp
from devices.esm import first_refusal
from devices.ethercat import AlState
from devices.events import StateChanged
from devices.trscat.alarms import FaultKey, TrsBus
from devices.trscat.diagnostics import DiagMessage, check_message
from devices.trscat.esm import (
    CYCLE_TOO_SMALL,
    FATAL_SYNC_ERROR,
    INVALID_DC_SYNC,
    MODULE_IDENT_MISMATCH,
    NO_VALID_OUTPUTS,
    SM_WATCHDOG,
    SYNC_ERROR,
    TRANSITION_CHECKS,
    UNSPECIFIED_ERROR,
    Esm,
    request_refusal,
)
from devices.trscat.outputs import outputs_on_error
from devices.trscat.sync import SYNC_CONTROL, DcRefusal, SyncMode, SyncState, SyncUnit

if TYPE_CHECKING:
    from devices.events import Event
    from devices.trscat.diagnostics import AppFault
    from devices.trscat.io import SlotIo

SM_WATCHDOG_US = 100_000  # ESC default SM watchdog (0x0420 = 1000 x 100 us)
SYNC = "sync"  # StateChanged.machine of the sync unit
_RANK = {AlState.INIT: 0, AlState.PREOP: 1, AlState.SAFEOP: 2, AlState.OP: 3}
# PREOP -> SAFEOP refusals of the sync configuration: AL code and diagnosis text (formatted
# with the register word and the mode the master wrote to 0x1C32:1).
_DC_REFUSAL: dict[DcRefusal, tuple[int, str]] = {
    DcRefusal.SYNC_CONTROL: (INVALID_DC_SYNC, "Sync Control 0x0980 = 0x{word:04X}: neither "
                             "DC-SYNC (0x0300) nor FREE-RUN (0x0000)"),
    DcRefusal.MODE_MISMATCH: (INVALID_DC_SYNC, "0x1C32:1 = {requested} but Sync Control "
                              "0x0980 = 0x{word:04X}"),
    DcRefusal.NO_CYCLE: (INVALID_DC_SYNC, "DC-SYNC: SYNC0 activated without a cycle "
                         "(0x09A0 = 0)"),
    DcRefusal.CYCLE_TOO_SMALL: (CYCLE_TOO_SMALL, "DC-SYNC: cycle time below the 500 us "
                                "minimum (0x1C32:5)"),
}
CHECK_TEXT = {
    SYNC_ERROR: "Synchronization error: SM events missed (0x1C32:11 reached 0x10F1:2)",
    FATAL_SYNC_ERROR: "Fatal sync error: SM events without SYNC0 (0x10F1:2 reached)",
    SM_WATCHDOG: "Sync manager watchdog: no process data from the master",
}


class OutputMode(enum.Enum):
    SAFE = "safe"  # INIT, PRE-OP, SAFE-OP: outputs off (§9.2 "safe-state")
    NORMAL = "normal"  # OP: the outputs of the last SM2 event
    ERROR = "error"  # SAFE-OP after a communication error in OP: 0xF700/0xF701/0xF710


def ident_mismatch(configured: Sequence[int], detected: Sequence[int]) -> int | None:
    """The first slot where 0xF030 and 0xF050 (sub 0 = count) differ (§9.3.2), or None when
    they match. A 0 entry is an unused expansion position, compared as it is."""
    return mdp.ident_mismatch(configured[1:configured[0] + 1], detected[1:detected[0] + 1])


class TransitionsMixin:
    """ESM handling of :class:`~devices.trscat.device.TrsCat`."""

    # Provided by TrsCat (declared for type checkers).
    now_us: int
    esm: Esm
    sync: SyncUnit
    sync_state: SyncState
    bus: TrsBus
    deadlocked: bool
    config_error: int | None
    injected: list[FaultKey]
    f030: list[int]
    f050: list[int]
    rail: list[SlotIo | None]
    error_values: list[int]
    error_modes: list[int]
    sysok_mask: int
    error_out: dict[int, list[int]]
    out_mode: OutputMode
    last_sm_event_us: int | None
    device_id: str

    if TYPE_CHECKING:  # defined by DeviceModel / TrsCat / AlarmsMixin
        def emit(self, event: Event) -> None: ...
        def reachable(self) -> bool: ...
        def report(self, message: DiagMessage, fault: AppFault | None = None,
                   slot: int | None = None) -> None: ...
        def _evaluate_alarms(self) -> None: ...
        def _refresh(self) -> None: ...
        def _touch(self) -> None: ...
        def _apply_output_image(self) -> None: ...

    def request_state(self, target: AlState, ack: bool = False) -> None:
        """AL control write; the answer is in ``al_status`` / ``al_status_code``."""
        if not self.reachable():
            return
        self._touch()
        now, esm = self.now_us, self.esm
        current = esm.state
        if not esm.take_request(target, ack, now):  # bit 4 "Error Ind Ack" (ETG.1000.6)
            return
        esm.requested = target
        refusal = request_refusal(current, target)
        if refusal is not None:
            esm.refuse(refusal, now)
        elif target is current:
            if self.deadlocked and current is AlState.PREOP:
                esm.refuse(UNSPECIFIED_ERROR, now)
            else:
                esm.accept(target, now)
        elif _RANK[target] < _RANK[current]:
            self._leave_to(target)
            esm.accept(target, now)
        elif current is AlState.INIT and self.bus is TrsBus.DETECTING:
            pass  # INIT -> PREOP completes when the power-up detection is over
        else:
            code = first_refusal(self, TRANSITION_CHECKS, current, target)
            if code is not None:
                esm.refuse(code, now)
            else:
                self._enter(target)
        esm.settle_request(now)
        self._refresh()

    # ---- ESM --------------------------------------------------------------------------------
    def check_not_deadlocked(self) -> int | None:
        return UNSPECIFIED_ERROR if self.deadlocked else None

    def check_dc(self) -> int | None:
        """§9.2 PS "verifica la correttezza ... del DC": the Sync Control register (§9.1.1)
        gives the mode; DC-SYNC needs a SYNC0 cycle of at least 0x1C32:5."""
        sync = self.sync
        reason = sync.start_refusal()
        if reason is None:
            return None
        code, text = _DC_REFUSAL[reason]
        if self.esm.code != code:  # one message per episode, not per retry of the master
            # SyncMode is an IntEnum: FREE_RUN (0) is falsy, hence "is None".
            requested = SyncMode.DC_SYNC if sync.requested is None else sync.requested
            text = text.format(word=sync.sync_control,
                               requested=f"0x{int(requested):04X} ({requested.label}, "
                                         f"0x0980 = 0x{SYNC_CONTROL[requested]:04X})")
            self.report(check_message(code, text, self.now_us * 1000))
        return code

    def check_idents(self) -> int | None:
        """§9.2 PS: 0xF030 (configured by the master) must equal 0xF050 (detected)."""
        slot = ident_mismatch(self.f030, self.f050)
        if slot is None and ("CONFIG_ERROR", None) not in self.injected:
            return None
        if slot is not None:
            self.config_error = slot
            self._evaluate_alarms()
        return MODULE_IDENT_MISMATCH

    def check_sync(self) -> int | None:
        if self.sync.fatal:
            return FATAL_SYNC_ERROR
        return SYNC_ERROR if self.sync.sync_error else None

    def check_outputs(self) -> int | None:
        """SO: the master must have sent outputs within the SM watchdog time."""
        last = self.last_sm_event_us
        return NO_VALID_OUTPUTS if last is None or self.now_us - last > SM_WATCHDOG_US else None

    def _enter(self, target: AlState) -> None:
        """An accepted upward transition."""
        now = self.now_us
        if target is AlState.SAFEOP:
            self.config_error = None
            self.sync.start(now)
            self.out_mode = OutputMode.SAFE
        if target is AlState.OP:
            self.out_mode = OutputMode.NORMAL
        self.esm.accept(target, now)
        self._evaluate_alarms()

    def _leave_to(self, target: AlState) -> None:
        """Side effects of going down to ``target`` (the caller moves the ESM)."""
        self.out_mode = OutputMode.SAFE
        if target in (AlState.PREOP, AlState.INIT):
            self.sync.stop()
            self.sync.restart_free_run(self.now_us)
        if target is AlState.INIT:  # the master's PRE-OP settings go; it writes them again
            self.sync.forget_request()
        self._apply_output_image()  # §9.2 "safe-state" from now, SYNC0 or not

    def _leave_op(self) -> None:
        """A request refused in OP takes the device to SAFE-OP + error (devices/esm.py
        ``Esm.leave_op``). It is the master's request, no ETG.1020 communication error: the
        outputs take the safe state of a requested SAFE-OP (§9.2), not §9.3.5's values."""
        self._touch()
        self._leave_to(AlState.SAFEOP)

    def _fall_on_comm_error(self, code: int) -> None:
        """ETG.1020: a communication error in OP -> SAFE-OP + error; outputs per §9.3.5.

        The value held ("l'ultimo valore noto") is the master's last, as the last SM2 event
        delivered it: what a working module drives in OP, and what one not driving now (a
        TRS-AN-E without its ±12 V, §9.3.7) drives once it works again."""
        for slot, io in enumerate(self.rail):
            if io is not None:
                self.error_out[slot] = outputs_on_error(
                    io.kind, io.latched, self.error_modes[slot], self.error_values[slot],
                    self.sysok_mask if slot == 0 else 0)
        self.out_mode = OutputMode.ERROR
        self._apply_output_image()  # §9.3.6 from now: a fatal sync error has no SYNC0 left
        if code == SM_WATCHDOG:  # the sync errors made their message when they began
            self.report(check_message(code, CHECK_TEXT[code], self.now_us * 1000))
        self.esm.fall(AlState.SAFEOP, code, self.now_us)

    # ---- sync -------------------------------------------------------------------------------
    def _sync_event(self) -> SyncState:
        """StateChanged "sync" on a change; a diagnosis message on entering an error. Returns
        the state."""
        state = self.sync.state
        if state is self.sync_state:
            return state
        self.emit(StateChanged(self.now_us, self.device_id, from_state=self.sync_state.value,
                               to_state=state.value, machine=SYNC))
        self.sync_state = state
        code = {SyncState.SYNC0_LOST: FATAL_SYNC_ERROR, SyncState.SYNC_ERROR: SYNC_ERROR}.get(
            state)
        if code is not None:
            self.report(check_message(code, CHECK_TEXT[code], self.now_us * 1000))
        return state

    def _check_sync(self) -> None:
        state = self._sync_event()
        # check_sync answers a code exactly in these two states (fatal / sync_error).
        if self.esm.state is AlState.OP and state in _SYNC_FAULTS:
            code = self.check_sync()
            if code is not None:
                self._fall_on_comm_error(code)


_SYNC_FAULTS = (SyncState.SYNC_ERROR, SyncState.SYNC0_LOST)
