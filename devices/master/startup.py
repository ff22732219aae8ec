"""Start-up and supervision of each slave's ESM by the master (seed 003; seed 000 §7.7).

Per slave: found on the line -> its state is read; each step the master requests the next
state toward its target (INIT -> PREOP -> SAFEOP -> OP), first sending the CoE init commands of
that transition from the network description (and, before PREOP -> SAFEOP, checking the
identity 0x1018 against it); the answer is checked ``check_delay_us`` later. A refused
transition leaves the slave where it is with its own AL status code (the model decides), logged
as TwinCAT does (§7.7), and is retried every ``retry_interval_us``. A slave that leaves its
state on its own is an "abnormal state change" and is brought back.
"""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING

from devices.ethercat import AL_STATUS_ERROR_FLAG, AlState, parse_emergency_frame
from devices.events import CoeEmergency, CommError
from devices.master.links import RANK, TRANSITION_NAME, SlaveLink, next_state
from devices.od import ABORT_TEXT, AbortCode, SdoAbort

if TYPE_CHECKING:
    from devices.events import Event

IDENTITY_SUBS = (1, 2, 3)  # 0x1018: vendor, product code, revision
DC_SYNC0_ON = 0x03  # ESC 0x0981: cyclic operation + SYNC0, as SOEM's dcsync0 writes it
DC_START_DELAY_NS = 100_000_000  # first SYNC0 100 ms after the registers are written (SOEM)


class StartupMixin:
    """ESM handling of :class:`~devices.master.master.EtherCatMaster`."""

    now_us: int
    target: AlState
    check_delay_us: int
    state_timeout_us: int
    retry_interval_us: int
    cycle_us: int
    dc_hold: bool

    if TYPE_CHECKING:
        def _log(self, link: SlaveLink | None, message: str, **params: object) -> None: ...
        def _event(self, event: Event) -> None: ...
        def _watch(self, link: SlaveLink, resync: bool = True) -> None: ...

    def _target_of(self, link: SlaveLink) -> AlState:
        """The master's target, capped at SAFEOP for DC slaves until DC is COMPENSATING (seed
        003: START_TIME is "the first time the slaves implement I/O"; NOT_SYNCHRONIZED: "all
        the slaves involved go to the SAFE_OP state")."""
        return self._target_of_dc() if link.dc else self.target

    def _target_of_dc(self) -> AlState:
        """:meth:`_target_of` a slave that uses DC."""
        if self.dc_hold and RANK[self.target] > RANK[AlState.SAFEOP]:
            return AlState.SAFEOP
        return self.target

    def _serve(self, link: SlaveLink, emergencies: list[bytes] | None = None) -> None:
        """One cycle's supervision of a slave; ``emergencies``: its mailbox, already taken."""
        slave, now = link.slave, self.now_us
        if emergencies is None:
            emergencies = slave.take_emergencies()
        for frame in emergencies:
            code, register, data = parse_emergency_frame(frame)
            link.counters.emergencies += 1
            self._event(CoeEmergency(now, "master", position=link.position,
                                     address=slave.station_address, code=code,
                                     register=register, data=data))
            self._log(link, "emergency", code=code, register=register, data=data)
        if link.pending is not None and not self._left_pending(link):
            self._check(link)
            return
        state, target = slave.al_state, self._target_of(link)
        if state is not link.believed:
            assert link.believed is not None
            if RANK.get(link.believed, 0) >= RANK[AlState.SAFEOP]:
                link.counters.wkc_errors += 1  # its process data stopped answering
            # "Try to go back to" where the master takes it: SAFEOP for a DC slave DC holds
            # there (seed 003), as the request below makes it; the §7.7 line names OP.
            self._log(link, "abnormal", from_state=link.believed.label, to_state=state.label,
                      code=slave.al_status_code, target=target.label)
            link.believed, link.next_try_us = state, now
            # The change is an event now (seed 003: "the status change of slaves"): the
            # request below may bring the slave back within this step, before the step's
            # watch reads its state again. The kept states no longer describe what was seen:
            # the step's watch runs in full (the slave back in OP is a change again).
            self._watch(link)
            self._watched = None
        if state is not target and now >= link.next_try_us:
            step = next_state(state, target)
            if step is AlState.OP and link.start_time_us is not None:
                if now < link.start_time_us:  # seed 003: no I/O before its START_TIME
                    link.next_try_us = link.start_time_us
                    return
                link.start_time_us = None
            if self._before_transition(link, state, step):
                self._request(link, step)
            else:
                link.stalled, link.next_try_us = True, now + self.retry_interval_us

    def _before_transition(self, link: SlaveLink, current: AlState, target: AlState) -> bool:
        """Identity check and init commands of ``current -> target``; False stops it."""
        desc = link.description
        if desc is None or RANK.get(current, 0) < RANK[AlState.PREOP]:
            return True  # INIT: no mailbox yet (IP commands go once PREOP is reached)
        if target is AlState.SAFEOP and current is AlState.PREOP:
            if not self._identity_ok(link):
                return False
            return self._send_init(link, "IP") and self._send_init(link, "PS")
        name = TRANSITION_NAME.get((current, target))
        return name is None or self._send_init(link, name)

    def _identity_ok(self, link: SlaveLink) -> bool:
        desc = link.description
        assert desc is not None
        if link.identity_ok is not None:
            return link.identity_ok
        if desc.vendor is None:
            return True  # derived from the rig: nothing to compare with
        sub = IDENTITY_SUBS[0]
        try:
            got = []
            for sub in IDENTITY_SUBS:
                got.append(struct.unpack("<I", link.slave.sdo_upload(0x1018, sub))[0])
        except (SdoAbort, ValueError, struct.error) as exc:
            # No usable answer (the SDO timed out or was aborted; no mailbox at all, or an
            # answer that is no UDINT, counts as the timeout): as a refused init command, a
            # communication error the master reports (seed 003 events: the diagnostic
            # structure, ECAT_Notify); the transition stops and is retried, and START_TIME
            # does not wait for the slave (stalled), as for any start-up the master found failed.
            abort = exc.code if isinstance(exc, SdoAbort) else AbortCode.SDO_TIMEOUT
            link.diagnosis = (f"identity not read: SDO upload 0x1018:{sub:02X} aborted with "
                              f"0x{int(abort):08X} ({ABORT_TEXT.get(abort, abort.name)}): "
                              f"the slave stays in PREOP")
            self._event(CommError(self.now_us, "master", position=link.position,
                                  address=link.slave.station_address, reason="identity",
                                  count=1))
            self._log(link, "identity_read", index=0x1018, sub=sub, abort=int(abort))
            return False
        if link.diagnosis.startswith("identity not read"):
            link.diagnosis = ""
        want = [desc.vendor, desc.product, desc.revision]
        link.identity_ok = got == want
        if not link.identity_ok:
            link.diagnosis = (f"identity mismatch: 0x1018 reads vendor 0x{got[0]:08X} product "
                              f"0x{got[1]:08X} revision 0x{got[2]:08X}, the network "
                              f"description expects 0x{want[0]:08X} 0x{want[1]:08X} "
                              f"0x{want[2]:08X}: the slave stays in PREOP")
            self._event(CommError(self.now_us, "master", position=link.position,
                                  address=link.slave.station_address, reason="identity",
                                  count=1))
            self._log(link, "identity", vendor=got[0], product=got[1], revision=got[2],
                      want_vendor=want[0], want_product=want[1], want_revision=want[2])
        return link.identity_ok

    def _send_init(self, link: SlaveLink, transition: str) -> bool:
        desc = link.description
        assert desc is not None
        for cmd in desc.commands(transition):
            try:
                link.slave.sdo_download(cmd.index, cmd.sub, cmd.data)
            except SdoAbort as exc:
                link.diagnosis = (f"init command '{cmd.comment}' ({transition}) refused: "
                                  f"{exc}")
                self._event(CommError(self.now_us, "master", position=link.position,
                                      address=link.slave.station_address,
                                      reason="init_command", count=1))
                self._log(link, "init_command", comment=cmd.comment, transition=transition,
                          index=cmd.index, sub=cmd.sub, abort=int(exc.code))
                return False
        if link.diagnosis.startswith("init command"):
            link.diagnosis = ""
        return True

    def _request(self, link: SlaveLink, target: AlState) -> None:
        if link.dc and target in (AlState.PREOP, AlState.SAFEOP) and \
                RANK.get(link.slave.al_state, 0) < RANK[target]:
            self._write_dc(link)
        current = link.slave.al_state
        link.pending, link.pending_from = target, current
        link.pending_floor = min(RANK.get(current, 0), RANK[target])
        link.requested, link.requested_at_us = target, self.now_us
        link.goal = self._target_of(link)
        # AL control bit 4 "Error Ind Ack" with a request over the error flag read set, as
        # TwinCAT acknowledges before it asks again (seed 000 §7.7 log): without it the slave
        # ignores the request (ETG.1000.6; devices/esm.py Esm.take_request).
        ack = bool(link.slave.al_status & AL_STATUS_ERROR_FLAG)
        link.slave.request_state(target, ack)

    def _write_dc(self, link: SlaveLink) -> None:
        """The DC registers of a DC slave (seed 001 §9.2 IP "il master inizializza il DC clock
        sync", written again before PS): SYNC0 on, one pulse per master cycle."""
        configure = getattr(link.slave, "configure_dc", None)
        if configure is not None:
            configure(activation=DC_SYNC0_ON, sync0_cycle_ns=self.cycle_us * 1000,
                      start_time_ns=self.now_us * 1000 + DC_START_DELAY_NS)

    def _left_pending(self, link: SlaveLink) -> bool:
        """The slave is below both the state it was asked from and the one requested, and
        refused nothing (no error flag): no transition goes that way, it left on its own (the
        FastCAT's CNF drops it to INIT, seed 000 §2). The request is dropped and _serve reads
        an abnormal state change from the state last read (seed 003: "the status change of
        slaves"), and asks for the way back at once, instead of waiting out the state timeout
        for a state the slave is no longer heading to. True: the request was dropped."""
        slave = link.slave
        if RANK.get(slave.al_state, 0) >= link.pending_floor \
                or slave.al_status & AL_STATUS_ERROR_FLAG:
            return False
        link.pending = None
        link.believed = link.seen if link.seen is not None else link.pending_from
        return True

    def _check(self, link: SlaveLink) -> None:
        slave, now = link.slave, self.now_us
        waited = now - link.requested_at_us
        if waited < self.check_delay_us:
            return
        state, target = slave.al_state, link.pending
        assert target is not None
        if state is target:
            link.believed, link.pending, link.next_try_us = state, None, now
            link.stalled = False
            return
        if not slave.al_status & AL_STATUS_ERROR_FLAG and waited < self.state_timeout_us:
            return  # still busy (INIT -> PREOP waits for the internal-bus scan)
        self._log(link, "failed", from_state=link.pending_from.label, to_state=target.label,
                  al_status=slave.al_status, expected=int(target), code=slave.al_status_code)
        # The target the request was made for (§7.7: "requested 'OP'" for a PREOP -> SAFEOP
        # step), not DC's hold since then: a request for OP that DC's fall to NOT_SYNCHRONIZED
        # overtook was still a request for OP.
        goal = link.goal if link.goal is not None else self.target
        self._log(link, "aborted", target=goal.label, state=state.label)
        link.believed, link.pending, link.stalled = state, None, True
        link.next_try_us = now + self.retry_interval_us
