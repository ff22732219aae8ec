"""The FastCAT's fault form offers only the targets the picked code takes (seed 000 §7.5:
byte 0 holds "l'eventuale indice del nodo"; 0x10-0x13 are about no node, and the coupler
refuses them on a module; §7.6: a module code needs a module). Before, every code offered the
coupler and every module, and the device refused 0x10-0x13 on a module once applied. The
choice is the device's (``AlarmCode.names_module`` / ``on_coupler``), not a table here.

Here the instructor's form (a classroom with a token: each instructor connection's own
widgets, ``ControlPanel._offer_targets``); an open rig's form, whose pickers are each page's
own, is tests/app/test_fastcat_fault_targets_per_page.py."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from app.ui.panels.classroom_rig import ServedRig
from app.ui.panels.control import COUPLER_TARGET, TABLE_LABELS
from devices.fastcat.alarms import COUPLER_CODES, MODULE_CODES, NO_NODE_COUPLER_CODES
from tests.app.test_classroom_leak import open_class


@pytest.fixture(scope="module")
def served() -> Iterator[ServedRig]:
    with open_class() as (live, _trainee, _instructor):
        live.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        live.runtime.advance(3_000_000).result(timeout=30)
        yield live


def _targets_for(served: ServedRig, table: str, label: str) -> tuple[str, ...]:
    control = served.dashboard._panels.control  # type: ignore[union-attr]
    [form] = control._forms.each()  # the instructor's
    form.table.value = TABLE_LABELS[table]
    form.fault.value = label
    served.runtime.advance(10_000).result(timeout=10)  # a frame: the form offers anew
    served.dashboard.tick()
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
