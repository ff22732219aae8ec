"""The drives' Modbus line served with pymodbus on TCP: MBAP framing, or RTU framing over TCP.

pymodbus does the transport, the framing and the CRC; the drive's application layer is
:func:`app.modbus.pdu.serve_line`, run between two simulation steps: with ``call`` (the runtime's
:meth:`~app.runtime.Runtime.call`) at once in the server's loop while the simulation thread is
between steps, so a request costs no thread hand-over (benchmark 4, docs/hardening.md); else
in the simulation thread through ``submit``. Two small hooks below pymodbus's public API keep
the seed's "exception 02 only, otherwise no reply" (seed 004 ch.2 "Eccezioni"); docs/modbus.md
says why:

- :class:`_RawDecoder` hands every de-framed PDU over as raw bytes, so pymodbus never decodes,
  validates or answers a request itself (its own decoder answers exception 01 to an unknown
  function code and exception 04 to an unknown unit id);
- :class:`_DriveRequestHandler` takes each request when it is framed and answers it (or not)
  from our outcome, instead of pymodbus's shared ``last_pdu`` slot. With MBAP framing it also
  checks each header before pymodbus frames it: a header with a protocol id other than 0 or a
  length outside 2..254 closes the connection at once (pymodbus would wait for more data, or
  cut the stream at a wrong place, and silently lose the valid frames behind it), and it
  lifts pymodbus's 264-byte receive limit, which flushed a long pipeline of valid frames.
  With RTU framing it drops part of a frame left waiting through a pause of
  :data:`RTU_SILENCE_S`: an incomplete frame, which pymodbus would glue to the next one.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from pymodbus.exceptions import ModbusIOException, NotImplementedException
from pymodbus.framer import FramerRTU, FramerSocket, FramerType
from pymodbus.pdu import DecodePDU, ModbusPDU
from pymodbus.server import ModbusTcpServer
from pymodbus.server.requesthandler import ServerRequestHandler
from pymodbus.transaction import TransactionManager

from app.modbus.line import ServedLine
from app.modbus.pdu import ModbusDrive, Outcome, Reply, Silence, serve_line

logger = logging.getLogger(__name__)

T = TypeVar("T")
Submit = Callable[[Callable[[], T]], "concurrent.futures.Future[T]"]
Call = Callable[[Callable[[], T]], T]

FRAMERS = {"socket": FramerType.SOCKET, "rtu": FramerType.RTU}
SAVE_REPLY_POLL_S = 0.02
SAVE_REPLY_GIVE_UP_S = 30.0  # a save lasts "a few seconds" (ch.2); past this the reply is lost
# MBAP: transaction id (2), protocol id (2, always 0), length (2) = unit id + PDU, unit id (1).
# A PDU is 1..253 bytes (Modbus/TCP ADU at most 260 bytes), so the length is 2..254.
MBAP_HEADER, MBAP_LENGTHS = 7, range(2, 255)
# pymodbus empties a connection's receive buffer past 264 bytes (transport.py,
# datagram_received): with MBAP every complete frame is taken at once, so only a partial frame
# ever stays behind and the buffer may hold whatever one read of a pipelining client brings.
MBAP_RECEIVE_BUFFER = 1 << 20
# After a broken header the server ends its side (FIN) once the requests before it are
# answered, reads and drops what the client still sends, and closes after this long: closing
# at once with unread input would reset the connection and lose those replies in transit.
BROKEN_STREAM_LINGER_S = 2.0
# RTU framing over TCP has no character clock. Part of a frame that waits this long for its
# rest is a frame cut by a silence: "dichiarato incompleto e ... scartato" (seed 004 ch.2, RTU
# transmission mode). Far above a TCP segment's jitter, far below the ~1 s a master waits
# before it retransmits ("Master": response timeout 1 s, turnaround 100-200 ms).
RTU_SILENCE_S = 0.1


class LoopStalls:
    """When the server's one event loop was last blocked in a rig call (``call`` path).

    A connection's bytes are stamped when the loop reads them; while a rig call of another
    connection blocks the loop, bytes that came meanwhile wait in the socket, and the gap
    read afterwards is the stall's, not the line's. Bytes read before the loop polls the
    sockets again after the stall (its first pass) may have come at any time during it, how
    late in wall time that pass runs (a loaded machine); bytes read after that poll came
    after it. Consecutive calls (a pipelined client's frames) make one stall."""

    def __init__(self) -> None:
        self.start_s = self.end_s = -1.0
        self._depth = 0
        self._ends = 0  # which end() the open first pass follows
        self._first_pass = False  # the loop has not polled the sockets since the last stall

    def begin(self) -> None:
        if not self._depth and not self._first_pass:
            self.start_s = time.monotonic()  # else the stall just before goes on
        self._depth += 1

    def end(self) -> None:
        self._depth -= 1
        self.end_s = time.monotonic()
        self._ends += 1
        self._first_pass = True
        # asyncio runs what call_soon queues in the loop's next pass, before the I/O that
        # pass's poll found: the first callback runs before the reads of the sockets that
        # filled during the stall, the one it queues after them.
        ends, loop = self._ends, asyncio.get_running_loop()
        loop.call_soon(loop.call_soon, self._polled, ends)

    def _polled(self, ends: int) -> None:
        if ends == self._ends:  # a later stall keeps its own first pass open
            self._first_pass = False

    def arrival(self, last_s: float, now_s: float) -> float:
        """The earliest time bytes read at ``now_s`` can have come, the previous ones having
        come at ``last_s``: at the stall's start when read in the loop's first pass after
        it, else now."""
        if self._first_pass and self.end_s >= last_s:
            return max(last_s, self.start_s)
        return now_s


class _RawPdu(ModbusPDU):
    """A PDU carried as bytes: requests as they came, replies as the PDU layer built them."""

    def __init__(self, frame: bytes, dev_id: int = 0, transaction_id: int = 0) -> None:
        super().__init__(dev_id=dev_id, transaction_id=transaction_id)
        self.frame = bytes(frame)
        self.function_code = frame[0]

    def encode(self) -> bytes:
        return self.frame[1:]  # the framer writes the function code itself


class _RawDecoder(DecodePDU):
    """Keeps pymodbus's function-code table for RTU frame sizing, but never decodes a PDU."""

    def __init__(self) -> None:
        super().__init__(is_server=True)

    def decode(self, frame: bytes) -> ModbusPDU | None:
        return _RawPdu(frame) if frame else None


class _DriveRequestHandler(ServerRequestHandler):
    """One client connection; every framed request goes to ``answer``, nothing else replies."""

    def __init__(self, server: _DriveTcpServer) -> None:
        super().__init__(server, None, None, None)
        self._answer = server.answer
        self._mbap = isinstance(self.framer, FramerSocket)
        if self._mbap:
            self.max_buffer_size = MBAP_RECEIVE_BUFFER
        self.in_flight = 0  # requests taken, not yet answered (or silenced)
        self._broken = False  # a broken MBAP header came: nothing more is served
        self._last_data_s = 0.0  # RTU: when the last bytes came (time.monotonic)
        self._stalls: LoopStalls = server.stalls

    def begin(self) -> None:
        self.in_flight += 1

    def end(self) -> None:
        self.in_flight -= 1
        if self._broken and not self.in_flight:
            self._hang_up()

    def datagram_received(self, data: bytes, addr: tuple | None) -> None:
        if not self._mbap:
            read_s = time.monotonic()
            came_s = self._stalls.arrival(self._last_data_s, read_s)
            if self.recv_buffer and came_s - self._last_data_s > RTU_SILENCE_S:
                # ch.2: a frame cut by a silence is incomplete and discarded; pymodbus would
                # glue it to the next frame and lose that one too (a master's retransmission)
                logger.debug("incomplete RTU frame %s discarded", self.recv_buffer.hex(" "))
                self.recv_buffer = b""
            # The latest these bytes can have come: the next gap is a silence only if it is
            # one whenever in a stall they came (the earliest, came_s, made the gap before).
            self._last_data_s = read_s
        super().datagram_received(data, addr)

    def callback_data(self, data: bytes, addr: tuple | None = None) -> int:
        # pymodbus frames one request per call; take every complete one in the buffer, so that
        # a request sent right behind a (never answered) broadcast is not left waiting.
        if self._broken:
            return len(data)  # the stream is lost: dropped until the connection closes
        used = 0
        while used < len(data):
            frame = data[used:]
            if self._mbap:
                size = self._mbap_size(frame)
                if size is None:
                    break  # a partial frame: wait for the rest
            else:
                size = self._rtu_size(frame)
                if size == 0:
                    break  # a partial frame: wait for the rest
            if size is not None:
                frame = frame[:size]  # pymodbus sees exactly one frame
            try:
                step = TransactionManager.callback_data(self, frame, addr)
            except ModbusIOException:
                return len(data)  # unreadable: discarded, no reply (pymodbus: exception 01)
            request, self.last_pdu = self.last_pdu, None  # pymodbus's handler never sees it
            used += step
            if isinstance(request, _RawPdu):
                self._answer(self, request, addr)
            if not step or (request is None and size is None):
                break  # pymodbus waits for more, or took what it could not frame
        return len(data) if self._broken else used  # a lost stream is dropped at once

    def _mbap_size(self, data: bytes) -> int | None:
        """The size of the MBAP frame at the start of ``data``; None while it is incomplete.

        A header that breaks the framing closes the connection (Modbus Messaging on TCP/IP
        Implementation Guide: an invalid MBAP header is dropped or the connection closed):
        behind it the stream cannot be cut into frames again, and every valid request that
        followed would be lost in silence. The client sees the close and reconnects.
        """
        if len(data) < MBAP_HEADER:
            return None
        protocol, length = int.from_bytes(data[2:4], "big"), int.from_bytes(data[4:6], "big")
        if protocol or length not in MBAP_LENGTHS:
            logger.info("Modbus/TCP header %s (protocol id %d, length %d): connection closed",
                        data[:MBAP_HEADER].hex(" "), protocol, length)
            self._broken = True
            if not self.in_flight:
                self._hang_up()
            return None
        return 6 + length if len(data) >= 6 + length else None

    def _rtu_size(self, data: bytes) -> int | None:
        """The size of the RTU frame at the start of ``data`` as pymodbus's RTU framer sizes
        it (its function-code table), 0 while its byte count has not come; None when that
        table cannot size it (pymodbus then hunts through the buffer for a frame).

        pymodbus's ``FramerRTU.decode`` takes the whole buffer with the first frame: a
        request read together with the frame before it was lost. A master waits the
        turnaround delay after a broadcast (seed 004 ch.2, "Master"), but TCP keeps no
        pause: a server that reads its socket late finds both frames in one read."""
        try:
            pdu_class = self.framer.decoder.lookupPduClass(data)
            if pdu_class is None:
                return None
            size = pdu_class.calculateRtuFrameSize(data)
        except (IndexError, NotImplementedException):
            return None
        return size if size == 0 or size >= FramerRTU.MIN_SIZE else None

    def _hang_up(self) -> None:
        """End our side once every reply before the broken header is on its way."""
        transport = self.transport
        if transport is None or transport.is_closing():
            return
        if getattr(transport, "can_write_eof", lambda: False)():
            transport.write_eof()  # type: ignore[attr-defined]
            asyncio.get_running_loop().call_later(BROKEN_STREAM_LINGER_S, self._close_if_open)
        else:
            self.close()

    def _close_if_open(self) -> None:
        if self.transport is not None:  # pymodbus's close() fails on a connection already lost
            self.close()


class _DriveTcpServer(ModbusTcpServer):
    def __init__(self, address: tuple[str, int], framer: FramerType,
                 answer: Callable[[_DriveRequestHandler, _RawPdu, tuple | None], None],
                 stalls: LoopStalls) -> None:
        # No datastore: no request ever reaches one. broadcast_enable stays off so that unit
        # id 0 reaches our line handler, which applies broadcasts itself.
        super().__init__([], framer=framer, address=address)
        self.decoder = _RawDecoder()
        self.answer = answer
        self.stalls = stalls

    def callback_new_connection(self) -> _DriveRequestHandler:
        return _DriveRequestHandler(self)


class DriveModbusServer:
    """The Modbus line of ``drives`` on ``host:port`` (port 0: any free port, see ``.port``)."""

    def __init__(self, drives: Sequence[ModbusDrive], submit: Submit, host: str = "127.0.0.1",
                 port: int = 5020, framer: str = "socket", call: Call | None = None) -> None:
        if framer not in FRAMERS:
            raise ValueError(f"framer must be one of {', '.join(FRAMERS)}, got {framer!r}")
        self._drives = list(drives)
        self._submit = submit
        self._call = call
        self.host = host
        self.port = port
        self.framer = framer
        self._server: _DriveTcpServer | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop_event: asyncio.Event | None = None
        self._stalls = LoopStalls()

    # ---- asyncio API ---------------------------------------------------------------------
    async def start(self) -> None:
        server = _DriveTcpServer((self.host, self.port), FRAMERS[self.framer], self._answer,
                                 self._stalls)
        await server.serve_forever(background=True)  # raises RuntimeError if it cannot listen
        self._server = server
        sockets = getattr(server.transport, "sockets", None) or []
        if sockets:
            self.port = sockets[0].getsockname()[1]
        logger.info("Modbus (%s framing) on %s:%d for node(s) %s", self.framer, self.host,
                    self.port, ", ".join(str(d.node_id) for d in self._drives) or "none")

    def served(self) -> ServedLine:
        """The framing and port it serves on (after start: the port it really listens on)."""
        return ServedLine(self.framer, self.port)

    async def stop(self) -> None:
        for task in list(self._tasks):
            task.cancel()
        if self._tasks:
            await asyncio.gather(*self._tasks, return_exceptions=True)
        if self._server is not None:
            await self._server.shutdown()
            self._server = None

    # ---- thread API (the runtime's) ------------------------------------------------------
    def start_in_thread(self, timeout: float = 5.0) -> None:
        """Serve from a daemon thread with its own loop; returns once listening."""
        ready = threading.Event()
        failure: list[BaseException] = []
        self._thread = threading.Thread(target=self._thread_main, args=(ready, failure),
                                        name=f"modbus-{self.port}", daemon=True)
        self._thread.start()
        if not ready.wait(timeout):
            raise TimeoutError("Modbus server did not start")
        if failure:
            self._thread.join(timeout)
            raise failure[0]

    def stop_in_thread(self, timeout: float = 5.0) -> None:
        if self._loop is not None and self._stop_event is not None:
            self._loop.call_soon_threadsafe(self._stop_event.set)
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def _thread_main(self, ready: threading.Event, failure: list[BaseException]) -> None:
        async def main() -> None:
            self._loop = asyncio.get_running_loop()
            self._stop_event = asyncio.Event()
            try:
                await self.start()
            except BaseException as exc:
                failure.append(exc)
                ready.set()
                return
            ready.set()
            await self._stop_event.wait()
            await self.stop()

        asyncio.run(main())

    # ---- one request ---------------------------------------------------------------------
    def _answer(self, handler: _DriveRequestHandler, request: _RawPdu,
                addr: tuple | None) -> None:
        handler.begin()  # ended when the request is answered or silenced
        if self._call is None:
            self._spawn(self._serve(handler, request, addr), handler)
            return
        # Answered right here, in frame order; only a reply held back by a save waits (ch.2).
        try:
            outcome = self._blocking(lambda: serve_line(self._drives, request.dev_id,
                                                        request.frame))
        except Exception:  # a model fault must not take the line down: the drive stays silent
            logger.exception("Modbus request %s to unit %d failed", request.frame.hex(" "),
                             request.dev_id)
            handler.end()
            return
        if isinstance(outcome, Reply) and outcome.after_save:
            self._spawn(self._reply_after_save(handler, request, addr, outcome), handler)
        else:
            self._reply(handler, request, addr, outcome)
            handler.end()

    def _spawn(self, coro: Any, handler: _DriveRequestHandler) -> None:
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        task.add_done_callback(lambda _task: handler.end())

    async def _serve(self, handler: _DriveRequestHandler, request: _RawPdu,
                     addr: tuple | None) -> None:
        unit, frame = request.dev_id, request.frame
        try:
            outcome: Outcome = await self._in_sim(lambda: serve_line(self._drives, unit, frame))
        except Exception:  # a model fault must not take the line down: the drive stays silent
            logger.exception("Modbus request %s to unit %d failed", frame.hex(" "), unit)
            return
        if isinstance(outcome, Reply) and outcome.after_save:
            await self._reply_after_save(handler, request, addr, outcome)
        else:
            self._reply(handler, request, addr, outcome)

    async def _reply_after_save(self, handler: _DriveRequestHandler, request: _RawPdu,
                                addr: tuple | None, outcome: Reply) -> None:
        if await self._saved(request.dev_id):
            self._reply(handler, request, addr, outcome)

    @staticmethod
    def _reply(handler: _DriveRequestHandler, request: _RawPdu, addr: tuple | None,
               outcome: Outcome) -> None:
        unit = request.dev_id
        if isinstance(outcome, Silence):
            logger.debug("unit %d %s: no reply (%s)", unit, request.frame.hex(" "),
                         outcome.reason)
            return
        if handler.transport is None:
            return  # the client went away meanwhile
        reply = _RawPdu(outcome.pdu, dev_id=unit, transaction_id=request.transaction_id)
        handler.pdu_send(reply, addr)

    async def _saved(self, unit: int) -> bool:
        """Wait until the drive at ``unit`` answers again after a save (ch.2, save method 1)."""
        deadline = time.monotonic() + SAVE_REPLY_GIVE_UP_S
        while time.monotonic() < deadline:
            if await self._in_sim(lambda: any(d.responding and d.node_id == unit
                                              for d in self._drives)):
                return True
            await asyncio.sleep(SAVE_REPLY_POLL_S)
        logger.warning("drive %d still saving after %.0f s: reply dropped", unit,
                       SAVE_REPLY_GIVE_UP_S)
        return False

    async def _in_sim(self, fn: Callable[[], Any]) -> Any:
        if self._call is not None:
            return self._blocking(fn)
        return await asyncio.wrap_future(self._submit(fn))

    def _blocking(self, fn: Callable[[], T]) -> T:
        """``fn`` through ``call``, which blocks the loop: the stall is kept for the RTU
        silence of the other connections (LoopStalls)."""
        assert self._call is not None
        self._stalls.begin()
        try:
            return self._call(fn)
        finally:
            self._stalls.end()
