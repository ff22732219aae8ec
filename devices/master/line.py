"""The line as the master sees it: cables, the slaves' power, lost frames, slaves lost and found,
damaged cables and the ESC error counters they move (esc_errors.py).

Cable N feeds line position N (from the master for N = 0, else from slave N-1's OUT port). The
master's frames reach a position when every cable up to it is plugged and every slave before
it is powered (an unpowered slave passes nothing on). The ports' physical links follow the
cables and the neighbours' power (the slaves' LINK LEDs, the FastCAT's 0x13); a link that
goes down counts in the ESC's lost link counter of that port. See docs/ethercat-master.md
"Line faults" and "Damaged cable".
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.ethercat import AlState
from devices.events import CommError
from devices.master.esc_errors import IN, OUT, run_frame
from devices.master.links import Slave, SlaveLink, own_in_link
from devices.master.still import StillCounts

if TYPE_CHECKING:
    import random

    from devices.events import Event

CRC_REPORT_US = 1_000_000  # a damaged cable's lost frames: one log line a second at most


class LineMixin:
    """Line handling of :class:`~devices.master.master.EtherCatMaster`."""

    links: list[SlaveLink]
    _slaves: tuple[Slave, ...]
    _power_names: tuple[str, ...]  # ("powered",) per slave: getattr's arguments in _line
    _power_defaults: tuple[bool, ...]  # (True,) per slave
    cables: list[bool]
    phys_in: list[bool]
    phys_out: list[bool]
    to_lose: int
    damaged: dict[int, float]
    rng: random.Random
    crc_unreported: int
    crc_report_us: int
    lost_frames: int
    network_op: bool
    external: bool
    now_us: int
    device_id: str
    _bursting: bool
    skipped: StillCounts
    _line_cables: list[bool]
    _line_powered: list[bool]
    _line_reach: list[bool]
    _watched: list[AlState | None] | None

    if TYPE_CHECKING:
        def _log(self, link: SlaveLink | None, message: str, **params: object) -> None: ...
        def _event(self, event: Event) -> None: ...
        def _request(self, link: SlaveLink, target: AlState) -> None: ...
        def _position(self, value: int, what: str) -> int: ...

    def cmd_pull_cable(self, cable: int) -> None:
        self.cables[self._position(cable, "cable")] = False
        self._apply_physical_links(self._powered_all())

    def cmd_plug_cable(self, cable: int) -> None:
        self.cables[self._position(cable, "cable")] = True
        self._apply_physical_links(self._powered_all())

    def cmd_power_slave(self, position: int, on: bool) -> None:
        self.links[self._position(position, "position")].slave.set_power(on)
        self._apply_physical_links(self._powered_all())

    def cmd_damage_cable(self, cable: int, percent: int) -> None:
        self.damaged[self._position(cable, "cable")] = percent / 100

    def cmd_repair_cable(self, cable: int) -> None:
        self.damaged.pop(self._position(cable, "cable"), None)
        if self.damaged:
            return
        # The line is healthy: the frames lost since the last report belong to this damage,
        # reported now, not added to the first report of a later one.
        count, self.crc_unreported, self.crc_report_us = self.crc_unreported, 0, 0
        if count:
            self._report_spoiled(count)

    def cmd_clear_esc_errors(self, position: int) -> None:
        esc = self.links[self._position(position, "position")].esc
        esc.write(0x0300, 0x14)  # 0x0300-0x0313: every block, as one write clears them

    def cmd_lose_frames(self, count: int) -> None:
        self.to_lose += count

    def _powered(self, position: int) -> bool:
        return bool(getattr(self.links[position].slave, "powered", True))

    def _connected(self, position: int) -> bool:
        """The master's frames reach this position: every cable up to it plugged, every
        slave before it powered (an unpowered slave does not pass frames on)."""
        return all(self.cables[: position + 1]) and all(
            self._powered(p) for p in range(position))

    def _reach(self, powered: list[bool]) -> list[bool]:
        """:meth:`_connected` for every position at once (one pass, each step)."""
        out, ok = [], True
        for p in range(len(self.links)):
            ok = ok and self.cables[p] and (p == 0 or powered[p - 1])
            out.append(ok)
        return out

    def _line(self, skip: bool) -> list[bool]:
        """Each position's reach, the physical links brought up to date first. With the cables
        and the power as they were last applied, applying them again would set no link (every
        ``phys_in`` / ``phys_out`` already is what they make it) and give the same reach."""
        # The values as the slaves give them (bools all, but == would also take 1 for True):
        # compared only; applied as bools. map() with the getattr builtin makes the same
        # getattr(slave, "powered", True) calls as a list comprehension, without its frame
        # (~0.3 us a step on the default line).
        powered = list(map(getattr, self._slaves, self._power_names, self._power_defaults))
        if skip and powered == self._line_powered and self.cables == self._line_cables:
            self.skipped.line += 1
            return self._line_reach
        self._apply_physical_links([bool(on) for on in powered])
        return self._line_reach

    def _apply_physical_links(self, powered: list[bool]) -> None:
        """Each port's link as the cables and the neighbours' power make it (LINK LEDs); an
        ESC switched on since the last call starts with its counters at 0, whichever action
        switched it (the master's power_slave or the slave's own power)."""
        before = self._line_powered
        if len(before) == len(powered):  # not the first call: the master's start is at 0
            for link, was, now in zip(self.links, before, powered, strict=True):
                if now and not was:
                    link.esc.clear()
        self._line_cables, self._line_powered = list(self.cables), list(powered)
        self._line_reach = self._reach(powered)
        n = len(self.links)
        for p, link in enumerate(self.links):
            want_in = self.cables[p] and (p == 0 or powered[p - 1])
            if want_in != self.phys_in[p]:
                self.phys_in[p] = want_in
                link.slave.set_link(want_in, "in")
                if not want_in and powered[p]:  # an unpowered ESC counts nothing
                    link.esc.lose_link(IN)
            if p + 1 < n:
                want_out = self.cables[p + 1] and powered[p + 1]
                if want_out != self.phys_out[p]:
                    self.phys_out[p] = want_out
                    link.slave.set_link(want_out, "out")
                    if not want_out and powered[p]:
                        link.esc.lose_link(OUT)

    def _powered_all(self) -> list[bool]:
        return [bool(getattr(link.slave, "powered", True)) for link in self.links]

    def _cause(self, position: int) -> str:
        for p in range(position + 1):
            if not self.cables[p]:
                return f"cable {p} pulled"
            if p < position and not self._powered(p):
                return f"the slave at position {p} is off"
            slave = self._slaves[p]
            if p < position and not own_in_link(slave):
                return f"no link on the IN port of the slave at position {p}"
            if p < position and not getattr(slave, "link_out", True) and self.cables[p + 1] \
                    and self._powered(p + 1):  # else the next cable or slave says why
                return f"no link on the OUT port of the slave at position {p}"
        if not self._powered(position):
            return "powered off"
        return "no link on its IN port"

    def _lose_frame(self) -> None:
        """One cycle's frame lost: counted per slave; one event per slave per burst."""
        first = not self._bursting
        burst = self.to_lose
        self.to_lose -= 1
        self.lost_frames += 1
        self._bursting = self.to_lose > 0
        for link in self.links:
            if link.present:
                link.counters.lost_frames += 1
                if first:
                    self._event(CommError(self.now_us, self.device_id,
                                          position=link.position,
                                          address=link.slave.station_address,
                                          reason="lost_frames", count=burst))
        if first:
            self._log(None, "lost_frames", count=burst)

    def _spoiled(self) -> bool:
        """This cycle's frame through the damaged cables, out to the last slave it reaches
        (the one before a slave that is off or whose own IN link is down, or one whose own OUT
        link is down, as :meth:`step` has it) and back: True when it comes back spoiled, lost
        to the master as in :meth:`_lose_frame`."""
        last = -1
        for p, ok in enumerate(self._line_reach):
            slave = self._slaves[p]
            if not (ok and slave.reachable()):
                break
            last = p
            if not getattr(slave, "link_out", True):
                break  # its own OUT cable pulled: the frame turns here
        if last < 0 or not run_frame([link.esc for link in self.links], last, self.damaged,
                                     self.rng):
            return False
        self._lose_spoiled()
        return True

    def _lose_spoiled(self) -> None:
        """A frame a damaged cable spoiled: counted as a lost frame, per slave. It goes on as
        long as the cable stays damaged, so the event and the log line come at the first one
        and then at most once a second, with the frames lost since the last one."""
        self.lost_frames += 1
        self.crc_unreported += 1
        for link in self.links:
            if link.present:
                link.counters.lost_frames += 1
        if self.now_us < self.crc_report_us:
            return
        count, self.crc_unreported = self.crc_unreported, 0
        self.crc_report_us = self.now_us + CRC_REPORT_US
        self._report_spoiled(count)

    def _report_spoiled(self, count: int) -> None:
        """``count`` frames the damaged cables spoiled: one event per slave, one log line."""
        for link in self.links:
            if link.present:
                self._event(CommError(self.now_us, self.device_id, position=link.position,
                                      address=link.slave.station_address,
                                      reason="lost_frames", count=count))
        self._log(None, "lost_frames", count=count)

    def _find(self, link: SlaveLink) -> bool:
        """The slave answers (again); True when it is a recovery after a loss."""
        slave = link.slave
        self._watched = None  # presence and reached_op change: the next watch runs in full
        link.present, link.believed, link.next_try_us = True, slave.al_state, self.now_us
        link.pending, link.identity_ok, link.reached_op = None, None, False
        link.stalled, link.in_link = False, True  # reached: its IN link is up
        if link.diagnosis.startswith("no link"):
            link.diagnosis = ""
        if link.lost_once:  # seed 003 network recovery: communication restarts from INIT
            self._log(link, "found", state=slave.al_state.label)
            if slave.al_state is not AlState.INIT and not self.external:
                self._request(link, AlState.INIT)
        return link.lost_once

    def _unreached(self, link: SlaveLink) -> None:
        """The frames do not reach ``link``'s slave this step (off the healthy path). When
        its own IN link went down since it was last reached or unreached, a cable pulled at
        the slave, not through the master's cables or power (``phys_in`` / ``phys_out`` still
        up): the ESC rule's lost link at both ends of that cable, as :meth:`_apply_physical_links`
        counts a master's pull."""
        p = link.position
        up = own_in_link(link.slave)
        if link.in_link and not up:
            powered = self._line_powered
            if self.phys_in[p] and powered[p]:
                link.esc.lose_link(IN)
            if p > 0 and self.phys_out[p - 1] and powered[p - 1]:
                self.links[p - 1].esc.lose_link(OUT)
        link.in_link = up
        self._lose(link)

    def _lose(self, link: SlaveLink) -> None:
        if not link.present:
            return
        cause = self._cause(link.position)
        link.present, link.believed, link.pending = False, None, None
        link.lost_once, link.reached_op, link.seen = True, False, None
        link.diagnosis = f"no link: {cause}"
        self.network_op, self._watched = False, None
        self._event(CommError(self.now_us, self.device_id, position=link.position,
                              address=link.slave.station_address, reason="link_lost",
                              count=1))
        self._log(link, "lost", cause=cause)
