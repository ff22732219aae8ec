"""The supplies the snapshot reports are what a meter at [XD] reads: an injected undervoltage
(seed 002 Tab. 21 0x3120 / 0x3320, Tab. 29) is that supply sagged below tolerance, so the
reading drops with it beside PS / PL blinking, and is the set value again once cleared
(docs/cpx-e-ec.md choice 27)."""

from __future__ import annotations

from typing import Any

import pytest
from cpx_bench import STI, tab9

from devices.cpx.actions import ACTIONS
from devices.cpx.device import INJECTED_SAG_V, SUPPLY_MIN_V
from devices.ethercat import AlState

# fault -> (the snapshot's volts key, its ok key, its LED, the supply action's keyword)
SUPPLIES = {"undervoltage_out": ("out_v", "out_ok", "PL", "out"),
            "undervoltage_el_sen": ("el_sen_v", "el_sen_ok", "PS", "el_sen")}


def _reading(bench: Any, fault: str) -> tuple[float, bool, str]:
    volts, ok, led, _ = SUPPLIES[fault]
    supply = bench.cpx.snapshot()["supply"]
    return supply[volts], supply[ok], bench.led(led)


def test_the_sag_is_an_undervoltage_the_electronics_ride() -> None:
    assert 10.0 <= INJECTED_SAG_V < SUPPLY_MIN_V  # device.py BROWNOUT_V .. Tab. 29's 18 V


@pytest.mark.parametrize("fault", list(SUPPLIES))
def test_an_injected_undervoltage_reads_below_tolerance_until_cleared(fault: str) -> None:
    keyword = SUPPLIES[fault][3]
    bench = tab9().to_op()
    assert _reading(bench, fault) == (24.0, True, "on")
    bench.apply("inject_fault", fault=fault)
    bench.run(0.01)
    assert _reading(bench, fault) == (INJECTED_SAG_V, False, "blinking")
    assert bench.cpx.powered
    # a supply set lower still is what the meter reads; the fault cannot raise it
    bench.apply("supply", **{keyword: 12.0})
    bench.run(0.01)
    assert _reading(bench, fault) == (12.0, False, "blinking")
    bench.apply("supply", **{keyword: 24.0})
    bench.run(0.01)
    assert _reading(bench, fault) == (INJECTED_SAG_V, False, "blinking")
    bench.apply("clear_fault", fault=fault)
    bench.run(0.01)
    assert _reading(bench, fault) == (24.0, True, "on")


def _seen(fault: str, injected: bool) -> dict[str, Any]:
    bench = tab9(**STI).to_op()
    if injected:
        bench.apply("inject_fault", fault=fault)
    else:
        bench.apply("supply", **{SUPPLIES[fault][3]: INJECTED_SAG_V})
    bench.run(0.05)
    snap = {k: v for k, v in bench.cpx.snapshot().items() if k != "injected"}
    snap["events"] = [e.to_record() for e in bench.events]
    return snap


@pytest.mark.parametrize("fault", list(SUPPLIES))
def test_an_injected_undervoltage_is_the_supply_sagged(fault: str) -> None:
    """faults.py: a fault with a physical cause sets that condition, as the physical action
    does; the instructor's list of injections is all that tells the two apart."""
    assert _seen(fault, injected=True) == _seen(fault, injected=False)


def test_a_bridged_dip_is_ridden_through_and_still_seen() -> None:
    """Tab. 29's 20 ms bridging keeps the electronics running through a shorter dip of
    U_EL/SEN, not the supply at [XD]: the bus module stays in OP with its history, and its
    supply monitor sees the dip as any undervoltage — CPX error 8 on module 0 (0x3120), PS
    dark while the terminals read 0 V — which goes when the supply is back
    (docs/cpx-e-ec.md choice 27)."""
    bench = tab9(history_flags=0x0001, **STI).to_op()
    since = len(bench.events)
    bench.apply("supply", el_sen=0.0)
    bench.run(0.015)
    assert bench.cpx.powered and bench.led("PS") == "off"
    assert [e["name"] for e in bench.cpx.snapshot()["diagnosis"]["errors"]] == ["UNDERVOLTAGE"]
    bench.apply("supply", el_sen=24.0)
    bench.run(0.01)
    assert bench.cpx.al_state is AlState.OP and bench.led("PS") == "on"
    assert [(r["code"], r["active"]) for r in bench.records("alarm", since)] == [
        ("0x3708", True), ("0x3708", False)]
    assert [r["code"] for r in bench.records("emergency", since)] == ["0x3120", "0x0000"]
    assert [m["text_id"] for m in bench.cpx.snapshot()["history"]["messages"]][-2:] == [
        "0x3708", "0x3700"]


def test_the_supply_action_puts_only_u_el_sen_at_xd() -> None:
    """Tab. 8: the bus module's [XD] carries +24 V / 0 V of U_EL/SEN (XD.0-XD.1, XD.2-XD.3
    bridged), no U_OUT: the form's words must not send a trainee to [XD] to measure the load
    supply (PL, Fig. 3), which the seed does not place."""
    doc = ACTIONS["supply"].doc
    assert "U_EL/SEN at [XD]" in doc and "U_OUT" in doc
    assert "U_OUT at [XD]" not in doc and "voltages at [XD]" not in doc
