"""The FastCAT's fault form offers only the targets the picked code takes (seed 000 §7.5:
byte 0 holds "l'eventuale indice del nodo"; 0x10-0x13 are about no node, and the coupler
refuses them on a module; §7.6: a module code needs a module). Before, every code offered the
coupler and every module, and the device refused 0x10-0x13 on a module once applied. The
choice is the device's (``AlarmCode.names_module`` / ``on_coupler``), not a table here."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from served_dashboard import drawn, served_default_rig

from app.screenshots import ServedRig
from app.ui.panels.control import COUPLER_TARGET, TABLE_LABELS
from devices.fastcat.alarms import COUPLER_CODES, MODULE_CODES, NO_NODE_COUPLER_CODES


@pytest.fixture(scope="module")
def served() -> Iterator[ServedRig]:
    with served_default_rig(8.0) as live:
        yield live


def _targets_for(served: ServedRig, table: str, label: str) -> tuple[str, ...]:
    control = served.dashboard._panels.control  # type: ignore[union-attr]
    [form] = control._forms.each()
    form.table.value = TABLE_LABELS[table]
    form.fault.value = label
    drawn(served)
    return tuple(form.target.options)


@pytest.mark.parametrize("code", sorted(NO_NODE_COUPLER_CODES))
def test_a_code_about_no_node_offers_the_coupler_only(served: ServedRig, code: int) -> None:
    row = COUPLER_CODES[code]
    assert _targets_for(served, "coupler", f"0x{code:02X} {row.symbol}") == (COUPLER_TARGET,)


def test_a_coupler_code_about_a_node_offers_the_coupler_and_the_modules(
        served: ServedRig) -> None:
    targets = _targets_for(served, "coupler", "0x04 MISSING_NODE_ANSWER")
    assert targets[0] == COUPLER_TARGET and len(targets) > 1  # the modules the bus numbered


def test_a_module_code_offers_the_modules_only(served: ServedRig) -> None:
    row = MODULE_CODES[0x01]
    targets = _targets_for(served, "module", f"0x01 {row.symbol}")
    assert targets and COUPLER_TARGET not in targets
    # and each target it offers the device takes
    for target in targets:
        module = int(target.split(" ", 1)[0])
        served.runtime.rig.device("fastcat").check_command(
            "inject_fault", {"fault": row.label}, module)
