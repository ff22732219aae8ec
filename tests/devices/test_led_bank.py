"""The LED bank the FastCAT, the TRS-CAT and the drive's CoE slave share (devices/leds.py)."""

from __future__ import annotations

from devices.events import Event
from devices.leds import LedBank, LedPattern


def changes(bank: LedBank, t_us: int, wanted: dict[str, LedPattern]) -> list[tuple[str, str]]:
    out: list[Event] = []
    bank.update(t_us, wanted, out.append)
    return [(e.to_record()["led"], e.to_record()["pattern"]) for e in out]


def test_only_changed_patterns_are_events() -> None:
    bank = LedBank("dev")
    on, off = LedPattern.ON, LedPattern.OFF
    # A new LED that starts dark is no change: the lamp was dark before it was known.
    assert changes(bank, 1, {"RUN": LedPattern.BLINKING, "ERR": off}) == [("RUN", "blinking")]
    assert changes(bank, 2, {"RUN": LedPattern.BLINKING, "ERR": off}) == []
    assert changes(bank, 3, {"RUN": on, "ERR": off}) == [("RUN", "on")]
    assert bank.snapshot() == {"RUN": "on", "ERR": "off"}


def test_an_led_no_longer_wanted_goes_dark() -> None:
    """A FastCAT module unplugged: its LEDs leave the bank, a lit one with an
    event 'off', a dark one silently."""
    bank = LedBank("dev")
    changes(bank, 1, {"RUN": LedPattern.ON, "1.red": LedPattern.ON, "1.yellow": LedPattern.OFF})
    assert changes(bank, 2, {"RUN": LedPattern.ON}) == [("1.red", "off")]
    assert bank.snapshot() == {"RUN": "on"}
    # The same count of names, another set: the new one comes, the old one goes.
    assert changes(bank, 3, {"ERR": LedPattern.ON}) == [("ERR", "on"), ("RUN", "off")]
    assert bank.snapshot() == {"ERR": "on"}
