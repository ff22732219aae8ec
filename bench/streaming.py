"""Benchmark 3 (issue 7): what the dashboard streams, and how late it arrives with many viewers.

The server is the default rig live at real-time speed behind the dashboard as shipped, in a
process of its own. The clients are Python websocket clients speaking viser's protocol (the
``viser-v<version>`` subprotocol; each binary frame is one window of messages: two 8-byte
lengths, zstd-compressed msgpack, raw buffers). They stand in for browsers: each sends the
camera message a browser's viewer sends first (viser counts a page from then on, and the
dashboard draws only while a page is counted: ``bench/_viser_page.py``), then receives what a
browser receives, byte for byte, but renders nothing, so 10 and 50 of them cost the machine
far less than 10 or 50 Chromium pages would.

- **bytes/s and messages/s to one client** for an idle rig (LEDs blinking: RUN of the FastCAT
  in OP, L/A flickering) and for a rig in motion (AX2 shafts turning, an analog input moving,
  every servo drive jogging), 10 s each, counted once the drive plots' 20 s window has filled
  (a chart's data is sent whole, so a filling window understates it; ``--quick`` counts after
  1 s and says so);
- **update latency** with 1, 10 and 50 clients: the server writes, after each dashboard
  update, the publication instant of the frame it showed into one extra markdown ("probe");
  the clients take the receive instant minus that (both are CLOCK_MONOTONIC of one machine):
  from the frame's publication by the runtime to its arrival at each client; p50 and p95;
- **clicking** (``bench/_stream_clicks.py``): bytes/s and messages/s to a watching page and to
  the clicking page, idle and while one page clicks a control 5 times a second, with 1 and
  10 pages watching; ``--trees`` runs other checkouts' servers side by side in the same run.

No target is set for these in issue 7 beyond "send only what changed" (docs/performance.md).

    python -m bench streaming [--quick] [--clicking-only] [--trees DIR,DIR]
"""

from __future__ import annotations

import argparse
import asyncio
import re
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.ui.drive.plots import WINDOW_S
from bench import _stream_clicks
from bench._browser import ServerProcess, serve_dashboard
from bench._viser_page import page, window

PROBE = re.compile(rb"probe (\d+) (\d+\.\d+)")
CLIENT_COUNTS = (1, 10, 50)


# ---- the server (a child process) ------------------------------------------------------------
def _serve(port: int, motion: bool, probe: bool) -> None:
    from app.runtime import Frame
    from app.ui.dashboard import Dashboard
    from bench.kernel import in_op
    from bench.kernel import motion as motion_workload

    published: dict[int, float] = {}

    class ProbedDashboard(Dashboard):
        """The dashboard as shipped, plus one markdown: when the frame it shows was published."""

        def __init__(self, *args: Any) -> None:
            super().__init__(*args)
            self._probe_seq = -1
            self._probe = self.server.gui.add_markdown("probe")

        def tick(self) -> None:
            super().tick()
            stamp = published.get(self.rendered_seq)
            if stamp is not None and self._probe_seq != self.rendered_seq:
                self._probe_seq = self.rendered_seq
                self._probe.content = f"probe {self.rendered_seq} {stamp:.6f}"

    def on_frame(frame: Frame) -> None:
        published[frame.seq] = time.monotonic()
        published.pop(frame.seq - 1000, None)

    def setup(rig: Any, runtime: Any, _dashboard: Any) -> None:
        runtime.add_frame_listener(on_frame)
        deadline = time.monotonic() + 30  # as a viewer would find it: booted, in OP
        while (not runtime.submit(lambda: in_op(rig)).result(10)
               and time.monotonic() < deadline):
            time.sleep(0.1)
        if motion:  # the kernel benchmark's workload, applied in the simulation thread
            each = runtime.submit(lambda: motion_workload(rig)).result(10)
            runtime.add_step_listener(lambda now_us: each(now_us // rig.clock.step_us))

    serve_dashboard(port, ProbedDashboard if probe else None, setup)


def start_server(motion: bool, probe: bool) -> ServerProcess:
    return ServerProcess("bench.streaming", "motion" if motion else "idle",
                         "probe" if probe else "plain", what="streaming server")


# ---- the clients -----------------------------------------------------------------------------
@dataclass
class Tally:
    frames: int = 0
    messages: int = 0
    bytes: int = 0
    latencies_ms: list[float] = field(default_factory=list)


async def _client(port: int, warmup_s: float, seconds: float, tally: Tally) -> None:
    """Count from ``warmup_s`` after the first window (the backlog of a new connection: the
    whole GUI and scene) for ``seconds``."""
    import msgspec
    import zstandard

    unzip = zstandard.ZstdDecompressor()
    async with page(port) as (ws, _backlog):
        start_at = time.monotonic() + warmup_s
        end_at = start_at + seconds
        while (now := time.monotonic()) < end_at:
            try:
                raw = await asyncio.wait_for(ws.recv(), timeout=end_at - now)
            except TimeoutError:
                break
            received = time.monotonic()
            if received < start_at or not isinstance(raw, bytes):
                continue
            inner = window(raw, unzip)
            tally.frames += 1
            tally.bytes += len(raw)
            tally.messages += len(msgspec.msgpack.decode(inner)["messages"])
            tally.latencies_ms += [(received - float(m[2])) * 1000 for m in PROBE.finditer(inner)]


def listen(port: int, clients: int, warmup_s: float, seconds: float) -> list[Tally]:
    tallies = [Tally() for _ in range(clients)]

    async def main() -> None:
        await asyncio.gather(*(_client(port, warmup_s, seconds, t) for t in tallies))
    asyncio.run(main())
    return tallies


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))] if ordered else 0.0


def report(quick: bool, clicking_only: bool = False, trees: list[Path] | None = None
           ) -> list[str]:
    if clicking_only:
        return ["Streaming while a page clicks", *_stream_clicks.report(quick, trees or [])]
    warmup, seconds = (1.0, 3.0) if quick else (2.0, 10.0)
    # The server's rig runs at real time from its start, so simulated time = wall time.
    steady = warmup if quick else WINDOW_S + warmup
    out = ["Streaming: the dashboard as shipped, default rig at real time, Python websocket "
           "clients speaking viser's protocol (stand-ins for browsers)",
           f"  one client counted from {steady:g} s: the plots' {WINDOW_S:g} s window "
           + ("NOT yet full (--quick)" if quick else "full")]
    for motion in (False, True):
        server = start_server(motion, probe=False)
        try:
            tally = listen(server.port, 1, steady, seconds)[0]
        finally:
            server.close()
        out.append(f"  one client, {'in motion' if motion else 'idle (LEDs blinking)':<22} "
                   f"{tally.bytes / seconds / 1000:8.1f} kB/s  {tally.messages / seconds:7.1f} "
                   f"messages/s  {tally.frames / seconds:5.1f} windows/s")
    server = start_server(motion=False, probe=True)
    try:
        for count in CLIENT_COUNTS[:2] if quick else CLIENT_COUNTS:
            tallies = listen(server.port, count, warmup, seconds)
            lat = [x for t in tallies for x in t.latencies_ms]
            received = sum(t.bytes for t in tallies) / seconds / 1000
            out.append(f"  update latency, {count:>2} client{'s' if count > 1 else ' '}  "
                       f"p50 {statistics.median(lat) if lat else 0:7.1f} ms  "
                       f"p95 {percentile(lat, 0.95):7.1f} ms  ({len(lat)} updates, "
                       f"{received:.0f} kB/s to all)")
    finally:
        server.close()
    out += _stream_clicks.report(quick, trees or [])
    out.append("  no target in issue 7: send only what changed (docs/performance.md)")
    return out


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["serve"]:
        _serve(int(argv[1]), argv[2] == "motion", argv[3] == "probe")
        return 0
    p = argparse.ArgumentParser(prog="python -m bench streaming",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true", help="short runs, up to 10 clients")
    p.add_argument("--clicking-only", action="store_true", help="only the clicking case")
    p.add_argument("--trees", default="",
                   help="comma-separated checkouts whose servers the clicking case also runs")
    args = p.parse_args(argv)
    trees = [Path(t).resolve() for t in args.trees.split(",") if t]
    print("\n".join(report(args.quick, args.clicking_only, trees)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
