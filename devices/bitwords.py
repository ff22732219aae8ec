"""Bit registers in a manual's words: the error register 0x1001 and the 0x10F3:5 flags.

Each device keeps its table where its other codes are (seed 002 Tab. 22 in
``devices.cpx.codes``, DS 301's in ``devices.canopen.emcy``, §9.3.7 in
``devices.trscat.diagnostics``, Tab. 18 / 19 in ``devices.cpx.history``); these classes only
say a value in those words, so the Slave tab, the Objects tab (``OdEntry.explain``) and the
Codes tab read a value the same way.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field


@dataclass(frozen=True)
class BitWords:
    """A register whose set bits each have a name (0x1001): ``names`` by bit mask, ``notes``
    the manual's explanation of a bit where it prints one, ``blank`` what a set bit the table
    leaves out reads as, ``whole`` values the manual names as a whole (seed 000's 0x81)."""

    names: Mapping[int, str]
    notes: Mapping[int, str] = field(default_factory=dict)
    blank: str = "not in the table"
    whole: Mapping[int, str] | None = None

    def _name(self, mask: int, notes: bool) -> str:
        name = self.names[mask]
        return f"{name} ({self.notes[mask]})" if notes and mask in self.notes else name

    def text(self, value: int, notes: bool = False) -> str:
        """``Generic Error, Current`` (``no error`` for 0); with ``notes`` each bit's
        explanation after its name."""
        if self.whole and value in self.whole:
            return self.whole[value]
        if not value:
            return "no error"
        return ", ".join(self._name(1 << bit, notes) if 1 << bit in self.names
                         else f"bit {bit} ({self.blank})"
                         for bit in range(value.bit_length()) if value >> bit & 1)

    def listing(self, notes: bool = False) -> str:
        """Every named bit: ``bit 0 Generic Error; bit 1 Current; ...``."""
        return "; ".join(f"bit {mask.bit_length() - 1} {self._name(mask, notes)}"
                         for mask in sorted(self.names))

    def value_text(self, value: int) -> str:
        """A U8 register as a view shows it: ``0x83 Generic Error, Current, ...``."""
        return f"0x{value:02X} {self.text(value)}"

    def said(self, value: int) -> str:
        """The Objects tab's Value cell (``OdEntry.explain``): ``0x83 = Generic Error, ...``,
        hex as the bits read, as 0x1003:1's words are."""
        return f"0x{value:02X} = {self.text(value)}"


@dataclass(frozen=True)
class FlagWords:
    """A register of switches (0x10F3:5): each known bit means one thing at 1 and another at
    0, ``flags`` by mask as (bit = 1, bit = 0); ``owner`` names the device in the words for a
    set bit it never holds."""

    flags: Mapping[int, tuple[str, str]]
    owner: str

    def text(self, value: int) -> str:
        """``bit 0 = 1: ...; bit 1 = 0: ...``: every known bit, then any other set bit."""
        known = [f"bit {mask.bit_length() - 1} = {int(bool(value & mask))}: "
                 f"{one if value & mask else zero}"
                 for mask, (one, zero) in sorted(self.flags.items())]
        other = [f"bit {bit} = 1: not a bit of the {self.owner}'s 0x10F3:5"
                 for bit in range(value.bit_length())
                 if value >> bit & 1 and 1 << bit not in self.flags]
        return "; ".join(known + other)

    def listing(self) -> str:
        """``bit 0: 1 = ..., 0 = ...; ...``."""
        return "; ".join(f"bit {mask.bit_length() - 1}: 1 = {one}, 0 = {zero}"
                         for mask, (one, zero) in sorted(self.flags.items()))

    def said(self, value: int) -> str:
        """The Objects tab's Value cell (``OdEntry.explain``): ``0x0011 = bit 0 = 1: ...``."""
        return f"0x{value:04X} = {self.text(value)}"
