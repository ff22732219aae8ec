"""Still-step keys read objects with slots slot by slot (devices/stillness.py), and the
objects a moving drive touches every tick have slots, so no key gives them a ``__dict__``
(on CPython 3.11 a ``__dict__`` read once slows every later attribute access of the object:
docs/performance.md "Session 21")."""

from __future__ import annotations

from servo_helpers import make_sim

from devices.servo.stillness import state_key
from devices.stillness import slot_names, value_key, value_key_for


class Pair:
    __slots__ = ("a", "b")

    def __init__(self, a: int, b: list[int]) -> None:
        self.a, self.b = a, b


class Later(Pair):
    __slots__ = ("c",)


def test_a_slotted_object_is_keyed_by_its_values() -> None:
    pair = Pair(1, [2])
    before = value_key(pair)
    assert value_key(pair) == before
    pair.b.append(3)
    assert value_key(pair) != before
    pair.b.pop()
    assert value_key(pair) == before
    pair.a = 5
    assert value_key(pair) != before
    assert value_key_for(())(Pair(5, [2])) == value_key(pair)


def test_slots_of_the_bases_come_first_and_an_unset_slot_is_a_value() -> None:
    assert slot_names(Later) == ("a", "b", "c")
    later = Later(1, [])
    unset = value_key(later)
    later.c = None
    assert value_key(later) != unset


def test_a_moving_drive_keeps_its_per_tick_objects_without_a_dict() -> None:
    sim = make_sim()
    drive = sim.drive
    sim.run(200)  # still steps: the drive takes its state keys
    drive.apply("enable", {"on": True})
    drive.apply("jog", {"direction": 1})
    sim.run(200)
    assert drive.plant.omega != 0.0
    state_key(drive)
    parts = [drive.plant, drive.plant.geometry, drive.trajectory, drive.meter, drive.alarms]
    monitor = drive.mode_logic.monitor
    if monitor is not None:
        parts.append(monitor)
    for part in parts:
        assert not hasattr(part, "__dict__"), type(part).__name__
