"""CPX-E I/O modules behind the bus module: field signals, process data, physical faults.

A module turns field signals into its input objects (0x60xx) when the bus module samples it,
drives its outputs from the output objects (0x70xx) the PLC wrote, and reports the faults it
sees (short circuit, wire break, undervoltage of U_OUT, a failed module) as causes the bus
module reports (devices/cpx/codes.py CAUSES). Detection follows the physics: an output short
circuit is seen only while the output is switched on and has its load supply U_OUT, a wire
break on an analog input only in the 4-20 mA range. Scaling and thresholds not in seed 002
are FieldRig's (docs/cpx-e-ec.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from devices.cpx.catalog import ModuleKind, ModuleType
from devices.names import did_you_mean
from devices.od import DataType


@dataclass(frozen=True)
class AnalogRange:
    code: int  # value of the 0x20xx "signal range" parameter
    name: str
    low: float
    high: float
    unit: str

    @property
    def bipolar(self) -> bool:
        return self.low < 0

    @property
    def current(self) -> bool:
        return self.unit == "mA"


ANALOG_RANGES: dict[int, AnalogRange] = {r.code: r for r in (
    AnalogRange(1, "0-10V", 0.0, 10.0, "V"),
    AnalogRange(2, "-10-+10V", -10.0, 10.0, "V"),
    AnalogRange(5, "0-20mA", 0.0, 20.0, "mA"),
    AnalogRange(6, "4-20mA", 4.0, 20.0, "mA"),
)}
RANGE_BY_NAME = {r.name.lower(): r for r in ANALOG_RANGES.values()}
DEFAULT_RANGE = 1
FULL_SCALE = 32767  # "signed 15 bit" data format: the nominal range end reads 32767
WIRE_BREAK_BELOW_MA = 2.0  # a 4-20 mA input below this is a broken wire
INT16 = (-0x8000, 0x7FFF)
INT32_SPAN = 1 << 32


@dataclass
class Monitors:
    """Global monitoring switches of 0x2400 (Tab. 27): a fault not monitored is not reported."""

    scs: bool = True  # 0x2400:2 sensor supply short circuit
    sco: bool = True  # 0x2400:3 output short circuit
    v_out: bool = True  # 0x2400:4 U_OUT


@dataclass(frozen=True)
class ModuleFault:
    """A fault a module sees now: which cause, on which channel (None: the whole module)."""

    module: int
    cause: str
    channel: int | None = None
    output: bool = False  # the channel is an output (history channel parameter 0x80 | n)


def _clamp(value: float, low: int, high: int) -> int:
    return max(low, min(high, round(value)))


@dataclass
class CpxModule:
    number: int
    mtype: ModuleType
    ranges: list[int] = field(default_factory=list)
    field_inputs: list[bool] = field(default_factory=list)  # 16DI: the sensors' signals
    analog_in: list[float] = field(default_factory=list)  # 4AI: V or mA at the terminals
    in_values: list[int] = field(default_factory=list)  # 0x60xx, as last sampled
    out_values: list[int] = field(default_factory=list)  # 0x70xx, as the PLC wrote them
    commanded: list[int] = field(default_factory=list)  # what the module tries to drive
    driven: list[int] = field(default_factory=list)  # what the outputs really do
    energised: list[bool] = field(default_factory=list)  # False: switched off (fault, U_OUT)
    failsafe: list[int] = field(default_factory=list)  # 0x21xx
    held: list[int] = field(default_factory=list)  # the outputs when OP was left
    shorted: set[int] = field(default_factory=set)
    sensor_supply_short: bool = False
    wire_broken: set[int] = field(default_factory=set)
    failed: bool = False
    forced: dict[int, int] = field(default_factory=dict)
    count_rate_hz: float = 0.0
    counter: float = 0.0
    latch: int = 0
    control_before: int = 0

    def __post_init__(self) -> None:
        n_in, n_out = len(self.mtype.inputs), len(self.mtype.outputs)
        self.in_values = [0] * n_in
        self.out_values = [0] * n_out
        self.commanded = [0] * n_out
        self.driven = [0] * n_out
        self.energised = [False] * n_out
        self.failsafe = [0] * n_out
        self.held = [0] * n_out
        self.field_inputs = [False] * (self.mtype.channels if self.is_digital_input else 0)
        if self.mtype.analog_ranges:
            self.ranges = self.ranges or [DEFAULT_RANGE] * self.mtype.channels
            # a sensor at rest: 0 V / 0 mA, 4 mA in the 4-20 mA range (no wire break)
            self.analog_in = [max(0.0, ANALOG_RANGES[r].low) for r in self.ranges] \
                if self.mtype.inputs else []

    @classmethod
    def build(cls, number: int, mtype: ModuleType, options: Mapping[str, Any]) -> CpxModule:
        """A module from a rig file entry; ValueError names the option that is wrong."""
        options = dict(options)
        ranges: list[int] = []
        raw = options.pop("ranges", None)
        if raw is not None:
            if not mtype.analog_ranges:
                raise ValueError(f"{mtype.name} has no signal ranges")
            names = [raw] * mtype.channels if isinstance(raw, str) else list(raw)
            if len(names) != mtype.channels:
                raise ValueError(f"ranges: {mtype.name} has {mtype.channels} channels, "
                                 f"got {len(names)} ranges")
            ranges = [_range_code(str(n)) for n in names]
        if options:
            raise ValueError(f"unknown option(s) {', '.join(sorted(options))} for {mtype.name}")
        return cls(number, mtype, ranges=ranges)

    def reset(self, ranges: list[int]) -> None:
        """A start of the terminal: process images, counter and parameters to their defaults;
        the field (signals, shorts, broken wires) stays as it is."""
        n_out = len(self.mtype.outputs)
        self.in_values = [0] * len(self.mtype.inputs)
        self.out_values = [0] * n_out
        self.commanded, self.driven, self.failsafe, self.held = ([0] * n_out for _ in range(4))
        self.energised = [False] * n_out
        self.counter, self.latch, self.control_before = 0.0, 0, 0
        self.ranges = list(ranges)

    @property
    def is_digital_input(self) -> bool:
        return self.mtype.kind is ModuleKind.DIGITAL and bool(self.mtype.inputs)

    @property
    def is_counter(self) -> bool:
        return self.mtype.short == "1CI"

    def channel_range(self, channel: int) -> AnalogRange:
        return ANALOG_RANGES[self.ranges[channel]]

    # ---- field side -----------------------------------------------------------------------
    def step(self, dt_us: int) -> None:
        if self.is_counter and not self.failed and 0 not in self.wire_broken:
            self.counter += self.count_rate_hz * dt_us / 1_000_000

    def sample_reads(self) -> tuple[Any, ...]:
        """Everything :meth:`sample_inputs` reads but the module's type (a full step skips a
        module whose reads and images are as it left them: devices/cpx/stillness.py)."""
        return (self.failed, self.sensor_supply_short, tuple(self.field_inputs),
                tuple(self.analog_in), frozenset(self.wire_broken), tuple(self.ranges),
                tuple(self.forced.items()))

    def sample_inputs(self) -> None:
        """Field signals -> 0x60xx (the bus module samples in SAFEOP and OP, Tab. 11)."""
        if self.is_counter:
            self.in_values = self._counter_inputs()
            return
        for i, entry in enumerate(self.mtype.inputs):
            if self.failed:
                value = 0
            elif entry.dtype is DataType.BOOLEAN:
                value = int(self.field_inputs[i] and not self.sensor_supply_short)
            else:
                value = self._analog_raw(i)
            self.in_values[i] = self.forced.get(i, value) if not self.failed else 0

    def _analog_raw(self, channel: int) -> int:
        if self.sensor_supply_short or channel in self.wire_broken:
            volts = 0.0
        else:
            volts = self.analog_in[channel]
        r = self.channel_range(channel)
        if r.bipolar:
            raw = volts / r.high * FULL_SCALE
        else:
            raw = (volts - r.low) / (r.high - r.low) * FULL_SCALE
        return _clamp(raw, *INT16)

    def _counter_inputs(self) -> list[int]:
        count = int(self.counter) % INT32_SPAN
        signed = count - INT32_SPAN if count >= INT32_SPAN // 2 else count
        counting = self.count_rate_hz != 0 and not self.failed and 0 not in self.wire_broken
        speed = _clamp(self.count_rate_hz if counting else 0, *INT16)
        return [signed, self.latch, speed, int(counting)]

    def output_reads(self, values: Sequence[int], supply_ok: bool) -> tuple[Any, ...]:
        """Everything :meth:`drive_outputs` reads but the type (not for the 1CI, whose
        control bits have edges)."""
        return (tuple(values), supply_ok, self.failed, frozenset(self.shorted),
                tuple(self.forced.items()), tuple(self.ranges))

    def drive_outputs(self, values: Sequence[int], supply_ok: bool) -> None:
        """What the outputs do for the values they are told; a short circuit or a missing
        U_OUT switches the output off."""
        self.commanded = [self.forced.get(i, v) for i, v in enumerate(values)]
        if self.is_counter:
            self._counter_control(self.commanded[0] if self.commanded else 0)
        for i, value in enumerate(self.commanded):
            off = self.failed or not supply_ok or (i in self.shorted and self.short_bites(i))
            self.energised[i] = not off
            self.driven[i] = 0 if off else value

    def held_off(self) -> list[int]:
        """The outputs told to drive (a value other than 0) that the module keeps switched
        off: a short circuit, U_OUT missing or a module failure. The output image still holds
        the PLC's value there (docs/cpx-e-ec.md choice 40)."""
        if self.is_counter:  # the 1CI's outputs are control bits, always taken
            return []
        return [i for i, value in enumerate(self.commanded)
                if value and not self.energised[i]]

    def short_bites(self, channel: int) -> bool:
        """A short circuit draws current only from a driven output in a voltage range."""
        if self.mtype.analog_ranges:
            return not self.channel_range(channel).current
        return bool(self.commanded[channel])

    def _counter_control(self, control: int) -> None:
        rising = control & ~self.control_before
        if rising & 0x0001:  # bit 0: set the counter to 0
            self.counter = 0.0
        if rising & 0x0002:  # bit 1: latch the counter value
            self.latch = self._counter_inputs()[0]
        self.control_before = control

    def output_value(self, channel: int) -> float:
        """Engineering value of an analog output (V or mA); 0 while it is switched off."""
        r = self.channel_range(channel)
        raw = self.driven[channel]
        if not self.energised[channel]:
            return 0.0
        if r.bipolar:
            return raw / FULL_SCALE * r.high
        return r.low + max(0, raw) / FULL_SCALE * (r.high - r.low)

    # ---- diagnosis --------------------------------------------------------------------------
    def fault_reads(self, monitors: Monitors, supply_ok: bool) -> tuple[Any, ...]:
        """Everything :meth:`faults` reads but the type and the module number."""
        return (self.failed, self.sensor_supply_short, monitors.scs, monitors.sco,
                monitors.v_out, supply_ok, frozenset(self.shorted), tuple(self.commanded),
                tuple(self.ranges), frozenset(self.wire_broken), tuple(self.analog_in))

    def faults(self, monitors: Monitors, supply_ok: bool) -> list[ModuleFault]:
        """The causes this module reports now, channel order."""
        n, out = self.number, []
        if self.failed:
            return [ModuleFault(n, "module_failure")]
        if self.sensor_supply_short and monitors.scs:
            out.append(ModuleFault(n, "short_circuit_sensor_supply"))
        # Without U_OUT no output is energised: nothing flows into a short, U_OUT low is
        # all the module sees (docs/cpx-e-ec.md choice 38).
        for ch in sorted(self.shorted):
            if ch < len(self.commanded) and supply_ok and self.short_bites(ch) and \
                    monitors.sco:
                out.append(ModuleFault(n, "short_circuit_outputs", ch, output=True))
        out.extend(self._wire_breaks(supply_ok))
        if self.mtype.has_outputs and not supply_ok and monitors.v_out:
            out.append(ModuleFault(n, "undervoltage_out"))
        return out

    def _wire_breaks(self, supply_ok: bool) -> list[ModuleFault]:
        n, out = self.number, []
        if self.is_counter:
            return [ModuleFault(n, "wire_break", 0)] if 0 in self.wire_broken else []
        if not self.mtype.analog_ranges:
            return out
        for ch in range(self.mtype.channels):
            if not self.wire_watched(ch):
                continue
            if self.mtype.inputs:  # a 4-20 mA loop reads ~0 mA when its wire is broken
                reading = 0.0 if ch in self.wire_broken else self.analog_in[ch]
                if reading < WIRE_BREAK_BELOW_MA:
                    out.append(ModuleFault(n, "wire_break", ch))
            elif ch in self.wire_broken and supply_ok:
                # an open current loop; without U_OUT no current flows in the loop, open or
                # not, and U_OUT low is all the module sees (docs/cpx-e-ec.md choice 38)
                out.append(ModuleFault(n, "wire_break", ch, output=True))
        return out

    def loop_needs_load_supply(self) -> bool:
        """Whether the loops a broken wire opens are driven from U_OUT: the current outputs'
        (an analog output module); the inputs' and the 1CI's are fed from U_EL/SEN."""
        return not self.is_counter and bool(self.mtype.analog_ranges) and not self.mtype.inputs

    def wire_watched(self, channel: int) -> bool:
        """Whether a broken wire on ``channel`` shows: the 1CI's encoder input, a 4-20 mA
        input (its live zero), a current output (an open loop); a voltage or 0-20 mA input
        reads a broken wire as a valid 0, a voltage output drives an open wire unharmed."""
        if self.is_counter:
            return channel == 0
        if not self.mtype.analog_ranges:
            return False
        r = self.channel_range(channel)
        return r.name == "4-20mA" if self.mtype.inputs else r.current

    def snapshot(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "module": self.number, "type": self.mtype.name, "short": self.mtype.short,
            "ident": f"0x{self.mtype.ident:08X}", "inputs": list(self.in_values),
            "outputs": list(self.out_values), "driven": list(self.driven),
            "energised": list(self.energised),
            "shorted": sorted(self.shorted),
            "sensor_supply_short": self.sensor_supply_short,
            "wire_broken": sorted(self.wire_broken), "failed": self.failed,
            "forced": {str(k): v for k, v in sorted(self.forced.items())}}
        if self.is_digital_input:
            out["field_inputs"] = [int(v) for v in self.field_inputs]
        if self.mtype.analog_ranges:
            out["ranges"] = [self.channel_range(c).name for c in range(self.mtype.channels)]
        if self.analog_in:
            out["analog_in"] = list(self.analog_in)
        if self.mtype.analog_ranges and self.mtype.outputs:
            out["analog_out"] = [self.output_value(c) for c in range(self.mtype.channels)]
        if self.is_counter:
            out["count_rate_hz"] = self.count_rate_hz
        return out


def held_off(channels: Sequence[int], diagnosed: Sequence[Mapping[str, object]],
             ) -> list[dict[str, object]]:
    """A module snapshot's "held_off": each output :meth:`CpxModule.held_off` names, with the
    worst cause the bus module diagnoses for it (``diagnosed``: ``Diagnosis.of_module``, worst
    first): the channel's own (a short), else the module's (U_OUT low, module failure). No
    cause when none is diagnosed (Monitor SCO off in 0x2400:3): the channel is off all the
    same, but the device does not say why, and no page may name an injected cause."""
    out: list[dict[str, object]] = []
    for channel in channels:
        causes = [d["cause"] for d in diagnosed if d.get("channel") == channel] + \
            [d["cause"] for d in diagnosed if d.get("channel") is None]
        out.append({"channel": channel, "cause": causes[0]} if causes else {"channel": channel})
    return out


def _range_code(name: str) -> int:
    found = RANGE_BY_NAME.get(name.strip().lower())
    if found is None:
        names = [r.name for r in ANALOG_RANGES.values()]
        raise ValueError(f"unknown signal range {name!r} (known: {', '.join(names)})"
                         f"{did_you_mean(name.strip(), names)}")
    return found.code
