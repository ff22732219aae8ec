"""The snapshot's ``causes`` and ``config``: the facts behind the FastCAT's alarm causes
(seed 000 §7.5, §7.6) and the rail as a scan would find it now against flash and the last
scan (§2, §3), for the State tab (devices/fastcat/causes.py)."""

from __future__ import annotations

import pytest
from fastcat_bench import Bench

from devices.device import CommandError
from devices.ethercat import AlState
from devices.fastcat.causes import first_difference
from devices.flash import MemoryFlash


def _stored_bench(modules: tuple[str, ...] = ("DB16", "AI8D", "AI8C")) -> Bench:
    flash = MemoryFlash()
    flash.save(("[" + ", ".join(f'"{m}"' for m in modules) + "]").encode())
    bench = Bench(modules, flash=flash)
    bench.to_state(AlState.OP)
    return bench


def _physical(bench: Bench) -> list[tuple[int | None, int, str]]:
    return [(c["code"], c["module"], c["text"]) for c in bench.fc.snapshot()["causes"]
            if not c["injected"]]


def test_first_difference() -> None:
    assert first_difference(["a", "b"], ["a", "b"]) is None
    assert first_difference(["a", "b"], ["a", "c"]) == 2
    assert first_difference(["a"], ["a", "b"]) == 2
    assert first_difference([], ["a"]) == 1


def test_a_module_without_supply_is_named() -> None:
    bench = _stored_bench()
    bench.apply("module_power", module=2, on=False)
    bench.step()
    assert _physical(bench) == [
        (0x04, 2, "module 2 (AI8D, slot 2) does not answer: its supply is off")]
    config = bench.fc.snapshot()["config"]
    assert config["now"] == [[1, "DB16"], [3, "AI8C"]]
    assert config["vs_flash"] == 2 and config["vs_scan"] == 2


def test_a_scan_with_a_module_less_than_flash_is_named() -> None:
    """§7.5 0x02: after a rescan without the last module the scan has fewer than flash."""
    bench = _stored_bench()
    bench.apply("unplug", module=3)
    bench.fc.request_state(AlState.INIT)
    bench.run_until(lambda: bench.fc.scan is None)
    assert (0x02, 3, "flash has 3 modules, the last scan found 2: module 3 (AI8C) missing") \
        in _physical(bench)
    config = bench.fc.snapshot()["config"]
    assert config["vs_flash"] == 3 and config["vs_scan"] is None  # the scan is the rail's


def test_an_injected_cause_is_marked_so() -> None:
    bench = _stored_bench()
    bench.apply("inject_fault", fault="MISSING_NODE_ANSWER", module=2)
    causes = bench.fc.snapshot()["causes"]
    assert [(c["code"], c["module"], c["injected"]) for c in causes] == [(0x04, 2, True)]


def test_tbus_low_without_a_scanned_module_is_still_a_fact() -> None:
    bench = Bench()
    bench.apply("tbus_voltage", low=True)
    assert _physical(bench) == [(None, 0, "Tbus supply low")]



def test_the_facts_name_an_analog_module_with_an() -> None:
    """Every analog and encoder type starts with a vowel sound (AI8D, AO4, AX2): the State
    tab read "the last scan found a AI8D there", a plug refusal "taken by a AO4"."""
    bench = _stored_bench()
    bench.apply("unplug", module=2)
    bench.step()
    assert _physical(bench) == [
        (0x04, 2, "slot 2 empty (module 2: the last scan found an AI8D there)")]
    bench.apply("plug", module=2, type="DI16")
    bench.step()
    assert _physical(bench)[0][2] == ("slot 2 holds a DI16, the last scan found an AI8D "
                                      "there (module 2)")
    with pytest.raises(CommandError) as caught:
        bench.apply("plug", module=3, type="DB16")
    assert str(caught.value) == "fastcat: rail position 3 is taken by an AI8C: unplug it first"


def test_a_modules_refusal_names_it_with_its_article() -> None:
    bench = _stored_bench()
    with pytest.raises(CommandError, match=r"^an AI8D module has no action 'nope'"):
        bench.fc.rail_module(2).apply("nope", {})
    with pytest.raises(CommandError, match=r"^a DB16 module has no action 'nope'"):
        bench.fc.rail_module(1).apply("nope", {})


def test_a_cause_behind_the_latched_alarm_is_marked_not_latched() -> None:
    """§7: only the first alarm is signalled. The facts say which cause is the latched
    alarm's, so a view can tell a pulled module that waits behind a module alarm from the
    one that is signalled (before, both read the same)."""
    bench = _stored_bench()
    bench.apply("inject_fault", module=1, fault="TARATURA")
    bench.step()
    bench.apply("unplug", module=3)
    bench.step()
    causes = bench.fc.snapshot()["causes"]
    assert [(c["code"], c["module"], c["latched"]) for c in causes] == [
        (0x0B, 1, True), (0x04, 3, False)]
    bench.apply("clear_fault", module=1, fault="TARATURA")
    bench.reset_fault()
    causes = bench.fc.snapshot()["causes"]
    assert [(c["code"], c["module"], c["latched"]) for c in causes] == [(0x04, 3, True)]
