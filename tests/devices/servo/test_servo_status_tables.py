"""The status word bit tables (R05 and 0x6041, in words per mode) are the model's, as seed 004
prints them, and the Drive tab has no copy of its own.

Seed 004 ch. 1 (quick reference, "R05 Status Word": bits 0-4 in every mode, bits 5-7
"specifico del modo selezionato") and ch. 4 ("Oggetto 0x6041 StatusWord: le specifiche dei bit
8, 14 e 15 sono a cura del costruttore"; homing on bits 12 / 13, "secondo lo standard DSP
402"). The expected tables below are transcribed from the seed, not from the code.
"""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import pytest

from app.ui.drive import drive_state
from devices.servo import control, ds402
from devices.servo.ds402 import State
from devices.servo.registers import MODE_NAMES

ROOT = Path(__file__).resolve().parents[3]

# Ch. 1, R05: bit -> (name, what "1" means in the seed's words, in English).
R05_COMMON = {0: ("Ten_st", "in torque"),  # "stato abilitazione coppia 1: asse in coppia"
              1: ("Ien_st", "motion enabled"),  # "1: movimentazioni abilitate"
              2: ("Stp_st", "stop ramp running"),  # "1: rampa di stop in corso"
              3: ("Alm_st", "in alarm"),  # "1: macchina in allarme"
              4: ("Ltc_st", "position latched")}  # "1: latch di posizione eseguito"
POSITIONER = {5: ("sp_rdy", "ready for a set-point"),  # "pronto per un nuovo set-point"
              6: ("EOJ", "End of Job"),  # "1: fine del posizionamento"
              7: ("Following_error", "following error")}  # "Following error: 1: errore"
R05_SEED: dict[int, dict[int, tuple[str, str]]] = {
    1: POSITIONER,
    -1: POSITIONER,  # the pulse positioner, "del tutto simile" (ch. 2 I/O)
    3: {7: ("Zero_velocity", "zero speed")},  # "Controllo Velocita: velocita nulla"
    -127: {7: ("Zero_velocity", "zero speed")},  # docs/servo-drive.md "mode -127"
    6: {6: ("Homing_ok", "homing OK"),  # "Zero asse (homing): Homing ok, homing completato"
        7: ("Homing_error", "homing error")},  # "1: Errore durante l'homing"
    7: {5: ("Ip_st", "interpolator active")},  # "1: interpolatore attivo"
    -2: {6: ("Axis_started", "electronic axis started")},  # "asse slave in asse col master"
    -50: {5: ("Save_done", "save done"),  # "1: salvataggio completato"
          6: ("Load_done", "load done")},  # "1: Caricamento terminato"
}
# Ch. 4, 0x6041: the manufacturer's bits 8, 14, 15 (their names as the seed prints them).
SW_MANUFACTURER = {8: "latching input", 14: "latched position update",
                   15: "target velocity forced to zero"}
# Bits 12 / 13 per mode: homing from ch. 4 ("bit 12 a 1 e bit 13 a zero: operazione
# completata con successo", "bit 12 a zero e bit 13 a 1: homing interrotto"); pp, pv and ip
# from DSP 402, to which ch. 4 refers.
SW_MODE_SEED: dict[int, dict[int, str]] = {
    1: {12: "set-point acknowledge", 13: "following error"},
    -1: {12: "set-point acknowledge", 13: "following error"},
    3: {12: "speed = 0"},
    -127: {12: "speed = 0"},
    6: {12: "homing attained", 13: "homing error"},
    7: {12: "ip mode active"},
    -2: {12: "axis started"},
    -50: {},
}


# Ch. 1, R00: bit -> name, as the quick reference prints them; in the electronic axis the
# quick reference puts Start/stop on bit 6, the I/O chapter on bit 5 ("il bit 5 di
# ControlWord è a 1"), and the drive takes either (docs/servo-drive.md §Modes, -2).
R00_COMMON = {0: "Ten_cmd", 1: "Ien_cmd", 2: "Stp_cmd", 3: "Alm_rst", 4: "Ltc_rst"}
R00_SEED: dict[int, dict[int, str]] = {
    1: {5: "Pos_str", 6: "Upd_mod", 7: "Inc_mod"},
    -1: {5: "Pos_str", 6: "Upd_mod", 7: "Inc_mod"},
    3: {}, -127: {},
    6: {6: "Homing_start"},  # "0 -> 1: start operazioni homing"
    7: {5: "Ip_str"},  # "1: start interpolatore"
    -2: {5: "Axis_start", 6: "Axis_start"},  # "1: start, asse slave in asse col master"
    -50: {5: "Save", 6: "Load"},
}


@pytest.mark.parametrize("mode", sorted(MODE_NAMES))
def test_r00_names_per_mode_are_the_seeds(mode: int) -> None:
    """Every R00 bit that acts in the mode has its name, so the Drive tab's "R00 control" row
    never shows a bit the drive obeys as a bare "bit 5" (mode -2 with the I/O chapter's 0x23)."""
    assert control.control_bit_names(mode) == R00_COMMON | R00_SEED[mode]


def test_the_drive_tab_names_the_electronic_axis_start_on_bit_5() -> None:
    snap = {"mode": -2, "control_register": 0x23, "controlword": 0x080F}
    (r00_row, _cw_row) = drive_state.control_rows(snap)
    assert r00_row[1] == "0x0023: Ten_cmd, Ien_cmd, Axis_start", r00_row


@pytest.mark.parametrize("mode", sorted(MODE_NAMES))
def test_r05_names_and_meanings_per_mode_are_the_seeds(mode: int) -> None:
    expected = R05_COMMON | R05_SEED[mode]
    shown = {bit: (name, control.STATUS_BIT_MEANING[name])
             for bit, name in control.status_bit_names(mode).items()}
    assert shown == expected


def test_every_r05_name_has_its_meaning_and_no_other() -> None:
    names = {n for mode in MODE_NAMES for n in control.status_bit_names(mode).values()}
    assert set(control.STATUS_BIT_MEANING) == names


@pytest.mark.parametrize("mode", sorted(MODE_NAMES))
def test_0x6041_mode_bits_per_mode_are_the_seeds(mode: int) -> None:
    assert control.statusword_mode_names(mode) == SW_MODE_SEED[mode]


def test_0x6041_manufacturer_bits_are_the_seeds() -> None:
    for bit, name in SW_MANUFACTURER.items():
        assert ds402.STATUSWORD_BITS[bit] == name
    assert set(ds402.STATUSWORD_SHORT) == set(range(16)) == set(ds402.STATUSWORD_BITS)


def _all_flags(mode: int) -> control.StatusFlags:
    """Every flag set: each bit the model can report in ``mode``."""
    flags = {f.name: True for f in dataclasses.fields(control.StatusFlags)
             if f.type in (bool, "bool")}
    return control.StatusFlags(state=State.OPERATION_ENABLED, mode=mode, **flags)


@pytest.mark.parametrize("mode", sorted(MODE_NAMES))
def test_each_mode_bit_the_model_sets_is_named_in_words(mode: int) -> None:
    """The words come from the same families that build the words: a bit the model sets in a
    mode has its name there, and a named bit is one the model can set (0x6041 bit 12 in -127
    and -2 read "mode specific" on the Drive tab while the model set it)."""
    sw = control.cia402_status(_all_flags(mode))
    assert {b for b in (12, 13) if sw >> b & 1} == set(control.statusword_mode_names(mode))
    r05 = control.register_status(_all_flags(mode))
    assert {b for b in (5, 6, 7) if r05 >> b & 1} == \
        set(control.status_bit_names(mode)) - set(range(5))


TABLE_NAMES = {"SW_MODE_SPECIFIC", "SW_SHORT", "R05_MEANING", "R05_ALERT", "SW_ALERT"}


def _bit_tables(path: Path) -> list[str]:
    """Module-level dict / set literals of ``path`` keyed by status bit numbers or names."""
    names = {n for mode in MODE_NAMES for n in control.status_bit_names(mode).values()}
    found = []
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        value = node.value if isinstance(node, ast.Assign | ast.AnnAssign) else None
        keys = value.keys if isinstance(value, ast.Dict) else \
            value.elts if isinstance(value, ast.Set) else []
        consts = [k.value for k in keys if isinstance(k, ast.Constant)]
        if len(consts) < 3:
            continue
        # words, not numbers: {bit: "text"} or {mode: {bit: "text"}}
        worded = isinstance(value, ast.Set) or (isinstance(value, ast.Dict) and all(
            isinstance(v, ast.Dict) or (isinstance(v, ast.Constant) and isinstance(v.value, str))
            for v in value.values))
        if worded and (all(isinstance(c, int) and 0 <= c < 16 for c in consts)
                       or all(c in names for c in consts)):
            found.append(ast.unparse(node)[:60])
    return found


def test_the_drive_tab_has_no_bit_table_of_its_own() -> None:
    """docs/architecture.md: code tables are data in devices/, one place each; the UI words
    what the model says."""
    assert not TABLE_NAMES & set(vars(drive_state))
    for path in sorted((ROOT / "app" / "ui" / "drive").glob("*.py")):
        assert _bit_tables(path) == [], path.name


@pytest.mark.parametrize("mode", sorted(MODE_NAMES))
def test_the_drive_tab_words_are_the_models(mode: int) -> None:
    r05 = drive_state.r05_names(mode)
    assert {b: n for b, (n, _) in r05.items()} == control.status_bit_names(mode)
    assert all(control.STATUS_BIT_MEANING[n] in tip for n, tip in r05.values())
    sw = drive_state.statusword_names(mode)
    expected = ds402.STATUSWORD_SHORT | control.statusword_mode_names(mode)
    assert {b: short for b, (short, _) in sw.items()} == expected
