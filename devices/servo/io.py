"""CN2 digital I/O (seed 004 ch. 2 "I/O digitali", repeated in ch. 4), TEN / IEN and the latch.

Bit numbers are those of digital_inputs (R48, 0x60FD) and digital_outputs / digital_out_mask
(R50 / R49, 0x60FE:1 / :2) for ECO2 / ECO4. TEN (torque consent) and IEN (motion consent) are
the hardware enables the examples wire to 24 V; they are not CN2 bits.
"""

from __future__ import annotations

from dataclasses import dataclass

LATCH_FILTER_US = 2_000  # "l'ingresso digitale rimanga alto per almeno 2 ms"


@dataclass(frozen=True)
class Pin:
    name: str
    pin: int | None  # CN2 pin
    bit: int | None  # bit in R48 / R50 / R49
    function: str


INPUTS: dict[str, Pin] = {p.name: p for p in (
    Pin("start", 1, 1, "Start / digital in"),
    Pin("in2", 2, 2, "digital in"),
    Pin("in3", 3, 3, "digital in"),
    Pin("in4", 4, 4, "digital in"),
    Pin("select", 5, 5, "Select / digital in"),
    Pin("in6", 6, 6, "digital in"),
    Pin("in7", 7, 7, "digital in"),
    Pin("neg_limit", 8, 8, "negative limit switch / digital in"),
    Pin("pos_limit", 9, 9, "positive limit switch / digital in"),
    Pin("in11", 10, 11, "digital in"),
    Pin("latch", 11, 0, "position latch / digital in"),
    Pin("home", 14, 10, "home switch / digital in"),
    Pin("ten", None, None, "TEN: torque enable (hardware consent)"),
    Pin("ien", None, None, "IEN: motion enable (hardware consent)"),
)}

# Outputs: pin 12 bit 0 End of Job, pin 13 bit 1, pin 15 bit 3 Near to target, pin 16 bit 2
# Brake. A mask bit at 1 makes the pin a generic output driven by R50; at 0 the pin keeps its
# primary function (docs/servo-drive.md §Outputs).
OUTPUTS: dict[str, Pin] = {p.name: p for p in (
    Pin("end_of_job", 12, 0, "End of Job / digital out"),
    Pin("out1", 13, 1, "digital out"),
    Pin("brake", 16, 2, "Brake / digital out"),
    Pin("near_target", 15, 3, "Near to target / digital out"),
)}

INPUT_NAMES = tuple(INPUTS)


def input_word(levels: dict[str, bool]) -> int:
    """digital_inputs (R48) from the input levels."""
    word = 0
    for name, pin in INPUTS.items():
        if pin.bit is not None and levels.get(name, False):
            word |= 1 << pin.bit
    return word


def output_levels(primary: dict[str, bool], mask: int, outputs: int) -> dict[str, bool]:
    """The level of each output pin: R50's bit where R49 selects it, else its function."""
    levels = {}
    for name, pin in OUTPUTS.items():
        assert pin.bit is not None
        if mask >> pin.bit & 1:
            levels[name] = bool(outputs >> pin.bit & 1)
        else:
            levels[name] = primary.get(name, False)
    return levels


@dataclass
class LatchFilter:
    """Capture the position at a rising edge, keep it only if the input stays high 2 ms."""

    level: bool = False
    rose_at_us: int | None = None
    candidate: int = 0

    def update(self, level: bool, now_us: int, position: int) -> int | None:
        """Feed the input level; return the latched position when a capture is confirmed."""
        if level and not self.level:
            self.rose_at_us, self.candidate = now_us, position
        self.level = level
        if not level:
            self.rose_at_us = None
            return None
        if self.rose_at_us is not None and now_us - self.rose_at_us >= LATCH_FILTER_US:
            self.rose_at_us = None
            return self.candidate
        return None
