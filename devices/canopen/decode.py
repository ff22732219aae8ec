"""Frames in words, as a bus monitor shows them: NMT, SYNC, EMCY, SDO, PDO, heartbeat.

Only for views (the drive panel's frame log); nothing here changes state. The SDO command
bytes and abort codes are DS 301's (seed 004 ch. 4 "Device Configuration via SDOs").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from devices.canopen.emcy import EMCY_BASE
from devices.canopen.nmt import HEARTBEAT_BASE, NMT_COB_ID, STATE_CODE, NmtCommand
from devices.canopen.sdo import SDO_FRAME_BYTES, SDO_RX_BASE, SDO_TX_BASE
from devices.od import ABORT_TEXT, AbortCode

STATE_BY_CODE = {code: state.label for state, code in STATE_CODE.items() if code}
NMT_NAMES = {
    NmtCommand.START: "Start remote node", NmtCommand.STOP: "Stop remote node",
    NmtCommand.ENTER_PRE_OPERATIONAL: "Enter pre-operational",
    NmtCommand.RESET_NODE: "Reset node", NmtCommand.RESET_COMMUNICATION: "Reset communication",
}


@dataclass(frozen=True)
class Context:
    """What the decoder needs to know about the bus it watches."""

    sync_id: int = 0x80
    pdo_text: Callable[[int, bytes], str | None] = lambda can_id, data: None
    # (COB-ID, error code, vendor bytes) -> what the sender means by them (a drive alarm)
    emcy_text: Callable[[int, int, bytes], str | None] = lambda can_id, code, vendor: None


def _mux(data: bytes) -> str:
    return f"0x{int.from_bytes(data[1:3], 'little'):04X}:{data[3]:02X}"


def _abort(data: bytes) -> str:
    code = int.from_bytes(data[4:8], "little")
    try:
        text = ABORT_TEXT[AbortCode(code)]
    except ValueError:
        text = "abort code not in DS 301"
    return f"abort {_mux(data)} 0x{code:08X} ({text})"


def _expedited_data(data: bytes) -> str:
    size = 4 - (data[0] >> 2 & 3) if data[0] & 1 else 4
    return " ".join(f"{b:02X}" for b in data[4:4 + size])


def sdo_request(data: bytes) -> str:
    cmd = data[0]
    ccs = cmd >> 5
    if ccs == 1:
        if cmd & 2:
            return f"download {_mux(data)} = {_expedited_data(data)}"
        size = int.from_bytes(data[4:8], "little")
        return f"download {_mux(data)}, {size} bytes in segments"
    if ccs == 2:
        return f"upload {_mux(data)}"
    if ccs == 3:
        return f"upload segment, toggle {cmd >> 4 & 1}"
    if ccs == 0:
        last = " (last)" if cmd & 1 else ""
        return f"download segment, toggle {cmd >> 4 & 1}{last}"
    if ccs == 4:
        return _abort(data)
    return f"command 0x{cmd:02X}"


def sdo_response(data: bytes) -> str:
    cmd = data[0]
    scs = cmd >> 5
    if scs == 3:
        return f"download {_mux(data)} done"
    if scs == 2:
        if cmd & 2:
            return f"upload {_mux(data)} = {_expedited_data(data)}"
        return f"upload {_mux(data)}: {int.from_bytes(data[4:8], 'little')} bytes in segments"
    if scs == 0:
        used = 7 - (cmd >> 1 & 7)
        last = " (last)" if cmd & 1 else ""
        text = data[1:1 + used].decode("latin-1")
        return f"upload segment, toggle {cmd >> 4 & 1}{last}: {text!r}"
    if scs == 1:
        return f"download segment done, toggle {cmd >> 4 & 1}"
    if scs == 4:
        return _abort(data)
    return f"command 0x{cmd:02X}"


def sdo_parts(can_id: int, data: bytes) -> dict[str, Any] | None:
    """The pieces of an SDO frame a sentence needs, as plain data (a view joins a request
    and its answer: "Download (write) 0x6040:00 = 0F 00 to node 1: done"); None for
    another frame. ``service``: download, upload, download segment, upload segment, abort;
    ``value``: the expedited bytes ("0F 00"), ``size``: the bytes announced for a
    segmented transfer, ``last``: a segment with the "no more segments" bit."""
    if len(data) != SDO_FRAME_BYTES:  # no SDO (describe: "malformed"), no exchange
        return None
    if SDO_RX_BASE < can_id <= SDO_RX_BASE + 127:
        node, request = can_id - SDO_RX_BASE, True
    elif SDO_TX_BASE < can_id <= SDO_TX_BASE + 127:
        node, request = can_id - SDO_TX_BASE, False
    else:
        return None
    cmd = data[0]
    specifier = cmd >> 5
    parts: dict[str, Any] = {"node": node, "request": request, "object": _mux(data),
                             "service": f"command 0x{cmd:02X}", "value": "", "size": None,
                             "abort": "", "last": False}
    if specifier == 4:
        parts["service"], parts["abort"] = "abort", _abort(data).split(" ", 2)[2]
        return parts
    # DS 301: a client's download initiate is ccs 1, upload 2; a server's answers scs 3, 2.
    initiate = {1: "download", 2: "upload"} if request else {3: "download", 2: "upload"}
    segment = {0: "download segment", 3: "upload segment"} if request \
        else {1: "download segment", 0: "upload segment"}
    if specifier in initiate:
        parts["service"] = initiate[specifier]
        expedited = bool(cmd & 2)
        if expedited and (request or specifier == 2):
            parts["value"] = _expedited_data(data)
        elif not expedited and (cmd & 1) and specifier in (1, 2):
            parts["size"] = int.from_bytes(data[4:8], "little")
    elif specifier in segment:
        parts["service"] = segment[specifier]
        parts["object"] = ""
        # Only a segment carrying data (the client's download, the server's upload
        # segment: specifier 0) has the "no more segments" bit.
        parts["last"] = specifier == 0 and bool(cmd & 1)
    return parts


def _short_sdo(data: bytes) -> str:
    return f"malformed ({len(data)} bytes, an SDO is always {SDO_FRAME_BYTES})"


def describe(can_id: int, data: bytes, rtr: bool, ctx: Context) -> tuple[str, str]:
    """(kind, text) of one frame; kind is NMT, SYNC, EMCY, SDO, PDO, NMT-EC or CAN."""
    if can_id == NMT_COB_ID:
        if len(data) != 2:
            return "NMT", f"malformed ({len(data)} bytes)"
        try:
            name = NMT_NAMES[NmtCommand(data[0])]
        except ValueError:
            name = f"command 0x{data[0]:02X}"
        return "NMT", f"{name} -> {'all nodes' if data[1] == 0 else f'node {data[1]}'}"
    if can_id == ctx.sync_id and not rtr:
        return "SYNC", "SYNC" + (f" counter {data[0]}" if data else "")
    if HEARTBEAT_BASE < can_id <= HEARTBEAT_BASE + 127:
        node = can_id - HEARTBEAT_BASE
        if rtr:
            return "NMT-EC", f"node guarding request -> node {node}"
        if not data:
            return "NMT-EC", f"node {node}: empty"
        if data[0] == 0:
            return "NMT-EC", f"node {node}: boot-up"
        state = STATE_BY_CODE.get(data[0] & 0x7F, f"state 0x{data[0] & 0x7F:02X}")
        return "NMT-EC", f"node {node}: {state}" + (" (toggle 1)" if data[0] & 0x80 else "")
    if EMCY_BASE < can_id <= EMCY_BASE + 127 and not rtr:
        if len(data) < 3:
            return "EMCY", f"node {can_id - EMCY_BASE}: malformed"
        code = int.from_bytes(data[0:2], "little")
        vendor = " ".join(f"{b:02X}" for b in data[3:8])
        what = "error reset" if code == 0 else f"code 0x{code:04X}"
        meaning = ctx.emcy_text(can_id, code, data[3:8])
        return "EMCY", f"node {can_id - EMCY_BASE}: {what}, register 0x{data[2]:02X}, " \
                       f"data {vendor}" + (f": {meaning}" if meaning else "")
    if SDO_RX_BASE < can_id <= SDO_RX_BASE + 127 and not rtr:
        if len(data) != SDO_FRAME_BYTES:  # the server ignores it (devices/canopen/sdo.py)
            return "SDO", f"-> node {can_id - SDO_RX_BASE}: {_short_sdo(data)}: not answered"
        return "SDO", f"-> node {can_id - SDO_RX_BASE}: {sdo_request(data)}"
    if SDO_TX_BASE < can_id <= SDO_TX_BASE + 127 and not rtr:
        if len(data) != SDO_FRAME_BYTES:
            return "SDO", f"node {can_id - SDO_TX_BASE} ->: {_short_sdo(data)}"
        return "SDO", f"node {can_id - SDO_TX_BASE} ->: {sdo_response(data)}"
    text = ctx.pdo_text(can_id, data)
    if text is not None:
        return "PDO", text
    if 0x180 <= can_id <= 0x57F:
        return "PDO", f"PDO 0x{can_id:03X}" + (" (remote request)" if rtr else "")
    return "CAN", f"0x{can_id:03X}" + (" (remote request)" if rtr else "")
