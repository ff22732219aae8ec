"""What the master shows: its snapshot and seed 003's diagnostic structures per slave."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from devices.device import CommandError
from devices.ethercat import AlState
from devices.master.links import RANK, SlaveLink
from devices.master.log_styles import STYLES

if TYPE_CHECKING:
    from devices.master.dc import DcUnit

# The snapshot's ``phase`` (a stable key: recordings, tests) and the words a trainee reads
# on the master's screen and in the Line tab. Seed 003 names none of these phases; it says
# the master "waits to see the link on that port", then with link "starts sending packets"
# and sends the init commands. Not one slave answering those packets is what the master
# reads (working counter 0), so the words say that, not "no answer" (whose?).
PHASE_TEXT: dict[str, str] = {
    "waiting_link": "waiting link",
    "no_answer": "no slave answers",
    "init_commands": "init commands",
    "starting": "starting",
    "running": "running",
}


def phase_text(phase: str) -> str:
    """The words for a ``phase`` of the snapshot (an unknown one as it is, underscores as
    spaces)."""
    return PHASE_TEXT.get(phase, phase.replace("_", " "))


def dc_words(state: str) -> str:
    """Seed 003's DC phase as words for the master's screen, like its phase: NOT_SYNCHRONIZED
    -> "not synchronized". The identifier broken at its underscore to fit the screen read
    "NOT_" / "SYNCHRONIZED"; the words fit whole, and the Codes tab reads them too."""
    return state.replace("_", " ").lower()


def phase_note(lost: int, not_found: int, held: int) -> str:
    """What "running" (or "starting") leaves out: slaves lost, slaves never found, DC slaves
    held in SAFEOP below the master's target ("2 slaves lost, 1 DC slave held in SAFEOP").
    "" when there is none."""
    def many(n: int, what: str) -> str:
        return f"{n} {what}" + ("s" if n > 1 else "")

    parts = [many(lost, "slave") + " lost"] if lost else []
    parts += [many(not_found, "slave") + " not found"] if not_found else []
    parts += [many(held, "DC slave") + " held in SAFEOP"] if held else []
    return ", ".join(parts)


def phase_note_short(lost: int, not_found: int, held: int) -> str:
    """:func:`phase_note` for the master's small screen, one line ("2 lost, 1 held"): a slave
    never found counts as lost there, as the master has no answer from either."""
    parts = [f"{lost + not_found} lost"] if lost + not_found else []
    parts += [f"{held} held"] if held else []
    return ", ".join(parts)


class ViewMixin:
    """The view part of :class:`~devices.master.master.EtherCatMaster`."""

    KIND: str
    device_id: str
    links: list[SlaveLink]
    link_up: bool
    external: bool
    target: AlState
    dc_hold: bool
    log_style: str
    dc: DcUnit
    cables: list[bool]
    damaged: dict[int, float]
    frames: int
    lost_frames: int
    cycle_us: int
    log: Any

    if TYPE_CHECKING:
        def _connected(self, position: int) -> bool: ...
        def _target_of(self, link: SlaveLink) -> AlState: ...
        def _plugs_all(self) -> list[tuple[bool, bool]]: ...
        def _plugged(self, plugs: list[tuple[bool, bool]]) -> list[bool]: ...

    # ---- diagnostic structures (seed 003: by position from 0, or by physical address) -------
    def slave_at(self, position: int) -> dict[str, Any]:
        if not 0 <= position < len(self.links):
            raise CommandError(f"no slave at position {position} (0..{len(self.links) - 1})")
        return self._diagnostic(self.links[position])

    def slave_by_address(self, address: int) -> dict[str, Any]:
        for link in self.links:
            if link.slave.station_address == address:
                return self._diagnostic(link)
        known = ", ".join(str(link.slave.station_address) for link in self.links)
        raise CommandError(f"no slave with physical address {address} (addresses: {known})")

    def _diagnostic(self, link: SlaveLink) -> dict[str, Any]:
        return link.diagnostic()

    def _injected(self) -> dict[str, Any]:
        """The line's truth, which no real master can read: why each lost slave is lost
        (``lost``: position and cause, "cable 2 pulled"), each slave's supply (``powered``),
        whether the master's frames physically reach it (``link``: every cable up to it
        plugged, every slave before it powered) and the DC fault injected (``dc_fault``).
        The instructor's view and the recording only; the master's log and diagnostic
        structures say what it observes (docs/ethercat-master.md "What the master knows")."""
        return {"lost": [{"position": link.position, "cause": link.injected_cause}
                         for link in self.links if link.injected_cause],
                "powered": [bool(getattr(link.slave, "powered", True)) for link in self.links],
                "link": [self._connected(link.position) for link in self.links],
                "dc_fault": self.dc.fault}

    def _damaged_percent(self, cable: int) -> int | None:
        share = self.damaged.get(cable)
        return None if share is None else round(share * 100)

    def _cable_views(self, names: list[str]) -> list[dict[str, Any]]:
        """Each cable as the line has it (line.py ``_plugged``): plugged only when the
        master's ``cables`` has it and both its ends are. ``pulled_at``: the ends a slave's
        own plug has out ("trscat OUT", "cpx IN"), ``master_pulled``: the master's
        ``pull_cable`` has it out (what its pull / plug controls move). Read afresh, as the
        slaves' ``link``: a plug is out from the slave's own action on, while the port at the
        cable's other end follows at the master's next step."""
        plugs = self._plugs_all()
        plugged = self._plugged(plugs)
        out = []
        for i, name in enumerate(names):
            before = names[i - 1] if i else "master"
            ends = [f"{before} OUT"] if i and not plugs[i - 1][1] else []
            ends += [] if plugs[i][0] else [f"{name} IN"]
            out.append({"index": i, "from": before, "to": name, "plugged": plugged[i],
                        "master_pulled": not self.cables[i], "pulled_at": ends,
                        "damaged": self._damaged_percent(i)})
        return out

    # ---- view -------------------------------------------------------------------------------
    @property
    def phase(self) -> str:
        if not self.link_up:
            return "waiting_link"
        present = [link for link in self.links if link.present]
        if not present:  # link, and not one slave answers its frames
            return "no_answer"
        if any(link.slave.al_state in (AlState.INIT, AlState.BOOT) for link in present):
            return "init_commands"
        if all(link.slave.al_state is self._target_of(link) for link in present):
            return "running"
        return "starting"

    def _phase_counts(self) -> tuple[int, int, int]:
        """Slaves lost, never found and DC-held, counted when a snapshot is made (the step
        never reads them: docs/ethercat-master.md "Step cost"). Held: a DC slave the master
        reads in SAFEOP while DC keeps it there below a higher target (seed 003)."""
        lost = sum(1 for link in self.links if not link.present and link.lost_once)
        not_found = sum(1 for link in self.links if not link.present and link.missing)
        # A wire master (external mode) holds nothing of the built-in master's DC unit.
        holds = not self.external and self.dc_hold and \
            RANK.get(self.target, 0) > RANK[AlState.SAFEOP]
        held = sum(1 for link in self.links if holds and link.present and link.dc
                   and link.slave.al_state is AlState.SAFEOP)
        return lost, not_found, held

    def snapshot(self) -> dict[str, Any]:
        names = [link.slave.device_id for link in self.links]
        phase = self.phase
        # Without link, or with not one answer, the phase says it all.
        counts = self._phase_counts() if phase not in ("waiting_link", "no_answer") \
            else (0, 0, 0)
        return {"kind": self.KIND, "id": self.device_id, "target": self.target.label,
                "external": self.external, "link": self.link_up, "phase": phase,
                "phase_note": phase_note(*counts),
                "phase_note_short": phase_note_short(*counts),
                "log_style": self.log_style, "log_styles": list(STYLES),
                "dc": self.dc.snapshot(),
                "cables": self._cable_views(names),
                "slaves": [self._diagnostic(link) for link in self.links],
                "injected": self._injected(),
                "stats": {"frames": self.frames, "lost_frames": self.lost_frames,
                          "cycle_us": self.cycle_us},
                "log": list(self.log)}
