"""Tell one browser its whole camera pose, every time.

viser 1.1.1's camera setters (``client.camera.position`` / ``look_at`` / ``up_direction``)
return without sending when the new value is ``np.allclose`` to the handle's state, and that
state is what the page REPORTED last (its throttled camera messages) or what the server set
last. A move then reached the browser or not depending on which of those came last: a page
that had been at the focus pose and was moved since, its report not in yet, kept its view.
The position setter also sends a look-at of its own (the old one dragged along) before ours.
So the pose goes out as three messages, whatever the handle holds; the page's next report
(it sends one after every camera change) brings the handle's state up to date.
"""

from __future__ import annotations

from collections.abc import Sequence

import viser
from viser._messages import (  # viser 1.1.1, pinned
    SetCameraLookAtMessage,
    SetCameraPositionMessage,
    SetCameraUpDirectionMessage,
)

UP = (0.0, 0.0, 1.0)  # the scene's z, as the initial camera has it (app/ui/line/view.py)


def send_pose(client: viser.ClientHandle, position: Sequence[float],
              look_at: Sequence[float], up: Sequence[float] = UP) -> None:
    """``client``'s camera at ``position`` looking at ``look_at``: the up direction first
    (the browser keeps its position through it), then the position (the browser keeps its
    look-at point), then the look-at point (it keeps the position): the same end pose from
    any pose before, in one batch."""
    def vector(values: Sequence[float]) -> tuple[float, float, float]:
        x, y, z = (float(v) for v in values)
        return x, y, z

    connection = client._websock_connection
    with client.atomic():
        connection.queue_message(SetCameraUpDirectionMessage(vector(up)))
        connection.queue_message(SetCameraPositionMessage(vector(position)))
        connection.queue_message(SetCameraLookAtMessage(vector(look_at)))
