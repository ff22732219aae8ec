"""Which state each CPX-E-EC LED shows, from the bus module's state (tables in leds.py).

Run follows the ESM (Tab. 11) and turns orange in the bootloader. Error shows the most
severe of what applies (Tab. 12): application controller failure, booting error, bootloader,
no link / no master / invalid configuration, watchdog, sync error. LA IN / LA OUT follow the
cables and the traffic (Tab. 13). PS / PL the supplies, SF the error class, M forcing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from devices.cpx.esm import ERROR_LED
from devices.cpx.leds import (
    DARK,
    ERROR_PRIORITY,
    ERROR_TABLE,
    LINK_TABLE,
    M_TABLE,
    RUN_TABLE,
    SF_BY_CLASS,
    SUPPLY_TABLE,
    ErrorShows,
    LedState,
    LinkShows,
    RunShows,
    SupplyShows,
)
from devices.cpx.switches import DiagMode
from devices.ethercat import AlState

if TYPE_CHECKING:
    from devices.cpx.device import CpxEEc

RUN_BY_STATE: dict[AlState, RunShows] = {
    AlState.INIT: RunShows.INIT, AlState.PREOP: RunShows.PREOP,
    AlState.SAFEOP: RunShows.SAFEOP, AlState.OP: RunShows.OP, AlState.BOOT: RunShows.BOOT,
}
U_OUT_ABSENT_V = 1.0  # below this PL is dark rather than flashing


def run_shows(dev: CpxEEc) -> RunShows:
    if dev.switches.active_mode is DiagMode.BOOTLOADER:
        return RunShows.BOOTLOADER
    return RUN_BY_STATE[dev.esm.state]


def error_shows(dev: CpxEEc) -> ErrorShows:
    applies = {ERROR_LED[dev.esm.error]}  # NONE when the AL status has no error flag
    if dev.has_fault("ac_failure"):
        applies.add(ErrorShows.AC_FAILURE)
    if dev.boot_failed:
        applies.add(ErrorShows.BOOTING_ERROR)
    if dev.switches.active_mode is DiagMode.BOOTLOADER:
        applies.add(ErrorShows.BOOTLOADER)
    if not dev.link_in or dev.master_silent():  # cable, no master, master inactive
        applies.add(ErrorShows.INVALID_CONFIGURATION)
    return next(shows for shows in ERROR_PRIORITY if shows in applies)


def link_shows(connected: bool, traffic: bool) -> LinkShows:
    if not connected:
        return LinkShows.NO_LINK
    return LinkShows.TRAFFIC if traffic else LinkShows.LINK


def supply_shows(volts: float, ok: bool) -> SupplyShows:
    if volts < U_OUT_ABSENT_V:
        return SupplyShows.ABSENT
    return SupplyShows.OK if ok else SupplyShows.UNDERVOLTAGE


def wanted_leds(dev: CpxEEc) -> dict[str, LedState]:
    if not dev.powered:
        return dict(DARK)
    traffic = dev.traffic()
    runs = dev.application_runs
    return {
        "Run": RUN_TABLE[run_shows(dev)],
        "Error": ERROR_TABLE[error_shows(dev)],
        "LA IN": LINK_TABLE[link_shows(dev.link_in, traffic)],
        "LA OUT": LINK_TABLE[link_shows(dev.link_out, traffic and dev.link_out)],
        "PS": SUPPLY_TABLE[supply_shows(dev.u_el_sen_v, dev.u_el_sen_ok)],
        "PL": SUPPLY_TABLE[supply_shows(dev.u_out_v, dev.u_out_ok)],
        "SF": SF_BY_CLASS[dev.diagnosis.error_class if runs else 0],
        "M": M_TABLE[runs and any(m.forced for m in dev.modules)],
    }
