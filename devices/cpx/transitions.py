"""The CPX-E-EC's answers to AL control requests: which transition checks what.

INIT -> PREOP: an application must run (not the bootloader of Tab. 6, no booting error of
Tab. 12: AL status code 0x0014) and the mailbox sync managers SM0 / SM1 must be valid
(0x0016). PREOP -> SAFEOP: the process-data sync managers SM2 / SM3 (0x001D / 0x001E whatever
is wrong, the Text-IDs 0x0011 ... 0x0013 of Tab. 17 in the history), the 64-byte address space
(§2.2), the bus-cycle measurement (0x000F, a warning) and the ident check, 0xF030 against
0xF050 (0x0070 with Text-ID 0x3800; skipped with 0x3801 when the PLC did not write 0xF030).
SAFEOP -> OP: process data arrive (Sync Manager watchdog, 0x001B) and the sync events are
not missed (0x001A). Downward requests, INIT and BOOT are always taken.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices import mdp
from devices import sync_managers as smc
from devices.cpx.catalog import MAX_INPUT_BYTES
from devices.cpx.codes import TEXT_BUS_CYCLE, TEXT_IDENT_FAILED, TEXT_IDENT_SKIPPED, DiagType
from devices.cpx.esm import (
    IDENT_MISMATCH,
    INVALID_INPUT_CONFIG,
    INVALID_INPUT_MAPPING,
    INVALID_OUTPUT_CONFIG,
    NO_VALID_FIRMWARE,
    SM_WATCHDOG,
    SYNC_ERROR,
    ErrorKind,
    request_refusal,
)
from devices.cpx.faults import SM_FAULT_TEXT
from devices.ethercat import AlState
from devices.od import DataType

if TYPE_CHECKING:
    from devices.cpx.device import CpxEEc

WATCHDOG_US = 100_000  # Sync Manager watchdog, the ESC default (ETG.1000)
# A sync manager configuration error: Text-ID -> the value the master wrote (FieldRig: an
# odd start address, a size one byte too long, a disabled sync manager).
SM_BAD_VALUE = {0x0011: 0x1001, 0x0012: 0x0081, 0x0013: 0x0000}


class TransitionsMixin:
    """``request_state`` of :class:`~devices.cpx.device.CpxEEc` and its checks."""

    def request_state(self: CpxEEc, target: AlState, ack: bool = False) -> None:
        """AL control write; the answer is in ``al_status`` / ``al_status_code``."""
        self.touch()  # the next step runs in full (devices/cpx/stillness.py)
        if not self.reachable() or self.has_fault("ac_failure"):
            return  # the ESC takes the request, but no application answers it (Tab. 12)
        now, esm = self.now_us, self.esm
        if not esm.take_request(target, ack, now):  # bit 4 "Error Ind Ack" (ETG.1000.6)
            return
        esm.requested = target
        refusal = request_refusal(esm.state, target)
        if target is esm.state:
            esm.accept(target, now)
        elif refusal is not None:
            esm.refuse(refusal, now)
        elif target in (AlState.INIT, AlState.BOOT) or _down(esm.state, target):
            esm.accept(target, now)
        else:
            refused = self._transition_check(esm.state, target)
            if refused is None:
                esm.accept(target, now)
            elif isinstance(refused, tuple):
                esm.refuse(refused[0], now, refused[1])
            else:
                esm.refuse(refused, now)
        esm.settle_request(now)
        self._refresh_leds()

    def _transition_check(self: CpxEEc, current: AlState,
                          target: AlState) -> int | tuple[int, ErrorKind] | None:
        """The checks of an upward transition: None, or the AL status code (with the error
        kind when it is not an invalid configuration)."""
        if current is AlState.INIT and target is AlState.PREOP:
            if self.boot_failed:  # still the booting error of the start (Tab. 12)
                return NO_VALID_FIRMWARE, ErrorKind.BOOTING
            if not self.application_runs:
                return NO_VALID_FIRMWARE
            return self._sm_check((0, 1))
        if current is AlState.SAFEOP and target is AlState.OP:  # outputs must be valid
            if self.now_us - self.last_pd_us > WATCHDOG_US:
                return SM_WATCHDOG, ErrorKind.WATCHDOG
            if self.sync_error():
                return SYNC_ERROR, ErrorKind.SYNC
            return None
        if current is AlState.PREOP and target is AlState.SAFEOP:
            code = self._sm_check((2, 3))
            if code is not None:
                return code
            if not self.tx_assign.complete():  # a 0x1C13 change left half-way (choice 37)
                return INVALID_INPUT_MAPPING
            if self.space is not None and self.space_error:  # more than 64 bytes (§2.2)
                return INVALID_INPUT_CONFIG if self.space.input_bytes > MAX_INPUT_BYTES \
                    else INVALID_OUTPUT_CONFIG
            if self.has_fault("bus_cycle_time"):
                self._report(TEXT_BUS_CYCLE, DiagType.WARNING)
            return self._ident_check()
        return None

    def _sm_check(self: CpxEEc, sync_managers: tuple[int, ...]) -> int | None:
        found = smc.injected_fault([(f.name, f.sm) for f in self.injected], sync_managers)
        if found is None:
            return None
        sm, fault = found
        text_id = SM_FAULT_TEXT[fault]
        self._report(text_id, DiagType.ERROR,
                     ((DataType.UNSIGNED8, sm), (DataType.UNSIGNED16, SM_BAD_VALUE[text_id])))
        return smc.fault_code(sm, fault)

    def _ident_check(self: CpxEEc) -> int | None:
        """0xF030 (written by the PLC in PREOP) against 0xF050 (Tab. 17 0x3800 / 0x3801)."""
        wrong = self._ident_mismatch()
        if wrong is not None:
            self._report(TEXT_IDENT_FAILED, DiagType.ERROR, ((DataType.UNSIGNED8, wrong),))
            return IDENT_MISMATCH
        if not self.f030_written or self.has_fault("f030_not_written"):
            self._report(TEXT_IDENT_SKIPPED, DiagType.WARNING)
        return None

    def _ident_mismatch(self: CpxEEc) -> int | None:
        """The CPX module number of the first configured module that is not the detected one."""
        injected = [f.module or 0 for f in self.injected if f.name == "module_ident_mismatch"]
        if injected:
            return min(injected)
        if not self.f030_written or self.has_fault("f030_not_written") or self.od is None:
            return None
        count = int(self.od.peek(0xF030, 0))
        configured = [int(self.od.peek(0xF030, sub)) for sub in range(1, count + 1)]
        return mdp.ident_mismatch(configured, [u.mtype.ident for u in self.units])

    def _report(self: CpxEEc, text_id: int, dtype: DiagType,
                params: tuple[tuple[DataType, int], ...] = ()) -> None:
        self.diagnosis.report(text_id, dtype, self.now_us, self._t_ns(), params)


def _down(current: AlState, target: AlState) -> bool:
    order = (AlState.INIT, AlState.PREOP, AlState.SAFEOP, AlState.OP)
    return current in order and target in order and order.index(target) < order.index(current)
