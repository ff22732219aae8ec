"""The Line tab's slave forms list only what their Target takes (docs/classroom.md, "What a
trainee does not see"). The model says which actions a target takes (``target_actions``: the
action table's ``module`` and, on a module, its type), as a FastCAT rail module says it for
Module I/O (``available_actions``). Before, the CPX-E-EC's form on ``cpx/2`` offered set_dil,
set_rotary and the device-level cable / power / supply, which the device then refused."""

from __future__ import annotations

import time
from typing import Any

from served_dashboard import drawn, served_default_rig

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.ui.line.target_actions import TargetActions, Watch

DEVICE_ONLY = {"power", "supply", "cable", "set_rotary", "set_dil", "restart"}


def test_the_cpx_says_what_each_target_takes() -> None:
    cpx = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None).device("cpx")
    device = set(cpx.target_actions(None))
    assert DEVICE_ONLY | {"inject_fault", "clear_fault"} <= device
    assert not device & {"set_input", "short_circuit", "force", "replace_module"}
    # the default rig: 1 = 16DI, 2 = 8DO, 3 = 4AI-U-I, 4 = 4AO-U-I
    do8 = set(cpx.target_actions(2))
    assert {"force", "short_circuit", "inject_fault", "replace_module"} <= do8
    assert not do8 & (DEVICE_ONLY | {"set_input", "set_analog", "set_count_rate",
                                     "wire_break"})
    di16 = set(cpx.target_actions(1))
    assert {"set_input", "short_circuit", "force"} <= di16 and "set_analog" not in di16
    ai = set(cpx.target_actions(3))
    assert {"set_analog", "wire_break"} <= ai and not ai & {"set_input", "force"}
    assert cpx.target_actions(9) == []


def test_the_trscat_says_what_each_target_takes() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    trscat = rig.device("trscat")
    device = set(trscat.target_actions(None))
    assert {"power", "link", "set_input", "set_output", "inject_fault"} <= device
    assert not device & {"plug", "unplug", "set_analog_input"}
    analog = set(trscat.target_actions(2))  # the default rig's TRS-AN-E
    assert {"set_analog_input", "unplug", "inject_fault"} <= analog
    assert not analog & {"power", "link", "set_input", "set_load"}


def test_the_forms_offer_what_the_picked_target_takes() -> None:
    with served_default_rig(1.0) as live:
        controls = live.dashboard.line.controls  # type: ignore[union-attr]
        operate, faults = controls.all_forms()["cpx"]
        controls.targets["cpx"].set_all("cpx/2")
        drawn(live)
        drawn(live)
        assert not set(operate.options()) & DEVICE_ONLY, operate.options()
        assert "force" in operate.options()
        assert not set(faults.options()) & {"cable", "power", "supply"}, faults.options()
        assert {"short_circuit", "inject_fault"} <= set(faults.options())
        controls.targets["cpx"].set_all("cpx")
        drawn(live)
        drawn(live)
        assert {"set_dil", "set_rotary", "restart"} <= set(operate.options())
        assert {"cable", "power", "supply"} <= set(faults.options())
        assert "short_circuit" not in faults.options()


def test_the_target_lists_follow_the_rig() -> None:
    """An expansion plugged after the first snapshot is offered as a Target, and the pick
    stays. Before, the lists were the first snapshot's for good."""
    with served_default_rig(1.0) as live:
        controls = live.dashboard.line.controls  # type: ignore[union-attr]
        target = controls.targets["trscat"]
        assert tuple(target.options) == ("trscat", "trscat/1", "trscat/2")
        target.set_all("trscat/2")
        live.runtime.command("trscat/3", "plug", {"type": "TRS-IO-E"}).result(timeout=10)
        # Frames until the list moves (drawn() allows a loaded machine too few for the
        # dashboard thread: it is not the list under test then).
        deadline = time.monotonic() + 30
        while len(target.options) < 4 and time.monotonic() < deadline:
            live.advance(0.05)
            time.sleep(0.05)
        assert tuple(target.options) == ("trscat", "trscat/1", "trscat/2", "trscat/3")
        assert target.default == "trscat/2"


class _Dropdown:
    def __init__(self, options: tuple[str, ...], value: str) -> None:
        self.options, self.value = options, value


class _Sender:
    def __init__(self) -> None:
        self.asked: list[str] = []

    def submit(self, _client: Any, what: str, _fn: Any, done: Any = None) -> None:
        self.asked.append(what)


def test_a_target_gone_from_the_rig_falls_back_to_the_device() -> None:
    sender = _Sender()
    actions = TargetActions(None, sender)  # type: ignore[arg-type]
    dropdown = _Dropdown(("cpx", "cpx/1", "cpx/2"), "cpx/2")
    watch = Watch("cpx", dropdown, (), asked={"cpx/2"})  # as watch() asked it
    first = {"cpx": {"modules": [{"module": 1, "type": "A"}, {"module": 2, "type": "B"}]}}
    actions.update([watch], first)
    assert dropdown.options == ("cpx", "cpx/1", "cpx/2") and sender.asked == []
    actions.update([watch], {"cpx": {"modules": [{"module": 1, "type": "A"}]}})
    assert dropdown.options == ("cpx", "cpx/1") and dropdown.value == "cpx"
    assert sender.asked == ["target actions"]  # the new pick's actions, asked again
