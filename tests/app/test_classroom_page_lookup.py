"""The fault-form tests find the instructor's own widgets whatever order its page got them in.

An instructor's page gets its own folders (the Line tab's "Slave faults" with a "cpx" folder:
Target, Fault action) on its connection's own messages, and the server-level ones (the Slave
tab's "cpx" folder: Target, Action) on the replay of the shared elements: two producers in no
set order (viser 1.1.1, infra/_infra.py ws_handler). Under load the replay came second and
the lookup by the newest "cpx" folder took the shared one: its Target was set instead of the
instructor's, and its Fault action never came (tests/app/test_classroom_fault_forms.py
timed out after 20 s with every message sent, seen in a logged run).
"""

from __future__ import annotations

from typing import Any

import pytest
from test_classroom_fault_forms import _in


def _folder(uuid: str, parent: str, label: str) -> dict[str, Any]:
    return {"type": "GuiFolderMessage", "uuid": uuid, "container_uuid": parent,
            "props": {"label": label}}


def _dropdown(uuid: str, parent: str, label: str) -> dict[str, Any]:
    return {"type": "GuiDropdownMessage", "uuid": uuid, "container_uuid": parent,
            "props": {"label": label}}


OWN = [  # the instructor's connection's own messages
    _folder("own-faults", "line-tab", "Slave faults"),
    _dropdown("own-device", "own-faults", "Device"),
    _folder("own-cpx", "own-faults", "cpx"),
    _dropdown("own-target", "own-cpx", "Target"),
    _dropdown("own-action", "own-cpx", "Fault action"),
]
SHARED = [  # the replay of the server-level elements
    _folder("slave-tab-cpx", "slave-tab", "cpx"),
    _dropdown("shared-target", "slave-tab-cpx", "Target"),
    _dropdown("shared-action", "slave-tab-cpx", "Action"),
]


class _Page:
    def __init__(self, messages: list[dict[str, Any]]) -> None:
        self._messages = messages

    def received(self) -> list[dict[str, Any]]:
        return list(self._messages)


@pytest.mark.parametrize("arrived", [OWN + SHARED, SHARED + OWN],
                         ids=["replay-last", "replay-first"])
def test_the_instructors_own_slave_fault_form_is_found_in_either_order(
        arrived: list[dict[str, Any]]) -> None:
    page: Any = _Page(arrived)
    assert _in(page, "Slave faults", "cpx", "Target") == "own-target"
    assert _in(page, "Slave faults", "cpx", "Fault action") == "own-action"
    assert _in(page, "Slave faults", "Device") == "own-device"
