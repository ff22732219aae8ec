"""Benchmark 4 (issue 7): Modbus request/response pairs per second, the drive against the floor.

Two servers, each in a process of its own, measured side by side in one run by the same
pymodbus async clients in this process:

- **drive**: the default rig (FastCAT, master, servo drive) live in :class:`app.runtime.Runtime`
  at real-time speed, its drive behind :class:`app.modbus.server.DriveModbusServer` as
  ``python -m app`` serves it: every request answered in the server's loop between two
  simulation steps (``Runtime.call``); the drive's simulated clock rate over the run is printed
  too, to show the requests do not hold the simulation up;
- **floor**: a plain pymodbus ``ModbusTcpServer`` with static register blocks of the same size
  (addresses 1..99, where the drive's 57 parameters are, and R00..R133 at 0x8000 as 268 words).

Each client repeats one FC 03 poll a master would send (R05 status word + R06 position, four
words at 0x8005) for a fixed wall time. Rounds alternate floor and drive so that a slow moment
of the machine hits both; the figure is the median of the rounds. Target: drive / floor >= 0.9.

    python -m bench modbus [--quick] [--seconds 2] [--rounds 3] [--clients 1,4] [--framer rtu]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass

TARGET_RATIO = 0.9
UNIT = 1
POLL_ADDRESS = 0x8005  # R05 status word, R06 position actual value (high word first)
POLL_COUNT = 4
REGISTER_BASE = 0x8000
REGISTER_WORDS = 2 * 134  # R00..R133, 32 bit each
PARAMETER_LAST = 99
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


# ---- the servers (child processes) -----------------------------------------------------------
def _serve_drive(framer: str) -> None:
    from app.modbus.server import DriveModbusServer
    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.runtime import Runtime
    from devices.servo.drive import ServoDrive

    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    runtime = Runtime(rig)
    runtime.start()
    for powered in runtime.power_on():  # as `python -m app` starts it
        powered.result(5)
    drives = [d for d in rig.devices.values() if isinstance(d, ServoDrive)]
    server = DriveModbusServer(drives, runtime.submit, port=0, framer=framer,
                               call=runtime.call)  # as python -m app serves it
    server.start_in_thread()
    wall0, sim0 = time.monotonic(), runtime.call(lambda: rig.clock.now_us)
    print(server.port, flush=True)
    sys.stdin.read()  # until the parent closes our stdin
    wall, sim = time.monotonic() - wall0, runtime.call(lambda: rig.clock.now_us) - sim0
    # Requests run between steps: the simulation must keep its pace while they come.
    print(f"clock {sim / 1e6 / wall:.3f}", flush=True)
    server.stop_in_thread()
    runtime.stop()


def _serve_floor(framer: str) -> None:
    from pymodbus.framer import FramerType
    from pymodbus.server import ModbusTcpServer
    from pymodbus.simulator import DataType, SimData, SimDevice

    async def main() -> None:
        device = SimDevice(id=UNIT, simdata=[
            SimData(1, count=PARAMETER_LAST, values=50, datatype=DataType.REGISTERS),
            SimData(REGISTER_BASE, count=REGISTER_WORDS, values=0,
                    datatype=DataType.REGISTERS),
        ])
        server = ModbusTcpServer(device, framer=FramerType(framer), address=("127.0.0.1", 0))
        await server.serve_forever(background=True)
        print(server.transport.sockets[0].getsockname()[1], flush=True)  # type: ignore[union-attr]
        await asyncio.to_thread(sys.stdin.read)
        await server.shutdown()

    asyncio.run(main())


class Server:
    """A server process; ``port`` once it listens."""

    def __init__(self, kind: str, framer: str) -> None:
        self.kind = kind
        self.clock: float | None = None  # the drive's simulated seconds per wall second
        self.proc = subprocess.Popen([sys.executable, "-m", "bench.modbus", "serve", kind,
                                      "--framer", framer], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, cwd=ROOT)
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line.strip().isdigit():
            self.close()
            raise RuntimeError(f"{kind} server did not start (said {line!r})")
        self.port = int(line)

    def close(self) -> None:
        try:
            out, _ = self.proc.communicate(timeout=10)  # closes stdin: the server stops
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return
        for line in (out or "").splitlines():
            if line.startswith("clock "):
                self.clock = float(line.split()[1])


# ---- the clients (this process) --------------------------------------------------------------
async def _client_loop(port: int, framer: str, until: float, counts: list[int], i: int) -> None:
    from pymodbus.client import AsyncModbusTcpClient
    from pymodbus.framer import FramerType

    client = AsyncModbusTcpClient("127.0.0.1", port=port, framer=FramerType(framer),
                                  timeout=5, retries=0)
    await client.connect()
    try:
        while time.monotonic() < until:
            reply = await client.read_holding_registers(POLL_ADDRESS, count=POLL_COUNT,
                                                        device_id=UNIT)
            if reply.isError() or len(reply.registers) != POLL_COUNT:
                raise RuntimeError(f"bad reply on port {port}: {reply}")
            counts[i] += 1
    finally:
        client.close()


async def _measure(port: int, framer: str, clients: int, seconds: float) -> float:
    """Request/response pairs per second over ``clients`` concurrent connections."""
    counts = [0] * clients
    # a short warm-up: connections up, caches and the simulation thread's queue warm
    await asyncio.gather(*(_client_loop(port, framer, time.monotonic() + 0.2, [0] * clients, i)
                           for i in range(clients)))
    start = time.monotonic()
    await asyncio.gather(*(_client_loop(port, framer, start + seconds, counts, i)
                           for i in range(clients)))
    return sum(counts) / (time.monotonic() - start)


@dataclass
class Row:
    clients: int
    drive: float
    floor: float

    @property
    def ratio(self) -> float:
        return self.drive / self.floor


def run(seconds: float, rounds: int, client_counts: list[int],
        framer: str) -> tuple[list[Row], float | None]:
    """The rows, and the drive's simulated clock rate over the whole run (1.0: real time)."""
    servers = {kind: Server(kind, framer) for kind in ("floor", "drive")}
    rows = []
    try:
        for clients in client_counts:
            got: dict[str, list[float]] = {"floor": [], "drive": []}
            for _ in range(rounds):
                for kind, server in servers.items():
                    got[kind].append(asyncio.run(_measure(server.port, framer, clients,
                                                          seconds)))
            rows.append(Row(clients, statistics.median(got["drive"]),
                            statistics.median(got["floor"])))
    finally:
        for server in servers.values():
            server.close()
    return rows, servers["drive"].clock


def report(rows: list[Row], framer: str, clock: float | None = None) -> list[str]:
    lines = [f"Modbus ({framer} framing), FC 03 x{POLL_COUNT} words, pymodbus async clients",
             f"{'clients':>8} {'drive req/s':>12} {'floor req/s':>12} {'ratio':>7}  target"]
    for row in rows:
        verdict = "ok" if row.ratio >= TARGET_RATIO else "BELOW"
        lines.append(f"{row.clients:>8} {row.drive:>12.0f} {row.floor:>12.0f} "
                     f"{row.ratio:>7.2f}  >= {TARGET_RATIO} {verdict}")
    if clock is not None:
        lines.append(f"  the drive's simulated clock meanwhile: {clock:.3f} s per wall second "
                     "(1.0: the requests did not hold the simulation up)")
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench modbus",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true",
                   help="one short round, one client (a smoke test, not a figure)")
    p.add_argument("--seconds", type=float, default=2.0, help="wall time per measurement")
    p.add_argument("--rounds", type=int, default=3, help="alternating rounds per server")
    p.add_argument("--clients", default="1,4", help="concurrent clients, comma-separated")
    p.add_argument("--framer", choices=("socket", "rtu"), default="socket")
    sub = p.add_subparsers(dest="verb")
    serve = sub.add_parser("serve", help="(internal) run one server process")
    serve.add_argument("kind", choices=("drive", "floor"))
    serve.add_argument("--framer", choices=("socket", "rtu"), default="socket")
    args = p.parse_args(argv)
    if args.verb == "serve":
        (_serve_drive if args.kind == "drive" else _serve_floor)(args.framer)
        return 0
    clients = [int(c) for c in args.clients.split(",")]
    if args.quick:
        args.seconds, args.rounds, clients = 0.5, 1, [1]
    rows, clock = run(args.seconds, args.rounds, clients, args.framer)
    print("\n".join(report(rows, args.framer, clock)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
