"""What the models say, sent to process B from the simulation thread (a mixin of
:class:`~app.ethercat_wire.bridge.WireBridge`).

Frames handed to the models as their clocks fall due, then per slave the AL status / code
and the station alias when they change, the SM3 image a frame would carry (at most every
``INPUTS_PERIOD_US``), emergencies as CoE mailbox messages; for the line, where the frames
stop (``link``) and which slaves on their way stay silent; each slave's ESC error counters.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from app.ethercat_wire import messages as msg
from app.ethercat_wire.wire_slave import WireSlave

if TYPE_CHECKING:
    from app.ethercat_wire.bridge import WireBridge

INPUTS_PERIOD_US = 2_000  # SM3 image refreshed with a frame, at most this often (sim. time)


class ToWire:
    def _relink(self: WireBridge) -> None:
        """Where the frames stop (``link``) and which slaves on their way do not answer
        (``silent``), as the built-in master's line has it: a powered ESC passes frames on
        whatever its application does (``frame_path``), so a silent slave does not cut off
        the slaves behind it."""
        path = getattr(self._master, "frame_path", None)
        reach = path() if path is not None else next(
            (s.position for s in self._slaves if not s.face.reachable(s.model)),
            len(self._slaves))  # a master without the line's physics: the answers decide
        down = reach if reach < len(self._slaves) else None
        if down != self._link_down:
            self._send(msg.LINK, 0, True)
            if down is not None:
                self._send(msg.LINK, down, False)
            self._link_down = down
        silent = frozenset(s.position for s in self._slaves[:reach]
                           if not s.face.reachable(s.model))
        for position in sorted(silent ^ self._silent):
            self._send(msg.SILENT, position, position in silent)
        self._silent = silent

    def _sync_esc_errors(self: WireBridge, s: WireSlave, counted: bool = False) -> None:
        """The model's counters to B when they changed, or when a batch or a write of B's was
        just taken (``counted``: B stops adding the batch on top, applying the write again)."""
        links = getattr(self._master, "links", None)
        if links is None or s.position >= len(links) or not hasattr(links[s.position], "esc"):
            return
        data = links[s.position].esc.registers()
        if data != s.esc_errors or counted:
            s.esc_errors = data
            self._send(msg.ESC_ERRORS, s.position, data, self._esc_seq)

    def _serve(self: WireBridge, s: WireSlave, now_us: int, step_wall: float) -> None:
        handed = s.clock.due(now_us, step_wall)
        for _ in range(handed):
            self._frame(s, now_us)
        for frame in s.face.take_emergencies(s.model):
            self._send(msg.MAILBOX_REPLY, s.position, s.coe.emergency(frame))
            note = getattr(self._master, "external_emergency", None)
            if note is not None:
                note(s.position, frame)
        status = s.face.al_status(s.model)
        if status != s.status:
            s.status = status
            self._send(msg.AL_STATUS, s.position, *status)
        alias = (s.face.power_ups(s.model), s.face.station_alias(s.model))
        if alias != s.alias:  # a start (B starts with the description's)
            s.alias = alias
            self._send(msg.ALIAS, s.position, alias[1])
        if handed and now_us >= s.inputs_due_us:  # the inputs a frame would carry
            s.inputs_due_us = now_us + INPUTS_PERIOD_US
            data = s.face.inputs(s.model)
            if data and data != s.inputs:
                s.inputs = data
                self._send(msg.INPUTS, s.position, data)

    def _frame(self: WireBridge, s: WireSlave, now_us: int) -> None:
        external = getattr(self._master, "external_frame", None)
        if external is not None:
            external(s.position)
        else:
            s.model.exchange_frame(now_us)
