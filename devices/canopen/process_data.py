"""Process data of the node: SYNC, RPDOs in, TPDOs out (seed 004 ch. 4 "Servizio PDO").

A mixin of :class:`~devices.canopen.node.CanOpenNode`. SYNC (Pre-operational and Operational):
the synchronous RPDOs received since the previous SYNC take effect ("attuati al Sync
immediatamente successivo"), the drive takes the Sync (the interpolator takes its set-point),
then the synchronous TPDOs go out with the values of that instant: type 0 when they changed,
type n every n SYNCs; every SYNC records them, sent or not, and a remote request gets that
record. Asynchronous RPDOs take effect when they arrive; asynchronous TPDOs go on a change or
on their event timer, never within the inhibit time of the previous one. A TPDO with no
object mapped (0x1A0x:0 = 0) is never sent: a PDO carries one to eight bytes.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from devices.canopen import emcy as em
from devices.canopen.nmt import NmtState
from devices.canopen.pdo import ASYNC_TYPES, COB_INVALID, COB_NO_RTR, Pdo
from devices.device import CommandError
from devices.od import SdoAbort

if TYPE_CHECKING:
    from devices.canopen.node import CanOpenNode

logger = logging.getLogger(__name__)


class ProcessData:
    def _sync(self: CanOpenNode, t: int) -> None:
        """SYNC: synchronous RPDOs take effect, the drive syncs, synchronous TPDOs go out."""
        self.syncs += 1
        operational = self.state is NmtState.OPERATIONAL
        if operational:
            for pdo in self.rpdos:
                if pdo.valid and pdo.synchronous and pdo.buffered is not None:
                    data, pdo.buffered = pdo.buffered, None
                    self._apply_rpdo(pdo, data)
        try:
            self.drive.apply("sync", {})
        except CommandError as exc:  # saving to flash
            logger.debug("%s: SYNC not taken: %s", self.drive.device_id, exc)
        if not operational:
            return
        for pdo in self.tpdos:
            if not (pdo.valid and pdo.synchronous):
                continue
            # recorded at every SYNC, sent or not: a remote request gets this record
            data = pdo.sampled = self._pack(pdo)
            if data is None:
                continue
            if pdo.trans_type == 0:
                if data != pdo.last_data:
                    self._send_pdo(pdo, data, t)
            else:
                pdo.syncs += 1
                if pdo.syncs >= pdo.trans_type:
                    pdo.syncs = 0
                    self._send_pdo(pdo, data, t)

    def _rpdo(self: CanOpenNode, pdo: Pdo, data: bytes, t: int) -> None:
        if len(data) < pdo.length:  # DS 301: not processed, EMCY 0x8210
            self._emergency(em.PDO_LENGTH_ERROR, b"", t, transient=True)
            return
        if pdo.synchronous:
            pdo.buffered = data  # "attuati al Sync immediatamente successivo"
        else:
            self._apply_rpdo(pdo, data)

    def _apply_rpdo(self: CanOpenNode, pdo: Pdo, data: bytes) -> None:
        for index, sub, value in pdo.unpack(data, self.dictionary.entry):
            try:
                self.dictionary.write(index, sub, value)
            except SdoAbort as exc:
                logger.info("%s: %s: %s", self.drive.device_id, pdo.name, exc)

    def _pdo_request(self: CanOpenNode, can_id: int, t: int) -> None:
        """A remote request for a TPDO (COB-ID bit 30 clear), answered at once: a synchronous
        one with the data recorded at the last SYNC ("con i valori rilevati" at the SYNC,
        ch. 4 l. 2218-2222), the data of this instant before any SYNC and for an asynchronous
        one; a TPDO with nothing mapped leaves it unanswered, as a switched-off one does."""
        if self.state is not NmtState.OPERATIONAL:
            return
        for pdo in self.tpdos:
            if pdo.valid and pdo.can_id == can_id and not pdo.cob_id & COB_NO_RTR:
                data = pdo.sampled if pdo.synchronous else None
                if data is None:
                    data = self._pack(pdo)
                if data is not None:
                    self._send_pdo(pdo, data, t)

    def _async_tpdos(self: CanOpenNode, now_us: int) -> bool:
        """The asynchronous TPDOs of a step in Operational; True when one went out."""
        sent = False
        for pdo in self.tpdos:
            if not pdo.cob_id & COB_INVALID and pdo.trans_type in ASYNC_TYPES:
                sent = self._async_tpdo(pdo, now_us) or sent
        return sent

    def _async_tpdo(self: CanOpenNode, pdo: Pdo, now_us: int) -> bool:
        data = self._pack(pdo)
        if data is None:
            return False
        last, start = pdo.last_sent_us, pdo.timer_from_us
        event = data != pdo.last_data
        timer = bool(pdo.event_timer_ms) and start is not None \
            and now_us >= start + pdo.event_timer_ms * 1000
        inhibited = last is not None and now_us - last <= pdo.inhibit_100us * 100
        if (event or timer) and not inhibited:
            self._send_pdo(pdo, data, now_us)
            return True
        return False

    def _pack(self: CanOpenNode, pdo: Pdo) -> bytes | None:
        """The TPDO's data, or None when it is not sent: nothing mapped ("Il campo dati di un
        PDO può essere compreso tra uno e otto byte"; so no frame at the timer, a SYNC or a
        remote request) or an object it maps cannot be read."""
        if not pdo.count:
            return None
        try:
            return pdo.pack_planned(self.dictionary)
        except (SdoAbort, CommandError) as exc:
            logger.debug("%s: %s not packed: %s", self.drive.device_id, pdo.name, exc)
            return None

    def _send_pdo(self: CanOpenNode, pdo: Pdo, data: bytes, t: int) -> None:
        pdo.last_sent_us = pdo.timer_from_us = t
        pdo.last_data = data
        self._send(pdo.can_id, data, t)
