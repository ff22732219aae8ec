"""The SDO server: the ``canopen`` library's SdoServer, fed one request at a time.

canopen.sdo.server.SdoServer does the protocol (expedited and segmented transfers, toggle bit,
aborts); it expects a node with ``get_data`` / ``set_data`` and a network with
``send_message``. :class:`SdoChannel` is both: reads and writes go to the node's dictionary
(access and range checks, DS 301 abort codes from devices.od), and answers go back to the node,
which puts them on its bus line at the simulated instant the request finished.

What the shim adds, each for a reason the library leaves open:

- The length rule of the drive (seed 004 ch. 4 "Servizio SDO": "Lo slave accetta ogni tipo di
  SDO, anche se il master non indica la lunghezza dei dati spediti"): an expedited download
  without the size bit brings four bytes; the object takes as many as it is wide. A download
  with a size takes up to the object's width (shorter data is extended, so the ch. 4 example
  "write object 2000, sub 2, value: u8 40" works on the 16-bit object); more bytes than the
  object holds abort with 0x06070012.
- A segmented download to a missing or read-only object aborts at the initiate request, not
  after the last segment (the library checks only at the end).
- The library's abort needs the index of the transfer: for a request it cannot parse it would
  fail before answering, so the index is set from the request first.
- A segment request outside a segmented transfer of its direction (an upload segment with no
  upload under way, a download segment with no download) aborts with 0x05040001, "command
  specifier not valid": the library would run into its empty buffer and answer 0x08000000
  with a logged traceback. The shim follows the transfer from the answers it sends, and a
  client's "abort SDO transfer" ends it (the library only notes the code and would take the
  next segment into the aborted transfer).
- Block upload: the drive has no block transfer (ch. 4, "supportato solo da alcuni
  dispositivi"; its feature list names none). The library answers every block upload request
  with a plain upload; DS 301 allows that switch only when the client's protocol switch
  threshold (pst, byte 5 of the initiate request) is not 0 and the object is at most pst
  bytes. Otherwise, and for a block upload's later requests, the answer is an abort 0x05040001
  ("ogni richiesta deve essere risolta ... Tale risposta negativa si chiama abort", ch. 4).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from canopen.objectdictionary import ObjectDictionary as CanopenDictionary
from canopen.sdo.exceptions import SdoAbortedError
from canopen.sdo.server import SdoServer

from devices.canopen.dictionary import CanOpenDictionary
from devices.od import AbortCode, DataType, OdEntry, SdoAbort, encode

SDO_RX_BASE = 0x600  # client -> server (request)
SDO_TX_BASE = 0x580  # server -> client (response)
SDO_FRAME_BYTES = 8  # "Un messaggio SDO è sempre otto byte" (ch. 4)
CCS_DOWNLOAD, CCS_UPLOAD = 0x20, 0x40
_CCS_DOWNLOAD_SEGMENT, _CCS_UPLOAD_SEGMENT, _CCS_ABORT = 0x00, 0x60, 0x80
_CCS_BLOCK_UPLOAD, _BLOCK_SUBCOMMAND = 0xA0, 0x03  # cs (bits 0-1) 0: the initiate request
_SCS_UPLOAD_SEGMENT, _SCS_DOWNLOAD_SEGMENT, _SCS_UPLOAD, _SCS_DOWNLOAD, _SCS_ABORT = (
    0x00, 0x20, 0x40, 0x60, 0x80)
EXPEDITED, SIZE_GIVEN, _LAST_SEGMENT = 0x02, 0x01, 0x01
_UP, _DOWN = "upload", "download"
_SIGNED = frozenset({DataType.INTEGER8, DataType.INTEGER16, DataType.INTEGER32})
_WIDTH = {DataType.BOOLEAN: 1, DataType.INTEGER8: 1, DataType.UNSIGNED8: 1,
          DataType.INTEGER16: 2, DataType.UNSIGNED16: 2, DataType.INTEGER32: 4,
          DataType.UNSIGNED32: 4}


class _Network:
    """What SdoServer calls to answer."""

    def __init__(self, send: Callable[[int, bytes], None]) -> None:
        self._send = send

    def send_message(self, can_id: int, data: bytes | bytearray) -> None:
        self._send(can_id, bytes(data))


def decode_download(entry: OdEntry, data: bytes, size_given: bool) -> Any:
    """The value a download carries, by the drive's length rule (see the module docstring)."""
    if entry.dtype is DataType.VISIBLE_STRING:
        return data.decode("latin-1")
    if entry.dtype is DataType.OCTET_STRING:
        return data
    width = _WIDTH[entry.dtype]
    if not size_given:
        data = data[:width]
    if len(data) > width:
        raise SdoAbort(AbortCode.LENGTH_TOO_HIGH, entry.index, entry.sub)
    if not data:
        raise SdoAbort(AbortCode.LENGTH_TOO_LOW, entry.index, entry.sub)
    return int.from_bytes(data, "little", signed=entry.dtype in _SIGNED)


class SdoChannel:
    """One SDO server channel (the drive has "1 server, 0 client", ch. 4)."""

    def __init__(self, node_id: int, dictionary: CanOpenDictionary,
                 object_dictionary: CanopenDictionary,
                 send: Callable[[int, bytes], None]) -> None:
        self.dictionary = dictionary
        self.object_dictionary = object_dictionary  # SdoServer's Mapping side reads it
        self.rx_cobid, self.tx_cobid = SDO_RX_BASE + node_id, SDO_TX_BASE + node_id
        self.server = SdoServer(self.rx_cobid, self.tx_cobid, self)
        self.server.network = _Network(self._answered)  # type: ignore[assignment]
        self._send = send
        self._size_given = True
        self._transfer: str | None = None  # the segmented transfer under way, if any
        self._request = b""

    def on_request(self, data: bytes) -> None:
        """One request frame. "Un messaggio SDO è sempre otto byte" (ch. 4): a frame of
        another length is no request and gets no answer (CANopenNode's server takes DLC 8
        only); "accetta ogni tipo di SDO" is about the size indicator (decode_download)."""
        if len(data) != SDO_FRAME_BYTES:
            return
        request = bytes(data)
        command, ccs = request[0], request[0] & 0xE0
        self._request = request
        if ccs == _CCS_ABORT:
            self._transfer = None  # "Abort SDO Transfer" from the client ends it (CiA 301)
        if (ccs == _CCS_UPLOAD_SEGMENT and self._transfer != _UP) or \
                (ccs == _CCS_DOWNLOAD_SEGMENT and self._transfer != _DOWN):
            if self.server._index is None:
                self.server._index, self.server._subindex = 0, 0
            self.server.abort(int(AbortCode.INVALID_COMMAND))
            return
        if ccs not in (_CCS_DOWNLOAD_SEGMENT, _CCS_UPLOAD_SEGMENT, _CCS_ABORT):
            # Every request but a segment names its object, and an abort of it must name
            # that object (ch. 4), also a block transfer or an unknown command specifier.
            self.server._index = int.from_bytes(request[1:3], "little")
            self.server._subindex = request[3]
        elif self.server._index is None:
            self.server._index, self.server._subindex = 0, 0
        if ccs == CCS_DOWNLOAD:
            self._size_given = bool(command & SIZE_GIVEN) or not command & EXPEDITED
            if not command & EXPEDITED and not self._initiate_segmented(request):
                return
        if ccs == _CCS_BLOCK_UPLOAD and not self._may_switch_protocol(request):
            return
        self.server.on_request(self.rx_cobid, request, 0.0)

    def _may_switch_protocol(self, request: bytes) -> bool:
        """A block upload request the library may answer with a plain upload (DS 301: an
        initiate whose pst lets the object through); else the abort it is owed is sent."""
        index, sub, pst = int.from_bytes(request[1:3], "little"), request[3], request[5]
        code = AbortCode.INVALID_COMMAND
        if not request[0] & _BLOCK_SUBCOMMAND:  # the initiate request names an object
            try:
                entry = self.dictionary.entry(index, sub)
                if not entry.access.readable:
                    raise SdoAbort(AbortCode.WRITE_ONLY, index, sub)
                size = len(encode(entry.dtype, self.dictionary.read(index, sub)))
            except SdoAbort as exc:
                code = exc.code
            else:
                if pst and size <= pst:
                    return True
        self.server.abort(int(code))
        return False

    def _initiate_segmented(self, request: bytes) -> bool:
        index, sub = int.from_bytes(request[1:3], "little"), request[3]
        try:
            entry = self.dictionary.entry(index, sub)
            if not entry.access.writable:
                raise SdoAbort(AbortCode.READ_ONLY, index, sub)
        except SdoAbort as exc:
            self.server.abort(int(exc.code))
            return False
        return True

    def _answered(self, can_id: int, response: bytes) -> None:
        """Follow the segmented transfer from the answer, then send it."""
        scs, request = response[0] & 0xE0, self._request
        if scs == _SCS_ABORT:
            self._transfer = None
        elif scs == _SCS_UPLOAD:
            self._transfer = None if response[0] & EXPEDITED else _UP
        elif scs == _SCS_DOWNLOAD:
            self._transfer = None if request[0] & EXPEDITED else _DOWN
        elif (scs == _SCS_UPLOAD_SEGMENT and response[0] & _LAST_SEGMENT) or \
                (scs == _SCS_DOWNLOAD_SEGMENT and request[0] & _LAST_SEGMENT):
            self._transfer = None  # the server's "no more data" / the client's last segment
        self._send(can_id, response)

    # ---- what SdoServer calls ------------------------------------------------------------
    def get_data(self, index: int, subindex: int, check_readable: bool = False) -> bytes:
        try:
            entry = self.dictionary.entry(index, subindex)
            return encode(entry.dtype, self.dictionary.read(index, subindex))
        except SdoAbort as exc:
            raise SdoAbortedError(int(exc.code)) from None

    def set_data(self, index: int, subindex: int, data: bytes | bytearray,
                 check_writable: bool = False) -> None:
        try:
            entry = self.dictionary.entry(index, subindex)
            if not entry.access.writable:
                raise SdoAbort(AbortCode.READ_ONLY, index, subindex)
            value = decode_download(entry, bytes(data), self._size_given)
            self.dictionary.write(index, subindex, value)
        except SdoAbort as exc:
            raise SdoAbortedError(int(exc.code)) from None
