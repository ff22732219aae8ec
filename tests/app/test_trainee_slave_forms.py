"""The Line tab's slave forms on a trainee's page (docs/classroom.md): every action a trainee
can pick in a form the trainee CSS leaves on the page is operation. The forms offered
inject_fault, cable, supply, short_circuit, ... next to the inputs, so a trainee saw (and
could pick) the instructor's fault actions and the last fault the instructor chose there."""

from __future__ import annotations

from typing import Any

import viser

from app.classroom.roles import INSTRUCTOR_ONLY
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.screenshots import free_port
from app.ui.dashboard import Dashboard
from app.ui.panels.widgets import instructor_folders, widget_uuid


def _shown(handle: Any, hidden: set[str]) -> bool:
    """Not hidden itself nor inside a hidden folder."""
    while True:
        if widget_uuid(handle) in hidden:
            return False
        impl = handle._impl
        parent = impl.gui_api._container_handle_from_uuid.get(impl.parent_container_id)
        if not isinstance(parent, viser.GuiFolderHandle):
            return True
        handle = parent


def _makes_faults(kind: str, action: str) -> bool:
    return any(r.kind in (kind, "*") and r.action == action for r in INSTRUCTOR_ONLY)


def test_a_trainee_sees_no_fault_action_in_the_slave_forms() -> None:
    runtime = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        dashboard = Dashboard(server, runtime)
        line = dashboard.line
        assert line is not None
        widgets = dashboard.instructor_widgets()
        hidden = {widget_uuid(w) for w in [*widgets, *instructor_folders(widgets)]}
        kinds = {d: str(getattr(dev, "KIND", "")) for d, dev in runtime.rig.devices.items()}
        shown: dict[str, set[str]] = {}
        offered: dict[str, set[str]] = {}
        for device, forms in line.controls.all_forms().items():
            for form in forms:
                options = set(form.options()) - {"(none)"}
                offered.setdefault(device, set()).update(options)
                if _shown(form.choice, hidden):
                    shown.setdefault(device, set()).update(options)
        assert {"trscat", "cpx"} <= set(offered)
        for device, names in shown.items():
            faults = sorted(n for n in names if _makes_faults(kinds[device], n))
            assert not faults, f"{device}: {faults} on a trainee's page"
        # Nothing is lost: the instructor still has every action, a trainee the operation.
        assert {"inject_fault", "cable", "short_circuit", "force"} <= offered["cpx"]
        assert {"inject_fault", "set_input"} <= offered["trscat"]
        assert {"force", "set_input", "set_dil"} <= shown["cpx"]
        assert {"set_input", "set_output", "acknowledge_messages"} <= shown["trscat"]
    finally:
        server.stop()
