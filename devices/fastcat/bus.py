"""The coupler's side of the internal bus (seed 000 §3, §6.18): who answers at each module number,
the rebinding of a module put back in its slot, and the cyclic exchange with the modules.

The table of which module sits where is rebuilt only when the rail, the last scan's result or
the binding changed (lists compared module by module, by identity), not every millisecond;
the exchange also reports whether every module answered and none moved, which lets the coupler
skip the next step (docs/performance.md).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devices.ethercat import AlState
from devices.fastcat.alarms import MODULE, Alarm

if TYPE_CHECKING:
    from devices.fastcat.esm import Esm
    from devices.fastcat.modules import IoModule

UDINT_MAX = 0xFFFF_FFFF
# Enum members read every step, bound once here: CPython 3.11 reads an enum class's
# attribute on a slow path (EnumType.__getattr__; docs/performance.md "Session 21").
_OP = AlState.OP


class BusMixin:
    """Internal-bus exchange of :class:`~devices.fastcat.coupler.FastCat`."""

    # Provided by FastCat (declared for type checkers).
    rail: list[IoModule | None]
    detected: list[tuple[int, str]]
    bound: list[IoModule]
    comm_errors: list[int]
    fresh_raised: list[Alarm]
    esm: Esm
    alarm: Alarm | None
    _bus_key: tuple[Any, ...]  # (rail, detected, bound) the table was built from
    _bus: list[IoModule | None]
    _rebound_for: tuple[Any, ...] | None  # the bus key of the last rebind
    _answering: list[bool] | None
    _bus_still: bool
    _exchange_key: tuple[int, bool] | None  # (step length, outputs enabled) of the last cycle
    # (bus table, answering, answering (number, module) pairs, silent numbers); None = stale
    _answer_cache: tuple[Any, ...] | None
    _moving: tuple[Any, list[tuple[int, IoModule]]]  # (bus table, modules left moving)
    _stepped: list[tuple[int, IoModule]] | None  # the modules this step's exchange stepped
    _woken: list[IoModule]  # to step at the next cycle, still or not (rail.py FIELD_ACTIONS)

    if TYPE_CHECKING:  # defined by FastCat
        def _build_od(self) -> None: ...

    def _exchange(self, dt_us: int, touched: bool) -> None:
        """One cycle on the internal bus. ``touched``: a command, AL control or object write
        came since the last step; without one, a module whose last step changed nothing and
        saw the same step length and output enable would do the same again: it is skipped,
        unless a field command changed it (``_woken``, rail.py FIELD_ACTIONS)."""
        outputs_enabled = self.esm.state is _OP and self.alarm is None
        # The rail, the scan result and the binding change only by a command (which drops
        # the answer cache), a scan (which drops it too) or a rebind (after which it is
        # built): while the cache is there, its table is the table.
        cache = self._answer_cache
        bus = cache[0] if cache is not None else self._bus_table()
        still = True
        if self._rebound_for is not self._bus_key:  # the rail, scan result or binding changed
            self._rebind()
            bus = self._bus_table()
            self._rebound_for = self._bus_key
            still = False
        repeat = not touched and still and self._exchange_key == (dt_us, outputs_enabled)
        self._exchange_key = (dt_us, outputs_enabled)
        # Who answers cannot change until the step ends: the alarm check reuses the list.
        answering, cycle, silent = self._who_answers(bus)
        self._answering = answering
        last_bus, last_moving = self._moving
        # The (number, module) pairs this cycle steps, for the alarm search (faults.py).
        stepped: list[tuple[int, IoModule]] | None = cycle  # not a repeat: every one answering
        skip_still = repeat
        if repeat:
            woken = self._woken
            if woken:  # the modules left moving (not still, as below) and the woken, in order
                self._woken = []
                stepped = cycle = [(n, m) for n, m in cycle if not m.still or m in woken]
                skip_still = False
            elif last_bus is bus:
                # A module's still flag changes only in its own step (or a reset, which comes
                # with a command or a scan): in a repeat, the modules the last cycle left
                # moving are the only ones that are not skipped.
                stepped = cycle = last_moving
            else:
                stepped = None  # skipped one by one below: not listed
        elif self._woken:
            self._woken = []  # every answering module is stepped
        self._stepped = stepped
        moving = []
        for n, module in cycle:
            if skip_still and module.still:
                continue
            module.step(dt_us, outputs_enabled)
            if not module.still:
                moving.append((n, module))
            if module._raised:  # take_raised_alarms() returns [] without any: no call
                self.fresh_raised.extend(Alarm(MODULE, code, n)
                                         for code in module.take_raised_alarms())
        for n in silent:  # §6.18: a failed exchange on the internal bus
            self.comm_errors[n - 1] = min(UDINT_MAX, self.comm_errors[n - 1] + 1)
        self._moving = (bus, moving)
        self._bus_still = still and not moving and not silent

    def _who_answers(self, bus: list[IoModule | None]) -> tuple[list[bool],
                                                                 list[tuple[int, IoModule]],
                                                                 list[int]]:
        """Per module number whether it answers; the (number, module) pairs that do; the
        numbers that do not. Answering changes only by a command (plug, power, failure),
        which touches the model (FastCat.step drops this then), or with the bus table."""
        cache = self._answer_cache
        if cache is None or cache[0] is not bus:
            answering = [m is not None and m.responds() for m in bus]
            cycle = [(n, m) for n, m in enumerate(bus, start=1)
                     if m is not None and answering[n - 1]]
            silent = [n for n, ok in enumerate(answering, start=1) if not ok]
            cache = self._answer_cache = (bus, answering, cycle, silent)
        return cache[1], cache[2], cache[3]

    def _answers(self, n: int) -> bool:
        module = self._bus_table()[n - 1]
        return module is not None and module.responds()

    def _bus_table(self) -> list[IoModule | None]:
        """Per module number, the module bound to it if it sits in its detected slot (the one
        the coupler talks to), else None. Rebuilt only when the rail, the scan result or the
        binding changed."""
        key, rail = self._bus_key, self.rail
        if key and rail == key[0] and self.detected is key[1] and self.bound == key[2]:
            return self._bus
        self._bus = [m if slot <= len(rail) and rail[slot - 1] is m else None
                     for (slot, _name), m in zip(self.detected, self.bound, strict=True)]
        self._bus_key = (list(rail), self.detected, list(self.bound))
        return self._bus

    def _rebind(self) -> None:
        """A module of the detected type put back in a detected slot answers at that address:
        the coupler talks to the bus position, not to one particular module."""
        changed = False
        for n, (slot, name) in enumerate(self.detected, start=1):
            module = self.rail[slot - 1] if slot <= len(self.rail) else None
            if module is not None and module is not self.bound[n - 1] \
                    and module.mtype.name == name:
                self.bound[n - 1] = module
                changed = True
        if changed:
            self._build_od()
