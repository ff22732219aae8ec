"""What a rig snapshot contributes to a recording: sampled scalar signals and state lanes.

Kept apart from the recorder so that the blueprint lays out exactly the entities the recorder
writes: both ask :func:`device_signals` for the same list. Extractors are chosen by the
snapshot's ``kind`` (a table, :data:`EXTRACTORS`); a kind without one still gets its LEDs and
state lanes, so a new device shows up in recordings before it has its own extractor.

This runs at every sample (100 times per simulated second by default), so everything about an
entity except its values (path, series names, plot) is built once and cached.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import rerun as rr

from devices.events import fmt_hex
from devices.leds import LedPattern, is_lit

ROOT = "rig"

# Snapshot keys that hold a state machine's current state, and the lane (StateChanged.machine)
# they feed; "" is the device's main state machine (for EtherCAT slaves, the ESM).
STATE_KEYS: dict[str, str] = {"esm": "", "ds402_state": "ds402"}

def _nested(key: str, field: str) -> Callable[[Mapping[str, Any]], Any]:
    return lambda snap: (snap.get(key) or {}).get(field)


# Other machines whose state a snapshot keeps in a table of its own, by kind: machine (as the
# events' StateChanged.machine names it) -> the state as the events print it.
NESTED_STATES: dict[str, dict[str, Callable[[Mapping[str, Any]], Any]]] = {
    "trscat": {"trs_bus": _nested("trs_bus", "state"), "sync": _nested("sync", "state")},
    "fastcat": {"cnf": _nested("cnf", "phase"),
                "cnf_button": lambda snap: None if not isinstance(snap.get("cnf"), Mapping)
                else "pressed" if snap["cnf"].get("pressed") else "released"},
    "master": {"dc": _nested("dc", "state")},
}

# A drive's fieldbus sides, by snapshot kind: the CoE slave (<drive>-ecat) and the CANopen node
# (<drive>-can) emit under the drive's id with machine "esm" / "nmt" (docs/architecture.md), so
# their samples feed the same lanes under the drive: snapshot key -> machine.
SIDE_KEYS: dict[str, dict[str, str]] = {"servo_ecat": {"esm": "esm"}, "canopen": {"nmt": "nmt"}}

# Drive signals recorded from a servo snapshot (issue 6: position, velocity, following error).
DRIVE_SIGNALS = ("position", "velocity", "following_error")
# The drive's words, one step plot each: CiA 402 0x6040 / 0x6041 and the register-mode R00 /
# R05 (seed 004 ch. 2), what a master wrote and what the drive answered.
DRIVE_WORDS = ("controlword", "statusword", "control_register", "status_register")
# Its CN2 pins (seed 004: inputs with TEN / IEN, outputs), one series a pin, by name.
DRIVE_PINS = ("inputs", "outputs")

# LED colours for the plots, by the colour in the LED's name (ETG.1300: RUN green, ERR red;
# FastCAT module LEDs are "<slot>.red" / "<slot>.yellow").
LED_RGBA = {"red": 0xE53935FF, "yellow": 0xFBC02DFF, "green": 0x43A047FF}

_PATTERNS = {p.value: p for p in LedPattern}


@dataclass(frozen=True)
class SeriesInfo:
    """How an entity's series are named and plotted; the same for all its samples."""

    names: tuple[str, ...]
    view: str  # title of the plot it belongs to; entities with one title share a plot
    step: bool = False  # digital-like: draw as steps, not as a ramp between samples
    colors: tuple[int, ...] | None = None


class Signal(NamedTuple):
    """One entity's sample: a row of values (one per series) under an entity path."""

    path: str
    values: tuple[float, ...]
    info: SeriesInfo
    # An LED's lit / dark row: the pattern it follows (the row at any time is is_lit's)
    pattern: LedPattern | None = None

    @property
    def view(self) -> str:
        return self.info.view


@functools.lru_cache(maxsize=4096)
def device_path(device_id: str, *parts: object) -> str:
    """``rig/<device>/<part>/...``; each part escaped, so a name with a space or a slash
    (the TRS-CAT's "LINK-ACT IN", "I/O 1") stays one path part."""
    return "/".join([ROOT, *(rr.escape_entity_path_part(str(p)) for p in (device_id, *parts))])


# The lane helpers run for every lane of every sample (~80 on the default rig): cached too.
@functools.lru_cache(maxsize=1024)
def state_lane(device_id: str, machine: str) -> str:
    """Entity path of a state machine's lane: ``rig/<device>/state[/<machine>]``."""
    return device_path(device_id, "state", machine) if machine else device_path(device_id,
                                                                                "state")


def al_status_lane(device_id: str) -> str:
    """The AL status code register's lane (seed 000 §7.7), codes as the events print them."""
    return device_path(device_id, "al_status")


# The master's lane of a slave that does not answer, lost or not found yet (state None).
SLAVE_LOST = "absent"


@functools.lru_cache(maxsize=1024)
def slave_lane(master_id: str, position: object) -> str:
    """The master's view of the slave at a line position (its slave_state events, seed 003)."""
    return device_path(master_id, "state", "slave", position)


@functools.lru_cache(maxsize=4096)
def led_lane(device_id: str, led: str) -> str:
    return device_path(device_id, "led", led)


@functools.lru_cache(maxsize=1024)
def led_color(led: str) -> int:
    name = led.rsplit(".", 1)[-1].lower()
    if name in LED_RGBA:
        return LED_RGBA[name]
    return LED_RGBA["red"] if name.startswith("err") else LED_RGBA["green"]


@functools.lru_cache(maxsize=1024)
def _led_entity(device_id: str, led: str) -> tuple[str, SeriesInfo]:
    """An LED's lit / dark entity: path and series."""
    return led_lane(device_id, led), SeriesInfo((led,), f"{device_id} LEDs (lit)", step=True,
                                                colors=(led_color(led),))


@functools.lru_cache(maxsize=4096)
def _series(prefix: str, count: int, view: str, step: bool = False,
            first: int = 1) -> SeriesInfo:
    """Series ``"di 1"``, ``"di 2"``, ...: channels numbered as the device's actions take them
    (the FastCAT's and the TRS-CAT's ``channel`` count from 1, the CPX-E-EC's from 0)."""
    return SeriesInfo(tuple(f"{prefix} {ch}" for ch in range(first, first + count)), view, step)


@functools.lru_cache(maxsize=1024)
def _single(name: str, view: str, step: bool = False) -> SeriesInfo:
    return SeriesInfo((name,), view, step)


@functools.lru_cache(maxsize=64)
def _supply_info(view: str) -> SeriesInfo:
    return SeriesInfo(("el_sen_v", "out_v"), view)


@functools.lru_cache(maxsize=1024)
def _named(names: tuple[str, ...], view: str) -> SeriesInfo:
    """Digital pins, one series each, by the name the snapshot gives them."""
    return SeriesInfo(names, view, step=True)


@functools.lru_cache(maxsize=4096)
def _io_entity(device_id: str, number: object, label: object, key: str, title: str,
               step: bool, count: int, first: int = 1) -> tuple[str, SeriesInfo]:
    """A module's (slot's) process-data entity ``rig/<device>/io/<number>/<key>``: path and
    series, its plot titled "<device> <number> <label> <title>". The same for every sample
    while the module stays, so built once per layout, not at each sample (the title's
    f-string and two more lookups per entity were a third of the extractors' time)."""
    return (device_path(device_id, "io", number, key),
            _series(key, count, f"{device_id} {number} {label} {title}", step, first))


def _num(value: Any) -> float:
    if value is None:
        return math.nan
    try:
        return float(value)  # bools too: True -> 1.0
    except (TypeError, ValueError):
        return math.nan


def _row(values: Iterable[Any]) -> tuple[float, ...]:
    try:
        return tuple(map(float, values))
    except (TypeError, ValueError):
        return tuple(_num(v) for v in values)


def led_signals(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    """LEDs as lit (1) / dark (0) at ``t_us``, from the pattern the snapshot shows."""
    rows = _lit_rows(t_us)
    for led, name in (snap.get("leds") or {}).items():
        pattern_row = rows.get(name)
        if pattern_row is None:
            continue  # not an ETG.1300 pattern name: nothing sensible to plot
        path, info = _led_entity(device_id, led)
        yield Signal(path, pattern_row[1], info, pattern_row[0])


@functools.lru_cache(maxsize=1)
def _lit_rows(t_us: int) -> dict[str, tuple[LedPattern, tuple[float, ...]]]:
    """Pattern name -> (pattern, its lit / dark row at ``t_us``): the seven patterns once per
    sample time, not ``is_lit`` once per LED (a rig shows ~60 LEDs, every device at the same
    time)."""
    return {name: (pattern, (1.0 if is_lit(pattern, t_us) else 0.0,))
            for name, pattern in _PATTERNS.items()}


def main_machine(snap: Mapping[str, Any]) -> str | None:
    """The lane (``StateChanged.machine``) that a device's main-machine events belong to: the
    one of the first STATE_KEYS key its snapshot holds (a servo drive's is CiA 402, "ds402",
    docs/architecture.md); None when the snapshot shows none."""
    return next((machine for key, machine in STATE_KEYS.items()
                 if isinstance(snap.get(key), str)), None)


def lane_owner(device_id: str, snap: Mapping[str, Any]) -> str:
    """The device whose lanes a snapshot feeds: a drive's side's is the drive."""
    if snap.get("kind") in SIDE_KEYS and isinstance(snap.get("drive"), str):
        return str(snap["drive"])
    return device_id


def state_values(device_id: str, snap: Mapping[str, Any]) -> Iterator[tuple[str, str]]:
    """(lane path, value) of every state machine and LED pattern the snapshot shows."""
    side = SIDE_KEYS.get(str(snap.get("kind", "")))
    if side is not None:
        # A silent CANopen node (drive off, or not on CANopen) shows "Off", a state no event
        # reports: its lane keeps what the events said (power-off: Initialisation).
        if snap.get("active", True):
            owner = lane_owner(device_id, snap)
            for key, machine in side.items():
                if isinstance(snap.get(key), str):
                    yield state_lane(owner, machine), snap[key]
    else:
        for key, machine in STATE_KEYS.items():
            if isinstance(snap.get(key), str):
                yield state_lane(device_id, machine), snap[key]
        for machine, read in NESTED_STATES.get(str(snap.get("kind", "")), {}).items():
            value = read(snap)
            if isinstance(value, str):
                yield state_lane(device_id, machine), value
    code = snap.get("al_status_code")
    if isinstance(code, int) and not isinstance(code, bool):  # an EtherCAT slave's 0x0134
        yield al_status_lane(lane_owner(device_id, snap)), fmt_hex(code, 4)
    for slave in snap.get("slaves") or []:  # the master's view of each line position
        yield slave_lane(device_id, slave.get("position")), slave.get("state") or SLAVE_LOST
    for led, pattern in (snap.get("leds") or {}).items():
        if isinstance(pattern, str):
            yield led_lane(device_id, led), pattern
    injected = snap.get("injected")
    if isinstance(injected, Mapping) and "lost" in injected:
        # The master's lost slaves and why (its log says only what it observes): the
        # instructor's record of the cause, docs/ethercat-master.md "What the master knows".
        lost = "; ".join(f"{c.get('position')}: {c.get('cause')}" for c in injected["lost"])
        yield state_lane(device_id, "injected"), lost or "none"


_FASTCAT_IO = (("di", "digital", True), ("do", "digital", True),
               ("ai", "analog in (raw)", False), ("ao", "analog out (raw)", False))
_FASTCAT_ENCODER = (("position", "encoder position"), ("rpm", "encoder rpm"))


def _fastcat(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    """The rail's process data: digital in/out as 0/1, analog raw codes, encoder counts."""
    for i, module in enumerate(snap.get("rail") or []):
        slot = module.get("slot", i + 1)
        mtype = module.get("type")
        for key, title, step in _FASTCAT_IO:
            values = module.get(key)
            if values:
                path, info = _io_entity(device_id, slot, mtype, key, title, step, len(values))
                yield Signal(path, _row(values), info)
        encoders = module.get("encoders")
        if encoders:
            for key, title in _FASTCAT_ENCODER:
                path, info = _encoder_entity(device_id, slot, mtype, key, title, len(encoders))
                yield Signal(path, _row(e.get(key) for e in encoders), info)


@functools.lru_cache(maxsize=1024)
def _encoder_entity(device_id: str, slot: object, mtype: object, key: str, title: str,
                    count: int) -> tuple[str, SeriesInfo]:
    """An AX2's encoder entity (series "position encoder 1", ...): see _io_entity."""
    return (device_path(device_id, "io", slot, key),
            _series(f"{key} encoder", count, f"{device_id} {slot} {mtype} {title}"))


# A TRS-CAT slot's process data (slot 0 the integrated I/O, seed 001): key, plot, digital-like.
# outputs_plc is what the PLC wrote, outputs what the lines drive: they part in the fallback.
_TRSCAT_IO = (("inputs", "inputs", True), ("outputs", "outputs", True),
              ("outputs_plc", "outputs (PLC)", True), ("analog_in_v", "analog in (V)", False),
              ("analog_out_v", "analog out (V)", False))


def _trscat(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    if "field_supply_v" in snap:  # seed 001 §10.3: the +24V LED's 18..30 V
        yield Signal(device_path(device_id, "supply"), (_num(snap["field_supply_v"]),),
                     _single("field_supply_v", f"{device_id} supply (V)"))
    bus = snap.get("trs_bus")
    if isinstance(bus, Mapping) and "current_a" in bus:
        yield Signal(device_path(device_id, "trs_bus", "current_a"), (_num(bus["current_a"]),),
                     _single("current_a", f"{device_id} TRS bus current (A)"))
    for slot in snap.get("slots") or []:
        number, stype = slot.get("slot"), slot.get("type")
        for key, title, step in _TRSCAT_IO:
            values = slot.get(key)
            if values:
                path, info = _io_entity(device_id, number, stype, key, title, step, len(values))
                yield Signal(path, _row(values), info)


# A CPX-E-EC module's process data (module 0 the bus module, seed 002), channels from 0.
# outputs is what the PLC wrote, driven what the channel drives (forced, shorted: they part).
_CPX_IO = (("inputs", "inputs", True), ("outputs", "outputs", True),
           ("driven", "outputs (driven)", True), ("analog_in", "analog in", False),
           ("analog_out", "analog out", False))


def _cpx(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    supply = snap.get("supply")
    if isinstance(supply, Mapping):  # seed 002 Tab. 29: U_EL/SEN and U_OUT, 24 V +- 25 %
        yield Signal(device_path(device_id, "supply"),
                     (_num(supply.get("el_sen_v")), _num(supply.get("out_v"))),
                     _supply_info(f"{device_id} supply (V)"))
    bus = snap.get("bus_module")
    for module in ([bus] if isinstance(bus, Mapping) else []) + list(snap.get("modules") or []):
        number, mtype = module.get("module"), module.get("short") or module.get("type")
        for key, title, step in _CPX_IO:
            values = module.get(key)
            if values:
                path, info = _io_entity(device_id, number, mtype, key, title, step,
                                        len(values), 0)
                yield Signal(path, _row(values), info)


def _master(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    """Per line position, the master's counters and the ESC error counters (seed 003). Not
    the frame count nor the DC deviation: they move at every quiet step ("Repeated samples")."""
    for slave in snap.get("slaves") or []:
        position = slave.get("position")
        counters = slave.get("counters")
        if isinstance(counters, Mapping) and counters:
            path, info = _slave_entity(device_id, position, "counters", "counters",
                                       tuple(counters))
            yield Signal(path, _row(counters.values()), info)
        esc = slave.get("esc_errors")
        if isinstance(esc, Mapping) and esc:
            names, values = _flat(esc)
            path, info = _slave_entity(device_id, position, "esc_errors", "ESC errors", names)
            yield Signal(path, values, info)


def _flat(counters: Mapping[str, Any]) -> tuple[tuple[str, ...], tuple[float, ...]]:
    """ESC counters, per port where the ESC has one (``rx 0``, ``rx 1``, ``epu``). The names
    follow from the keys and which of them have ports, how many: looked up, not formatted
    anew at each sample."""
    values: list[Any] = []
    ports: list[int | None] = []
    for value in counters.values():
        if isinstance(value, list | tuple):
            values.extend(value)
            ports.append(len(value))
        else:
            values.append(value)
            ports.append(None)
    return _flat_names(tuple(counters), tuple(ports)), _row(values)


@functools.lru_cache(maxsize=256)
def _flat_names(keys: tuple[str, ...], ports: tuple[int | None, ...]) -> tuple[str, ...]:
    names: list[str] = []
    for key, count in zip(keys, ports, strict=True):
        names.extend([key] if count is None else (f"{key} {port}" for port in range(count)))
    return tuple(names)


@functools.lru_cache(maxsize=1024)
def _slave_entity(master_id: str, position: object, key: str, title: str,
                  names: tuple[str, ...]) -> tuple[str, SeriesInfo]:
    """The master's counters of a line position (``rig/<master>/slave/<position>/<key>``):
    path and series, built once per layout."""
    return (device_path(master_id, "slave", position, key),
            SeriesInfo(names, f"{master_id} slave {position} {title}", step=True))


@functools.lru_cache(maxsize=256)
def _drive_entities(device_id: str) -> tuple[tuple[str, str, SeriesInfo], ...]:
    """(snapshot key, path, series) of a drive's signals, then its words (step plots): the
    same for every sample of the drive, so built once."""
    return tuple((key, device_path(device_id, "drive", key),
                  _single(key, f"{device_id} {key.replace('_', ' ')}", key in DRIVE_WORDS))
                 for key in DRIVE_SIGNALS + DRIVE_WORDS)


@functools.lru_cache(maxsize=256)
def _pins_entity(device_id: str, key: str, names: tuple[str, ...]) -> tuple[str, SeriesInfo]:
    return device_path(device_id, "io", key), _named(names, f"{device_id} {key}")


def _servo(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    for key, path, info in _drive_entities(device_id):
        if key in snap:
            yield Signal(path, (_num(snap[key]),), info)
    for key in DRIVE_PINS:
        pins = snap.get(key)
        if isinstance(pins, Mapping) and pins:
            path, info = _pins_entity(device_id, key, tuple(pins))
            yield Signal(path, _row(pins.values()), info)


Extractor = Callable[[str, Mapping[str, Any], int], Iterator[Signal]]

EXTRACTORS: dict[str, Extractor] = {"fastcat": _fastcat, "trscat": _trscat,
                                     "cpx_e_ec": _cpx, "servo": _servo, "master": _master}


def device_signals(device_id: str, snap: Mapping[str, Any], t_us: int) -> Iterator[Signal]:
    """Every sampled signal of one device snapshot: its LEDs, then its kind's own signals."""
    yield from led_signals(device_id, snap, t_us)
    extractor = EXTRACTORS.get(str(snap.get("kind", "")))
    if extractor is not None:
        yield from extractor(device_id, snap, t_us)


def rig_signals(snapshot: Mapping[str, Any], t_us: int) -> Iterator[tuple[str, Signal]]:
    for device_id, snap in (snapshot.get("devices") or {}).items():
        for signal in device_signals(device_id, snap, t_us):
            yield device_id, signal
