"""The words of the CANopen node's EMCY codes, the 0x1001 bits and a drive alarm's effect.

Architecture rule "code tables as data in one place each", in devices/: the Codes tab kept these
three tables in app/decoder.py. Now devices/canopen/emcy.py and devices/servo/alarms.py hold
them, the decoder reads them, and every code the node sends has its text there.
"""

from __future__ import annotations

import pytest

from app.decoder import CANOPEN, SERVO, decode, register_text
from devices.canopen import emcy
from devices.servo import alarms as servo


@pytest.mark.parametrize("code", [emcy.ERROR_RESET, emcy.LIFE_GUARD_ERROR,
                                  emcy.PDO_LENGTH_ERROR])
def test_every_code_the_node_sends_has_its_text(code: int) -> None:
    text = emcy.EMCY_TEXT[code]
    found = [m for m in decode(f"0x{code:04X}") if m.family == CANOPEN]
    assert found and found[0].text.startswith(text), found


def test_the_register_bits_are_named_by_the_model() -> None:
    bits = (emcy.REG_GENERIC, emcy.REG_CURRENT, emcy.REG_VOLTAGE, emcy.REG_TEMPERATURE,
            emcy.REG_COMMUNICATION, emcy.REG_PROFILE, emcy.REG_RESERVED, emcy.REG_MANUFACTURER)
    assert sorted(emcy.REGISTER_BIT_NAMES) == sorted(bits)
    assert register_text(0x81) == (f"0x81: {emcy.REGISTER_BIT_NAMES[emcy.REG_GENERIC]}, "
                                   f"{emcy.REGISTER_BIT_NAMES[emcy.REG_MANUFACTURER]}")


@pytest.mark.parametrize("effect", list(servo.Effect))
def test_a_drive_alarms_effect_in_the_models_words(effect: servo.Effect) -> None:
    """Seed 004 ch. 3 "Azione": the words live next to the alarm table."""
    spec = next(s for s in servo.DRIVE_ALARMS.values() if s.effect is effect)
    found = [m for m in decode(f"alarm {spec.code}") if m.family == SERVO]
    assert found and servo.EFFECT_TEXT[effect] in found[0].text, found


@pytest.mark.parametrize(("code", "name"), [
    (0x1099, "Generic error"), (0x2999, "Current"), (0x3999, "Voltage"),
    (0x4999, "Temperature"), (0x5555, "Device hardware"), (0x6999, "Device software"),
    (0x7099, "Additional modules"), (0x8F99, "Monitoring"), (0x8999, "Monitoring"),
    (0x90FF, "External error"), (0xF001, "Additional functions"), (0xFF99, "Device specific"),
])
def test_an_unknown_emcy_code_gets_the_class_of_the_seeds_table(code: int, name: str) -> None:
    """Seed 004 ch. 4 "Emergency Message": the high byte gives the error category (10xx
    generic, 2xxx current, ..., 8xxx monitoring, 90xx external, F0xx additional functions,
    FFxx device specific). The decoder used to name the error register bit instead: 0x90FF
    read "class 'generic'", 0x8999 "class 'device profile'"."""
    (m,) = [m for m in decode(f"0x{code:04X}") if m.family == CANOPEN]
    assert f"class '{name}'" in m.text, m
    assert emcy.error_class(code) == name
