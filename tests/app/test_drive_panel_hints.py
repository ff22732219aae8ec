"""The drive's Register and Parameter boxes cut labels such as "c9 operating mode / fieldbus
(3 Modbus, ...)" (the box holds about 25 characters): the picked one's whole label, range,
access and Modbus address are the box's hint (seed 004 ch. 1 "Registri", "Parametri")."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from app.ui.drive.drive_panel import (
    PARAMETER_OPTIONS,
    REGISTER_OPTIONS,
    parameter_details,
    register_details,
)
from app.ui.panels.widgets import DetailHint


class Dropdown:
    """What DetailHint uses of a viser dropdown: value, hint, on_update."""

    def __init__(self, value: str) -> None:
        self.value, self.hint = value, None
        self._callbacks: list[Callable[[Any], None]] = []

    def on_update(self, fn: Callable[[Any], None]) -> None:
        self._callbacks.append(fn)

    def pick(self, value: str) -> None:
        self.value = value
        for fn in self._callbacks:
            fn(None)


def test_every_register_and_parameter_has_its_whole_label_in_the_hint() -> None:
    registers, parameters = register_details(), parameter_details()
    assert set(registers) == set(REGISTER_OPTIONS)
    assert set(parameters) == set(PARAMETER_OPTIONS)
    assert all(hint.startswith(f"{label}: ") for label, hint in registers.items())
    assert all(hint.startswith(f"{label}: ") for label, hint in parameters.items())


def test_hints_say_range_access_and_address_as_the_quick_reference() -> None:
    registers, parameters = register_details(), parameter_details()
    assert registers["R05 status_word"] == "R05 status_word: 0..255, read only; Modbus 0x8005"
    assert registers["R02 feed_constant"].endswith("kept by Save to flash; Modbus 0x8002")
    assert parameters["d1 speed loop proportional gain KP"] == (
        "d1 speed loop proportional gain KP: 1..99 %, default 20; Modbus 0x0001")
    c9 = next(label for label in parameters if label.startswith("c9 "))
    assert "default 3; read at power-up; Modbus 0x0016" in parameters[c9]


def test_the_hint_follows_the_pick() -> None:
    box = Dropdown(REGISTER_OPTIONS[0])
    DetailHint(box, register_details)
    assert box.hint == register_details()[REGISTER_OPTIONS[0]]
    box.pick("R05 status_word")
    assert box.hint == "R05 status_word: 0..255, read only; Modbus 0x8005"
