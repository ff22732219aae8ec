"""Events as text log lines: the entity they go under, a readable line and a log level.

Levels (issue 6): an emergency or an active alarm is a warning or an error, everything else is
information. Codes print as the event schema prints them (``0xFF00``), with the meaning from
the shared code tables where the rig has one (AL status codes, seed 000 §7.7).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from app.recording.signals import al_status_lane, device_path, slave_lane, state_lane
from devices.ethercat import describe_al_status_code
from devices.events import Event
from devices.master.links import al_status_code_text

INFO, WARN, ERROR = "INFO", "WARN", "ERROR"


def _state(r: dict[str, Any]) -> str:
    machine = r.get("machine") or "state"
    return f"{machine}: {r['from']} -> {r['to']}"


def _emergency(r: dict[str, Any]) -> str:
    return f"EMCY {r['code']} register {r['register']} data [{r['data']}]"


# Reads an AL status code as the device that set it reads it: (device id, code) -> text.
AlStatusReader = Callable[[str, int], str]


def _al_status(r: dict[str, Any], device: str = "", read: AlStatusReader | None = None) -> str:
    code = int(r["code"], 16)
    meaning = read(device, code) if read is not None else describe_al_status_code(code)
    return f"AL status code {r['code']}: {meaning}"


def al_status_reader(devices: Mapping[str, Any]) -> AlStatusReader:
    """A slave with manufacturer codes of its own names them (the FastCAT's 0x80XX: the
    module and the coupler code, seed 000 §7.7), as the master's log and the State and Codes
    tabs do; any other device gets the ETG text."""
    def read(device_id: str, code: int) -> str:
        device = devices.get(device_id)
        if device is None:
            return describe_al_status_code(code)
        return al_status_code_text(device, code)
    return read


def _alarm(r: dict[str, Any]) -> str:
    where = f" (module {r['module']})" if r.get("module") else ""
    what = "raised" if r["active"] else "cleared"
    return f"alarm {r['code']} {r['name']} {what}{where}"


def _log(r: dict[str, Any]) -> str:
    return f"[port {r['port']}] {r['text']}" if r.get("port") else str(r["text"])


def _slave(r: dict[str, Any]) -> str:
    """How the master names a slave in its events: its place on the line and its address."""
    return f"slave {r['position']} ({r['address']})"


def _slave_state(r: dict[str, Any]) -> str:
    move = f"{r['from']} -> {r['to']}" if r["from"] else str(r["to"])
    code = f", AL status code {r['code']}" if int(r["code"], 16) else ""
    return f"{_slave(r)}: {move}{code}"


def _resync(r: dict[str, Any]) -> str:
    if r["position"] < 0:
        return "ECAT_Resync: the whole network"
    return f"ECAT_Resync: {_slave(r)} {r['slave']}"


FORMATS: dict[str, Callable[[dict[str, Any]], str]] = {
    "state": _state,
    "emergency": _emergency,
    "al_status": _al_status,
    "led": lambda r: f"LED {r['led']}: {r['pattern']}",
    "alarm": _alarm,
    "log": _log,
    "caption": lambda r: f"caption: {r['text']}",
    "checkpoint": lambda r: f"checkpoint: {r['name']}",
    "read": lambda r: f"read {r['address']} = {r['value']}"
                      + (f" ({r['hex']})" if r.get("hex") else ""),
    "focus": lambda r: f"focus: {r['target']}",
    # The EtherCAT master's events (seed 003), about a slave by position and address.
    "slave_state": _slave_state,
    "comm_error": lambda r: f"{_slave(r)}: communication error {r['reason']} "
                            f"(count {r['count']})",
    "coe_emergency": lambda r: f"{_slave(r)}: CoE {_emergency(r)}",
    "resync": _resync,
    "network_recovery": lambda r: "network recovery: slaves "
                                  + ", ".join(str(p) for p in r["positions"]),
}


def level(event: Event, record: dict[str, Any]) -> str:
    if event.kind == "alarm":
        return ERROR if record["active"] else INFO
    if event.kind in ("emergency", "coe_emergency"):
        # Error code 0x0000 is the "error reset / no error" emergency (DS301): good news.
        return INFO if int(record["code"], 16) == 0 else WARN
    if event.kind in ("al_status", "slave_state"):
        return INFO if int(record["code"], 16) == 0 else WARN
    if event.kind == "comm_error":
        return WARN
    return INFO


def text(event: Event, record: dict[str, Any], al_status: AlStatusReader | None = None) -> str:
    """``al_status``: the rig's reading of AL status codes (:func:`al_status_reader`: a
    FastCAT's 0x80XX names the module and the coupler code, seed 000 §7.7; a module alarm sets
    no AL status code); without it, the ETG text."""
    if al_status is not None and event.kind == "al_status":
        return _al_status(record, event.device, al_status)
    fmt = FORMATS.get(event.kind)
    if fmt is None:
        extra = ", ".join(f"{k}={v}" for k, v in record.items()
                          if k not in ("t", "device", "event"))
        return f"{event.kind}: {extra}" if extra else event.kind
    return fmt(record)


RIG_LOG = device_path("session", "events")  # the recorder's own lines (a rig restart)


def log_path(event: Event) -> str:
    return device_path(event.device, "events")


def lane_change(event: Event, record: dict[str, Any],
                main: str = "") -> tuple[str, str] | None:
    """(lane path, new value) when the event moves a state lane (a state machine, an LED,
    the AL status code, the master's view of a slave).
    ``main``: the lane of the device's main machine (signals.main_machine: "ds402" for a
    drive), where its events without ``machine`` go, so they meet its samples."""
    if event.kind == "state":
        return state_lane(event.device, record.get("machine") or main), str(record["to"])
    if event.kind == "led":
        return device_path(event.device, "led", record["led"]), str(record["pattern"])
    if event.kind == "al_status":
        return al_status_lane(event.device), str(record["code"])
    if event.kind == "slave_state":
        return slave_lane(event.device, record["position"]), str(record["to"])
    return None
