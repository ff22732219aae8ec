"""The field side of a slot: bidirectional lines with the 4-sample debounce, analog and words.

Seed 001 §3 (16 bidirectional PNP lines, high-side driver, debounce of 4 samples), §4 (input
thresholds 0..10 V = 0, 14..24 V = 1; 0.5 A per output, short-circuit and overload
protection), §6.2 (field supply 18..30 V), §10.3 (8 A on the TRS bus). One sample per local
cycle of the module (devices/trscat/sync.py decides when a local cycle runs).
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


@dataclass
class Debounce:
    """§3: a new input state is taken when it has lasted 4 consecutive samples."""

    value: bool = False
    run: int = 0  # consecutive samples that differ from ``value``

    def sample(self, raw: bool) -> bool:
        if raw == self.value:
            self.run = 0
        else:
            self.run += 1
            if self.run >= DEBOUNCE_SAMPLES:
                self.value, self.run = raw, 0
        return self.value


def logic_level(volts: float, previous: bool) -> bool:
    """§4 thresholds; between 10 and 14 V the level is undefined: the last one is kept."""
    if volts <= INPUT_LOW_MAX_V:
        return False
    if volts >= INPUT_HIGH_MIN_V:
        return True
    return previous


@dataclass
class Line:
    """One bidirectional terminal (§3): the module's high-side driver or the field drives it."""

    external_v: float = 0.0  # what a sensor puts on the terminal when the driver is off
    load_a: float = 0.0  # current the load draws when the driver is on
    command: bool = False  # what the module asks of its driver
    driving: bool = False  # the driver really on (field supply ok, no protection trip)
    tripped: bool = False  # short circuit / overload protection active (§4)
    level: bool = False  # logic level on the terminal now
    debounce: Debounce = field(default_factory=Debounce)

    def drive(self, command: bool, field_v: float) -> None:
        self.command = command
        powered = field_in_range(field_v)
        self.tripped = command and powered and self.load_a > OUTPUT_MAX_A
        self.driving = command and powered and not self.tripped
        volts = field_v if self.driving else self.external_v
        self.level = logic_level(volts, self.level)

    @property
    def current_a(self) -> float:
        return self.load_a if self.driving else 0.0

    def sample(self) -> bool:
        return self.debounce.sample(self.level)


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
    lines: list[Line] = field(default_factory=list)
    analog_in_v: list[float] = field(default_factory=list)
    words_in: list[int] = field(default_factory=list)
    plc: list[int] = field(default_factory=list)
    latched: list[int] = field(default_factory=list)  # the outputs of the last SM2 event
    applied: list[int] = field(default_factory=list)
    inputs: list[int] = field(default_factory=list)

    @classmethod
    def new(cls, kind: ModuleKind) -> SlotIo:
        digital = kind.shape is IoShape.DIGITAL
        return cls(kind, lines=[Line() for _ in range(kind.inputs if digital else 0)],
                   analog_in_v=[0.0] * (kind.inputs if kind.shape is IoShape.ANALOG else 0),
                   words_in=[0] * (kind.inputs if kind.shape is IoShape.WORDS else 0),
                   plc=[0] * kind.outputs, latched=[0] * kind.outputs,
                   applied=[0] * kind.outputs, inputs=[0] * kind.inputs)

    def reset(self) -> None:
        """Power-up (or power-down): process images cleared, debounce restarted. What the
        field does to the terminals (sensor voltages, loads) is not the module's and stays."""
        outs, ins = self.kind.outputs, self.kind.inputs
        self.plc, self.latched, self.applied, self.inputs = [0] * outs, [0] * outs, \
            [0] * outs, [0] * ins
        for line in self.lines:
            line.command = line.driving = line.tripped = False
            line.level = logic_level(line.external_v, False)
            line.debounce = Debounce()

    def cycle(self, outputs: list[int], field_v: float, working: bool) -> None:
        """One local cycle: drive ``outputs``, then sample the inputs.

        ``working`` False (TRS bus down, or the module's own supply fault): the outputs are
        off and the TxPDO image reads 0. The terminals still follow the field.
        """
        self.applied = list(outputs) if working else [0] * self.kind.outputs
        shape = self.kind.shape
        if shape is IoShape.DIGITAL:
            for line, out in zip(self.lines, self.applied, strict=True):
                line.drive(bool(out), field_v)
            sampled = [int(line.sample()) for line in self.lines]
        elif shape is IoShape.ANALOG:
            sampled = [volts_to_counts(v) for v in self.analog_in_v]
        else:
            sampled = list(self.words_in)
        self.inputs = sampled if working else [0] * self.kind.inputs

    def field_current_a(self) -> float:
        return sum(line.current_a for line in self.lines)

    def snapshot(self) -> dict[str, Any]:
        out: dict[str, Any] = {"outputs_plc": list(self.plc), "outputs": list(self.applied),
                               "inputs": list(self.inputs)}
        shape = self.kind.shape
        if shape is IoShape.DIGITAL:
            out["lines"] = [{"level": ln.level, "external_v": ln.external_v, "load_a": ln.load_a,
                             "driving": ln.driving, "tripped": ln.tripped}
                            for ln in self.lines]
        elif shape is IoShape.ANALOG:
            out["analog_in_v"] = list(self.analog_in_v)
            out["analog_out_v"] = [round(counts_to_volts(c), 4) for c in self.applied]
        else:
            out["words_in"] = list(self.words_in)
        return out
