"""The EtherCAT state machine's state holder, shared by every slave model: AL status and code.

The state, the requested state, why the error flag is set and the AL status code, and the
events they emit. What a slave allows (which checks a transition runs) is decided in its own
package, which also keeps its own ``ErrorKind`` enum: it drives that device's ERR LED
(ETG.1300). Requests outside the ETG.1000.6 transition table
(devices.ethercat.ALLOWED_TRANSITIONS) answer the seed 000 §7.7 codes below.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import ClassVar, Generic, TypeVar

from devices.ethercat import AL_STATE_MASK, AL_STATUS_ERROR_FLAG, ALLOWED_TRANSITIONS, AlState
from devices.events import AlStatusChanged, EsmLogLine, Event, StateChanged, fmt_hex
from devices.od import AbortCode, ObjectDictionary, SdoAbort, download_value, encode

# §7.7 codes for requests the ESM itself refuses.
NO_ERROR = 0x0000
INVALID_STATE_CHANGE = 0x0011  # "Invalid requested state change"
UNKNOWN_REQUESTED_STATE = 0x0012  # "Unknown requested state" (AL control bits 0-3 no state)
BOOTSTRAP_NOT_SUPPORTED = 0x0013  # "Bootstrap not supported" (INIT -> BOOT, no BOOT state)

# Order of the states a slave steps up through (BOOT is outside it).
RANK: dict[AlState, int] = {AlState.INIT: 0, AlState.PREOP: 1, AlState.SAFEOP: 2,
                            AlState.OP: 3}
# ETG.1000.6: CoE (SDO, SDO information, emergencies) runs from PREOP on. INIT runs no
# mailbox; BOOT only the bootstrap mailbox, which carries the firmware download (FoE).
NO_COE_STATES = frozenset({AlState.INIT, AlState.BOOT})

K = TypeVar("K", bound=enum.Enum)


def request_refusal(current: AlState, target: AlState,
                    transitions: frozenset[tuple[AlState, AlState]] = ALLOWED_TRANSITIONS,
                    *, has_boot: bool = False) -> int | None:
    """The AL status code for a request the transition table forbids, or None when allowed.

    BOOT is entered from INIT only (ETG.1000.6), so a BOOT request from PREOP, SAFEOP or OP is
    an invalid transition (0x0011) on every slave; 0x0013 "Bootstrap not supported" answers
    INIT -> BOOT on a slave without a BOOT state (``has_boot`` False), as Beckhoff SSC
    ``AL_ControlInd`` (INIT_2_BOOT -> BOOTNOTSUPP, PREOP / SAFEOP / OP_2_BOOT -> INVALIDALCONTROL)
    and SOES ``ESC_state`` answer. A slave with BOOT finds it in its own ``transitions``.
    """
    if target is AlState.BOOT and not has_boot:
        return BOOTSTRAP_NOT_SUPPORTED if current is AlState.INIT else INVALID_STATE_CHANGE
    if target is current or (current, target) in transitions:
        return None
    return INVALID_STATE_CHANGE


def first_refusal(slave: object,
                  checks: Mapping[tuple[AlState, AlState], tuple[str, ...]],
                  current: AlState, target: AlState) -> int | None:
    """The AL status code of the first check of ``current`` -> ``target`` that refuses it, None
    when all pass. ``checks`` is a slave's table of them, in order, each the name of a method
    of ``slave`` returning None or its refusing code (the TRS-CAT's and the drive's CoE side's
    ``TRANSITION_CHECKS``)."""
    for name in checks.get((current, target), ()):
        code = getattr(slave, name)()
        if code is not None:
            return code
    return None


# Slots: every step reads a slave's state and error flag (the master, the slave's own step).
# A field's default left in the class (an enum member: a mutable type's instance) keeps
# CPython 3.11 from specialising those reads; slots take the defaults out of the class.
# Each subclass is a slotted dataclass too, or its redeclared default would be back.
@dataclass(slots=True)
class Esm(Generic[K]):
    """One slave's ESM. A subclass names its ``ErrorKind`` enum in ``kinds`` (members NONE and
    REFUSED at least) and redeclares ``error`` with that enum's NONE as the default.

    Every move to INIT from another state, whatever the path (a master's request, a fall, a
    restart), calls ``stop_mailbox``: the mailbox runs from PREOP only (ETG.1000.6), and a
    slave stack stops its mailbox handler on the way to INIT, disabling SM0 / SM1 and freeing
    the send queue (Beckhoff SSC MBX_StopMailboxHandler), so the emergencies the master has not
    read yet are lost. The slave model passes what drops its queue; its histories (0x1003,
    0x10F3, ...) are objects and stay."""

    emit: Callable[[Event], None]
    device: str
    state: AlState = AlState.INIT
    requested: AlState = AlState.INIT
    error: K = None  # type: ignore[assignment]  # each subclass: its ErrorKind.NONE
    code: int = NO_ERROR
    stop_mailbox: Callable[[], None] | None = None
    # The slave's own way out of OP (outputs to their safe state, a drive stopped: what its
    # OP -> SAFEOP does), run when a refusal in OP takes it to SAFEOP (:meth:`refuse`).
    leave_op: Callable[[], None] | None = None
    # AL control values (bit n for value n) already logged as ignored in this error episode:
    # a master repeating a request every cycle gets one line, not one per cycle.
    ignored: int = 0

    kinds: ClassVar[type[enum.Enum]]
    machine: ClassVar[str] = ""  # StateChanged.machine; empty for the device's main machine

    @property
    def error_flag(self) -> bool:
        return self.error is not self.kinds.NONE

    @property
    def register(self) -> int:
        """AL status register 0x0130: the state, plus 0x10 while the error flag is set."""
        return int(self.state) | (AL_STATUS_ERROR_FLAG if self.error_flag else 0)

    def at_least(self, state: AlState) -> bool:
        return RANK[self.state] >= RANK[state]

    def take_request(self, target: AlState, ack: bool, t_us: int) -> bool:
        """An AL control write (0x0120) reaches the slave: bits 0-3 ``target``, bit 4 ``ack``
        ("Error Ind Ack", ETG.1000.6; Beckhoff SSC AL_ControlInd, SOES alike). False: the
        request is ignored and the slave must not process it.

        While the error flag is set a request without the acknowledge is ignored, state, flag
        and code as they are, except one for INIT (SSC: "Error Acknowledge with 0xX1 is
        allowed"); the slave logs why (:meth:`_log_ignored`). With it the flag is cleared and
        the request processed; the code clears with the answer (:meth:`settle_request`), so a
        request refused again keeps its code with no 0x0000 in between: the master reads
        0x0130 / 0x0134 after the whole write."""
        if not self.error_flag:
            return True
        if ack:
            self.error = self.kinds.NONE  # type: ignore[assignment]
            return True
        if target is AlState.INIT:
            return True
        self._log_ignored(int(target), f"'{target.label}'", t_us)
        return False

    def request_unknown(self, value: int, ack: bool, t_us: int) -> None:
        """An AL control write whose bits 0-3 (``value``) name no state: refused with 0x0012,
        "Unknown requested state", the state kept. Over the error flag it is ignored without
        the acknowledge like any request but INIT (SSC AL_ControlInd, SOES ESC_state), so a
        trainee still reads the code of the original cause."""
        if self.error_flag and not ack:
            self._log_ignored(value, "unknown", t_us)
            return
        self.refuse(UNKNOWN_REQUESTED_STATE, t_us)

    def _log_ignored(self, value: int, name: str, t_us: int) -> None:
        """One log line per error episode and AL control value: the request went nowhere and
        a trainee must see why (the slave answers nothing else)."""
        bit = 1 << (value & AL_STATE_MASK)
        if self.ignored & bit:
            return
        self.ignored |= bit
        self.emit(EsmLogLine(t_us, self.device, text=(
            f"Requested state 0x{value:02X} ({name}) ignored: error indication not acknowledged "
            f"(AL control bit 4 'Error Ind Ack' not set); AL status 0x{self.register:02X}, "
            f"AL status code {fmt_hex(self.code, 4)} kept")))

    def settle_request(self, t_us: int) -> None:
        """The end of a processed request: a flag the request left clear (an acknowledge the
        transition did not raise again) leaves no AL status code behind (SSC SetALStatus)."""
        if not self.error_flag:
            self._set_code(NO_ERROR, t_us)

    def accept(self, target: AlState, t_us: int) -> None:
        """A requested transition done: the error flag is acknowledged, the code cleared."""
        self.requested = target
        self.error = self.kinds.NONE  # type: ignore[assignment]
        self._set_code(NO_ERROR, t_us)
        self._move(target, t_us)

    def refuse(self, code: int, t_us: int, kind: K | None = None) -> None:
        """A requested transition refused: stay, raise the error flag, report why.

        In OP the slave does not stay: it goes to SAFEOP + error through its own way out of
        OP (``leave_op``, outputs to their safe state), as ETG.1000.6 has it (Beckhoff SSC
        ``AL_ControlInd``: a failed transition from OP goes to SAFEOP with the error flag;
        SOES ``ESC_state``: OP -> BOOT and an unknown state stop the outputs, SAFEOP|ERR).
        ``kind`` (default REFUSED) says which ERR LED pattern tells why."""
        self.error = self.kinds.REFUSED if kind is None else kind  # type: ignore[assignment]
        self.ignored = 0  # a new error episode
        leaving = self.state is AlState.OP
        if leaving and self.leave_op is not None:
            self.leave_op()
        self._set_code(code, t_us)
        if leaving:
            self._move(AlState.SAFEOP, t_us)

    def fall_to(self, target: AlState, kind: K, code: int, t_us: int) -> None:
        """Leave the state on the slave's own initiative: error flag (``kind``) + code."""
        self.error = kind
        self.ignored = 0  # a new error episode
        self._set_code(code, t_us)
        self._move(target, t_us)

    def reset(self, t_us: int) -> None:
        """Back to INIT without an error (power loss or power-up, restart)."""
        self.requested = AlState.INIT
        self.error = self.kinds.NONE  # type: ignore[assignment]
        self._set_code(NO_ERROR, t_us)
        self._move(AlState.INIT, t_us)

    def _set_code(self, code: int, t_us: int) -> None:
        if code != self.code:
            self.code = code
            self.emit(AlStatusChanged(t_us, self.device, code=code))

    def _move(self, target: AlState, t_us: int) -> None:
        if target is not self.state:
            before, self.state = self.state, target
            self.emit(StateChanged(t_us, self.device, from_state=before.label,
                                   to_state=target.label, machine=self.machine))
            if target is AlState.INIT and self.stop_mailbox is not None:
                self.stop_mailbox()


class AlStatusView:
    """What a master reads of a slave's ESM: the state, the AL status register (0x0130) and
    the AL status code (0x0134). Every EtherCAT slave model holds its ``esm`` and mixes this
    in (devices.master.Slave)."""

    esm: Esm

    @property
    def al_state(self) -> AlState:
        return self.esm.state

    @property
    def al_status(self) -> int:
        return self.esm.register

    @property
    def al_status_code(self) -> int:
        return self.esm.code


class CoeMailbox:
    """The CoE SDO service of a slave's mailbox, as a master reaches it (devices.master.Slave):
    from PREOP on, with the slave reachable and its dictionary built; otherwise the mailbox
    does not answer and the master's SDO times out (0x05040000). Values travel as the bytes
    of the entry's type. A slave whose writes or reads must go through its own path (side
    effects of a read, say) overrides :meth:`mailbox_write` / :meth:`mailbox_read`."""

    od: ObjectDictionary | None
    esm: Esm

    def sdo_download(self, index: int, sub: int, data: bytes) -> None:
        od = self._mailbox_od(index, sub)
        self.mailbox_write(index, sub, download_value(od.entry(index, sub), data))

    def sdo_upload(self, index: int, sub: int) -> bytes:
        od = self._mailbox_od(index, sub)
        return encode(od.entry(index, sub).dtype, self.mailbox_read(index, sub))

    def mailbox_read(self, index: int, sub: int) -> object:
        assert self.od is not None  # _mailbox_od checked it
        return self.od.read(index, sub)

    def mailbox_write(self, index: int, sub: int, value: object) -> None:
        assert self.od is not None  # _mailbox_od checked it
        self.od.write(index, sub, value)

    def mailbox_runs(self) -> bool:
        """Whether the controller behind the ESC serves the mailbox; a slave whose CoE runs on
        a controller that can fail while the ESC still passes frames overrides this."""
        return True

    def bootstrap_mailbox(self) -> bool:
        """Whether only the bootstrap mailbox runs (BOOT, ETG.1000.6): it answers a CoE
        request with a mailbox error instead of serving it (docs/cpx-e-ec.md choice 47)."""
        return self.esm.state is AlState.BOOT

    def _mailbox_od(self, index: int, sub: int) -> ObjectDictionary:
        if not self.reachable() or not self.mailbox_runs() or self.od is None or \
                self.esm.state in NO_COE_STATES:  # type: ignore[attr-defined]
            raise SdoAbort(AbortCode.SDO_TIMEOUT, index, sub)
        return self.od
