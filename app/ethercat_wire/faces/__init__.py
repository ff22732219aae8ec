"""One face per kind of slave model: how the wire sees it (identity, PDOs, images, ESM, CoE).

``face_for(model)`` picks the face by the model's ``KIND``; the module-level functions are the
face operations the bridge and the tests call.
"""

from __future__ import annotations

from typing import Any

from app.ethercat_wire.description import SlaveDescription
from app.ethercat_wire.faces.base import Face, NoAnswer
from app.ethercat_wire.faces.cpx import CpxFace
from app.ethercat_wire.faces.drive import DriveFace
from app.ethercat_wire.faces.fastcat import FastCatFace
from app.ethercat_wire.faces.trscat import TrsCatFace
from devices.ethercat import AlState

FACES: dict[str, type[Face]] = {f.kind: f for f in (FastCatFace, TrsCatFace, CpxFace, DriveFace)}

__all__ = ["FACES", "Face", "NoAnswer", "al_status", "apply_outputs", "describe", "face_for",
           "inputs", "request_state"]


def face_for(model: Any) -> Face:
    try:
        return FACES[model.KIND]()
    except KeyError:
        known = ", ".join(FACES)
        raise ValueError(f"no EtherCAT wire face for a '{model.KIND}' model (faces: {known})"
                         ) from None


def describe(model: Any) -> SlaveDescription:
    return face_for(model).describe(model)


def inputs(model: Any) -> bytes:
    return face_for(model).inputs(model)


def apply_outputs(model: Any, data: bytes, face: Face | None = None) -> None:
    """``face``: the slave's face, kept by the caller so the change tracking carries over."""
    (face or face_for(model)).apply_outputs(model, data)


def request_state(model: Any, state: AlState, ack: bool = False) -> None:
    face_for(model).request_state(model, state, ack)


def al_status(model: Any) -> tuple[int, int]:
    return face_for(model).al_status(model)
