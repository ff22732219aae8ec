"""The Line tab's slave fault form on the default rig's CPX-E-EC (session 15 walkthrough).

The form sent every parameter of the picked action: a number box holds a number, so an
optional ``channel`` and ``sm`` went as 0 and ``inject_fault module_failure`` on cpx/3 was
refused "module_failure takes no sync manager" (emptied boxes too: viser keeps their last
value). An optional parameter without a default is now a text box, blank = not given, and a
blank one is left out; the device still refuses a wrong combination a user types. The form is
each page's own (app/ui/panels/client_action_form.py): a page fills it here
(tests/app/form_page.py).
"""

from __future__ import annotations

from typing import Any

from form_page import fill, page_on, press
from served_dashboard import drawn, served_default_rig
from viser_page import Page, wait

from app.screenshots import ServedRig
from app.ui.panels.client_action_form import ClientActionForm


def _form(live: ServedRig, page: Page, target: str) -> ClientActionForm:
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    controls.targets["cpx"].set_all(target)
    drawn(live)
    drawn(live)  # the actions the target takes, read and offered
    return controls.fault_forms["cpx"]


def _apply(live: ServedRig, page: Page, form: ClientActionForm, action: str,
           **values: Any) -> list[dict[str, Any]]:
    """The page fills the form and presses Apply; what the form handed on (then sent)."""
    sent: list[dict[str, Any]] = []
    apply = form._apply
    form._apply = lambda client, name, args: (sent.append(args),  # type: ignore
                                              apply(client, name, args))
    try:
        fill(page, form, action, **values)
        press(page, form)
        wait(lambda: sent)
    finally:
        form._apply = apply  # type: ignore[method-assign]
    drawn(live)
    return sent


def _modules(live: ServedRig) -> list[tuple[bool, set[int], bool]]:
    """Each CPX-E module's (failed, shorted channels, sensor supply short), read in the
    simulation thread."""
    cpx = live.runtime.rig.device("cpx")
    return live.runtime.submit(lambda: [(m.failed, set(m.shorted), m.sensor_supply_short)
                                        for m in cpx.modules]).result(timeout=10)


def test_module_failure_on_a_module_from_the_form() -> None:
    with served_default_rig(1.0) as live, page_on(live) as page:
        form = _form(live, page, "cpx/3")
        blank = {p: form.field("inject_fault", p).value_of(None) for p in ("channel", "sm")}
        assert blank == {"channel": "", "sm": ""}  # blank boxes
        assert _apply(live, page, form, "inject_fault", fault="module_failure") == [
            {"fault": "module_failure"}]
        wait(lambda: _modules(live)[2][0])


def test_short_circuit_with_a_channel_and_the_sensor_supply_without() -> None:
    with served_default_rig(1.0) as live, page_on(live) as page:
        form = _form(live, page, "cpx/2")
        _apply(live, page, form, "inject_fault", fault="short_circuit", channel="3")
        wait(lambda: _modules(live)[1][1:] == ({3}, False))
        operate = live.dashboard.line.controls.all_forms()["cpx"][0]  # type: ignore[union-attr]
        assert "short_circuit" not in operate.options()  # a fault action: the fault form's
        form = _form(live, page, "cpx/1")
        _apply(live, page, form, "short_circuit", on=True)  # no channel: the sensor supply
        wait(lambda: _modules(live)[0][1:] == (set(), True))


def test_a_wrong_combination_typed_is_still_refused_by_the_device() -> None:
    with served_default_rig(1.0) as live, page_on(live) as page:
        form = _form(live, page, "cpx/3")
        sent = _apply(live, page, form, "inject_fault", fault="module_failure", sm="1")
        assert sent == [{"fault": "module_failure", "sm": 1}]
        drawn(live)
        assert not _modules(live)[2][0]


def test_the_trscat_form_sends_its_parameters_as_before() -> None:
    """Required parameters and optional ones with a default stay number boxes, always sent
    (the drive's per-page form: tests/app/test_client_action_form.py)."""
    with served_default_rig(1.0) as live, page_on(live) as page:
        controls = live.dashboard.line.controls  # type: ignore[union-attr]
        trscat = controls.fault_forms["trscat"]
        assert _apply(live, page, trscat, "field_supply", volts=12.5) == [{"volts": 12.5}]
