"""Every refusal a device's apply() gives for bad arguments, whatever the device's state, is also
given by its check_command, with the same message.

A scenario's check before the run, an exercise file's check and an ``[[on]]`` command's check
call check_command only (app.scenario.check_against, app.classroom.exercise_file): a rule that
only the command's handler knows lets such a file pass and fail at run time instead.
What depends on the modules a step finds (a module number, a module's kind) is the
check_module hook's (tests/app/test_scenario_module_checks.py), not this table's.
"""

from __future__ import annotations

import random
from typing import Any

import pytest

from devices.cpx.device import CpxEEc
from devices.device import CommandError, DeviceModel
from devices.fastcat.coupler import FastCat
from devices.flash import MemoryFlash
from devices.master import EtherCatMaster
from devices.servo.drive import DriveConfig, ServoDrive
from devices.trscat.device import TrsCat


def cpx() -> CpxEEc:
    return CpxEEc("cpx", random.Random(1), ["CPX-E-16DI", "CPX-E-8DO", "CPX-E-4AI-U-I"])


def fastcat() -> FastCat:
    return FastCat("fastcat", random.Random(1), [("DB16", {}), ("DI16", {}), ("DO16", {})])


def trscat() -> TrsCat:
    return TrsCat("trscat", random.Random(1), ["TRS-IO-E", "TRS-AN-E"])


def servo() -> ServoDrive:
    return ServoDrive("servo", random.Random(1), DriveConfig(), MemoryFlash())


def master() -> EtherCatMaster:
    return EtherCatMaster("master", random.Random(1), slaves=[cpx(), trscat()])


DEVICES = {"cpx": cpx, "fastcat": fastcat, "trscat": trscat, "servo": servo, "master": master}

# (device, module, action, args, what the refusal says)
BAD: list[tuple[str, int | None, str, dict[str, Any], str]] = [
    ("cpx", None, "inject_fault", {"fault": "module_failure"},
     "module_failure needs a module: target 'cpx/N'"),
    ("cpx", None, "clear_fault", {"fault": "module_failure"},
     "module_failure needs a module: target 'cpx/N'"),
    ("cpx", None, "inject_fault", {"fault": "short_circuit"},
     "short_circuit needs a module: target 'cpx/N'"),
    ("cpx", 3, "inject_fault", {"fault": "wire_break"},
     "wire_break needs a module and a channel: target 'cpx/N' with channel="),
    ("cpx", None, "inject_fault", {"fault": "wire_break", "channel": 1},
     "wire_break needs a module and a channel"),
    ("cpx", 1, "inject_fault", {"fault": "undervoltage_out"},
     "undervoltage_out is a fault of the bus module: target the device"),
    ("cpx", None, "inject_fault", {"fault": "sm_invalid_size"},
     "sm_invalid_size needs sm= 0 ... 3"),
    ("cpx", None, "clear_fault", {"fault": "watchdog", "sm": 2},
     "watchdog takes no sync manager"),
    # An argument the fault has no use for is refused, not ignored (session 17): a channel
    # on a fault of the bus module, of a whole module or of a sync manager, a module on a
    # sync manager's fault.
    ("cpx", None, "inject_fault", {"fault": "watchdog", "channel": 2},
     "watchdog takes no channel (only short_circuit and wire_break name one)"),
    ("cpx", 1, "inject_fault", {"fault": "module_failure", "channel": 0},
     "module_failure takes no channel"),
    ("cpx", None, "clear_fault", {"fault": "module_ident_mismatch", "channel": 1},
     "module_ident_mismatch takes no channel"),
    ("cpx", None, "inject_fault", {"fault": "sm_invalid_size", "sm": 2, "channel": 1},
     "sm_invalid_size takes no channel"),
    ("cpx", 2, "inject_fault", {"fault": "sm_invalid_size", "sm": 2},
     "sm_invalid_size is a fault of the bus module: target the device"),
    # Seed 000 §7.5: byte 0 is "l'eventuale indice del nodo"; these codes name none.
    ("fastcat", 2, "inject_fault", {"fault": "LINK_LOSS"},
     "LINK_LOSS is an alarm of the coupler itself (§7.5: byte 0 names no module): "
     "target 'fastcat'"),
    ("fastcat", 3, "clear_fault", {"fault": "coupler:0x12"},
     "ADDRESS_MASTER_NOT_OK is an alarm of the coupler itself"),
    ("fastcat", 1, "inject_fault", {"fault": "NO_MOD"}, "NO_MOD is an alarm of the coupler"),
    ("fastcat", 1, "inject_fault", {"fault": "SAVE_FLASH"},
     "SAVE_FLASH is an alarm of the coupler"),
    ("fastcat", None, "inject_fault", {"fault": "TARATURA", "channel": 1},
     "action 'inject_fault' takes no argument channel"),
    ("servo", None, "inject_alarm", {"code": "16", "channel": 1},
     "action 'inject_alarm' takes no argument channel"),
    ("trscat", 1, "inject_fault", {"fault": "CONFIG_ERROR"},
     "CONFIG_ERROR is a fault of the TRS-CAT itself: target 'trscat'"),
    ("trscat", 2, "clear_fault", {"fault": "0xA000"},
     "CONFIG_ERROR is a fault of the TRS-CAT itself: target 'trscat'"),
    ("trscat", None, "inject_fault", {"fault": "AN_PLUS_12V"},
     "AN_PLUS_12V (0x5114) is a TRS-AN-E fault; position 0 is a TRS-CAT integrated"),
    ("trscat", None, "clear_fault", {"fault": "0x5115"},
     "AN_MINUS_12V (0x5115) is a TRS-AN-E fault; position 0 is a TRS-CAT integrated"),
    ("trscat", 8, "plug", {"type": "TRS-IO-E"}, "a TRS-CAT has expansion positions 1..7 (§5)"),
    ("servo", None, "inject_alarm", {"code": "999"}, "no alarm 999 (codes: "),
    ("servo", None, "clear_alarm", {"code": "NO_SUCH_ALARM"}, "no alarm named 'NO_SUCH_ALARM'"),
    ("master", None, "pull_cable", {"cable": 2}, "cable 2: the line has positions 0..1"),
    ("master", None, "plug_cable", {"cable": 5}, "cable 5: the line has positions 0..1"),
    ("master", None, "damage_cable", {"cable": 2, "percent": 10},
     "cable 2: the line has positions 0..1"),
    ("master", None, "repair_cable", {"cable": 2}, "cable 2: the line has positions 0..1"),
    ("master", None, "power_slave", {"position": 3, "on": False},
     "position 3: the line has positions 0..1"),
    ("master", None, "clear_esc_errors", {"position": 2},
     "position 2: the line has positions 0..1"),
]

# Near misses of the rows above that both paths take (the check must not refuse too much).
GOOD: list[tuple[str, int | None, str, dict[str, Any]]] = [
    ("cpx", 1, "inject_fault", {"fault": "module_failure"}),
    ("cpx", None, "inject_fault", {"fault": "module_ident_mismatch"}),  # the bus module
    ("cpx", 3, "inject_fault", {"fault": "wire_break", "channel": 1}),
    ("cpx", None, "inject_fault", {"fault": "sm_invalid_size", "sm": 2}),
    ("cpx", 2, "inject_fault", {"fault": "short_circuit", "channel": 1}),
    ("cpx", 1, "inject_fault", {"fault": "short_circuit"}),  # the sensor supply
    ("fastcat", 2, "inject_fault", {"fault": "MISSING_NODE_ANSWER"}),
    ("fastcat", None, "inject_fault", {"fault": "LINK_LOSS"}),
    ("fastcat", 2, "inject_fault", {"fault": "TARATURA"}),
    ("trscat", None, "inject_fault", {"fault": "CONFIG_ERROR"}),
    ("trscat", 2, "inject_fault", {"fault": "AN_PLUS_12V"}),
    ("trscat", None, "inject_fault", {"fault": "FIELD_SUPPLY"}),
    ("trscat", 1, "inject_fault", {"fault": "FIELD_SUPPLY"}),
    ("servo", None, "clear_alarm", {"code": "16"}),
    ("master", None, "pull_cable", {"cable": 1}),
    ("master", None, "power_slave", {"position": 1, "on": True}),
]


def refusal(call: Any) -> str:
    with pytest.raises(CommandError) as caught:
        call()
    return str(caught.value)


@pytest.mark.parametrize(("device", "module", "action", "args", "says"), BAD,
                         ids=[f"{d}/{m}-{a}-{'-'.join(map(str, x.values()))}"
                              for d, m, a, x, _ in BAD])
def test_check_command_refuses_what_apply_refuses(device: str, module: int | None,
                                                  action: str, args: dict[str, Any],
                                                  says: str) -> None:
    model: DeviceModel = DEVICES[device]()
    checked = refusal(lambda: model.check_command(action, args, module))
    applied = refusal(lambda: DEVICES[device]().apply(action, args, module))
    assert says in checked, checked
    assert checked == applied


@pytest.mark.parametrize(("device", "module", "action", "args"), GOOD,
                         ids=[f"{d}/{m}-{a}-{'-'.join(map(str, x.values()))}"
                              for d, m, a, x in GOOD])
def test_check_command_takes_what_apply_takes(device: str, module: int | None, action: str,
                                              args: dict[str, Any]) -> None:
    DEVICES[device]().check_command(action, args, module)
    DEVICES[device]().apply(action, args, module)


@pytest.mark.parametrize(("device", "module", "action", "args", "hint"), [
    ("fastcat", None, "powr", {}, "did you mean 'power'?"),
    ("master", None, "set_log_style", {"styl": "sirio"}, "did you mean 'style'?"),
    ("master", None, "set_log_style", {"style": "twincta"}, "did you mean 'twincat'?"),
    ("cpx", 2, "inject_fault", {"fault": "wire_brake"}, "did you mean 'wire_break'?"),
    ("trscat", None, "inject_fault", {"fault": "FIELD_SUPLY"}, "did you mean 'FIELD_SUPPLY'?"),
])
def test_an_unknown_name_in_a_command_says_what_was_meant(device: str, module: int | None,
                                                          action: str, args: dict[str, Any],
                                                          hint: str) -> None:
    """The hint of devices/names.py, for a scenario's or an exercise's command as for a
    rig file's key."""
    with pytest.raises(CommandError) as caught:
        DEVICES[device]().check_command(action, args, module)
    assert str(caught.value).endswith(f"; {hint}"), caught.value
