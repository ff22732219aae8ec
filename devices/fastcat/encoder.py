"""The AX2 module (seed 000 §2, §6.11-§6.14, §6.26, §6.27, §6.30, §7.6): two encoder inputs.

Each input watches a simulated shaft turning at a speed the operator sets. The shaft angle is an
integer number of 1/65536 pulse steps of the *real* encoder, advanced with an integer rate
and remainder, so every pulse edge and zero mark is found exactly, in order, however many of
them fall in one step (a 6000 rpm shaft at 1 ms steps crosses ~205 pulses per step).

The module only sees pulses and zero marks; it knows a revolution through 0x4000.k, the
pulses/rev it was told. Hence the count alarm (§6.13: exactly 0x4000.k pulses between two zero
marks) and the 1.5-turn zero-cycle limit (§7.6) are measured in configured pulses.
"""

from __future__ import annotations

import logging
import random
from collections.abc import Callable
from typing import Any

from devices.fastcat.module_od import add_object, pdo_entries
from devices.od import ObjectDictionary

logger = logging.getLogger(__name__)

SUB = 1 << 16  # shaft angle steps per real pulse
US_PER_S = 1_000_000
PPR_DEFAULT = 2048  # §6.11
FAULTS = ("signal_lost", "pulse_noise", "no_zero_mark")
# Chance, per millisecond of motion with "pulse_noise", that the counter gains or loses a pulse.
NOISE_PER_MS = 0.05

# 0x7600 operating parameters (§6.30). §6.30 prints "Bit 1 (0x1)": the mask 0x0001 is what a
# PLC programmer writes, so bit 0 it is (docs). Two inversions of one encoder cancel (XOR).
COMMAND_INDEX = 0x7600  # module N's at 0x7600 + 0x10 * (N - 1) (module_od.object_index)
CMD_INVERT_BOTH = 0x0001
CMD_ZERO_CYCLE = (0x1000, 0x2000)  # bit 12 / 13: zero cycle encoder 1 / 2
CMD_INVERT = (0x4000, 0x8000)  # bit 14 / 15: invert encoder 1 / 2
# 0x6600 operating status (§6.27).
ST_ZERO_DONE = (0x1000, 0x2000)  # bit 12 / 13: zero cycle done encoder 1 / 2
ST_ALARM = 0x8000  # bit 15: alarm active in the module

# Module alarm codes of §7.6, per encoder (index 0 = encoder 1).
CODE_COUNT = (0x10, 0x11)
CODE_SIGNAL = (0x12, 0x13)
CODE_ZERO_CYCLE = (0x14, 0x15)
CODES = (*CODE_COUNT, *CODE_SIGNAL, *CODE_ZERO_CYCLE)

RPM_LIMIT = 60000.0


def wrap32(value: int) -> int:
    """0x6500 is a DINT: the counter rolls over like the module's 32-bit register."""
    return (value + 0x8000_0000) % 0x1_0000_0000 - 0x8000_0000


class EncoderInput:
    """One encoder input: the physical shaft and encoder, and the module's counter for it."""

    def __init__(self, k: int, real_ppr: int) -> None:
        self.k = k  # 0 = encoder 1, 1 = encoder 2
        # Physical world (kept across module resets).
        self.real_ppr = real_ppr
        self.rpm = 0.0
        self.theta = SUB // 2  # half a pulse past a zero mark: no edge sits at the start
        self._rate = 0  # shaft steps per second
        self._rem = 0  # remainder of rate * dt, in steps * us
        self.faults: set[str] = set()
        self.reset()

    def reset(self) -> None:
        """Power-up / CNF: settings at their §6 defaults, counter at 0, no zero cycle."""
        self.ppr_setting = PPR_DEFAULT  # 0x4000.k
        self.home_offset = 0  # 0x4001.k
        self.count_alarm_off = False  # 0x4002.k
        self.disabled = False  # 0x4003.k
        self.position = 0  # 0x6500.k
        self.zero_done = False
        self.armed = False
        self.travel = 0  # pulses counted since the zero cycle was armed
        self.since_mark = 0  # pulses counted since the last zero mark
        self.last_mark_dir = 0  # direction of the last mark crossing; 0 = no reference
        self.raised: list[int] = []

    # --- physical side ---------------------------------------------------------------------
    def set_rpm(self, rpm: float) -> None:
        self.rpm = rpm
        self._rate = round(rpm * self.real_ppr * SUB / 60)

    def set_real_ppr(self, ppr: int) -> None:
        """Another encoder fitted on the same shaft: keep the angle, change the pulse grid."""
        self.theta = self.theta * ppr // self.real_ppr
        self.real_ppr = ppr
        self.set_rpm(self.rpm)

    def set_fault(self, fault: str, active: bool) -> None:
        if active:
            self.faults.add(fault)
        else:
            self.faults.discard(fault)

    @property
    def angle_deg(self) -> float:
        rev = self.real_ppr * SUB
        return 360.0 * (self.theta % rev) / rev

    # --- module side -----------------------------------------------------------------------
    def set_ppr_setting(self, ppr: int) -> None:
        self.ppr_setting = ppr
        self.last_mark_dir = 0  # the mark-to-mark check restarts with the new setting

    def set_disabled(self, off: bool) -> None:
        self.disabled = off
        if off:
            self.armed = False
            self.last_mark_dir = 0

    def arm_zero_cycle(self) -> None:
        if self.disabled:
            return
        self.armed = True
        self.zero_done = False
        self.travel = 0

    @property
    def counting(self) -> bool:
        return not self.disabled and "signal_lost" not in self.faults

    @property
    def turning(self) -> bool:
        return self._rate != 0

    def rest(self) -> bool:
        """A step of a shaft standing still: no pulse, no mark, no noise draw (``step`` with
        a zero rate, without the arithmetic). True when it changed nothing."""
        if self.last_mark_dir and not self.counting:
            self.last_mark_dir = 0
            return False
        return True

    def step(self, dt_us: int, invert: bool, rng: random.Random) -> None:
        old = self.theta
        adv, self._rem = divmod(self._rate * dt_us + self._rem, US_PER_S)
        new = self.theta = old + adv
        if not self.faults and not self.disabled:
            rev = self.real_ppr * SUB
            if old // rev == new // rev:  # counting, no noise, no zero mark crossed
                delta = new // SUB - old // SUB  # what the lines below count
                if delta and not self.armed:  # _count, inline (a turning shaft, every ms)
                    self.position = (self.position + (-delta if invert else delta)
                                     + 0x8000_0000) % 0x1_0000_0000 - 0x8000_0000  # wrap32
                    self.since_mark += delta
                else:
                    self._count(delta, invert)
                return
        if not self.counting:
            self.last_mark_dir = 0  # pulses are being missed: no mark-to-mark check on resume
            return
        direction = (adv > 0) - (adv < 0)
        if "pulse_noise" in self.faults and direction and rng.random() < _noise_chance(dt_us):
            self._count(direction * rng.choice((1, -1)), invert)
        cur = old // SUB
        for mark_pulse, mark_dir in self._marks(old, self.theta):
            self._count(mark_pulse - cur, invert)
            cur = mark_pulse
            self._on_mark(mark_dir)
        self._count(self.theta // SUB - cur, invert)

    def _marks(self, old: int, new: int) -> list[tuple[int, int]]:
        """Zero marks crossed from angle old to new: (pulse index right after it, direction)."""
        if "no_zero_mark" in self.faults:
            return []
        rev = self.real_ppr * SUB
        ka, kb = old // rev, new // rev
        if kb == ka:
            return []  # the usual step: within one revolution
        if kb > ka:
            return [(k * self.real_ppr, 1) for k in range(ka + 1, kb + 1)]
        return [(k * self.real_ppr - 1, -1) for k in range(ka, kb, -1)]

    def _count(self, delta: int, invert: bool) -> None:
        if not delta:
            return
        self.position = wrap32(self.position + (-delta if invert else delta))
        self.since_mark += delta
        if self.armed:
            self.travel += abs(delta)
            if 2 * self.travel > 3 * self.ppr_setting:  # no mark within 1.5 turns (§7.6)
                self.armed = False
                self._raise(CODE_ZERO_CYCLE[self.k])

    def _on_mark(self, direction: int) -> None:
        if self.armed:  # zero cycle: the mark sets the home offset (§6.12)
            self.armed = False
            self.zero_done = True
            self.position = wrap32(self.home_offset)
        if (self.last_mark_dir == direction and not self.count_alarm_off
                and abs(self.since_mark) != self.ppr_setting):
            self._raise(CODE_COUNT[self.k])
        self.last_mark_dir = direction
        self.since_mark = 0

    def _raise(self, code: int) -> None:
        logger.debug("encoder %d raises module alarm 0x%02X", self.k + 1, code)
        self.raised.append(code)

    # --- alarm causes ----------------------------------------------------------------------
    def signal_alarm(self) -> bool:
        return not self.disabled and "signal_lost" in self.faults

    def cause_present(self, code: int) -> bool:
        if self.disabled:
            return False
        if code == CODE_SIGNAL[self.k]:
            return "signal_lost" in self.faults
        if code == CODE_COUNT[self.k]:
            return not self.count_alarm_off and (
                self.real_ppr != self.ppr_setting or "pulse_noise" in self.faults)
        if code == CODE_ZERO_CYCLE[self.k]:
            return "no_zero_mark" in self.faults or 2 * self.real_ppr > 3 * self.ppr_setting
        return False

    def snapshot(self, status: int) -> dict[str, Any]:
        return {"position": self.position, "status": status, "homed": self.zero_done,
                "homing": self.armed, "rpm": self.rpm, "faults": sorted(self.faults),
                "ppr": self.real_ppr, "ppr_setting": self.ppr_setting,
                "disabled": self.disabled, "angle_deg": round(self.angle_deg, 3)}


def _noise_chance(dt_us: int) -> float:
    return min(1.0, NOISE_PER_MS * dt_us / 1000)


class Ax2:
    """The AX2 module's two inputs and its command / status words."""

    def __init__(self, real_ppr: tuple[int, int], in_alarm: Callable[[], bool]) -> None:
        self.inputs = (EncoderInput(0, real_ppr[0]), EncoderInput(1, real_ppr[1]))
        self._in_alarm = in_alarm
        self.command = 0  # 0x7600
        self._seen_command = 0
        self._inverts = (False, False)  # inverted(0), inverted(1) for _seen_command
        self.still = False  # the last step changed nothing and would not in a repeat

    def reset(self) -> None:
        for enc in self.inputs:
            enc.reset()
        self.command = 0
        self._seen_command = 0
        self._inverts = (False, False)

    def inverted(self, k: int) -> bool:
        return bool(self.command & CMD_INVERT_BOTH) != bool(self.command & CMD_INVERT[k])

    @property
    def status(self) -> int:
        word = ST_ALARM if self._in_alarm() else 0
        for enc in self.inputs:
            if enc.zero_done:
                word |= ST_ZERO_DONE[enc.k]
        return word

    def step(self, dt_us: int, rng: random.Random) -> list[int]:
        enc1, enc2 = self.inputs
        command = self.command
        # ``_rate`` is what ``turning`` reads (read here directly: this runs every step)
        if command == self._seen_command and not enc1._rate and not enc2._rate:
            still1 = enc1.rest()  # the usual case: shafts still, no new command bit
            self.still = enc2.rest() and still1
            return []
        self.still = False
        if command != self._seen_command:  # the inversions follow the command word
            rising = command & ~self._seen_command
            self._seen_command = command
            self._inverts = (self.inverted(0), self.inverted(1))
            for enc in self.inputs:
                if rising & CMD_ZERO_CYCLE[enc.k]:
                    enc.arm_zero_cycle()
        raised: list[int] = []
        for enc in self.inputs:
            if enc._rate:
                enc.step(dt_us, self._inverts[enc.k], rng)
            else:
                enc.rest()  # 0 <= remainder < 1 s: a zero rate moves nothing
            if enc.raised:
                raised += enc.raised
                enc.raised = []
        return raised

    def physical_alarms(self) -> set[int]:
        return {CODE_SIGNAL[e.k] for e in self.inputs if e.signal_alarm()}

    def cause_present(self, code: int) -> bool:
        return any(e.cause_present(code) for e in self.inputs)

    def add_objects(self, od: ObjectDictionary, n: int) -> None:
        def put_ppr(ch: int, v: Any) -> None:
            self.inputs[ch].set_ppr_setting(int(v))

        def put_offset(ch: int, v: Any) -> None:
            self.inputs[ch].home_offset = int(v)

        def put_count_off(ch: int, v: Any) -> None:
            self.inputs[ch].count_alarm_off = bool(v)

        def put_disabled(ch: int, v: Any) -> None:
            self.inputs[ch].set_disabled(bool(v))

        def put_position(ch: int, v: Any) -> None:  # preset (§6.26 rw)
            self.inputs[ch].position = int(v)

        def put_command(_ch: int, v: Any) -> None:
            self.command = int(v)

        add_object(od, 0x4000, n, 2, lambda ch: self.inputs[ch].ppr_setting, put_ppr)
        add_object(od, 0x4001, n, 2, lambda ch: self.inputs[ch].home_offset, put_offset)
        add_object(od, 0x4002, n, 2, lambda ch: int(self.inputs[ch].count_alarm_off),
                   put_count_off)
        add_object(od, 0x4003, n, 2, lambda ch: int(self.inputs[ch].disabled), put_disabled)
        add_object(od, 0x6500, n, 2, lambda ch: self.inputs[ch].position, put_position)
        add_object(od, 0x6600, n, 1, lambda _ch: self.status)
        add_object(od, COMMAND_INDEX, n, 1, lambda _ch: self.command, put_command)

    @staticmethod
    def tx_entries(n: int) -> list[tuple[int, int, int]]:
        return pdo_entries(0x6500, n, 2) + pdo_entries(0x6600, n, 1)

    @staticmethod
    def rx_entries(n: int) -> list[tuple[int, int, int]]:
        return pdo_entries(COMMAND_INDEX, n, 1)

    def snapshot(self) -> list[dict[str, Any]]:
        status = self.status
        return [e.snapshot(status) for e in self.inputs]
