"""The drive's Register and Parameter boxes cut labels such as "c9 operating mode / fieldbus
(3 Modbus, ...)" (the box holds about 25 characters): the picked one's whole label, range,
access and Modbus address are the box's hint (seed 004 ch. 1 "Registri", "Parametri"). The
address is the one of the map the drive serves: e3 = 9 moves it for Siemens PLCs (ch. 2
"Estensione della mappatura"); the drive's snapshot says which (``modbus_map``)."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from test_widgets_synced_panels import DRIVE, Sender, Server, frames

from app.ui.drive.drive_options import (
    PARAMETER_OPTIONS,
    REGISTER_OPTIONS,
    parameter_details,
    register_details,
)
from app.ui.drive.drive_panel import DrivePanel
from app.ui.panels.widgets import DetailHint
from devices.servo.flashsave import SAVED_REGISTERS
from devices.servo.modbus_map import NORMAL, SIEMENS
from devices.servo.registers import REGISTERS


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


def test_the_save_hint_is_what_a_save_keeps() -> None:
    """R00 is printed "Si" (ch. 1) but a save does not keep it (docs/servo-drive.md §Flash):
    its hint must not promise that; every hint saying "kept" names a register the image holds
    (devices/servo/flashsave.py)."""
    registers = register_details()
    assert "kept by Save to flash" not in registers["R00 control_word"]
    assert registers["R00 control_word"].endswith("not saved; Modbus 0x8000")
    kept = {label for label, hint in registers.items() if "kept by Save to flash" in hint}
    assert kept == {f"R{n:02d} {REGISTERS[n].name}" for n in SAVED_REGISTERS
                    if REGISTERS[n].writable}


def test_the_hint_follows_the_pick() -> None:
    box = Dropdown(REGISTER_OPTIONS[0])
    DetailHint(box, register_details)
    assert box.hint == register_details()[REGISTER_OPTIONS[0]]
    box.pick("R05 status_word")
    assert box.hint == "R05 status_word: 0..255, read only; Modbus 0x8005"


def test_the_siemens_map_s_addresses_as_the_seed_s_examples() -> None:
    """Ch. 2 "Esempi ... per PLC Siemens": d1 at 40001 + 1 = 40002 = 0x9C42, d3 at 0x9C44,
    R00 at 44097 + 0 = 0xAC41, R09 at 0xAC4A."""
    registers, parameters = register_details(SIEMENS), parameter_details(SIEMENS)
    siemens = "(e3 = 9, Siemens map)"
    assert parameters["d1 speed loop proportional gain KP"].endswith(
        f"; Modbus 40002 = 0x9C42 {siemens}")
    d3 = next(label for label in parameters if label.startswith("d3 "))
    assert parameters[d3].endswith(f"; Modbus 40004 = 0x9C44 {siemens}")
    assert registers["R00 control_word"].endswith(f"; Modbus 44097 = 0xAC41 {siemens}")
    assert registers["R09 target_position"].endswith(f"; Modbus 44106 = 0xAC4A {siemens}")
    assert register_details(NORMAL) == register_details()


def test_the_panel_s_hints_follow_the_drive_s_map() -> None:
    loop = asyncio.new_event_loop()
    try:
        server, sender = Server(loop, pages=1), Sender()
        panel = DrivePanel(server, None, sender, lambda _client: "drive", {})  # type: ignore[arg-type]
        register, parameter = server.gui.handles["Register"], server.gui.handles["Parameter"]
        page, d1 = server.clients[1], "d1 speed loop proportional gain KP"
        register.user(page, "R05 status_word")
        parameter.user(page, d1)

        def hints() -> tuple[str, str]:
            """The page's own hints, the last sent."""
            return (page.sent(register._impl.uuid, "hint")[-1],
                    page.sent(parameter._impl.uuid, "hint")[-1])

        frames(loop, server, lambda: panel.update({**DRIVE, "modbus_map": SIEMENS}))
        assert hints() == (register_details(SIEMENS)["R05 status_word"],
                           parameter_details(SIEMENS)[d1])
        assert "0xAC46" in hints()[0] and "0x9C42" in hints()[1]
        frames(loop, server, lambda: panel.update({**DRIVE, "modbus_map": NORMAL}))
        assert hints()[0] == "R05 status_word: 0..255, read only; Modbus 0x8005"
        assert hints()[1].endswith("; Modbus 0x0001")
    finally:
        loop.close()


def test_a_closed_set_of_codes_is_named_in_the_hint() -> None:
    """R01 takes the modes of ch. 1's list only and R27 the three profiles of ch. 4 (0x6086),
    inside their printed ranges 0x81..0x7F and 0x8000..0x7FFF: the drive refuses R01 = 2 (no
    reply on Modbus), so the hint names the codes it takes, not the range alone."""
    registers = register_details()
    assert registers["R01 modes_of_operation"].startswith(
        "R01 modes_of_operation: one of 1, 3, 6, 7, -1, -2, -50, -127 (printed -127..127), ")
    assert registers["R27 motion_profile_type"].startswith(
        "R27 motion_profile_type: one of 0, -1, -2 (printed -32768..32767), ")


def test_the_node_number_hint_gives_the_modbus_range() -> None:
    """c7 is 1..99 (ch. 4), but "ogni valore tra 1 e 90" with c9 = 3 (ch. 2 "Configurazione
    della rete"): a Modbus drive refuses c7 = 91, and its hint says so."""
    parameters = parameter_details()
    c7 = next(label for label in parameters if label.startswith("c7 "))
    assert parameters[c7].startswith(f"{c7}: 1..99 (1..90 with c9 = 3, Modbus RTU), default 1;")


def test_r18_names_the_homing_methods_the_drive_runs() -> None:
    """R18 takes 0..255 (ch. 1 prints 0x0 - ff) and Home with a method the drive has not is a
    homing error, alarm 14 (docs/servo-drive.md "Homing"): a trainee who wrote R18 = 5 from the
    panel got alarm 14 with a hint that said only "0..255". The hint names the methods."""
    hint = register_details()["R18 homing_method"]
    assert hint == ("R18 homing_method: 0..255 (Home runs methods 1-4, 17-20, 33-35; any "
                    "other: alarm 14 HOMING), kept by Save to flash; Modbus 0x8012")
