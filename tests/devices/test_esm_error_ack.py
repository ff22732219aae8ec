"""AL control bit 4, "Error Ind Ack" (ETG.1000.6; Beckhoff SSC ``AL_ControlInd``), on every
EtherCAT slave model through the shared ESM (devices/esm.py): while the AL status error flag
is set, a request without the acknowledge is ignored (a request for INIT excepted); with it
the flag and the AL status code are cleared and the request is processed."""

from __future__ import annotations

import random
from typing import Any

import pytest

from devices.coe.drive_slave import DriveEcatSlave
from devices.cpx.device import CpxEEc
from devices.ethercat import AlState
from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive
from devices.trscat.device import TrsCat

KINDS = ("fastcat", "trscat", "cpx", "coe")
INVALID_STATE_CHANGE = 0x0011  # seed 000 §7.7


class Line:
    """One slave on a 1 ms clock with a frame every step, as a master's cyclic task."""

    def __init__(self, kind: str) -> None:
        if kind == "fastcat":
            self.devices: list[Any] = [FastCat("fastcat", random.Random(1), [("DB16", {})],
                                               flash=MemoryFlash())]
        elif kind == "trscat":
            self.devices = [TrsCat("trscat", random.Random(1), [])]
        elif kind == "cpx":
            self.devices = [CpxEEc("cpx", random.Random(1), ["CPX-E-16DI"])]
        else:
            drive = ServoDrive("servo", random.Random(7), DriveConfig(fieldbus="ethercat"),
                               MemoryFlash())
            self.devices = [drive, DriveEcatSlave("servo-ecat", drive, random.Random(3))]
        self.slave = self.devices[-1]
        self.now = 0

    def run(self, steps: int) -> None:
        for _ in range(steps):
            self.now += 1_000
            for device in self.devices:
                device.step(self.now)
            self.slave.exchange_frame(self.now)

    def esm_events(self) -> list[str]:
        """The ESM's events since the last call (state changes, AL status codes)."""
        return [f"{e.kind}:{e.to_record()}" for d in self.devices for e in d.drain_events()
                if e.kind in ("state", "al_status")]

    def answer(self) -> tuple[AlState, int, int]:
        s = self.slave
        return s.al_state, s.al_status, s.al_status_code


def refused_in_preop(kind: str) -> Line:
    """The slave in PREOP after a refused PREOP -> OP: 0x12, code 0x0011."""
    line = Line(kind)
    line.run(3000)  # past every slave's power-up (FastCAT scan, TRS bus detection, drive test)
    line.slave.request_state(AlState.PREOP)
    line.run(5)
    assert line.answer() == (AlState.PREOP, 0x02, 0)
    line.slave.request_state(AlState.OP)  # not an ETG.1000.6 transition
    assert line.answer() == (AlState.PREOP, 0x12, INVALID_STATE_CHANGE)
    line.esm_events()
    return line


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("target", (AlState.PREOP, AlState.SAFEOP, AlState.OP))
def test_a_request_without_ack_over_the_error_flag_is_ignored(kind: str,
                                                              target: AlState) -> None:
    line = refused_in_preop(kind)
    line.slave.request_state(target)
    line.run(5)
    assert line.answer() == (AlState.PREOP, 0x12, INVALID_STATE_CHANGE)
    assert line.esm_events() == []


@pytest.mark.parametrize("kind", KINDS)
def test_the_current_state_with_ack_clears_the_flag_and_the_code(kind: str) -> None:
    line = refused_in_preop(kind)
    line.slave.request_state(AlState.PREOP, ack=True)
    assert line.answer() == (AlState.PREOP, 0x02, 0)


@pytest.mark.parametrize("kind", KINDS)
def test_init_without_ack_is_processed(kind: str) -> None:
    """SSC: "Error Acknowledge with 0xX1 is allowed"."""
    line = refused_in_preop(kind)
    line.slave.request_state(AlState.INIT)
    assert line.answer() == (AlState.INIT, 0x01, 0)


@pytest.mark.parametrize("kind", KINDS)
def test_a_refusal_again_after_the_ack_keeps_the_code_without_a_gap(kind: str) -> None:
    """The ack clears the flag, the request is refused again: the master reads the answer of
    the whole AL control write, 0x12 with 0x0011, and no 0x0000 in between."""
    line = refused_in_preop(kind)
    line.slave.request_state(AlState.OP, ack=True)
    assert line.answer() == (AlState.PREOP, 0x12, INVALID_STATE_CHANGE)
    assert line.esm_events() == []


@pytest.mark.parametrize("kind", KINDS)
def test_without_the_error_flag_the_ack_changes_nothing(kind: str) -> None:
    line = refused_in_preop(kind)
    line.slave.request_state(AlState.PREOP, ack=True)
    line.slave.request_state(AlState.INIT, ack=True)
    assert line.answer() == (AlState.INIT, 0x01, 0)
    line.run(3000)
    line.slave.request_state(AlState.PREOP)
    line.run(5)
    assert line.answer() == (AlState.PREOP, 0x02, 0)


UNKNOWN_REQUESTED_STATE = 0x0012  # seed 000 §7.7


def ignored_lines(line: Line) -> list[str]:
    """The slave's log lines since the last call that say a request was ignored."""
    return [e.text for d in line.devices for e in d.drain_events()
            if e.kind == "log" and e.device == line.slave.esm.device and "ignored" in e.text]


@pytest.mark.parametrize("kind", KINDS)
def test_an_unknown_state_without_ack_over_the_error_flag_is_ignored(kind: str) -> None:
    """SSC AL_ControlInd / SOES ESC_state: over the flag only INIT or the acknowledge gets
    past; an unknown state code is neither, so the original cause (0x0011) stays."""
    line = refused_in_preop(kind)
    line.slave.esm.request_unknown(0x05, False, line.now)
    line.run(5)
    assert line.answer() == (AlState.PREOP, 0x12, INVALID_STATE_CHANGE)
    assert line.esm_events() == []


@pytest.mark.parametrize("kind", KINDS)
def test_an_unknown_state_with_ack_answers_0x0012(kind: str) -> None:
    line = refused_in_preop(kind)
    line.slave.esm.request_unknown(0x05, True, line.now)
    assert line.answer() == (AlState.PREOP, 0x12, UNKNOWN_REQUESTED_STATE)


@pytest.mark.parametrize("kind", KINDS)
def test_an_unknown_state_without_the_error_flag_answers_0x0012(kind: str) -> None:
    line = refused_in_preop(kind)
    line.slave.request_state(AlState.PREOP, ack=True)
    line.slave.esm.request_unknown(0x0F, False, line.now)
    assert line.answer() == (AlState.PREOP, 0x12, UNKNOWN_REQUESTED_STATE)


@pytest.mark.parametrize("kind", KINDS)
def test_an_ignored_request_is_logged_once_per_error_episode(kind: str) -> None:
    """A master repeating a request without bit 4 every cycle gets one line per episode and
    requested state, naming the state, the missing acknowledge and the code kept."""
    line = refused_in_preop(kind)
    ignored_lines(line)
    for _ in range(5):
        line.slave.request_state(AlState.SAFEOP)
        line.run(1)
    lines = ignored_lines(line)
    assert len(lines) == 1
    assert "'SAFEOP'" in lines[0] and "bit 4" in lines[0] and "0x0011" in lines[0]
    for _ in range(3):
        line.slave.request_state(AlState.OP)
        line.slave.esm.request_unknown(0x05, False, line.now)
        line.run(1)
    lines = ignored_lines(line)
    assert len(lines) == 2 and "'OP'" in lines[0] and "0x05" in lines[1]
    line.slave.request_state(AlState.OP, ack=True)  # refused again: a new episode
    assert line.answer() == (AlState.PREOP, 0x12, INVALID_STATE_CHANGE)
    line.slave.request_state(AlState.SAFEOP)
    assert len(ignored_lines(line)) == 1


@pytest.mark.parametrize("kind", KINDS)
def test_a_processed_request_logs_no_ignore(kind: str) -> None:
    line = refused_in_preop(kind)
    ignored_lines(line)
    line.slave.request_state(AlState.INIT)
    line.slave.request_state(AlState.PREOP, ack=True)
    assert ignored_lines(line) == []
