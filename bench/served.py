"""What a served rig costs beyond the simulation kernel (issue 7, benchmark 1's classroom).

``python -m app`` serves each rig through a :class:`app.runtime.Runtime`: a thread that keeps
the simulated clock on the wall clock and publishes a snapshot of the rig 30 times a second for
the views. The kernel benchmark measures the models alone; this one measures the same rigs
served, in one process, without a browser (the dashboard and each browser cost more on top:
benchmark 3, docs/scaling.md):

- the kernel alone: CPU per simulated millisecond of one rig idle in OP (``Rig.step`` in a loop);
- one snapshot of the rig (``Rig.snapshot``), and what 30 a second cost;
- 1 and 3 rigs served for some seconds of wall time, idle (nobody talks to them) and busy (a
  no-op queued on each every 100 ms, as a browser or a protocol client does, which keeps the
  simulation thread on 1 ms wake-ups): how far each rig's clock kept up with the wall clock, and
  the process's CPU per simulated millisecond per rig, i.e. the share of a core one served rig
  takes;
- one rig served idle and recorded as ``python -m app`` records it (a Rerun file, samples every
  10 ms), with the recorder repeating its last sample while the rig's revision stands, and in
  the same run with a snapshot at every sample (docs/recording.md "Repeated samples").

CPU is ``time.process_time()`` (every thread of this process). Method and figures:
docs/performance.md "Served rigs".

    python -m bench served [--quick] [--rig FILE]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
import time
from pathlib import Path

from app.recording.recorder import RigRecorder, attach_to_runtime
from app.rig_config import DEFAULT_RIG, RigSpec, build_rig, load_rig_spec
from app.runtime import Runtime
from bench.kernel import boot, run

PUBLISH_HZ = 30.0  # the runtime's default, what python -m app uses
BUSY_PERIOD_S = 0.1


def kernel_us(spec: RigSpec, seconds: float) -> float:
    """CPU microseconds per simulated millisecond of one rig idle in OP, stepped in a loop."""
    rig = build_rig(spec, state_dir=None)
    boot([rig])
    return run([rig], seconds) / seconds * 1000.0


def snapshot_us(spec: RigSpec, count: int = 200) -> float:
    rig = build_rig(spec, state_dir=None)
    boot([rig])
    start = time.process_time()
    for _ in range(count):
        rig.snapshot()
    return (time.process_time() - start) / count * 1e6


def served(spec: RigSpec, count: int, wall_s: float, busy: bool,
           record: bool | None = None) -> tuple[float, float]:
    """(the slowest rig's simulated seconds per wall second, CPU µs per simulated ms per rig).
    ``record``: recorded to a file, repeating samples (True) or not (False)."""
    rigs = [build_rig(spec, state_dir=None) for _ in range(count)]
    boot(rigs)
    runtimes = [Runtime(rig, publish_hz=PUBLISH_HZ) for rig in rigs]
    with tempfile.TemporaryDirectory() as tmp:
        recorders = [RigRecorder(Path(tmp) / f"rig{i}.rrd") for i in range(count)] \
            if record is not None else []
        for runtime, recorder in zip(runtimes, recorders, strict=False):
            attach_to_runtime(runtime, recorder, repeat=bool(record))
        try:
            return _serve(rigs, runtimes, wall_s, busy)
        finally:
            for recorder in recorders:
                recorder.close()


def _serve(rigs: list, runtimes: list[Runtime], wall_s: float,
           busy: bool) -> tuple[float, float]:
    starts = [rig.clock.now_us for rig in rigs]
    stop = threading.Event()

    def talk() -> None:
        while not stop.wait(BUSY_PERIOD_S):
            for runtime in runtimes:
                runtime.submit(lambda: None)

    talker = threading.Thread(target=talk, daemon=True) if busy else None
    cpu0, wall0 = time.process_time(), time.monotonic()
    for runtime in runtimes:
        runtime.start()
    if talker is not None:
        talker.start()
    time.sleep(wall_s)
    stop.set()
    for runtime in runtimes:
        runtime.stop()
    cpu, wall = time.process_time() - cpu0, time.monotonic() - wall0
    simulated = [(rig.clock.now_us - t0) / 1e6 for rig, t0 in zip(rigs, starts, strict=True)]
    return min(simulated) / wall, cpu / sum(simulated) * 1000.0


def report(spec: RigSpec, name: str, wall_s: float, counts: tuple[int, ...]) -> list[str]:
    kernel = kernel_us(spec, 3.0)
    snap = snapshot_us(spec)
    out = [f"Served rigs: {name}, CPU per simulated ms per rig (= % of a core / 10)",
           f"  kernel alone, idle in OP (Rig.step in a loop)        {kernel:7.1f} us",
           f"  one snapshot {snap / 1000:.2f} ms; at {PUBLISH_HZ:g} Hz                      "
           f"{snap * PUBLISH_HZ / 1000:7.1f} us"]
    for busy in (False, True):
        mode = "busy (work queued every 100 ms)" if busy else "idle (nobody talks to it)"
        for count in counts:
            pace, per_ms = served(spec, count, wall_s, busy)
            label = f"{count} rig{'s' if count > 1 else ' '} served, {mode}"
            out.append(f"  {label:<52} {per_ms:7.1f} us  (the slowest clock at "
                       f"{pace:.2f}x wall time)")
    for record, how in ((True, "repeating samples"), (False, "a snapshot per sample")):
        pace, per_ms = served(spec, 1, wall_s, False, record)
        label = f"1 rig  served, idle, recorded ({how})"
        out.append(f"  {label:<52} {per_ms:7.1f} us  (the slowest clock at {pace:.2f}x wall time)")
    out.append("  no target in issue 7: the gap to the kernel is the runtime's wake-ups and "
               "snapshots (docs/performance.md)")
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench served",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true", help="short runs, one rig (a smoke test)")
    p.add_argument("--rig", type=Path, default=DEFAULT_RIG, metavar="TOML",
                   help="the rig file (default: the default rig)")
    args = p.parse_args(argv)
    wall_s, counts = (1.5, (1,)) if args.quick else (6.0, (1, 3))
    for text in report(load_rig_spec(args.rig), args.rig.name, wall_s, counts):
        print(text, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
