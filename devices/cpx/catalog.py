"""The CPX-E modules FieldRig can put behind a CPX-E-EC, and the bus module's own variants.

Seed 002 names the modules of its addressing example (§2.3.2: CPX-E-16DI, -8DO, -4AI-U-I,
-4AO-U-I), the DC-capable ones (§2.1.4: 16DI, 8DO, 1CI) and the bus module's module code
222/37 "E-EC" (Tab. 28). Process data layouts, module codes and idents of the I/O modules are
not in the seed: FieldRig values, written down in docs/cpx-e-ec.md. A module ident packs the
module code in its top byte and the subcode in the next, so the bus module's 222/37 is
0xDE25xxxx.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from devices.names import did_you_mean
from devices.od import DataType


class ModuleKind(enum.Enum):
    """Decides the address group (§2.3.1: module types are addressed separately)."""

    BUS = "bus"  # module 0: status bits / I/O diagnostic interface (first of all)
    ANALOG = "analog"  # analog and technology modules (word-oriented, before the digital ones)
    DIGITAL = "digital"


@dataclass(frozen=True)
class PdEntry:
    """One process-data object of a module: 0x60xx:n (input) or 0x70xx:n (output)."""

    name: str
    dtype: DataType

    @property
    def bits(self) -> int:
        return 1 if self.dtype is DataType.BOOLEAN else _BITS[self.dtype]


_BITS = {DataType.INTEGER16: 16, DataType.UNSIGNED16: 16, DataType.INTEGER32: 32,
         DataType.UNSIGNED32: 32, DataType.UNSIGNED8: 8}


@dataclass(frozen=True)
class ModuleType:
    name: str  # "CPX-E-16DI"
    short: str  # "16DI", what a rig file may write
    kind: ModuleKind
    module_code: str  # as Tab. 28 prints the bus module's: "222/37"
    ident: int  # the 0xF050 / 0xF030 entry
    inputs: tuple[PdEntry, ...] = ()
    outputs: tuple[PdEntry, ...] = ()
    input_pad_bits: int = 0  # mapped but unused (the status bits' second byte, Tab. 28 note 4)
    dc_capable: bool = False  # §2.1.4
    channels: int = 0  # channels a diagnosis can name
    analog_ranges: bool = False  # per-channel signal range in 0x20xx

    @property
    def input_bits(self) -> int:
        return sum(e.bits for e in self.inputs) + self.input_pad_bits

    @property
    def output_bits(self) -> int:
        return sum(e.bits for e in self.outputs)

    @property
    def input_bytes(self) -> int:
        return (self.input_bits + 7) // 8  # byte-oriented address space (§2.2)

    @property
    def output_bytes(self) -> int:
        return (self.output_bits + 7) // 8

    @property
    def has_outputs(self) -> bool:
        return bool(self.outputs)


def _bits(prefix: str, n: int) -> tuple[PdEntry, ...]:
    return tuple(PdEntry(f"{prefix} {i}", DataType.BOOLEAN) for i in range(n))


def _words(prefix: str, n: int) -> tuple[PdEntry, ...]:
    return tuple(PdEntry(f"{prefix} channel {i}", DataType.INTEGER16) for i in range(n))


IO_MODULES: dict[str, ModuleType] = {m.name: m for m in (
    ModuleType("CPX-E-16DI", "16DI", ModuleKind.DIGITAL, "29", 0x1D00_0010,
               inputs=_bits("Input", 16), dc_capable=True, channels=16),
    ModuleType("CPX-E-8DO", "8DO", ModuleKind.DIGITAL, "31", 0x1F00_0800,
               outputs=_bits("Output", 8), dc_capable=True, channels=8),
    ModuleType("CPX-E-4AI-U-I", "4AI-U-I", ModuleKind.ANALOG, "142/1", 0x8E01_0008,
               inputs=_words("Input", 4), channels=4, analog_ranges=True),
    ModuleType("CPX-E-4AO-U-I", "4AO-U-I", ModuleKind.ANALOG, "142/2", 0x8E02_0800,
               outputs=_words("Output", 4), channels=4, analog_ranges=True),
    ModuleType("CPX-E-1CI", "1CI", ModuleKind.ANALOG, "174/10", 0xAE0A_020C,
               inputs=(PdEntry("Counter value", DataType.INTEGER32),
                       PdEntry("Latch value", DataType.INTEGER32),
                       PdEntry("Speed", DataType.INTEGER16),
                       PdEntry("Status", DataType.UNSIGNED16)),
               outputs=(PdEntry("Control", DataType.UNSIGNED16),), dc_capable=True,
               channels=1),
)}

# The bus module as module 0, one variant per diagnosis mode of the DIL switches (Tab. 6).
# Status bits: 16 inputs of which 8 are used (§2.3.1, Tab. 28 note 4); the I/O diagnostic
# interface: 16 inputs and 16 outputs (§2.3.1, §2.4.3).
BUS_PLAIN = ModuleType("CPX-E-EC", "E-EC", ModuleKind.BUS, "222/37", 0xDE25_0000)
BUS_STATUS_BITS = ModuleType("CPX-E-EC", "E-EC [Status]", ModuleKind.BUS, "222/37",
                             0xDE25_0002, inputs=_bits("Status bit", 8), input_pad_bits=8)
BUS_IO_DIAGNOSIS = ModuleType("CPX-E-EC", "E-EC [STI]", ModuleKind.BUS, "222/37", 0xDE25_0202,
                              inputs=(PdEntry("Diagnostic data", DataType.UNSIGNED16),),
                              outputs=(PdEntry("Diagnostic request", DataType.UNSIGNED16),))

MAX_IO_MODULES = 10  # §2.2: "максимум 10 модулей входов/выходов + шинного модуля"
MAX_INPUT_BYTES = 64  # §2.2: 64 input bytes ...
MAX_OUTPUT_BYTES = 64  # ... and 64 output bytes


def module_type(name: str) -> ModuleType:
    """A catalog entry by full name ("CPX-E-8DO") or short name ("8DO"), any case."""
    wanted = name.strip().upper()
    for mtype in IO_MODULES.values():
        if wanted in (mtype.name.upper(), mtype.short.upper()):
            return mtype
    known = ", ".join(IO_MODULES)
    raise KeyError(f"unknown CPX-E module {name!r} (known: {known})"
                   f"{did_you_mean(name.strip(), IO_MODULES)}")
