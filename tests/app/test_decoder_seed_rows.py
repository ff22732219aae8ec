"""Rows of the seeds' code tables the Codes tab read wrongly, fed the way a trainee types them.

Each test names the seed row it checks; the words the tab shows come from the devices' tables
(devices/), so the tests compare with those and with the seed's own terms.
"""

from __future__ import annotations

import pytest

from app.decoder import SERVO, decode
from devices.servo import alarms as servo

_SPECS = sorted({(s.code, s.name): s for bus in ("ethercat", "profinet")
                 for s in servo.alarm_table(bus).values()}.values(),
                key=lambda s: (s.code, s.name))


@pytest.mark.parametrize("spec", _SPECS, ids=lambda s: f"{s.code}-{s.name}")
def test_a_drive_alarm_keeps_the_seeds_capitals(spec: servo.AlarmSpec) -> None:
    """Seed 004 ch. 3 / ch. 5 / ch. 6 write IGBT, DSP, LS1, PDO, EtherCAT, Profinet: the
    tab lowercased all but the first letter ("Igbt module", "(ls1)", "Pdo mapping")."""
    found = [m for m in decode(f"alarm {spec.code}") if m.family == SERVO
             and m.title == f"Drive alarm {spec.code} {spec.name}"]
    assert found, decode(f"alarm {spec.code}")
    first = spec.description[:1].upper() + spec.description[1:]
    assert found[0].text.startswith(first + ";"), found[0].text


@pytest.mark.parametrize(("query", "word"), [
    ("alarm 1", "IGBT module"), ("alarm 7", "(DSP processor in fault)"),
    ("alarm 20", "(LS1)"), ("alarm 33", "PDO mapping"), ("alarm 35", "EtherCAT EEPROM"),
])
def test_the_seeds_acronyms_survive(query: str, word: str) -> None:
    assert any(word in m.text for m in decode(query) if m.family == SERVO), decode(query)


_BUSES = ("modbus", "canopen", "ethercat", "profinet")


@pytest.mark.parametrize("spec", _SPECS, ids=lambda s: f"{s.code}-{s.name}")
def test_a_drive_alarm_says_how_it_is_reset(spec: servo.AlarmSpec) -> None:
    """Seed 004 gives the reset per fieldbus: R00 bit 3 (ch. 2, Modbus), 0x80 on 0x6040 (ch. 4
    CANopen, ch. 5 "Reset allarmi" over CoE), the Control Word 0x08 (ch. 6 Profinet, with
    "Resettabile" NO for 30-33), and "if it fails the alarm condition may persist". The tab
    said nothing of it, for the alarm by number and for its emergency."""
    code = spec.error_code_or_generic
    queries = (f"alarm {spec.code}",
               f"CoE - Emergency (Hex: {code:04x}, 81, {spec.code:02x} 00 00 00 00').")
    for query in queries:
        found = [m for m in decode(query) if m.family == SERVO and spec.name in m.title + m.text]
        assert found, (query, decode(query))
        text = found[0].text
        for bus in _BUSES:
            row = servo.alarm_table(bus).get(spec.code)
            if row is None or row.name != spec.name:
                continue
            if row.resettable:
                assert servo.RESET_HINT[bus] in text and bus_name(bus) in text, (bus, text)
            else:
                assert f"not resettable on {bus_name(bus)}" in text and "power cycle" in text, \
                    (bus, text)
        rows = [servo.alarm_table(b).get(spec.code) for b in _BUSES]
        if any(r is not None and r.name == spec.name and r.resettable for r in rows):
            assert "once the cause is gone" in text, text


def bus_name(bus: str) -> str:
    return {"modbus": "Modbus", "canopen": "CANopen", "ethercat": "EtherCAT",
            "profinet": "Profinet"}[bus]
