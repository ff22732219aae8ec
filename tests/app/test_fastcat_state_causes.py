"""The FastCAT State tab names the rail's physical causes and tells the truth about flash.

Seed 000 §2 / §7.5: a module pulled or replaced by another type latches 0x04 / 0x01 with its
cause present. Before, the Causes row listed only the cable and the Tbus ("none" next to
"cause present") and the Configuration badge compared flash with the last scan only, so it
stayed "matches flash" with another module on the rail (/tmp/s14/ui/11_reset_wrongmodule.png).
"""

from __future__ import annotations

import random

from app.ui.panels.state import state_rows
from devices.ethercat import AlState
from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash

STEP_US = 1_000
RAIL = ("DB16", "DI16", "DO16", "AI8D")


class Coupler:
    """A FastCAT stepped by hand, its configuration stored by a CNF press (§2), brought to OP
    with a master's frame after every step from SAFEOP on (its SM watchdog wants them)."""

    def __init__(self) -> None:
        self.fc = FastCat("fastcat", random.Random(3), [(m, {}) for m in RAIL],
                          flash=MemoryFlash())
        self.now = 0
        self.frames = False
        self.run(3.0)
        self.fc.apply("hold_cnf", {"seconds": 3.5})
        self.run(7.0)
        assert self.fc.stored == list(RAIL)
        self.frames = True
        self.fc.exchange_frame(self.now)
        for target in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
            self.fc.request_state(target)
        assert self.fc.al_state is AlState.OP

    def run(self, seconds: float) -> None:
        end = self.now + round(seconds * 1_000_000)
        while self.now < end:
            self.now += STEP_US
            self.fc.step(self.now)
            if self.frames:
                self.fc.exchange_frame(self.now)

    def apply(self, action: str, module: int | None = None, **args: object) -> None:
        self.fc.apply(action, args, module)
        self.run(0.01)

    def reset_fault(self) -> None:
        self.apply("set_reset_fault", on=False)
        self.apply("set_reset_fault", on=True)

    def rows(self) -> dict[str, str]:
        return dict(state_rows(self.fc.snapshot()))


def test_a_pulled_module_is_named_in_causes_and_configuration() -> None:
    rig = Coupler()
    assert "matches flash" in rig.rows()["Configuration"]
    rig.apply("unplug", module=3)
    rows = rig.rows()
    assert "MISSING_NODE_ANSWER" in rows["Alarm"] and "cause present" in rows["Alarm"]
    assert "slot 3 empty" in rows["Causes"] and "DO16" in rows["Causes"]
    assert "differs from flash" in rows["Configuration"]
    assert "matches flash" not in rows["Configuration"]
    assert "slot 3 empty: the last scan (at t = " in rows["Configuration"]


def test_a_module_of_another_type_is_named_in_causes_and_configuration() -> None:
    """The reviewer's steps: OP, unplug the DO16 of slot 3, plug a DB16, Reset fault."""
    rig = Coupler()
    rig.apply("unplug", module=3)
    rig.apply("plug", module=3, type="DB16")
    rig.reset_fault()
    rows = rig.rows()
    assert "cause present" in rows["Alarm"]
    assert "slot 3 holds a DB16" in rows["Causes"] and "DO16" in rows["Causes"]
    config = rows["Configuration"]
    assert "differs from flash" in config and "module 3: DB16" in config
    assert "flash DO16" in config and "slot 3 holds a DB16: the last scan (at t = " in config


def test_the_right_module_back_matches_flash_and_leaves_no_cause() -> None:
    rig = Coupler()
    rig.apply("unplug", module=3)
    rig.apply("plug", module=3, type="DO16")
    rig.reset_fault()
    rows = rig.rows()
    assert rig.fc.alarm is None
    assert "none" in rows["Causes"]
    assert "matches flash" in rows["Configuration"] and "older" not in rows["Configuration"]


def test_cable_and_tbus_are_still_named() -> None:
    rig = Coupler()
    rig.apply("tbus_voltage", low=True)
    rig.apply("link", connected=False)
    causes = rig.rows()["Causes"]
    assert "EtherCAT cable out" in causes and "Tbus supply low" in causes


def test_an_injected_cause_stays_out_of_causes() -> None:
    """Injected causes have their own row (Injected); Causes is the rail's physical ones."""
    rig = Coupler()
    rig.apply("inject_fault", module=2, fault="MISSING_NODE_ANSWER")
    rows = rig.rows()
    assert "MISSING_NODE_ANSWER on module 2" in rows["Injected"]
    assert "none" in rows["Causes"]


def test_a_cause_waiting_behind_the_latched_alarm_says_it_is_not_signalled() -> None:
    """§7 "il primo allarme ricevuto": a module pulled while a module alarm is latched sends
    nothing. The instructor's Causes row said "slot 3 empty" as it does for the signalled
    0x04, beside an Alarm row naming another alarm and the ESM in OP."""
    rig = Coupler()
    rig.apply("inject_fault", module=2, fault="TARATURA")
    rig.apply("unplug", module=3)
    causes = rig.rows()["Causes"]
    assert "slot 3 empty" in causes
    assert "not signalled: 0x0B TARATURA latched first (§7)" in causes
    rig.apply("clear_fault", module=2, fault="TARATURA")
    rig.reset_fault()
    causes = rig.rows()["Causes"]
    assert "slot 3 empty" in causes and "not signalled" not in causes


LAST_SCAN = r"the last scan \(at t = (\d+(?:\.\d+)?) s\)"


def _scan_note(rig: Coupler, fact: str) -> None:
    """The Configuration row's note on the last scan: ``fact``, then when that scan ran (the
    CNF press of Coupler: released at 6.5 s, the scan done before 10 s)."""
    import re

    config = rig.rows()["Configuration"]
    assert "older than the rail" not in config, config
    found = re.search(re.escape(fact).replace(re.escape("{scan}"), LAST_SCAN), config)
    assert found, config
    assert 6.5 < float(found.group(1)) < 10.0, config


def test_a_module_without_supply_is_named_as_not_powered() -> None:
    """A walk-through: a module switched off read "last scan older than the rail: it found
    DO16 as module 3", which no trainee understood. It says what is wrong at the rail, in
    the Causes row's words, and when the scan it is compared with ran (seed 000: the coupler
    scans the Tbus at a CNF press, §2, and whenever it returns to Init, §3)."""
    rig = Coupler()
    rig.apply("module_power", module=3, on=False)
    _scan_note(rig, "module 3 not powered (its supply is off): {scan} found a DO16 in slot 3")


def test_every_difference_from_the_last_scan_is_worded_at_the_rail() -> None:
    rig = Coupler()
    rig.apply("module_failure", module=3, active=True)
    _scan_note(rig, "module 3 does not answer: {scan} found a DO16 in slot 3")
    rig = Coupler()
    rig.apply("unplug", module=3)
    _scan_note(rig, "slot 3 empty: {scan} found a DO16 there (module 3)")
    rig.apply("plug", module=3, type="DB16")
    _scan_note(rig, "slot 3 holds a DB16: {scan} found a DO16 there (module 3)")
    rig = Coupler()
    rig.apply("plug", module=5, type="DI16")
    _scan_note(rig, "slot 5 holds a DI16 that {scan} did not find (it would be module 5)")
