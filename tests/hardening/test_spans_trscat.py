"""Quiet spans of the TRS-CAT (docs/trscat.md "Quiet spans"): skipping changes nothing.

- a TRS-CAT alone (no master, no frame ever): powered off, the power-up detection, INIT, with
  random operator commands (power cycles, field supply, inputs, loads, outputs, faults,
  expansions, sync faults, object writes) and stretches of 1 .. 3000 steps, a skipping rig
  against a plain one (tests/hardening/span_runs.py);
- the same with a small master (``Wire``) that sends a frame every step, writes the DC
  registers and the 0xF030 list and walks the ESM (INIT .. OP, DC-SYNC or FREE-RUN), promises
  its frames (``frames_promised``) and stops sending at random: the sync0 spans under frames,
  the free spans bounded by the activity window and the SM watchdog when the frames stop;
- frames_quiet / skip_frames directly: two identical devices in a quiet state, one stepped
  with a frame after every step, the other skip_to + skip_frames; the deep state compared.

Reduced (CI): 1 x 40 rounds each, the file 15-35 s with a load average of ~8 on 2 cores;
``--full``: 6 x 250 (2.5 min so loaded).
"""

from __future__ import annotations

import random
from collections.abc import Mapping
from typing import Any, ClassVar

import pytest
from span_runs import Op, deep_state, differential

from app.clock import SimClock
from app.rig import Rig
from devices.device import Action, DeviceModel, Param
from devices.ethercat import AlState
from devices.trscat.device import TrsCat
from devices.trscat.sync import SYNC0_ACTIVE, SyncMode

STEP_US = 1_000
UP = {AlState.INIT: AlState.PREOP, AlState.PREOP: AlState.SAFEOP,
      AlState.SAFEOP: AlState.OP, AlState.OP: AlState.OP}
# The 0xF030 list the master writes: the integrated module, TRS-IO-E, TRS-AN-E (§9.3.2).
CONFIGURED = (3, 0x494F2D42, 0x494F2D45, 0x414E2D45)
STATES = {"init": AlState.INIT, "preop": AlState.PREOP, "safeop": AlState.SAFEOP,
          "op": AlState.OP}


class Wire(DeviceModel):
    """A master for one TRS-CAT, as the built-in one behaves toward it: a frame at every step
    after the slave's step (while ``sending``), the DC registers written before PREOP and
    SAFEOP (SYNC0 = the step), the ESM walked by command. Its quiet span: any, as long as the
    slave's frames_quiet holds; its skip_to hands the frames to skip_frames."""

    KIND = "wire"
    ACTIONS: ClassVar[Mapping[str, Action]] = {a.name: a for a in (
        Action("up", "request the state above the slave's"),
        Action("request", "request a state", (Param("state", str, choices=tuple(STATES)),)),
        Action("sending", "send frames or not", (Param("on", bool),)),
        Action("noop", "nothing"),
    )}

    def __init__(self, device_id: str, slave: TrsCat, step_us: int = STEP_US) -> None:
        super().__init__(device_id=device_id, rng=random.Random(0))
        self.slave = slave
        self.step_us = step_us
        self.sending = True
        slave.frames_promised = self.promise

    def promise(self, step_us: int) -> bool:
        return self.sending and step_us == self.step_us

    def step(self, now_us: int) -> None:
        super().step(now_us)
        if self.sending:
            self.slave.exchange_frame(now_us)

    def quiet_until(self, step_us: int) -> int:
        if self.sending and not self.slave.frames_quiet():
            return self.now_us
        return self.now_us + (1 << 40) * step_us

    def skip_to(self, t_us: int, step_us: int) -> None:
        if self.sending:
            self.slave.skip_frames((t_us - self.now_us) // self.step_us, t_us)
        self.now_us = t_us

    def cmd_up(self) -> None:
        self.cmd_request(next(k for k, v in STATES.items() if v is UP[self.slave.esm.state]))

    def cmd_request(self, state: str) -> None:
        target = STATES[state]
        slave = self.slave
        # A master set up for the rig's mode, or for the one it wrote to 0x1C32:1: it
        # activates SYNC0 for DC-SYNC (the device takes its mode from that at PS).
        mode = slave.sync.requested if slave.sync.requested is not None else \
            slave.master_sync_mode
        if target in (AlState.PREOP, AlState.SAFEOP) and mode is SyncMode.DC_SYNC:
            slave.configure_dc(SYNC0_ACTIVE, self.step_us * 1000, (self.now_us + 100) * 1000)
        if target is AlState.SAFEOP and slave.esm.state is AlState.PREOP:
            for sub, value in enumerate(CONFIGURED):  # its PS init commands (seed 001 §9.2)
                slave.write_object(0xF030, sub, value)
        slave.request_state(target)

    def cmd_sending(self, on: bool) -> None:
        self.sending = on

    def cmd_noop(self) -> None:
        pass

    def snapshot(self) -> dict[str, Any]:
        return {"sending": self.sending}


def trscat(sync_mode: str = "dc") -> TrsCat:
    return TrsCat("trscat", random.Random(7), ["TRS-IO-E", "TRS-AN-E"], sync_mode=sync_mode)


def alone() -> Rig:
    return Rig(name="trscat alone", devices={"trscat": trscat()},
               clock=SimClock(step_us=STEP_US), seed=1)


def wired(sync_mode: str = "dc") -> Rig:
    slave = trscat(sync_mode)
    return Rig(name="trscat wired", devices={"trscat": slave, "wire": Wire("wire", slave)},
               clock=SimClock(step_us=STEP_US), seed=1)


def trscat_op(rng: random.Random) -> Op:
    """A random operator command to the TRS-CAT; idle ones often, so that spans happen."""
    r = rng.random()
    if r < 0.3:
        return "trscat", "read_object", {"index": 0x1000, "sub": 0}  # touches, moves nothing
    if r < 0.4:
        return "trscat", "power", {"on": rng.random() < 0.6}
    if r < 0.42:  # shuts the TRS bus down until power-off: rarely
        return "trscat", "inject_fault", {"fault": "TRS_OVERCURRENT"}
    choices: list[Op] = [
        ("trscat", "field_supply", {"volts": rng.choice([24.0, 24.0, 12.0, 35.0])}),
        ("trscat", "set_input", {"channel": rng.randrange(1, 5), "on": rng.random() < 0.5}),
        ("trscat/1", "set_input", {"channel": rng.randrange(1, 5), "on": rng.random() < 0.5}),
        ("trscat", "set_input_voltage", {"channel": 1, "volts": rng.choice([5.0, 12.0, 20.0])}),
        ("trscat", "set_load", {"channel": rng.randrange(1, 3), "amps": rng.choice([0.1, 0.8])}),
        ("trscat/2", "set_analog_input", {"channel": 1, "volts": rng.uniform(-10, 10)}),
        ("trscat", "set_output", {"channel": rng.randrange(1, 5), "value": rng.randrange(2)}),
        ("trscat/2", "set_output", {"channel": 1, "value": rng.randrange(-1000, 1000)}),
        ("trscat", "inject_fault", {"fault": rng.choice(["FIELD_SUPPLY", "CONFIG_ERROR"])}),
        ("trscat", "clear_fault", {"fault": rng.choice(["FIELD_SUPPLY", "CONFIG_ERROR"])}),
        ("trscat/2", "inject_fault", {"fault": "AN_PLUS_12V"}),
        ("trscat/2", "clear_fault", {"fault": "AN_PLUS_12V"}),
        ("trscat/2", "unplug", {}),
        ("trscat/2", "plug", {"type": "TRS-AN-E"}),
        ("trscat", "link", {"port": "in", "connected": rng.random() < 0.7}),
        ("trscat", "link", {"port": "out", "connected": rng.random() < 0.5}),
        ("trscat", "drop_frames", {"count": rng.choice([0, 1, 5])}),
        ("trscat", "lose_sync0", {"lost": rng.random() < 0.3}),
        ("trscat", "frame_jitter", {"us": rng.choice([0, 0, 50, 1000])}),
        ("trscat", "set_sync_mode", {"mode": rng.choice(["dc", "free_run"])}),
        ("trscat", "acknowledge_messages", {}),
        ("trscat", "write_object", {"index": 0x10F3, "sub": 5, "value": rng.randrange(2)}),
        ("trscat", "write_object", {"index": 0xF700, "sub": 1, "value": rng.randrange(2)}),
    ]
    return rng.choice(choices)


def wired_op(rng: random.Random) -> Op:
    r = rng.random()
    if r < 0.3:
        return "wire", "up", {}
    if r < 0.4:
        return "wire", "noop", {}
    if r < 0.55:  # the frames stop (or come back): the spans without frames
        return "wire", "sending", {"on": rng.random() < 0.5}
    if r < 0.6:
        return "wire", "request", {"state": rng.choice(list(STATES))}
    return trscat_op(rng)


def sizes(full: bool) -> tuple[int, int]:
    return (6, 250) if full else (1, 40)


def test_alone(full: bool) -> None:
    """No master, no frame: off, detecting, INIT, with every kind of operator command."""
    seeds, rounds = sizes(full)
    skipped = sum(differential(alone, trscat_op, seed, rounds) for seed in range(seeds))
    assert skipped > 1000 * seeds


@pytest.mark.parametrize("sync_mode", ["dc", "free_run"])
def test_wired(full: bool, sync_mode: str) -> None:
    """A master sending a frame every step (or stopping): every ESM state, DC-SYNC running."""
    seeds, rounds = sizes(full)
    skipped = sum(differential(lambda: wired(sync_mode), wired_op, 100 + seed, rounds)
                  for seed in range(seeds))
    assert skipped > 1000 * seeds


def walked(sync_mode: str, target: AlState) -> Rig:
    """A wired rig walked up to ``target`` and left to settle (stepped one by one)."""
    rig = wired(sync_mode)
    rig.SKIP_SPANS = False  # type: ignore[misc]
    rig.advance(600)  # past the power-up detection
    wire = rig.devices["wire"]
    while rig.devices["trscat"].esm.state is not target:  # type: ignore[attr-defined]
        wire.apply("up", {})
        rig.advance(10)
    rig.advance(200)
    return rig


@pytest.mark.parametrize(("sync_mode", "state"), [
    ("dc", "op"), ("dc", "safeop"), ("free_run", "op"), ("dc", "preop"), ("dc", "init")])
@pytest.mark.parametrize("n", [2, 7, 300])
def test_frames_direct(sync_mode: str, state: str, n: int) -> None:
    """One device: n steps each followed by its frame; its twin: skip_to + skip_frames."""
    target = STATES[state]
    stepped, skipped = walked(sync_mode, target), walked(sync_mode, target)
    a, b = stepped.devices["trscat"], skipped.devices["trscat"]
    assert isinstance(a, TrsCat) and isinstance(b, TrsCat)
    assert a.esm.state is target
    assert deep_state(a) == deep_state(b)
    now = b.now_us
    assert b.quiet_until(STEP_US) >= now + n * STEP_US
    assert b.frames_quiet()
    for k in range(1, n + 1):
        a.step(now + k * STEP_US)
        a.exchange_frame(now + k * STEP_US)
    end = now + n * STEP_US
    b.skip_to(end, STEP_US)
    b.skip_frames(n, end)
    assert deep_state(a) == deep_state(b)
    assert a.drain_events() == b.drain_events() == []


@pytest.mark.parametrize(("sync_mode", "state", "steps"), [
    ("dc", "op", 0), ("dc", "safeop", 0),  # SYNC0 needs the frames
    ("free_run", "op", 50), ("dc", "preop", 50), ("dc", "init", 50)])
def test_without_promise(sync_mode: str, state: str, steps: int) -> None:
    """Without frames promised the span ends before a missing frame changes a step: the
    activity window (50 ms after the last frame), at once under DC-SYNC (the next SYNC0 but
    one counts a missed SM event)."""
    rig = walked(sync_mode, STATES[state])
    trs = rig.devices["trscat"]
    assert isinstance(trs, TrsCat)
    trs.frames_promised = None
    assert trs.quiet_until(STEP_US) == trs.now_us + steps * STEP_US
