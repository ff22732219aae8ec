"""Rotary switches (Explicit Device ID) and DIL switches (diagnosis mode) of the CPX-E-EC.

Seed 002 §2.1.7, Tab. 5 and Tab. 6. Both take effect only after a restart of the bus node
(§2.1.7: "вступают в действие только после перезапуска шинного узла"): the model keeps what
the switches are set to apart from what the running firmware read at its last start.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from devices.cpx.catalog import BUS_IO_DIAGNOSIS, BUS_PLAIN, BUS_STATUS_BITS, ModuleType

ROTARY_MAX = 0xFFF  # Tab. 5: three hex rotary switches, 1 ... 4095 (1h ... FFFh)
ROTARY_FACTORY = 0  # Tab. 5: factory setting 0


class DiagMode(enum.Enum):
    NONE = "no diagnosis"
    STATUS_BITS = "status bits"
    IO_DIAGNOSIS = "I/O diagnostic interface"
    BOOTLOADER = "OS bootloader"


# Tab. 6: (DIL 1, DIL 2) -> mode; factory setting OFF / OFF.
DIL_MODES: dict[tuple[bool, bool], DiagMode] = {
    (False, False): DiagMode.NONE,
    (False, True): DiagMode.STATUS_BITS,
    (True, False): DiagMode.IO_DIAGNOSIS,
    (True, True): DiagMode.BOOTLOADER,  # recovery after a failed FFT firmware update
}

# The bus module's own process data in each mode (§2.3.1); the bootloader runs no I/O.
BUS_MODULE: dict[DiagMode, ModuleType] = {
    DiagMode.NONE: BUS_PLAIN,
    DiagMode.STATUS_BITS: BUS_STATUS_BITS,
    DiagMode.IO_DIAGNOSIS: BUS_IO_DIAGNOSIS,
    DiagMode.BOOTLOADER: BUS_PLAIN,
}


def check_rotary(value: int) -> int:
    if not 0 <= value <= ROTARY_MAX:
        raise ValueError(f"rotary switches {value}: they read 0 ... {ROTARY_MAX} "
                         f"(0x000 ... 0xFFF, seed 002 Tab. 5)")
    return value


@dataclass(slots=True)  # slots: as devices/esm.py's Esm (every frame reads active_mode)
class Switches:
    """What the switches are set to now (``rotary``, ``dil1``, ``dil2``) and what the firmware
    read at its last start (``active_*``)."""

    rotary: int = ROTARY_FACTORY
    dil1: bool = False
    dil2: bool = False
    active_rotary: int = ROTARY_FACTORY
    active_mode: DiagMode = DiagMode.NONE

    def __post_init__(self) -> None:
        check_rotary(self.rotary)

    @property
    def mode(self) -> DiagMode:
        """The mode the DIL switches are set to (not yet active before a restart)."""
        return DIL_MODES[(self.dil1, self.dil2)]

    def read_at_start(self) -> None:
        self.active_rotary = self.rotary
        self.active_mode = self.mode

    @property
    def explicit_device_id(self) -> int:
        """Tab. 5: 0 = no Explicit Device ID (stored address, the master auto-increments)."""
        return self.active_rotary

    @property
    def pending(self) -> bool:
        """The switches differ from what the firmware runs with (a restart would apply them)."""
        return self.rotary != self.active_rotary or self.mode is not self.active_mode

    def snapshot(self) -> dict[str, object]:
        return {"rotary": self.rotary, "rotary_hex": f"{self.rotary:03X}", "dil1": self.dil1,
                "dil2": self.dil2, "mode": self.mode.value,
                "active_rotary": self.active_rotary, "active_mode": self.active_mode.value,
                "explicit_device_id": self.explicit_device_id, "pending": self.pending}
