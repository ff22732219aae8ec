"""Address assignment of a CPX-E system behind the CPX-E-EC (seed 002 §2.2, §2.3).

The rules of §2.3.1, in the order the code applies them:
- inputs and outputs are counted independently;
- the bus module is module 0: 0 inputs / 0 outputs without diagnosis, status bits, or the I/O
  diagnostic interface (16 inputs + 16 outputs), and its addresses come first;
- module types are addressed separately: analog and technology modules (word-oriented) before
  the digital modules (byte-oriented), as the example of §2.3.2 (Tab. 9) shows;
- within a group, ascending module number (left to right).

The status bits occupy 16 inputs of the address space of which 8 are used (§2.3.1, Tab. 28
note 4): the 64-byte budget counts 2 bytes, while the addresses Tab. 9 prints for them are
the 8 used ones, I0 ... I7, with the next module at I8. FieldRig reproduces Tab. 9 exactly and
counts both bytes against the budget (docs/cpx-e-ec.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from devices.cpx.catalog import (
    MAX_INPUT_BYTES,
    MAX_IO_MODULES,
    MAX_OUTPUT_BYTES,
    ModuleKind,
    ModuleType,
)

GROUP_ORDER = (ModuleKind.BUS, ModuleKind.ANALOG, ModuleKind.DIGITAL)


@dataclass(frozen=True)
class BitRange:
    first: int
    last: int

    @property
    def width(self) -> int:
        return self.last - self.first + 1

    def text(self, prefix: str) -> str:
        return f"{prefix}{self.first} ... {prefix}{self.last}"


@dataclass(frozen=True)
class ModuleAddresses:
    number: int  # CPX module number (0 = bus module)
    name: str
    inputs: BitRange | None
    outputs: BitRange | None

    def row(self) -> dict[str, object]:
        """One row of Tab. 9."""
        return {"module": self.number, "name": self.name,
                "inputs": self.inputs.text("I") if self.inputs else "-",
                "outputs": self.outputs.text("O") if self.outputs else "-"}


def assign_addresses(bus: ModuleType, modules: Sequence[ModuleType]) -> list[ModuleAddresses]:
    """Tab. 9 for the bus module variant ``bus`` and the I/O modules 1..n in line order."""
    numbered = [(0, bus), *enumerate(modules, start=1)]
    inputs: dict[int, BitRange] = {}
    outputs: dict[int, BitRange] = {}
    next_in = next_out = 0
    for kind in GROUP_ORDER:
        for number, mtype in numbered:
            if mtype.kind is not kind:
                continue
            if kind is ModuleKind.DIGITAL:  # byte-oriented: a digital module starts a byte
                next_in, next_out = _round_up(next_in), _round_up(next_out)
            width_in = sum(e.bits for e in mtype.inputs)  # the used inputs get addresses
            width_out = mtype.output_bits
            if kind is ModuleKind.DIGITAL:
                width_in, width_out = _round_up(width_in), _round_up(width_out)
            if width_in:
                inputs[number] = BitRange(next_in, next_in + width_in - 1)
                next_in += width_in
            if width_out:
                outputs[number] = BitRange(next_out, next_out + width_out - 1)
                next_out += width_out
    return [ModuleAddresses(n, m.name, inputs.get(n), outputs.get(n)) for n, m in numbered]


def _round_up(bits: int) -> int:
    return (bits + 7) // 8 * 8


@dataclass(frozen=True)
class AddressSpace:
    """Bytes of the 64 + 64 byte address space a configuration occupies (§2.2)."""

    input_bytes: int
    output_bytes: int

    @classmethod
    def of(cls, bus: ModuleType, modules: Sequence[ModuleType]) -> AddressSpace:
        every = [bus, *modules]
        return cls(sum(m.input_bytes for m in every), sum(m.output_bytes for m in every))

    def snapshot(self) -> dict[str, int]:
        return {"input_bytes": self.input_bytes, "output_bytes": self.output_bytes,
                "max_input_bytes": MAX_INPUT_BYTES, "max_output_bytes": MAX_OUTPUT_BYTES}


def check_configuration(bus: ModuleType, modules: Sequence[ModuleType]) -> AddressSpace:
    """§2.2: at most 10 I/O modules and 64 + 64 bytes, diagnosis included; ValueError if not."""
    if len(modules) > MAX_IO_MODULES:
        raise ValueError(f"{len(modules)} I/O modules: a CPX-E system takes at most "
                         f"{MAX_IO_MODULES} I/O modules + the bus module (seed 002 §2.2)")
    space = AddressSpace.of(bus, modules)
    for what, used, limit in (("input", space.input_bytes, MAX_INPUT_BYTES),
                              ("output", space.output_bytes, MAX_OUTPUT_BYTES)):
        if used > limit:
            raise ValueError(f"{used} {what} bytes with {bus.short}: the CPX-E-EC address "
                             f"space is {limit} {what} bytes, diagnosis included "
                             f"(seed 002 §2.2)")
    return space
