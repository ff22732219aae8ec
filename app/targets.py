"""Command targets as users write them: ``fastcat`` (the device) or ``fastcat/2`` (module 2)."""

from __future__ import annotations

import re

from devices.device import CommandError

_TARGET = re.compile(r"^(?P<device>[A-Za-z_][A-Za-z0-9_\-]*)(?:/(?P<module>[0-9]+))?$")


def parse_target(text: str) -> tuple[str, int | None]:
    match = _TARGET.match(text.strip()) if isinstance(text, str) else None
    if match is None:
        raise CommandError(f"target {text!r} is not 'device' or 'device/N' (N = module number "
                           "from 1)")
    module = match.group("module")
    if module is not None and int(module) < 1:
        raise CommandError(f"target {text!r}: modules are numbered from 1")
    return match.group("device"), int(module) if module is not None else None
