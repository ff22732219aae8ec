"""State names for the Codes tab: the EtherCAT states and the master's distributed-clock phases
(seed 003), the CANopen NMT states and their heartbeat / guarding byte (seed 004 ch. 4).

The words are the devices' tables (``devices.ethercat.AL_STATE_TEXT``,
``devices.master.dc.DC_STATE_TEXT``, ``devices.canopen.nmt.STATE_TEXT``); this module only
finds the state in what a trainee pastes: a name as the State tab, the seed or the log writes
it (``SAFE_OP``, ``Pre-Op``, ``NOT_SYNCHRONIZED``, ``Arrestato``), the master's DC log line
(``distributed clocks: COMPENSATING -> NOT_SYNCHRONIZED ...``), the CAN monitor's heartbeat
line (``node 2: Pre-operational (toggle 1)``) or a state byte (``heartbeat 7F``,
``guarding 85``).
"""

from __future__ import annotations

import re
from dataclasses import replace

from app.decoder_meaning import CANOPEN, ETHERCAT, DecodeError, Meaning
from devices.canopen.nmt import GUARDING_TOGGLE, STATE_CODE, STATE_TEXT, NmtState
from devices.ethercat import AL_STATE_TEXT, AL_STATUS_ERROR_FLAG, AlState
from devices.events import fmt_hex
from devices.master.dc import DC_STATE_TEXT, DcState

MASTER = "EtherCAT master"


def _key(name: str) -> str:
    """``Pre-Op``, ``PRE_OP``, ``pre op`` -> ``PREOP``: the seeds and the logs spell a state
    with and without separators."""
    return re.sub(r"[\s_\-]+", "", name).upper()


_ESM_NAMES: dict[str, AlState] = {
    **{_key(s.name): s for s in AlState},
    "PREOPERATIONAL": AlState.PREOP, "SAFEOPERATIONAL": AlState.SAFEOP,
    "OPERATIONAL": AlState.OP, "BOOTSTRAP": AlState.BOOT,
}
_DC_NAMES: dict[str, DcState] = {_key(s.value): s for s in DcState}
_NMT_NAMES: dict[str, NmtState] = {
    **{_key(s.label): s for s in NmtState},
    "INITIALIZATION": NmtState.INITIALISATION, "INITIALIZING": NmtState.INITIALISATION,
    "BOOTUP": NmtState.INITIALISATION, "ARRESTATO": NmtState.STOPPED,  # ch. 4's Italian word
}
_NMT_BY_CODE: dict[int, NmtState] = {code: state for state, code in STATE_CODE.items()}

# Seed 000 §7.4: the states as their AL status values in decimal (8 OP, 2 PREOP).
_TRACE_CHANGE = re.compile(r"SlaveStateChange\s+slave\s*=\s*(\d+)\s+from\s+(\d+)\s+to\s+(\d+)")
# The phases may come spelt as words ("not synchronized", "NOT-SYNCHRONIZED"): each ends at
# the arrow, at the line's "(deviation ...)" or at its end.
_DC_LINE = re.compile(r"distributed clocks:\s*(\S.*?)\s*->\s*(\S.*?)\s*(?:\(.*|\.)?\s*$",
                      re.IGNORECASE | re.DOTALL)
_DC_PREFIX = re.compile(r"distributed clocks:", re.IGNORECASE)
_MONITOR_LINE = re.compile(r"\bnode\s+\d+:\s*([A-Za-z\-]+)(?:\s*\(toggle\s*([01])\))?",
                           re.IGNORECASE)
_STATE_BYTE = re.compile(r"(heartbeat|(?:node\s*)?guarding)\s*(?:state\s*)?(?:0x)?"
                         r"([0-9A-Fa-f]{1,2})h?", re.IGNORECASE)


def state_readings(text: str) -> list[Meaning]:
    """Every state reading of ``text``; [] when it names no state (then it is no state
    query), DecodeError for a state byte the seed does not list."""
    raw = text.strip()
    change = _TRACE_CHANGE.search(raw)
    # Pasted with its callback line, the AL status code on that line is the reading.
    if change and "EcatManagerSlaveStateCallback" not in raw:
        return _trace_change(int(change.group(1)), int(change.group(2)), int(change.group(3)))
    line = _DC_LINE.search(raw)
    if line:
        return _dc_line(line.group(1), line.group(2))
    if _DC_PREFIX.search(raw):
        raise DecodeError("a distributed clocks line reads 'distributed clocks: FROM -> TO', "
                          f"each a DC phase of seed 003 ({_DC_LISTED})")
    byte = _STATE_BYTE.fullmatch(raw)
    if byte:
        return [_state_byte(int(byte.group(2), 16), guarding="guard" in byte.group(1).lower())]
    monitor = _MONITOR_LINE.search(raw)
    if monitor and _key(monitor.group(1)) in _NMT_NAMES:
        toggle = monitor.group(2)
        return [_nmt(_NMT_NAMES[_key(monitor.group(1))],
                     None if toggle is None else int(toggle))]
    key = _key(raw)
    found = []
    if key in _ESM_NAMES:
        found.append(_esm(_ESM_NAMES[key]))
    if key in _DC_NAMES:
        found.append(_dc(_DC_NAMES[key]))
    if key in _NMT_NAMES:
        found.append(_nmt(_NMT_NAMES[key]))
    return found


_DC_LISTED = ", ".join(s.value for s in DcState)


def _dc_line(old: str, new: str) -> list[Meaning]:
    """Both phases of the master's DC line; DecodeError naming each word that is no phase
    (before, such a line read "no code and no alarm name", its words unnamed)."""
    ends = (("from", old), ("to", new))
    states = {end: _DC_NAMES.get(_key(name)) for end, name in ends}
    unknown = [f"'{name}' ({end})" for end, name in ends if states[end] is None]
    if unknown:
        what = " and ".join(unknown) + (" are no DC phases" if len(unknown) > 1
                                        else " is no DC phase")
        raise DecodeError(f"distributed clocks: {what} of the master: seed 003 names "
                          f"{_DC_LISTED}")
    return [_dc(state, f" ({end})") for end, state in states.items() if state is not None]


def _trace_change(slave: int, old: int, new: int) -> list[Meaning]:
    try:
        states = [AlState(old), AlState(new)]
    except ValueError:
        names = ", ".join(f"{int(s)} {s.name}" for s in AlState)
        raise DecodeError(f"SlaveStateChange from {old} to {new}: the states are AL status "
                          f"values ({names}; seed 000 §7.4)") from None
    found = [replace(_esm(state), title=f"EtherCAT state {state.name} ({end}, slave {slave})")
             for state, end in zip(states, ("from", "to"), strict=True)]
    where = (" The AL status code of the change is on the EcatManagerSlaveStateCallback line "
             "just before it (seed 000 §7.4).")
    found[1] = replace(found[1], text=found[1].text + where, source="seed 000 §7.4, seed 003")
    return found


def _esm(state: AlState) -> Meaning:
    return Meaning(ETHERCAT, f"EtherCAT state {state.name}",
                   f"{AL_STATE_TEXT[state][:1].upper()}{AL_STATE_TEXT[state][1:]}. AL status "
                   f"register (0x0130) state bits {fmt_hex(int(state), 2)}; with the error "
                   f"flag (bit 4) {fmt_hex(int(state) | AL_STATUS_ERROR_FLAG, 2)}.",
                   "ETG.1000.6" if state is AlState.BOOT else "seed 003")


def _dc(state: DcState, end: str = "") -> Meaning:
    text = DC_STATE_TEXT[state]
    return Meaning(MASTER, f"DC phase {state.value}{end}",
                   f"Distributed clocks: {text}.", "seed 003")


def _nmt(state: NmtState, toggle: int | None = None) -> Meaning:
    code = STATE_CODE[state]
    what = "boot-up message" if state is NmtState.INITIALISATION else "heartbeat / guarding"
    bit = "" if toggle is None else f"; toggle bit {toggle} (node guarding)"
    return Meaning(CANOPEN, f"NMT state {state.label}",
                   f"{STATE_TEXT[state][:1].upper()}{STATE_TEXT[state][1:]}. State byte "
                   f"{fmt_hex(code, 2)} in the {what}{bit}.", "seed 004 ch. 4")


def _state_byte(value: int, guarding: bool) -> Meaning:
    """Ch. 4: the state in bits 0-6; bit 7 toggles with node guarding, stays 0 with
    heartbeat. The boot-up message (0x00) comes on the heartbeat's CAN-ID, never toggled."""
    toggle = value & GUARDING_TOGGLE
    state = _NMT_BY_CODE.get(value & ~GUARDING_TOGGLE)
    if state is None or (toggle and not guarding) or (toggle and state is
                                                      NmtState.INITIALISATION):
        listed = ", ".join(fmt_hex(c, 2) for c in sorted(_NMT_BY_CODE))
        raise DecodeError(f"state byte {fmt_hex(value, 2)} is no NMT state: seed 004 ch. 4 lists "
                          f"{listed} (bit 7 toggles with node guarding only)")
    return _nmt(state, (1 if toggle else 0) if guarding else None)
