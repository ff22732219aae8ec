"""The kernel benchmark's floor rig stands for the real rig: same devices, same master line."""

from __future__ import annotations

from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from bench._kernel_floor import _Master, stand_in


def test_the_floor_rig_has_the_rigs_devices_and_the_masters_line() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    floor = stand_in(rig)
    assert list(floor.devices) == list(rig.devices)
    master = floor.devices["master"]
    assert isinstance(master, _Master)
    assert [s.device_id for s in master.slaves] == \
        [link.slave.device_id for link in rig.devices["master"].links]
    for _ in range(25):
        floor.step()
    assert floor.clock.now_us == 25 * rig.clock.step_us
    assert all(s.frames == 25 for s in master.slaves)
    assert all(d.now_us == floor.clock.now_us for d in floor.devices.values())
