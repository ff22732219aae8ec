"""The master port's link is a PHY property (ETG.1000.4: the link partner's PHY powered and the
cable in), apart from whether the slave behind it answers (the working counter). A drive whose
c9 does not select EtherCAT (seed 004 ch. 2: c9 is read at power-up) is powered, its ESC passes
the frames on, but it does not answer: the master's port has link and the slave is silent."""

from __future__ import annotations

from typing import Any

from line_bench import US, master_view

from app.rig import Rig
from app.rig_config import build_rig, parse_rig_spec

SAVE_US = 3_500_000  # the drive's flash save takes 3 s (seed 004 ch. 4, flashsave.py)


def _drive_first(c9: int | None = None, fastcat: bool = True) -> Rig:
    """master -> the drive's CoE side -> (a FastCAT); ``c9`` the drive's at its first power-up."""
    line = '"drive_ec-ecat", "fastcat"' if fastcat else '"drive_ec-ecat"'
    params = f"parameters = {{ c9 = {c9} }}\n" if c9 is not None else ""
    box = '[[fastcat]]\nid = "fastcat"\nmodules = ["DI16"]\n' if fastcat else ""
    text = (f'[rig]\nname = "drive first"\nseed = 1\nstep_ms = 1\n[master]\nline = [{line}]\n'
            f'[[servo]]\nid = "drive_ec"\nfieldbus = "ethercat"\nnode_id = 3\n{params}{box}')
    return build_rig(parse_rig_spec(text))


def _view(rig: Rig, until_us: int) -> dict[str, Any]:
    rig.run_until(until_us)
    return master_view(rig)


def test_a_powered_first_slave_that_does_not_answer_leaves_the_port_link_up() -> None:
    rig = _drive_first(c9=3)  # the drive on Modbus: powered, silent on the EtherCAT line
    view = _view(rig, 4 * US)
    assert [s["present"] for s in view["slaves"]] == [False, True]
    assert view["link"] is True
    assert view["phase"] == "running"  # the FastCAT behind it answers and is in OP
    assert view["stats"]["frames"] > 0  # with link the master sends its frames
    rig.apply("master", "pull_cable", {"cable": 0})
    assert _view(rig, 4 * US + 10_000)["link"] is False
    rig.apply("master", "plug_cable", {"cable": 0})
    assert _view(rig, 4 * US + 20_000)["link"] is True
    rig.apply("master", "power_slave", {"position": 0, "on": False})  # no link partner
    assert _view(rig, 4 * US + 30_000)["link"] is False


def test_link_up_and_no_slave_answering_is_not_waiting_for_link() -> None:
    view = _view(_drive_first(c9=3, fastcat=False), 2 * US)
    assert (view["link"], view["phase"]) == (True, "no_answer")
    assert not view["slaves"][0]["present"]


def test_a_slave_silent_behind_a_port_with_link_is_diagnosed_without_a_link_finding() -> None:
    """The drive powered off: link down on the master port. Powered again with c9 = 3 (Modbus)
    latched: the port has link, the FastCAT is found again, the drive stays silent and its
    diagnosis drops the link finding the port no longer reads."""
    rig = _drive_first()
    rig.run_until(4 * US)
    rig.apply("drive_ec", "write_parameter", {"parameter": "c9", "value": 3})
    rig.apply("drive_ec", "save", {})
    rig.run_until(4 * US + SAVE_US)
    rig.apply("drive_ec", "power", {"on": False})
    view = _view(rig, 5 * US + SAVE_US)
    assert view["link"] is False
    assert [s["diagnosis"] for s in view["slaves"]] == [
        "no answer from position 0 on (link down on the master port)"] * 2
    rig.apply("drive_ec", "power", {"on": True})
    view = _view(rig, 8 * US + SAVE_US)
    assert view["link"] is True
    assert [s["present"] for s in view["slaves"]] == [False, True]
    assert [s["diagnosis"] for s in view["slaves"]] == [
        "no answer from position 0, position 1 answers", ""]


def _drive_leds(rig: Rig) -> dict[str, str]:
    return rig.snapshot()["devices"]["drive_ec"]["leds"]


def test_the_out_port_lights_with_a_next_slave_cabled_and_powered() -> None:
    """Seed 004 ch. 5: one L/A per RJ45. The drive's OUT port has link while the next slave
    is cabled and powered, and flickers with the frames it passes on."""
    rig = _drive_first()  # master -> drive -> FastCAT
    rig.run_until(4 * US)
    assert _drive_leds(rig)["L/A OUT"] == "flickering"  # the frames pass on to the FastCAT
    rig.apply("master", "pull_cable", {"cable": 1})
    rig.run_until(4 * US + 10_000)
    assert (_drive_leds(rig)["L/A IN"], _drive_leds(rig)["L/A OUT"]) == ("flickering", "off")
    assert rig.snapshot()["devices"]["drive_ec-ecat"]["link_out"] is False
    rig.apply("master", "plug_cable", {"cable": 1})
    rig.run_until(4 * US + 20_000)
    assert _drive_leds(rig)["L/A OUT"] == "flickering"
    rig.apply("master", "power_slave", {"position": 1, "on": False})  # no link partner
    rig.run_until(4 * US + 30_000)
    assert _drive_leds(rig)["L/A OUT"] == "off"
