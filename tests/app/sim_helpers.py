"""Test helpers for the Modbus side: a tiny simulation thread and a fake drive.

:class:`SimThread` steps devices 1 ms of simulated time per loop and runs submitted functions
between steps, like the runtime does (app/runtime.py).

Free-running (as fast as the CPU allows) or paused; paused, it still runs submitted work, and
:meth:`SimThread.advance` steps a given amount of simulated time. Waiting is on simulated time:
:meth:`SimThread.wait_for` returns when a predicate holds, checked in the simulation thread
after every step, or fails once the simulated budget is spent.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any, Protocol, TypeVar

from devices.servo.errors import AccessError

T = TypeVar("T")

STEP_US = 1_000
WALL_TIMEOUT_S = 60.0


class Steppable(Protocol):
    def step(self, now_us: int) -> None: ...


class SimThread:
    def __init__(self, devices: Sequence[Steppable], paused: bool = False) -> None:
        self.devices = list(devices)
        self.now_us = 0
        self._work: queue.Queue[tuple[Callable[[], Any], Future[Any]]] = queue.Queue()
        self._running = not paused
        self._budget_us = 0  # simulated time still to step while paused
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="test-sim", daemon=True)
        self._watch: list[tuple[Callable[[], bool], int, int, Future[int]]] = []

    def __enter__(self) -> SimThread:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._work.put((lambda: None, Future()))  # wake the thread if it is idle
        self._thread.join(5)

    # ---- what the server uses ------------------------------------------------------------
    def submit(self, fn: Callable[[], T]) -> Future[T]:
        fut: Future[T] = Future()
        self._work.put((fn, fut))
        return fut

    # ---- what tests use ------------------------------------------------------------------
    def call(self, fn: Callable[[], T]) -> T:
        """Run ``fn`` in the simulation thread and return its result."""
        return self.submit(fn).result(WALL_TIMEOUT_S)

    def pause(self) -> None:
        self.call(lambda: setattr(self, "_running", False))

    def resume(self) -> None:
        self.call(lambda: setattr(self, "_running", True))

    def advance(self, us: int) -> None:
        """While paused: step ``us`` of simulated time, then return."""
        target = self.call(lambda: self._add_budget(us))
        self.wait_for(lambda: self.now_us >= target, us + STEP_US)

    def wait_for(self, predicate: Callable[[], bool], within_us: int) -> int:
        """Block until ``predicate()`` (run in the simulation thread) holds; return the
        simulated time it took. Fails once ``within_us`` of simulated time passed first."""
        fut: Future[int] = Future()
        self.submit(lambda: self._watch.append((predicate, self.now_us, within_us, fut)))
        took = fut.result(WALL_TIMEOUT_S)
        if took < 0:
            raise AssertionError(f"condition not met within {within_us} us of simulated time")
        return took

    # ---- the thread ----------------------------------------------------------------------
    def _add_budget(self, us: int) -> int:
        self._budget_us += us
        return self.now_us + self._budget_us

    def _run(self) -> None:
        while not self._stop.is_set():
            stepping = self._running or self._budget_us > 0
            self._drain(block=not stepping)
            self._check_watches()
            if self._running or self._budget_us > 0:
                self.now_us += STEP_US
                self._budget_us = max(0, self._budget_us - STEP_US)
                for device in self.devices:
                    device.step(self.now_us)
                self._check_watches()

    def _drain(self, block: bool) -> None:
        try:
            fn, fut = self._work.get(timeout=0.05) if block else self._work.get_nowait()
        except queue.Empty:
            return
        while True:
            if fut.set_running_or_notify_cancel():
                try:
                    fut.set_result(fn())
                except BaseException as exc:
                    fut.set_exception(exc)
            try:
                fn, fut = self._work.get_nowait()
            except queue.Empty:
                return

    def _check_watches(self) -> None:
        keep = []
        for pred, since, within, fut in self._watch:
            if pred():
                fut.set_result(self.now_us - since)
            elif self.now_us - since > within:
                fut.set_result(-1)
            else:
                keep.append((pred, since, within, fut))
        self._watch = keep


# ---- a fake drive ----------------------------------------------------------------------------
# The ServoDrive access API and nothing else, to isolate the Modbus quirks. Values and ranges are
# free here: the seed's R00/R01 read example shows 0x1122 and 0x3344, which the real control
# word and mode register cannot hold.
@dataclass
class Cell:
    value: int
    low: int
    high: int
    readonly: bool = False


@dataclass
class FakeDrive:
    node_id: int = 1
    responding: bool = True
    fieldbus: str = "modbus"
    registers: dict[int, Cell] = field(default_factory=dict)
    parameters: dict[int, Cell] = field(default_factory=dict)
    saves: int = 0
    save_us: int = 3_000_000  # "operazione della durata di qualche secondo" (ch.2)
    now_us: int = 0
    save_ends_us: int | None = None
    #: writing R00 = 0x20 in mode -50 starts a save during which the drive does not answer
    save_on_control_word: bool = True

    @classmethod
    def default(cls, node_id: int = 1) -> FakeDrive:
        s32 = (-0x8000_0000, 0x7FFF_FFFF)
        regs = {n: Cell(0, *s32) for n in range(134)}
        regs[0] = Cell(0, 0, 0xFFFF)  # control word
        regs[1] = Cell(0, -128, 127)  # modes of operation 0x81..0x7f
        regs[3] = Cell(0, 0, 0xFFFF_FFFF)  # following_error_window (unsigned, as printed)
        regs[5] = Cell(0, 0, 0xFF, readonly=True)  # status word
        regs[6] = Cell(0, *s32, readonly=True)  # position_actual_value
        params = {a: Cell(50, 1, 99) for a in (*range(1, 23), *range(35, 54), 55, 58,
                                                *range(59, 68), 81, 82, 83, 90, 99)}
        params[1], params[2] = Cell(20, 1, 99), Cell(50, 1, 99)  # ch.2 example: d1 20, d2 50
        params[20] = Cell(node_id, 1, 90)  # c7
        params[58] = Cell(0, 0, 99)  # e3
        params[81] = Cell(0, 0, 0xFFFF, readonly=True)  # o1 instantaneous current
        return cls(node_id=node_id, registers=regs, parameters=params)

    # ---- the ServoDrive access API ---------------------------------------------------------
    def is_register(self, n: int) -> bool:
        return n in self.registers

    def parameter_addresses(self) -> list[int]:
        return sorted(self.parameters)

    def read_register(self, n: int) -> int:
        return self._cell(self.registers, n).value

    def write_register(self, n: int, value: int) -> None:
        cell = self._cell(self.registers, n)
        if cell.low < 0 and value > 0x7FFF_FFFF:
            value -= 1 << 32  # the wire pattern read as signed, like RegisterSpec.normalize
        self._write(cell, value)
        if n == 0 and value == 0x20 and self.registers[1].value == -50 and \
                self.save_on_control_word:
            self._start_save()

    def read_parameter(self, address: int) -> int:
        return self._cell(self.parameters, address).value

    def write_parameter(self, address: int, value: int) -> None:
        if address == 0x3802:  # the save command (ch.2 "Salvataggio su flash")
            if value != 0x0011:
                raise AccessError("value", "0x3802 takes 0x0011 only")
            self._start_save()
            return
        self._write(self._cell(self.parameters, address), value)

    def step(self, now_us: int) -> None:
        self.now_us = now_us
        if self.save_ends_us is not None and now_us >= self.save_ends_us:
            self.save_ends_us = None
            self.responding = True

    def _start_save(self) -> None:
        self.saves += 1
        self.responding = False
        self.save_ends_us = self.now_us + self.save_us

    # ---- test helpers ----------------------------------------------------------------------
    def state(self) -> tuple:
        return (self.responding, self.saves,
                tuple((n, c.value) for n, c in sorted(self.registers.items())),
                tuple((a, c.value) for a, c in sorted(self.parameters.items())))

    @staticmethod
    def _cell(table: dict[int, Cell], key: int) -> Cell:
        if key not in table:
            raise AccessError("address", f"nothing at {key}")
        return table[key]

    @staticmethod
    def _write(cell: Cell, value: int) -> None:
        if cell.readonly:
            raise AccessError("readonly", "read-only")
        if not cell.low <= value <= cell.high:
            raise AccessError("value", f"{value} outside {cell.low}..{cell.high}")
        cell.value = value
