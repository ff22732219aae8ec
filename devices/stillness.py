"""Generic parts of skipping still steps (docs/performance.md): a value copy and a backoff.

A model may skip a step that repeats one which changed nothing, if it can prove "changed
nothing" exactly. Two pieces serve every model that does so by comparing its state:

- :func:`value_key`: a comparable copy of a value, containers and plain objects one value at
  a time all the way down, so ``value_key(x) == value_key(y)`` means the two hold the same
  values (not merely the same objects, which a step mutates in place); :func:`value_key_for`
  makes one that takes a model's deeply immutable classes as they are. An object with
  ``__slots__`` is read slot by slot (:func:`slot_names`), never through a ``__dict__``: on
  CPython 3.11 reading an object's ``__dict__`` once leaves every later attribute access of
  that object on the interpreter's slow path (docs/performance.md "Session 21"), so the
  small objects a moving drive touches every tick have slots;
- :class:`Backoff`: when a check for stillness failed, wait 1, 2, 4 .. :data:`MAX_WAIT` steps
  before the next one, so a model that looks still but is not (a filter settling, a timer
  counting) pays about 1 % of a step for the checks. Waiting only delays the skipping; it can
  never make a skipped step differ.
"""

from __future__ import annotations

import enum
import functools
from collections.abc import Callable, Iterable
from typing import Any

MAX_WAIT = 128
# Immutable values compared as themselves (tuples / frozensets of these are values too).
ATOMS = (int, float, str, bytes, bool, type(None), enum.Enum, tuple, frozenset)
_ATOM_TYPES = frozenset({int, float, str, bytes, bool, type(None)})


def value_key_for(values: Iterable[type] = ()) -> Callable[[Any], Any]:
    """:func:`value_key` that takes instances of ``values`` as they are: classes whose
    instances are deeply immutable (frozen dataclasses of numbers, strings, enums and tuples
    of them), compared by ``==`` instead of field by field, which is cheaper."""
    taken = _ATOM_TYPES | frozenset(values)

    def key(v: Any) -> Any:
        if type(v) in taken or isinstance(v, ATOMS):
            return v
        if isinstance(v, dict):  # of plain values: copied at C speed
            if taken.issuperset(map(type, v.values())):
                return tuple(v.items())
            return tuple((k, key(x)) for k, x in v.items())
        if isinstance(v, list):
            if taken.issuperset(map(type, v)):
                return tuple(v)
            return tuple(key(x) for x in v)
        if isinstance(v, set):
            return frozenset(v)
        state = getattr(v, "__dict__", None)
        if state is None:
            names = slot_names(type(v))
            if not names:  # nothing to read: compare the object itself
                return v
            return (type(v), tuple((k, key(getattr(v, k, _UNSET))) for k in names))
        return (type(v), tuple((k, key(x)) for k, x in state.items()))
    return key


_UNSET = object()  # a slot not assigned (as a key a __dict__ would not have yet)


@functools.cache
def slot_names(cls: type) -> tuple[str, ...]:
    """The slots of ``cls`` and its bases, bases first (``__weakref__`` and ``__dict__``
    left out); empty for a class without slots."""
    names: list[str] = []
    for base in reversed(cls.__mro__):
        slots = base.__dict__.get("__slots__", ())
        for name in (slots,) if isinstance(slots, str) else slots:
            if name not in ("__dict__", "__weakref__"):
                names.append(name)
    return tuple(names)


value_key = value_key_for()
value_key.__doc__ = """A comparable copy: containers and plain objects one value at a time, all
the way down."""


class Backoff:
    """When to check for stillness again after a failed check: after 1, 2, 4 .. MAX_WAIT."""

    __slots__ = ("wait", "wait_left")

    def __init__(self) -> None:
        self.wait = 1
        self.wait_left = 0

    def due(self) -> bool:
        """A check now? (Counts down the wait after a failed one.)"""
        if self.wait_left:
            self.wait_left -= 1
            return False
        return True

    def checked(self, still: bool) -> None:
        self.wait = 1 if still else min(self.wait * 2, MAX_WAIT)
        self.wait_left = 0 if still else self.wait

    def restart(self) -> None:
        """Touched from outside: check at the next chance."""
        self.wait, self.wait_left = 1, 0
