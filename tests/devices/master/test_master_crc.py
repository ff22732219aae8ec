"""A damaged cable and the ESC error counters that locate it (seed 004 "Error Detection";
ET1100 register description 0x0300-0x0313; docs/ethercat-master.md "Damaged cable").

The default rig's line: cable 0 master -> fastcat (0), 1 -> trscat (1), 2 -> cpx (2),
3 -> drive (3). Port 0 is each slave's IN, port 1 its OUT.
"""

from __future__ import annotations

import copy
import functools
import random

import pytest

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from devices.device import CommandError
from devices.master import EtherCatMaster
from devices.master.esc_errors import EscErrors, run_frame

IN_OP_US = 4_000_000
IN, OUT = 0, 1


@functools.cache
def _default_in_op() -> Rig:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    rig.run_until(IN_OP_US)
    return rig


def default_in_op() -> Rig:
    return copy.deepcopy(_default_in_op())


def master(rig: Rig) -> EtherCatMaster:
    m = rig.devices["master"]
    assert isinstance(m, EtherCatMaster)
    return m


def errors(rig: Rig) -> list[dict]:
    return [s["esc_errors"] for s in rig.snapshot()["devices"]["master"]["slaves"]]


def run_ms(rig: Rig, ms: int) -> None:
    rig.run_until(rig.clock.now_us + ms * 1000)


def damaged_for(rig: Rig, cable: int, percent: int, ms: int) -> tuple[int, list[dict]]:
    """Cable ``cable`` damaged for ``ms``: the frames the master lost meanwhile, and the
    slaves' ESC counters then."""
    lost = master(rig).lost_frames
    rig.apply("master", "damage_cable", {"cable": cable, "percent": percent})
    run_ms(rig, ms)
    return master(rig).lost_frames - lost, errors(rig)


def test_every_crossing_spoiled_moves_the_counters_of_the_ports_behind_the_cable() -> None:
    """Cable 2 spoils every frame: the CPX-E-EC (first to receive it, port 0) counts it
    invalid and marks it; the drive after it counts it forwarded on port 0; on the way back
    every slave before the cable counts it forwarded on port 1; the processing units of the
    CPX-E-EC and the drive (forward direction only) count it; the master loses every frame."""
    rig = default_in_op()
    n, e = damaged_for(rig, 2, 100, 10)
    assert n == 10
    assert [s["invalid"] for s in e] == [[0, 0], [0, 0], [n, 0], [0, 0]]
    assert [s["forwarded"] for s in e] == [[0, n], [0, n], [0, n], [n, 0]]
    assert [s["epu"] for s in e] == [0, 0, n, n]
    assert [s["rx"] for s in e] == [[0, 0]] * 4
    assert [s["counters"]["lost_frames"] for s in
            rig.snapshot()["devices"]["master"]["slaves"]] == [n] * 4


def test_a_share_of_the_frames_spoiled_forward_or_on_the_way_back() -> None:
    """Half of the crossings of cable 2: a frame spoiled forward is invalid at the CPX-E-EC's
    port 0; one that passed forward and is spoiled on its way back is invalid at the
    TRS-CAT's port 1 (the first ESC to receive it), forwarded at the FastCAT's port 1. The
    slaves that no spoiled frame reached first count nothing as invalid."""
    rig = default_in_op()
    n, e = damaged_for(rig, 2, 50, 200)  # n stays below 0xFF, where counting stops
    forward, back = e[2]["invalid"][IN], e[1]["invalid"][OUT]
    assert forward > 0 and back > 0 and forward + back == n
    assert 100 < n < 200  # 1 - 0.5 * 0.5 of 200 frames, roughly
    assert e[0]["invalid"] == [0, 0] and e[3]["invalid"] == [0, 0]
    assert e[3]["forwarded"][IN] == forward and e[2]["forwarded"][OUT] == forward
    assert e[1]["forwarded"][OUT] == forward and e[0]["forwarded"][OUT] == n
    # deterministic: the rig's random generator draws the crossings
    assert damaged_for(default_in_op(), 2, 50, 200)[1] == e


def test_cable_0_spoiled_on_the_way_back_reaches_no_slave() -> None:
    """The first slave counts what cable 0 spoils on the way out; what it spoils on the way
    back only the master sees (a lost frame, no ESC counter)."""
    rig = default_in_op()
    n, e = damaged_for(rig, 0, 50, 200)
    assert 0 < e[0]["invalid"][IN] < n
    assert all(s["invalid"][OUT] == 0 for s in e)
    assert e[3]["forwarded"][IN] == e[0]["invalid"][IN]


def test_repair_stops_new_errors_the_counters_stay_until_a_write_clears_them() -> None:
    rig = default_in_op()
    m = master(rig)
    rig.apply("master", "damage_cable", {"cable": 3, "percent": 100})
    run_ms(rig, 5)
    rig.apply("master", "repair_cable", {"cable": 3})
    lost = m.lost_frames
    run_ms(rig, 20)
    assert m.lost_frames == lost
    e = errors(rig)
    assert e[3]["invalid"] == [5, 0] and e[2]["forwarded"] == [0, 5]
    # a write to 0x0300-0x030B clears those (and only those): the ESC's rule
    esc = m.links[3].esc
    esc.lost_link[IN] = 2
    assert esc.write(0x0300, 2)
    assert esc.invalid == [0] * 4 and esc.forwarded == [0] * 4 and esc.epu == 5
    assert esc.lost_link[IN] == 2
    assert esc.write(0x030C, 1) and esc.epu == 0
    assert esc.write(0x0312, 1) and esc.lost_link == [0] * 4
    assert not esc.write(0x0314, 4)
    rig.apply("master", "clear_esc_errors", {"position": 2})
    assert errors(rig)[2] == EscErrors().snapshot()


def test_counters_stop_at_0xff() -> None:
    esc = [EscErrors(), EscErrors()]
    for _ in range(300):
        assert run_frame(esc, 1, {1: 1.0}, random.Random(1))
    assert esc[1].invalid[IN] == 0xFF and esc[0].forwarded[OUT] == 0xFF and esc[1].epu == 0xFF
    assert esc[1].registers()[:2] == b"\xff\x00" and esc[0].registers()[9] == 0xFF


def test_a_pulled_cable_counts_a_lost_link_on_both_its_ends() -> None:
    rig = default_in_op()
    rig.apply("master", "pull_cable", {"cable": 2})
    run_ms(rig, 5)
    rig.apply("master", "plug_cable", {"cable": 2})
    run_ms(rig, 5)
    e = errors(rig)
    assert [s["lost_link"] for s in e] == [[0, 0], [0, 1], [1, 0], [0, 0]]


def test_a_damaged_cable_is_one_the_rig_names_and_shows_in_the_snapshot() -> None:
    rig = default_in_op()
    with pytest.raises(CommandError):
        rig.apply("master", "damage_cable", {"cable": 4, "percent": 10})
    rig.apply("master", "damage_cable", {"cable": 1, "percent": 10})
    cables = rig.snapshot()["devices"]["master"]["cables"]
    assert [c.get("damaged") for c in cables] == [None, 10, None, None]


def test_lost_frames_of_a_damaged_cable_are_logged_once_a_second_at_most() -> None:
    """As lose_frames: counted per slave, comm_error and a log line; a damaged cable loses
    frames on and on, so the line says how many were lost since the last one."""
    rig = default_in_op()
    m = master(rig)
    lost = m.lost_frames
    rig.apply("master", "damage_cable", {"cable": 1, "percent": 100})
    events = []
    for _ in range(1500):
        events += rig.step()
    records = [e.to_record() for e in events]
    comm = [r for r in records if r["event"] == "comm_error" and r["position"] == 0]
    assert [r["count"] for r in comm] == [1, 1000]
    assert m.lost_frames - lost == 1500
    lines = [r for r in records if r["event"] == "log" and "lost" in r["text"]]
    assert len(lines) == 2


def test_a_wire_masters_lost_frames_are_counted_and_reported_as_the_built_in_masters() -> None:
    """External mode: the frames process B lost to a damaged cable (its statistics: a total
    in the run) go the built-in master's way: counted per slave, comm_error per slave and a
    log line at the first, then at most once a second with those lost since
    (docs/ethercat-wire.md "Damaged cable")."""
    rig = default_in_op()
    m = master(rig)
    m.set_external(True)
    events = []
    for lost, ms in ((3, 1), (8, 1), (8, 1000), (10, 1)):
        m.external_stats(frames=100, lost_frames=lost, cycle_us=1000, wkc_errors=0)
        for _ in range(ms):
            events += rig.step()
    records = [e.to_record() for e in events]
    comm = [r for r in records if r["event"] == "comm_error" and r["position"] == 0]
    assert [r["count"] for r in comm] == [3, 7]
    assert m.lost_frames == 10
    assert [link.counters.lost_frames for link in m.links] == [10] * len(m.links)
    lines = [r for r in records if r["event"] == "log" and "lost" in r["text"]]
    assert len(lines) == 2


def test_a_damaged_line_is_never_quiet_a_healthy_one_again_after_repair() -> None:
    rig = default_in_op()
    m = master(rig)
    step = rig.clock.step_us
    rig.apply("master", "damage_cable", {"cable": 1, "percent": 1})
    run_ms(rig, 5)
    assert m.quiet_until(step) == m.now_us
    rig.apply("master", "repair_cable", {"cable": 1})
    assert not m.damaged


@pytest.mark.parametrize(("device", "position"), [
    ("master", 1), ("fastcat", 0), ("trscat", 1), ("cpx", 2), ("drive_ec", 3)])
def test_an_esc_switched_on_starts_at_0_whoever_switched_it(device: str, position: int) -> None:
    """docs/ethercat-master.md: "An ESC switched on starts at 0" — through the master's
    power_slave and through the slave's own power action alike (the line notices the power
    change at the master's next step)."""
    rig = default_in_op()
    rig.apply("master", "damage_cable", {"cable": position, "percent": 100})
    run_ms(rig, 5)
    rig.apply("master", "repair_cable", {"cable": position})
    assert errors(rig)[position]["invalid"][IN] == 5
    for on in (False, True):
        if device == "master":
            rig.apply("master", "power_slave", {"position": position, "on": on})
        else:
            rig.apply(device, "power", {"on": on})
        run_ms(rig, 50)
    assert errors(rig)[position] == EscErrors().snapshot()


def test_a_power_on_is_applied_at_one_step_the_steps_after_it_skip_the_line() -> None:
    """The power-on clear rides on the line's own change test (docs/performance.md): one
    step applies the change, the next ones skip the line and keep what the ESC counts."""
    rig = default_in_op()
    m = master(rig)
    rig.apply("trscat", "power", {"on": False})
    run_ms(rig, 5)
    rig.apply("trscat", "power", {"on": True})
    skipped = m.skipped.line
    run_ms(rig, 5)
    assert m.skipped.line == skipped + 4
    m.links[1].esc.invalid[IN] = 7
    run_ms(rig, 5)
    assert m.skipped.line == skipped + 9
    assert m.links[1].esc.invalid[IN] == 7


def test_the_last_frames_of_a_damage_are_reported_at_the_repair_not_with_a_later_one() -> None:
    """Repairing the last damaged cable reports the frames lost since the last report (the
    same comm_error / log line); a later, unrelated damage starts counting at 0 and is
    reported at its first lost frame."""
    rig = default_in_op()
    m = master(rig)

    def comm_counts(steps: int) -> tuple[list[int], int]:
        events = []
        for _ in range(steps):
            events += rig.step()
        records = [e.to_record() for e in events]
        return ([r["count"] for r in records
                 if r["event"] == "comm_error" and r["position"] == 0],
                sum(1 for r in records if r["event"] == "log" and "lost" in r["text"]))

    rig.apply("master", "damage_cable", {"cable": 1, "percent": 100})
    assert comm_counts(1500) == ([1, 1000], 2)
    rig.take_events()
    rig.apply("master", "repair_cable", {"cable": 1})
    records = [e.to_record() for e in rig.take_events()]
    assert [r["count"] for r in records
            if r["event"] == "comm_error" and r["position"] == 0] == [499]
    assert sum(1 for r in records if r["event"] == "log" and "499" in r["text"]) == 1
    assert m.crc_unreported == 0
    comm_counts(5000)
    rig.apply("master", "damage_cable", {"cable": 1, "percent": 100})
    assert comm_counts(1) == ([1], 1)


# A slave's own IN cable pulled (its own action, not the master's pull_cable): (device,
# action, args to pull, position).
OWN_IN_PULLS = [
    ("fastcat", "link", {"connected": False}, 0),
    ("trscat", "link", {"port": "in", "connected": False}, 1),
    ("cpx", "cable", {"port": "in", "connected": False}, 2),
    ("drive_ec-ecat", "link", {"connected": False}, 3),
]


@pytest.mark.parametrize(("device", "action", "args", "position"), OWN_IN_PULLS)
def test_a_cable_pulled_at_the_slave_carries_no_frame_to_count(
        device: str, action: str, args: dict, position: int) -> None:
    """The cable into a slave whose own IN link is down carries no frame: damaged, it spoils
    nothing, no ESC counts an invalid frame there (the frame turns at the slave before, as
    the master's step treats a slave that is not reachable)."""
    rig = default_in_op()
    m = master(rig)
    rig.apply(device, action, args)
    run_ms(rig, 100)
    lost = m.lost_frames
    rig.apply("master", "damage_cable", {"cable": position, "percent": 100})
    run_ms(rig, 10)
    e = errors(rig)
    assert [s["invalid"] for s in e] == [[0, 0]] * 4
    assert [s["forwarded"] for s in e] == [[0, 0]] * 4
    assert [s["epu"] for s in e] == [0] * 4
    assert m.lost_frames == lost


@pytest.mark.parametrize(("device", "action", "args", "position"), OWN_IN_PULLS)
def test_a_cable_pulled_at_the_slave_counts_a_lost_link_on_both_its_ends(
        device: str, action: str, args: dict, position: int) -> None:
    """As the master's pull_cable (ESC rule, 0x0310 + port): the slave's IN port and the OUT
    port of the slave before it (the master has no ESC) count the link that went down, once;
    plugged again, nothing more."""
    rig = default_in_op()
    rig.apply(device, action, args)
    run_ms(rig, 5)
    rig.apply(device, action, {**args, "connected": True})
    run_ms(rig, 5)
    want = [[0, 0] for _ in range(4)]
    want[position][IN] = 1
    if position:
        want[position - 1][OUT] = 1
    assert [s["lost_link"] for s in errors(rig)] == want


def test_clear_esc_errors_help_names_the_write_the_command_makes() -> None:
    """The command writes 0x0300-0x0313 (0x030C, the processing unit's counter, included); a
    write to 0x0300 and one to 0x0310 would leave 0x030C: the help names the range."""
    from devices.master.actions import MASTER_ACTIONS

    doc = MASTER_ACTIONS["clear_esc_errors"].doc
    assert "a master's write of 0x0300-0x0313" in doc
    rig = default_in_op()
    rig.apply("master", "damage_cable", {"cable": 2, "percent": 100})
    run_ms(rig, 5)
    assert errors(rig)[2]["epu"] == 5
    rig.apply("master", "clear_esc_errors", {"position": 2})
    assert errors(rig)[2] == EscErrors().snapshot()
