"""A master on the wire finds 0xF030 as seed 001 §9.3.2 gives it at power-up (sub 0 = 1, sub 1 =
0x494F2D42), whatever the rig file's ``configured`` says: that list is the built-in master's
PS init commands (docs/trscat.md "Who writes 0xF030"). A wire master that writes the list
reaches SAFE-OP; one that writes nothing has the default compared with the expansions found
(§9.2 PS "0xF030 = 0xF050"): SAFE-OP refused, AL 0x0070, 0xA000 in 0x10F3, ERROR blinking.

Before, the model wrote the rig's list itself on entering PRE-OP, so TwinCAT or SOEM with an
empty Startup tab reached OP, where a real TRS-CAT with expansions stays in PRE-OP."""

from __future__ import annotations

from wire_line import line_spec

from app.ethercat_wire import faces
from app.rig import Rig
from app.rig_config import build_rig, parse_rig_spec
from devices.ethercat import AlState
from devices.trscat.catalog import EXPANSIONS, INTEGRATED

IO_B, IO_E = INTEGRATED.ident, EXPANSIONS["TRS-IO-E"].ident


def _preop() -> tuple[Rig, faces.Face, object]:
    """The line rig (one TRS-IO-E, ``configured = ["TRS-IO-E"]``), the wire's master in
    charge from power-up, the TRS-CAT asked for PRE-OP."""
    rig = build_rig(parse_rig_spec(line_spec(), "wire.toml"))
    rig.devices["master"].set_external(True)  # as --ethercat-if: the wire's master runs it
    trs = rig.devices["trscat"]
    face = faces.face_for(trs)
    face.request_state(trs, AlState.PREOP)
    rig.run_until(1_000_000)
    assert trs.al_state is AlState.PREOP
    return rig, face, trs


def _f030(face: faces.Face, trs: object) -> list[int]:
    return [face.upload(trs, 0xF030, sub) for sub in range(3)]


def test_a_wire_master_finds_the_seed_default_in_preop() -> None:
    _, face, trs = _preop()
    assert _f030(face, trs) == [1, IO_B, 0]


def test_a_wire_master_that_writes_nothing_is_refused_at_ps() -> None:
    rig, face, trs = _preop()
    trs.take_emergencies()
    face.request_state(trs, AlState.SAFEOP)
    rig.run_until(rig.clock.now_us + 200_000)
    assert faces.al_status(trs) == (int(AlState.PREOP) | 0x10, 0x0070)
    assert trs.snapshot()["leds"]["ERROR"] == "blinking"
    [message] = trs.snapshot()["diagnosis"]["messages"]  # 0xA000 in 0x10F3, slot 1 (§9.3.7)
    assert (message["diag_code"], message["params"]) == ("0xE800A000", [1])
    assert trs.take_emergencies() == []  # 0x10F3:5 bit 0 (emergencies) unwritten, off


def test_a_wire_master_that_writes_the_list_reaches_safeop() -> None:
    rig, face, trs = _preop()
    face.download(trs, 0xF030, 0, 2)
    face.download(trs, 0xF030, 2, IO_E)
    face.request_state(trs, AlState.SAFEOP)
    rig.run_until(rig.clock.now_us + 200_000)
    assert faces.al_status(trs) == (int(AlState.SAFEOP), 0x0000)
    rig.apply("trscat", "power", {"on": False})
    rig.step()
    rig.apply("trscat", "power", {"on": True})
    face.request_state(trs, AlState.PREOP)
    rig.run_until(rig.clock.now_us + 1_000_000)
    assert _f030(face, trs) == [1, IO_B, 0]  # a power cycle: §9.3.2's default again
