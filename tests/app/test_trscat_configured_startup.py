"""0xF030 of the TRS-CAT: §9.3.2's default (1, 0x494F2D42) at every power-up, the rig's
``configured`` list the built-in master's PS init commands (seed 001 §9.2 PS "Invia la
configurazione TRS mediante oggetto 0xF030", §9.3.2 "deve essere inviata dal master a TRS-CAT
durante la transizione PS"; docs/trscat.md "Who writes 0xF030").

Before, the model wrote the rig's list into its own 0xF030 on entering PRE-OP: a master on the
wire that writes nothing reached SAFE-OP, which a real TRS-CAT with expansions refuses (0x0070).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.network.generate import generate
from app.rig import Rig
from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec, parse_rig_spec
from devices.ethercat import AlState
from devices.trscat.catalog import EXPANSIONS, INTEGRATED

IO_B, IO_E, AN_E = INTEGRATED.ident, EXPANSIONS["TRS-IO-E"].ident, EXPANSIONS["TRS-AN-E"].ident
DEFAULT_LIST = [1, IO_B, 0]  # §9.3.2: sub 0 "Default 1", sub 1 0x494F2D42 "(default)"
# The TRS-CAT alone on the built-in master, no network description.
ALONE = """
[rig]
name = "TRS-CAT alone"
seed = 3

[[trscat]]
id = "trscat"
expansions = ["TRS-IO-E", "TRS-AN-E"]
{configured}
"""


def _f030(rig: Rig) -> list[int]:
    return list(rig.devices["trscat"].f030[:3])


def _run_to(rig: Rig, state: AlState, limit_s: float = 10.0) -> dict[AlState, list[int]]:
    """Step until the TRS-CAT is in ``state``; the 0xF030 it had on entering each state."""
    trs = rig.devices["trscat"]
    seen: dict[AlState, list[int]] = {}
    end = rig.clock.now_us + round(limit_s * 1e6)
    while trs.al_state is not state:
        assert rig.clock.now_us < end, \
            f"{state.name} not reached: {trs.al_state.name}, 0x{trs.al_status_code:04X}"
        rig.step()
        seen.setdefault(trs.al_state, list(trs.f030[:4]))
    return seen


def test_preop_has_the_seed_default_until_the_masters_ps_write() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    seen = _run_to(rig, AlState.OP)
    assert seen[AlState.PREOP][:3] == DEFAULT_LIST
    assert seen[AlState.SAFEOP] == [3, IO_B, IO_E, AN_E]


def test_a_power_cycle_brings_the_default_back_until_the_master_writes() -> None:
    rig = build_rig(load_rig_spec(DEFAULT_RIG))
    _run_to(rig, AlState.OP)
    rig.apply("trscat", "power", {"on": False})
    rig.step()
    rig.apply("trscat", "power", {"on": True})
    rig.step()
    assert _f030(rig) == DEFAULT_LIST
    seen = _run_to(rig, AlState.OP)
    assert seen[AlState.PREOP][:3] == DEFAULT_LIST
    assert seen[AlState.SAFEOP] == [3, IO_B, IO_E, AN_E]


def test_a_rig_without_description_still_gets_the_list() -> None:
    rig = build_rig(parse_rig_spec(ALONE.format(
        configured='configured = ["TRS-IO-E", "TRS-AN-E"]'), "alone.toml"))
    seen = _run_to(rig, AlState.OP)
    assert seen[AlState.PREOP][:3] == DEFAULT_LIST
    assert seen[AlState.SAFEOP] == [3, IO_B, IO_E, AN_E]


def test_a_rig_that_configures_nothing_is_refused_at_ps() -> None:
    """No list written: §9.3.2's default (the integrated module alone) against the two
    expansions found, as on a real TRS-CAT: SAFE-OP refused, 0x0070."""
    rig = build_rig(parse_rig_spec(ALONE.format(configured=""), "alone.toml"))
    trs = rig.devices["trscat"]
    rig.run_until(3_000_000)
    assert (trs.al_state, trs.al_status_code) == (AlState.PREOP, 0x0070)
    assert _f030(rig) == DEFAULT_LIST


def _without_network(text: str) -> str:
    return re.sub(r'(?m)^(eni|mapping) = .*\n', "", text)


def _generated_eni() -> str:
    return generate(_without_network(DEFAULT_RIG.read_text()), "static/rigs/default.toml")[0]


def _trscat_f030(eni: str) -> list[tuple[str, int, str]]:
    """(transition, sub, data) of the TRS-CAT's 0xF030 init commands in ``eni``."""
    slave = re.search(r"<Slave>(?:(?!</Slave>).)*<Device>trscat</Device>.*?</Slave>", eni,
                      flags=re.S)
    assert slave is not None
    return [(t, int(s), d) for t, s, d in re.findall(
        r"<Transition>(\w+)</Transition>\s*<Comment>[^<]*</Comment>\s*<Index>#xF030</Index>"
        r"\s*<SubIndex>(\d+)</SubIndex>\s*<Data>(\w*)</Data>", slave.group(0))]


def _without_f030(eni: str) -> str:
    return re.sub(r"\s*<InitCmd>(?:(?!</InitCmd>).)*#xF030(?:(?!</InitCmd>).)*</InitCmd>", "",
                  eni, flags=re.S)


def _rig_file(tmp_path: Path, eni: str, configured: str) -> Path:
    (tmp_path / "net.eni.xml").write_text(eni)
    text = _without_network(DEFAULT_RIG.read_text())
    text = text.replace("[master]\n", '[master]\neni = "net.eni.xml"\n')
    text = re.sub(r'(?m)^configured = .*\n', configured + "\n" if configured else "", text)
    (tmp_path / "rig.toml").write_text(text)
    return tmp_path / "rig.toml"


def test_the_generator_writes_the_rig_list_in_ps() -> None:
    assert _trscat_f030(_generated_eni()) == [
        ("PS", 0, "03"), ("PS", 1, "422d4f49"), ("PS", 2, "452d4f49"), ("PS", 3, "452d4e41")]


def test_an_old_description_without_the_list_keeps_working(tmp_path: Path) -> None:
    old = _without_f030(_generated_eni())
    assert _trscat_f030(old) == []
    rig = build_rig(load_rig_spec(_rig_file(tmp_path, old, 'configured = ["IO-E", "AN-E"]')))
    assert _run_to(rig, AlState.OP)[AlState.SAFEOP] == [3, IO_B, IO_E, AN_E]


def test_the_description_alone_sets_it(tmp_path: Path) -> None:
    rig = build_rig(load_rig_spec(_rig_file(tmp_path, _generated_eni(), "")))
    assert _run_to(rig, AlState.OP)[AlState.SAFEOP] == [3, IO_B, IO_E, AN_E]


def test_the_same_list_in_rig_and_description_is_written_once(tmp_path: Path) -> None:
    rig = build_rig(load_rig_spec(_rig_file(tmp_path, _generated_eni(),
                                            'configured = ["TRS-IO-E", "TRS-AN-E"]')))
    [desc] = [link.description for link in rig.devices["master"].links
              if link.slave.device_id == "trscat"]
    assert [c.sub for c in desc.commands("PS") if c.index == 0xF030] == [0, 1, 2, 3]


def test_rig_and_description_disagreeing_is_one_error(tmp_path: Path) -> None:
    path = _rig_file(tmp_path, _generated_eni(), 'configured = ["TRS-IO-E"]')
    with pytest.raises(RigConfigError) as info:
        build_rig(load_rig_spec(path))
    assert info.value.key == "trscat[0].configured"
    assert "TRS-IO-E, TRS-AN-E" in info.value.reason and "net.eni.xml" in info.value.reason


@pytest.mark.parametrize(("value", "reason"), [
    ('["TRS-ZZ-E"]', "configured expansion 1"),
    ('["TRS-AC-E", "TRS-AC-E", "TRS-AC-E", "TRS-AC-E"]', "do not fit"),
])
def test_a_wrong_list_is_one_clear_error(value: str, reason: str) -> None:
    text = ALONE.format(configured=f"configured = {value}")
    with pytest.raises(RigConfigError) as info:
        build_rig(parse_rig_spec(text, "alone.toml"))
    assert info.value.key == "trscat[0].configured"
    assert reason in info.value.reason
