"""Differential tests of the FastCAT's in-motion shortcuts (docs/fastcat-coupler.md, "Step
cost"): each shortcut is run beside the plain computation it replaces and must agree with it
step for step, events, snapshots and object values alike.

- the coupler keeps who answers between steps and, in a repeat, steps only the modules the
  last cycle left moving (bus.py); after a search that found no alarm cause it looks only at
  the modules it stepped (faults.py); the plain twin is touched before every step and its
  caches dropped, so it asks every module, steps every answering one and searches every
  cause (seed 000 §6.18 comm errors, §7 alarms);
- an analog input recomputes the law (target, filter coefficient) of the channels whose
  inputs changed only (§6.8-§6.10, §6.15); the plain twin recomputes every channel;
- an encoder step within one revolution counts at once (§6.26); the plain twin takes the
  general path (zero marks, noise and signal checks);
- analog outputs on their target are not ramped (§6.7).
"""

from __future__ import annotations

import json
import math
import random
from collections.abc import Callable
from typing import Any

import pytest

from devices.device import Action, CommandError
from devices.ethercat import AlState
from devices.fastcat.analog import AnalogInputs, AnalogOutputs, ramp_toward
from devices.fastcat.catalog import module_type
from devices.fastcat.coupler import FastCat
from devices.fastcat.encoder import SUB, EncoderInput
from devices.flash import MemoryFlash
from devices.master import EtherCatMaster
from devices.od import SdoAbort

DEFAULT = ("DB16", "DI16", "DO16", "AI8D", "AO4", "AI8TC", "AX2")  # static/rigs/default.toml
STEP_US = 1_000


class FreshActivityFastCat(FastCat):
    """The coupler reading the LINK activity afresh where the step used to (the LEDs, the
    settled key) instead of the step's one reading at its start (session 10)."""

    def _refresh(self, activity: bool | None = None) -> None:
        super()._refresh(None)

    def step(self, now_us: int) -> None:
        super().step(now_us)
        if self._settled is not None:
            self._settled = (self._settled[0], self._activity(now_us))


class Twin:
    """A coupler and its master stepped at 1 ms, with the events they emitted, as JSON."""

    def __init__(self, plain: bool, seed: int = 3, master: bool = True) -> None:
        coupler = FreshActivityFastCat if plain else FastCat
        self.fc = coupler("fastcat", random.Random(seed), [(m, {}) for m in DEFAULT],
                          flash=MemoryFlash())
        self.devices: list[Any] = [self.fc]
        self.master: Any = None
        if master:
            self.master = EtherCatMaster("master", random.Random(seed + 1), slaves=[self.fc])
            self.devices.append(self.master)
        self.plain = plain
        self.now = 0
        self.events: list[str] = []

    def step(self) -> None:
        if self.plain:  # a full step: who answers asked again, every answering module
            # stepped, every alarm cause searched for
            self.fc._touched = self.fc._modules_touched = True
            self.fc._answer_cache = None
            self.fc._quiet = False
        self.now += STEP_US
        for device in self.devices:
            device.step(self.now)
            self.events += [json.dumps(e.to_record(), sort_keys=True)
                            for e in device.drain_events()]

    def apply(self, action: str, module: int | None = None, **args: Any) -> Any:
        return self.fc.apply(action, args, module)

    def view(self) -> str:
        od = self.fc.od

        def read(index: int, sub: int) -> Any:
            assert od is not None
            try:
                return od.read(index, sub)
            except SdoAbort as abort:  # module numbers move with a rescan
                return str(abort)

        values = [] if od is None else [
            read(0x6000, ch) for ch in range(1, 17)] + [  # 0x6000 of module 1
            read(0x6400 + 0x10 * 3, ch) for ch in range(1, 9)] + [  # 0x6400 of module 4
            read(0x6500 + 0x10 * 6, k) for k in (1, 2)] + [  # 0x6500 of module 7
            self.fc.od_comm_errors(n) for n in range(1, 8)]
        return json.dumps([self.fc.snapshot(), values], sort_keys=True, default=str)


# Motion as bench/kernel.py drives it, and the field changes that touch the shortcuts' caches.
def _motion(t: Twin, i: int) -> None:
    if i == 0:
        t.apply("set_shaft_speed", module=7, encoder=1, rpm=600.0)
        t.apply("set_shaft_speed", module=7, encoder=2, rpm=-150.0)
        t.apply("write_object", index=0x200A + 0x40, sub=1, value=2)  # AO4 ramp, 2 codes/ms
    if i % 10 == 0:
        value = round(2.5 + 2.5 * math.sin(i / 2000 * 2 * math.pi), 3)
        t.apply("set_analog", module=4, channel=1, value=value)
        t.apply("set_analog", module=6, channel=1, value=20.0 + 10 * value)
    if i % 250 == 0:
        t.apply("write_object", index=0x7400 + 0x40, sub=1,
                value=1000 if (i // 250) % 2 else -1000)


EPISODES: dict[str, Callable[[Twin, int], Any]] = {
    "module fails and comes back": lambda t, i: (
        i == 300 and t.apply("module_failure", module=2, active=True),
        i == 900 and t.apply("module_failure", module=2, active=False)),
    "module unplugged and put back": lambda t, i: (
        i == 300 and t.apply("unplug", module=5),
        i == 700 and t.apply("plug", module=5, type="AO4")),
    "EtherCAT cable out and back": lambda t, i: (
        i == 300 and t.apply("link", connected=False),
        i == 700 and t.apply("link", connected=True)),
    "master stops sending frames and starts again": lambda t, i: (  # LINK activity off, on
        i == 300 and t.devices.pop(),
        i == 700 and t.devices.append(t.master)),
    "module supply off and on": lambda t, i: (
        i == 300 and t.apply("module_power", module=7, on=False),
        i == 800 and t.apply("module_power", module=7, on=True)),
    "encoder faults": lambda t, i: (
        i == 200 and t.apply("encoder_fault", module=7, encoder=1, fault="pulse_noise",
                             active=True),
        i == 400 and t.apply("encoder_fault", module=7, encoder=2, fault="no_zero_mark",
                             active=True),
        i == 600 and t.apply("encoder_fault", module=7, encoder=1, fault="signal_lost",
                             active=True)),
    "thermocouple and cold junction": lambda t, i: (
        i == 250 and t.apply("wire_thermocouple", module=6, channel=1, type="K"),
        i == 500 and t.apply("write_object", index=0x200B + 0x50, sub=1, value=1),
        i == 700 and t.apply("write_object", index=0x2104 + 0x50, sub=0, value=10000)),
    "output short and reset fault": lambda t, i: (
        i == 200 and t.apply("write_object", index=0x7000 + 0x20, sub=3, value=1),
        i == 300 and t.apply("output_short", module=3, channel=3, active=True),
        i == 600 and t.apply("output_short", module=3, channel=3, active=False),
        i == 700 and t.apply("set_reset_fault", on=True)),
    "modules swapped and swapped back": lambda t, i: (
        i == 200 and t.apply("swap", module=1, other=2),
        i == 500 and t.apply("swap", module=1, other=2),
        i == 800 and t.apply("set_reset_fault", on=False),
        i == 801 and t.apply("set_reset_fault", on=True)),
    "CNF rescan with a module changed": lambda t, i: (
        i == 100 and t.apply("unplug", module=2),
        i == 101 and t.apply("plug", module=2, type="DI16"),  # a new one of the same type
        i == 200 and t.apply("hold_cnf", seconds=3.0)),
}
STEPS = {"CNF rescan with a module changed": 9000}  # CNF 3 s, scan 3 s, master back to OP


@pytest.mark.parametrize("episode", sorted(EPISODES))
def test_in_motion_shortcuts_match_the_plain_step(episode: str) -> None:
    """Seed 000 §6.18, §6.24-§6.30, §7: the same commands on a coupler taking its shortcuts
    and on one doing every step in full leave the same events, snapshots and objects."""
    fast, plain = Twin(plain=False), Twin(plain=True)
    for t in (fast, plain):  # boot and let the master take the line to OP
        for _ in range(4000):
            t.step()
        assert t.fc.al_state is AlState.OP
    assert fast.view() == plain.view()
    for i in range(STEPS.get(episode, 1200)):
        for t in (fast, plain):
            _motion(t, i)
            EPISODES[episode](t, i)
            t.step()
        if i % 50 == 0:
            assert fast.view() == plain.view(), f"step {i}"
    if episode in STEPS:
        assert fast.fc.al_state is AlState.OP and fast.fc.scan is None
    assert fast.events == plain.events
    assert fast.view() == plain.view()


def test_rescan_without_a_master_matches_the_plain_step() -> None:
    """§2, §3, §6.18, §7.5: with no master to touch the coupler, a CNF scan binds a module
    plugged at the end of the rail (the bus table and who answers change with the scan
    alone); the flash write fails, so the first cause found is SAVE_FLASH (0x11) and the
    alarm search stops before it looks at the bus."""
    fast, plain = Twin(plain=False, master=False), Twin(plain=True, master=False)
    for t in (fast, plain):
        for _ in range(4000):  # past the power-up scan
            t.step()
    for i in range(9000):
        for t in (fast, plain):
            if i == 0:
                t.apply("set_shaft_speed", module=7, encoder=1, rpm=600.0)
            if i % 10 == 0 and not 1000 <= i < 8000:  # nothing touches the coupler from
                # the CNF press to well after the scan
                t.apply("set_analog", module=4, channel=1, value=round(math.sin(i / 300), 3))
            if i == 500:
                t.apply("plug", module=8, type="AX2")
                t.apply("set_shaft_speed", module=8, encoder=2, rpm=-300.0)
            if i == 600:
                t.fc.flash.fail = True  # type: ignore[attr-defined]
            if i == 1000:
                t.apply("hold_cnf", seconds=3.0)
            t.step()
        if i % 250 == 0:
            assert fast.view() == plain.view(), f"step {i}"
    assert [name for _slot, name in fast.fc.detected] == [*DEFAULT, "AX2"]
    assert fast.fc.alarm is not None and fast.fc.alarm.code == 0x11
    assert fast.fc.rail[7].ax2.inputs[1].position != 0  # type: ignore[union-attr]
    assert fast.events == plain.events


def test_level_alarm_from_a_module_step_is_found() -> None:
    """§7, §7.6: a level alarm that appears in a module's own step, with no command, is latched
    in that step as by the full search. No module type does that today (their level alarms
    follow commands), so the AX2 is given one: encoder 1's signal alarm (0x12) once its
    counter passes 15000 pulses."""
    twins = Twin(plain=False), Twin(plain=True)
    for t in twins:
        for _ in range(4000):
            t.step()
        ax2 = t.fc.rail[6]
        assert ax2 is not None and ax2.ax2 is not None
        encoder = ax2.ax2.inputs[0]

        def codes(e: Any = encoder) -> tuple[int, ...]:
            return (0x12,) if e.position > 15_000 else ()
        ax2.physical_alarm_codes = codes  # type: ignore[method-assign]
    fast, plain = twins
    for i in range(1500):
        for t in twins:
            _motion(t, i)
            t.step()
    assert fast.fc.alarm is not None and fast.fc.alarm.code == 0x12
    assert fast.events == plain.events
    assert fast.view() == plain.view()


def test_fast_twin_takes_the_shortcut() -> None:
    """The comparison above is not between two plain steps: in motion and without a command,
    the coupler steps only the moving modules, in bus order (§6.18)."""
    fast = Twin(plain=False)
    for _ in range(4000):
        fast.step()
    _motion(fast, 0)
    for _ in range(5):
        fast.step()
    stepped: list[str] = []
    for module in fast.fc.modules():
        original = module.step

        def counted(dt_us: int, enabled: bool, m: Any = module, f: Any = original) -> None:
            stepped.append(m.mtype.name)
            f(dt_us, enabled)
        module.step = counted  # type: ignore[method-assign]
    for _ in range(9):
        fast.step()
    assert stepped == ["AI8D", "AO4", "AI8TC", "AX2"] * 9


def test_field_command_steps_its_module_only() -> None:
    """A field value on an analog input (set_analog) is no input of who answers, of the still
    modules' steps or of any alarm cause (§6.18, §7): the next cycle steps the modules left
    moving and that module, still or not, asks no module whether it answers and searches no
    cause; the value reaches 0x6400 as in a full step (the differential above)."""
    fast = Twin(plain=False)
    for _ in range(4000):
        fast.step()
    for _ in range(5):
        fast.step()  # everything settled: no module moving
    stepped: list[str] = []
    asked: list[str] = []
    for module in fast.fc.modules():
        step, responds = module.step, module.responds

        def counted(dt_us: int, enabled: bool, m: Any = module, f: Any = step) -> None:
            stepped.append(m.mtype.name)
            f(dt_us, enabled)

        def answers(m: Any = module, f: Any = responds) -> bool:
            asked.append(m.mtype.name)
            return bool(f())
        module.step = counted  # type: ignore[method-assign]
        module.responds = answers  # type: ignore[method-assign]
    searched: list[int] = []
    causes = fast.fc._causes

    def counted_causes() -> Any:
        searched.append(1)
        return causes()
    fast.fc._causes = counted_causes  # type: ignore[method-assign]
    fast.step()
    assert stepped == []  # settled: the step skipped whole
    fast.apply("set_analog", module=4, channel=2, value=3.0)
    fast.step()
    assert stepped == ["AI8D"] and asked == [] and searched == []
    for _ in range(20):
        fast.step()
    assert set(stepped) == {"AI8D"} and asked == [] and searched == []
    assert fast.fc.od is not None and fast.fc.od.read(0x6400 + 0x10 * 3, 2) != 0


def test_module_command_checks_its_arguments_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """A module command through the coupler (fastcat/N) is checked once: the coupler's check
    gives the arguments the module's own check would (rail.py MODULE_ACTIONS are the module's
    actions with the same parameters), and what the module's type cannot take is still
    refused; the module's own ``apply`` (rig-file options, module tests) still checks."""
    fc = FastCat("fastcat", random.Random(1), [(m, {}) for m in DEFAULT], flash=MemoryFlash())
    checks: list[str] = []
    check_args = Action.check_args

    def counted(spec: Action, args: Any) -> dict[str, Any]:
        checks.append(spec.name)
        return check_args(spec, args)
    monkeypatch.setattr(Action, "check_args", counted)
    fc.apply("set_analog", {"channel": 2, "value": 3}, 4)
    fc.apply("set_input", {"channel": 1, "value": True}, 2)
    assert checks == ["set_analog", "set_input"]
    ai = fc.rail[3]
    assert ai is not None and ai.ai is not None and ai.ai.field[1] == 3.0
    assert type(ai.ai.field[1]) is float  # the checked (converted) value, as before
    with pytest.raises(CommandError, match="needs a module with"):
        fc.apply("set_analog", {"channel": 1, "value": 1.0}, 1)  # DB16: no analog input
    with pytest.raises(CommandError, match="must be float"):
        fc.apply("set_analog", {"channel": 1, "value": "x"}, 4)
    checks.clear()
    ai.apply("set_analog", {"channel": 2, "value": 4.0})
    assert checks == ["set_analog"]


# --- analog inputs: only the channels whose inputs changed are recomputed ----------------------
@pytest.mark.parametrize("name", ["AI8D", "AI8TC", "AI8M", "AI4P", "AB4M4"])
def test_analog_law_per_channel_matches_every_channel(name: str) -> None:
    """§6.8-§6.10, §6.15: random changes to field values, filters, types, thermocouple types,
    wiring, cold junction and pot supply; the fast module (per-channel law) and the plain one
    (every channel recomputed each step, ``_seen`` forgotten) read the same codes."""
    mtype = module_type(name)
    fast, plain = AnalogInputs(mtype), AnalogInputs(mtype)
    rng = random.Random(name)
    for i in range(3000):
        if rng.random() < 0.2:
            change = _random_change(rng, fast)
            for ai in (fast, plain):
                change(ai)
        dt = rng.choice((1000, 1000, 1000, 250, 2000))
        plain._seen = ()  # the plain path: every channel's law recomputed
        fast.step(dt)
        plain.step(dt)
        assert [fast.code(ch) for ch in range(fast.count)] == \
            [plain.code(ch) for ch in range(plain.count)], f"step {i}"
        assert fast._law == [(fast.target(ch), fast.coeff(ch)) for ch in range(fast.count)]
        assert fast.still == plain.still


class MethodFilterInputs(AnalogInputs):
    """The analog inputs advancing each channel through ``InputFilter.advance``, as before
    the step wrote it out (session 10)."""

    def step(self, dt_us: int) -> None:
        inputs = (self.field, self.cold_junction_c, self.pot_supply_short, self.filter_all,
                  self.filters, self.types, self.tc_types, self.wired)
        active = self._active
        if inputs != self._seen:
            changed = self._relaw(inputs)
            active = sorted(changed.union(active))
        if dt_us != self._active_dt:
            active, self._active_dt = list(range(self.count)), dt_us
        self.still = not active
        filters, law = self._filters, self._law
        self._active = [ch for ch in active
                        if filters[ch].advance(*law[ch], dt_us)]  # type: ignore[misc]


@pytest.mark.parametrize("name", ["AI8D", "AI8TC", "AI8M", "AI4P", "AB4M4"])
def test_inline_filter_advance_matches_the_method(name: str) -> None:
    """§6.9-§6.10: the step's inline filter arithmetic against InputFilter.advance, under
    random field, filter and type changes at several step lengths: every filter's state (y
    and the sub-millisecond remainder) bit for bit, the channels left moving, ``still``."""
    mtype = module_type(name)
    fast, plain = AnalogInputs(mtype), MethodFilterInputs(mtype)
    rng = random.Random(f"inline {name}")
    for i in range(4000):
        if rng.random() < 0.1:
            change = _random_change(rng, fast)
            for ai in (fast, plain):
                change(ai)
        dt = rng.choice((1000, 1000, 1000, 250, 700, 2000, 5000))
        fast.step(dt)
        plain.step(dt)
        assert [(f.y.hex(), f._rem_us) for f in fast._filters] == \
            [(f.y.hex(), f._rem_us) for f in plain._filters], f"step {i}"
        assert fast._active == plain._active and fast.still == plain.still


def _random_change(rng: random.Random, ai: AnalogInputs) -> Callable[[AnalogInputs], None]:
    """One change to an input of the law, to apply to both twins alike."""
    ch = rng.randrange(ai.count)
    kind = ai.kind(ch)
    value = round(rng.uniform(kind.field_low, kind.field_high), 2)
    coeff = rng.choice((1, 100, 4000, 10000))
    bit = rng.randrange(2)
    ai_type = rng.randrange(1, 6)
    choices: list[Callable[[AnalogInputs], None]] = [
        lambda a: a.field.__setitem__(ch, value),
        lambda a: a.field.__setitem__(ch, value),
        lambda a: setattr(a, "cold_junction_c", value % 40),
        lambda a: setattr(a, "pot_supply_short", not a.pot_supply_short),
        lambda a: setattr(a, "filter_all", coeff),
        lambda a: a.filters.__setitem__(ch, coeff),
        lambda a: a.tc_types.__setitem__(ch, bit),
        lambda a: a.wired.__setitem__(ch, "K" if bit else "J"),
    ]
    if ai.configurable:
        choices.append(lambda a: a.set_type(ch, ai_type))
    return rng.choice(choices)


# --- encoders: the one-revolution shortcut against the general path ---------------------------
class _NeverEmpty(set[str]):
    """A fault set that reads as non-empty: the encoder takes its general path."""

    def __bool__(self) -> bool:
        return True


@pytest.mark.parametrize("rpm", [600.0, -150.0, 6000.0, -59999.0, 0.5, 3.0])
@pytest.mark.parametrize("invert", [False, True])
def test_encoder_one_revolution_shortcut_matches_the_general_path(rpm: float,
                                                                  invert: bool) -> None:
    """§6.12, §6.13, §6.26: positions, mark-to-mark counts, zero cycle and raised alarms agree
    with the general path over many revolutions, with odd step lengths and a zero cycle."""
    fast, plain = EncoderInput(0, 1000), EncoderInput(0, 1000)
    plain.faults = _NeverEmpty()
    rng = random.Random(5)
    for enc in (fast, plain):
        enc.set_rpm(rpm)
        enc.ppr_setting = 999  # a count alarm at every mark
    for i in range(4000):
        if i == 100:
            for enc in (fast, plain):
                enc.arm_zero_cycle()
        dt = rng.choice((1000, 1000, 333, 2500))
        fast.step(dt, invert, random.Random(i))
        plain.step(dt, invert, random.Random(i))
        assert (fast.theta, fast.position, fast.since_mark, fast.travel, fast.armed,
                fast.zero_done, fast.last_mark_dir, fast.raised) == \
            (plain.theta, plain.position, plain.since_mark, plain.travel, plain.armed,
             plain.zero_done, plain.last_mark_dir, plain.raised), f"step {i}"
    assert abs(fast.theta - SUB // 2) > 0


@pytest.mark.parametrize("rpm", [6000.0, -6000.0])
def test_encoder_shortcut_rolls_over_as_the_general_path(rpm: float) -> None:
    """§6.26: 0x6500 is a DINT; the one-revolution step (its count written out inline,
    session 10) rolls over at ±2^31 exactly as the general path's wrap32."""
    fast, plain = EncoderInput(0, 1000), EncoderInput(0, 1000)
    plain.faults = _NeverEmpty()
    for enc in (fast, plain):
        enc.set_rpm(rpm)
        enc.position = 0x7FFF_FF00 if rpm > 0 else -0x8000_0000 + 0x100
    for i in range(100):
        fast.step(1000, False, random.Random(i))
        plain.step(1000, False, random.Random(i))
        assert (fast.position, fast.since_mark) == (plain.position, plain.since_mark)
    assert (fast.position < 0) == (rpm > 0)  # it did roll over


# --- analog outputs: a channel on its target is left alone --------------------------------------
@pytest.mark.parametrize("ramp", [0, 1, 7, 40000])
def test_ao_channel_on_target_is_where_a_ramp_leaves_it(ramp: int) -> None:
    """§6.7: ``ramp_toward`` of a channel already on its target returns the target, so not
    calling it changes nothing; outputs still ramp as before."""
    for code in (-2047, 0, 5, 2047):
        assert ramp_toward(code, code, ramp, 3) == code
    ao = AnalogOutputs(module_type("AO4"))
    ao.ramps = [ramp, 0, 2, 0]
    ao.targets = [1500, 0, -300, 0]
    expected = [0, 0, 0, 0]
    for _ in range(200):
        expected = [ramp_toward(a, max(-ao.full, min(ao.full, t)), r, 1)
                    for a, t, r in zip(expected, ao.targets, ao.ramps, strict=True)]
        ao.step(1000, True)
        assert ao.actual == expected
