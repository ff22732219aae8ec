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
