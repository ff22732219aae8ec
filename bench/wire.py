"""EtherCAT wire benchmark (issue 8): frames per second and the shortest clean cycle.

Two measurements for lines of 1, 5 and 30 slaves (each 4 output and 4 input bytes, DC):

- Python cost per frame: `Line.process` on the frame SOEM sends every cycle (LRW of the whole
  image + FRMW of the reference clock's system time), in this process, no socket;
- over a veth pair (root, pysoem): process B (`wire_process.run`) on one end, SOEM through
  pysoem in another process on the other end, this process answering B's AL control messages
  in place of the app (process data never waits on process A). Back-to-back frames per second
  and the median round trip; then fixed periods from 4 ms down, each for a few seconds: the
  shortest with no wrong working counter is the "shortest clean cycle".

Anchor (ethercat-wire-notes.md, measured with a prototype on this machine): about 20 us + 3 us
per slave per frame in Python; 4 ms cycles clean, 1 ms nearly (one wrong WKC in 10,000).

    python -m bench wire [--quick] [--slaves 1 5 30]
"""

from __future__ import annotations

import argparse
import contextlib
import multiprocessing
import os
import shutil
import statistics
import subprocess
import threading
import time

from app.ethercat_wire import messages, wire_process
from app.ethercat_wire.datagrams import Cmd, Request, build
from app.ethercat_wire.description import Pdo, PdoEntry, SlaveDescription, SyncManager

SLAVES = (1, 5, 30)
PERIODS_US = (4000, 2000, 1000, 500, 250)
ANCHOR_BASE_US, ANCHOR_PER_SLAVE_US = 20.0, 3.0


def description(i: int) -> SlaveDescription:
    """A slave without mailbox: SOEM maps it from the SII PDOs alone (no CoE round trips)."""
    return SlaveDescription(
        device_id=f"bench{i}", name=f"Bench {i}", vendor_id=0xF1E1D, product_code=0xBE00,
        revision=1, serial=i, group="Bench", order_code="BENCH",
        mailbox=None, coe_details=0,
        sync_managers=(SyncManager(0, 0, 0, 0), SyncManager(0, 0, 0, 0),
                       SyncManager(0x1100, 4, 0x64, 1), SyncManager(0x1400, 4, 0x20, 1)),
        rx_pdos=(Pdo(0x1600, "Out", (PdoEntry(0x7000, 1, 32, "Out"),)),),
        tx_pdos=(Pdo(0x1A00, "In", (PdoEntry(0x6000, 1, 32, "In"),)),),
        dc_supported=True)


def python_cost(n: int, frames: int) -> float:
    """Microseconds of Python per cyclic frame through a line of `n` configured slaves."""
    outbox: list[tuple] = []
    line = wire_process.build_line([description(i) for i in range(n)], outbox)
    for i, esc in enumerate(line.escs):
        esc.write(0x0010, (0x1001 + i).to_bytes(2, "little"))
        esc.write(0x0810, bytes.fromhex("0011 0400 64 00 01 00"))
        esc.write(0x0818, bytes.fromhex("0014 0400 20 00 01 00"))
        out = (4 * i).to_bytes(4, "little") + bytes.fromhex("0400 00 07 0011 00 02 01 000000")
        inp = (4 * n + 4 * i).to_bytes(4, "little") + bytes.fromhex(
            "0400 00 07 0014 00 01 01 000000")
        esc.write(0x0600, out + inp)
    template = build([Request.logical(Cmd.LRW, 0, bytes(8 * n)),
                      Request(Cmd.FRMW, 0x1001, 0x0910, bytes(8))])
    start = time.process_time()  # CPU time: other work on a shared machine does not count
    for k in range(frames):
        frame = bytearray(template)
        frame[28:32] = k.to_bytes(4, "little")  # outputs change every frame
        line.process(frame)
        outbox.clear()
    return (time.process_time() - start) / frames * 1e6


# ---- over the wire -----------------------------------------------------------------------
def master_main(iface: str, n: int, seconds: float, periods_us: tuple[int, ...], conn) -> None:
    import pysoem

    with contextlib.suppress(OSError):
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
    m = pysoem.Master()
    m.open(iface)
    found = m.config_init()
    m.config_map()
    m.config_dc()
    m.state = pysoem.OP_STATE
    m.write_state()
    for _ in range(500):
        m.send_processdata()
        m.receive_processdata(2000)
        if m.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
            break
    result = {"found": found, "op": m.state_check(pysoem.OP_STATE, 50000) == pysoem.OP_STATE}
    trips, end = [], time.perf_counter() + seconds
    while time.perf_counter() < end:
        t = time.perf_counter()
        m.send_processdata()
        m.receive_processdata(2000)
        trips.append(time.perf_counter() - t)
    result["frames_per_s"] = len(trips) / seconds
    result["median_trip_us"] = statistics.median(trips) * 1e6
    result["periods"] = {}
    for period_us in periods_us:
        cycles = max(200, int(seconds * 1e6 / period_us))
        bad = lost = late = 0
        t = time.perf_counter()
        for _ in range(cycles):
            m.send_processdata()
            wkc = m.receive_processdata(2000)
            if wkc < 0:  # EC_NOFRAME: not back within the timeout
                lost += 1
            elif wkc != m.expected_wkc:
                bad += 1
            t += period_us / 1e6
            rest = t - time.perf_counter()
            if rest < 0:
                late += 1  # the next cycle is already due: an overrun
                continue
            # sleep, then spin the last 200 us: a real-time process that spins all the time
            # is throttled by the kernel (sched_rt_runtime_us) and misses whole cycles
            time.sleep(max(0.0, rest - 0.0002))
            while time.perf_counter() < t:
                pass
        result["periods"][period_us] = (cycles, bad, lost, late)
    m.close()
    conn.send(result)


def answer_al_control(conn, stop: threading.Event) -> None:
    """Process A's part, reduced to the ESM: every requested state is granted."""
    while not stop.is_set():
        try:
            if not conn.poll(0.05):
                continue
            msg = conn.recv()
        except (EOFError, OSError):
            return  # the wire process has gone: the run is over
        if msg[0] == messages.AL_CONTROL:
            conn.send((messages.AL_STATUS, msg[1], msg[2] & 0x0F, 0))


def over_the_wire(n: int, seconds: float, periods_us: tuple[int, ...]) -> dict | str:
    if os.geteuid() != 0:
        return "needs root (veth pair, raw socket)"
    try:
        import pysoem  # noqa: F401
    except ImportError:
        return "needs pysoem"
    if shutil.which("ip") is None:
        return "needs the `ip` command (iproute2)"
    a, b = f"bwm{os.getpid() % 10000}", f"bws{os.getpid() % 10000}"
    made = subprocess.run(["ip", "link", "add", a, "type", "veth", "peer", "name", b],
                          capture_output=True, text=True)
    if made.returncode:
        return f"cannot create a veth pair: {made.stderr.strip()}"
    ctx = multiprocessing.get_context("spawn")
    try:
        for name in (a, b):
            subprocess.run(["ip", "link", "set", name, "up"], check=True)
        a_end, b_end = ctx.Pipe()
        wire = ctx.Process(target=wire_process.run,
                           args=(b, [description(i) for i in range(n)], b_end), daemon=True)
        wire.start()
        if a_end.recv()[0] != messages.READY:
            return "wire process did not start"
        stop = threading.Event()
        threading.Thread(target=answer_al_control, args=(a_end, stop), daemon=True).start()
        m_end, child = ctx.Pipe()
        master = ctx.Process(target=master_main, args=(a, n, seconds, periods_us, child),
                             daemon=True)
        master.start()
        limit = 60 + seconds * (2 + len(periods_us))
        result = m_end.recv() if m_end.poll(limit) else "master did not finish"
        stop.set()
        a_end.send((messages.STOP,))
        for proc in (master, wire):
            proc.join(timeout=5)
            if proc.is_alive():
                proc.terminate()
        return result
    finally:
        subprocess.run(["ip", "link", "del", a], capture_output=True)


def shortest_clean(periods: dict[int, tuple[int, int, int, int]]) -> str:
    """Going down from 4 ms: the last period with no wrong WKC, no lost frame and at most
    1 % overruns before the first one that fails any."""
    best = None
    for period in sorted(periods, reverse=True):
        cycles, bad, lost, late = periods[period]
        if bad or lost or late > cycles // 100:
            break
        best = period
    return f"{best / 1000:g} ms" if best else "none"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench wire", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="short runs (CI smoke)")
    parser.add_argument("--slaves", type=int, nargs="+", default=list(SLAVES))
    args = parser.parse_args(argv)
    seconds = 0.5 if args.quick else 3.0
    print("Python cost per cyclic frame (LRW + FRMW), target ~20 us + 3 us per slave:")
    for n in args.slaves:
        cost = python_cost(n, 500 if args.quick else 5000)
        anchor = ANCHOR_BASE_US + ANCHOR_PER_SLAVE_US * n
        print(f"  {n:3d} slaves: {cost:7.1f} us/frame  (anchor {anchor:.0f} us)")
    print("Over a veth pair with SOEM (pysoem), target: 4 ms clean, 1 ms nearly:")
    for n in args.slaves:
        result = over_the_wire(n, seconds, PERIODS_US)
        if isinstance(result, str):
            print(f"  {n:3d} slaves: skipped, {result}")
            continue
        print(f"  {n:3d} slaves: found {result['found']}, OP {result['op']}, "
              f"{result['frames_per_s']:.0f} frames/s back to back, median round trip "
              f"{result['median_trip_us']:.0f} us; shortest clean cycle "
              f"{shortest_clean(result['periods'])}")
        for period, (cycles, bad, lost, late) in result["periods"].items():
            print(f"        {period / 1000:5.2f} ms: {cycles} cycles, {bad} wrong WKC, "
                  f"{lost} lost frames, {late} overruns")
    return 0
