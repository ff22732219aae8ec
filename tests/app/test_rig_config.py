"""Rig files: one clear error naming file, key and reason (issue 2 §2)."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.rig_config import DEFAULT_RIG, RigConfigError, load_rig_spec, parse_rig_spec

GOOD = """
[rig]
name = "bench"
seed = 7
[[fastcat]]
id = "fc"
modules = ["DB16", {type = "AI8TC"}]
"""


def test_default_rig_parses() -> None:
    spec = load_rig_spec(DEFAULT_RIG)
    assert spec.fastcats[0].id == "fastcat"
    # issue 3: one drive on Modbus at node 1 with TEN and IEN wired
    wanted = {"fieldbus": "modbus", "node_id": 1, "ten_wired": True, "ien_wired": True}
    assert wanted.items() <= spec.servos[0].settings.items()
    assert [m.type for m in spec.fastcats[0].modules][:2] == ["DB16", "DI16"]


def test_good_rig() -> None:
    spec = parse_rig_spec(GOOD, "bench.toml")
    assert spec.name == "bench" and spec.seed == 7 and spec.step_us == 1000
    assert [m.type for m in spec.fastcats[0].modules] == ["DB16", "AI8TC"]


@pytest.mark.parametrize(("text", "key", "reason"), [
    ("[rig]\ncolour = 1\n", "rig.colour", "unknown key"),
    ("bogus = 1\n", "bogus", "unknown key"),
    ("[[fastcat]]\nmodules = [\"DB17\"]\n", "fastcat[0].modules[0]", "unknown module type 'DB17'"),
    ("[[fastcat]]\nmodules = [" + ", ".join(['"DI16"'] * 17) + "]\n", "fastcat[0].modules",
     "at most 16"),
    ("[[fastcat]]\nmodules = []\nrotary_switch = 0\n", "fastcat[0].rotary_switch",
     "between 1 and 15"),
    ("[[fastcat]]\nmodules = []\nrotary_switch = \"one\"\n", "fastcat[0].rotary_switch",
     "must be int"),
    ("[[fastcat]]\nmodules = []\nrotary_switch = true\n", "fastcat[0].rotary_switch",
     "must be int"),
    ("[[fastcat]]\nrotary_switch = 2\n", "fastcat[0].modules", "is required"),
    ("[[fastcat]]\nmodules = [{options = 1}]\n", "fastcat[0].modules[0]", "needs type"),
    ("[[fastcat]]\nmodules = [3]\n", "fastcat[0].modules[0]", "module name or a table"),
    ("[rig]\nstep_ms = 0\n", "rig.step_ms", "between"),
    ("[rig]\nepoch = \"yesterday\"\n", "rig.epoch", "ISO date-time"),
    ("[[fastcat]]\nid = \"a\"\nmodules = []\n[[fastcat]]\nid = \"a\"\nmodules = []\n",
     "fastcat[1].id", "duplicate"),
    ("[rig\n", "", "not valid TOML"),
    # c7's range follows the fieldbus (seed 004 ch. 2: a Modbus line has slaves 1..90 only)
    ("[[servo]]\nnode_id = 0\n", "servo[0]", "outside 1..90"),
    ("[[servo]]\nnode_id = 500\n", "servo[0]", "node_id 500 is outside 1..90 on Modbus"),
    ("[[servo]]\nnode_id = 91\n", "servo[0]", "outside 1..90"),
    ("[[servo]]\nfieldbus = \"canopen\"\nnode_id = 500\n", "servo[0]",
     "node_id 500 is outside 1..99 on CANopen"),
    ("[[servo]]\nfieldbus = \"ethercat\"\nnode_id = 100\n", "servo[0]", "outside 1..99"),
    ("[[servo]]\nfieldbus = \"profibus\"\n", "servo[0]", "not one of"),
    ("[[servo]]\nfeed_constant = 1.5\n", "servo[0].feed_constant", "must be int"),
    ("[[servo]]\nwheels = 4\n", "servo[0].wheels", "unknown key"),
    ("[[servo]]\nid = \"a\"\n[[servo]]\nid = \"b\"\n", "servo[1].node_id",
     "already used on the Modbus line"),
    ("[[servo]]\nid = \"master\"\n", "servo[0].id", "reserved"),
    ("[[trscat]]\nexpansions = \"TRS-IO-E\"\n", "trscat[0].expansions", "must be list"),
    ("[[cpx]]\nfoo = 1\n", "cpx[0].foo", "unknown key"),
    ("[master]\nline = [\"x\"]\n[[cpx]]\n", "master.line[0]", "not an EtherCAT slave"),
    ("[master]\nline = []\n[[cpx]]\n", "master.line", "every EtherCAT slave once"),
])
def test_errors_name_file_key_reason(text: str, key: str, reason: str) -> None:
    with pytest.raises(RigConfigError) as info:
        parse_rig_spec(text, "bad.toml")
    assert info.value.source == "bad.toml"
    assert info.value.key == key
    assert reason in info.value.reason
    assert str(info.value).startswith("bad.toml: ")


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(RigConfigError, match="cannot read rig file"):
        load_rig_spec(tmp_path / "nope.toml")


def test_ethercat_line_rig_builds_in_line_order() -> None:
    """Issue 5: master -> FastCAT -> TRS-CAT -> CPX-E-EC, station addresses 1001.. in order."""
    from app.rig_config import build_rig

    rig = build_rig(load_rig_spec(DEFAULT_RIG.parent / "ethercat_line.toml"), state_dir=None)
    master = rig.devices["master"].snapshot()
    assert [(s["name"], s["station_address"]) for s in master["slaves"]] == [
        ("Box 1 (FastCAT)", 1001), ("Box 2 (TRS-CAT)", 1002), ("Box 3 (CPX-E-EC)", 1003),
        ("Drive 4 (SelemaDriveECAT)", 1004)]


def test_ethercat_line_rig_names_its_devices_as_the_default_rig() -> None:
    """The line rig is the default rig without the CANopen drive: its scenarios play on the
    default rig, so a device id (and the master's line entry) means the same device in both."""
    from app.rig_config import build_rig

    line = build_rig(load_rig_spec(DEFAULT_RIG.parent / "ethercat_line.toml"), state_dir=None)
    default = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    kinds = {name: type(device) for name, device in default.devices.items()}
    assert {name: type(device) for name, device in line.devices.items()}.items() \
        <= kinds.items()
    assert load_rig_spec(DEFAULT_RIG.parent / "ethercat_line.toml").line \
        == load_rig_spec(DEFAULT_RIG).line


def test_bad_slave_configuration_is_one_clear_error() -> None:
    from app.rig_config import build_rig

    spec = parse_rig_spec('[[cpx]]\nmodules = ["CPX-E-99XX"]\n', "bad.toml")
    with pytest.raises(RigConfigError) as info:
        build_rig(spec, state_dir=None)
    assert info.value.key == "cpx" and "CPX-E-99XX" in info.value.reason


@pytest.mark.parametrize("step_ms", [0.5, 2])
def test_master_without_mapping_cycles_every_rig_step(step_ms: float) -> None:
    """No [master] mapping: the master's cycle is the rig step (docs/ethercat-master.md
    start-up 3, docs/rig-file.md `step_ms`), one frame a step - not a fixed 1 ms, which
    sent frames every other step at 0.5 ms and claimed a 1 ms cycle (DC SYNC0, stats) at 2."""
    from app.rig_config import build_rig

    spec = parse_rig_spec(f'[rig]\nstep_ms = {step_ms}\n[[cpx]]\nid = "cpx"\n', "step.toml")
    rig = build_rig(spec, state_dir=None)
    master = rig.devices["master"]
    assert master.cycle_us == spec.step_us
    assert master.snapshot()["stats"]["cycle_us"] == spec.step_us
    rig.advance(40)
    assert master.frames == 40


@pytest.mark.parametrize(("text", "key", "reason"), [
    ("[[servo]]\nid = \"a\"\nflash = \"drive.flash\"\n[[servo]]\nid = \"b\"\nnode_id = 2\n"
     "flash = \"drive.flash\"\n", "servo[1].flash",
     "'drive.flash' is servo[0]'s flash file too: two devices would overwrite each other's "
     "saved settings (give each its own file, or \":memory:\")"),
    ("[[fastcat]]\nmodules = []\nflash = \"flash/x.bin\"\n[[servo]]\nflash = \"./flash//x.bin\"\n",
     "servo[0].flash", "'./flash//x.bin' is fastcat[0]'s flash file too"),
])
def test_two_devices_on_one_flash_file_are_refused(text: str, key: str, reason: str) -> None:
    """Two drives with ``flash = "drive.flash"`` loaded: a flash file holds one device's
    image (app/flash_file.py), so each save replaced the other's under --state-dir and at the
    next start both devices read the image saved last. Paths are compared normalised."""
    with pytest.raises(RigConfigError) as info:
        parse_rig_spec(text, "two.toml")
    assert str(info.value).startswith(f"two.toml: {key}: {reason}")


def test_memory_flash_may_be_shared() -> None:
    spec = parse_rig_spec("[[servo]]\nid = \"a\"\nflash = \":memory:\"\n[[servo]]\nid = \"b\"\n"
                          "node_id = 2\nflash = \":memory:\"\n", "mem.toml")
    assert [s.flash for s in spec.servos] == [":memory:", ":memory:"]


@pytest.mark.parametrize(("text", "key", "hint"), [
    ("[rig]\nnmae = \"x\"\n", "rig.nmae", "did you mean 'name'?"),
    ("[[fastcat]]\nmodules = [\"DB17\"]\n", "fastcat[0].modules[0]", "did you mean 'DB16'?"),
    ("[[fastcat]]\nmodules = [\"db16\"]\n", "fastcat[0].modules[0]", "did you mean 'DB16'?"),
    ("[[servo]]\nnode_di = 3\n", "servo[0].node_di", "did you mean 'node_id'?"),
    ("[master]\nline = [\"cpx_\"]\n[[cpx]]\n", "master.line[0]", "did you mean 'cpx'?"),
    ("[[fastcats]]\n", "fastcats", "did you mean 'fastcat'?"),
])
def test_an_unknown_name_says_what_was_meant(text: str, key: str, hint: str) -> None:
    """The reason names the closest allowed name (devices/names.py did_you_mean), the
    scenarios' and the device commands' hint."""
    with pytest.raises(RigConfigError) as info:
        parse_rig_spec(text, "bad.toml")
    assert info.value.key == key or info.value.key.startswith(key), info.value
    assert info.value.reason.endswith(hint), info.value.reason


@pytest.mark.parametrize(("text", "hint"), [
    ("[[trscat]]\nexpansions = [\"TRS-IO-F\"]\n", "did you mean 'TRS-IO-E'?"),
    ("[[cpx]]\nmodules = [\"CPX-E-8D0\"]\n", "did you mean 'CPX-E-8DO'?"),
    ("[[fastcat]]\nmodules = [{type = \"AI8TC\", thermocuple = \"J\"}]\n",
     "did you mean 'thermocouple'?"),
])
def test_an_unknown_module_name_says_what_was_meant(text: str, hint: str) -> None:
    from app.rig_config import build_rig

    with pytest.raises(RigConfigError) as info:
        build_rig(parse_rig_spec(text, "bad.toml"), state_dir=None)
    assert hint in info.value.reason, info.value.reason
