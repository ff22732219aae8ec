"""With a token, the instructor's own *Slave faults* form lists only what its Target takes,
and an Apply in a fault form is confirmed on the instructor's page only (docs/classroom.md
"What a trainee does not see"). Driven through the websocket, as the browsers drive them."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from test_classroom_fault_forms import _in
from test_classroom_leak import TOKEN, Page, _wait

from app.classroom.roles import Access, Role
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.screenshots import free_port
from app.ui.panels.classroom_rig import ServedRig, serve_rig


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ServedRig, Page, Page]]:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    live = serve_rig(rig, Access(TOKEN), port=free_port(), paused=True)
    trainee, instructor = Page(live.port), Page(live.port)
    try:
        clients = _wait(lambda: len(live.server.get_clients()) == 2 and live.server.get_clients())
        first, second = sorted(clients)
        assert live.classroom.access.present(second, TOKEN)
        live.classroom._promoted(clients[second])
        assert live.classroom.access.role(first) is Role.TRAINEE
        live.runtime.command("fastcat", "power", {"on": True}).result(timeout=10)
        live.runtime.advance(1_000_000).result(timeout=30)
        _in(instructor, "Slave faults", "Device")
        yield live, trainee, instructor
    finally:
        trainee.close()
        instructor.close()
        live.stop()


def _options(page: Page, uuid: str) -> tuple[str, ...]:
    """The options the page shows now in dropdown ``uuid``: as created, then as updated."""
    shown: tuple[str, ...] = ()
    for m in page.received():
        if m.get("uuid") != uuid:
            continue
        options = (m.get("props") or {}).get("options") or (m.get("updates") or {}).get("options")
        if options:
            shown = tuple(options)
    return shown


def test_the_slave_faults_form_on_a_module_lists_its_actions_only(
        served: tuple[ServedRig, Page, Page]) -> None:
    _live, _trainee, instructor = served
    instructor.set(_in(instructor, "Slave faults", "Device"), "cpx")
    action = _in(instructor, "cpx", "Fault action")
    instructor.set(_in(instructor, "cpx", "Target"), "cpx/2")
    _wait(lambda: "cable" not in _options(instructor, action))
    shown = set(_options(instructor, action))
    assert not shown & {"cable", "power", "supply"}, shown
    assert {"short_circuit", "inject_fault"} <= shown
    instructor.set(_in(instructor, "cpx", "Target"), "cpx")
    _wait(lambda: "cable" in _options(instructor, action))
    assert "short_circuit" not in _options(instructor, action)

