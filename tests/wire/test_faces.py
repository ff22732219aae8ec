"""The wire faces against the slave models: identity, image sizes, outputs in, inputs out, ESM.

Identity is each model's 0x1018; the SM2 / SM3 lengths are what a master computes from the
mapping objects it reads (0x1C12 / 0x1C13 -> 0x16xx / 0x1Axx, ETG.1000.6; the CPX-E-EC assigns
its module PDOs by its address rules §2.3.1, devices/cpx/assignment.py); outputs written
through the face reach the model (seed 000 §5 / §6.28: a DO16 channel the master sets drives
the terminal); state refusals keep the model's own codes (seed 001 §9.3.2: 0x0070).
"""

from __future__ import annotations

import pytest
from wire_line import LINE, line_spec

from app.ethercat_wire import faces
from app.ethercat_wire.description import Pdo, PdoEntry
from app.ethercat_wire.faces import image
from app.rig_config import build_rig, parse_rig_spec
from devices.ethercat import AlState
from devices.od import Access, DataType, OdEntry

TIMEOUT_US = 8_000_000


def line_rig(state: str = "OP", **spec):
    """The rig of ``line_spec(**spec)`` with every slave brought to ``state`` by the built-in
    master."""
    rig = build_rig(parse_rig_spec(line_spec(**spec)))
    for device in rig.devices.values():
        if "power" in device.ACTIONS:
            device.apply("power", {"on": True}, None)
    rig.apply("master", "set_target", {"state": state})
    while rig.clock.now_us < TIMEOUT_US:
        rig.run_until(rig.clock.now_us + 50_000)
        if all(rig.devices[d].al_state is AlState[state] for d in LINE):
            return rig
    raise AssertionError([rig.devices[d].al_state for d in LINE])


@pytest.fixture(scope="module")
def rig():
    return line_rig()


def mapped_bits(od, assign: int) -> int:
    """Bits of the assigned PDOs, read as a master reads them (independent of the faces)."""
    total = 0
    for sub in range(1, od.peek(assign, 0) + 1):
        pdo = od.peek(assign, sub)
        total += sum(od.peek(pdo, s) & 0xFF for s in range(1, od.peek(pdo, 0) + 1))
    return total


@pytest.mark.parametrize("device", LINE)
def test_identity_is_the_models_0x1018(rig, device):
    model = rig.devices[device]
    desc = faces.describe(model)
    od = faces.face_for(model).od(model)
    assert (desc.vendor_id, desc.product_code, desc.revision, desc.serial) == \
        tuple(od.peek(0x1018, s) for s in (1, 2, 3, 4))
    assert desc.device_id == device


@pytest.mark.parametrize(("device", "name"), [
    ("fastcat", "FastCAT"), ("trscat", "TRS-CAT"), ("cpx", "CPX-E-EC"),
    ("drive_ecat-ecat", "SelemaDriveECAT")])
def test_names_are_the_esi_names(rig, device, name):
    """Seed 000 §7.1 'Box 1 (FastCAT)', seed 004 ch. 5 'Drive 5 (SelemaDriveECAT)', ..."""
    assert faces.describe(rig.devices[device]).name == name


@pytest.mark.parametrize("device", ["fastcat", "trscat", "drive_ecat-ecat"])
def test_image_sizes_are_the_mapping_objects(rig, device):
    model = rig.devices[device]
    od = faces.face_for(model).od(model)
    desc = faces.describe(model)
    out_bytes = (mapped_bits(od, 0x1C12) + 7) // 8
    in_bytes = (mapped_bits(od, 0x1C13) + 7) // 8
    assert (desc.sync_managers[2].length, desc.sync_managers[3].length) == (out_bytes, in_bytes)
    assert len(faces.inputs(model)) == in_bytes
    assert [p.index for p in desc.rx_pdos] == \
        [od.peek(0x1C12, s) for s in range(1, od.peek(0x1C12, 0) + 1)]


def test_fastcat_pdos_are_seed_000_section_5(rig):
    """§5: 0x16FF / 0x1AFF first, then 0x1600 + (n - 1) / 0x1A00 + (n - 1) per module."""
    desc = faces.describe(rig.devices["fastcat"])
    assert [p.index for p in desc.rx_pdos] == [0x16FF, 0x1601]  # DI16 has no outputs
    assert [p.index for p in desc.tx_pdos] == [0x1AFF, 0x1A00, 0x1A02]
    assert desc.sync_managers[2].length == 3  # 1 bit Reset fault + 16 DO bits
    assert desc.mailbox == (0x1000, 128, 0x1080, 128)


def test_cpx_image_follows_the_addressing_rules(rig):
    """§2.3.1: bus module (status bits, 16 bits mapped) first, analog before digital."""
    model = rig.devices["cpx"]
    desc = faces.describe(model)
    numbers = {u.mtype.name: u.number for u in model.units}
    assert [p.index for p in desc.tx_pdos] == [
        0x1A00, 0x1A00 + numbers["CPX-E-4AI-U-I"], 0x1A00 + numbers["CPX-E-16DI"]]
    assert [p.index for p in desc.rx_pdos] == [
        0x1600 + numbers["CPX-E-4AO-U-I"], 0x1600 + numbers["CPX-E-8DO"]]
    assert (desc.sync_managers[2].length, desc.sync_managers[3].length) == (9, 12)
    assert len(faces.inputs(model)) == 12


def test_fastcat_do16_output_written_by_the_master_drives_the_terminal():
    """Seed 000 §6.28: module 2 (DO16) channel 3 = bit 8 + 2 of SM2, after 0x16FF's byte
    (the Reset fault bit and §6.17's seven reserved bits)."""
    rig = line_rig()
    model = rig.devices["fastcat"]
    face = faces.face_for(model)
    data = (1 << (8 + 2)).to_bytes(3, "little")
    face.apply_outputs(model, data)
    rig.run_until(rig.clock.now_us + 10_000)
    do16 = rig.snapshot()["devices"]["fastcat"]["rail"][1]
    assert do16["type"] == "DO16"
    assert do16["do"] == [ch == 2 for ch in range(16)]
    face.apply_outputs(model, bytes(3))
    rig.run_until(rig.clock.now_us + 10_000)
    assert not any(rig.snapshot()["devices"]["fastcat"]["rail"][1]["do"])


@pytest.mark.parametrize("state", ["PREOP", "SAFEOP"])
def test_fastcat_outputs_written_before_op_wait_for_the_first_op_cycle(state):
    """ETG.1000.6: in PREOP / SAFEOP the outputs stay in their safe state, the slave does not
    act on them (seed 000 §7: Reset fault is "mappato nei dati scambiati con il coupler").
    A Reset fault edge in the image before OP resets nothing; the ESC keeps the SM2 buffer
    (a master writes its image every cycle), so at the first OP cycle the coupler takes the
    bit's edge and the DO16 channel (docs/fastcat-coupler.md "Process data before OP")."""
    rig = line_rig(state)
    model = rig.devices["fastcat"]
    face = faces.face_for(model)
    rig.apply("fastcat/2", "inject_fault", {"fault": "TARATURA"})
    rig.run_until(rig.clock.now_us + 10_000)
    rig.apply("fastcat/2", "clear_fault", {"fault": "TARATURA"})
    rig.run_until(rig.clock.now_us + 10_000)
    assert model.snapshot()["fault_active"]  # latched, its cause gone: a Reset fault clears it
    face.apply_outputs(model, (1 | 1 << (8 + 2)).to_bytes(3, "little"))
    rig.run_until(rig.clock.now_us + 10_000)
    snap = model.snapshot()
    assert model.al_state is AlState[state]
    assert snap["fault_active"] and not snap["reset_fault"]
    assert not any(snap["rail"][1]["do"])
    rig.apply("master", "set_target", {"state": "OP"})
    while model.al_state is not AlState.OP and rig.clock.now_us < TIMEOUT_US:
        rig.run_until(rig.clock.now_us + 10_000)
    rig.run_until(rig.clock.now_us + 10_000)
    snap = model.snapshot()
    assert not snap["fault_active"] and snap["reset_fault"]
    assert snap["rail"][1]["do"] == [ch == 2 for ch in range(16)]


def test_fastcat_input_reaches_the_image():
    """Seed 000 §6.24: DI16 (module 1) channel 5 -> 0x6000:5 -> bit 8 + 4 of SM3, after
    0x1AFF's byte (Fault active and §6.16's seven reserved bits)."""
    rig = line_rig()
    model = rig.devices["fastcat"]
    before = int.from_bytes(faces.inputs(model), "little")
    rig.apply("fastcat/1", "set_input", {"channel": 5, "value": True})
    rig.run_until(rig.clock.now_us + 10_000)
    after = int.from_bytes(faces.inputs(model), "little")
    assert before ^ after == 1 << (8 + 4)


def test_drive_outputs_reach_the_drive():
    """Seed 004 ch. 5: 0x1600 (controlword first) applied in OP at the next frame."""
    rig = line_rig()
    model = rig.devices["drive_ecat-ecat"]
    face = faces.face_for(model)
    size = image.byte_size(face.rx_pdos(model))
    face.apply_outputs(model, (0x0006).to_bytes(2, "little") + bytes(size - 2))
    rig.run_until(rig.clock.now_us + 10_000)
    assert model.dictionary.peek(0x6040, 0) == 0x0006


def test_trscat_refuses_safeop_when_0xf030_differs_from_0xf050():
    """Seed 001 §9.3.2: 0xF030 written in PRE-OP over the wire, SAFEOP refused 0x0070."""
    rig = line_rig("PREOP")
    rig.devices["master"].set_external(True)
    model = rig.devices["trscat"]
    face = faces.face_for(model)
    face.download(model, 0xF030, 2, 0x414E2D45)  # TRS-AN-E where a TRS-IO-E is
    face.request_state(model, AlState.SAFEOP)
    rig.run_until(rig.clock.now_us + 200_000)
    assert faces.al_status(model) == (int(AlState.PREOP) | 0x10, 0x0070)


def test_an_unknown_al_control_state_answers_0x0012():
    """Seed 000 §7.7 / ETG.1000.6: 0x0012 "Unknown requested state"; over the error flag an
    unknown state without the acknowledge is ignored (SSC AL_ControlInd, SOES ESC_state)."""
    rig = line_rig("PREOP")
    rig.devices["master"].set_external(True)
    model = rig.devices["cpx"]
    faces.face_for(model).request_unknown_state(model, 0x05, False)
    assert faces.al_status(model) == (int(AlState.PREOP) | 0x10, 0x0012)
    faces.face_for(model).request_state(model, AlState.OP, True)  # PREOP -> OP: 0x0011
    faces.face_for(model).request_unknown_state(model, 0x0F, False)
    assert faces.al_status(model) == (int(AlState.PREOP) | 0x10, 0x0011)
    faces.face_for(model).request_unknown_state(model, 0x0F, True)
    assert faces.al_status(model) == (int(AlState.PREOP) | 0x10, 0x0012)


def test_image_packing_is_bitwise_and_signed():
    """1-bit entries take one bit; a gap entry (index 0) skips bits; INT16 sign-extends."""
    pdos = (Pdo(0x1600, "p", (PdoEntry(0x7000, 1, 1, "a"), PdoEntry(0, 0, 3, ""),
                              PdoEntry(0x7400, 1, 16, "b"))),)
    values = {(0x7000, 1): 1, (0x7400, 1): -2}
    types = {(0x7000, 1): DataType.BOOLEAN, (0x7400, 1): DataType.INTEGER16}
    data = image.pack(pdos, lambda i, s: values[(i, s)])
    assert data == bytes.fromhex("e1ff0f")
    lookup = lambda i, s: OdEntry(i, s, "", types[(i, s)], Access.RW)  # noqa: E731
    assert image.unpack(pdos, data, lookup) == [(0x7000, 1, 1), (0x7400, 1, -2)]
    assert image.changed(pdos, data, data) == set()
    assert image.changed(pdos, data, bytes.fromhex("e0ff0f")) == {(0x7000, 1)}
