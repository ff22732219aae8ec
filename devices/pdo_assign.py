"""A writable PDO assignment object, 0x1C12 or 0x1C13 (ETG.1000.6, CiA 301 as CoE takes it).

Sub 0 = the number of assigned PDOs, subs 1..size = their mapping indices, in image order.
Changed as a mapping is: sub 0 = 0, the entries, then sub 0 = n. Aborts: an entry written
while sub 0 is not 0 0x06010000; a PDO the device does not have 0x06090030; sub 0 past the
entries 0x06090031; sub 0 = n over an empty entry or a PDO twice 0x06090030; outside the
state the device allows 0x08000022. Shared by the drive (seed 004 ch. 5,
devices/coe/assignment.py) and the CPX-E-EC (seed 002 l. 539-541, devices/cpx/assignment.py):
each gives the PDOs it has, its state guard and its number of entries.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field

from devices.od import AbortCode, SdoAbort


def _anytime() -> bool:
    return True


@dataclass
class PdoAssignment:
    index: int  # 0x1C12 / 0x1C13
    allowed: Collection[int]  # the PDOs the device has in this direction
    size: int  # subs 1..size
    may_write: Callable[[], bool] = _anytime  # the device's state guard (PREOP)
    entries: list[int] = field(init=False)
    count: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self.entries = [0] * self.size

    @property
    def assigned(self) -> tuple[int, ...]:
        return tuple(self.entries[:self.count])

    def _check_state(self, sub: int) -> None:
        if not self.may_write():
            raise SdoAbort(AbortCode.CANNOT_STORE_STATE, self.index, sub)

    def set_entry(self, sub: int, value: int) -> None:
        self._check_state(sub)
        if self.count != 0:
            raise SdoAbort(AbortCode.UNSUPPORTED_ACCESS, self.index, sub)
        if value != 0 and value not in self.allowed:
            raise SdoAbort(AbortCode.VALUE_RANGE, self.index, sub)
        self.entries[sub - 1] = value

    def set_count(self, value: int) -> None:
        self._check_state(0)
        if value > self.size:
            raise SdoAbort(AbortCode.VALUE_TOO_HIGH, self.index, 0)
        self.check_sequence(self.entries[:value])
        self.count = value

    def check_sequence(self, chosen: Sequence[int]) -> None:
        """Whether the first n entries make an assignment (sub 0 = n is refused otherwise)."""
        if 0 in chosen or len(set(chosen)) != len(chosen):
            raise SdoAbort(AbortCode.VALUE_RANGE, self.index, 0)

    def assign(self, pdo_indices: Sequence[int]) -> None:
        """The whole sequence at once, as a configuration tool writes it."""
        self.set_count(0)
        for sub, value in enumerate(pdo_indices, start=1):
            self.set_entry(sub, value)
        self.set_count(len(pdo_indices))
