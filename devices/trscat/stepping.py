"""How a TRS-CAT step runs, and which parts of it are skipped as repeats (docs/trscat.md
"Still steps").

A step: the power-up detection when due, the local cycles the sync unit releases (seed 001
§9.1.1: one per SYNC0 in DC-SYNC, every 500 us in FREE-RUN; each latches the outputs of an SM2
event taken and runs every slot's I/O with the 4-sample debounce of §3), the sync checks
(§9.1.1 / §9.3.7), the SM watchdog, the alarm causes (§9.3.7) and the LEDs (§8).

Under a master in OP the sync bookkeeping moves every cycle, so a step is never still as a
whole; what repeats is the rest. A step is *quiet* when the last one changed nothing (no slot
changed, no event) and nothing came in since (``_touch``: commands, object writes, AL control,
DC registers and faults, cables, power; the master's frames only feed the sync unit and the
latched image, which are looked at by value). In a quiet step the slot plan (who works, at
which field volts), the alarm causes and every LED input but activity are those of the last
step, so: no slot whose last cycle changed nothing is rerun with the same outputs, no alarm
cause is evaluated, no LED input is rebuilt. ``SKIP_STILL`` = False runs every part.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from devices.ethercat import AlState
from devices.events import Event
from devices.trscat.alarms import TrsBus
from devices.trscat.esm import SM_WATCHDOG
from devices.trscat.indicators import LedInputs, wanted_patterns
from devices.trscat.io import SlotIo, field_in_range
from devices.trscat.sync import SYNC_ERROR_LIMIT, SyncState
from devices.trscat.transitions import SM_WATCHDOG_US, OutputMode

if TYPE_CHECKING:
    from devices.events import EventQueue
    from devices.leds import LedBank
    from devices.trscat.alarms import FaultKey
    from devices.trscat.esm import Esm
    from devices.trscat.sync import SyncUnit

ACTIVITY_WINDOW_US = 50_000  # LINK-ACT flickers while a frame passed this recently
AN_SUPPLY_FAULTS = frozenset({"AN_PLUS_12V", "AN_MINUS_12V"})  # §9.3.7: the module stops
BASE_FIELD_FAULT: FaultKey = ("FIELD_SUPPLY", 0)  # 0x3220 on the base: the +24V LED's check (§8.4)
_LATCHING = (AlState.SAFEOP, AlState.OP)  # the states in which an SM2 event latches outputs
# Enum members as module constants: reading one off its class costs ~0.1 us in CPython 3.11
# (the enum's descriptor), a module global a tenth of that; the steady step reads them.
_DC_RUNNING, _DETECTING = SyncState.DC_RUNNING, TrsBus.DETECTING


class SteppingMixin:
    """The step of :class:`~devices.trscat.device.TrsCat`."""

    # Skip the parts of a step that repeat the last one; the tests switch it off on an
    # instance to compare.
    SKIP_STILL: ClassVar[bool] = True

    # Provided by TrsCat (declared for type checkers).
    now_us: int
    events: EventQueue
    powered: bool
    bus: TrsBus
    detect_done_us: int
    rail: list[SlotIo | None]
    injected: list[FaultKey]
    field_v: float
    esm: Esm
    sync: SyncUnit
    sync_state: SyncState
    out_mode: OutputMode
    error_out: dict[int, list[int]]
    last_sm_event_us: int | None
    last_frame_us: int | None
    deadlocked: bool
    link_in: bool
    link_out: bool
    leds: LedBank
    _led_inputs: LedInputs | None

    if TYPE_CHECKING:  # defined by DeviceModel / TrsCat and the other mixins
        def _finish_detection(self) -> None: ...
        def _check_sync(self) -> None: ...
        def check_outputs(self) -> int | None: ...
        def _fall_on_comm_error(self, code: int) -> None: ...
        def _evaluate_alarms(self) -> None: ...
        def _sync_event(self) -> SyncState: ...
        def serviced(self, slot: int) -> bool: ...
        def slot_fault(self, slot: int, names: frozenset[str]) -> bool: ...

    def _still_state(self) -> None:
        # _dirty: something came in from outside or an event was emitted since the last step
        # began; _quiet: the last step ended with nothing changed; _plan: each slot's
        # (slot, io, working, field volts) of the last local cycle, kept while quiet.
        self._dirty, self._quiet = True, False
        self._plan: list[tuple[int, SlotIo, bool, float]] | None = None
        # _all_still: the last run of the slot loop left every slot still; _latched_moved: a
        # latched image changed since (an SM2 event with new outputs).
        self._all_still, self._latched_moved = False, True
        self.skipped_slot_cycles = 0  # for the tests: local cycles of a slot not rerun
        # _plc_written: a plc image was written since the last _latch_outputs. Only writes,
        # a latch and power-up / plugging (both give plc == latched) move either image, so
        # without one every latched image equals its plc image and a latch copies nothing.
        self._plc_written = False

    def apply(self, action: str, args: Mapping[str, Any], module: int | None = None) -> Any:
        self._touch()
        return super().apply(action, args, module)  # type: ignore[misc]

    def emit(self, event: Event) -> None:
        self._dirty = True  # whatever emits an event changed something a step depends on
        self.events.put(event)

    def _touch(self) -> None:
        """Something from outside may change what a step computes (every way in but the
        master's frames, which only feed the sync unit and the latched outputs)."""
        self._dirty = True

    def step(self, now_us: int) -> None:
        # The steady step (docs/trscat.md "Step cost"): a quiet step in SAFE-OP / OP whose one
        # SYNC0 takes the one frame in time, every slot still, no output written, the sync
        # state DC_RUNNING. _step_in_full would then only take its short ways: what they leave
        # is done here, without its calls and lists. Every condition is read before anything
        # is written, so a step that is not steady runs in full from the same state. Some of
        # the conditions follow from others today; each is kept so that this stays exact on
        # its own reading (SKIP_STILL off: never taken).
        sync = self.sync
        if self._quiet and not self._dirty and self.SKIP_STILL and now_us >= self.now_us \
                and self.esm.state in _LATCHING and not self._plc_written \
                and self._all_still and not self._latched_moved and self._plan is not None \
                and sync.without_sync0 < SYNC_ERROR_LIMIT \
                and self.sync_state is _DC_RUNNING \
                and now_us - sync.next_sync0_us <= SM_WATCHDOG_US \
                and self.powered and self.bus is not _DETECTING:
            t = sync.take_one_sync0(now_us)
            if t is not None:
                self.now_us = now_us  # DeviceModel.step: time checked above
                self._dirty = False
                self.last_sm_event_us = t  # the SM2 event latches nothing (_plc_written)
                self.skipped_slot_cycles += len(self._plan)
                last = self.last_frame_us  # _refresh(quiet=True)'s own test, inlined
                activity = last is not None and now_us - last <= ACTIVITY_WINDOW_US
                old = self._led_inputs
                if old is None or old.activity is not activity:
                    self._refresh(True)
                self._quiet = not self._dirty
                return
        self._step_in_full(now_us)

    def _step_in_full(self, now_us: int) -> None:
        super().step(now_us)  # type: ignore[misc]
        if not self.powered:
            return
        if self.bus is TrsBus.DETECTING and now_us >= self.detect_done_us:
            self._finish_detection()
        # Quiet: the last step changed nothing and nothing came in since: the slot plan, the
        # alarm causes and the LED inputs other than activity are as that step left them.
        quiet = self._quiet and not self._dirty and self.SKIP_STILL
        self._dirty = False
        if not quiet:
            self._plan = None
        changed = False
        cycled = False
        esm = self.esm
        for t, sm_event in self.sync.cycles_until(now_us):
            cycled = True
            if sm_event and esm.state in _LATCHING:
                if self._plc_written or not self.SKIP_STILL:
                    self._latch_outputs(t)
                else:  # every latched image is its plc image already (_plc_written)
                    self.last_sm_event_us = t
            if self._plan is not None and self._all_still and not self._latched_moved \
                    and self.SKIP_STILL:  # _local_cycle would skip every slot
                self.skipped_slot_cycles += len(self._plan)
            elif self._local_cycle():
                changed = True
        if not (quiet or cycled) and self._redrive_on_supply_change():
            changed = True
        # _check_sync has nothing to do when the sync state (SyncUnit.state, written out) is
        # the one last seen and not an error: DC_RUNNING or FREE_RUN.
        sync = self.sync
        if sync.running:
            calm = sync.without_sync0 < SYNC_ERROR_LIMIT and sync.sm_missed < SYNC_ERROR_LIMIT \
                and self.sync_state is SyncState.DC_RUNNING
        else:
            calm = self.sync_state is SyncState.FREE_RUN
        if not (calm and self.SKIP_STILL):
            self._check_sync()
        last = self.last_sm_event_us  # check_outputs(), inlined
        if esm.state is AlState.OP and (last is None or now_us - last > SM_WATCHDOG_US):
            self._fall_on_comm_error(SM_WATCHDOG)
        quiet = quiet and not changed and not self._dirty
        if not quiet:
            self._evaluate_alarms()
        self._refresh(quiet)
        self._quiet = not changed and not self._dirty

    def _latch_outputs(self, t_us: int) -> None:
        self._plc_written = False
        for io in self.rail:
            if io is not None and io.latched != io.plc:
                io.latched = list(io.plc)
                self._latched_moved = True
        self.last_sm_event_us = t_us

    def _local_cycle(self) -> bool:
        """Every slot's local cycle; True when one of them changed anything.

        A slot whose last cycle changed nothing (``io.still``) is a fixed point: with the same
        working state, field volts and outputs it would change nothing again, so it is not
        rerun. Working and volts are the plan's, made by the first cycle after the last
        change; the outputs are compared by value (the latched image can change without a
        touch, when a frame written long ago is taken at this SYNC0). When the last run of
        this loop left every slot still, and so with its outputs applied, and no latched image
        moved since, every slot would be skipped: the loop is.
        """
        plan = self._plan
        if plan is None:
            plan = self._plan = self._slot_plan()
            skip = False
        else:
            skip = self.SKIP_STILL
            if skip and self._all_still and not self._latched_moved:
                self.skipped_slot_cycles += len(plan)
                return False
        self._latched_moved = False
        changed = False
        normal = self.out_mode is OutputMode.NORMAL
        for slot, io, working, field_v in plan:
            outputs = io.latched if normal else self._slot_outputs(slot, io)
            if skip and io.still and (not working or outputs == io.applied):
                self.skipped_slot_cycles += 1
                continue
            if io.cycle(outputs, field_v, working):
                changed = True
        self._all_still = not changed  # a slot skipped was still, one run is unless changed
        return changed

    def _slot_plan(self) -> list[tuple[int, SlotIo, bool, float]]:
        """(slot, io, working, field volts) of every module on the rail."""
        plan = []
        for slot, io in enumerate(self.rail):
            if io is None:
                continue
            working = self.serviced(slot) and not self.slot_fault(slot, AN_SUPPLY_FAULTS)
            plan.append((slot, io, working, self._slot_field_v(slot)))
        return plan

    def _apply_output_image(self) -> None:
        """The outputs of ``out_mode`` on the terminals now (transitions.py calls it when the
        mode leaves NORMAL, alarms.py when the TRS bus shuts down and every slot stops):
        firmware puts the safe or error state out at the state change, and a module the bus
        no longer services stops there. The local cycle would only do it at the next SYNC0,
        and in DC-SYNC none comes while SYNC0 is lost or switched off (§9.1.1). A slot changed
        is no longer still, so the next local cycle runs it and no step skips it
        (docs/trscat.md "Still steps")."""
        for slot, io, working, field_v in self._slot_plan():
            if io.apply_outputs(self._slot_outputs(slot, io), field_v, working):
                self._all_still = False

    def _redrive_on_supply_change(self) -> bool:
        """In a step with no local cycle, drive again each slot whose field supply or working
        state changed since its last drive; True when one changed.

        An output driver that loses its supply does not wait for a SYNC0 (§10.3: the +24Vdc
        "viene utilizzata per il driver degli output"), nor does one that gets it back: in
        DC-SYNC with SYNC0 lost or switched off (§9.1.1) no local cycle would ever come. The
        image driven is the one the module holds: in OP its applied outputs (the master's
        newer ones wait for a local cycle, as ever), else the safe or error image of the state
        (what the next local cycle drives). Only a step that is not quiet can find a change:
        the plan's inputs move only through a touch or with an event. No sample is taken."""
        normal = self.out_mode is OutputMode.NORMAL
        changed = False
        for slot, io, working, field_v in self._slot_plan():
            if io.driven_with == (working, field_in_range(field_v)):
                continue
            outputs = io.applied if normal else self._slot_outputs(slot, io)
            if io.apply_outputs(outputs, field_v, working):
                changed = True
        if changed:
            self._all_still = False
        return changed

    def _slot_outputs(self, slot: int, io: SlotIo) -> list[int]:
        if self.out_mode is OutputMode.NORMAL:
            return io.latched
        if self.out_mode is OutputMode.ERROR:
            return self.error_out.get(slot, [0] * io.kind.outputs)
        return [0] * io.kind.outputs

    def _slot_field_v(self, slot: int) -> float:
        """Expansions take the field supply from the TRS bus (§10.3: the base's +24Vdc "di
        norma viene erogata verso il bus TRS, per fornire l'alimentazione alle eventuali
        espansioni"): none where their own 0x3220 is injected, none anywhere with the base's
        (that supply failing, as ``field_supply`` out of range)."""
        injected = self.injected
        if ("FIELD_SUPPLY", slot) in injected or BASE_FIELD_FAULT in injected:
            return 0.0
        return self.field_v

    def field_ok(self) -> bool:
        """The base's check of the field supply, which the +24V LED shows (§4 "Controllo
        software e segnalazione a led", §8.4 off "quando l'alimentazione è assente o fuori dal
        range"): in 18..30 V and no 0x3220 injected on the base (the check failing)."""
        return field_in_range(self.field_v) and BASE_FIELD_FAULT not in self.injected

    def _refresh(self, quiet: bool = False) -> None:
        """The LEDs from their inputs. ``quiet``: nothing but the time moved since the last
        refresh (no touch, no event, no slot changed), so only activity can differ."""
        now = self.now_us
        activity = self.last_frame_us is not None and now - self.last_frame_us <= \
            ACTIVITY_WINDOW_US
        old = self._led_inputs
        if quiet and old is not None and old.activity is activity:
            return
        if self.powered:
            self._sync_event()
        base = self.rail[0]
        assert base is not None and base.lines is not None
        powered, esm, lines = self.powered, self.esm, base.lines
        bus_running, field_ok = self.bus is TrsBus.RUNNING, self.field_ok()
        if old is not None and old.activity is activity and old.powered is powered \
                and old.state is esm.state and old.error is esm.error \
                and old.deadlocked is self.deadlocked and old.link_in is self.link_in \
                and old.link_out is self.link_out and old.bus_running is bus_running \
                and old.field_ok is field_ok and old.io_mask == lines.level \
                and old.io_count == lines.count:
            return  # the same inputs (field by field: building LedInputs costs more)
        inputs = LedInputs(
            powered=powered, state=esm.state, error=esm.error,
            deadlocked=self.deadlocked, link_in=self.link_in, link_out=self.link_out,
            activity=activity, bus_running=bus_running, field_ok=field_ok,
            io_mask=lines.level, io_count=lines.count)
        if inputs != old:  # the patterns are a function of these inputs only
            self._led_inputs = inputs
            self.leds.update(now, wanted_patterns(inputs), self.emit)
