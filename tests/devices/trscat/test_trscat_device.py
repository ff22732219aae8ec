"""The TRS-CAT device: construction from rig values, power, LEDs of seed 001 §8, links,
actions, snapshot and determinism."""

from __future__ import annotations

import json
import random

import pytest
from trscat_bench import Bench, detect_us

from devices.device import CommandError
from devices.ethercat import AlState
from devices.trscat.commands import ACTIONS
from devices.trscat.device import TrsCat


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"expansions": ["IO-E"] * 8}, "at most 7"),
    ({"expansions": ["KK-E", "KK-E", "KK-E", "IO-E", "IO-E"]}, "do not fit"),  # §5
    ({"expansions": ["IO-E", "ZZ-E"]}, "expansion 2: unknown TRS expansion"),
    ({"expansions": "IO-E"}, "a list of names"),
    ({"sync_mode": "sm"}, "'dc' .* or 'free_run'"),
    ({"field_supply_v": 50.0}, "0..40 V"),
])
def test_construction_errors(kwargs: dict, message: str) -> None:
    """Rig values checked against §5, §9.3.2, §9.1.1; ValueError for the rig loader."""
    with pytest.raises(ValueError, match=message):
        TrsCat("trscat", random.Random(0), **kwargs)


def test_power_up_and_down() -> None:
    """§8.2: BUS off at start-up (normal), on once the TRS bus runs; power off: all dark."""
    bench = Bench(["IO-E"])
    assert bench.leds()["BUS"] == "off" and bench.leds()["+24V"] == "on"
    bench.run_until(lambda: bench.trs.od is not None)
    assert bench.now == detect_us(2)
    assert bench.leds()["BUS"] == "on"
    bench.apply("power", on=False)
    snap = bench.trs.snapshot()
    assert snap["esm"] == "INIT" and not snap["powered"] and not bench.trs.reachable()
    assert set(snap["leds"].values()) == {"off"}
    with pytest.raises(CommandError, match="not powered"):
        bench.read(0x1000, 0)


def test_volatile_objects_reset_at_power_up() -> None:
    bench = Bench()
    bench.to_state(AlState.PREOP)
    bench.write(0xF701, 1, 0xFFFF)
    bench.write(0x10F3, 5, 0x0002)
    bench.apply("power", on=False)
    bench.apply("power", on=True)
    bench.settle()
    assert bench.read(0xF701, 1) == 0 and bench.read(0x10F3, 5) == 0


@pytest.mark.parametrize(("port", "led"), [("in", "LINK-ACT IN"), ("out", "LINK-ACT OUT")])
def test_link_leds(port: str, led: str) -> None:
    """§8.1 -> ETG.1300 L/A: off without link, flickering with traffic, on without."""
    bench = Bench(out_link=True)
    bench.settle()
    assert bench.leds()[led] == "flickering"
    bench.apply("link", port=port, connected=False)
    bench.step()
    assert bench.leds()[led] == "off"
    bench.apply("link", port=port, connected=True)
    bench.frames = False
    bench.run(0.1)
    assert bench.leds()[led] == "on"


def test_cable_pulled_in_op_and_plugged_back() -> None:
    """No frames: the DC sync error takes the device to SAFE-OP + error (§9.1.1); with the
    cable back the built-in master brings it to OP again."""
    bench = Bench(master=True)
    bench.run(1.0)
    assert bench.trs.al_state is AlState.OP
    bench.apply("link", port="in", connected=False)
    bench.run(0.01)
    assert bench.trs.al_state is AlState.SAFEOP and bench.trs.al_status_code == 0x001A
    assert not bench.trs.reachable()
    bench.apply("link", port="in", connected=True)
    bench.run(3.0)
    assert bench.trs.al_state is AlState.OP and bench.leds()["ERROR"] == "off"


def test_every_action_has_a_handler() -> None:
    trs = Bench().trs
    for name in ACTIONS:
        assert callable(getattr(trs, f"cmd_{name}"))
    assert trs.ACTIONS is ACTIONS


@pytest.mark.parametrize(("action", "args", "module", "message"), [
    ("unplug", {}, None, "needs a module"),
    ("power", {"on": True}, 1, "takes the device"),
    ("plug", {"type": "TRS-IO-E"}, 1, "holds a TRS-IO-E"),
    ("plug", {"type": "TRS-KK-E"}, 8, "positions 1..7"),
    ("link", {"port": "middle", "connected": True}, None, "not one of"),
])
def test_action_errors(action: str, args: dict, module: int | None, message: str) -> None:
    bench = Bench(["IO-E"])
    with pytest.raises(CommandError, match=message):
        bench.apply(action, module=module, **args)


def test_plug_respects_the_slot_limits() -> None:
    """§5: three smart expansions leave room for one standard one."""
    bench = Bench(["KK-E", "AC-E", "KK-E", "IO-E"])
    with pytest.raises(CommandError, match="do not fit"):
        bench.apply("plug", module=5, type="TRS-XX-E")


def test_plug_under_power_is_seen_at_the_next_power_up() -> None:
    """§9.2: the configuration is detected at power-up only."""
    bench = Bench()
    bench.settle()
    bench.apply("plug", module=1, type="TRS-IO-E")
    assert bench.trs.f050[0] == 1
    assert any("not allowed" in r["text"] for r in bench.records("log"))
    bench.apply("power", on=False)
    bench.apply("power", on=True)
    bench.settle()
    assert bench.trs.f050[0] == 2


@pytest.mark.parametrize(("action", "args"), [
    ("unplug", {}), ("plug", {"type": "TRS-IO-E"})])
@pytest.mark.parametrize("module", [0, -1])
def test_the_integrated_module_is_no_expansion_position(action: str, args: dict,
                                                        module: int) -> None:
    """§5 / §9.3.2: slot 0 is the module "integrato direttamente in TRS-CAT", part of the
    base; expansions sit at positions 1..7. The model's own check let ``unplug`` at module 0
    take the integrated I/O off the rail (and -1 the last expansion), and the next step
    crashed on the missing base; a plug there was refused with "unplug it first". (The app's
    targets never name module 0: app/targets.py refuses "trscat/0".) Both are refused by
    check_command, and the rail is as it was."""
    bench = Bench(["IO-E"])
    before = [io.kind.name if io else None for io in bench.trs.rail]
    with pytest.raises(CommandError, match=r"positions 1\.\.7"):
        bench.trs.check_command(action, args, module)
    with pytest.raises(CommandError, match=r"positions 1\.\.7"):
        bench.apply(action, module=module, **args)
    assert [io.kind.name if io else None for io in bench.trs.rail] == before
    bench.run(0.01)


def test_write_object_takes_toml_booleans() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("write_object", index=0x7000, sub=3, value=True)
    assert bench.read(0x7000, 3) == 1


def test_emergencies_need_the_mailbox() -> None:
    """The mailbox runs from PRE-OP on (§9.2 INIT: no mailbox)."""
    bench = Bench()
    bench.settle()
    bench.trs.mailbox = [b"\x00" * 8]
    assert bench.trs.take_emergencies() == []
    bench.request(AlState.PREOP)
    assert bench.trs.take_emergencies() == [b"\x00" * 8]


def test_snapshot_is_json_and_complete() -> None:
    bench = Bench(["IO-E", "AN-E", "KK-E"], configured=["IO-E", "AN-E", "KK-E"])
    bench.to_state(AlState.OP)
    snap = bench.trs.snapshot()
    json.dumps(snap)
    for key in ("kind", "id", "powered", "esm", "al_status", "al_status_code", "leds", "slots",
                "sync", "trs_bus", "diagnosis", "f030", "f050"):
        assert key in snap
    assert snap["kind"] == "trscat" and len(snap["slots"]) == 4
    assert {"RUN", "ERROR", "LINK-ACT IN", "LINK-ACT OUT", "BUS", "+24V", "I/O 1",
            "I/O 16"} <= set(snap["leds"])


def test_led_events_only_on_change() -> None:
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.clear()
    bench.run(0.5)
    assert bench.records("led") == []


def test_same_seed_same_run() -> None:
    """Randomness only from the rig's rng (jitter, serial number)."""
    def run() -> list[dict]:
        bench = Bench(["IO-E"], master=True, configured=["IO-E"], seed=11)
        bench.run(0.6)
        bench.apply("frame_jitter", us=1100)
        bench.run(2.0)
        return bench.records()
    assert run() == run()
