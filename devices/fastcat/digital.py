"""Digital channels of DB16, DI16, DO82, DO16 (seed 000 §2, §6.6, §6.24, §6.28, §7.6 0x02).

Channel numbers here are 0-based; objects and actions count from 1 like the seed. DB16
channels are outputs when their group of 4 is set to 1 in 0x2004; an output channel reads
back its own driven state in 0x6000, so a shorted output shows up as a read-back mismatch.
The outputs are recomputed only when one of their inputs differs from the last step's
(docs/performance.md).
"""

from __future__ import annotations

from typing import Any

from devices.fastcat.catalog import ModuleType
from devices.fastcat.module_od import add_object, pdo_entries
from devices.od import ObjectDictionary

CODE_READBACK = 0x02  # §7.6 CO_E_IOFAULT: "Fault rilettura uscite digitali"


class DigitalIo:
    def __init__(self, mtype: ModuleType) -> None:
        self.mtype = mtype
        self.channels = mtype.di + mtype.do + mtype.dio
        self.group_size = mtype.dio_group_size
        self.groups_n = mtype.dio // mtype.dio_group_size if mtype.dio else 0
        # Physical world (kept across module resets).
        self.field = [False] * self.channels  # what the field puts on input terminals
        self.shorted = [False] * self.channels  # output wired into a short
        self._seen_enabled: bool | None = None  # the inputs of the last step: enable flag,
        self._seen: tuple[list[bool], ...] = ()  # groups, command, short
        self.still = False  # the last step changed nothing and found the inputs unchanged
        self.reset()

    def reset(self) -> None:
        self.groups = [False] * self.groups_n  # 0x2004: False = inputs (default, §6.6)
        self.command = [False] * self.channels  # 0x7000
        self.driven = [False] * self.channels  # what the output stage puts on the terminal
        self.readback_fault = False
        self._seen_enabled = None

    def is_input_channel(self, ch: int) -> bool:
        """May the field drive this terminal (an input, or a DB16 channel of any group)?"""
        return ch < self.channels and (self.mtype.di > 0 or self.mtype.dio > 0)

    def is_output_channel(self, ch: int) -> bool:
        """Does this terminal have an output stage (an output, or a DB16 channel)?"""
        return ch < self.channels and (self.mtype.do > 0 or self.mtype.dio > 0)

    def is_output_now(self, ch: int) -> bool:
        if self.mtype.dio:
            return self.groups[ch // self.group_size]
        return self.mtype.do > 0

    def step(self, outputs_enabled: bool) -> None:
        """Outputs follow 0x7000 only while enabled; otherwise the safe state is all off."""
        self.still = outputs_enabled is self._seen_enabled \
            and (self.groups, self.command, self.shorted) == self._seen
        if self.still:
            return  # same inputs, same outputs
        self._seen_enabled = outputs_enabled
        self._seen = (list(self.groups), list(self.command), list(self.shorted))
        fault = False
        for ch in range(self.channels):
            on = outputs_enabled and self.is_output_now(ch) and self.command[ch]
            self.driven[ch] = on and not self.shorted[ch]  # short: the driver folds back
            fault = fault or (on and self.shorted[ch])
        self.readback_fault = fault

    def input_value(self, ch: int) -> bool:
        """0x6000 sub ch+1: the field for an input, the read-back for a DB16 output group."""
        if self.is_output_now(ch):
            return self.driven[ch]
        return self.field[ch]

    def physical_alarms(self) -> set[int]:
        """An output driven on but read back off (§7.6 0x02), as of the last step."""
        return {CODE_READBACK} if self.readback_fault else set()

    # --- object dictionary and PDOs ---------------------------------------------------------
    @property
    def inputs_n(self) -> int:
        return self.mtype.di + self.mtype.dio

    @property
    def outputs_n(self) -> int:
        return self.mtype.do + self.mtype.dio

    def add_objects(self, od: ObjectDictionary, n: int) -> None:
        def put_group(g: int, v: Any) -> None:
            self.groups[g] = bool(v)

        def put_output(ch: int, v: Any) -> None:
            self.command[ch] = bool(v)

        if self.groups_n:
            add_object(od, 0x2004, n, self.groups_n, lambda g: int(self.groups[g]), put_group)
        if self.inputs_n:
            add_object(od, 0x6000, n, self.inputs_n, lambda ch: int(self.input_value(ch)))
        if self.outputs_n:
            add_object(od, 0x7000, n, self.outputs_n, lambda ch: int(self.command[ch]),
                       put_output, plain_store=True)

    def tx_entries(self, n: int) -> list[tuple[int, int, int]]:
        return pdo_entries(0x6000, n, self.inputs_n) if self.inputs_n else []

    def rx_entries(self, n: int) -> list[tuple[int, int, int]]:
        return pdo_entries(0x7000, n, self.outputs_n) if self.outputs_n else []

    def snapshot(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if self.inputs_n:
            out["di"] = [self.input_value(ch) for ch in range(self.channels)]
        if self.outputs_n:
            out["do"] = list(self.driven)
            out["do_command"] = list(self.command)
        if self.groups_n:
            out["groups"] = ["outputs" if g else "inputs" for g in self.groups]
        return out
