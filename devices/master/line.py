"""The line as the master sees it: cables, the slaves' power, lost frames, slaves lost and found,
damaged cables and the ESC error counters they move (esc_errors.py).

Cable N feeds line position N (from the master for N = 0, else from slave N-1's OUT port). The
master's frames reach a position when every cable up to it is plugged and every slave before
it is powered (an unpowered slave passes nothing on). A cable is plugged when the master's
``cables`` has it so and both its ends are: the slaves' own plugs (``plugs``: IN, OUT; the
TRS-CAT's ``link``, the CPX-E-EC's ``cable``, the FastCAT's and the drive's ``link``), so a
slave's own OUT pulled is the cable after it pulled, its own IN the cable before it. The
ports' physical links follow those cables and the neighbours' power (the slaves' LINK LEDs,
the FastCAT's 0x13); a link that goes down counts in the ESC's lost link counter of the ports
at both ends. See docs/ethercat-master.md
"Line faults" and "Damaged cable".
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.ethercat import AlState
from devices.events import CommError, NetworkRecovery
from devices.master.esc_errors import IN, OUT, run_frame
from devices.master.links import RANK, Slave, SlaveLink
from devices.master.log_styles import silent_run
from devices.master.still import StillCounts

if TYPE_CHECKING:
    import random

    from devices.events import Event

CRC_REPORT_US = 1_000_000  # a damaged cable's lost frames: one log line a second at most
SILENT_CAUSE = "powered and reached by the frames: it does not answer"  # the line has none
LOST, MISSING = "lost", "missing"  # what _unreached found


class LineMixin:
    """Line handling of :class:`~devices.master.master.EtherCatMaster`."""

    links: list[SlaveLink]
    _slaves: tuple[Slave, ...]
    _power_names: tuple[str, ...]  # ("powered",) per slave: getattr's arguments in _line
    _power_defaults: tuple[bool, ...]  # (True,) per slave
    _plug_names: tuple[str, ...]  # ("plugs",) per slave: the slaves' own plugs, as power
    _plug_defaults: tuple[tuple[bool, bool], ...]  # (True, True) per slave
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
    _links_moved: bool
    skipped: StillCounts
    _line_cables: list[bool]
    _line_powered: list[bool]
    _line_plugs: list[tuple[bool, bool]]
    _line_reach: list[bool]
    _watched: list[AlState | None] | None
    link_up: bool

    if TYPE_CHECKING:
        def _log(self, link: SlaveLink | None, message: str, **params: object) -> None: ...
        def _event(self, event: Event) -> None: ...
        def _request(self, link: SlaveLink, target: AlState) -> None: ...
        def _position(self, value: int, what: str) -> int: ...
        def _watch(self, link: SlaveLink, resync: bool = True) -> None: ...

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
        """The master's frames reach this position: every cable up to it plugged (at both
        ends, :meth:`_plugged`), every slave before it powered (an unpowered slave does not
        pass frames on). Read afresh: a slave's own plug may have moved since the last step."""
        return all(self._plugged(self._plugs_all())[: position + 1]) and all(
            self._powered(p) for p in range(position))

    def _plugs_all(self) -> list[tuple[bool, bool]]:
        return list(map(getattr, self._slaves, self._plug_names, self._plug_defaults))

    def _plugged(self, plugs: list[tuple[bool, bool]]) -> list[bool]:
        """Each cable as the line has it: in the master's ``cables`` and plugged at both its
        ends (the IN of the slave it feeds, the OUT of the slave before it)."""
        out, before = [], True  # cable 0 comes from the master
        for cable, (inp, after) in zip(self.cables, plugs, strict=True):
            out.append(bool(cable and inp and before))
            before = after
        return out

    def _reach(self, powered: list[bool], plugged: list[bool]) -> list[bool]:
        """:meth:`_connected` for every position at once (one pass, each step)."""
        out, ok = [], True
        for p in range(len(self.links)):
            ok = ok and plugged[p] and (p == 0 or powered[p - 1])
            out.append(ok)
        return out

    def _line(self, skip: bool) -> list[bool]:
        """Each position's reach, the physical links brought up to date first. With the cables,
        the slaves' own plugs and the power as they were last applied, applying them again
        would set no link (every ``phys_in`` / ``phys_out`` already is what they make it) and
        give the same reach."""
        # The values as the slaves give them (bools all, but == would also take 1 for True):
        # compared only; applied as bools. map() with the getattr builtin makes the same
        # getattr(slave, "powered", True) calls as a list comprehension, without its frame
        # (~0.3 us a step on the default line).
        # The plugs: a slave replaces its tuple only when its own cable action moves it, so
        # the comparison mostly meets the same objects.
        powered = list(map(getattr, self._slaves, self._power_names, self._power_defaults))
        plugs = list(map(getattr, self._slaves, self._plug_names, self._plug_defaults))
        if skip and powered == self._line_powered and plugs == self._line_plugs \
                and self.cables == self._line_cables:
            self.skipped.line += 1
            return self._line_reach
        self._apply_physical_links([bool(on) for on in powered], plugs)
        return self._line_reach

    def _apply_physical_links(self, powered: list[bool],
                              plugs: list[tuple[bool, bool]] | None = None) -> None:
        """Each port's link as the cables (plugged at both ends, :meth:`_plugged`) and the
        neighbours' power make it (LINK LEDs), a change to down counted by the ESCs at both
        ends of the cable, whichever end it was pulled at; an ESC switched on since the last
        call starts with its counters at 0, whichever action switched it (the master's
        power_slave or the slave's own power)."""
        if plugs is None:
            plugs = self._plugs_all()
        before = self._line_powered
        if len(before) == len(powered):  # not the first call: the master's start is at 0
            for link, was, now in zip(self.links, before, powered, strict=True):
                if now and not was:
                    link.esc.clear()
        self._line_cables, self._line_powered = list(self.cables), list(powered)
        self._line_plugs = plugs
        self._links_moved = True
        plugged = self._plugged(plugs)
        self._line_reach = self._reach(powered, plugged)
        n = len(self.links)
        for p, link in enumerate(self.links):
            want_in = plugged[p] and (p == 0 or powered[p - 1])
            if want_in != self.phys_in[p]:
                self.phys_in[p] = want_in
                link.slave.set_link(want_in, "in")
                if not want_in and powered[p]:  # an unpowered ESC counts nothing
                    link.esc.lose_link(IN)
            if p + 1 < n:
                want_out = plugged[p + 1] and powered[p + 1]
                if want_out != self.phys_out[p]:
                    self.phys_out[p] = want_out
                    link.slave.set_link(want_out, "out")
                    if not want_out and powered[p]:
                        link.esc.lose_link(OUT)
        # A lost slave's injected cause follows the line while it stays lost (the instructor
        # may take one cause away and put another): else the Causes row kept the first one.
        # One the frames reach again keeps its cause: the next step finds it, or finds it
        # silent (_line_news).
        for p, link in enumerate(self.links):
            if link.injected_cause and not (self._line_reach[p] and powered[p]):
                link.injected_cause = self._injected_cause(p)

    def _powered_all(self) -> list[bool]:
        return [bool(getattr(link.slave, "powered", True)) for link in self.links]

    def _injected_cause(self, position: int) -> str:
        """Why the frames do not reach ``position``, as the simulator knows it ("cable 2
        pulled"): the instructor's view only (``injected``), never a log line."""
        plugs = self._plugs_all()
        for p in range(position + 1):
            if not self.cables[p]:
                return f"cable {p} pulled"
            if p < position and not self._powered(p):
                return f"the slave at position {p} is off"
            if p < position and not plugs[p][0]:
                return f"no link on the IN port of the slave at position {p}"
            if p < position and not plugs[p][1] and self.cables[p + 1] \
                    and self._powered(p + 1):  # else the next cable or slave says why
                return f"no link on the OUT port of the slave at position {p}"
        if not self._powered(position):
            return "powered off"
        if not plugs[position][0]:
            return "no link on its IN port"
        # On the line and powered: its ESC passes the frames on, its application does not
        # answer (a drive whose c9 did not select EtherCAT at power-up, seed 004 ch. 2).
        return SILENT_CAUSE

    def _first_silent(self, position: int) -> int:
        """The first position of the run of slaves that no longer answer, ``position`` among
        them: what the master knows, from which slaves still answer its frames."""
        first = position
        while first > 0 and not self.links[first - 1].present:
            first -= 1
        return first

    def _last_silent(self, position: int) -> int:
        """The last position of that run: the slaves behind ``position`` that do not answer
        this step (read live: later positions' ``present`` is not this step's yet while the
        step's loop runs). A silent slave's ESC passes the frames on, so one behind the run
        may answer."""
        last, reach, links = position, self._line_reach, self.links
        while last + 1 < len(links):
            q = last + 1
            if reach[q] and links[q].slave.reachable():  # as the step's loop asks (q > 0)
                break
            last = q
        return last

    def _silent_words(self, position: int) -> tuple[int, str]:
        """The run of silent slaves ``position`` is in: its first position and the words
        the master's lines and diagnoses use for it."""
        first = self._first_silent(position)
        return first, silent_run(first, self._last_silent(position), len(self.links))

    def _port_finding(self, first: int) -> str:
        """What the master reads of the link where its frames stop: its own port's link for
        position 0, else the DL status (0x0110) of the last slave that answers, port 1 (OUT);
        "" when that link is up (the slave behind it does not answer)."""
        if first == 0:
            port_up = bool(self._line_reach) and self._line_reach[0] and self._line_powered[0]
            return "" if port_up else "link down on the master port"
        return "" if self.phys_out[first - 1] else \
            f"no link on port 1 (OUT) of position {first - 1}"

    def _lose_frame(self) -> None:
        """One cycle's frame lost (``lose_frames``): counted per slave and reported as the
        master sees it, as a damaged cable's (:meth:`_lose_spoiled`): the first at once, then
        at most once a second, the rest when a frame comes back (:meth:`_end_burst`). Until
        session 19 the first lost frame reported the whole burst ("20 frame(s) lost."), which
        no master knows then."""
        self.to_lose -= 1
        self._bursting = True
        self._lose_spoiled()

    def _end_burst(self) -> None:
        """A frame came back after a ``lose_frames`` burst: the frames lost since the last
        report are reported now (while a cable stays damaged its own reports go on)."""
        self._bursting = False
        count, self.crc_unreported, self.crc_report_us = self.crc_unreported, 0, 0
        if count:
            self._report_spoiled(count)

    def frame_path(self) -> int:
        """How many positions the master's frames pass through, from position 0: each one
        physically reached (every cable up to it plugged at both ends, every slave before it
        powered) and powered. A powered ESC passes frames on whatever its application does: a
        slave that does not answer (a drive whose c9 did not select EtherCAT at power-up, seed
        004 ch. 2) is on the path, and the frames go on to the slaves behind it. The line as
        last applied (a step)."""
        n = 0
        for reached, powered in zip(self._line_reach, self._line_powered, strict=True):
            if not (reached and powered):
                break
            n += 1
        return n

    def _pass_silent(self, slave: Slave) -> None:
        """This cycle's frame crossed ``slave``, powered and on the frames' path, which does not
        answer: its ESC forwards the frame (:meth:`frame_path`), and a slave whose L/A LEDs
        follow that traffic is told so (``frame_passed``: the drive with c9 != 11, whose L/A
        are its ESC's, docs/ethercat-coe.md "LEDs of a drive with c9 != 11"). Silent slaves
        only: the step's loop comes here from its branch for slaves that do not answer, and
        ``external_frame`` for a wire master's frame at one that does not answer."""
        passed = getattr(slave, "frame_passed", None)
        if passed is not None:
            passed(self.now_us)

    def _spoiled(self) -> bool:
        """This cycle's frame through the damaged cables, out to the last slave on its
        physical path (:meth:`frame_path`; answering or not) and back: True when it comes back
        spoiled, lost to the master as in :meth:`_lose_frame`. Until session 16 the frame
        turned back at the first slave that did not answer: a silent drive at position 0
        spared every damaged cable behind it."""
        last = self.frame_path() - 1
        if last < 0 or not run_frame([link.esc for link in self.links], last, self.damaged,
                                     self.rng):
            return False
        self._lose_spoiled()
        return True

    def _lose_spoiled(self, count: int = 1) -> None:
        """``count`` frames lost (a damaged cable's, a wire master's in batches, one of a
        ``lose_frames`` burst): counted as lost frames, per slave. The loss may go on, so the
        event and the log line come at the first one and then at most once a second, with the
        frames lost since the last one."""
        self.lost_frames += count
        self.crc_unreported += count
        for link in self.links:
            if link.present:
                link.counters.lost_frames += count
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
        link.stalled = False
        link.injected_cause = ""
        if link.diagnosis.startswith("no answer"):
            link.diagnosis = ""
        if link.missing:  # reported not found: it comes now (not a recovery: never lost)
            self._log(link, "found_late", state=slave.al_state.label)
        link.missing = False
        if link.lost_once:  # seed 003 network recovery: communication restarts from INIT
            self._log(link, "found", state=slave.al_state.label)
            if slave.al_state is not AlState.INIT and not self.external:
                # The state read (and its AL status code: 0x001B after a watchdog) is the
                # seed's status change before the restart takes the slave to INIT; its OP,
                # if found there, is not the first OP of the restart (no ECAT_Resync).
                self._watch(link, resync=False)
                self._request(link, AlState.INIT)
        return link.lost_once

    def _unreached(self, link: SlaveLink) -> str:
        """``link``'s slave does not answer this step: LOST when the master loses it now,
        MISSING when it reports it not found now, else ""."""
        if link.present:
            return LOST if self._lose(link) else ""
        if link.lost_once or link.missing or not self.link_up:
            return ""
        self._report_missing(link)
        return MISSING

    def _report_missing(self, link: SlaveLink) -> None:
        """A configured slave that has not answered since the master started, reported once
        its port has link (its frames go out: seed 003 waits for link, then sends): as a real
        master's start-up reports the slaves it expected and did not find. What it reads, not
        why (the cause stays the line's)."""
        link.missing = True
        link.injected_cause = self._injected_cause(link.position)  # the instructor's, as lost
        link.diagnosis, silent = self._silent_finding(link.position)
        self._event(CommError(self.now_us, self.device_id, position=link.position,
                              address=link.slave.station_address, reason="not_found",
                              count=1))
        self._log(link, "missing", silent=silent)

    def _lose(self, link: SlaveLink) -> bool:
        """The slave no longer answers: the master logs and diagnoses what it sees (from which
        position on nothing answers, the link where its frames stop); why (a cable, a supply)
        is kept as the injected cause, the instructor's."""
        if not link.present:
            return False
        believed = link.believed
        if believed is not None and RANK.get(believed, 0) >= RANK[AlState.SAFEOP] and \
                not self.external:  # a wire master counts its own (external_stats)
            link.counters.wkc_errors += 1  # its process data stopped answering, as in a drop
        link.present, link.believed, link.pending = False, None, None
        link.lost_once, link.reached_op, link.seen = True, False, None
        link.injected_cause = self._injected_cause(link.position)
        link.diagnosis, silent = self._silent_finding(link.position)
        self.network_op, self._watched = False, None
        self._event(CommError(self.now_us, self.device_id, position=link.position,
                              address=link.slave.station_address, reason="link_lost",
                              count=1))
        self._log(link, "lost", silent=silent)
        return True

    def _silent_finding(self, position: int) -> tuple[str, str]:
        """A lost or missing slave's diagnosis (which slaves do not answer, and the link read
        where the frames stop answering) and the first part alone, for its log line."""
        first, silent = self._silent_words(position)
        finding = self._port_finding(first)
        return silent + (f" ({finding})" if finding else ""), silent

    def _line_news(self, lost_now: list[int], recovered: list[int],
                   missing_now: list[int] | None = None) -> None:
        """The end of a step in which slaves were lost, found or reported not found, or the
        ports' links moved: the master's lines, then every lost or missing slave's diagnosis
        as the line reads now. A slave
        lost in an earlier step keeps no stale finding when the silent run grows towards the
        master or shrinks back, or when the link where the frames stop comes up or goes down
        (tests/devices/master/test_master_observed.py, test_master_port_link.py)."""
        self._links_moved = False
        if lost_now:
            self._report_lost(lost_now)
        if missing_now:
            self._report_lost(missing_now, "missing_line")
        if recovered:
            self._event(NetworkRecovery(self.now_us, self.device_id,
                                        positions=tuple(recovered)))
            self._log(None, "recovery", positions=", ".join(map(str, recovered)))
        for link in self.links:
            if (link.lost_once or link.missing) and not link.present:
                link.diagnosis = self._silent_finding(link.position)[0]
                # Read after the slaves stepped: one the frames reach that still does not
                # answer is silent, not "powered off" as it was when switched on again.
                link.injected_cause = self._injected_cause(link.position)

    def _report_lost(self, positions: list[int], message: str = "lost_line") -> None:
        """The master's own lines for the slaves lost (or ``missing_line``: not found) this
        step, one per run of silent slaves (an answering slave between two runs): which, from
        where nothing answers, its AL status read's working counter (one per slave that
        answers, the description's slave count expected) and the link it reads where the
        frames stop."""
        runs: list[list[int]] = []
        for p in positions:  # ascending: the step's loop order
            if runs and self._first_silent(p) <= runs[-1][-1]:
                runs[-1].append(p)
            else:
                runs.append([p])
        wkc, expected = sum(link.present for link in self.links), len(self.links)
        for run in runs:
            first, silent = self._silent_words(run[0])
            finding = self._port_finding(first)
            self._log(None, message, positions=", ".join(map(str, run)), silent=silent,
                      wkc=wkc, expected=expected, finding=f"; {finding}" if finding else "")
