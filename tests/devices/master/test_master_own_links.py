"""A cable pulled at a slave's own port (the TRS-CAT's ``link``, the CPX-E-EC's ``cable``)
cuts the line there, as the master's ``pull_cable`` of the same cable does: no frame passes a
port without link, so every slave behind it is lost too, and found again when it is back."""

from __future__ import annotations

import pytest

from app.rig_config import build_rig, load_rig_spec

NAMES = ("fastcat", "trscat", "cpx", "drive_ec")


def _present(rig) -> list[bool]:
    return [bool(s.get("present")) for s in rig.snapshot()["devices"]["master"]["slaves"]]


@pytest.mark.parametrize(("device", "action", "port", "kept"), [
    ("trscat", "link", "in", 1),    # the TRS-CAT itself and everything behind it
    ("trscat", "link", "out", 2),   # the TRS-CAT stays, the CPX-E-EC and the drive go
    ("cpx", "cable", "in", 2),
    ("cpx", "cable", "out", 3),
])
def test_a_slave_s_own_cable_cuts_the_line_behind_it(device, action, port, kept) -> None:
    rig = build_rig(load_rig_spec("static/rigs/default.toml"))
    rig.advance(8000)
    assert _present(rig) == [True] * 4
    rig.apply(device, action, {"connected": False, "port": port})
    events = rig.advance(300)
    assert _present(rig) == [True] * kept + [False] * (4 - kept)
    lost = [e.text for e in events
            if e.device == "master" and "not found" in getattr(e, "text", "")]
    at = NAMES.index(device)
    cut = f"(no link on the {port.upper()} port of the slave at position {at})"
    behind = lost[1:] if port == "in" else lost  # the slave itself: "no link on its IN port"
    assert len(lost) == 4 - kept and behind and all(text.endswith(cut + ".") for text in behind)
    rig.apply(device, action, {"connected": True, "port": port})
    rig.advance(8000)
    assert _present(rig) == [True] * 4
