"""The physical facts behind the FastCAT's alarm causes, and the rail against flash, for views.

The cause search (faults.py) gives alarm codes; a technician at the rail wants the fact behind
each one: a slot empty that the last scan found (§7.5 0x04), a module of another type than the
scan found there (0x01), the last scan against flash (0x01 / 0x02 / 0x10), the cable (0x13),
the Tbus supply (§7.6 0x0C), a module's own alarm. This module words them from the coupler's
state and compares the rail as a scan would find it now with flash and with the last scan
(seed 000 §2, §3), and names the module that belongs in an empty slot. Read-only: nothing
here changes the coupler.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from devices.fastcat.alarms import COUPLER, MODULE, Alarm
from devices.fastcat.catalog import a_module

if TYPE_CHECKING:
    from devices.fastcat.coupler import FastCat

LOW_VOLTAGE = (MODULE, 0x0C)  # §7.6: reported only with a module scanned


def first_difference(a: Sequence[Any], b: Sequence[Any]) -> int | None:
    """The first module number (from 1) where two module lists differ; None if equal."""
    for i in range(max(len(a), len(b))):
        if i >= len(a) or i >= len(b) or a[i] != b[i]:
            return i + 1
    return None


def cause_facts(fc: FastCat) -> list[dict[str, Any]]:
    """Every cause present now (report order), what it is on the rail, whether an
    instructor injected it and whether it is the latched alarm's (§7: the first one is
    signalled, a later one waits for a reset). Tbus low with no module scanned raises
    nothing but is a fact."""
    out = []
    for alarm in dict.fromkeys(fc._present_causes()):
        out.append({"table": alarm.table, "code": alarm.code, "name": alarm.info.symbol,
                    "module": alarm.module, "injected": alarm in fc.injected,
                    "latched": alarm == fc.alarm, "text": _fact(fc, alarm)})
    if fc.tbus_low and not any((c["table"], c["code"]) == LOW_VOLTAGE for c in out):
        out.append({"table": None, "code": None, "name": "", "module": 0, "injected": False,
                    "latched": False, "text": "Tbus supply low"})
    return out


def config_view(fc: FastCat) -> dict[str, Any]:
    """The rail as a scan would find it now (slot, type per module number), and the first
    module number where it differs from flash and from the last scan (only while a last scan
    stands: powered, booted, no scan running), with the fact at the rail there
    (``vs_scan_text``)."""
    now = [(slot, m.mtype.name) for slot, m in enumerate(fc.rail, start=1)
           if m is not None and m.responds()]
    names = [name for _slot, name in now]
    scan_stands = fc.powered and fc.booted and fc.scan is None
    vs_scan = first_difference(fc.detected, now) if scan_stands else None
    out: dict[str, Any] = {
        "now": [list(entry) for entry in now],
        "vs_flash": None if fc.stored is None else first_difference(fc.stored, names),
        "vs_scan": vs_scan}
    if vs_scan is not None:
        out["vs_scan_text"] = since_scan(fc, vs_scan, now)
    return out


def since_scan(fc: FastCat, n: int, now: Sequence[tuple[int, str]]) -> str:
    """What changed at module ``n`` since the last scan, said at the rail: a trainee read
    "last scan older than the rail: it found DO16 as module 3" and did not see that module 3
    was switched off. The scan is seed 000's: the coupler scans the Tbus at a CNF press (§2)
    and whenever it returns to Init (§3), and numbers the modules it finds."""
    t_us = fc.detected_us if fc.detected_us is not None else 0
    scan = f"the last scan (at t = {round(t_us / 1000) / 1000:g} s)"
    found = fc.detected[n - 1] if n <= len(fc.detected) else None
    here = now[n - 1] if n <= len(now) else None
    if here is not None and (found is None or here[0] < found[0]):  # a module the scan missed
        return (f"slot {here[0]} holds {a_module(here[1])} that {scan} did not find (it "
                f"would be module {n})")
    if found is None:  # n where neither list has a module: no difference to word
        return f"{scan} found no module {n}"
    slot, name = found
    module = fc.rail[slot - 1] if slot <= len(fc.rail) else None
    if module is None:
        return f"slot {slot} empty: {scan} found {a_module(name)} there (module {n})"
    if module.mtype.name != name:
        return (f"slot {slot} holds {a_module(module.mtype.name)}: {scan} found "
                f"{a_module(name)} there (module {n})")
    if not module.powered:
        return f"module {n} not powered (its supply is off): {scan} found {a_module(name)} " \
               f"in slot {slot}"
    return f"module {n} does not answer: {scan} found {a_module(name)} in slot {slot}"


def _fact(fc: FastCat, alarm: Alarm) -> str:
    if alarm in fc.injected:
        return "injected"
    n, key = alarm.module, (alarm.table, alarm.code)
    scanned = fc.detected[n - 1] if 0 < n <= len(fc.detected) else None
    if key == (COUPLER, 0x13):
        return "EtherCAT cable out"
    if key == (COUPLER, 0x11):
        return "the configuration could not be written to flash"
    if key == (COUPLER, 0x10):
        return "the last scan found no module"
    if key == (COUPLER, 0x04) and scanned is not None:
        return _silent(fc, n, *scanned)
    if key == (COUPLER, 0x01):
        return "; ".join(_changed(fc, n, scanned)) or alarm.info.description
    if key == (COUPLER, 0x02) and fc.stored is not None:
        return (f"flash has {len(fc.stored)} modules, the last scan found {len(fc.detected)}: "
                f"module {n} ({fc.stored[n - 1]}) missing")
    if key == (COUPLER, 0x12) and fc.wire_station is not None:
        return (f"rotary switch read {fc.rotary_read} at power-up, the wire master's station "
                f"address (0x0010) is {fc.wire_station}")
    if key == (COUPLER, 0x12):
        return (f"rotary switch read {fc.rotary_read} at power-up, the master's address is "
                f"{fc.master_address}")
    if key == (COUPLER, 0x14):
        return f"the master's 0xF030:{n} is not the module found (0xF050:{n})"
    if key == LOW_VOLTAGE:
        return "Tbus supply low"
    if alarm.table == MODULE and scanned is not None:
        return f"module {n} ({scanned[1]}, slot {scanned[0]}): {alarm.info.description}"
    return alarm.info.description


def _silent(fc: FastCat, n: int, slot: int, name: str) -> str:
    module = fc.rail[slot - 1] if slot <= len(fc.rail) else None
    if module is None:
        return f"slot {slot} empty (module {n}: the last scan found {a_module(name)} there)"
    if not module.powered:
        return f"module {n} ({name}, slot {slot}) does not answer: its supply is off"
    return f"module {n} ({name}, slot {slot}) does not answer"


def _changed(fc: FastCat, n: int, scanned: tuple[int, str] | None) -> list[str]:
    """0x01 has two sources: the last scan against flash, a module now against the scan."""
    out = []
    stored = fc.stored
    if scanned is not None and stored is not None \
            and (n > len(stored) or stored[n - 1] != scanned[1]):
        flash = stored[n - 1] if n <= len(stored) else "no module"
        out.append(f"the last scan found {a_module(scanned[1])} as module {n}, flash has {flash}")
    if scanned is not None:
        slot, name = scanned
        module = fc.rail[slot - 1] if slot <= len(fc.rail) else None
        if module is not None and module.mtype.name != name:
            out.append(f"slot {slot} holds {a_module(module.mtype.name)}, the last scan "
                       f"found {a_module(name)} there (module {n})")
    return out


def expected_in_slot(fc: FastCat, slot: int) -> tuple[str | None, str | None]:
    """(type, "flash" | "last scan") of the module that belongs in an empty slot. Flash
    counts modules, not slots: this slot is module k + 1 when k slots before it hold a module
    now or held one at the last scan (the ones pulled since count: they belong there too)."""
    scanned = dict(fc.detected)
    if fc.stored is not None:
        k = sum(1 for s in range(1, slot)
                if (s <= len(fc.rail) and fc.rail[s - 1] is not None) or s in scanned)
        if k < len(fc.stored):
            return fc.stored[k], "flash"
    if slot in scanned:
        return scanned[slot], "last scan"
    return None, None
