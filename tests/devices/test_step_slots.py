"""The small objects every step reads (each slave's ESM, the master's DC unit, the CPX-E-EC's
switches) have slots: a class-level field default (an enum member) would keep CPython 3.11
from specialising the reads, and a ``__dict__`` read once slows them for good
(docs/performance.md "Session 21"). Still-step keys read them slot by slot."""

from __future__ import annotations

import enum

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from bench.kernel import boot
from devices.cpx.stillness import state_key
from devices.esm import Esm
from devices.master.dc import DcUnit


def test_the_per_step_objects_of_the_default_rig_have_no_dict() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    boot([rig])  # to OP: the CPX-E-EC and the drives took their still-step keys
    esms = [d.esm for d in rig.devices.values() if isinstance(getattr(d, "esm", None), Esm)]
    assert len(esms) >= 4  # FastCAT, TRS-CAT, CPX-E-EC, the drive's CoE slave
    dc = rig.devices["master"].dc
    assert isinstance(dc, DcUnit)
    cpx = rig.devices["cpx"]
    for part in [*esms, dc, cpx.switches]:
        assert not hasattr(part, "__dict__"), type(part).__qualname__
        defaults = [getattr(type(part), name, None) for name in ("state", "error", "active_mode")]
        assert not any(isinstance(d, enum.Enum) for d in defaults), type(part).__qualname__
    key = state_key(cpx)
    keyed = dict(key)
    assert keyed["esm"][1] and keyed["switches"][1]  # read slot by slot, not as objects
