"""Soak: the default rig in the live runtime for simulated minutes (an hour with ``--full``) at
the 1 ms cycle, with faults injected and reset in a loop, served as ``python -m app`` serves
it: the dashboard drawing every frame on a viser server and the Rerun recorder attached.

Issue 7 "Hardening". Every 10 s of simulated time, on every device of the line: a FastCAT module
is unplugged and plugged back and the coupler's fault is reset (0x5200:1 rising edge, seed 000
§6.17); the TRS-CAT loses its field supply and gets it back (0x3220, seed 001); the CPX-E-EC's
outputs supply drops and returns (seed 002); the Modbus and CANopen drives get an alarm, its
cause is removed and it is reset (seed 004 ch. 2 / 4); the cable into the EtherCAT drive is
pulled and plugged back, and its sync-timeout alarm reset. The script runs in the simulation
thread as a step listener, at exact simulated instants. Checked: every cycle left its traces
(alarms raised and cleared on each device) and the line is back to OP without alarm at the
end; the process (simulation, dashboard, recorder) grows by less than 10 MB between the end of
the warm-up and the end; the runtime's event journal and the master's log stay within their
caps, and no other list in the snapshot grows.

The runtime is paused and driven with ``Runtime.advance`` in 10 s chunks: the simulation thread
steps, journals and calls the step listeners exactly as it does live, as fast as the machine
allows; no assertion depends on how fast that is.
"""

from __future__ import annotations

import gc
from collections import Counter
from pathlib import Path
from typing import Any

from app.recording import RigRecorder, attach_to_runtime
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import JOURNAL_LENGTH, Runtime
from app.screenshots import ServedRig
from devices.events import Event
from devices.master import LOG_LENGTH

US = 1_000_000
PERIOD_S = 10
FIRST_CYCLE_S = 5  # the coupler is in OP by then
WARM_UP_CYCLES = 2
SETTLED_S = 9  # into a cycle: every fault of the cycle reset
MAX_GROWTH_BYTES = 10 * 1024 * 1024
CHUNK_TIMEOUT_S = 600.0  # wall time for 10 s of simulated time: only against a hang
# (seconds into the cycle, target, action, arguments)
SCRIPT: tuple[tuple[float, str, str, dict[str, Any]], ...] = (
    (0.0, "fastcat/3", "unplug", {}),
    (0.5, "trscat", "field_supply", {"volts": 0.0}),
    (1.0, "cpx", "inject_fault", {"fault": "undervoltage_out"}),
    (1.5, "trscat", "field_supply", {"volts": 24.0}),
    (2.0, "fastcat/3", "plug", {"type": "DO16"}),
    (2.5, "cpx", "clear_fault", {"fault": "undervoltage_out"}),
    (3.0, "fastcat", "set_reset_fault", {"on": True}),
    (3.1, "fastcat", "set_reset_fault", {"on": False}),
    (4.0, "drive", "inject_alarm", {"code": "16"}),
    (4.2, "drive_co", "inject_alarm", {"code": "16"}),
    (5.0, "drive", "clear_alarm", {"code": "16"}),
    (5.05, "drive_co", "clear_alarm", {"code": "16"}),
    (5.1, "drive", "alarm_reset", {}),
    (5.15, "drive_co", "alarm_reset", {}),
    (5.5, "master", "pull_cable", {"cable": 3}),  # into the EtherCAT drive: alarm 34
    (6.0, "master", "plug_cable", {"cable": 3}),
    (8.0, "drive_ec", "alarm_reset", {}),  # the line is back in OP by now
)
# Devices that raise and clear at least one alarm every cycle
ALARMED = ("fastcat", "trscat", "cpx", "drive", "drive_co", "drive_ec")


BOUNDED = {".devices.master.log"}  # fills up to LOG_LENGTH, checked above
SHORT_LIST = 64


def list_lengths(data: Any, path: str = "") -> dict[str, int]:
    """Length of every list in a snapshot, by path (items of a list share its path + "[]")."""
    found: dict[str, int] = {}
    if isinstance(data, dict):
        for key, value in data.items():
            found.update(list_lengths(value, f"{path}.{key}"))
    elif isinstance(data, list):
        found[path] = len(data)
        for value in data:
            for sub, n in list_lengths(value, f"{path}[]").items():
                found[sub] = max(found.get(sub, 0), n)
    return found


class FaultLoop:
    """Applies SCRIPT every PERIOD_S from FIRST_CYCLE_S on (in the simulation thread)."""

    def __init__(self, runtime: Runtime) -> None:
        self.rig = runtime.rig
        self.at = {round((FIRST_CYCLE_S + at) * US) % (PERIOD_S * US): (target, action, args)
                   for at, target, action, args in SCRIPT}
        self.applied = 0
        self.refused: list[str] = []

    def on_step(self, now_us: int) -> None:
        if now_us < FIRST_CYCLE_S * US:
            return
        command = self.at.get(now_us % (PERIOD_S * US))
        if command is not None:
            target, action, args = command
            try:
                self.rig.apply(target, action, args)
                self.applied += 1
            except Exception as exc:
                self.refused.append(f"{now_us / US:.3f} s {target} {action}: {exc}")


def rss_bytes() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS in /proc/self/status")


def _advance_to(runtime: Runtime, t_us: int) -> None:
    while (now := runtime.rig.clock.now_us) < t_us:  # read between advances: the thread idles
        runtime.advance(min(PERIOD_S * US, t_us - now)).result(CHUNK_TIMEOUT_S)


def test_faults_in_a_loop_keep_memory_and_logs_bounded(full: bool, tmp_path: Path) -> None:
    cycles = (3600 if full else 60) // PERIOD_S
    end_us = (FIRST_CYCLE_S + (cycles - 1) * PERIOD_S + SETTLED_S) * US  # the last cycle done
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    recorder = RigRecorder(tmp_path / "soak.rrd")
    loops: list[FaultLoop] = []
    kinds: Counter[str] = Counter()
    alarms: Counter[tuple[str, bool]] = Counter()

    def count(events: list[Event]) -> None:
        kinds.update(e.kind for e in events)
        alarms.update((e.device, bool(getattr(e, "active", False))) for e in events
                      if e.kind == "alarm")

    def attach(runtime: Runtime) -> None:
        loops.append(FaultLoop(runtime))
        runtime.add_listener(count)
        runtime.add_step_listener(loops[0].on_step)
        attach_to_runtime(runtime, recorder)

    # Paused and stepped by advance(); the dashboard draws every frame published (as with a
    # browser connected), the recorder samples and logs as it does live.
    served = ServedRig.start(rig, quiet=True, before_start=attach)
    runtime, loop = served.runtime, loops[0]
    try:
        for device_id, info in rig.describe().items():  # powered, as `python -m app` does
            if "power" in info["actions"]:
                runtime.command(device_id, "power", {"on": True}).result(60)
        _advance_to(runtime, (FIRST_CYCLE_S + WARM_UP_CYCLES * PERIOD_S) * US)
        gc.collect()
        rss_warm = rss_bytes()
        lists_warm = list_lengths(runtime.submit(rig.snapshot).result(60))
        _advance_to(runtime, end_us)
        gc.collect()
        rss_end = rss_bytes()
        snap = runtime.submit(rig.snapshot).result(60)
        _seq, journal = runtime.events_since(0)
        drawn = served.dashboard.rendered_seq
    finally:
        served.stop()
        recorder.close()
    assert not loop.refused, loop.refused[:5]
    assert loop.applied >= cycles * len(SCRIPT)
    # every cycle raised and cleared an alarm on every device
    for device in ALARMED:
        assert alarms[(device, True)] >= cycles and alarms[(device, False)] >= cycles, alarms
    devices = snap["devices"]
    fastcat = devices["fastcat"]
    assert fastcat["esm"] == "OP" and not fastcat["fault_active"]
    assert [s["state"] for s in devices["master"]["slaves"]] == ["OP"] * 4
    assert devices["trscat"]["alarms"] == [] and devices["cpx"]["diagnosis"]["errors"] == []
    assert all(devices[d]["alarm"] is None for d in ("drive", "drive_co", "drive_ec"))
    assert drawn > 0 and recorder.path.stat().st_size > 0  # both ran beside the rig
    growth = rss_end - rss_warm
    print(f"soak: {cycles} cycles, RSS {rss_warm / 2**20:.1f} -> {rss_end / 2**20:.1f} MB, "
          f"journal {len(journal)} events, events {sum(kinds.values())}")
    assert growth < MAX_GROWTH_BYTES, f"grew {growth / 2**20:.1f} MB ({kinds})"
    assert len(journal) <= JOURNAL_LENGTH
    assert len(snap["devices"]["master"]["log"]) <= LOG_LENGTH
    # every other list in the snapshot is no longer than after the warm-up, or short
    for path, n in list_lengths(snap).items():
        if path not in BOUNDED:
            assert n <= max(lists_warm.get(path, 0), SHORT_LIST), (path, n)
