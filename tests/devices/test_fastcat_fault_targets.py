"""A §7.6 module fault names a module (byte 0 of the emergency): one the coupler cannot have
there is refused, at run time and at a scenario's or exercise file's check, with one line
naming the empty position and the modules there are (docs/fastcat-coupler.md "Injection")."""

from __future__ import annotations

import pytest
from fastcat_bench import Bench

from devices.device import CommandError
from devices.fastcat.alarms import MODULE

FOUR = ("DB16", "DI16", "DO16", "AI8D")
SEVEN = ("DB16", "DI16", "DO16", "AI8D", "AO4", "AI8TC", "AX2")


def refusal(call: object) -> str:
    with pytest.raises(CommandError) as caught:
        call()  # type: ignore[operator]
    return str(caught.value)


def test_a_module_fault_past_the_last_module_is_refused_at_run_time() -> None:
    bench = Bench(FOUR)
    bench.settle()
    said = refusal(lambda: bench.apply("inject_fault", module=5, fault="TARATURA"))
    assert said == (
        "fastcat: TARATURA is a module alarm (§7.6): there is no module 5, rail "
        "position 5 is empty (modules: 1=DB16, 2=DI16, 3=DO16, 4=AI8D)"
    )
    assert bench.fc.injected == [] and not bench.fc.snapshot()["fault_active"]


def test_a_module_fault_on_a_slot_emptied_since_the_scan_is_refused() -> None:
    """Slot 5 pulled: the last scan's module 5 is not on the rail to raise a §7.6 alarm."""
    bench = Bench(SEVEN)
    bench.settle()
    bench.apply("unplug", module=5)
    said = refusal(lambda: bench.apply("inject_fault", module=5, fault="module:0x04"))
    assert said == (
        "fastcat: ALARM_IO_FAULT is a module alarm (§7.6): there is no module 5, "
        "rail position 5 is empty (modules: 1=DB16, 2=DI16, 3=DO16, 4=AI8D, "
        "6=AI8TC, 7=AX2)"
    )


def test_the_check_before_a_run_refuses_it_with_the_same_words() -> None:
    bench = Bench(SEVEN)
    fc = bench.fc
    layout = fc.module_layout()
    fc.check_module("unplug", {}, 5, layout)
    args = fc.check_command("inject_fault", {"fault": "module:0x04"}, 5)
    said = refusal(lambda: fc.check_module("inject_fault", args, 5, layout))
    assert said == (
        "fastcat: ALARM_IO_FAULT is a module alarm (§7.6): there is no module 5, "
        "rail position 5 is empty (modules: 1=DB16, 2=DI16, 3=DO16, 4=AI8D, "
        "6=AI8TC, 7=AX2)"
    )
    said = refusal(lambda: fc.check_module("inject_fault", args, 8, fc.module_layout()))
    assert "there is no module 8, rail position 8 is empty (modules: 1=DB16" in said


def test_a_module_fault_on_a_module_there_is_taken() -> None:
    bench = Bench(SEVEN)
    bench.settle()
    fc = bench.fc
    args = fc.check_command("inject_fault", {"fault": "TARATURA"}, 7)
    fc.check_module("inject_fault", args, 7, fc.module_layout())
    bench.apply("inject_fault", module=7, fault="TARATURA")
    bench.step()
    assert fc.alarm is not None and (fc.alarm.table, fc.alarm.module) == (MODULE, 7)


def test_after_a_rescan_the_module_number_is_the_buses() -> None:
    """Byte 0 is the module number the scan gave (§7): with slot 5 empty and a CNF rescan,
    module 5 is the AI8TC in slot 6, and the fault on module 5 is taken."""
    bench = Bench(SEVEN)
    bench.settle()
    bench.apply("unplug", module=5)
    bench.apply("hold_cnf", seconds=3.0)
    bench.run(10.0)  # 3 s hold, then reset, scan and store
    assert bench.fc.detected[4] == (6, "AI8TC")
    bench.apply("inject_fault", module=5, fault="TARATURA")
    said = refusal(lambda: bench.apply("inject_fault", module=7, fault="TARATURA"))
    assert said.endswith(
        "there is no module 7: the last scan numbered 6 (modules: 1=DB16, "
        "2=DI16, 3=DO16, 4=AI8D, 5=AI8TC, 6=AX2)"
    ), said


def test_a_fault_injected_before_the_unplug_can_still_be_cleared() -> None:
    bench = Bench(SEVEN)
    bench.settle()
    bench.apply("inject_fault", module=5, fault="TARATURA")
    bench.apply("unplug", module=5)
    bench.apply("clear_fault", module=5, fault="TARATURA")
    assert bench.fc.injected == []


def test_a_coupler_code_naming_an_empty_position_is_taken() -> None:
    """§7.5 codes whose byte 0 names a node are about a missing one too (0x02 MODULE_NO_PRES,
    0x04 MISSING_NODE_ANSWER): the coupler reports them for an empty position."""
    bench = Bench(FOUR)
    bench.settle()
    bench.apply("inject_fault", module=5, fault="MODULE_NO_PRES")
    bench.step()
    assert bench.emergencies() == ["05 00 00 02 00"]
