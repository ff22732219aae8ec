"""Reading a rig's network description and mapping files (``[master] eni`` / ``mapping``).

Paths are relative to the rig file. The description must name the line's slaves in line order
(``<Device>`` = the rig's device id); a slave that is not on the line, or a line slave the
description leaves out, is a :class:`~app.rig_config.RigConfigError` naming the file and the
element. An identity that differs from the slave's 0x1018 is not an error here: the master
finds it at start-up, logs it and leaves the slave in PREOP, as a real master does.
"""

from __future__ import annotations

import codecs
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from devices.master.network import (
    Mapping,
    NetworkFileError,
    SlaveDescription,
    check_mapping,
    parse_eni,
    parse_mapping,
)

CPX_DC_MODULES = ("CPX-E-16DI", "CPX-E-8DO", "CPX-E-1CI")  # seed 002 §2.1.4
MAX_BYTES = 4_000_000  # a network file larger than this is not a description


def uses_dc(device: Any) -> bool:
    """DC use of a slave model when no description says it: the TRS-CAT set up for DC-SYNC
    (its rig ``sync_mode``, the master's option of seed 001 §9.3; SYNC0 activated makes it
    DC-SYNC at PS, §9.1.1), the CPX-E-EC with a module that runs synchronously (seed 002
    §2.1.4)."""
    if device.KIND == "trscat":
        from devices.trscat.sync import SyncMode

        return device.master_sync_mode is SyncMode.DC_SYNC
    if device.KIND == "cpx_e_ec":
        return any(m.mtype.name.startswith(CPX_DC_MODULES) for m in device.modules)
    return False


# The encoding an XML declaration names (XML 1.0 §4.3.3): TwinCAT and other configurators
# often write ENI / ESI files as ISO-8859-1 and say so there.
_DECLARED = re.compile(rb"<\?xml[^>]*?encoding\s*=\s*[\"']([A-Za-z][A-Za-z0-9._-]*)[\"']")


def decode_xml(data: bytes) -> str:
    """The text of an XML file as its parser would read it: a UTF-16 or UTF-8 byte order mark,
    else the declared encoding, else UTF-8. LookupError for an encoding Python lacks,
    UnicodeDecodeError for bytes that are not in it."""
    if data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return data.decode("utf-16")
    if data.startswith(codecs.BOM_UTF8):
        data = data[len(codecs.BOM_UTF8):]
    declared = _DECLARED.match(data)
    return data.decode(declared.group(1).decode("ascii") if declared else "utf-8")


def _read(path: Path, rig_source: str, key: str) -> str:
    from app.rig_config import RigConfigError, not_utf8

    try:
        if path.stat().st_size > MAX_BYTES:
            raise RigConfigError(str(path), "", f"larger than {MAX_BYTES} bytes")
        return decode_xml(path.read_bytes())
    except OSError as exc:
        raise RigConfigError(rig_source, key, f"cannot read {path}: "
                                              f"{exc.strerror or exc}") from None
    except LookupError as exc:
        raise RigConfigError(str(path), "", f"declares an encoding Python does not know: "
                                            f"{exc}") from None
    except UnicodeDecodeError as exc:
        utf8 = exc.encoding.replace("-", "").lower() in ("utf8", "utf8sig")
        raise RigConfigError(str(path), "", not_utf8(exc, None if utf8 else exc.encoding)) \
            from None


def resolve(rig_source: str, name: str) -> Path:
    path = Path(name)
    return path if path.is_absolute() else Path(rig_source).resolve().parent / path


def load_description(rig_source: str, eni: str, line: Sequence[str]) -> list[SlaveDescription]:
    from app.rig_config import RigConfigError

    path = resolve(rig_source, eni)
    try:
        slaves = parse_eni(_read(path, rig_source, "master.eni"))
    except NetworkFileError as exc:
        raise RigConfigError(str(path), exc.element, exc.reason) from None
    for s in slaves:
        where = f"Config/Slave[{s.position}]/Info/Device"
        if s.device not in line:
            raise RigConfigError(str(path), where, f"{s.device!r} is not a slave on the "
                                 f"line (line: {', '.join(line)})")
        if line.index(s.device) != s.position:
            raise RigConfigError(str(path), where, f"{s.device!r} is at line position "
                                 f"{line.index(s.device)}, the description has it at "
                                 f"{s.position}")
    if len(slaves) != len(line):
        missing = ", ".join(line[len(slaves):])
        raise RigConfigError(str(path), "Config", f"describes {len(slaves)} slaves, the line "
                                                  f"has {len(line)} (missing: {missing})")
    return list(slaves)


def load_mapping(rig_source: str, mapping: str,
                 slaves: Sequence[SlaveDescription] | None, line_length: int) -> Mapping:
    from app.rig_config import RigConfigError

    path = resolve(rig_source, mapping)
    try:
        parsed = parse_mapping(_read(path, rig_source, "master.mapping"))
        if slaves is not None:
            check_mapping(parsed, tuple(slaves))
        else:
            for j, var in enumerate(parsed.variables):
                if not 0 <= var.position < line_length:
                    raise NetworkFileError(f"Variables/Variable[{j}]@Slave",
                                           f"no slave at position {var.position}")
    except NetworkFileError as exc:
        raise RigConfigError(str(path), exc.element, exc.reason) from None
    return parsed
