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
    rig = _rig()
    rig.apply(device, action, {"connected": False, "port": port})
    events = rig.advance(300)
    assert _present(rig) == [True] * kept + [False] * (4 - kept)
    lost = [e.text for e in events
            if e.device == "master" and "slave lost" in getattr(e, "text", "")]
    # What the master reads where its frames stop: the OUT port of the last slave that
    # answers (its DL status); which end was pulled is the instructor's injected cause.
    cut = f"no link on port 1 (OUT) of position {kept - 1}"
    assert len(lost) == 4 - kept and all(
        text.endswith(f"slave lost: no answer from position {kept} on.") for text in lost)
    master = rig.snapshot()["devices"]["master"]
    assert {s["diagnosis"] for s in master["slaves"][kept:]} == {
        f"no answer from position {kept} on ({cut})"}
    at = NAMES.index(device)
    causes = [c["cause"] for c in master["injected"]["lost"]]
    own = f"no link on the {port.upper()} port of the slave at position {at}"
    assert causes[1 if port == "in" else 0:] == [own] * (3 - kept if port == "in" else 4 - kept)
    rig.apply(device, action, {"connected": True, "port": port})
    rig.advance(8000)
    assert _present(rig) == [True] * 4


def _rig():
    rig = build_rig(load_rig_spec("static/rigs/default.toml"))
    rig.advance(8000)
    assert _present(rig) == [True] * 4
    return rig


def _leds(rig, device: str) -> dict[str, str]:
    leds = rig.snapshot()["devices"][device]["leds"]
    return {name: led if isinstance(led, str) else led["pattern"] for name, led in leds.items()}


def _cable_2(rig, how: str, connected: bool) -> None:
    """Cable 2 (TRS-CAT OUT -> CPX-E-EC IN) pulled or plugged by the master or at one end."""
    if how == "pull_cable":
        rig.apply("master", "plug_cable" if connected else "pull_cable", {"cable": 2})
    elif how == "own_out":
        rig.apply("trscat", "link", {"connected": connected, "port": "out"})
    else:
        rig.apply("cpx", "cable", {"connected": connected, "port": "in"})


@pytest.mark.parametrize("how", ["pull_cable", "own_out", "own_in"])
def test_the_neighbour_sees_the_cut_as_when_the_master_pulls_the_cable(how) -> None:
    """Cable 2 (TRS-CAT OUT -> CPX-E-EC IN) pulled at either end, or by the master: both ports
    of that cable lose their link (LEDs, reachable, the master's reach) alike."""
    rig = _rig()
    master, trs, cpx = (rig.devices[d] for d in ("master", "trscat", "cpx"))
    _cable_2(rig, how, connected=False)
    rig.advance(300)
    assert (trs.link_out, cpx.link_in, cpx.reachable()) == (False, False, False)
    assert not master._connected(2) and not master._connected(3) and master._connected(1)
    assert _leds(rig, "cpx")["LA IN"] == "off"
    assert _leds(rig, "trscat")["LINK-ACT OUT"] == "off"
    _cable_2(rig, how, connected=True)
    rig.advance(8000)
    assert (trs.link_out, cpx.link_in, cpx.reachable()) == (True, True, True)
    assert master._connected(3) and _present(rig) == [True] * 4
    assert _leds(rig, "cpx")["LA IN"] != "off"


def test_the_slave_s_own_plug_and_the_master_s_cable_do_not_overwrite_each_other() -> None:
    rig = _rig()
    trs, cpx = rig.devices["trscat"], rig.devices["cpx"]
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.advance(300)
    # Pulling and plugging back the TRS-CAT's OUT plug does not plug the master's cable in.
    rig.apply("trscat", "link", {"connected": False, "port": "out"})
    rig.apply("trscat", "link", {"connected": True, "port": "out"})
    rig.advance(300)
    assert (trs.link_out, cpx.link_in) == (False, False)
    assert _leds(rig, "trscat")["LINK-ACT OUT"] == "off"
    # The master's cable back in while the TRS-CAT's own plug is out: still no link.
    rig.apply("trscat", "link", {"connected": False, "port": "out"})
    rig.apply("master", "plug_cable", {"cable": 2})
    rig.advance(300)
    assert (trs.link_out, cpx.link_in) == (False, False)
    assert _present(rig) == [True, True, False, False]
    rig.apply("trscat", "link", {"connected": True, "port": "out"})
    rig.advance(8000)
    assert (trs.link_out, cpx.link_in) == (True, True)
    assert _present(rig) == [True] * 4


def test_external_mode_delivers_no_frame_past_a_slave_s_own_pulled_cable() -> None:
    rig = _rig()
    master, cpx = rig.devices["master"], rig.devices["cpx"]
    master.set_external(True)
    rig.apply("trscat", "link", {"connected": False, "port": "out"})
    rig.advance(300)
    before = cpx.last_frame_us
    master.external_frame(2)
    assert cpx.last_frame_us == before and not master._connected(2)
    rig.apply("trscat", "link", {"connected": True, "port": "out"})
    rig.advance(10)
    master.external_frame(2)
    assert cpx.last_frame_us == master.now_us


@pytest.mark.parametrize(("device", "lost", "port_down"), [
    ("drive_ec-ecat", [3], ("cpx", "link_out")),  # the last slave's IN: the CPX-E-EC's OUT
    ("fastcat", [0, 1, 2, 3], None),  # cable 0: the master's own port, no slave's
])
def test_the_drive_s_and_the_fastcat_s_own_link_are_their_in_cable(device, lost,
                                                                  port_down) -> None:
    rig = _rig()
    rig.apply(device, "link", {"connected": False})
    rig.advance(300)
    assert [not p for p in _present(rig)] == [p in lost for p in range(4)]
    if port_down is not None:
        assert getattr(rig.devices[port_down[0]], port_down[1]) is False
    rig.apply(device, "link", {"connected": True})
    rig.advance(8000)
    assert _present(rig) == [True] * 4
    if port_down is not None:
        assert getattr(rig.devices[port_down[0]], port_down[1]) is True


def _cables(rig) -> list[dict]:
    return rig.snapshot()["devices"]["master"]["cables"]


@pytest.mark.parametrize(("how", "pulled_at", "master_pulled"), [
    ("pull_cable", [], True),
    ("own_out", ["trscat OUT"], False),
    ("own_in", ["cpx IN"], False),
])
def test_the_snapshot_s_cable_is_plugged_only_when_both_its_ends_are(how, pulled_at,
                                                                     master_pulled) -> None:
    """The line view: a cable pulled at a slave's own port reads pulled, at that end, as the
    slaves' ``link`` reads it lost; the master's own pull is told apart (``master_pulled``),
    which is what its pull / plug controls move."""
    rig = _rig()
    _cable_2(rig, how, connected=False)
    rig.advance(300)
    cables = _cables(rig)
    assert [c["plugged"] for c in cables] == [True, True, False, True]
    assert [c["pulled_at"] for c in cables] == [[], [], pulled_at, []]
    assert [c["master_pulled"] for c in cables] == [False, False, master_pulled, False]
    links = rig.snapshot()["devices"]["master"]["injected"]["link"]
    assert links == [all(c["plugged"] for c in cables[: p + 1]) for p in range(4)]
    _cable_2(rig, how, connected=True)
    rig.advance(10)
    assert all(c["plugged"] and not c["pulled_at"] and not c["master_pulled"]
               for c in _cables(rig))


def test_a_cable_pulled_at_both_ends_and_by_the_master_names_every_one() -> None:
    rig = _rig()
    for how in ("pull_cable", "own_out", "own_in"):
        _cable_2(rig, how, connected=False)
    cable = _cables(rig)[2]
    assert (cable["plugged"], cable["master_pulled"]) == (False, True)
    assert cable["pulled_at"] == ["trscat OUT", "cpx IN"]
    _cable_2(rig, "pull_cable", connected=True)  # the master's cable back: still out at both
    assert (_cables(rig)[2]["plugged"], _cables(rig)[2]["master_pulled"]) == (False, False)


@pytest.mark.parametrize(("device", "cable", "end"), [
    ("fastcat", 0, "fastcat IN"), ("drive_ec-ecat", 3, "drive_ec-ecat IN")])
def test_the_fastcat_s_and_the_drive_s_own_link_is_their_in_end(device, cable, end) -> None:
    rig = _rig()
    rig.apply(device, "link", {"connected": False})
    cables = _cables(rig)
    assert [c["plugged"] for c in cables] == [c["index"] != cable for c in cables]
    assert cables[cable]["pulled_at"] == [end]


def test_the_cable_reads_pulled_at_once_its_other_end_s_port_a_step_later() -> None:
    """docs/ethercat-master.md: the slave's own port goes down with its action, the other end's
    port at the master's next step (1 ms). The cable is the plug as it is: out at once, as
    the slaves' ``link`` (the master's reach, read afresh) has it."""
    rig = _rig()
    trs = rig.devices["trscat"]
    rig.apply("cpx", "cable", {"connected": False, "port": "in"})
    snap = rig.snapshot()["devices"]["master"]
    assert snap["cables"][2]["plugged"] is False and snap["cables"][2]["pulled_at"] == ["cpx IN"]
    assert snap["injected"]["link"] == [True, True, False, False]
    assert trs.link_out is True  # the TRS-CAT's OUT port follows at the master's next step
    rig.advance(1)
    assert trs.link_out is False
