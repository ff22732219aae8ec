"""On an open rig each page's Faults Target offers only the targets its own picked code takes
(seed 000 §7.5: 0x10-0x13 name no node, the coupler only; §7.6: a module code names a module),
and keeps doing so when the rail changes. The Target is one server-level ClientPick whose
options the server broadcasts when the rail changes (ClientPick.set_options); each page's own
options must reach it after that broadcast, else the page shows every target again. Before,
the open rig's Target offered the coupler and every module to every page, whatever its code
(docs/dashboard.md "Several browsers", docs/fastcat-coupler.md). Two websocket connections
stand in for the browsers (tests/app/test_picks_per_browser.py)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest

from app.ui.panels.classroom_rig import ServedRig
from app.ui.panels.control import COUPLER_TARGET, TABLE_LABELS, fault_targets
from devices.fastcat.alarms import COUPLER_CODES, MODULE_CODES
from tests.app.test_classroom_leak import Page, _wait
from tests.app.test_picks_per_browser import _ids, _settle, _widget
from tests.app.two_pages import powered, two_pages

NO_NODE = f"0x10 {COUPLER_CODES[0x10].symbol}"  # §7.5: about no node
MODULE_CODE = f"0x02 {MODULE_CODES[0x02].symbol}"  # §7.6


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    with two_pages(prepare=powered) as pages:
        yield pages


def _modules(live: ServedRig) -> tuple[str, ...]:
    rail = live.runtime.submit(
        lambda: live.rig.device("fastcat").snapshot()["rail"]).result(timeout=10)
    return tuple(fault_targets(rail))


def _offered(page: Page, uuid: str) -> tuple[str, ...]:
    """The options the page shows last: its messages apply in the order they arrive."""
    found: Any = ()
    for m in page.received():
        if m.get("uuid") != uuid:
            continue
        found = (m.get("props") or {}).get("options", found)
        if m.get("type") == "GuiUpdateMessage":
            found = (m.get("updates") or {}).get("options", found)
    return tuple(found)


def _frames_until(live: ServedRig, done: Callable[[], bool]) -> None:
    """Frames drawn until ``done()``; still true after one more settled frame (a broadcast
    still on its way would land after a page's own options)."""
    def step() -> bool:
        live.runtime.advance(10_000).result(timeout=10)
        live.dashboard.tick()
        live.server.flush()
        return done()
    _wait(step)
    _settle(live)
    live.runtime.advance(10_000).result(timeout=10)
    _settle(live)
    assert done()


def test_each_page_s_target_offers_what_its_own_code_takes_also_after_a_rail_change(
        served: tuple[ServedRig, Page, Page]) -> None:
    live, first, second = served
    control = live.dashboard._panels.control  # type: ignore[union-attr]
    target = _widget(first, "Target", COUPLER_TARGET)
    modules = _modules(live)
    assert len(modules) > 2
    # Page B's Target on a module, for the default code (0x01: the coupler and the modules)
    second.set(target, modules[1])
    _settle(live)
    first.set(_widget(first, "Table", TABLE_LABELS["module"]), TABLE_LABELS["module"])
    _settle(live)
    first.set(_widget(first, "Fault", MODULE_CODE), MODULE_CODE)
    second.set(_widget(second, "Fault", NO_NODE), NO_NODE)
    _settle(live)
    one, two = _ids(live)
    _frames_until(live, lambda: _offered(first, target) == modules
                  and _offered(second, target) == (COUPLER_TARGET,))
    # Each page's pick moved to the first target its code takes, on that page only
    assert control._target.value_for(one) == modules[0]
    assert control._target.value_for(two) == COUPLER_TARGET
    assert first.updates(target)[-1] == modules[0]
    assert second.updates(target)[-1] == COUPLER_TARGET
    # A module unplugged: the rail's targets change, broadcast to every page
    live.runtime.command("fastcat/3", "unplug", {}).result(timeout=10)
    live.runtime.advance(100_000).result(timeout=30)
    after = _modules(live)
    assert after != modules
    _frames_until(live, lambda: _offered(first, target) == after
                  and _offered(second, target) == (COUPLER_TARGET,))
    assert control._target.value_for(one) in after
    assert control._target.value_for(two) == COUPLER_TARGET


def test_inject_sends_the_page_s_code_to_a_target_it_takes(
        served: tuple[ServedRig, Page, Page]) -> None:
    """Page A's module code goes to its own (module) Target, which the device takes."""
    live, first, _second = served
    control = live.dashboard._panels.control  # type: ignore[union-attr]
    one, _two = _ids(live)
    picked = control._target.value_for(one)
    assert picked != COUPLER_TARGET
    first.set(_widget(first, "Injection", None), "Inject")
    _wait(lambda: live.runtime.submit(
        lambda: live.rig.device("fastcat").snapshot()["injected"]).result(timeout=10))
    injected = live.runtime.submit(
        lambda: live.rig.device("fastcat").snapshot()["injected"]).result(timeout=10)
    assert injected == [{"fault": MODULE_CODES[0x02].symbol, "code": 0x02,
                         "module": int(picked.split(" ", 1)[0])}]
