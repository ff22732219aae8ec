"""The field side of a slot: bidirectional lines with the 4-sample debounce, analog and words.

Seed 001 §3 (16 bidirectional PNP lines, high-side driver, debounce of 4 samples), §4 (input
thresholds 0..10 V = 0, 14..24 V = 1; 0.5 A per output, short-circuit and overload
protection), §6.2 (field supply 18..30 V), §10.3 (8 A on the TRS bus). One sample per local
cycle of the module (devices/trscat/sync.py decides when a local cycle runs).

The lines of a slot are bit masks (bit n = line n + 1): a local cycle is a few integer
operations whatever the number of lines, which keeps a rig with several TRS-CATs real time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from devices.trscat.catalog import IoShape, ModuleKind

DEBOUNCE_SAMPLES = 4  # §3: "stabile quando permane nello stato per 4 campioni"
INPUT_LOW_MAX_V = 10.0  # §4: 0 = 0..10 V
INPUT_HIGH_MIN_V = 14.0  # §4: 1 = 14..24 V
OUTPUT_MAX_A = 0.5  # §4 "Max corrente Output: 0.5 A"; above it the protection switches off
FIELD_MIN_V = 18.0  # §6.2 VO Output Power Supply, min
FIELD_MAX_V = 30.0  # §6.2 VO, max
BUS_MAX_A = 8.0  # §10.3: at most 8 A from the +24Vdc along the TRS bus (receiver + expansions)
ANALOG_FULL_SCALE_V = 10.0  # FieldRig: AN-E channels are +-10 V (it has +-12 V rails, §9.3.7)
ANALOG_FULL_SCALE = 0x7FFF


def field_in_range(volts: float) -> bool:
    """§8.4: the +24Vdc LED is off when the supply is absent or out of range (§6.2)."""
    return FIELD_MIN_V <= volts <= FIELD_MAX_V


def logic_level(volts: float, previous: bool) -> bool:
    """§4 thresholds; between 10 and 14 V the level is undefined: the last one is kept."""
    if volts <= INPUT_LOW_MAX_V:
        return False
    if volts >= INPUT_HIGH_MIN_V:
        return True
    return previous


def bits(mask: int, count: int) -> list[int]:
    return [(mask >> i) & 1 for i in range(count)]


def to_mask(values: list[int]) -> int:
    out = 0
    for i, v in enumerate(values):
        if v:
            out |= 1 << i
    return out


@dataclass
class LineBank:
    """The bidirectional terminals of one slot (§3): the module's high-side driver or the
    field (a sensor) drives each of them; the module samples them through the debounce."""

    count: int
    external_v: list[float] = field(default_factory=list)  # what a sensor puts on a line
    load_a: list[float] = field(default_factory=list)  # what a load draws when driven
    ext_high: int = 0  # sensor >= 14 V
    ext_band: int = 0  # sensor in the undefined band: the line keeps its level
    overload: int = 0  # load above 0.5 A: the protection trips if driven (§4)
    driving: int = 0  # driver really on (field supply ok, not tripped)
    tripped: int = 0
    level: int = 0  # logic level on the terminals now
    history: tuple[int, ...] = (0,) * (DEBOUNCE_SAMPLES - 1)  # the previous raw samples
    value: int = 0  # debounced (§3)
    current_a: float = 0.0  # drawn by the driven lines

    def __post_init__(self) -> None:
        self.external_v = self.external_v or [0.0] * self.count
        self.load_a = self.load_a or [0.0] * self.count
        self.full = (1 << self.count) - 1
        self._recompute_field()

    def set_external(self, line: int, volts: float) -> None:
        """A sensor's voltage: the terminal's logic level follows at once (the I/O LED, §8.3),
        local cycle or not; only the sample (§3) waits for one."""
        self.external_v[line] = volts
        self._recompute_field()
        self._settle_level()

    def _settle_level(self) -> None:
        """The level on the terminals: a driven line is high, a free one the sensor's (§4;
        in the undefined band it keeps its level)."""
        free = self.full & ~self.driving
        self.level = self.driving | (free & (self.ext_high | (self.ext_band & self.level)))

    def set_load(self, line: int, amps: float) -> None:
        """What a load draws: the §4 protection is the high-side driver's own, so it acts at
        once, local cycle or not: an output on trips when its load goes above 0.5 A and
        drives again once it is back within (no reset command, §9.3). Unpowered, nothing is
        commanded through (``drive``), so nothing trips."""
        self.load_a[line] = amps
        self._recompute_field()
        self.drive(self.driving | self.tripped, True)
        self.current_a = self._current(self.driving)  # a line that stays driven draws anew

    def _recompute_field(self) -> None:
        high = band = over = 0
        for i, (volts, amps) in enumerate(zip(self.external_v, self.load_a, strict=True)):
            if volts >= INPUT_HIGH_MIN_V:
                high |= 1 << i
            elif volts > INPUT_LOW_MAX_V:
                band |= 1 << i
            if amps > OUTPUT_MAX_A:
                over |= 1 << i
        self.ext_high, self.ext_band, self.overload = high, band, over

    def _current(self, driving: int) -> float:
        return sum(a for i, a in enumerate(self.load_a) if driving >> i & 1)

    def drive(self, command: int, powered: bool) -> None:
        """The outputs ``command`` (mask) with the field supply ``powered`` or not."""
        drv = command & ~self.overload & self.full if powered else 0
        self.tripped = command & self.overload if powered else 0
        if drv != self.driving:
            self.current_a = self._current(drv)
        self.driving = drv
        self._settle_level()

    def sample(self) -> int:
        """§3: a line takes a new state when its last 4 samples all show it."""
        raw = self.level
        seen_high = raw
        seen_any = raw
        for past in self.history:
            seen_high &= past
            seen_any |= past
        self.value = (self.value | seen_high) & ~(self.full & ~seen_any)
        self.history = (*self.history[1:], raw)
        return self.value

    def reset(self) -> None:
        """Power-up: driver off, debounce restarted at 0; the field (sensors, loads) stays."""
        self.driving = self.tripped = self.value = 0
        self.current_a = 0.0
        self.history = (0,) * (DEBOUNCE_SAMPLES - 1)
        self.level = self.ext_high

    def snapshot(self) -> list[dict[str, Any]]:
        return [{"level": bool(self.level >> i & 1), "external_v": self.external_v[i],
                 "load_a": self.load_a[i], "driving": bool(self.driving >> i & 1),
                 "tripped": bool(self.tripped >> i & 1)} for i in range(self.count)]


def volts_to_counts(volts: float) -> int:
    scaled = round(volts / ANALOG_FULL_SCALE_V * ANALOG_FULL_SCALE)
    return max(-ANALOG_FULL_SCALE, min(ANALOG_FULL_SCALE, scaled))


def counts_to_volts(counts: int) -> float:
    return counts * ANALOG_FULL_SCALE_V / ANALOG_FULL_SCALE


@dataclass
class SlotIo:
    """A module on the TRS bus: its field terminals and its two process-data images.

    ``plc`` is the RxPDO image the master writes (0x7nn0), ``latched`` that image as the last
    SM2 event delivered it, ``applied`` what the module drives now, ``inputs`` the TxPDO image
    (0x6nn0) the module last sent over the TRS bus.
    """

    kind: ModuleKind
    lines: LineBank | None = None
    analog_in_v: list[float] = field(default_factory=list)
    words_in: list[int] = field(default_factory=list)
    plc: list[int] = field(default_factory=list)
    latched: list[int] = field(default_factory=list)
    applied: list[int] = field(default_factory=list)
    inputs: list[int] = field(default_factory=list)

    @classmethod
    def new(cls, kind: ModuleKind) -> SlotIo:
        digital = kind.shape is IoShape.DIGITAL
        io = cls(kind, lines=LineBank(kind.inputs) if digital else None,
                 analog_in_v=[0.0] * (kind.inputs if kind.shape is IoShape.ANALOG else 0),
                 words_in=[0] * (kind.inputs if kind.shape is IoShape.WORDS else 0))
        io.reset()
        return io

    def reset(self) -> None:
        """Power-up (or power-down): process images cleared, debounce restarted. What the
        field does to the terminals (sensor voltages, loads) is not the module's and stays."""
        outs, ins = self.kind.outputs, self.kind.inputs
        self.plc, self.latched, self.applied = [0] * outs, [0] * outs, [0] * outs
        self.inputs = [0] * ins
        self._zeros_out, self._zeros_in = [0] * outs, [0] * ins
        self._applied_mask = 0
        self._inputs_mask = 0
        self.still = False  # the last cycle changed nothing (set by cycle)
        # (working, field supply in range) of the last drive: the driver follows a change of
        # either at once, local cycle or not (stepping.py _redrive_on_supply_change).
        self.driven_with = (False, False)
        self.analog_powered = False  # the field supply reaches the output stage (§10.3)
        if self.lines is not None:
            self.lines.reset()

    def cycle(self, outputs: list[int], field_v: float, working: bool) -> bool:
        """One local cycle: drive ``outputs``, then sample the inputs; True when it changed
        anything (``still`` keeps the answer: docs/trscat.md "Still steps").

        ``working`` False (TRS bus down, or the module's own supply fault): the outputs are
        off and the TxPDO image reads 0. The terminals still follow the field.
        """
        changed = self._drive(outputs, field_v, working)
        lines = self.lines
        if lines is not None:
            history, debounced = lines.history, lines.value
            sampled = lines.sample()  # the terminals are sampled (and lit) bus or no bus
            changed = changed or debounced != sampled or history != lines.history
            value = sampled if working else 0
            if value != self._inputs_mask:
                changed = True
                self._inputs_mask = value
                self.inputs = bits(value, lines.count)
        else:
            if not working:
                inputs = self._zeros_in
            elif self.kind.shape is IoShape.ANALOG:
                inputs = [volts_to_counts(v) for v in self.analog_in_v]
            else:
                inputs = list(self.words_in)
            if inputs != self.inputs:  # by value: the image is only ever read, never mutated
                changed = True
                self.inputs = inputs
        self.still = not changed
        return changed

    def apply_outputs(self, outputs: list[int], field_v: float, working: bool) -> bool:
        """Drive ``outputs`` now, outside a local cycle: what a state change or a TRS bus
        shutdown does to the terminals (seed 001 §9.2: the safe state is the state's, not the
        next SYNC0's; §9.3.7: a module the bus no longer services stops), and a driver that
        lost or regained its field supply (§10.3). No sample is taken:
        the §3 debounce keeps its count. A working slot's inputs wait for the next local
        cycle; a stopped one's TxPDO image reads 0 from now, as ``cycle`` would give it. True
        when the terminals or an image changed; the slot is then not still.
        """
        changed = self._drive(outputs, field_v, working)
        if not working:
            changed = self._stop_inputs() or changed
        if changed:
            self.still = False
        return changed

    def _stop_inputs(self) -> bool:
        """The TxPDO image of a module not working: 0 (what ``cycle`` sends for it)."""
        if self.lines is not None:
            if not self._inputs_mask:
                return False
            self._inputs_mask = 0
            self.inputs = list(self._zeros_in)
            return True
        if self.inputs == self._zeros_in:
            return False
        self.inputs = self._zeros_in
        return True

    def _drive(self, outputs: list[int], field_v: float, working: bool) -> bool:
        powered = field_in_range(field_v)
        self.driven_with = (working, powered)
        applied = outputs if working else self._zeros_out
        changed = applied != self.applied
        if changed:
            self.applied = list(applied)
            self._applied_mask = to_mask(self.applied)
        lines = self.lines
        if lines is not None:
            driving, tripped, level = lines.driving, lines.tripped, lines.level
            lines.drive(self._applied_mask, powered)
            changed = changed or driving != lines.driving or tripped != lines.tripped \
                or level != lines.level
        elif powered is not self.analog_powered:
            # §10.3: an AN-E's output stage runs on the field supply the TRS bus carries
            self.analog_powered = powered
            changed = changed or self.kind.shape is IoShape.ANALOG
        return changed

    def field_current_a(self) -> float:
        return self.lines.current_a if self.lines is not None else 0.0

    def snapshot(self) -> dict[str, Any]:
        out: dict[str, Any] = {"outputs_plc": list(self.plc), "outputs": list(self.applied),
                               "inputs": list(self.inputs)}
        if self.lines is not None:
            out["lines"] = self.lines.snapshot()
        elif self.kind.shape is IoShape.ANALOG:
            out["analog_in_v"] = list(self.analog_in_v)
            # the terminals: no voltage without the field supply, whatever the image
            out["analog_out_v"] = [round(counts_to_volts(c), 4) if self.analog_powered
                                   else 0.0 for c in self.applied]
        else:
            out["words_in"] = list(self.words_in)
        return out
