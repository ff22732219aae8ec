"""Faults an operator or a scenario can inject into the CPX-E-EC by name, with the seed section
each one comes from. Faults with a physical cause (short circuit, wire break, undervoltage)
set that physical condition, exactly as the physical actions do; the others are conditions of
the bus module or of its EtherCAT side. Cause -> code mapping: docs/cpx-e-ec.md.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from devices.device import CommandError
from devices.names import did_you_mean
from devices.sync_managers import SmFault


class Target(enum.Enum):
    DEVICE = "device"  # the bus module
    MODULE = "module"  # an I/O module, target "cpx/N"
    CHANNEL = "channel"  # an I/O module's channel: "cpx/N" and channel=
    SYNC_MANAGER = "sync manager"  # sm= 0 ... 3


@dataclass(frozen=True)
class FaultSpec:
    name: str
    target: Target
    seed: str
    doc: str
    channel: bool = False  # a channel= says which channel (optional for short_circuit)


FAULTS: dict[str, FaultSpec] = {f.name: f for f in (
    FaultSpec("short_circuit", Target.MODULE, "§2.5.3 Tab. 21-23",
              "Output short circuit (channel=, KZA; seen while the output is on) or, without "
              "channel, the module's sensor supply (KZS)", channel=True),
    FaultSpec("wire_break", Target.CHANNEL, "§2.5.3 Tab. 21-23",
              "Broken wire on a channel (analog 4-20 mA inputs, current outputs, the 1CI)",
              channel=True),
    FaultSpec("undervoltage_out", Target.DEVICE, "§2.5.3 Tab. 21 0x3320",
              "U_OUT below tolerance: output modules report undervoltage, outputs off"),
    FaultSpec("undervoltage_el_sen", Target.DEVICE, "§2.5.3 Tab. 21 0x3120, Tab. 29",
              "U_EL/SEN below 24 V - 25 %: the bus module reports undervoltage"),
    FaultSpec("module_failure", Target.MODULE, "§2.5.3 Tab. 21 0x5000",
              "The module's hardware fails (CPX error above 128)"),
    FaultSpec("module_ident_mismatch", Target.MODULE, "§2.5.2 Tab. 17 0x3800",
              "The PLC's configured module differs from the detected one: PREOP -> SAFEOP "
              "is refused (without a module: the bus module, slot 1)"),
    FaultSpec("f030_not_written", Target.DEVICE, "§2.5.2 Tab. 17 0x3801",
              "The PLC does not write 0xF030: the ident check is skipped"),
    FaultSpec(SmFault.ADDRESS.value, Target.SYNC_MANAGER, "§2.5.2 Tab. 17 0x0011",
              "The master configures sync manager sm= with an invalid address"),
    FaultSpec(SmFault.SIZE.value, Target.SYNC_MANAGER, "§2.5.2 Tab. 17 0x0012",
              "The master configures sync manager sm= with an invalid size"),
    FaultSpec(SmFault.SETTINGS.value, Target.SYNC_MANAGER, "§2.5.2 Tab. 17 0x0013",
              "The master configures sync manager sm= with invalid settings"),
    FaultSpec("bus_cycle_time", Target.DEVICE, "§2.5.2 Tab. 17 0x000F",
              "The local timer is too slow to measure the bus cycle (a warning at "
              "PREOP -> SAFEOP)"),
    FaultSpec("watchdog", Target.DEVICE, "§2.4.1 Tab. 12 double flash",
              "Process data no longer reach the application: the Sync Manager watchdog "
              "takes OP to SAFEOP"),
    FaultSpec("sync_error", Target.DEVICE, "§2.4.1 Tab. 12 single flash",
              "Sync events are missed: OP -> SAFEOP with a sync error"),
    FaultSpec("ac_failure", Target.DEVICE, "§2.4.1 Tab. 12 red on",
              "The application controller stops answering (nothing is diagnosed); clearing "
              "it restarts the module"),
    FaultSpec("booting_error", Target.DEVICE, "§2.4.1 Tab. 12 flickering",
              "Flash checksum error of the application controller, found at the next start"),
)}

SM_FAULT_TEXT = {SmFault.ADDRESS: 0x0011, SmFault.SIZE: 0x0012,
                 SmFault.SETTINGS: 0x0013}  # Tab. 17 Text-IDs
SYNC_MANAGERS = range(4)  # SM0/SM1 mailbox, SM2 outputs, SM3 inputs


@dataclass(frozen=True)
class Injected:
    name: str
    module: int | None = None
    channel: int | None = None
    sm: int | None = None

    def label(self) -> str:
        where = [f"module {self.module}" if self.module is not None else "",
                 f"channel {self.channel}" if self.channel is not None else "",
                 f"SM{self.sm}" if self.sm is not None else ""]
        return " ".join([self.name, *[w for w in where if w]])

    def entry(self) -> dict[str, str | int | None]:
        """The snapshot's form, as the TRS-CAT's: a reader matches a fault by its name and
        where it sits without parsing :meth:`label`."""
        return {"fault": self.name, "module": self.module, "channel": self.channel,
                "sm": self.sm}


class ModuleState(Protocol):
    """What of an I/O module (devices/cpx/modules.py CpxModule) the physical faults set."""

    number: int
    failed: bool
    sensor_supply_short: bool
    shorted: set[int]
    wire_broken: set[int]


def held(injected: Sequence[Injected], modules: Sequence[ModuleState]) -> list[Injected]:
    """The named faults the device has now: those kept as injected, then those that set a
    module's condition (module_failure, short_circuit, wire_break), which live on the module
    only: without them a failed module read as no fault (an exercise's fault_gone)."""
    physical = [
        *(Injected("module_failure", m.number) for m in modules if m.failed),
        *(Injected("short_circuit", m.number) for m in modules if m.sensor_supply_short),
        *(Injected("short_circuit", m.number, c) for m in modules for c in sorted(m.shorted)),
        *(Injected("wire_break", m.number, c) for m in modules for c in sorted(m.wire_broken))]
    return [*injected, *physical]


def fault_spec(name: str) -> FaultSpec:
    spec = FAULTS.get(name.strip().lower())
    if spec is None:
        raise CommandError(f"unknown fault {name!r} (known: {', '.join(FAULTS)})"
                           f"{did_you_mean(name.strip(), FAULTS)}")
    return spec


def check_target(spec: FaultSpec, module: int | None, channel: int | None,
                 sm: int | None) -> None:
    """The fault's target as the seed's diagnosis would name it; CommandError if not, also
    for an argument the fault has no use for (refused, not ignored)."""
    if spec.target in (Target.DEVICE, Target.SYNC_MANAGER) and module is not None:
        raise CommandError(f"{spec.name} is a fault of the bus module: target the device")
    if channel is not None and not spec.channel:
        with_channel = " and ".join(f.name for f in FAULTS.values() if f.channel)
        raise CommandError(f"{spec.name} takes no channel (only {with_channel} name one)")
    if spec.target is Target.CHANNEL and (module is None or channel is None):
        raise CommandError(f"{spec.name} needs a module and a channel: target 'cpx/N' with "
                           f"channel=")
    if spec.target is Target.SYNC_MANAGER:
        if sm is None or sm not in SYNC_MANAGERS:
            raise CommandError(f"{spec.name} needs sm= 0 ... 3 (SM0/SM1 mailbox, SM2 "
                               f"outputs, SM3 inputs)")
    elif sm is not None:
        raise CommandError(f"{spec.name} takes no sync manager")
    if spec.name in ("module_failure", "short_circuit") and module is None:
        # module_ident_mismatch alone has a meaning without a module (the bus module)
        raise CommandError(f"{spec.name} needs a module: target 'cpx/N'")
