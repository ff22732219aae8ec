"""NMT commands for the Codes tab (seed 004 ch. 4 "CANopen network management"): CAN-ID 0, two
data bytes, the command then the node-ID (0 = every node).

The words are the drive's CANopen node's tables: the names the frame log prints
(``devices.canopen.decode.NMT_NAMES``), the state each command leads to
(``devices.canopen.nmt.TRANSITIONS``, ``STATE_TEXT``) and what a reset does (``RESET_TEXT``).
Read here: ``NMT 01``, ``nmt command 0x82``, ``NMT 01 02`` (command, node), a frame log row as
a browser copies it (``0.500 rx 0x000 NMT 01 02 Start remote node -> node 2``) and its meaning
alone (``Start remote node -> node 2``, ``reset communication``).
"""

from __future__ import annotations

import re

from app.decoder_meaning import CANOPEN, DecodeError, Meaning
from devices.canopen.decode import NMT_NAMES
from devices.canopen.nmt import (
    MAX_NODE_ID,
    NMT_COB_ID,
    NODE_ID_ALL,
    RESET_TEXT,
    STATE_CODE,
    STATE_TEXT,
    TRANSITIONS,
    NmtCommand,
)
from devices.events import fmt_hex

SOURCE = "seed 004 ch. 4, DS 301"
# "NMT" (the frame log's type column) or "nmt command", then the data bytes.
_BYTES = re.compile(r"\bNMT(?:\s+command)?((?:\s+(?:0x)?[0-9A-Fa-f]{1,2}\b)+)", re.IGNORECASE)
_NAMED = re.compile(
    r"\b(" + "|".join(re.escape(name) for name in NMT_NAMES.values()) + r")\b"
    r"(?:\s*->\s*(?:(all nodes)|node\s+(\d+)))?", re.IGNORECASE)


def nmt_readings(text: str) -> list[Meaning]:
    """The NMT command in ``text``; [] when it holds none, DecodeError for a frame that is no
    NMT command (its length, an unknown command byte, a node-ID above 127)."""
    frame = _BYTES.search(text)
    if frame:
        data = [int(b, 16) for b in frame.group(1).split()]
        if len(data) > 2:
            raise DecodeError(f"{len(data)} bytes: an NMT frame is two bytes, the command and "
                              "the node-ID (seed 004 ch. 4)")
        return [_command(data[0], data[1] if len(data) == 2 else None)]
    named = _NAMED.fullmatch(text.strip())
    if named:
        by_name = {name.lower(): command for command, name in NMT_NAMES.items()}
        node = NODE_ID_ALL if named.group(2) else (
            int(named.group(3)) if named.group(3) else None)
        return [_command(int(by_name[named.group(1).lower()]), node)]
    return []


def _command(byte: int, node: int | None) -> Meaning:
    try:
        command = NmtCommand(byte)
    except ValueError:
        listed = ", ".join(f"{int(c):02X} {NMT_NAMES[c]}" for c in NmtCommand)
        state = next((s for s, code in STATE_CODE.items() if code == byte), None)
        # 04, 05, 7F are what a node answers, not commands: the heartbeat's state byte
        hint = "" if state is None else (f"; {fmt_hex(byte, 2)} is the state byte of "
                                         f"{state.label} (paste 'heartbeat {byte:02X}')")
        raise DecodeError(f"NMT command {fmt_hex(byte, 2)} is none of DS 301's ({listed}); a "
                          f"node ignores it{hint}") from None
    if node is not None and node > MAX_NODE_ID:
        raise DecodeError(f"node-ID {node} ({fmt_hex(node, 2)}): an NMT command's second byte is "
                          f"a node-ID 1-{MAX_NODE_ID}, or 0 for every node (seed 004 ch. 4)")
    where = "" if node is None else (" -> all nodes" if node == NODE_ID_ALL
                                     else f" -> node {node}")
    return Meaning(CANOPEN, f"NMT command {fmt_hex(byte, 2)} {NMT_NAMES[command]}{where}",
                   f"{_effect(command)}. Sent on CAN-ID {NMT_COB_ID}: byte 0 the command, "
                   "byte 1 the node-ID (0 = every node).", SOURCE)


def _effect(command: NmtCommand) -> str:
    if command in RESET_TEXT:
        return RESET_TEXT[command]
    moves = {state: new for (state, cmd), new in TRANSITIONS.items() if cmd is command}
    target = next(iter(set(moves.values())))
    sources = [s.label for s, new in moves.items() if s is not new]
    return f"{' or '.join(sources)} -> {target.label}: {STATE_TEXT[target]}"
