"""Events are small: the runtime journals the last 20,000 of them (app/runtime.py
JOURNAL_LENGTH), so an event's per-instance ``__dict__`` was most of the journal's memory
(issue 7, "Soak: memory grows less than 10 MB"). Every event class has slots and no
``__dict__``, and still renders, compares, pickles and copies as a frozen dataclass."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import pytest

import devices.events as events_module
from devices.events import (
    CoeEmergency,
    CommError,
    Event,
    NetworkRecovery,
    SlaveStateChange,
    ValueRead,
)


def event_classes() -> list[type[Event]]:
    return [c for c in vars(events_module).values()
            if isinstance(c, type) and issubclass(c, Event)]


@pytest.mark.parametrize("cls", event_classes(), ids=lambda c: c.__name__)
def test_every_event_class_has_slots_and_no_dict(cls: type[Event]) -> None:
    event = cls(1_500_000, "dev")
    assert not hasattr(event, "__dict__")
    with pytest.raises(dataclasses.FrozenInstanceError):
        event.device = "other"  # type: ignore[misc]
    assert event.to_record()["event"] == cls.kind
    assert pickle.loads(pickle.dumps(event)) == event
    assert copy.deepcopy(event) == event
    assert dataclasses.replace(event, t_us=2) == cls(2, "dev")


def test_slave_events_render_their_position_and_own_fields() -> None:
    """The master's slave events build their record on SlaveEvent's (position, address)."""
    assert SlaveStateChange(0, "m", position=2, address=0x1003, from_state="PREOP",
                            to_state="SAFEOP", code=0x1B).fields() == {
        "position": 2, "address": 0x1003, "from": "PREOP", "to": "SAFEOP", "code": "0x001B"}
    assert CommError(0, "m", position=1, address=0x1002, reason="link_lost",
                     count=3).fields() == {"position": 1, "address": 0x1002,
                                           "reason": "link_lost", "count": 3}
    assert CoeEmergency(0, "m", position=3, address=0x1004, code=0x8700, register=0x11,
                        data=b"\x01\x02").fields() == {
        "position": 3, "address": 0x1004, "code": "0x8700", "register": "0x11",
        "data": "01 02"}
    assert NetworkRecovery(0, "m", positions=(1, 2)).to_record()["positions"] == [1, 2]
    assert ValueRead(0, "d", address="0x6041", value=0x237).fields()["hex"] == "0x00000237"
