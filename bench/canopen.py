"""Benchmark 5 (issue 7): SDO expedited uploads per second, the drive against the floor, and the
bus-timing model against the physical bound.

Throughput: a ``canopen`` master in this process (``RemoteNode`` from static/eds) uploads
0x6064 (position actual value, expedited, 4 bytes) one request after the other, for a fixed
wall time, from

- **drive**: the default rig with its drive on CANopen (c9 = 5, n1 = 8: 1 Mbit/s) live in
  :class:`app.runtime.Runtime` at real-time speed, on the bus through
  :class:`app.canopen_bus.CanOpenBus`;
- **floor**: a bare ``canopen.LocalNode`` built from the same EDS, the library's own SDO server.

Each server is a process of its own on python-can's ``udp_multicast`` interface (its own group
and port); rounds alternate floor and drive, the figure is the median. Target: drive / floor
>= 0.9.

Bus timing: frames per second of 8-byte frames (worst-case stuffing) that the model's
:class:`~devices.canopen.bus_timing.CanLine` carries in one simulated second, and SDO round
trips per simulated second of the pure node stepped at the rig's 1 ms cycle, each against the
physical bound at that bit rate.

    python -m bench canopen [--quick] [--seconds 2] [--rounds 3] [--timing-only]
"""

from __future__ import annotations

import argparse
import os
import random
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EDS = ROOT / "static" / "eds" / "servo_drive.eds"
TARGET_RATIO = 0.9
NODE = 1
INDEX, SUB = 0x6064, 0  # position actual value, INTEGER32: an expedited upload
N1_1MBIT = 8
STEP_US = 1_000
SIM_SECOND_US = 1_000_000


# ---- the servers (child processes) -----------------------------------------------------------
def _serve_drive(channel: str) -> None:
    from app.canopen_bus import CanOpenBus
    from app.rig_config import build_rig, parse_rig_spec
    from app.runtime import Runtime
    from devices.canopen.node import CanOpenNode

    # The default rig's drive alone (its other devices are measured by benchmark 1), on
    # CANopen at 1 Mbit/s.
    spec = parse_rig_spec(f'[rig]\nname = "CANopen drive"\nseed = 1\n\n[[servo]]\n'
                          f'id = "drive"\nfieldbus = "canopen"\nnode_id = {NODE}\n'
                          f'parameters = {{ n1 = {N1_1MBIT} }}\n', "<CANopen drive>")
    rig = build_rig(spec, state_dir=None)
    runtime = Runtime(rig)
    nodes = [d for d in rig.devices.values() if isinstance(d, CanOpenNode)]
    bus = CanOpenBus(nodes, runtime.submit, "udp_multicast", channel)
    bus.attach(runtime)
    bus.start()
    runtime.start()
    for powered in runtime.power_on():  # as `python -m app` starts it
        powered.result(5)
    deadline = time.monotonic() + 10
    while not runtime.submit(lambda: nodes[0].state.label != "Initialisation" and
                             nodes[0].active).result(5):
        if time.monotonic() > deadline:
            raise RuntimeError("the drive's CANopen node did not boot")
        time.sleep(0.01)
    print("ready", flush=True)
    sys.stdin.read()  # until the parent closes our stdin
    bus.stop()
    runtime.stop()


def _serve_floor(channel: str) -> None:
    import canopen

    from app.canopen_bus import open_bus

    network = canopen.Network(open_bus("udp_multicast", channel))  # loopback, as the drive's
    node = canopen.LocalNode(NODE, str(EDS))
    network.add_node(node)
    node.sdo[INDEX].raw = 0  # a value to serve (the EDS gives 0x6064 no default)
    network.connect()
    print("ready", flush=True)
    sys.stdin.read()
    network.disconnect()


class Server:
    """A server process on its own multicast group and port."""

    def __init__(self, kind: str, channel: str) -> None:
        self.kind, self.channel = kind, channel
        self.proc = subprocess.Popen([sys.executable, "-m", "bench.canopen", "serve", kind,
                                      channel], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, cwd=ROOT)
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if line.strip() != "ready":
            self.close()
            raise RuntimeError(f"{kind} CANopen server did not start (said {line!r})")

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def _channels() -> dict[str, str]:
    """A fresh multicast group and port per server: no crosstalk with tests running meanwhile."""
    rng = random.Random(os.getpid() ^ time.monotonic_ns())
    return {kind: f"239.74.{rng.randrange(200, 250)}.{rng.randrange(1, 250)}:"
                  f"{rng.randrange(46000, 49000)}" for kind in ("floor", "drive")}


# ---- the master (this process) ---------------------------------------------------------------
def _uploads_per_s(channel: str, seconds: float) -> float:
    import canopen

    from app.canopen_bus import open_bus

    network = canopen.Network(open_bus("udp_multicast", channel))
    node = canopen.RemoteNode(NODE, str(EDS))
    node.sdo.RESPONSE_TIMEOUT = 2.0
    network.add_node(node)
    network.connect()
    try:
        end = time.monotonic() + 0.2  # warm-up
        while time.monotonic() < end:
            node.sdo.upload(INDEX, SUB)
        count, start = 0, time.monotonic()
        while time.monotonic() < start + seconds:
            data = node.sdo.upload(INDEX, SUB)
            if len(data) != 4:
                raise RuntimeError(f"0x{INDEX:04X} upload of {len(data)} bytes")
            count += 1
        return count / (time.monotonic() - start)
    finally:
        network.disconnect()


@dataclass
class Throughput:
    drive: float
    floor: float

    @property
    def ratio(self) -> float:
        return self.drive / self.floor


def run_throughput(seconds: float, rounds: int) -> Throughput:
    servers = {kind: Server(kind, channel) for kind, channel in _channels().items()}
    got: dict[str, list[float]] = {"floor": [], "drive": []}
    try:
        for _ in range(rounds):
            for kind, server in servers.items():
                got[kind].append(_uploads_per_s(server.channel, seconds))
    finally:
        for server in servers.values():
            server.close()
    return Throughput(statistics.median(got["drive"]), statistics.median(got["floor"]))


# ---- the bus-timing model against physics (pure, simulated time) -----------------------------
@dataclass
class Timing:
    kbit: int
    frame_bits: int
    physical_frames: float
    model_frames: int
    physical_sdo: float
    model_sdo: int


def model_frames_per_s(bitrate: int) -> int:
    """8-byte frames the modelled line completes in one simulated second when a busy master
    keeps it saturated: each 1 ms step it tops the line up and takes what finished."""
    from devices.canopen.bus_timing import CanFrame, CanLine, frame_time_us

    line = CanLine(bitrate)
    per_step = -(-STEP_US // frame_time_us(8, bitrate)) + 1  # more than one step carries
    done = 0
    for t in range(0, SIM_SECOND_US, STEP_US):
        for i in range(per_step):
            line.offer(CanFrame(0x200 + i, bytes(8)), t)
        while line.next_done(t + STEP_US) is not None:
            done += 1
    return done


def model_sdo_per_s(n1: int) -> int:
    """SDO uploads per simulated second of the pure node at the 1 ms step, each request sent at
    the step after the previous answer left (as the rig's adapter hands frames over)."""
    from devices.canopen.node import CanOpenNode
    from devices.flash import MemoryFlash
    from devices.servo.drive import DriveConfig, ServoDrive

    drive = ServoDrive("servo", random.Random(1), DriveConfig(
        fieldbus="canopen", node_id=NODE, parameters={"n1": n1}), MemoryFlash())
    node = CanOpenNode("servo-can", drive)
    request = bytes((0x40,)) + INDEX.to_bytes(2, "little") + bytes((SUB, 0, 0, 0, 0))
    t = 0
    while node.state.label == "Initialisation" or not node.active:
        t += STEP_US
        drive.step(t)
        node.step(t)
    node.take_frames()
    answers, start, waiting = 0, t, False
    while t < start + SIM_SECOND_US:
        if not waiting:
            node.receive(0x600 + NODE, request)
            waiting = True
        t += STEP_US
        drive.step(t)
        node.step(t)
        if any(f.can_id == 0x580 + NODE for f in node.take_frames()):
            answers += 1
            waiting = False
    return answers


def run_timing() -> list[Timing]:
    from devices.canopen.bus_timing import frame_bits
    from devices.servo.parameters import CAN_KBAUD_BY_N1

    bits = frame_bits(8)
    rows = []
    for n1 in (4, 8):  # 125 kbit/s and 1 Mbit/s
        bitrate = CAN_KBAUD_BY_N1[n1] * 1000
        rows.append(Timing(CAN_KBAUD_BY_N1[n1], bits, bitrate / bits,
                           model_frames_per_s(bitrate), bitrate / (2 * bits),
                           model_sdo_per_s(n1)))
    return rows


# ---- output ----------------------------------------------------------------------------------
def report(result: Throughput | None, timing: list[Timing]) -> list[str]:
    lines = []
    bound = next((row.model_sdo for row in timing if row.kbit == 1000), None)
    if result is not None:
        verdict = "ok" if result.ratio >= TARGET_RATIO else "BELOW"
        lines += [f"CANopen SDO expedited upload 0x{INDEX:04X}, canopen master, udp_multicast, "
                  f"1 Mbit/s",
                  f"{'drive up/s':>11} {'floor up/s':>11} {'ratio':>7}  target",
                  f"{result.drive:>11.0f} {result.floor:>11.0f} {result.ratio:>7.2f}  "
                  f">= {TARGET_RATIO} {verdict}"]
        if bound:
            lines.append(f"  drive / the model's own bound ({bound} up/s at the 1 ms step): "
                         f"{result.drive / bound:.2f}")
    lines += ["CAN bus-timing model vs physical bound (8-byte frames, worst-case stuffing)",
              f"{'kbit/s':>7} {'bits':>5} {'phys fr/s':>10} {'model fr/s':>11} "
              f"{'phys SDO/s':>11} {'model SDO/s':>12}"]
    for row in timing:
        lines.append(f"{row.kbit:>7} {row.frame_bits:>5} {row.physical_frames:>10.0f} "
                     f"{row.model_frames:>11} {row.physical_sdo:>11.0f} {row.model_sdo:>12}")
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench canopen",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true",
                   help="one short round (a smoke test, not a figure)")
    p.add_argument("--seconds", type=float, default=2.0, help="wall time per measurement")
    p.add_argument("--rounds", type=int, default=3, help="alternating rounds per server")
    p.add_argument("--timing-only", action="store_true", help="skip the live throughput run")
    sub = p.add_subparsers(dest="verb")
    serve = sub.add_parser("serve", help="(internal) run one server process")
    serve.add_argument("kind", choices=("drive", "floor"))
    serve.add_argument("channel", help="GROUP:PORT")
    args = p.parse_args(argv)
    if args.verb == "serve":
        (_serve_drive if args.kind == "drive" else _serve_floor)(args.channel)
        return 0
    if args.quick:
        args.seconds, args.rounds = 0.5, 1
    result = None if args.timing_only else run_throughput(args.seconds, args.rounds)
    print("\n".join(report(result, run_timing())), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
