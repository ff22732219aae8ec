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
    queries: tuple[str, ...] = (f"alarm {spec.code}",)
    if any(servo.alarm_table(b)[spec.code] == spec for b in servo.CODED_FIELDBUSES):
        queries += (f"CoE - Emergency (Hex: {code:04x}, 81, {spec.code:02x} 00 00 00 00').",)
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


_PROFINET_ONLY = [s for s in servo.alarm_table("profinet").values()
                  if servo.alarm_table("ethercat")[s.code].name != s.name]


@pytest.mark.parametrize("spec", _PROFINET_ONLY, ids=lambda s: f"{s.code}-{s.name}")
def test_a_profinet_alarm_has_no_0x603f_code(spec: servo.AlarmSpec) -> None:
    """Seed 004 ch. 6 "Codici allarmi specifici" prints code, meaning and "Resettabile" only:
    no 0x603F column (ch. 5's table is the EtherCAT one, "Codice Allarme ECO"). A Profinet drive
    has no 0x603F and sends no emergency (ch. 6: a 32-byte shared memory). The tab offered
    31-34's Profinet meanings for the EtherCAT codes 0x7500 / 0x6320 / 0x8700, so the emergency
    of a refused PDO mapping read as "Profinet fieldbus did not start correctly" too."""
    assert spec.error_code is None
    coe = servo.alarm_table("ethercat")[spec.code]
    frame = f"CoE - Emergency (Hex: {coe.error_code_or_generic:04x}, 81, {spec.code:02x} 00 00 " \
            "00 00').'"
    for query in (frame, f"0x{coe.error_code_or_generic:04X}"):
        assert not [m for m in decode(query) if spec.name in m.title + m.text], decode(query)
    found = [m for m in decode(f"alarm {spec.code}") if m.title.endswith(spec.name)]
    assert found and "no 0x603F code" in found[0].text and "0x603F code 0x" not in found[0].text
