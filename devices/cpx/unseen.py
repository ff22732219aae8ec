"""What a module has wired but the bus module does not diagnose now, and why.

A module snapshot's "undiagnosed" (docs/cpx-e-ec.md choice 30): each wired cause (a short
circuit, a broken wire, a shorted sensor supply, a failed module; seed 002 Tab. 21-23) that
the diagnosis does not hold, with its channels and the reason the model finds in its own
state. It names what the device does not report, so it is the instructor's part of the
snapshot (docs/classroom.md); a dashboard only puts the reason into words.
"""

from __future__ import annotations

from collections.abc import Collection

from devices.cpx.modules import CpxModule, Monitors

# Reason ids, in the order they are asked: the first that holds is the one given. The
# physics first (with it nothing could be seen, whatever is switched on), then what keeps the
# bus module from reporting what the module would see.
UNSEEN_REASONS: dict[str, str] = {
    "output_off": "a digital output switched off draws no current into its short",
    "current_range": "an analog output in a current range limits its current: no short",
    "no_load_supply": "U_OUT (the load supply) is out of tolerance: an output without it is "
                      "not energised, so no current flows into its short or through its "
                      "open loop (choice 38)",
    "signal_range": "a broken wire shows only on a 4-20 mA input, a current output, the 1CI",
    "no_application": "the application controller does not run (unpowered, bootloader, AC "
                      "failure, booting error): nothing is diagnosed",
    "module_failed": "a failed module reports its failure only (0x5000)",
    "monitor_off": "monitoring switched off: 0x2400:2 Monitor SCS (sensor supply), 0x2400:3 "
                   "Monitor SCO (outputs), Tab. 27",
    "pending": "wired since the last diagnosis: the next step reports it",
}
# The order of the causes in the list (each cause's groups in the order of UNSEEN_REASONS).
WIRED_ORDER = ("short_circuit_outputs", "wire_break", "short_circuit_sensor_supply",
               "module_failure")

Wired = tuple[str, int | None]


def wired(module: CpxModule) -> list[Wired]:
    """The causes wired on ``module`` now, (cause, channel) pairs."""
    return [*(("short_circuit_outputs", c) for c in sorted(module.shorted)),
            *(("wire_break", c) for c in sorted(module.wire_broken)),
            *([("short_circuit_sensor_supply", None)] if module.sensor_supply_short else []),
            *([("module_failure", None)] if module.failed else [])]


def _physics(module: CpxModule, cause: str, channel: int | None,
             load_supply: bool) -> str | None:
    if cause == "short_circuit_outputs" and channel is not None and \
            channel < len(module.commanded):
        if not module.short_bites(channel):
            return "current_range" if module.mtype.analog_ranges else "output_off"
        if not load_supply:
            return "no_load_supply"
    if cause == "wire_break" and channel is not None:
        if not module.wire_watched(channel):
            return "signal_range"
        if module.loop_needs_load_supply() and not load_supply:
            return "no_load_supply"  # a current output's open loop, as in CpxModule.faults
    return None


def reason(module: CpxModule, cause: str, channel: int | None, monitors: Monitors | None,
           runs: bool, load_supply: bool) -> str:
    """Why ``cause`` on ``channel``, wired, is not diagnosed now (an id of UNSEEN_REASONS).
    ``monitors`` are 0x2400's switches (None without a dictionary: unpowered), ``runs`` whether
    the application controller runs, ``load_supply`` whether U_OUT is in tolerance."""
    physical = _physics(module, cause, channel, load_supply)
    if physical is not None:
        return physical
    if not runs or monitors is None:
        return "no_application"
    if module.failed and cause != "module_failure":
        return "module_failed"
    if (cause == "short_circuit_sensor_supply" and not monitors.scs) or \
            (cause == "short_circuit_outputs" and not monitors.sco):
        return "monitor_off"
    return "pending"


def undiagnosed(module: CpxModule, diagnosed: Collection[Wired], monitors: Monitors | None,
                runs: bool, load_supply: bool) -> list[dict[str, object]]:
    """The module's wired causes not in ``diagnosed`` (its (cause, channel) pairs), one entry
    per cause and reason: ``{"cause", "channels", "reason"}``, ``channels`` empty for a cause
    of the whole module."""
    groups: dict[tuple[str, str], list[int]] = {}
    for cause, channel in wired(module):
        if (cause, channel) in diagnosed:
            continue
        why = reason(module, cause, channel, monitors, runs, load_supply)
        channels = groups.setdefault((cause, why), [])
        if channel is not None:
            channels.append(channel)
    order = list(UNSEEN_REASONS)
    return [{"cause": cause, "channels": channels, "reason": why}
            for (cause, why), channels in sorted(
                groups.items(),
                key=lambda g: (WIRED_ORDER.index(g[0][0]), order.index(g[0][1])))]
