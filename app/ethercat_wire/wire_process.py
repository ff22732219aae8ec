"""Process B: one raw AF_PACKET socket (EtherType 0x88A4) and the emulated ESC line behind it.

Started by the bridge (process A) with
    multiprocessing.get_context("spawn").Process(target=run, args=(iface, descriptions, conn))
Frames are answered at once from the ESCs' memory (no round trip to A per frame); what the
devices must decide goes to A over `conn` (app/ethercat_wire/messages.py) and A's answers are
applied between frames. A poll loop on the socket and the connection, nothing else.
"""

from __future__ import annotations

import ctypes
import logging
import os
import select
import socket
import time
from multiprocessing.connection import Connection

from app.ethercat_wire import dc, messages, sii
from app.ethercat_wire.datagrams import ETHERTYPE, FrameError
from app.ethercat_wire.description import SlaveDescription
from app.ethercat_wire.esc import Esc, Line

logger = logging.getLogger(__name__)

SOL_PACKET = 263
PACKET_IGNORE_OUTGOING = 23  # Linux >= 4.20: our own answers do not come back to us
PACKET_OUTGOING = 4
FRAME_BUFFER = 2048
POLL_MS = 10
RT_PRIORITY = 10  # SCHED_FIFO priority asked for when allowed: frames answered before batch work
MCL_CURRENT, MCL_FUTURE = 1, 2  # <sys/mman.h>


def build_line(descriptions: list[SlaveDescription], outbox: list[tuple],
               clock: dc.DcClock | None = None) -> Line:
    clock = clock or dc.DcClock()
    escs = [Esc(pos, desc, sii.build(desc, desc.station_alias or 0), clock, outbox)
            for pos, desc in enumerate(descriptions)]
    return Line(escs, outbox)


def realtime_priority() -> bool:
    """Ask for a low SCHED_FIFO priority (root / CAP_SYS_NICE): a slave must answer within the
    master's datagram timeout (SOEM: 2 ms) even on a loaded machine. Process B sleeps in poll()
    between frames, so it takes the CPU only while a frame waits."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(RT_PRIORITY))
    except (AttributeError, OSError) as exc:
        logger.info("no real-time priority for the wire process (%s): timing as scheduled", exc)
        return False
    return True


def lock_memory() -> bool:
    """mlockall (root / CAP_IPC_LOCK), as real-time EtherCAT stacks do: a page of B's evicted
    and faulted back in from disk (this host runs DAMON's proactive reclaim, which evicts cold
    pages with memory free) stalls an answer past the master's 2 ms. B is one small
    interpreter, so locking it all costs a few tens of MB."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.mlockall(MCL_CURRENT | MCL_FUTURE) != 0:
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
    except (AttributeError, OSError) as exc:
        logger.info("wire process memory not locked (%s): pages may fault", exc)
        return False
    return True


def open_socket(iface: str) -> socket.socket:
    """A raw EtherCAT socket on `iface` alone. Opened with protocol 0, which receives nothing
    (packet(7)), and given the EtherType by the bind: opened for 0x88A4 it would take every
    interface's EtherCAT frames until bound, and run another master's through our ESCs."""
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, 0)
    sock.bind((iface, ETHERTYPE))
    try:
        sock.setsockopt(SOL_PACKET, PACKET_IGNORE_OUTGOING, 1)
    except OSError:
        logger.info("PACKET_IGNORE_OUTGOING not available: filtering our own frames by type")
    sock.setblocking(False)
    return sock


class Stats:
    """Counters reported to A: frames, WKC errors and frames a damaged cable spoiled in A's
    run (since B started or A's last scenario load; ``run``: which), process-data frames since
    B started, and the mean interval between process-data frames over the last report period
    (the cycle; 0.0 when none came). B cannot see frames the master lost on its side."""

    def __init__(self) -> None:
        self.last_pd = 0
        self.last_t = time.monotonic()

    def report(self, line: Line) -> dict:
        now = time.monotonic()
        n = line.pd_frames - self.last_pd
        cycle_us = (now - self.last_t) * 1e6 / n if n else 0.0
        self.last_pd, self.last_t = line.pd_frames, now
        return {"frames": line.frames, "lrw": line.pd_frames, "cycle_us": round(cycle_us, 1),
                "wkc_errors": line.wkc_errors, "lost_frames": line.spoiled,
                "run": line.damage.run}


def apply_message(line: Line, msg: tuple) -> bool:
    """Apply one message from A; False on ("stop",)."""
    tag = msg[0]
    if tag == messages.STOP:
        return False
    if tag == messages.DAMAGE:
        line.set_damage(msg[1], msg[2], msg[3])
        return True
    esc = line.escs[msg[1]]
    if tag == messages.AL_STATUS:
        esc.set_al_status(msg[2], msg[3])
    elif tag == messages.MAILBOX_REPLY:
        esc.queue_mailbox(msg[2])
    elif tag == messages.INPUTS:
        esc.set_inputs(msg[2])
    elif tag == messages.LINK:
        line.set_link(msg[1], bool(msg[2]))
    elif tag == messages.SILENT:
        line.set_silent(msg[1], bool(msg[2]))
    elif tag == messages.ALIAS:
        esc.set_alias(msg[2])
    elif tag == messages.ESC_ERRORS:
        esc.set_error_counters(msg[2], msg[3])
    else:
        logger.warning("unknown message from process A: %r", tag)
    return True


def cycle_counts(line: Line) -> dict[int, int]:
    """Per slave, its process-data exchanges since the last call; for a silent slave, the
    frames that crossed its ESC (it takes no datagram: A tells its model they passed)."""
    counts = line.take_passed()
    for esc in line.escs:
        if esc.exchanges:
            counts[esc.position] = counts.get(esc.position, 0) + esc.exchanges
            esc.exchanges = 0
    return counts


def run(iface: str, descriptions: list[SlaveDescription], conn: Connection) -> None:
    """The wire process: serve frames on `iface` until A says stop or the pipe closes."""
    logging.basicConfig(level=logging.INFO, format="wire %(levelname)s %(message)s")
    outbox: list[tuple] = []
    line = build_line(list(descriptions), outbox)
    try:
        sock = open_socket(iface)
    except OSError as exc:
        conn.send((messages.ERROR, f"cannot open a raw socket on {iface}: {exc}"))
        return
    realtime_priority()
    lock_memory()
    conn.send((messages.READY, iface))
    try:
        serve(sock, line, conn, outbox)
    finally:
        sock.close()


class Mailman:
    """Messages to A, sent only while the pipe has room: B never blocks on A (A may be sending
    to B at the same moment; two blocking writers on a full pipe pair would deadlock and the
    wire would stop answering). Outputs, cycle counts and stats are state, not history: an
    unsent one is replaced by a newer one."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.pending: list[tuple] = []
        self._writable = select.poll()
        self._writable.register(conn.fileno(), select.POLLOUT)

    def post(self, msg: tuple) -> None:
        tag = msg[0]
        if tag in _REPLACEABLE:
            key = msg[1] if tag == messages.OUTPUTS else None
            for i, old in enumerate(self.pending):
                if old[0] == tag and (key is None or old[1] == key):
                    if tag == messages.CYCLE:  # counts add up
                        merged = dict(old[1])
                        for pos, n in msg[1].items():
                            merged[pos] = merged.get(pos, 0) + n
                        msg = (tag, merged)
                    self.pending[i] = msg
                    return
        self.pending.append(msg)

    def flush(self) -> None:
        while self.pending and self._writable.poll(0):
            self.conn.send(self.pending.pop(0))


_REPLACEABLE = frozenset({messages.OUTPUTS, messages.CYCLE, messages.STATS})


def serve(sock: socket.socket, line: Line, conn: Connection, outbox: list[tuple]) -> None:
    poller = select.poll()
    poller.register(sock.fileno(), select.POLLIN)
    poller.register(conn.fileno(), select.POLLIN)
    buf = bytearray(FRAME_BUFFER)
    view = memoryview(buf)
    stats = Stats()
    mail = Mailman(conn)
    next_cycle = next_stats = time.monotonic()
    running = True
    while running:
        for fd, _ev in poller.poll(POLL_MS):
            if fd == sock.fileno():
                _drain_socket(sock, line, buf, view, mail)
            else:
                running = _drain_conn(conn, line, mail)
        if outbox:
            for msg in outbox:
                mail.post(msg)
            outbox.clear()
        now = time.monotonic()
        if now >= next_cycle:
            counts = cycle_counts(line)
            if counts:
                mail.post((messages.CYCLE, counts))
            batch = line.take_esc_counts()
            if batch is not None:  # in order with the master's writes (not replaceable)
                mail.post((messages.ESC_COUNTS, *batch, line.damage.run))
            next_cycle = now + messages.CYCLE_REPORT_S
        if now >= next_stats:
            mail.post((messages.STATS, stats.report(line)))
            next_stats = now + messages.STATS_REPORT_S
        mail.flush()


def _drain_socket(sock: socket.socket, line: Line, buf: bytearray, view: memoryview,
                  mail: Mailman) -> None:
    while True:
        try:
            n, addr = sock.recvfrom_into(buf)
        except (BlockingIOError, InterruptedError):
            return
        if addr[2] == PACKET_OUTGOING:
            continue
        frame = bytearray(view[:n])
        try:
            if line.process(frame):
                sock.send(frame)
        except FrameError as exc:
            logger.debug("frame dropped: %s", exc)
        except Exception as exc:  # a bug must not take the whole wire down: drop the frame
            logger.exception("frame dropped")
            mail.post((messages.ERROR, f"frame dropped: {exc!r}"))


def _drain_conn(conn: Connection, line: Line, mail: Mailman) -> bool:
    try:
        while conn.poll():
            msg = conn.recv()
            try:
                if not apply_message(line, msg):
                    return False
            except (IndexError, TypeError, ValueError) as exc:
                mail.post((messages.ERROR, f"bad message {msg!r:.80}: {exc}"))
    except (EOFError, OSError):
        return False
    return True
