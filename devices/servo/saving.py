"""Saving to and loading from flash: when it may run, how long the drive is busy, what is kept.

Seed 004 ch. 2 "Salvataggio su flash" (mode -50 + control word 0x20 or 0x3802 = 0x0011, not in
torque, no Modbus answer for the few seconds of the save), ch. 4 (0x1010:1 = 0x65766173: with
the motor enabled the save completes when it is disabled, "segnali IEN e/o TEN disabilitati":
also with IEN low in torque), ch. 5 (0x2007 = 0x11, "--" on the
display during the save). The FlashStore writes atomically, and only when the save completes:
a power cut in the middle keeps the previous content.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.flash import FlashError
from devices.servo import flashsave
from devices.servo.ds402 import State
from devices.servo.parameters import C9_BY_FIELDBUS, default_parameters
from devices.servo.registers import R, default_registers

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive


class DriveFlash:
    """Mixin of :class:`~devices.servo.drive.ServoDrive`."""

    # ---- flash ------------------------------------------------------------------------------
    def request_save(self: ServoDrive, trigger: str) -> None:
        self._touched = True  # the next step runs in full (stillness.py)
        if self.saving:
            return
        self.save_done = False
        if self.may_save:
            self._start_save(trigger)
        else:
            self.save_pending = trigger
            self.log(f"flash save requested ({trigger}) with the motor enabled: it runs when "
                     "torque goes off or IEN goes low")

    @property
    def may_save(self: ServoDrive) -> bool:
        """Ch. 4: "possibile solo se il motore non è abilitato (segnali IEN e/o TEN
        disabilitati)": out of torque, or in operation with the IEN input low (motion not
        enabled, the axis held). Not during a quick stop or fault reaction: their ramp runs."""
        state = self.state
        return not state.in_torque or (state is State.OPERATION_ENABLED
                                       and not self.wired.get("ien", False))

    def _start_save(self: ServoDrive, trigger: str) -> None:
        self.save_pending = None
        self.save_trigger = trigger
        self._save_blob = flashsave.encode(self.params, self.regs)
        self.saving_until = self._t_us + flashsave.SAVE_DURATION_US
        self.log(f"saving to flash ({trigger})")

    def _update_saving(self: ServoDrive) -> None:
        if self.save_pending and self.may_save:
            self._start_save(self.save_pending)
        if self.saving_until is not None and self._t_us >= self.saving_until:
            self.saving_until = None
            try:
                self.flash.save(self._save_blob)
            except FlashError as exc:
                self.log(f"flash save failed: {exc}")
                self.raise_alarm(9)
                return
            self.save_done = True
            self.log("flash save done")

    def load_from_flash(self: ServoDrive) -> None:
        """Mode -50, R00 bit 6: registers and parameters from flash (the mode stays -50).

        With nothing ever saved the flash holds the first power-up values.
        """
        self._touched = True  # the next step runs in full (stillness.py)
        blob = self.flash.load()
        if blob is None:
            blob = flashsave.encode(*self._first_power_up_values())
        problem = self._load_image(blob, include_mode=False)
        if problem:
            self.log(f"flash load failed: {problem}")
            self.raise_alarm(9)
            return
        self.load_done = True
        self.log("registers and parameters loaded from flash")

    def _first_power_up_values(self: ServoDrive) -> tuple[dict[int, int], dict[int, int]]:
        cfg = self.config
        params = default_parameters({"c7": cfg.node_id, "c9": C9_BY_FIELDBUS[cfg.fieldbus],
                                     **{k.lower(): v for k, v in cfg.parameters.items()}})
        regs = default_registers({int(R.FEED_CONSTANT): cfg.feed_constant, **cfg.registers})
        return params, regs

    def _load_image(self: ServoDrive, blob: bytes | None, include_mode: bool) -> str | None:
        if blob is None:
            return None
        try:
            image = flashsave.decode(blob)
        except flashsave.FlashContentError as exc:
            return str(exc)
        self.params.update(image.parameters)
        for n, value in image.registers.items():
            if include_mode or n != R.MODES_OF_OPERATION:
                self.regs[n] = value
        return None
