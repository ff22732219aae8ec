"""CoE SDO services of the drive's mailbox: upload, download, SDO information.

Seed 004 ch. 5 "SDO: tipologia e dizionario oggetti": "SDO Upload (come nel canopen), SDO
Download (come nel canopen), SDO Info support (tipico di ethercat)"; "utilizzando la funzione
SDO Info support è possibile visualizzare l'elenco aggiornato degli oggetti implementati nel
dizionario direttamente dal master". The mailbox exists from PREOP on ("Disponibile la
comunicazione via Mailbox"); in INIT, or while the slave is off the line, a request never
reaches the drive (:class:`MailboxClosed`), which a master sees as a timeout.

Values travel as bytes, little endian; a download follows the drive's SDO length rule of
ch. 4 (:func:`devices.canopen.sdo.decode_download`: shorter data is extended, longer data
aborts 0x06070012). Refusals are :class:`devices.od.SdoAbort` with the DS 301 codes.
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING, Any

from devices.canopen.sdo import decode_download
from devices.device import CommandError
from devices.ethercat import AlState
from devices.od import AbortCode, SdoAbort, encode

if TYPE_CHECKING:
    from devices.canopen.dictionary import CanOpenDictionary
    from devices.coe.drive_slave import DriveEcatSlave


class MailboxClosed(CommandError):
    """No mailbox: the slave is in INIT or not on the line (a master would time out)."""


def upload(dictionary: CanOpenDictionary, index: int, sub: int) -> bytes:
    entry = dictionary.entry(index, sub)
    return encode(entry.dtype, dictionary.read(index, sub))


def download(dictionary: CanOpenDictionary, index: int, sub: int, data: bytes) -> Any:
    """Write ``data`` to an object; returns the value written."""
    entry = dictionary.entry(index, sub)
    if not entry.access.writable:
        raise SdoAbort(AbortCode.READ_ONLY, index, sub)
    value = decode_download(entry, bytes(data), size_given=True)
    dictionary.write(index, sub, value)
    return value


def object_list(dictionary: CanOpenDictionary) -> list[int]:
    """SDO Info "get OD list" (all objects)."""
    return dictionary.indices()


def entry_description(dictionary: CanOpenDictionary, index: int, sub: int) -> dict[str, Any]:
    """SDO Info "get entry description": data type, bit length, access, mappability, name."""
    entry = dictionary.entry(index, sub)
    return {"index": index, "sub": sub, "name": entry.name, "data_type": int(entry.dtype),
            "type": entry.dtype.short, "bit_length": entry.bit_length,
            "access": entry.access.value, "pdo_mappable": entry.pdo_mappable}


class SdoServices:
    """Mixin of :class:`~devices.coe.drive_slave.DriveEcatSlave`: the mailbox's SDO side."""

    sdo_log: deque[dict[str, Any]]

    def _mailbox(self: DriveEcatSlave) -> CanOpenDictionary:
        if not self.reachable():
            raise MailboxClosed(f"'{self.box_name}' is not on the EtherCAT line (drive off, "
                                "c9 != 11 at power-up, or no link)")
        if not self.esm.at_least(AlState.PREOP):
            raise MailboxClosed(f"'{self.box_name}' is in INIT: no mailbox yet")
        return self.dictionary

    def sdo_upload(self: DriveEcatSlave, index: int, sub: int) -> bytes:
        try:
            data = upload(self._mailbox(), index, sub)
        except SdoAbort as exc:
            self._log_sdo("upload", index, sub, abort=exc)
            raise
        self._log_sdo("upload", index, sub, data=data)
        return data

    def sdo_download(self: DriveEcatSlave, index: int, sub: int, data: bytes) -> None:
        try:
            download(self._mailbox(), index, sub, data)
        except SdoAbort as exc:
            self._log_sdo("download", index, sub, data=data, abort=exc)
            raise
        self._log_sdo("download", index, sub, data=data)
        self._refresh()

    def sdo_info(self: DriveEcatSlave, index: int | None = None, sub: int = 0) -> Any:
        """SDO Information: the object list (no index), or one entry's description."""
        od = self._mailbox()
        return object_list(od) if index is None else entry_description(od, index, sub)

    def _log_sdo(self: DriveEcatSlave, op: str, index: int, sub: int, data: bytes = b"",
                 abort: SdoAbort | None = None) -> None:
        """The panel's "last SDO" lines, failures included."""
        self.sdo_log.append({"t": self.now_us / 1e6, "op": op, "address": f"0x{index:04X}:{sub}",
                             "data": data.hex(" ").upper(),
                             "abort": f"0x{int(abort.code):08X}" if abort else None})
