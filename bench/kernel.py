"""Benchmark 1 (issue 7): simulation kernel speed, in simulated seconds per CPU second.

Rigs are built from rig specs as ``python -m app`` builds them (every flash in memory) and
stepped by :meth:`app.rig.Rig.step` at the 1 ms cycle, all in one loop in this process. CPU time
is ``time.process_time()``, so other work on a shared machine costs this process less than
wall time would. A figure of 20x means 20 simulated seconds per CPU second.

Figures, each with its target (issue 7 sets two: the default rig >= 20x on one core, and 100
default rigs in real time on one core, i.e. >= 1x for the hundred together):

- each rig file (``static/rigs/default.toml`` as shipped and ``ethercat_line.toml``, the full
  line master -> FastCAT -> TRS-CAT -> CPX-E-EC -> drive; ``--rig FILE`` for others): the first
  5 s from power-on (internal-bus scan, master walking to OP), idle in OP, cyclic (the
  Reset-fault bit of the coupler's RxPDO written through the object dictionary every cycle, as
  a master writes its process image) and in motion (AX2 shafts turning, an analog input moving
  every 10 ms, analog outputs ramping to a new target every 250 ms, every servo drive enabled
  and jogging one way then the other each second, all through rig commands); then CPU per
  step by device;
- the FastCAT line: the first rig with its couplers and master only (the default rig issue 7
  was written against);
- 1, 10 and 100 rigs of each stepped together in one loop, idle in OP, after all of them booted
  (a count that would take more than 25 s of CPU is projected from the one before, and says so),
  and beside them the floor: the same rig's device ids stepped as models that do nothing
  (bench/_kernel_floor.py), what the loop and the calls alone cost;
- 1, 4, 8 and 16 modules on one coupler (a mix of digital, analog and encoder modules with at
  most 8 analog ones), idle and cyclic.

Method and latest figures: docs/performance.md.

    python -m bench kernel [--quick] [--rig FILE ...]
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, RigSpec, build_rig, load_rig_spec, parse_rig_spec
from bench._kernel_floor import floor_line
from devices.device import CommandError
from devices.ethercat import AlState
from devices.fastcat.coupler import FastCat
from devices.servo.drive import ServoDrive

TARGET_ONE = 20.0  # x real time: one default rig on one core
TARGET_MANY = 1.0  # x real time for 100 default rigs stepped together on one core
MANY = 100
# Steps per Rig.advance in the "advanced" figures: a runtime without per-step observers and
# `scenario run` advance a rig by what is due, not one step per call (docs/performance.md).
BATCH_STEPS = 10
BOOT_LIMIT_S = 12.0  # power-on to OP takes about 3.5 s with seven modules
MIX = ("DB16", "DI16", "DO16", "AI8D", "AO4", "AI8TC", "AX2", "AI8C")  # 4 analog per 8
MODULE_COUNTS = (1, 4, 8, 16)
# The rig files measured: the default rig as shipped and the full EtherCAT line of issue 5.
RIG_FILES = (DEFAULT_RIG, DEFAULT_RIG.parent / "ethercat_line.toml")


@dataclass(frozen=True)
class Durations:
    """Simulated seconds measured per figure (the 100-rig loop runs a shorter span)."""

    power_on: float = 5.0
    one: float = 5.0
    loaded: float = 5.0
    group: float = 2.0
    many: float = 0.5
    modules: float = 3.0
    budget: float = 25.0  # CPU seconds a rig count may take (boot included) before projecting


QUICK = Durations(power_on=1.0, one=1.0, loaded=1.0, group=0.5, many=0.1, modules=0.5,
                  budget=5.0)


# ---- rigs ------------------------------------------------------------------------------------
def default_spec() -> RigSpec:
    return load_rig_spec(DEFAULT_RIG)


def fastcat_line_spec(spec: RigSpec) -> RigSpec:
    """The same rig with its couplers and the master only."""
    # No network description: the rig file's ENI / mapping name the slaves left out here.
    network = {name: None for name in ("eni", "mapping") if hasattr(spec, name)}
    return replace(spec, source=f"{spec.source} (FastCAT line)", servos=(), slaves=(),
                   line=tuple(fc.id for fc in spec.fastcats), **network)


def modules_spec(count: int) -> RigSpec:
    """A rig file (docs/rig-file.md) with one coupler carrying ``count`` modules of the mix."""
    names = ", ".join(f'"{MIX[i % len(MIX)]}"' for i in range(count))
    return parse_rig_spec(f'[rig]\nname = "{count} modules"\nseed = 1\n\n'
                          f'[[fastcat]]\nid = "fastcat"\nmodules = [{names}]\n',
                          f"<{count} modules>")


def couplers(rig: Rig) -> list[FastCat]:
    return [d for d in rig.devices.values() if isinstance(d, FastCat)]


def in_op(rig: Rig) -> bool:
    """Every coupler in OP with its scan done, every slave on the master's line in OP."""
    if not all(fc.al_state is AlState.OP and fc.scan is None for fc in couplers(rig)):
        return False
    master = rig.devices.get("master")
    links = getattr(master, "links", [])
    return all(link.slave.al_state is AlState.OP for link in links)


def boot(rigs: Sequence[Rig]) -> None:
    """Power-on to OP (every coupler), then one more second."""
    limit_us = round(BOOT_LIMIT_S * 1_000_000)
    while not all(in_op(r) for r in rigs):
        if rigs[0].clock.now_us > limit_us:
            raise RuntimeError(f"{rigs[0].name}: not in OP after {BOOT_LIMIT_S} s")
        for rig in rigs:
            rig.step()
    run(rigs, 1.0)


def run(rigs: Sequence[Rig], seconds: float,
        each_step: Callable[[int], None] | None = None) -> float:
    """Step every rig ``seconds`` of simulated time; CPU seconds it took."""
    steps = round(seconds * 1_000_000 / rigs[0].clock.step_us)
    start = time.process_time()
    for i in range(steps):
        if each_step is not None:
            each_step(i)
        for rig in rigs:
            rig.step()
    return time.process_time() - start


def speed(seconds: float, cpu_s: float) -> float:
    return seconds / cpu_s if cpu_s > 0 else math.inf


# ---- workloads -------------------------------------------------------------------------------
def cyclic(rig: Rig) -> Callable[[int], None]:
    """The master's process image every cycle: 0x5200:1 Reset fault = 0 (RxPDO 0x16FF)."""
    ods = [fc.od for fc in couplers(rig) if fc.od is not None]

    def each(_i: int) -> None:
        for od in ods:
            od.write(0x5200, 1, 0)
    return each


def drives(rig: Rig) -> list[ServoDrive]:
    return [d for d in rig.devices.values() if isinstance(d, ServoDrive)]


def motion(rig: Rig) -> Callable[[int], None]:
    """Shafts turning, analog inputs moving, analog outputs ramping, every servo drive jogging
    one way then the other each second (rig commands)."""
    axes = [d.device_id for d in drives(rig)]
    for axis in axes:
        rig.apply(axis, "enable", {"on": True})
    inputs: list[str] = []
    outputs: list[tuple[str, int]] = []
    for fc in couplers(rig):
        for slot, module in enumerate(fc.rail, start=1):
            if module is None:
                continue
            target = f"{fc.device_id}/{slot}"
            if module.mtype.encoders:
                rig.apply(target, "set_shaft_speed", {"encoder": 1, "rpm": 600.0})
                rig.apply(target, "set_shaft_speed", {"encoder": 2, "rpm": -150.0})
            if module.mtype.ai:
                inputs.append(target)
            if module.mtype.ao:
                index = 0x7400 + 0x10 * (slot - 1)
                rig.apply(fc.device_id, "write_object",
                          {"index": 0x200A + 0x10 * (slot - 1), "sub": 1, "value": 2})
                outputs.append((fc.device_id, index))

    def each(i: int) -> None:
        if i % 1000 == 0:
            for axis in axes:
                with contextlib.suppress(CommandError):  # a drive powered off: it stays still
                    rig.apply(axis, "jog", {"direction": 1 if (i // 1000) % 2 == 0 else -1})
        if i % 10 == 0:
            for target in inputs:  # 0..5 and back over 2 s: in range of every input kind
                value = 2.5 + 2.5 * math.sin(i / 2000 * 2 * math.pi)
                rig.apply(target, "set_analog", {"channel": 1, "value": round(value, 3)})
        if i % 250 == 0:
            for device, index in outputs:
                value = 1000 if (i // 250) % 2 else -1000
                rig.apply(device, "write_object", {"index": index, "sub": 1, "value": value})
    return each


def per_device_us(rig: Rig, seconds: float) -> dict[str, float]:
    """Step time per device, in the order Rig.step uses: perf_counter around each device's
    step, the timer's own cost taken off, the slowest 1 % of the samples (the process was
    preempted) dropped. Wall time, so only the split: the speed figures are process time."""
    devices = list(rig.devices.items())
    samples: dict[str, list[int]] = {device_id: [] for device_id in rig.devices}
    steps = round(seconds * 1_000_000 / rig.clock.step_us)
    clock = time.perf_counter_ns
    overhead = statistics.median(-clock() + clock() for _ in range(10_000))
    for _ in range(steps):
        now = rig.clock.tick()
        for device_id, device in devices:
            start = clock()
            device.step(now)
            samples[device_id].append(clock() - start)
        rig.take_events()
    kept = max(1, steps * 99 // 100)
    return {device_id: max(0.0, statistics.fmean(sorted(ns)[:kept]) - overhead) / 1000
            for device_id, ns in samples.items()}


# ---- report ----------------------------------------------------------------------------------
def verdict(value: float, target: float) -> str:
    return f"(target >= {target:g}x) {'PASS' if value >= target else 'FAIL'}"


def line(label: str, value: float, target: float | None = None) -> str:
    text = f"    {label:<44} {value:8.1f}x real time"
    return f"{text}  {verdict(value, target)}" if target is not None else text


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            cpu = next((row.split(":", 1)[1].strip() for row in info
                        if row.startswith("model name")), cpu)
    except OSError:
        pass
    load = " ".join(f"{v:.1f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return (f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"load average {load}")


def one_rig(title: str, spec: RigSpec, d: Durations) -> list[str]:
    out = [f"  {title}"]
    rig = build_rig(spec, state_dir=None)
    out.append(line(f"power-on, first {d.power_on:g} s (scan, walk to OP)",
                    speed(d.power_on, run([rig], d.power_on)), TARGET_ONE))
    boot([rig])
    idle = [speed(d.one, run([rig], d.one)) for _ in range(3)]
    out.append(line("idle in OP (median of 3)", statistics.median(idle), TARGET_ONE))
    shares = per_device_us(rig, d.loaded)
    out.append("      per device, idle: " + ", ".join(
        f"{device_id} {us:.1f} us" for device_id, us in shares.items()) + " per step")
    out.append(line("cyclic (RxPDO written every cycle)",
                    speed(d.loaded, run([rig], d.loaded, cyclic(rig))), TARGET_ONE))
    out.append(line("in motion (AX2, analog in and out)",
                    speed(d.loaded, run([rig], d.loaded, motion(rig))), TARGET_ONE))
    return out


def run_spans(rigs: Sequence[Rig], seconds: float) -> tuple[float, float]:
    """Advance every rig ``seconds`` of simulated time, BATCH_STEPS steps at a time with
    :meth:`Rig.advance` (quiet spans skipped); (CPU seconds, share of the steps skipped)."""
    steps = round(seconds * 1_000_000 / rigs[0].clock.step_us)
    skipped = sum(r.skipped_steps for r in rigs)
    start = time.process_time()
    for _ in range(steps // BATCH_STEPS):
        for rig in rigs:
            rig.advance(BATCH_STEPS)
    cpu = time.process_time() - start
    share = (sum(r.skipped_steps for r in rigs) - skipped) / max(1, steps * len(rigs))
    return cpu, share


def many_rigs(title: str, spec: RigSpec, d: Durations, counts: Sequence[int]) -> list[str]:
    """Rigs stepped together, one step at a time, then advanced BATCH_STEPS at a time (quiet
    spans skipped, docs/performance.md "Quiet spans"). A count whose boot and run would cost
    more than the budget is not run: its figure is projected from the count before it, and
    says so."""
    out = [f"  {title}: rigs stepped together in one loop, idle in OP; each count stepped one "
           f"step at a time, then advanced {BATCH_STEPS} steps at a time"]
    boot_cpu = idle_cpu = span_cpu = 0.0  # per rig: CPU to boot, per simulated second idle
    for count in counts:
        seconds = d.many if count >= MANY else d.group if count > 1 else d.one
        target = TARGET_MANY if count >= MANY else None
        label = f"{count} rig{'s' if count > 1 else ''}"
        projected = count * (boot_cpu + (idle_cpu + span_cpu) * seconds)
        if idle_cpu and projected > d.budget:
            out.append(line(f"{label} (projected; {projected:.0f} s CPU to run)",
                            1 / (idle_cpu * count), target))
            out.append(line(f"{label}, advanced (projected)", 1 / (span_cpu * count), target))
            continue
        rigs = [build_rig(spec, state_dir=None) for _ in range(count)]
        start = time.process_time()
        boot(rigs)
        boot_cpu = (time.process_time() - start) / count
        cpu = run(rigs, seconds)
        idle_cpu = cpu / seconds / count
        together = speed(seconds, cpu)
        out.append(line(f"{label} ({together * count:.0f}x per rig)", together, target))
        cpu, share = run_spans(rigs, seconds)
        span_cpu = cpu / seconds / count
        together = speed(seconds, cpu)
        out.append(line(f"{label}, advanced ({together * count:.0f}x per rig, "
                        f"{share:.1%} of steps skipped)", together, target))
    out.append(floor_line(build_rig(spec, state_dir=None), spec.step_us,
                          steps=round(d.many * 100_000)))
    return out


def modules(d: Durations) -> list[str]:
    out = [f"  modules per coupler (FastCAT + master; mix {' '.join(MIX)}, repeated)",
           "    no target in issue 7; shown against the one-rig 20x"]
    for count in MODULE_COUNTS:
        rig = build_rig(modules_spec(count), state_dir=None)
        boot([rig])
        idle = speed(d.modules, run([rig], d.modules))
        loaded = speed(d.modules, run([rig], d.modules, cyclic(rig)))
        out.append(f"    {count:>2} module{'s' if count > 1 else ' '}  idle {idle:8.1f}x   "
                   f"cyclic {loaded:7.1f}x  {verdict(min(idle, loaded), TARGET_ONE)}")
    return out


def report(d: Durations, counts: Sequence[int] = (1, 10, MANY),
           files: Sequence[Path] = RIG_FILES) -> Iterator[str]:
    """The figures, section by section as each is measured."""
    specs = [(path.name, load_rig_spec(path)) for path in files]
    line_spec = fastcat_line_spec(specs[0][1])
    specs.append(("FastCAT line (the first rig's FastCAT and master only)", line_spec))
    yield ("Simulation kernel: simulated seconds per CPU second (time.process_time), "
           f"{line_spec.step_us / 1000:g} ms cycle")
    yield f"  machine: {machine()}"
    for name, spec in specs:
        devices = ", ".join(build_rig(spec, state_dir=None).devices)
        yield from one_rig(f"{name} ({devices})", spec, d)
    for name, spec in specs:
        yield from many_rigs(name.split(" (")[0], spec, d, counts)
    yield from modules(d)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench kernel",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true",
                   help="short runs, 10 rigs at most (a smoke test, not a figure)")
    p.add_argument("--rig", action="append", type=Path, default=None, metavar="TOML",
                   help="a rig file to measure (repeatable; default: "
                        f"{', '.join(str(f.name) for f in RIG_FILES)})")
    args = p.parse_args(argv)
    durations, counts = (QUICK, (1, 10)) if args.quick else (Durations(), (1, 10, MANY))
    for text in report(durations, counts, args.rig or RIG_FILES):
        print(text, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
