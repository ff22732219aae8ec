"""Rig files: TOML in, a checked :class:`RigSpec` out, then a live :class:`~app.rig.Rig`.

Every error names the file, the key (``fastcat[0].modules[3]``) and the reason, so the CLI can
print one line and exit 2. TOML is parsed with :mod:`tomllib`: nothing in a rig file is ever
executed. See docs/rig-file.md for the format.
"""

from __future__ import annotations

import datetime as dt
import os
import random
import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from app.clock import SimClock
from app.flash_file import FileFlash
from app.rig import Rig
from devices.device import DeviceModel
from devices.flash import FlashStore, MemoryFlash
from devices.names import did_you_mean

if TYPE_CHECKING:
    from devices.master.network import SlaveDescription

DEFAULT_RIG = Path(__file__).resolve().parent.parent / "static" / "rigs" / "default.toml"
MAX_MODULES = 16  # seed 000 §2
MEMORY = ":memory:"


def one_line(text: str) -> str:
    """``text`` with every character that is not printable escaped as Python writes it
    (``\\n``, ``\\x85``, ``\\u2028``). A quoted TOML key may hold any of them, and the
    messages name keys: a line break would split the CLI's one ``fieldrig: error:`` line, an
    ESC would reach the terminal."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class RigConfigError(ValueError):
    def __init__(self, source: str, key: str, reason: str) -> None:
        self.source, self.key, self.reason = source, key, reason
        where = f"{source}: {key}" if key else source
        super().__init__(one_line(f"{where}: {reason}"))


@dataclass(frozen=True)
class ModuleSpec:
    type: str
    options: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class FastCatSpec:
    id: str
    modules: tuple[ModuleSpec, ...]
    rotary_switch: int = 1
    master_address: int = 1
    flash: str = MEMORY
    box_name: str = ""


@dataclass(frozen=True)
class ServoSpec:
    id: str
    settings: dict[str, Any]  # DriveConfig keyword arguments, checked against its fields
    flash: str = MEMORY


@dataclass(frozen=True)
class SlaveSpec:
    """A TRS-CAT or CPX-E-EC on the EtherCAT line: constructor keywords, checked by kind."""

    kind: str  # "trscat" or "cpx"
    id: str
    settings: dict[str, Any]


@dataclass(frozen=True)
class RigSpec:
    source: str
    name: str = "rig"
    seed: int = 0
    step_us: int = 1000
    epoch: dt.datetime = dt.datetime(2019, 11, 12, 14, 51, 30)
    retry_interval_us: int = 2_000_000
    fastcats: tuple[FastCatSpec, ...] = ()
    servos: tuple[ServoSpec, ...] = ()
    slaves: tuple[SlaveSpec, ...] = ()
    line: tuple[str, ...] = ()  # EtherCAT line order (device ids); default: file order by kind
    eni: str | None = None  # network description file (relative to the rig file)
    mapping: str | None = None  # mapping file (PLC variables, cycle time, DC sync window)


class _Table:
    """A TOML table being read: typed getters that know their key path, and leftovers check."""

    def __init__(self, source: str, path: str, data: Any) -> None:
        if not isinstance(data, Mapping):
            raise RigConfigError(source, path, f"must be a table, got {type(data).__name__}")
        self.source, self.path, self.data = source, path, dict(data)
        self.used: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def get(self, name: str, kind: type | tuple[type, ...], default: Any = None,
            check: Callable[[Any], str | None] | None = None) -> Any:
        self.used.add(name)
        if name not in self.data:
            if default is _REQUIRED:
                raise RigConfigError(self.source, self.key(name), "is required")
            return default
        value = self.data[name]
        kinds = kind if isinstance(kind, tuple) else (kind,)
        if isinstance(value, bool) and bool not in kinds:
            value = None  # TOML booleans are not numbers here
        if kind is float and isinstance(value, int):
            value = float(value)
        if not isinstance(value, kinds):
            names = " or ".join(k.__name__ for k in kinds)
            raise RigConfigError(self.source, self.key(name),
                                 f"must be {names}, got {self.data[name]!r}")
        problem = check(value) if check else None
        if problem:
            raise RigConfigError(self.source, self.key(name), problem)
        return value

    def finish(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise RigConfigError(self.source, self.key(unknown[0]),
                                 f"unknown key (known here: {', '.join(sorted(self.used))})"
                                 f"{did_you_mean(unknown[0], self.used)}")


_REQUIRED = object()


def _id_problem(device_id: str) -> str | None:
    """What is wrong with a device's ``id`` (the same rule for every kind of device: it is the
    target of commands, scenarios and the event log), None when nothing."""
    if device_id.replace("_", "").replace("-", "").isalnum():
        return None
    return "use letters, digits, '-' and '_' only"


def _in_range(low: float, high: float) -> Callable[[Any], str | None]:
    return lambda v: None if low <= v <= high else f"must be between {low} and {high}, got {v}"


def not_utf8(exc: UnicodeDecodeError, declared: str | None = None) -> str:
    """Why a file is refused when it is not UTF-8 (an editor's Latin-1 or UTF-16 save), or not
    in the encoding it ``declared`` (an XML declaration): the first bad byte and its offset,
    so that it can be found in a hex view."""
    what = f"{declared} text as it declares" if declared else "UTF-8 text"
    return f"not {what}: byte 0x{exc.object[exc.start]:02x} at offset {exc.start}"


# What people write for a TOML boolean (``on = True``, ``on = yes``) and what TOML takes.
_BOOLEAN_WORDS = {"true": "true", "false": "false", "yes": "true", "no": "false",
                  "on": "true", "off": "false"}


# A bare word where a value belongs (``DO16``, ``True``, ``module:0x04``, ``Übung``): it ends
# where a value in an array or inline table ends. Anything else (``-abc``, ``.5``, ``@b``) gets
# no guess. A ``key =`` line's whole value is one text (``name = Sales demo``).
_WORD_START = r"[^\W\d]"  # a letter of any script, or _
_BARE_WORD = re.compile(_WORD_START + r"[^\s,\]}#\"'\[{]*")
_WHOLE_VALUE = re.compile(r"\s*(?P<key>[^=\[{#\"']+?)\s*=\s*(?P<value>" + _WORD_START
                          + r"[^#\"'\[\]{}]*?)\s*(?:\s#.*)?")
_INVALID_VALUE = re.compile(r"Invalid value \(at line (\d+), column (\d+)\)")
_MAX_FIXES = 16  # bare words fixed on one line before the hint gives up on showing it


def not_toml(exc: tomllib.TOMLDecodeError, text: str) -> str:
    """tomllib's message, and for its "Invalid value" the commonest cause fixed at the line
    and column it names: an unquoted text value (``fault = module:0x04``, ``[..., DO16]``) or
    a boolean written ``True`` or ``yes``. The hint shows the line with every bare word on it
    fixed when that line then parses, else only the fixed word (a value continued from the
    line before); no hint when there is no bare word at the column. One line."""
    said = f"not valid TOML: {exc}"
    found = _INVALID_VALUE.match(str(exc))
    lines = text.splitlines()
    if found is None or not 1 <= int(found[1]) <= len(lines):
        return said
    first = _fix_word(lines[int(found[1]) - 1], int(found[2]) - 1)
    if first is None:
        return said
    line, word, boolean = first
    shown: str | None = None
    for _ in range(_MAX_FIXES):
        try:
            tomllib.loads(line)
        except tomllib.TOMLDecodeError as again:
            more = _INVALID_VALUE.match(str(again))
            step = _fix_word(line, int(more[2]) - 1) if more and more[1] == "1" else None
            if step is None:
                break
            line = step[0]
        else:
            shown = line
            break
    if boolean is not None:
        return f"{said}: a yes/no value is true or false, lower case: {shown or boolean}"
    return f'{said}: text values need quotes: {shown or chr(34) + word + chr(34)}'


def _fix_word(line: str, column: int) -> tuple[str, str, str | None] | None:
    """``line`` with the bare word at ``column`` (0-based) quoted or made a TOML boolean, the
    word, and the boolean it became (None: quoted); None when no bare word starts there."""
    whole = _WHOLE_VALUE.fullmatch(line)
    if whole is not None and whole.start("value") == column:  # key = "the whole value"
        word, before, after = whole["value"], f"{whole['key']} = ", ""
    else:
        token = _BARE_WORD.match(line, column)
        if token is None:
            return None
        word, before, after = token[0], line[:column].lstrip(), line[token.end():].rstrip()
    boolean = _BOOLEAN_WORDS.get(word.lower())
    return f"{before}{boolean if boolean is not None else chr(34) + word + chr(34)}{after}", \
        word, boolean


def load_rig_spec(path: str | Path) -> RigSpec:
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise RigConfigError(source, "", f"cannot read rig file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise RigConfigError(source, "", not_utf8(exc)) from None
    return parse_rig_spec(text, source)


def parse_rig_spec(text: str, source: str = "<rig>") -> RigSpec:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RigConfigError(source, "", not_toml(exc, text)) from None
    if {"scenario", "step"} & set(data) and not DEVICE_KEYS & set(data):
        # The other kind of file, not a broken rig: "did you mean 'servo'?" misled
        raise RigConfigError(source, "", "a scenario file, not a rig file (a rig file has "
                                         "[rig] and device tables: docs/rig-file.md); play it "
                                         "with: python -m app scenario run FILE")
    top = _Table(source, "", data)
    rig = _Table(source, "rig", top.get("rig", dict, {}))
    name = rig.get("name", str, "rig")
    seed = rig.get("seed", int, 0, _in_range(0, 2**63 - 1))
    step_ms = rig.get("step_ms", float, 1.0, _in_range(0.1, 100))
    epoch_text = rig.get("epoch", (str, dt.datetime), None)
    rig.finish()
    epoch = RigSpec.epoch
    if isinstance(epoch_text, dt.datetime):
        epoch = epoch_text.replace(tzinfo=None)
    elif epoch_text is not None:
        try:
            epoch = dt.datetime.fromisoformat(epoch_text)
        except ValueError:
            raise RigConfigError(source, "rig.epoch", f"not an ISO date-time: {epoch_text!r}") \
                from None
    master = _Table(source, "master", top.get("master", dict, {}))
    retry_s = master.get("retry_interval_s", float, 2.0, _in_range(0.01, 3600))
    line = master.get("line", list, None)
    eni = master.get("eni", str, None)
    mapping = master.get("mapping", str, None)
    master.finish()
    fastcats = tuple(_fastcat(source, i, t)
                     for i, t in enumerate(top.get("fastcat", list, [])))
    servos = tuple(_servo(source, i, t) for i, t in enumerate(top.get("servo", list, [])))
    slaves = tuple(_slave(source, kind, i, t) for kind in _SLAVE_KEYS
                   for i, t in enumerate(top.get(kind, list, [])))
    top.finish()
    keyed = [(f"fastcat[{i}].id", f.id) for i, f in enumerate(fastcats)]
    keyed += [(f"servo[{i}].id", s.id) for i, s in enumerate(servos)]
    keyed += [(f"{s.kind}.id", s.id) for s in slaves]
    seen: set[str] = {"master", "scenario"} | {f"{s.id}-can" for s in servos} | \
        {f"{s.id}-ecat" for s in servos}
    for key, device_id in keyed:
        if device_id in seen:
            raise RigConfigError(source, key, f"duplicate or reserved device id {device_id!r}")
        seen.add(device_id)
    _check_flash_files(source, fastcats, servos)
    modbus_nodes = [(i, s.settings.get("node_id", 1)) for i, s in enumerate(servos)
                    if s.settings.get("fieldbus", "modbus") == "modbus"]
    for j, (i, node) in enumerate(modbus_nodes):
        if node in [n for _, n in modbus_nodes[:j]]:
            raise RigConfigError(source, f"servo[{i}].node_id",
                                 f"node {node} is already used on the Modbus line")
    # A drive whose rig file says fieldbus = "ethercat" is cabled into the line (its CoE slave);
    # every drive keeps its CANopen node, silent unless c9 chose CANopen at power-up.
    on_line = [f.id for f in fastcats] + [s.id for s in slaves] + [
        f"{s.id}-ecat" for s in servos if s.settings.get("fieldbus") == "ethercat"]
    if line is None:
        line = on_line
    else:
        for j, device_id in enumerate(line):
            if device_id not in on_line:
                raise RigConfigError(source, f"master.line[{j}]",
                                     f"{device_id!r} is not an EtherCAT slave of this rig "
                                     f"(slaves: {', '.join(on_line) or 'none'})"
                                     f"{did_you_mean(device_id, on_line)}")
        if sorted(line) != sorted(on_line):
            missing = sorted(set(on_line) - set(line)) or sorted(line)
            raise RigConfigError(source, "master.line",
                                 f"must name every EtherCAT slave once ({', '.join(missing)})")
    return RigSpec(source=source, name=name, seed=seed, step_us=round(step_ms * 1000),
                   epoch=epoch, retry_interval_us=round(retry_s * 1e6), fastcats=fastcats,
                   servos=servos, slaves=slaves, line=tuple(line), eni=eni, mapping=mapping)


def _check_flash_files(source: str, fastcats: Sequence[FastCatSpec],
                       servos: Sequence[ServoSpec]) -> None:
    """A flash file holds one device's image (app/flash_file.py): two devices on one file
    overwrote each other's saved settings, and both read the image saved last at start-up."""
    owners: dict[str, str] = {}
    keyed = [(f"fastcat[{i}]", f.flash) for i, f in enumerate(fastcats)]
    keyed += [(f"servo[{i}]", s.flash) for i, s in enumerate(servos)]
    for key, flash in keyed:
        if flash == MEMORY:
            continue
        path = os.path.normpath(flash)
        if path in owners:
            raise RigConfigError(source, f"{key}.flash",
                                 f"{flash!r} is {owners[path]}'s flash file too: two devices "
                                 "would overwrite each other's saved settings (give each its "
                                 f'own file, or "{MEMORY}")')
        owners[path] = key


def _fastcat(source: str, i: int, data: Any) -> FastCatSpec:
    from devices.fastcat.catalog import CATALOG

    t = _Table(source, f"fastcat[{i}]", data)
    device_id = t.get("id", str, "fastcat" if i == 0 else _REQUIRED, _id_problem)
    modules_raw = t.get("modules", list, _REQUIRED)
    if len(modules_raw) > MAX_MODULES:
        raise RigConfigError(source, t.key("modules"),
                             f"{len(modules_raw)} modules: a FastCAT takes at most "
                             f"{MAX_MODULES} (seed 000 §2)")
    modules = []
    for j, raw in enumerate(modules_raw):
        key = f"{t.key('modules')}[{j}]"
        if isinstance(raw, str):
            mtype, options = raw, {}
        elif isinstance(raw, Mapping):
            options = dict(raw)
            mtype = options.pop("type", None)
            if not isinstance(mtype, str):
                raise RigConfigError(source, key, "a module table needs type = \"<name>\"")
        else:
            raise RigConfigError(source, key, f"must be a module name or a table, got {raw!r}")
        if mtype not in CATALOG:
            raise RigConfigError(source, key, f"unknown module type {mtype!r} "
                                              f"(known: {', '.join(CATALOG)})"
                                              f"{did_you_mean(mtype, CATALOG)}")
        modules.append(ModuleSpec(mtype, options))
    spec = FastCatSpec(
        id=device_id,
        modules=tuple(modules),
        rotary_switch=t.get("rotary_switch", int, 1, _in_range(1, 15)),
        master_address=t.get("master_address", int, 1, _in_range(1, 15)),
        flash=t.get("flash", str, MEMORY),
        box_name=t.get("box_name", str, ""),
    )
    t.finish()
    return spec


# Keys a rig file may give each slave kind, with their TOML types (constructor keywords).
_SLAVE_KEYS: dict[str, dict[str, type | tuple[type, ...]]] = {
    "trscat": {"expansions": list, "sync_mode": str, "configured": list,
               "field_supply_v": float, "box_name": str},
    "cpx": {"modules": list, "rotary_switch": int, "dil1": bool, "dil2": bool,
            "history_flags": int, "box_name": str},
}
# A rig file's top-level tables: a file with none of them and a [scenario] is a scenario.
DEVICE_KEYS = frozenset({"rig", "master", "fastcat", "servo", *_SLAVE_KEYS})


def _slave(source: str, kind: str, i: int, data: Any) -> SlaveSpec:
    t = _Table(source, f"{kind}[{i}]", data)
    device_id = t.get("id", str, kind if i == 0 else _REQUIRED, _id_problem)
    settings = {key: t.get(key, kinds) for key, kinds in _SLAVE_KEYS[kind].items()
                if key in t.data}
    t.used.update(_SLAVE_KEYS[kind])
    t.finish()
    if kind == "cpx" and "history_flags" in settings:
        from devices.cpx.history import flags_error

        wrong = flags_error(settings["history_flags"])
        if wrong is not None:
            raise RigConfigError(source, f"{kind}[{i}].history_flags", wrong)
    if kind == "trscat" and "configured" in settings:
        from devices.trscat.catalog import expansion_list

        try:
            expansion_list(settings["configured"], "configured expansion")
        except ValueError as exc:
            raise RigConfigError(source, f"{kind}[{i}].configured", str(exc)) from None
    return SlaveSpec(kind, device_id, settings)


def _servo(source: str, i: int, data: Any) -> ServoSpec:
    import dataclasses

    from devices.servo.config import DriveConfig

    t = _Table(source, f"servo[{i}]", data)
    device_id = t.get("id", str, "drive" if i == 0 else _REQUIRED, _id_problem)
    flash = t.get("flash", str, MEMORY)
    settings: dict[str, Any] = {}
    for f in dataclasses.fields(DriveConfig):
        default = f.default if f.default is not dataclasses.MISSING else None
        if isinstance(default, bool):
            kind: type | tuple[type, ...] = bool
        elif isinstance(default, float):
            kind = float
        elif isinstance(default, int):
            kind = int
        elif isinstance(default, str):
            kind = str
        else:
            kind = dict
        if f.name in t.data:
            settings[f.name] = t.get(f.name, kind)
        else:
            t.used.add(f.name)
    if "registers" in settings:
        try:
            settings["registers"] = {int(k): v for k, v in settings["registers"].items()}
        except ValueError:
            raise RigConfigError(source, t.key("registers"),
                                 "keys are register numbers (\"2\" = R02)") from None
    t.finish()
    try:
        DriveConfig(**settings)
    except (ValueError, TypeError) as exc:
        raise RigConfigError(source, f"servo[{i}]", str(exc)) from None
    return ServoSpec(device_id, settings, flash)


def _flash(spec_flash: str, state_dir: Path | None) -> FlashStore:
    if spec_flash == MEMORY or state_dir is None:
        return MemoryFlash()
    path = Path(spec_flash)
    return FileFlash(path if path.is_absolute() else state_dir / path)


def _build_slave(spec: RigSpec, slave: SlaveSpec, rng: random.Random, position: int,
                 last: bool) -> DeviceModel:
    from devices.cpx.device import CpxEEc
    from devices.trscat.device import TrsCat

    settings = dict(slave.settings)
    try:
        if slave.kind == "trscat":
            settings.setdefault("box_name", f"Box {position} (TRS-CAT)")
            settings.pop("configured", None)  # the master's 0xF030 list (app/network/startup)
            return TrsCat(slave.id, rng, out_link=not last, station_address=1000 + position,
                          **settings)
        settings.setdefault("box_name", f"Box {position} (CPX-E-EC)")
        settings.pop("history_flags", None)  # the master's start-up write (app/network/startup)
        modules: list[Any] = []
        for j, m in enumerate(settings.pop("modules", [])):
            if isinstance(m, str):
                modules.append(m)
            elif isinstance(m, Mapping) and isinstance(m.get("type"), str):
                modules.append((m["type"], {k: v for k, v in m.items() if k != "type"}))
            else:
                raise RigConfigError(spec.source, f"{slave.kind}.modules[{j}]",
                                     f"must be a module name or a table with type, got {m!r}")
        return CpxEEc(slave.id, rng, modules=modules, out_connected=not last,
                      station_address=1000 + position, **settings)
    except (ValueError, TypeError) as exc:
        raise RigConfigError(spec.source, slave.kind, str(exc)) from None


def _with_rig_commands(spec: RigSpec, descriptions: list[SlaveDescription] | None,
                       dc: list[bool]) -> list[SlaveDescription | None] | None:
    from app.network.startup import StartupConflict, rig_commands, with_rig_commands

    commands = rig_commands([(s.kind, s.id, s.settings) for s in spec.slaves])
    try:
        return with_rig_commands(descriptions, spec.line, commands, dc, spec.eni)
    except StartupConflict as exc:
        raise RigConfigError(spec.source, exc.key, exc.reason) from None


def build_rig(spec: RigSpec, state_dir: str | Path | None = None) -> Rig:
    """Construct the device models of a checked spec; model refusals become RigConfigError.

    ``state_dir=None`` (the default) keeps every flash in memory: a scenario run or a test then
    starts from the same factory state every time, whatever earlier runs stored. The served
    dashboard passes ``--state-dir`` so that a stored configuration survives a restart.
    """
    from devices.coe.drive_slave import DriveEcatSlave
    from devices.fastcat.coupler import FastCat
    from devices.master import EtherCatMaster

    state = Path(state_dir) if state_dir is not None else None
    rng = random.Random(spec.seed)
    devices: dict[str, DeviceModel] = {}
    slaves: dict[str, Any] = {}
    for i, fc in enumerate(spec.fastcats):
        position = spec.line.index(fc.id) + 1
        try:
            device = FastCat(
                fc.id, random.Random(rng.getrandbits(64)),
                modules=[(m.type, dict(m.options)) for m in fc.modules],
                rotary_switch=fc.rotary_switch, flash=_flash(fc.flash, state),
                master_address=fc.master_address,
                box_name=fc.box_name or f"Box {position} (FastCAT)",
                station_address=1000 + position)
        except ValueError as exc:
            raise RigConfigError(spec.source, f"fastcat[{i}]", str(exc)) from None
        devices[fc.id] = device
        slaves[fc.id] = device
    for slave in spec.slaves:
        position = spec.line.index(slave.id) + 1
        devices[slave.id] = slaves[slave.id] = _build_slave(
            spec, slave, random.Random(rng.getrandbits(64)), position,
            last=position == len(spec.line))
    for servo in spec.servos:
        from devices.canopen.node import CanOpenNode
        from devices.servo.config import DriveConfig
        from devices.servo.drive import ServoDrive

        drive = ServoDrive(servo.id, random.Random(rng.getrandbits(64)),
                           DriveConfig(**servo.settings), _flash(servo.flash, state))
        devices[servo.id] = drive
        # The drive's CANopen side: silent unless c9 chose CANopen at the drive's power-up,
        # so a trainee who sets c9 = 5, saves and power-cycles sees the node boot.
        can_id = f"{servo.id}-can"
        devices[can_id] = CanOpenNode(can_id, drive, random.Random(rng.getrandbits(64)))
        ecat_id = f"{servo.id}-ecat"
        if ecat_id in spec.line:
            position = spec.line.index(ecat_id) + 1
            # A string seed: adding a drive to the line leaves every other device's draws.
            devices[ecat_id] = slaves[ecat_id] = DriveEcatSlave(
                ecat_id, drive, random.Random(f"{spec.seed}/{ecat_id}"),
                box_name=f"Drive {position} (SelemaDriveECAT)", station_address=1000 + position,
                out_link=position < len(spec.line))
    if slaves:
        from app.network.files import load_description, load_mapping, uses_dc

        described = load_description(spec.source, spec.eni, spec.line) if spec.eni else None
        mapping = load_mapping(spec.source, spec.mapping, described, len(spec.line)) \
            if spec.mapping else None
        descriptions = _with_rig_commands(
            spec, described, [uses_dc(slaves[device_id]) for device_id in spec.line])
        if mapping is not None and mapping.parameters.cycle_us % spec.step_us:
            raise RigConfigError(spec.source, "master.mapping", f"cycle time "
                                 f"{mapping.parameters.cycle_us} us is not a multiple of the "
                                 f"rig step ({spec.step_us} us)")
        devices["master"] = EtherCatMaster(
            "master", random.Random(rng.getrandbits(64)),
            slaves=[slaves[device_id] for device_id in spec.line],
            retry_interval_us=spec.retry_interval_us, epoch=spec.epoch,
            descriptions=descriptions, mapping=mapping,
            dc_slaves=[uses_dc(slaves[device_id]) for device_id in spec.line],
            step_us=spec.step_us)
    return Rig(name=spec.name, devices=devices, clock=SimClock(step_us=spec.step_us),
               seed=spec.seed)
