"""The drive's sync manager checks (seed 004 ch. 5 "Transizioni").

I -> P: "Il Master ... configura ... SyncManager per la comunicazione via mailbox" and the
figure's "Slave checks ESC register settings received from the master"; P -> S: "Il Master
configura ... i SyncManager o le FMMU"; a wrong one is "Error Init / Error PreOp / Error SafeOp:
Errori nella configurazione (es sui DC, FMMU, SyncManager etc ..)". The rule is
devices/sync_managers.py (the TRS-CAT's and the CPX-E-EC's): SM0 / SM1 as the ESI says
(0x0016), SM2 / SM3 as long as the PDOs 0x1C12 / 0x1C13 assign (0x001D / 0x001E). It runs on
what a master on the wire wrote (``configure_sync_managers``); the built-in master sets them up
right, so with nothing written there is nothing to refuse.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from devices import sync_managers as smc
from devices.coe import process_image
from devices.sync_managers import SmSetup

if TYPE_CHECKING:
    from devices.coe.esm import Esm
    from devices.servo.drive import ServoDrive



class SmChecks:
    """Sync manager checks of :class:`~devices.coe.drive_slave.DriveEcatSlave`."""

    # Provided by DriveEcatSlave (declared for type checkers).
    drive: ServoDrive
    esm: Esm
    sm_setup: tuple[SmSetup, ...] | None

    if TYPE_CHECKING:
        @property
        def rx_assigned(self) -> list: ...
        @property
        def tx_assigned(self) -> list: ...

    def configure_sync_managers(self, setups: Sequence[SmSetup]) -> None:
        """The SM registers a master on the wire wrote (0x0800 + 8 n, SM0 first). Kept through
        a power cycle of the drive: the wire's ESC keeps them, and a master rewriting the same
        values sends nothing (docs/ethercat-wire.md)."""
        self.sm_setup = tuple(setups)

    def check_mailbox(self) -> int | None:
        return self._sm_check(smc.MAILBOX_SMS)

    def check_sync_managers(self) -> int | None:
        return self._sm_check(smc.PROCESS_DATA_SMS)

    def _sm_check(self, sms: tuple[int, ...]) -> int | None:
        if self.sm_setup is None:
            return None
        found = smc.check_setup(self.sm_setup, sms, self._pd_bytes)
        if found is None:
            return None
        sm, fault = found
        code = smc.fault_code(sm, fault)
        if self.esm.code != code:  # one message per refusal episode, not per retry
            self.drive.log(f"EtherCAT: SM{sm} refused (0x{code:04X}): "
                           f"invalid {smc.SM_FAULT_WORDS[fault]}")
        return code

    def _pd_bytes(self, sm: int) -> int:
        return process_image.size(self.rx_assigned if sm == 2 else self.tx_assigned)
