"""The FastCAT's SM2 (process data) watchdog: the ESI declares SM2 with control 0x64, watchdog
trigger on, and the coupler's firmware is an SSC one (seed 000 §7.7 lists its AL status codes,
0x001B "Sync manager watchdog" among them). No process data for 100 ms in OP (ESC 0x0420
default) -> SAFEOP + error flag + 0x001B, outputs in their safe state (the 0x7000 / 0x7400
values kept for the next OP), ERR double flash (ETG.1300). SAFEOP -> OP without process data
in that time is refused with 0x001B. The cable out is §7.5 0x13 LINK_LOSS, at once
(docs/fastcat-coupler.md "SM watchdog").
"""

from __future__ import annotations

from fastcat_bench import Bench

from devices.ethercat import AlState

WATCHDOG_US = 100_000
STEP_US = 1_000


def _do1(bench: Bench) -> bool:
    return bool(bench.fc.snapshot()["rail"][0]["do"][0])


def _line_in_op() -> Bench:
    """DO16 (output 1 on) and AI8D in OP under the built-in master, a frame every 1 ms."""
    bench = Bench(["DO16", "AI8D"], master=True)
    bench.run_until(lambda: bench.fc.al_state is AlState.OP)
    bench.run(0.2)  # the master's check of its OP request (141 ms) done
    bench.write(0x7000, 1, 1)
    bench.step()
    assert _do1(bench)
    return bench


def test_frames_stopping_in_op_expire_the_watchdog_and_the_master_brings_it_back() -> None:
    bench = _line_in_op()
    assert bench.master is not None
    last_frame = bench.now  # the master's frame of this step went through
    bench.master.apply("lose_frames", {"count": 150})
    since = bench.mark()
    bench.run_to(last_frame + WATCHDOG_US)
    assert bench.fc.al_state is AlState.OP and _do1(bench)  # 100 ms: not expired yet
    bench.step()
    fc = bench.fc
    assert fc.al_state is AlState.SAFEOP
    assert (fc.al_status, fc.al_status_code) == (0x14, 0x001B)
    assert [(r["event"], r.get("code"), r.get("from"), r.get("to"))
            for r in bench.records(since=since) if r["device"] == "fastcat"
            and r["event"] in ("al_status", "state")] == [
        ("al_status", "0x001B", None, None), ("state", None, "OP", "SAFEOP")]
    leds = fc.snapshot()["leds"]
    assert (leds["RUN"], leds["ERR"]) == ("single_flash", "double_flash")
    assert not _do1(bench)  # outputs in the safe state ...
    assert bench.read(0x7000, 1) == 1  # ... the master's value kept for the next OP
    assert fc.alarm is None and bench.emergencies(since) == []  # no §7 alarm
    # The frames come back at the 151st cycle: the master reads the fall, logs it and asks
    # for OP again (with the error acknowledge), which the coupler takes at once.
    bench.run_to(last_frame + 151 * STEP_US)
    master = [r for r in bench.records(since=since) if r["device"] == "master"
              and r["event"] in ("slave_state", "log") and "lost" not in r.get("text", "")]
    assert [(r["event"], r.get("from"), r.get("to"), r.get("code")) for r in master] == [
        ("log", None, None, None), ("slave_state", "OP", "SAFEOP", "0x001B"),
        ("slave_state", "SAFEOP", "OP", "0x0000")]
    assert master[0]["text"] == ("'Box 1 (FastCAT)' (1001): abnormal state change (from 'OP' "
                                 "to 'SAFEOP') with code 0x001B. Try to go back to 'OP'...")
    assert fc.al_state is AlState.OP and (fc.al_status, fc.al_status_code) == (0x08, 0)
    bench.step()
    assert _do1(bench)  # the kept value drives the output again
    assert fc.snapshot()["leds"]["ERR"] == "off"


def test_op_is_refused_without_process_data() -> None:
    """SSC with the SM2 watchdog trigger on: SAFEOP -> OP needs outputs received first."""
    bench = Bench(["DO16"])
    bench.to_state(AlState.PREOP)
    fc = bench.fc
    fc.request_state(AlState.SAFEOP)
    fc.request_state(AlState.OP)  # no frame ever
    assert fc.al_state is AlState.SAFEOP
    assert (fc.al_status, fc.al_status_code) == (0x14, 0x001B)
    bench.step()
    assert fc.snapshot()["leds"]["ERR"] == "double_flash"
    fc.exchange_frame(bench.now)
    bench.run_to(bench.now + WATCHDOG_US + STEP_US)  # that frame is 101 ms old now
    fc.request_state(AlState.OP, ack=True)
    assert fc.al_state is AlState.SAFEOP and fc.al_status_code == 0x001B
    fc.exchange_frame(bench.now)
    fc.request_state(AlState.OP, ack=True)
    assert fc.al_state is AlState.OP and (fc.al_status, fc.al_status_code) == (0x08, 0)


def test_the_cable_out_is_link_loss_at_once_not_the_watchdog() -> None:
    """§7.5 0x13: the coupler sees its link go and drops to PREOP with 0x8013 at the next
    exchange, before any watchdog could expire."""
    bench = _line_in_op()
    since = bench.mark()
    bench.apply("link", connected=False)
    bench.run(1.0)
    assert bench.fc.al_state is AlState.PREOP and bench.fc.al_status_code == 0x8013
    assert [r["code"] for r in bench.records("al_status", since)
            if r["device"] == "fastcat"] == ["0x8013"]


def test_behind_a_module_alarm_the_cable_out_ends_in_the_watchdog() -> None:
    """0x13 waits behind a latched module alarm (§7, "A coupler cause behind a module alarm"),
    so OP stays; the frames have stopped all the same, and 100 ms later the watchdog takes the
    coupler to SAFEOP with 0x001B. It is no §7 alarm: no emergency, 0x5400 and the latched
    alarm stay those of the module alarm."""
    bench = _line_in_op()
    bench.apply("inject_fault", module=2, fault="TARATURA")
    bench.run(0.1)
    assert bench.fc.al_state is AlState.OP and bench.fc.alarm is not None
    since = bench.mark()
    bench.apply("link", connected=False)
    cut = bench.now
    bench.run_to(cut + WATCHDOG_US)
    assert bench.fc.al_state is AlState.OP
    bench.run(0.5)
    fc = bench.fc
    assert fc.al_state is AlState.SAFEOP and fc.al_status_code == 0x001B
    assert bench.records("al_status", since)[0]["t"] == (cut + WATCHDOG_US + STEP_US) / 1e6
    assert bench.emergencies(since) == []
    assert fc.alarm is not None and fc.alarm.code == 0x0B
    assert fc.od_emergency_word() == 0x000B0002
    assert fc.snapshot()["leds"]["ERR"] == "double_flash"


def test_frames_stopped_first_then_the_cable_out_drops_safeop_to_preop() -> None:
    """A master stopped (the watchdog: SAFEOP, 0x001B), then the cable pulled: 0x13 latched in
    SAFEOP drops the coupler to PREOP with 0x8013 and its emergency, as any coupler alarm."""
    bench = Bench(["DO16"])
    bench.to_state(AlState.OP)
    bench.frames = False  # the PLC stops
    bench.run(0.2)
    assert (bench.fc.al_state, bench.fc.al_status_code) == (AlState.SAFEOP, 0x001B)
    since = bench.mark()
    bench.apply("link", connected=False)
    bench.step()
    assert (bench.fc.al_state, bench.fc.al_status_code) == (AlState.PREOP, 0x8013)
    assert bench.emergencies(since) == ["00 00 00 13 00"]
    assert bench.fc.snapshot()["leds"]["ERR"] == "single_flash"
