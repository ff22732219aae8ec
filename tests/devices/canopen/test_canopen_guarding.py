"""Heartbeat and node guarding (seed 004 ch. 4 "Node Monitoring via Node-Guarding or Heartbeat
Messages", "Note sui servizi di Guard", example "Abilitazione e disabilitazione del servizio
node guarding").
"""

from __future__ import annotations

import pytest
from canopen_bench import hexs, make_bench

from devices.canopen.nmt import NmtCommand


def _heartbeats(bench, ms: float) -> list:
    bench.take()
    bench.run(ms)
    return [f for f in bench.take() if f.can_id == 0x701]


def test_heartbeat_seed_example_4000_ms() -> None:
    """"2B 17 10 00 A0 0F 00 00" -> "60 17 10 00 00 00 00 00"; then one heartbeat every
    4 s with the state byte (0x7F pre-operational, 0x05 operational), bit 7 constant 0."""
    bench = make_bench(n1=8)
    assert bench.sdo("2B 17 10 00 A0 0F 00 00") == "60 17 10 00 00 00 00 00"
    written = bench.t_us
    beats = _heartbeats(bench, 8_500)
    assert [hexs(f.data) for f in beats] == ["7F", "7F"]
    first = beats[0].t_us - written
    assert 3_995_000 <= first <= 4_001_000
    assert beats[1].t_us - beats[0].t_us == 4_000_000  # exact period, simulated time
    bench.nmt(NmtCommand.START)
    assert {hexs(f.data) for f in _heartbeats(bench, 8_000)} == {"05"}
    bench.nmt(NmtCommand.STOP)
    assert {hexs(f.data) for f in _heartbeats(bench, 8_000)} == {"04"}


def test_heartbeat_zero_disables() -> None:
    """"Il valore 0 disattiva il meccanismo dell'heartbeat"."""
    bench = make_bench()
    bench.ok(0x1017, 0, 100, 2)
    assert len(_heartbeats(bench, 1_000)) == 10
    bench.ok(0x1017, 0, 0, 2)
    assert _heartbeats(bench, 1_000) == []


def _guard_answers(bench, count: int) -> list[str]:
    out = []
    for _ in range(count):
        bench.take()
        bench.send(0x701, rtr=True, dlc=1)
        bench.run(3)
        out += [hexs(f.data) for f in bench.take() if f.can_id == 0x701]
    return out


@pytest.mark.parametrize(("guard_ms", "heartbeat_ms", "answers"), [
    (500, 0, ["7F", "FF", "7F", "FF"]),  # guarding: the toggle bit alternates, first 0
    (500, 1000, ["7F", "7F", "7F", "7F"]),  # heartbeat on: "senza variare il toggle bit"
    (0, 1000, ["7F", "7F", "7F", "7F"]),
    (0, 0, []),  # neither active: no answer
])
def test_guarding_answers(guard_ms: int, heartbeat_ms: int, answers: list[str]) -> None:
    bench = make_bench()
    bench.ok(0x100C, 0, guard_ms, 2)
    bench.ok(0x1017, 0, heartbeat_ms, 2)
    assert _guard_answers(bench, 4) == answers


def test_guarding_answers_a_remote_request_with_dlc_zero() -> None:
    """"La risposta viene inviata anche se il campo DLC nella richiesta è posto a zero"."""
    bench = make_bench()
    bench.ok(0x100C, 0, 500, 2)
    bench.take()
    bench.send(0x701, rtr=True, dlc=0)
    bench.run(3)
    assert [hexs(f.data) for f in bench.take()] == ["7F"]


def test_life_guarding_emcy_once_not_reset() -> None:
    """Seed example: guard time 500 ms, life time factor 2. Without remote requests for
    1 s the drive sends an EMCY (0x8130, communication bit); when requests resume it answers
    again; "L'EMCY non viene resettato": no error-reset EMCY, 0x1001 keeps bit 4."""
    bench = make_bench()
    bench.ok(0x100C, 0, 500, 2)
    bench.ok(0x100D, 0, 2, 1)
    assert _guard_answers(bench, 1) == ["7F"]
    start = bench.node.guard.last_request_us
    bench.take()
    bench.run(2_500)
    emcys = [f for f in bench.take() if f.can_id == 0x081]
    assert [hexs(f.data) for f in emcys] == ["30 81 11 00 00 00 00 00"]
    assert 1_000_000 < emcys[0].t_us - start <= 1_002_000  # life time, then the frame
    assert _guard_answers(bench, 2) == ["FF", "7F"]
    bench.run(500)
    assert [f for f in bench.take() if f.can_id == 0x081] == []
    assert bench.read(0x1001) == 0x11
    assert bench.read(0x1003, 1) == 0x8130


def test_guarding_off_stops_life_guarding() -> None:
    """Seed example "Disabilitazione del node guarding": 100C = 0, 100D = 0."""
    bench = make_bench()
    bench.ok(0x100C, 0, 500, 2)
    bench.ok(0x100D, 0, 2, 1)
    _guard_answers(bench, 1)
    bench.ok(0x100C, 0, 0, 2)
    bench.ok(0x100D, 0, 0, 1)
    bench.take()
    bench.run(3_000)
    assert [f for f in bench.take() if f.can_id == 0x081] == []


@pytest.mark.parametrize("heartbeat_ms", [0, 1000])
def test_life_guarding_starts_with_a_request_made_while_guarding_is_on(heartbeat_ms: int) -> None:
    """"Il servizio di Node Guarding è attivo se l'oggetto 0x100C è diverso da zero": a
    remote request made while 0x100C = 0 (unanswered, or answered for the heartbeat) is no
    guarding request. Guard time and life time factor written seconds later start no life
    time from it: no EMCY 0x8130 before the master guards and stops."""
    bench = make_bench()
    bench.ok(0x1017, 0, heartbeat_ms, 2)
    bench.send(0x701, rtr=True, dlc=1)
    bench.run(5_000)
    bench.ok(0x100C, 0, 500, 2)
    bench.ok(0x100D, 0, 2, 1)
    bench.take()
    bench.run(3_000)
    assert [f for f in bench.take() if f.can_id == 0x081] == []
    assert bench.read(0x1001) == 0
    assert _guard_answers(bench, 1) == ["7F"]  # guarding starts now: first toggle 0
    bench.take()
    bench.run(1_100)
    assert [hexs(f.data) for f in bench.take() if f.can_id == 0x081] \
        == ["30 81 11 00 00 00 00 00"]


def _emcys(bench) -> list[str]:
    return [hexs(f.data) for f in bench.take() if f.can_id == 0x081]


def test_a_life_time_factor_written_after_guarding_started_counts_from_the_next_request() -> None:
    """Guarding on (0x100C = 500 ms, 0x100D = 0: answers, no life guarding), one request, then
    the master pauses. Writing 0x100D = 2 three seconds later starts life guarding over: the
    life time 0x100C x 0x100D counts from the master's next request, not from the old one
    (which would send EMCY 0x8130 at once, 2 s "late" before the factor even existed)."""
    bench = make_bench()
    bench.ok(0x100C, 0, 500, 2)
    assert _guard_answers(bench, 1) == ["7F"]
    bench.run(3_000)
    bench.take()
    bench.ok(0x100D, 0, 2, 1)
    bench.run(3_000)
    assert _emcys(bench) == []
    assert bench.read(0x1001) == 0
    assert _guard_answers(bench, 1) == ["FF"]  # the toggle goes on: guarding never stopped
    start = bench.node.guard.last_request_us
    bench.take()
    bench.run(1_100)
    frames = [f for f in bench.take() if f.can_id == 0x081]
    assert [hexs(f.data) for f in frames] == ["30 81 11 00 00 00 00 00"]
    assert 1_000_000 < frames[0].t_us - start <= 1_002_000


@pytest.mark.parametrize(("index", "value", "size", "life_ms"), [
    (0x100D, 1, 1, 500),  # factor 2 -> 1: 500 ms
    (0x100D, 4, 1, 2_000),  # factor 2 -> 4: 2 s
    (0x100C, 300, 2, 600),  # guard time 500 -> 300 ms: 600 ms
])
def test_a_new_life_time_applies_from_the_next_request(index, value, size, life_ms) -> None:
    """Life guarding running (500 ms x 2) and the master guarding every 400 ms: a write of
    0x100D or 0x100C 700 ms after a request (past the new 500 / 600 ms life time) sends no
    EMCY; the new life time is watched from the next request on."""
    bench = make_bench()
    bench.ok(0x100C, 0, 500, 2)
    bench.ok(0x100D, 0, 2, 1)
    for _ in range(3):
        _guard_answers(bench, 1)
        bench.run(400)
    _guard_answers(bench, 1)
    bench.run(700)
    bench.take()
    bench.ok(index, 0, value, size)
    bench.run(300)
    assert _emcys(bench) == []
    _guard_answers(bench, 1)
    start = bench.node.guard.last_request_us
    bench.take()
    bench.run(life_ms + 100)
    frames = [f for f in bench.take() if f.can_id == 0x081]
    assert [hexs(f.data) for f in frames] == ["30 81 11 00 00 00 00 00"]
    assert life_ms * 1_000 < frames[0].t_us - start <= life_ms * 1_000 + 2_000


def test_the_request_that_ends_a_life_guard_error_is_answered_and_rearms_the_flag() -> None:
    """"Quando il master ricomincia ad inviare Remote Request il drive abbassa il flag e
    ricomincia a rispondere" (ch. 4 "Servizi di Guard"): the drive never refuses a guard
    request; "ricomincia a rispondere" because the master had stopped asking. The first
    request after the expiry is answered at once, the toggle going on, and drops the flag:
    a new silence of one life time raises it again and sends a second EMCY 0x8130, still
    with no error reset (docs/canopen.md §Heartbeat)."""
    bench = make_bench()
    bench.ok(0x100C, 0, 100, 2)
    bench.ok(0x100D, 0, 2, 1)
    assert _guard_answers(bench, 1) == ["7F"]
    bench.run(300)
    assert _emcys(bench) == ["30 81 11 00 00 00 00 00"]
    asked = bench.t_us
    bench.send(0x701, rtr=True, dlc=1)
    bench.run(3)
    answers = [f for f in bench.take() if f.can_id == 0x701]
    assert [hexs(f.data) for f in answers] == ["FF"]
    assert answers[0].t_us - asked <= 1_000  # the request's and the answer's frame times
    bench.run(150)
    assert _emcys(bench) == []  # the life time runs again from that request
    bench.run(100)
    assert _emcys(bench) == ["30 81 11 00 00 00 00 00"]
    assert _guard_answers(bench, 2) == ["7F", "FF"]
    bench.run(150)
    assert _emcys(bench) == []
    assert bench.read(0x1001) == 0x11
