"""DC-SYNC and FREE-RUN (seed 001 §9.1.1), 0x1C32 / 0x1C33 (§9.3.1), the SM event missed
counter and the sync error with the 0x10F1:2 limit of 3 (§9.3.7)."""

from __future__ import annotations

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.od import AbortCode, SdoAbort
from devices.trscat.sync import SYNC0_ACTIVE, SYNC_ERROR_LIMIT, SyncMode, SyncUnit


@pytest.mark.parametrize("index", [0x1C32, 0x1C33])
@pytest.mark.parametrize(("sub", "value"), [
    (4, 0x0005),  # Sync Mode Supported: FREE-RUN and DC-SYNC only
    (5, 500_000),  # Min cycle time, ns
    (6, 100_000),  # Calc and copy time, ns
    (9, 150_000),  # Delay time, ns
])
def test_constant_subs(index: int, sub: int, value: int) -> None:
    """§9.3.1 tables."""
    bench = Bench()
    bench.settle()
    assert bench.read(index, sub) == value


@pytest.mark.parametrize(("mode", "sync_mode", "sync_control"), [
    ("dc", 0x0002, 0x0300), ("free_run", 0x0000, 0x0000)])
def test_modes(mode: str, sync_mode: int, sync_control: int) -> None:
    """§9.1.1: DC-SYNC (default) 0x0002 with ESC 0x980 = 0x0300, FREE-RUN 0x0000 / 0x0000: a
    master set up for the mode writes the register, PS takes the mode from it."""
    bench = Bench(sync_mode=mode)
    bench.to_state(AlState.SAFEOP)
    assert bench.read(0x1C32, 1) == bench.read(0x1C33, 1) == sync_mode
    assert bench.trs.snapshot()["sync"]["sync_control"] == sync_control


def test_dc_is_the_default() -> None:
    bench = Bench()
    assert bench.trs.sync.mode is SyncMode.DC_SYNC


@pytest.mark.parametrize(("mode", "state", "cycle_ns"), [
    ("free_run", AlState.PREOP, 0), ("free_run", AlState.SAFEOP, 500_000),
    ("free_run", AlState.OP, 500_000),
    ("dc", AlState.PREOP, 0), ("dc", AlState.SAFEOP, 1_000_000), ("dc", AlState.OP, 1_000_000)])
def test_cycle_time(mode: str, state: AlState, cycle_ns: int) -> None:
    """§9.3.1 0x1C32:2: FREE-RUN fixed 500 us (§9.1.1); DC-SYNC 1:1 with the master cycle
    (1 ms here), known once SYNC0 runs. Before the first PS the device is in its default
    DC-SYNC, not yet running: 0."""
    bench = Bench(sync_mode=mode)
    bench.to_state(state)
    assert bench.read(0x1C32, 2) == bench.read(0x1C33, 2) == cycle_ns


def test_dc_one_local_cycle_per_master_cycle() -> None:
    """§9.1.1: "ad ogni ciclo del master corrisponde 1 ciclo sincrono di TRS-CAT"."""
    unit = SyncUnit()
    unit.configure(SYNC0_ACTIVE, 2_000_000, 0, now_us=0)
    unit.frame(0, None)  # type: ignore[arg-type]
    unit.frame(2000, None)  # type: ignore[arg-type]
    unit.start(2000)
    cycles = unit.cycles_until(20_000)
    assert [t for t, _ in cycles] == list(range(4000, 20_001, 2000))


def test_free_run_cycle_is_500_us() -> None:
    unit = SyncUnit(mode=SyncMode.FREE_RUN)
    assert [t for t, _ in unit.cycles_until(3000)] == [0, 500, 1000, 1500, 2000, 2500, 3000]


@pytest.mark.parametrize("missed", range(0, SYNC_ERROR_LIMIT + 2))
def test_sm_event_missed_counter_and_limit(missed: int) -> None:
    """§9.3.1 0x1C32:11 counts consecutive missed SM events; §9.3.7 0x10F1:2 = 3 -> sync
    error 0x1C32:32 TRUE. In SAFE-OP the device stays (no outputs to protect)."""
    bench = Bench()
    bench.to_state(AlState.SAFEOP)
    assert bench.read(0x10F1, 2) == 3
    bench.apply("drop_frames", count=missed)
    bench.run((missed + 1) / 1000)  # a frame is missed at the SYNC0 after it (1 ms later)
    assert bench.read(0x1C32, 11) == bench.read(0x1C33, 11) == missed
    assert bench.read(0x1C32, 32) is (missed >= 3)
    bench.run(0.003)  # frames again: the counter is of consecutive misses
    assert bench.read(0x1C32, 11) == 0 and bench.read(0x1C32, 32) is False


@pytest.mark.parametrize("missed", [2, 3])
def test_sync_error_in_op(missed: int) -> None:
    """§9.1.1 "pena la perdita del sincronismo": 3 missed SM events in OP -> SAFE-OP + error,
    AL status code 0x001A, ERROR LED single flash (ETG.1300 local error)."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("drop_frames", count=missed)
    bench.run(0.005)
    if missed < SYNC_ERROR_LIMIT:
        assert bench.trs.al_state is AlState.OP
        return
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status == 0x14
    assert bench.trs.al_status_code == 0x001A
    assert bench.leds()["ERROR"] == "single_flash"
    assert [m["code"] for m in bench.messages()] == ["0x001A"]
    states = [(r["from"], r["to"]) for r in bench.records("state") if r.get("machine") == "sync"]
    assert ("dc_running", "sync_error") in states


def test_sync_error_refuses_op() -> None:
    bench = Bench()
    bench.to_state(AlState.SAFEOP)
    bench.apply("drop_frames", count=1000)
    bench.run(0.01)
    bench.request(AlState.OP)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0x001A


def test_lost_sync0_is_a_fatal_sync_error() -> None:
    """§9.1.1: the application runs on SYNC0; without it the SM events come alone and, at the
    0x10F1:2 limit, the device leaves OP with 0x002C; its I/O stops being sampled."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("lose_sync0", lost=True)
    bench.apply("set_input", channel=1, on=True)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0x002C
    assert bench.read(0x1C32, 32) is False  # the SM events did not miss: SYNC0 did
    assert bench.read(0x6000, 1) == 0
    bench.apply("lose_sync0", lost=False)
    bench.run(0.01)
    bench.request(AlState.OP)
    bench.run(0.005)
    assert bench.trs.al_state is AlState.OP and bench.read(0x6000, 1) == 1


@pytest.mark.parametrize(("jitter_us", "falls"), [(0, False), (800, False), (5000, True)])
def test_jitter_into_calc_and_copy(jitter_us: int, falls: bool) -> None:
    """§9.1.1: SM2 jitter must not invade the calc+copy time (100 us before SYNC0): frames
    late by more than cycle - 100 us miss their SYNC0."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("frame_jitter", us=jitter_us)
    bench.run(1.0)
    assert (bench.trs.al_state is AlState.SAFEOP) is falls


def test_free_run_has_no_sync_error_but_a_watchdog() -> None:
    """FREE-RUN: no SYNC0, so no sync error; the SM watchdog (100 ms) catches a master that
    stopped sending: 0x001B, ERROR LED double flash (ETG.1300)."""
    bench = Bench(sync_mode="free_run")
    bench.to_state(AlState.OP)
    bench.apply("drop_frames", count=99)
    bench.run(0.1)
    assert bench.trs.al_state is AlState.OP
    bench.apply("drop_frames", count=1000)
    bench.run(0.2)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0x001B
    assert bench.leds()["ERROR"] == "double_flash"
    assert bench.messages()[-1]["code"] == "0x001B"


@pytest.mark.parametrize(("step_us", "code"), [(400, 0x002E), (500, None), (2000, None)])
def test_dc_cycle_below_minimum_refuses_safeop(step_us: int, code: int | None) -> None:
    """§9.3.1 0x1C32:5: SYNC0 below 500 us is refused at PREOP -> SAFEOP (AL 0x002E); the
    bench's master writes one SYNC0 per step to 0x09A0."""
    bench = Bench(step_us=step_us)
    bench.settle()
    bench.request(AlState.PREOP)
    bench.step()
    bench.request(AlState.SAFEOP)
    if code is None:
        assert bench.trs.al_state is AlState.SAFEOP
        assert bench.read(0x1C32, 2) == step_us * 1000
    else:
        assert bench.trs.al_state is AlState.PREOP and bench.trs.al_status_code == code
        bench.request(AlState.SAFEOP)  # a master retrying: one message per episode
        assert [m["code"] for m in bench.messages()] == ["0x002E"]


def test_a_master_without_sync0_gets_free_run() -> None:
    """§9.1.1: 0x0980 = 0x0000 is FREE-RUN. A master that never activated SYNC0 (0x0981 = 0)
    takes the default device (DC-SYNC at power-up) to SAFE-OP in FREE-RUN."""
    bench = Bench(dc=False)
    bench.settle()
    assert bench.read(0x1C32, 1) == 0x0002
    bench.request(AlState.PREOP)
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0
    assert bench.read(0x1C32, 1) == bench.read(0x1C33, 1) == 0x0000


@pytest.mark.parametrize("index", [0x1C32, 0x1C33])
@pytest.mark.parametrize(("state", "value", "error"), [
    (AlState.PREOP, 0x0000, None),
    (AlState.PREOP, 0x0002, None),
    (AlState.PREOP, 0x0001, AbortCode.VALUE_RANGE),  # SM-synchronous: not supported
    (AlState.SAFEOP, 0x0000, AbortCode.CANNOT_STORE_STATE),
])
def test_sync_mode_written_in_preop(index: int, state: AlState, value: int,
                                    error: AbortCode | None) -> None:
    """§9.1.1 / §9.3.1: the mode is chosen by the master before SAFE-OP (0x1C32:1 / 0x1C33:1
    RW); a refusal names the object written, as an SDO abort does."""
    bench = Bench()
    bench.to_state(state)
    if error is None:
        bench.write(index, 1, value)
        assert bench.read(0x1C32, 1) == bench.read(0x1C33, 1) == value
    else:
        with pytest.raises(SdoAbort) as info:
            bench.write(index, 1, value)
        assert (info.value.code, info.value.index, info.value.sub) == (error, index, 1)


def test_switch_to_free_run_then_op() -> None:
    """A FREE-RUN master (0x0981 left at 0) that also writes 0x1C32:1 = FREE-RUN in PRE-OP."""
    bench = Bench(dc=False)
    bench.settle()
    bench.request(AlState.PREOP)
    bench.apply("set_sync_mode", mode="free_run")
    bench.to_state(AlState.OP)
    assert bench.read(0x1C32, 2) == 500_000
    assert bench.trs.snapshot()["sync"]["mode"] == "FREE-RUN"
