"""The TRS-CAT's sync manager checks (seed 001 §9.2): the mailbox at INIT -> PREOP ("verifica la
correttezza dell'inizializzazione delle Mailbox") and the process data at PREOP -> SAFEOP
("verifica la correttezza della configurazione dei canali SM per i Process Data").

The rule is devices/sync_managers.py (shared with the CPX-E-EC): SM0 / SM1 as the ESI says,
SM2 / SM3 as long as the PDOs 0x1C12 / 0x1C13 assign. It runs on what a master on the wire
wrote to the SM registers (``configure_sync_managers``; unknown with the built-in master,
which sets them up right) and on faults injected by name (``inject_sm_fault``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from devices import sync_managers as smc
from devices.device import CommandError
from devices.sync_managers import SmSetup
from devices.trscat.diagnostics import check_message
from devices.trscat.pdo import RXPDO_ASSIGN, TXPDO_ASSIGN

if TYPE_CHECKING:
    from devices.od import ObjectDictionary
    from devices.trscat.diagnostics import AppFault, DiagMessage
    from devices.trscat.esm import Esm

SmKey = tuple[str, int]  # (fault name, SM number)


class SmChecksMixin:
    """Sync manager checks of :class:`~devices.trscat.device.TrsCat`."""

    # Provided by TrsCat (declared for type checkers).
    now_us: int
    esm: Esm
    od: ObjectDictionary | None
    sm_setup: tuple[SmSetup, ...] | None
    injected_sm: list[SmKey]

    if TYPE_CHECKING:  # defined by TrsCat / AlarmsMixin
        def report(self, message: DiagMessage, fault: AppFault | None = None,
                   slot: int | None = None) -> None: ...
        def _touch(self) -> None: ...

    def configure_sync_managers(self, setups: Sequence[SmSetup]) -> None:
        """The SM registers a master on the wire wrote (0x0800 + 8 n, SM0 first). The ESC
        keeps them through a power cycle of the model: the wire's ESC is not switched off."""
        self._touch()
        self.sm_setup = tuple(setups)

    def check_mailbox(self) -> int | None:
        return self._sm_check(smc.MAILBOX_SMS)

    def check_sync_managers(self) -> int | None:
        return self._sm_check(smc.PROCESS_DATA_SMS)

    def _sm_check(self, sms: tuple[int, ...]) -> int | None:
        found = smc.injected_fault(self.injected_sm, sms)
        if found is None and self.sm_setup is not None:
            found = smc.check_setup(self.sm_setup, sms, self._pd_bytes)
        if found is None:
            return None
        sm, fault = found
        code = smc.fault_code(sm, fault)
        if self.esm.code != code:  # one message per episode, not per retry of the master
            self.report(check_message(code, f"SM{sm}: invalid {smc.SM_FAULT_WORDS[fault]}",
                                      self.now_us * 1000))
        return code

    def _pd_bytes(self, sm: int) -> int:
        od = self.od
        if od is None:
            return 0
        return smc.assigned_bytes(od.peek, RXPDO_ASSIGN if sm == 2 else TXPDO_ASSIGN)

    def cmd_inject_sm_fault(self, fault: str, sm: int) -> None:
        self._touch()
        if (fault, sm) not in self.injected_sm:
            self.injected_sm.append((fault, sm))

    def cmd_clear_sm_fault(self, fault: str, sm: int) -> None:
        self._touch()
        if (fault, sm) not in self.injected_sm:
            now = ", ".join(f"{n}@SM{s}" for n, s in self.injected_sm) or "none"
            raise CommandError(f"{fault} is not injected on SM{sm} (injected: {now})")
        self.injected_sm.remove((fault, sm))
