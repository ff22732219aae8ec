"""Analog process models of the FastCAT modules: input scaling, filter, thermocouples, AO ramps.

All formulas are in docs/fastcat-modules.md. Integers where the module works in ADC/DAC codes;
the first-order filter state is a float, advanced in whole milliseconds so that the result
depends only on simulated time, not on how the runtime slices it.

Speed (docs/performance.md): a step whose inputs are those of the previous step and after which
nothing moved is a fixed point, so the next identical step is skipped. Inputs are compared
by value, not tracked by setters, so that no way of changing them can be missed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from devices.fastcat.catalog import ModuleType
from devices.fastcat.module_od import add_object, pdo_entries
from devices.od import ObjectDictionary

US_PER_MS = 1000
# AnalogInputs.step's inputs tuple: the positions of the per-channel lists (_relaw).
_PER_CHANNEL = (0, 4, 5, 6, 7)

FILTER_MIN = 1  # §6.9 / §6.10: 1 = strongest filter
FILTER_MAX = 10000  # §6.9 / §6.10: 10000 = no filter
FILTER_DEFAULT = 4000  # §6.9 analog modules, §6.10 single filters
FILTER_DEFAULT_TEMPERATURE = 100  # §6.9 modules with temperatures


@dataclass(frozen=True)
class AiKind:
    """One kind of analog input channel: field value (engineering units) -> 0x6400 raw code."""

    name: str
    unit: str
    low: float  # engineering value mapped to raw_low
    high: float  # engineering value mapped to raw_high
    raw_low: int
    raw_high: int
    field_low: float  # what the operator may put on the terminals (over-range saturates)
    field_high: float

    def raw(self, value: float) -> int:
        """The ADC code for a field value, saturated at the kind's code range."""
        code = self.raw_low + (value - self.low) * (self.raw_high - self.raw_low) / (
            self.high - self.low)
        return min(self.raw_high, max(self.raw_low, round_half_up(code)))

    def value(self, raw: int) -> float:
        """The engineering value a raw code stands for (for views)."""
        return self.low + (raw - self.raw_low) * (self.high - self.low) / (
            self.raw_high - self.raw_low)


# Codes from §6.15 (0x4500 types); temperatures in tenths of °C (§6.15 type 5). Thermocouple
# codes are of the temperature the module computes (see thermocouple_reading).
AI_KINDS: dict[str, AiKind] = {k.name: k for k in (
    AiKind("diff_pm10", "V", -10.0, 10.0, -2047, 2047, -12.0, 12.0),
    AiKind("diff_0_10", "V", 0.0, 10.0, 0, 4096, -12.0, 12.0),
    AiKind("current", "mA", 0.0, 20.0, 0, 4096, 0.0, 24.0),
    AiKind("pot", "%", 0.0, 100.0, 0, 4096, 0.0, 100.0),
    AiKind("pt100", "°C", -200.0, 850.0, -2000, 8500, -200.0, 850.0),
    AiKind("pt1000", "°C", -200.0, 850.0, -2000, 8500, -200.0, 850.0),
    AiKind("thermocouple", "°C", -270.0, 1372.0, -2700, 13720, -200.0, 1200.0),
)}

# 0x4500 "Type of analog input" values of AI8M / AB4M4 (§6.15); 4 is the default.
CONFIGURABLE_TYPES: dict[int, str] = {
    1: "pot",  # Potenziometrico (0:4096)
    2: "current",  # Corrente 0:20mA (0:4096)
    3: "diff_0_10",  # Differenziale 0:10V (0:4096)
    4: "diff_pm10",  # Differenziale -10:10V (-2047:2047), valore di default
    5: "pt100",  # PT100 (decimi di grado)
}
CONFIGURABLE_DEFAULT = 4

# 0x200B values (§6.8): 0 = J (default), 1 = K.
THERMOCOUPLE_TYPES: dict[int, str] = {0: "J", 1: "K"}
# Mean Seebeck coefficients, mV/°C (commonly quoted: J about 50 µV/°C, K about 41 µV/°C).
SEEBECK_MV_PER_C: dict[str, float] = {"J": 0.050, "K": 0.041}
COLD_JUNCTION_DEFAULT_C = 25.0


def thermocouple_reading(t_hot: float, wired: str, configured: str, t_cold: float) -> float:
    """Temperature the module computes: the wired couple's EMF, linearised as `configured`.

    EMF = S_wired * (T_hot - T_cj); the module adds its cold-junction temperature back with the
    configured couple: T = T_cj + EMF / S_configured. Right type -> T_hot exactly.
    """
    emf_mv = SEEBECK_MV_PER_C[wired] * (t_hot - t_cold)
    return t_cold + emf_mv / SEEBECK_MV_PER_C[configured]


def round_half_up(x: float) -> int:
    return math.floor(x + 0.5)


class InputFilter:
    """First-order low-pass of one channel, per millisecond: y += (x - y) * f / 10000 (§6.9).

    Over k whole milliseconds with a constant target: y = x + (y0 - x) * (1 - f/10000) ** k.
    f = 10000 follows the input at once (no filter), f = 1 has a time constant of ~10 s.
    """

    __slots__ = ("_rem_us", "y")

    def __init__(self, start: int = 0) -> None:
        self.y: float = float(start)
        self._rem_us = 0

    def settle(self, target: int) -> None:
        """Jump to the target (power-up, channel reconfigured)."""
        self.y = float(target)
        self._rem_us = 0

    def advance(self, target: int, coeff: int, dt_us: int) -> bool:
        """One step toward ``target``; False when it changed nothing (a fixed point)."""
        y, rem = self.y, self._rem_us
        if coeff >= FILTER_MAX:
            self.y = float(target)
            return self.y != y
        ms, self._rem_us = divmod(rem + dt_us, US_PER_MS)
        if ms:
            keep = (1.0 - coeff / FILTER_MAX) ** ms
            self.y = target + (y - target) * keep
        return self.y != y or self._rem_us != rem

    @property
    def code(self) -> int:
        return min(0x7FFF, max(-0x8000, round_half_up(self.y)))


def ao_full_scale(bits: int) -> int:
    """Largest code of a ±10 V DAC of `bits` (12 -> 2047, 16 -> 32767): signed codes."""
    return (1 << (bits - 1)) - 1


def ao_volts(code: int, bits: int) -> float:
    return 10.0 * code / ao_full_scale(bits)


def ramp_toward(actual: int, target: int, bits_per_ms: int, ms: int) -> int:
    """0x200A ramp (§6.7): move `bits_per_ms` codes per millisecond; 0 = no ramp (step)."""
    if bits_per_ms == 0:
        return target
    reach = bits_per_ms * ms
    if abs(target - actual) <= reach:
        return target
    return actual + reach if target > actual else actual - reach


# --- module state ----------------------------------------------------------------------------

CODE_POT_SUPPLY = 0x03  # §7.6 CO_E_ALARM_10V: potentiometer supply shorted
CODE_AO_PROTECTION = 0x04  # §7.6 CO_E_ALARM_IO_FAULT: analog output protection


class AnalogInputs:
    """The analog inputs of one module: field values, configuration objects, filters."""

    def __init__(self, mtype: ModuleType) -> None:
        self.mtype = mtype
        self.count = mtype.ai
        self.configurable = mtype.configurable_ai
        # Physical world (kept across module resets).
        ambient = COLD_JUNCTION_DEFAULT_C if mtype.temperature else 0.0
        self.field = [ambient] * self.count  # engineering units of each channel's kind
        self.wired = ["J"] * self.count  # thermocouple actually connected (AI8TC)
        self.cold_junction_c = COLD_JUNCTION_DEFAULT_C
        self.pot_supply_short = False
        self._filters = [InputFilter() for _ in range(self.count)]
        self._seen: tuple[Any, ...] = ()  # the inputs _law was computed from
        self._law: list[tuple[int, int] | None] = [None] * self.count  # (target, coefficient)
        # The channels a step of _active_dt may still move; the others sit at a fixed point
        # of their law for that step length.
        self._active: list[int] = list(range(self.count))
        self._active_dt: int | None = None
        self.still = False  # the last step was skipped as a repeat of a step that moved nothing
        self.reset()

    def reset(self) -> None:
        default = FILTER_DEFAULT_TEMPERATURE if self.mtype.temperature else FILTER_DEFAULT
        self.filter_all = default  # 0x2104
        self.filters = [FILTER_DEFAULT] * self.count  # 0x2106
        self.types = [CONFIGURABLE_DEFAULT] * self.count  # 0x4500
        self.tc_types = [0] * self.count  # 0x200B
        for ch in range(self.count):
            self._filters[ch].settle(self.target(ch))
        self._active_dt = None  # every channel again

    def kind(self, ch: int) -> AiKind:
        if self.configurable:
            return AI_KINDS[CONFIGURABLE_TYPES[self.types[ch]]]
        return AI_KINDS[self.mtype.ai_kind or ""]

    def reading(self, ch: int) -> float:
        """What the module measures in engineering units, before the ADC."""
        kind = self.kind(ch)
        if kind.name == "pot" and self.pot_supply_short:
            return 0.0  # no reference voltage across the potentiometer
        if kind.name == "thermocouple":
            return thermocouple_reading(self.field[ch], self.wired[ch],
                                        THERMOCOUPLE_TYPES[self.tc_types[ch]],
                                        self.cold_junction_c)
        return self.field[ch]

    def target(self, ch: int) -> int:
        return self.kind(ch).raw(self.reading(ch))

    def coeff(self, ch: int) -> int:
        return self.filters[ch] if self.configurable else self.filter_all

    def code(self, ch: int) -> int:
        return self._filters[ch].code

    def set_type(self, ch: int, value: int) -> None:
        if value != self.types[ch]:
            self.types[ch] = value
            self._filters[ch].settle(self.target(ch))  # a new range, not a step to filter
            self._active_dt = None

    def step(self, dt_us: int) -> None:
        # Every value the targets and the filter coefficients are computed from:
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
        # A channel that did not move is at a fixed point of its law for this step length.
        # InputFilter.advance, inline (the same expressions in order): a moving input's
        # channel runs it every millisecond
        moved = []
        for ch in active:
            flt = filters[ch]
            target, coeff = law[ch]  # type: ignore[misc]
            y, rem = flt.y, flt._rem_us
            if coeff >= FILTER_MAX:
                flt.y = float(target)
                if flt.y != y:
                    moved.append(ch)
                continue
            ms, flt._rem_us = divmod(rem + dt_us, US_PER_MS)
            if ms:
                keep = (1.0 - coeff / FILTER_MAX) ** ms
                flt.y = target + (y - target) * keep
            if flt.y != y or flt._rem_us != rem:
                moved.append(ch)
        self._active = moved

    def _relaw(self, inputs: tuple[Any, ...]) -> set[int]:
        """Recompute (target, coefficient) of the channels whose inputs differ from the last
        ones seen; the channels whose law changed. A channel's law depends on its own field
        value, filter, type, thermocouple type and wiring, and on the module-wide values
        (cold junction, pot supply, 0x2104): one field value moving recomputes one channel."""
        seen = self._seen
        redo: set[int] | range
        if not seen or inputs[1:4] != seen[1:4]:
            redo = range(self.count)
            self._seen = tuple(list(v) if isinstance(v, list) else v for v in inputs)
        else:
            redo = set()
            copies = list(seen)
            for i in _PER_CHANNEL:  # field, 0x2106, 0x4500, 0x200B, wired
                now, before = inputs[i], seen[i]
                if now != before:  # whole lists compared first: usually only the field differs
                    redo.update(ch for ch in range(self.count) if now[ch] != before[ch])
                    copies[i] = list(now)
            self._seen = tuple(copies)  # the unchanged lists' copies are equal: kept
        changed = set()
        law = self._law
        for ch in sorted(redo):
            new = (self.target(ch), self.coeff(ch))
            if new != law[ch]:
                law[ch] = new
                changed.add(ch)
        return changed

    def physical_alarms(self) -> set[int]:
        if self.pot_supply_short and any(
                self.kind(ch).name == "pot" for ch in range(self.count)):
            return {CODE_POT_SUPPLY}
        return set()

    def add_objects(self, od: ObjectDictionary, n: int) -> None:
        def put_filter_all(_ch: int, v: Any) -> None:
            self.filter_all = int(v)

        def put_filter(ch: int, v: Any) -> None:
            self.filters[ch] = int(v)

        def put_tc(ch: int, v: Any) -> None:
            self.tc_types[ch] = int(v)

        def put_type(ch: int, v: Any) -> None:
            self.set_type(ch, int(v))

        if self.mtype.thermocouple:
            add_object(od, 0x200B, n, self.count, lambda ch: self.tc_types[ch], put_tc)
        if self.configurable:
            add_object(od, 0x2106, n, self.count, lambda ch: self.filters[ch], put_filter)
            add_object(od, 0x4500, n, self.count, lambda ch: self.types[ch], put_type)
        else:
            default = FILTER_DEFAULT_TEMPERATURE if self.mtype.temperature else FILTER_DEFAULT
            add_object(od, 0x2104, n, 1, lambda _ch: self.filter_all, put_filter_all,
                       default=default)
        add_object(od, 0x6400, n, self.count, self.code)

    def tx_entries(self, n: int) -> list[tuple[int, int, int]]:
        return pdo_entries(0x6400, n, self.count)

    @staticmethod
    def rx_entries(_n: int) -> list[tuple[int, int, int]]:
        return []

    def snapshot(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "ai": [self.code(ch) for ch in range(self.count)],
            "ai_kind": [self.kind(ch).name for ch in range(self.count)],
            "ai_unit": [self.kind(ch).unit for ch in range(self.count)],
        }
        if self.configurable:
            out["ai_type"] = list(self.types)
            out["ai_filter"] = list(self.filters)
        else:
            out["ai_filter"] = self.filter_all
        if self.mtype.thermocouple:
            out["tc_type"] = [THERMOCOUPLE_TYPES[t] for t in self.tc_types]
        return out


class AnalogOutputs:
    """The analog outputs of one module: 0x7400 targets, 0x200A ramps, the DAC codes."""

    def __init__(self, mtype: ModuleType) -> None:
        self.count = mtype.ao
        self.bits = mtype.ao_bits
        self.full = ao_full_scale(mtype.ao_bits)
        self.overload = False  # physical: outputs wired into an overload (kept across resets)
        self._seen_targets: list[int] | None = None  # 0x7400 that _goal was computed from
        self._goal: list[int] = []  # the DAC codes the outputs ramp to
        self.still = False  # the last step changed nothing and would not in a repeat
        self.reset()

    def reset(self) -> None:
        self.targets = [0] * self.count  # 0x7400 as written by the master
        self.ramps = [0] * self.count  # 0x200A
        self.actual = [0] * self.count  # DAC code now
        self._rem_us = 0

    def step(self, dt_us: int, outputs_enabled: bool) -> None:
        ms, rem = divmod(self._rem_us + dt_us, US_PER_MS)
        self.still = rem == self._rem_us  # whole milliseconds: the remainder stays
        self._rem_us = rem
        if not outputs_enabled or self.overload:
            if any(self.actual):
                self.actual = [0] * self.count  # safe state / protection: at once, no ramp
                self.still = False
            return
        if self.targets != self._seen_targets:
            self._seen_targets = list(self.targets)
            self._goal = [min(self.full, max(-self.full, t)) for t in self.targets]  # saturates
        elif self.actual == self._goal:
            return  # on target: a ramp (0x200A is unsigned) has nowhere to go
        self.still = False
        actual = self.actual
        for ch, target in enumerate(self._goal):
            if actual[ch] != target:  # a channel on its target stays there (ramp_toward)
                actual[ch] = ramp_toward(actual[ch], target, self.ramps[ch], ms)

    def physical_alarms(self) -> set[int]:
        return {CODE_AO_PROTECTION} if self.overload else set()

    def add_objects(self, od: ObjectDictionary, n: int) -> None:
        def put_ramp(ch: int, v: Any) -> None:
            self.ramps[ch] = int(v)

        def put_target(ch: int, v: Any) -> None:
            self.targets[ch] = int(v)

        add_object(od, 0x200A, n, self.count, lambda ch: self.ramps[ch], put_ramp)
        add_object(od, 0x7400, n, self.count, lambda ch: self.targets[ch], put_target,
                   plain_store=True)

    def rx_entries(self, n: int) -> list[tuple[int, int, int]]:
        return pdo_entries(0x7400, n, self.count)

    @staticmethod
    def tx_entries(_n: int) -> list[tuple[int, int, int]]:
        return []

    def snapshot(self) -> dict[str, Any]:
        return {"ao": list(self.actual), "ao_target": list(self.targets),
                "ao_volts": [round(ao_volts(c, self.bits), 4) for c in self.actual],
                "ao_ramp": list(self.ramps)}
