"""The Line tab's slave fault form on the default rig's CPX-E-EC (session 15 walkthrough).

The form sent every parameter of the picked action: a number box holds a number, so an
optional ``channel`` and ``sm`` went as 0 and ``inject_fault module_failure`` on cpx/3 was
refused "module_failure takes no sync manager" (emptied boxes too: viser keeps their last
value). An optional parameter without a default is now a text box, blank = not given, and a
blank one is left out; the device still refuses a wrong combination a user types.
"""

from __future__ import annotations

from typing import Any

from served_dashboard import drawn, served_default_rig

from app.screenshots import ServedRig
from app.ui.panels.action_form import ActionForm


def _form(live: ServedRig, target: str, action: str) -> ActionForm:
    controls = live.dashboard.line.controls  # type: ignore[union-attr]
    controls.targets["cpx"].set_all(target)
    form = controls.fault_forms["cpx"]
    other = next(n for n in form.options() if n != action)
    for name in (other, action):  # as a page picks it
        form.choice.value = name
        form.rebuild()
    return form


def _apply(live: ServedRig, form: ActionForm, **values: Any) -> None:
    """Fill the widgets and press Apply (the server's own click: client None)."""
    for name, value in values.items():
        form.handle(name).value = value
    form.submit(None)
    drawn(live)


def _modules(live: ServedRig) -> list[tuple[bool, set[int], bool]]:
    """Each CPX-E module's (failed, shorted channels, sensor supply short), read in the
    simulation thread."""
    cpx = live.runtime.rig.device("cpx")
    return live.runtime.submit(lambda: [(m.failed, set(m.shorted), m.sensor_supply_short)
                                        for m in cpx.modules]).result(timeout=10)


def test_module_failure_on_a_module_from_the_form() -> None:
    with served_default_rig(1.0) as live:
        form = _form(live, "cpx/3", "inject_fault")
        assert form.values()["channel"] == "" and form.values()["sm"] == ""  # blank boxes
        _apply(live, form, fault="module_failure")
        assert _modules(live)[2][0]


def test_short_circuit_with_a_channel_and_the_sensor_supply_without() -> None:
    with served_default_rig(1.0) as live:
        form = _form(live, "cpx/2", "inject_fault")
        _apply(live, form, fault="short_circuit", channel="3")
        assert _modules(live)[1][1:] == ({3}, False)
        form = live.dashboard.line.controls.all_forms()["cpx"][0]  # type: ignore[union-attr]
        assert "short_circuit" not in form.options()  # a fault action: the fault form's
        form = _form(live, "cpx/1", "short_circuit")
        _apply(live, form, on=True)  # no channel: the module's sensor supply (KZS)
        assert _modules(live)[0][1:] == (set(), True)


def test_a_wrong_combination_typed_is_still_refused_by_the_device() -> None:
    with served_default_rig(1.0) as live:
        form = _form(live, "cpx/3", "inject_fault")
        sent: list[dict[str, Any]] = []
        apply = form._apply
        form._apply = lambda client, name, args: (sent.append(args),  # type: ignore
                                                  apply(client, name, args))
        _apply(live, form, fault="module_failure", sm="1")
        assert sent == [{"fault": "module_failure", "sm": 1}]
        assert not _modules(live)[2][0]


def _sent_by(form: ActionForm, action: str, **values: Any) -> list[dict[str, Any]]:
    """What the form hands its apply for ``action`` (picked as a page does)."""
    other = next(n for n in form.options() if n != action)
    for name in (other, action):
        form.choice.value = name
        form.rebuild()
    sent: list[dict[str, Any]] = []
    form._apply = lambda client, name, args: sent.append(args)  # type: ignore[method-assign]
    for name, value in values.items():
        form.handle(name).value = value
    form.submit(None)
    return sent


def test_the_trscat_form_sends_its_parameters_as_before() -> None:
    """Required parameters and optional ones with a default stay number boxes, always sent
    (the drive's per-page form: tests/app/test_client_action_form.py)."""
    with served_default_rig(1.0) as live:
        controls = live.dashboard.line.controls  # type: ignore[union-attr]
        trscat = controls.fault_forms["trscat"]
        assert _sent_by(trscat, "field_supply", volts=12.5) == [{"volts": 12.5}]
