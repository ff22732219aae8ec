"""0x10F3:5 "Flags" of the CPX-E-EC: 0x0000 at every power-up (seed 002 Tab. 14), the rig's
``history_flags`` a PS init command the built-in master sends (docs/cpx-e-ec.md choice 19).

Before, the model powered up with the rig's value: a wire master that writes no 0x10F3:5 saw
emergencies on from power-up, and a power cycle brought the 1 back with no write at all.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.network.generate import generate
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec, parse_rig_spec
from devices.ethercat import AlState

ROOT = Path(__file__).resolve().parents[2]
STEP_US = 1000
FLAGS = (0x10F3, 5)
# The CPX-E-EC alone on the built-in master, no network description.
ALONE = """
[rig]
name = "CPX alone"
seed = 3

[[cpx]]
id = "cpx"
dil1 = true
dil2 = false
{flags}
modules = ["CPX-E-16DI", "CPX-E-8DO"]
"""


def _flags(rig: Rig) -> int:
    return int(rig.devices["cpx"].od.peek(*FLAGS))


def _run_to(rig: Rig, state: AlState, limit_s: float = 20.0) -> list[int]:
    """Step until the CPX-E-EC is in ``state``; the flags it had in each state on the way."""
    cpx = rig.devices["cpx"]
    seen: dict[AlState, int] = {}
    end = rig.clock.now_us + round(limit_s * 1e6)
    while cpx.al_state is not state:
        assert rig.clock.now_us < end, f"{state.name} not reached"
        rig.step()
        seen.setdefault(cpx.al_state, _flags(rig))
    return [seen.get(s, -1) for s in (AlState.PREOP, AlState.SAFEOP)]


def test_the_default_rig_powers_up_with_tab14s_default() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    assert _flags(rig) == 0x0000  # Tab. 14: default 0x0000, whatever the rig file says


def test_the_built_in_master_writes_the_rig_value_at_ps() -> None:
    """PREOP still 0x0000; SAFEOP reached with the start-up write done (PS, as TwinCAT's
    Startup tab lists a CoE object by default)."""
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    assert _run_to(rig, AlState.OP) == [0x0000, 0x0001]
    assert _flags(rig) == 0x0001


def test_a_power_cycle_brings_tab14s_default_back_until_the_master_writes() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    _run_to(rig, AlState.OP)
    rig.apply("cpx", "power", {"on": False})
    while rig.devices["cpx"].powered:
        rig.step()
    rig.apply("cpx", "power", {"on": True})
    assert _flags(rig) == 0x0000
    assert _run_to(rig, AlState.OP) == [0x0000, 0x0001]


def test_a_rig_without_description_still_gets_the_write() -> None:
    """An old rig file with history_flags = 1 and no eni: the same flags in OP as before."""
    rig = build_rig(parse_rig_spec(ALONE.format(flags="history_flags = 1"), "alone.toml"))
    assert _flags(rig) == 0x0000
    assert _run_to(rig, AlState.OP) == [0x0000, 0x0001]
    plain = build_rig(parse_rig_spec(ALONE.format(flags=""), "alone.toml"))
    assert _run_to(plain, AlState.OP) == [0x0000, 0x0000]


def _rig_file(tmp_path: Path, eni: str, flags: str = "history_flags = 1") -> Path:
    (tmp_path / "net.eni.xml").write_text(eni)
    text = DEFAULT_RIG.read_text()
    text = re.sub(r'(?m)^(eni|mapping) = .*\n', "", text)
    text = text.replace("[master]\n", '[master]\neni = "net.eni.xml"\n')
    text = text.replace("history_flags = 1\n", flags + "\n" if flags else "")
    (tmp_path / "rig.toml").write_text(text)
    return tmp_path / "rig.toml"


def _generated_eni() -> str:
    text = DEFAULT_RIG.read_text()
    text = re.sub(r'(?m)^(eni|mapping) = .*\n', "", text)
    return generate(text, "static/rigs/default.toml")[0]


def _without_flags_command(eni: str) -> str:
    return re.sub(r"\s*<InitCmd>(?:(?!</InitCmd>).)*#x10F3(?:(?!</InitCmd>).)*</InitCmd>", "",
                  eni, flags=re.S)


def test_the_generator_turns_the_rig_value_into_a_ps_command() -> None:
    eni = _generated_eni()
    block = re.search(r"<InitCmd>(?:(?!</InitCmd>).)*#x10F3(?:(?!</InitCmd>).)*</InitCmd>",
                      eni, flags=re.S)
    assert block is not None, "no 0x10F3 init command in the generated description"
    assert "<Transition>PS</Transition>" in block.group(0)
    assert "<SubIndex>5</SubIndex>" in block.group(0)
    assert "<Data>0100</Data>" in block.group(0)


def test_an_old_description_without_the_command_keeps_working(tmp_path: Path) -> None:
    """A description made before the command existed: the rig's value still goes at PS."""
    old = _without_flags_command(_generated_eni())
    assert "#x10F3" not in old
    rig = build_rig(load_rig_spec(_rig_file(tmp_path, old)))
    assert _run_to(rig, AlState.OP) == [0x0000, 0x0001]


def test_the_description_alone_sets_it(tmp_path: Path) -> None:
    rig = build_rig(load_rig_spec(_rig_file(tmp_path, _generated_eni(), flags="")))
    assert _run_to(rig, AlState.OP) == [0x0000, 0x0001]


def test_rig_and_description_disagreeing_is_one_error(tmp_path: Path) -> None:
    path = _rig_file(tmp_path, _generated_eni(), flags="history_flags = 0")
    with pytest.raises(RigConfigError) as info:
        build_rig(load_rig_spec(path))
    assert info.value.key == "cpx[0].history_flags"
    assert "0x0000" in info.value.reason and "0x0001" in info.value.reason
    assert "net.eni.xml" in info.value.reason


@pytest.mark.parametrize("value", ["0x0100", "-1", "0x20"])
def test_a_wrong_value_is_one_clear_error(value: str) -> None:
    text = ALONE.format(flags=f"history_flags = {value}")
    with pytest.raises(RigConfigError) as info:
        build_rig(parse_rig_spec(text, "alone.toml"))
    assert info.value.key == "cpx[0].history_flags"
    assert "bits 0-4" in info.value.reason and "Tab. 18" in info.value.reason
