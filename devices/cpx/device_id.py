"""Explicit Device ID (seed 002 §2.1.7 Tab. 5, §2.1 "Hot Connect") as a master reads it.

The three rotary switches give the bus module its Explicit Device ID, 1 ... 4095; 0 = none
(the master assigns the address). ETG.1000.6 / ETG.1020 "Requesting ID mechanism": a master
writes AL control with bit 5 (ID request); while the bit stays set in its AL control writes
the slave answers AL status bit 5 ("ID loaded") and the ID in the AL status code 0x0134
instead of 0x0000 — not over an error code, not in BOOT (Beckhoff SSC SetALStatus does the
same). Only the wire shows it (``al_status_on_wire``, the face's ``al_status``): the
model's ``al_status`` / ``al_status_code`` stay the ESM's. The ID in force is the one read at
the last start (``Switches.explicit_device_id``); it is also the configured station alias the
wire shows at 0x0012 / SII word 4. A switch at 0 answers "ID loaded" with 0: no Explicit
Device ID; the stored alias (SII word 4) stays then (docs/cpx-e-ec.md choice 35).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.cpx.esm import AL_STATUS_ID_LOADED
from devices.ethercat import AlState

if TYPE_CHECKING:
    from devices.cpx.device import CpxEEc


class DeviceIdMixin:
    """The ID request of :class:`~devices.cpx.device.CpxEEc` and the AL status it answers."""

    id_requested: bool = False  # RAM: a restart forgets it (devices/cpx/device.py)
    # Starts (power-up, restart) so far: each is an ESC power-up, which loads 0x0012 from SII
    # word 4 (the wire's bridge watches it, docs/ethercat-wire.md "Alias").
    power_ups: int = 0

    def request_id(self: CpxEEc, on: bool) -> None:
        """AL control bit 5 of the master's AL control write (every write carries it)."""
        if not self.reachable() or self.has_fault("ac_failure"):
            return  # no application answers AL control (Tab. 12, choice 25)
        if on != self.id_requested:
            self.touch()
            self.id_requested = on

    @property
    def id_loaded(self: CpxEEc) -> bool:
        esm = self.esm
        return self.id_requested and self.application_runs and not esm.error_flag and \
            esm.code == 0 and esm.state is not AlState.BOOT

    @property
    def station_alias(self: CpxEEc) -> int | None:
        """The configured station alias the switches set: the Explicit Device ID in force, or
        None at 0 (Tab. 5 «0 = сохраненный адрес EtherCAT»: the stored alias stays)."""
        return self.switches.explicit_device_id or None

    def al_status_on_wire(self: CpxEEc) -> tuple[int, int]:
        """0x0130 / 0x0134 as a master on the wire reads them: with the ID loaded, bit 0x20 and
        the ID. ``al_status`` / ``al_status_code`` stay the ESM's: the built-in master, which
        never requests the ID, reads them as state and error (its diagnostic, its log)."""
        if self.id_loaded:
            return self.esm.register | AL_STATUS_ID_LOADED, self.switches.explicit_device_id
        return self.esm.register, self.esm.code
