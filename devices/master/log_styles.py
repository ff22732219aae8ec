"""The master logger's lines in the styles of the seeds: tables of templates, one per style.

- ``twincat``: seed 000 §7.1 / §7.7 ("'Box 1 (FastCAT)' (1001): CoE - Emergency (Hex: ff00,
  81, 02 00 00 04 00')."), the only style of the first master; lines the seed does not show
  (link lost, identity, DC, recovery) are FieldRig's, written the same way.
- ``sirio``: the Sirio emergency display of §7.2 (three rows, data byte 0 first);
- ``pegaso``: the Pegaso display of §7.3 (data high byte first);
- ``aitraceprint``: the telnet trace of §7.4 (``<ms> - <mask> - <text>``; state changes as the
  EcatManagerSlaveStateCallback + SlaveStateChange pair, states and AL status code numeric;
  a slave's emergency after its other lines of the same instant, :data:`LATE`).
Sirio and Pegaso are emergency displays: their other lines are the TwinCAT text. Choices on
the seed's layout (which byte each header names) are in docs/ethercat-master.md.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from devices.ethercat import AL_STATUS_CODES, AlState

STYLES = ("twincat", "sirio", "pegaso", "aitraceprint")
MASTER_NAME = "Device 1 (EtherCAT)"  # TwinCAT's name for the master's own lines

# TwinCAT message templates (seed 000 §7.1 / §7.7; the FieldRig lines in the same manner).
TWINCAT: dict[str, str] = {
    "emergency": "CoE - Emergency (Hex: {code:04x}, {register:02x}, {data_lower}').",
    "abnormal": "abnormal state change (from '{from_state}' to '{to_state}') with code "
                "0x{code:04X}. Try to go back to '{target}'...",
    "failed": "'{from_state} to {to_state}' failed! Error: 'check device state for "
              "{to_state}'. AL Status '0x{al_status:04X}' read and '0x{expected:04X}' "
              "expected. AL Status Code '0x{code:04X}'",
    "aborted": "state change aborted (requested '{target}', back to '{state}').",
    "lost": "slave lost: {silent}.",
    "lost_line": "slave(s) at position(s) {positions} lost: {silent} (working counter {wkc}, "
                 "{expected} expected){finding}.",
    "found": "found on the line again in '{state}'.",
    "missing": "slave not found: {silent}.",
    "missing_line": "slave(s) at position(s) {positions} not found: {silent} (working counter "
                    "{wkc}, {expected} expected){finding}.",
    "found_late": "found on the line in '{state}'.",
    "identity": "identity check failed: vendor 0x{vendor:08X}, product 0x{product:08X}, "
                "revision 0x{revision:08X} read and vendor 0x{want_vendor:08X}, product "
                "0x{want_product:08X}, revision 0x{want_revision:08X} expected.",
    "identity_read": "identity check failed: SDO upload 0x{index:04X}:{sub:02X} aborted with "
                     "0x{abort:08X}.",
    "init_command": "init command '{comment}' ({transition}) failed: SDO download "
                    "0x{index:04X}:{sub:02X} aborted with 0x{abort:08X}.",
    "lost_frames": "{count} frame(s) lost.",
    "dc": "distributed clocks: {from_state} -> {to_state} (deviation {deviation} ns, sync "
          "window {window} ns).",
    # From or into IDLE: the master's clock is independent, no deviation is measured (seed 003).
    "dc_unmeasured": "distributed clocks: {from_state} -> {to_state} (sync window {window} ns).",
    "recovery": "network recovery: slave(s) at position(s) {positions} back on the line.",
}

# Which slaves do not answer, as the master reads it (``silent_run``): up to the end of the
# line, or a run the frames cross (a silent slave's ESC passes them on) with an answer behind.
SILENT_TO_END = "no answer from position {first} on"
SILENT_ONE = "no answer from position {first}, position {after} answers"
SILENT_RUN = "no answer from positions {first} to {last}, position {after} answers"


def silent_run(first: int, last: int, count: int) -> str:
    """The words for slaves ``first``..``last`` silent on a line of ``count`` slaves."""
    if last >= count - 1:
        return SILENT_TO_END.format(first=first)
    template = SILENT_ONE if first == last else SILENT_RUN
    return template.format(first=first, last=last, after=last + 1)


# Messages a style prints after a slave's other lines of the same instant. The §7.4 trace
# (seed 000 lines 592-599, oldest first) has slave 11's state-change pair at 380808 and its
# emergency at 380856, after it; TwinCAT (§7.7, newest first) logs the emergency first, as the
# master reads it (the mailbox before the state), so the other styles keep that order.
LATE: dict[str, frozenset[str]] = {"aitraceprint": frozenset({"emergency"})}

# §7.4: the mask column of the trace (00000001 for ECAT events, 00000100 for PLC alarms).
TRACE_MASK = "00000001"


@dataclass(frozen=True)
class Entry:
    """One logged message, kept as data so that the log can be rendered in any style."""

    t_us: int
    message: str  # a key of TWINCAT
    params: Mapping[str, Any] = field(default_factory=dict)
    slave: str = ""  # box name; empty for the master's own lines
    address: int = 0
    position: int = -1


def twincat(entry: Entry) -> str:
    params = dict(entry.params)
    if "data" in params:
        params["data_lower"] = " ".join(f"{b:02x}" for b in params["data"])
    text = TWINCAT[entry.message].format(**params)
    if entry.slave:
        return f"'{entry.slave}' ({entry.address}): {text}"
    return f"'{MASTER_NAME}': {text}"


def _significant(data: bytes) -> int:
    """The data byte a display's header names: byte 3 (coupler error, seed 000 §7.5) or
    byte 2 (module error, §7.6) for the FastCAT layout, else the last non-zero byte."""
    for i in (3, 2):
        if len(data) > i and data[i]:
            return i
    nonzero = [i for i, b in enumerate(data) if b]
    return nonzero[-1] if nonzero else 0


def sirio(entry: Entry) -> str:
    """§7.2: "Emergency Reset Byte 0 basso Byte 3 alto" / "Byte 0 Byte 2" headers."""
    if entry.message != "emergency":
        return twincat(entry)
    data: bytes = entry.params["data"]
    top = _significant(data)
    header = "Byte 0 basso\tByte 3 alto" if top == 3 else f"Byte 0\tByte {top}"
    return "\n".join((
        f"Emergency\tReset\t{header}",
        f"Err. Code\t{entry.params['code']:04X}\tAdditional Code\t",
        f"Err. Reg.\t{entry.params['register']:04X}\t0x low "
        f"{' '.join(f'{b:02X}' for b in data)} high\t"))


def pegaso(entry: Entry) -> str:
    """§7.3: the data high byte first; the header names the significant byte and byte 0."""
    if entry.message != "emergency":
        return twincat(entry)
    data: bytes = entry.params["data"]
    top = _significant(data)
    high = "alto " if top == 3 else ""
    return "\n".join((
        f"ERR CODE\t[0x{entry.params['code']:04X}]",
        f"ERR REG\tByte {top} [0x{entry.params['register']:02X}] Byte 0",
        f"ERR DATA\t{high}[0x{' '.join(f'{b:02X}' for b in reversed(data))}] basso"))


def _state_number(label: str) -> int:
    return int(AlState[label])


def _code_text(code: int) -> str:
    """§7.4 prints 33540:Unknown for the manufacturer code 0x8304."""
    return AL_STATUS_CODES.get(code, "Unknown")


def aitraceprint(entry: Entry) -> str:
    prefix = f"{entry.t_us // 1000} - {TRACE_MASK} - "
    p, slave = entry.params, entry.position
    if entry.message == "emergency":
        data = "".join(f"{b:02X}" for b in p["data"])
        lines = [f"ECAT_EVENT Emergency slave = {slave} emcyCode = 0x{p['code']:04X} "
                 f"emcyReg = 0x{p['register']:02X} data=0x{data}"]
    elif entry.message == "abnormal":
        to = _state_number(p["to_state"])
        lines = [f"** ECAT: EcatManagerSlaveStateCallback: {slave} {to} {p['code']}:"
                 f"{_code_text(p['code'])}",
                 f"ECAT_EVENT SlaveStateChange slave = {slave} from "
                 f"{_state_number(p['from_state'])} to {to}"]
    else:
        lines = [f"ECAT: {twincat(entry)}"]
    return "\n".join(prefix + line for line in lines)


RENDERERS: dict[str, Callable[[Entry], str]] = {
    "twincat": twincat, "sirio": sirio, "pegaso": pegaso, "aitraceprint": aitraceprint}


def render(style: str, entry: Entry) -> str:
    return RENDERERS[style](entry)


def is_late(style: str, entry: Entry) -> bool:
    """A line ``style`` prints after the other lines of its slave and instant (:data:`LATE`)."""
    return entry.position >= 0 and entry.message in LATE.get(style, ())


def same_group(a: Entry, b: Entry) -> bool:
    """One slave's lines of one instant: the run within which :data:`LATE` reorders."""
    return a.t_us == b.t_us and a.position == b.position


def arrange(style: str, entries: Iterable[Entry]) -> list[Entry]:
    """``entries`` (in the order logged) in the order ``style`` prints them: in each run of
    one slave's entries of one instant, the style's late ones last, each part in its order.
    The master's live log holds late lines back the same way (EtherCatMaster._log)."""
    out: list[Entry] = []
    held: list[Entry] = []
    for entry in entries:
        if held and not same_group(held[0], entry):
            out += held
            held = []
        if is_late(style, entry):
            held.append(entry)
        else:
            out.append(entry)
    return out + held
