"""Regression guards for the simulation-kernel speed work (docs/performance.md), counted and
compared, never timed.

An idle coupler in OP does no work whose inputs did not change; anything from outside (a
command, an AL control write, an object write) still reaches the model at the next step; and
the shortcuts change no event and no value (seed 000 §2, §6.25, §6.28, §7).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest
from fastcat_bench import Bench

from devices.ethercat import AlState
from devices.fastcat import coupler as coupler_module
from devices.fastcat.analog import AnalogInputs
from devices.fastcat.coupler import FastCat
from devices.fastcat.modules import IoModule
from devices.leds import LedBank

DEFAULT = ("DB16", "DI16", "DO16", "AI8D", "AO4", "AI8TC", "AX2")  # static/rigs/default.toml


def counter(monkeypatch: pytest.MonkeyPatch, owner: Any, name: str) -> list[Any]:
    """Every call of ``owner.name`` from now on appends its first argument to the list."""
    calls: list[Any] = []
    original = getattr(owner, name)

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls.append(args[0] if args else None)
        return original(*args, **kwargs)
    monkeypatch.setattr(owner, name, counted)
    return calls


def in_op(modules: tuple[str, ...] = DEFAULT) -> Bench:
    bench = Bench(modules, master=True)
    bench.run_until(lambda: bench.fc.al_state is AlState.OP and bench.fc.scan is None)
    bench.run(0.5)
    return bench


def test_idle_op_rig_redoes_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two idle seconds in OP: no module step, no alarm-cause search, no LED table, no object
    dictionary, no analog target recomputed, no event."""
    bench = in_op()
    counts = {name: counter(monkeypatch, owner, attr) for name, owner, attr in (
        ("module steps", IoModule, "step"),
        ("cause searches", FastCat, "_causes"),
        ("LED updates", LedBank, "update"),
        ("OD builds", coupler_module, "build_od"),
        ("analog targets", AnalogInputs, "target"),
    )}
    since = bench.mark()
    bench.run(2.0)
    assert {name: len(calls) for name, calls in counts.items()} == dict.fromkeys(counts, 0)
    assert bench.events[since:] == []


def test_only_the_moving_module_is_stepped(monkeypatch: pytest.MonkeyPatch) -> None:
    """A turning AX2 shaft (§6.26) keeps its module stepping every cycle; the still modules
    beside it are not stepped again."""
    bench = in_op()
    od = bench.fc.od
    assert od is not None
    bench.apply("set_shaft_speed", module=7, encoder=1, rpm=600.0)
    bench.step()
    stepped = counter(monkeypatch, IoModule, "step")
    before = od.read(0x6560, 1)  # 0x6500 of module 7 (§6.26)
    bench.run(0.1)
    assert [m.mtype.name for m in stepped] == ["AX2"] * 100
    assert od.read(0x6560, 1) - before == 2048  # 600 rpm: one turn in 100 ms


def test_object_write_without_a_command_reaches_the_module() -> None:
    """A master's RxPDO write goes straight into the object dictionary, not through a
    command: the next cycle still drives the output (§6.28 0x7000 of module 3)."""
    bench = in_op()
    do16 = bench.fc.rail[2]
    assert do16 is not None and not do16.snapshot()["do"][0]
    assert bench.fc.od is not None
    bench.fc.od.write(0x7020, 1, 1)
    bench.step()
    assert do16.snapshot()["do"][0]


def test_al_control_write_without_a_command_reaches_the_outputs() -> None:
    """Leaving OP puts the outputs in their safe state at the next cycle (§6.28; ETG.1000.6:
    outputs only in OP), although no command was applied."""
    bench = in_op()
    bench.write(0x7020, 1, 1)
    bench.step()
    do16 = bench.fc.rail[2]
    assert do16 is not None and do16.snapshot()["do"][0]
    assert bench.master is not None
    bench.master.cmd_set_target("SAFEOP")  # the master writes AL control at its next step
    bench.run(0.01)
    assert bench.fc.al_state is AlState.SAFEOP
    assert not do16.snapshot()["do"][0]


def script(bench: Bench, before_step: Callable[[], None]) -> list[str]:
    """Power-on, OP, outputs, analog in and out, encoder homing, a fault and its reset, a
    cable pulled: every event and a snapshot every 50 ms, as JSON lines."""
    out: list[str] = []
    seen = 0

    def run(seconds: float) -> None:
        nonlocal seen
        for i in range(round(seconds * 1000)):
            before_step()
            bench.step()
            if i % 50 == 0:
                out.append(json.dumps(bench.fc.snapshot(), sort_keys=True))
        out.extend(json.dumps(e.to_record(), sort_keys=True) for e in bench.events[seen:])
        seen = len(bench.events)

    run(6.0)
    if bench.master is None:
        bench.to_state(AlState.OP)  # AL control answered at once, between two cycles
    bench.write(0x7020, 1, 1)  # DO16 output 1 (§6.28)
    bench.write(0x204A, 1, 3)  # AO4 ramp 3 codes/ms (§6.7), then a target (§6.29)
    bench.write(0x7440, 1, 1500)
    bench.apply("set_analog", module=4, channel=1, value=5.0)  # AI8D filter (§6.9, §6.25)
    bench.apply("set_shaft_speed", module=7, encoder=1, rpm=120.0)
    bench.write(0x7660, 0, 0x1000)  # AX2 zero cycle encoder 1 (§6.30)
    run(2.0)
    bench.apply("set_shaft_speed", module=7, encoder=1, rpm=0.0)
    run(1.0)  # every module still again: the steps are skipped until the next change
    bench.apply("calibrated", module=6, value=False)  # §7.6 0x0B TARATURA
    run(0.5)
    bench.apply("calibrated", module=6, value=True)
    bench.reset_fault()  # §6.17
    run(3.0)
    bench.apply("link", connected=False)  # §7.5 0x13 LINK_LOSS
    run(0.5)
    bench.apply("link", connected=True)
    bench.reset_fault()
    run(3.0)
    return out


@pytest.mark.parametrize("master", [True, False], ids=["with master", "coupler alone"])
def test_shortcuts_change_nothing(master: bool) -> None:
    """The same script with a no-op command before every cycle (every shortcut off: each step
    a full one, every module stepped) gives the same events and the same snapshots."""
    quick = Bench(DEFAULT, master=master)
    full = Bench(DEFAULT, master=master)
    rotary = full.fc.rotary_switch
    reference = script(full, lambda: full.fc.apply("set_rotary", {"value": rotary}))
    assert script(quick, lambda: None) == reference
    assert any('"event": "alarm"' in line for line in reference)  # the script reached them
    assert any('"homed": true' in line for line in reference)
