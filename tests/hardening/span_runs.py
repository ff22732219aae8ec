"""What the quiet-span differential tests share (docs/performance.md "Quiet spans").

Two rigs built alike take the same commands; one advances with quiet spans skipped
(``Rig.advance``), the other with ``SKIP_SPANS`` off, one step at a time. After every stretch
both must give the same events, the same snapshots and the same deep state: every attribute of
every model, all the way down, rng states included (:func:`deep_state`), except what only says
how much work a step saved (:data:`BOOKKEEPING`).
"""

from __future__ import annotations

import functools
import json
import random
import types
from collections.abc import Callable, Iterable
from typing import Any

from app.rig import Rig
from devices.device import CommandError
from devices.stillness import Backoff

# Attributes that count or pace the skipping itself, never read by a model's behaviour.
BOOKKEEPING = frozenset({"skipped", "skipped_steps"})

Op = tuple[str, str, dict[str, Any]]
CALLS = (types.FunctionType, types.MethodType, types.BuiltinFunctionType,
         types.BuiltinMethodType, functools.partial)


def deep_state(value: Any, ignore: frozenset[str] = BOOKKEEPING) -> Any:
    """A comparable copy of ``value``: containers and objects one value at a time, rngs by
    their state, bound methods and functions by name, :class:`Backoff` left out."""
    seen: dict[int, Any] = {}

    def key(v: Any) -> Any:
        if v is None or isinstance(v, (int, float, str, bytes, bool)):
            return v
        if isinstance(v, random.Random):
            return ("rng", v.getstate())
        if isinstance(v, Backoff):
            return "backoff"
        if isinstance(v, CALLS):
            return ("call", getattr(v, "__qualname__", type(v).__name__))
        if id(v) in seen:  # shared or cyclic: the path it was first met by
            return ("seen", seen[id(v)])
        seen[id(v)] = len(seen)
        if isinstance(v, dict):
            return ("dict", tuple((key(k), key(x)) for k, x in v.items()))
        if isinstance(v, (list, tuple)):
            return (type(v).__name__, tuple(key(x) for x in v))
        if isinstance(v, (set, frozenset)):
            return ("set", tuple(sorted(repr(key(x)) for x in v)))
        if hasattr(v, "__dict__") or hasattr(type(v), "__slots__"):
            fields = dict(getattr(v, "__dict__", {}))
            for cls in type(v).__mro__:
                for name in getattr(cls, "__slots__", ()):
                    if hasattr(v, name):
                        fields[name] = getattr(v, name)
            return (type(v).__qualname__,
                    tuple((k, key(x)) for k, x in sorted(fields.items()) if k not in ignore))
        return repr(v)

    return key(value)


def rig_state(rig: Rig) -> Any:
    return rig.snapshot(), tuple((i, deep_state(d)) for i, d in rig.devices.items())


def plain(rig: Rig) -> Rig:
    """The rig with quiet spans switched off: ``advance`` steps one step at a time."""
    rig.SKIP_SPANS = False  # type: ignore[misc]  # the instance's, for the differential
    return rig


def outcome(rig: Rig, op: Op) -> str:
    try:
        return repr(rig.apply(*op))
    except CommandError as exc:
        return f"refused: {exc}"
    except Exception as exc:  # a model's own refusal (an SDO abort): compared as text
        return f"refused: {type(exc).__name__}: {exc}"


def lines(events: Iterable[Any]) -> list[str]:
    return [json.dumps(e.to_record(), sort_keys=True, default=str) for e in events]


def differential(build: Callable[[], Rig], ops: Callable[[random.Random], Op], seed: int,
                 rounds: int, lengths: tuple[int, ...] = (1, 3, 20, 200, 900, 3000),
                 finale: tuple[Op, ...] = (), finale_steps: int = 0) -> int:
    """``rounds`` of (a random op, a random stretch) on a skipping rig and a plain one,
    compared after each, then the ``finale`` ops (e.g. every fault cleared) each followed by
    ``finale_steps``; the steps the skipping rig skipped."""
    rng = random.Random(seed)
    skipping, stepping = build(), plain(build())
    plan = [(ops(rng), rng.choice(lengths)) for _ in range(rounds)]
    plan += [(op, finale_steps) for op in finale]
    for op, steps in plan:
        assert outcome(skipping, op) == outcome(stepping, op), op
        assert lines(skipping.take_events()) == lines(stepping.take_events()), op
        advance_alike(skipping, stepping, steps, op)
        assert rig_state(skipping) == rig_state(stepping), (op, steps)
    return skipping.skipped_steps


def advance_alike(skipping: Rig, stepping: Rig, steps: int, why: object) -> list[Any]:
    """``Rig.advance(steps)`` on both, span by span: after each skipped span the stepping rig
    is stepped as far and the two snapshots compared, so a span one step too long shows where
    it happened, even in a model that would catch up by the end of the stretch. Returns the
    events, the same on both (a span has none)."""
    events: list[Any] = []
    while steps > 0:
        span = skipping.quiet_steps(steps)
        if span:
            skipping.skip(span)
            assert lines(stepping.advance(span)) == [], (why, "events in a quiet span")
            assert skipping.snapshot() == stepping.snapshot(), (why, "after a span", span)
            steps -= span
        else:
            stepped = skipping.step()
            assert lines(stepped) == lines(stepping.step()), why
            events += stepped
            steps -= 1
    return events
