"""The line rig (master -> FastCAT -> TRS-CAT -> CPX-E-EC -> drive) for the master's tests:
built and run to OP for each test. It used to be built once and deep-copied, but a model's
object dictionary calls back into its device through closures, which copy.deepcopy shares
with the original: a copy's SDO writes (the TRS-CAT's 0xF030 list the master writes again
after a recovery) landed in the cached rig's device, and the copy refused them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from app.rig import Rig
from app.rig_config import build_rig, load_rig_spec
from devices.events import Event

ROOT = Path(__file__).resolve().parents[3]
LINE_RIG = ROOT / "static" / "rigs" / "ethercat_line.toml"
US = 1_000_000
IN_OP_US = 4 * US


def _line_in_op() -> Rig:
    rig = build_rig(load_rig_spec(LINE_RIG))
    rig.run_until(IN_OP_US)
    return rig


def line_in_op() -> Rig:
    """The line rig at 4 s: every slave in OP, DC COMPENSATING."""
    return _line_in_op()


def records(events: list[Event], kind: str, device: str | None = None) -> list[dict[str, Any]]:
    out = [e.to_record() for e in events]
    return [r for r in out if r["event"] == kind and (device is None or r["device"] == device)]


def master_view(rig: Rig) -> dict[str, Any]:
    return rig.snapshot()["devices"]["master"]
