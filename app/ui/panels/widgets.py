"""Small pieces the control panels share: mirroring device state into input widgets.

An input widget that also shows device state (Power, Hold CNF, module power, ...) follows the
device only when the device's value *changes*: a click then stays visible until the model
has acted on it, instead of being overwritten by the previous frame. Writing ``.value`` from
here fires the widget's callbacks with ``event.client is None``; the callbacks ignore those
(:func:`from_user`), so the view never echoes a command back.
"""

from __future__ import annotations

from typing import Any

import viser


def from_user(event: viser.GuiEvent) -> bool:
    """True for a change a person made in a browser, False for the view's own writes."""
    return event.client is not None


class Mirror:
    """Follow a device value into a widget on change only."""

    def __init__(self, handle: Any) -> None:
        self.handle = handle
        self._seen: Any = object()

    def follow(self, value: Any) -> None:
        if value != self._seen:
            self._seen = value
            if self.handle.value != value:
                self.handle.value = value

    def forget(self) -> None:
        """Take the next value even if it equals the last one (after a selection change, or
        after a user's click: a burst of clicks can leave the box on the opposite of a model
        that ended where it was, and only a change would set it back)."""
        self._seen = object()


def set_options(dropdown: Any, options: list[str], keep_prefix: str | None = None) -> None:
    """Replace a dropdown's options, keeping the selection on the entry starting with
    ``keep_prefix`` (e.g. the slot number) when there is one."""
    if list(dropdown.options) == options:
        return
    current = keep_prefix if keep_prefix is not None else str(dropdown.value)
    dropdown.options = tuple(options)
    for option in options:
        if option == current or option.split(" ", 1)[0] == current.split(" ", 1)[0]:
            dropdown.value = option
            return
    if options:
        dropdown.value = options[0]
