"""ECAT_Notify / ECAT_Resync hooks and the external (wire master) mode (seed 003)."""

from __future__ import annotations

from typing import Any

from line_bench import IN_OP_US, LINE_RIG, US, line_in_op, master_view

from app.rig_config import build_rig, load_rig_spec
from devices.ethercat import AlState
from devices.events import Event, Resync, SlaveStateChange


def test_notify_runs_after_the_diagnostic_structures_are_updated() -> None:
    rig = build_rig(load_rig_spec(LINE_RIG))
    master = rig.devices["master"]
    seen: list[tuple[Any, ...]] = []
    changes: dict[int, int] = {}

    def notify(event: Event) -> None:
        if isinstance(event, SlaveStateChange) and event.from_state:
            # the structure already counts this change (and maybe later ones of the step)
            changes[event.position] = changes.get(event.position, 0) + 1
            counted = master.slave_at(event.position)["counters"]["state_changes"]
            seen.append((changes[event.position], counted))

    master.on_notify(notify)
    rig.run_until(IN_OP_US)
    assert seen and all(mine <= counted for mine, counted in seen)


def test_resync_hook_may_issue_sdos() -> None:
    """ECAT_Resync: the first time a node reaches OP, once per node, then the network."""
    rig = build_rig(load_rig_spec(LINE_RIG))
    master = rig.devices["master"]
    calls: list[int] = []

    def resync(event: Event) -> None:
        assert isinstance(event, Resync)
        calls.append(event.position)
        if event.slave == "trscat":  # an SDO download from the PLC task
            master.links[event.position].slave.sdo_download(0xF710, 1, b"\x01\x00")

    master.on_resync(resync)
    rig.run_until(IN_OP_US + US)
    assert sorted(calls) == [-1, 0, 1, 2, 3] and calls[-1] == -1
    assert rig.devices["trscat"].sysok_mask == 1


def test_external_mode_leaves_the_line_to_the_wire_master() -> None:
    rig = line_in_op()
    master = rig.devices["master"]
    frames = master.frames
    master.set_external(True)
    master.external_request(1, AlState.PREOP)
    rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert view["external"] is True and view["stats"]["frames"] == frames
    assert view["slaves"][1]["state"] == "PREOP"  # nobody takes it back to OP
    assert view["slaves"][1]["requested"] == "PREOP"
    master.external_frame(1)
    master.external_stats(frames=10, lost_frames=2, cycle_us=2000, wkc_errors=1)
    view = master_view(rig)
    assert view["stats"] == {"frames": 10, "lost_frames": 2, "cycle_us": 2000}


def test_external_emergency_is_logged_and_counted() -> None:
    from devices.ethercat import emergency_frame

    rig = line_in_op()
    master = rig.devices["master"]
    master.set_external(True)
    master.external_emergency(2, emergency_frame(0x2320, 0x03, bytes.fromhex("2202020003")))
    events = rig.take_events()
    assert [e.to_record()["data"] for e in events if e.kind == "coe_emergency"] == [
        "22 02 02 00 03"]
    assert master_view(rig)["slaves"][2]["counters"]["emergencies"] == 1
    assert master.log[-1]["text"] == \
        "'Box 3 (CPX-E-EC)' (1003): CoE - Emergency (Hex: 2320, 03, 22 02 02 00 03')."
