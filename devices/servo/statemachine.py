"""The control words and the CiA 402 state machine of the drive, and its alarms.

Both control words (R00 register view, 0x6040 CiA 402 view) end up in one controlword that the
state machine of :mod:`devices.servo.ds402` evaluates. Seed 004 ch. 1 (R00 bits), ch. 2 (the
example sequences 8, 3, 0x43, 0, 0x23), ch. 3 (alarm actions), ch. 4 (enable sequence, reset
through bit 7), ch. 5 (reset by 0x80 on 0x6040), ch. 6 (reset by 0x08 on the control word).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from devices.events import AlarmChanged, StateChanged
from devices.servo import control, ds402
from devices.servo.alarms import Effect
from devices.servo.ds402 import TRANSITIONS, Command, State
from devices.servo.registers import R

if TYPE_CHECKING:
    from devices.servo.drive import ServoDrive

logger = logging.getLogger(__name__)
# Commands that leave torque for a state of statusword bit 0 (Ready to switch on, Switched on)
_SAVE_HOLDS = frozenset({Command.SHUTDOWN, Command.SWITCH_ON})


class DriveStateMachine:
    """Mixin of :class:`~devices.servo.drive.ServoDrive`."""

    # (state, controlword, source, TEN) of the last evaluation that moved nothing: a cache
    _quiet_evaluation: tuple[State, int, str, bool] | None = None

    # ---- control words --------------------------------------------------------------------------
    def _write_control_register(self: ServoDrive, value: int) -> None:
        rising = value & ~self.regs[R.CONTROL_WORD]
        self.regs[R.CONTROL_WORD] = value
        if not value & control.TEN_CMD:
            self.ten_cmd_held_at_reset = False
        self.ien_cmd = bool(value & control.IEN_CMD)
        self.cw_source = "register"
        self._apply_controlword(control.controlword_from_register(value, self.mode))
        if self.mode in control.SAVE_LOAD:  # after the torque bits: 0x20 saves with torque off
            if rising & control.BIT5:
                self.request_save("mode -50, control word bit 5")
            if rising & control.BIT6:
                self.load_from_flash()

    def write_controlword(self: ServoDrive, value: int) -> None:
        """0x6040 from a CiA 402 master (CANopen, CoE, a scenario)."""
        self._touched = True  # the next step runs in full (stillness.py)
        self._require_power()
        self.ien_cmd = True
        self.cw_source = "cia402"
        self.ten_cmd_held_at_reset = False  # DSP 402: after 15 it needs 6, 7, F anyway
        self.regs[R.CONTROL_WORD] = control.register_from_controlword(value, self.mode, True)
        self._apply_controlword(value)

    def _apply_controlword(self: ServoDrive, new: int) -> None:
        old, self.cw = self.cw, new
        rising, falling = new & ~old, old & ~new
        if rising & ds402.CW_FAULT_RESET:
            self._fault_reset()
        if rising & ds402.CW_LATCH_RESET:
            self.latched_flag = False
        self._evaluate()
        self.mode_logic.on_controlword(self, rising, falling)

    def set_point_taken(self: ServoDrive) -> bool:
        """Pos_str returns to 0 by itself (ch. 2); True when it did (register view only)."""
        self._touched = True  # the next step runs in full (stillness.py)
        if self.cw_source != "register" or self.mode not in control.POSITIONER:
            return False
        self.regs[R.CONTROL_WORD] &= ~control.BIT5
        self.cw &= ~ds402.CW_NEW_SET_POINT
        return True

    # ---- CiA 402 state machine ------------------------------------------------------------------
    def _transition(self: ServoDrive, command: Command) -> bool:
        found = TRANSITIONS.get((self.state, command))
        if found is None:
            return False
        self._set_state(*found)
        return True

    def _set_state(self: ServoDrive, new: State, number: int) -> None:
        old, self.state = self.state, new
        if old is new:
            return
        self.emit(StateChanged(self.now_us, self.device_id, from_state=old.label,
                               to_state=new.label))
        logger.debug("%s: %s -> %s (transition %d)", self.device_id, old.label, new.label,
                     number)
        if new is State.OPERATION_ENABLED:
            self.trajectory.hold(self.plant.theta)
            self._was_allowed = False
            self.mode_logic.torque_on(self)
        elif new is State.QUICK_STOP_ACTIVE:
            self.trajectory.stop(self.quick_stop_limits())
        elif new is State.FAULT_REACTION_ACTIVE:
            if self._fault_effect is Effect.RELEASE or not old.in_torque:
                self._transition(Command.FAULT_REACTION_DONE)
            else:
                self.trajectory.stop(self.quick_stop_limits())

    def _evaluate(self: ServoDrive) -> None:
        """Apply the controlword's level command and the hardware consent TEN.

        What it does depends only on (state, controlword, its source, TEN); inputs whose last
        evaluation moved nothing are remembered and not evaluated again (a moving drive
        evaluates every tick, docs/servo-drive.md §Step cost)."""
        if not self.powered:
            return
        ten = self.wired.get("ten", False)  # input_level("ten"): TEN is no switch
        if self.saving:
            # The state holds still while saving, but TEN is the hardware consent: a save
            # started with IEN low (in torque, saving.may_save) loses the torque with it.
            if not ten:
                self._transition(Command.TORQUE_LOST)
            return
        inputs = (self.state, self.cw, self.cw_source, ten)
        if inputs == self._quiet_evaluation:
            return
        moved = False
        if not ten:
            moved = self._transition(Command.TORQUE_LOST)
        command = ds402.decode(self.cw)
        if command is not None:
            moved = self._evaluate_command(command) or moved
        if not moved:
            self._quiet_evaluation = inputs

    def _evaluate_command(self: ServoDrive, command: Command) -> bool:
        """Follow the level command up to four transitions; True when the state moved."""
        moved = False
        for _ in range(4):
            step = command
            if step is Command.ENABLE_OPERATION and self.state is State.SWITCH_ON_DISABLED \
                    and self.cw_source == "register":
                if self.ten_cmd_held_at_reset:
                    break  # every reset in seed 004 drops the enable: no torque by itself
                step = Command.SHUTDOWN  # Ten_cmd goes all the way into torque (2, 3, 4)
            if step is Command.ENABLE_OPERATION and self.state is State.SWITCHED_ON \
                    and not self.input_level("ten"):
                break
            if self.save_pending and self.state is State.OPERATION_ENABLED \
                    and step in _SAVE_HOLDS:
                # Ch. 4: a save asked in torque runs when torque goes off, and "è completo
                # quando il bit 0 di StatusWord vale 1": torque goes off to Switch on disabled
                # (9), where the manual's own sequence saves (0x0002); the command goes on
                # from there once the save is over (_evaluate waits while saving).
                return self._transition(Command.DISABLE_VOLTAGE) or moved
            if not self._transition(step):
                break
            moved = True
        return moved

    # ---- alarms ------------------------------------------------------------------------------
    def raise_alarm(self: ServoDrive, code: int, lasting: bool = False,
                    injected: bool = False) -> None:
        self._touched = True  # also raised from outside (the CoE slave's checks)
        spec = self.alarm_table[code]
        if self.alarms.latch(code, lasting or injected, injected):
            self.emit(AlarmChanged(self.now_us, self.device_id, code=str(code), name=spec.name,
                                   active=True))
            self.log(f"alarm {code} {spec.name}: {spec.description} ({spec.effect.value})")
        if self.state not in (State.FAULT_REACTION_ACTIVE, State.FAULT):
            self._fault_effect = spec.effect
            self.mode_logic.halted(self)
            self._transition(Command.FAULT)

    def _fault_reset(self: ServoDrive) -> None:
        """Every way in (R00 bit 3, 0x6040 bit 7, the panel's pulse) comes here: DSP 402
        resets in Fault only (transition 15). During the fault reaction the alarm stays: a
        reset there used to clear it and the ramp then ended in Fault with no code."""
        if self.state is State.FAULT_REACTION_ACTIVE:
            self.log(f"alarm reset ignored: {self.reset_refusal()}")
        if self.state is not State.FAULT:
            return
        for code in self.alarms.reset(self.alarm_table):
            spec = self.alarm_table[code]
            self.emit(AlarmChanged(self.now_us, self.device_id, code=str(code), name=spec.name,
                                   active=False))
        if self.alarms.latched:
            self.log(f"alarm reset refused: {self.reset_refusal()}")
        else:
            self._transition(Command.FAULT_RESET)
            # The seed resets with the enable off (ch. 2 / ch. 6: 0x08; ch. 4 / ch. 5: 0x80 in
            # the enable sequence): a Ten_cmd held through the reset re-enables nothing
            self.ten_cmd_held_at_reset = self.cw_source == "register" \
                and bool(self.regs[R.CONTROL_WORD] & control.TEN_CMD)

    def reset_refusal(self: ServoDrive) -> str | None:
        """Why an alarm reset now leaves the drive in Fault, None when nothing holds it. In what
        the drive shows ("la condizione di allarme persiste", ch. 5): a cause, never whether it
        was injected (the answer reaches a trainee's page; ``injected`` is the snapshot's)."""
        code = self.alarms.active
        if self.state is State.FAULT_REACTION_ACTIVE:
            return f"alarm {code} still stopping the axis: reset in Fault"
        if self.state is not State.FAULT or not code:
            return None
        if code in self.alarms.causes:
            return f"alarm {code} persists: the cause persists"
        if not self.alarm_table[code].resettable:  # ch. 6: Profinet 30-33
            return f"alarm {code} is not resettable: switch the drive off and on"
        return f"alarm {code} persists"
