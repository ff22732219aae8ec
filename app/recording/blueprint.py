"""How a rig recording opens in the Rerun viewer: the layout (a blueprint) and series styles.

Left column: the state machines and the LED patterns as state timelines, the event log under
them. Right: one tab per device with its plots (LEDs lit/dark, each module's process data,
the drive's signals), one plot per group of signals of the same scale, as
:func:`app.recording.signals.device_signals` groups them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import rerun as rr
import rerun.blueprint as rrb

from app.recording.signals import ROOT, Signal, led_color, rig_signals
from devices.ethercat import AlState
from devices.leds import LedPattern

TIMELINE = "sim_time"

# ESM lane colours: grey while not communicating, blue/amber on the way up, green in OP.
ESM_RGBA: dict[str, int] = {
    AlState.INIT.label: 0x9E9E9EFF,
    AlState.PREOP.label: 0x1E88E5FF,
    AlState.BOOT.label: 0x8E24AAFF,
    AlState.SAFEOP.label: 0xFB8C00FF,
    AlState.OP.label: 0x43A047FF,
}
LED_OFF_RGBA = 0x424242FF


def series_style(signal: Signal) -> rr.SeriesLines:
    """Static style of a signal's entity: series names, colours, steps for digital data."""
    info = signal.info
    mode = rr.components.InterpolationMode.StepAfter if info.step else None
    return rr.SeriesLines(names=list(info.names),
                          colors=list(info.colors) if info.colors else None,
                          interpolation_mode=mode)


def lane_style(path: str) -> rr.StateConfiguration | None:
    """Static colours of a state lane: ESM states, or an LED's patterns in the LED's colour."""
    parts = path.split("/")
    if len(parts) >= 4 and parts[2] == "led":
        lit = led_color(parts[3])
        faded = (lit & 0xFFFFFF00) | 0x99  # blinking patterns: the LED colour, lighter
        values = [p.value for p in LedPattern]
        colors = [LED_OFF_RGBA if p is LedPattern.OFF else lit if p is LedPattern.ON else faded
                  for p in LedPattern]
        return rr.StateConfiguration(values=values, colors=colors)
    # A drive's ESM and the master's view of each slave are ESM lanes too.
    if parts[2:] in (["state"], ["state", "esm"]) or parts[2:4] == ["state", "slave"]:
        return rr.StateConfiguration(values=list(ESM_RGBA), colors=list(ESM_RGBA.values()))
    return None


def _device_tab(device_id: str, signals: list[Signal]) -> rrb.Container:
    views: dict[str, list[str]] = {}
    for signal in signals:
        views.setdefault(signal.view, []).append(f"/{signal.path}")
    plots = [rrb.TimeSeriesView(name=title, origin=f"/{ROOT}/{device_id}", contents=paths)
             for title, paths in views.items()]
    return rrb.Grid(*plots, name=device_id)


def rig_blueprint(snapshot: Mapping[str, Any], t_us: int = 0) -> rrb.Blueprint:
    """The layout for the devices of ``snapshot`` (a :meth:`app.rig.Rig.snapshot`)."""
    devices = list((snapshot.get("devices") or {}).keys())
    by_device: dict[str, list[Signal]] = {d: [] for d in devices}
    for device_id, signal in rig_signals(snapshot, t_us):
        by_device[device_id].append(signal)
    left = rrb.Vertical(
        rrb.StateTimelineView(name="Device states", origin=f"/{ROOT}",
                              contents=[f"/{ROOT}/{d}/{lane}" for d in devices
                                        for lane in ("state/**", "al_status")]),
        rrb.StateTimelineView(name="LED patterns", origin=f"/{ROOT}",
                              contents=[f"/{ROOT}/{d}/led/**" for d in devices]),
        rrb.TextLogView(name="Events", origin=f"/{ROOT}"),
        row_shares=[1, 2, 3],
    )
    tabs = [_device_tab(d, s) for d, s in by_device.items() if s]
    right = rrb.Tabs(*tabs) if tabs else rrb.TextLogView(name="Log", origin=f"/{ROOT}")
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[2, 3]),
        rrb.TimePanel(timeline=TIMELINE),
        collapse_panels=False,
    )
