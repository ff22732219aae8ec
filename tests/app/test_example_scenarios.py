"""The example scenarios run from the CLI and their events match seed 000 (issue 2 §4)."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from pathlib import Path

import pytest

from app.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((ROOT / "static" / "scenarios").glob("*.toml"))


def run(name: str, capsys: pytest.CaptureFixture[str], tmp_path: Path) -> list[dict]:
    out = tmp_path / name
    rc = main(["scenario", "run", str(ROOT / "static" / "scenarios" / f"{name}.toml"),
               "--out", str(out)])
    printed = capsys.readouterr().out
    assert rc == 0
    assert (out / "events.jsonl").read_text() == printed
    return [json.loads(line) for line in printed.splitlines()]


def without(records: list[dict], *kinds: str) -> list[dict]:
    return [r for r in records if r["event"] not in kinds]


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_every_example_is_deterministic(path: Path, capsys, tmp_path) -> None:
    first = run(path.stem, capsys, tmp_path)
    second = run(path.stem, capsys, tmp_path)
    assert first == second
    assert {"t", "device", "event"} <= set(first[0])
    assert any(r["event"] == "checkpoint" for r in first)


def test_module_lost_in_op_matches_seed_7_1_and_7_7(capsys, tmp_path) -> None:
    records = run("module_lost_in_op", capsys, tmp_path)
    emcy = [r for r in records if r["event"] == "emergency"]
    assert emcy[0] | {"t": 0} == {"t": 0, "device": "fastcat", "event": "emergency",
                                  "code": "0xFF00", "register": "0x81",
                                  "data": "02 00 00 04 00"}
    t0 = emcy[0]["t"]
    assert {"t": t0, "device": "fastcat", "event": "al_status", "code": "0x8204"} in records
    assert {"t": t0, "device": "fastcat", "event": "state", "from": "OP", "to": "PREOP"} \
        in records
    box = "'Box 1 (FastCAT)' (1001): "
    # Only the coupler's lines: the master also logs its DC start-up (seed 003) on this line.
    logs = [r for r in records if r["event"] == "log" and r["device"] == "master"
            and r["text"].startswith(box)]
    assert [(round(r["t"] - t0, 3), r["text"]) for r in logs[:4]] == [
        (0.0, box + "CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00')."),
        (0.0, box + "abnormal state change (from 'OP' to 'PREOP') with code 0x8204. "
                    "Try to go back to 'OP'..."),
        (0.141, box + "'PREOP to SAFEOP' failed! Error: 'check device state for SAFEOP'. "
                      "AL Status '0x0012' read and '0x0004' expected. AL Status Code '0x8204'"),
        (0.141, box + "state change aborted (requested 'OP', back to 'PREOP')."),
    ]
    reads = [r for r in records if r["event"] == "read"]
    assert reads[0]["address"] == "0x5400:0" and reads[0]["hex"] == "0x04000002"
    # Reset fault while the module is still missing does nothing (§7: only once the cause is
    # gone); after it is plugged back the same reset clears the alarm and OP comes back.
    cleared = [r for r in records if r["event"] == "alarm" and not r["active"]]
    assert len(cleared) == 1 and cleared[0]["t"] == 10.5
    states = [(r["from"], r["to"]) for r in records
              if r["event"] == "state" and r["device"] == "fastcat" and "machine" not in r]
    assert states[-2:] == [("PREOP", "SAFEOP"), ("SAFEOP", "OP")]


def test_cnf_scan_lights_reds_in_order_then_yellows(capsys, tmp_path) -> None:
    records = run("cnf_scan", capsys, tmp_path)
    release = next(r["t"] for r in records if r["event"] == "state"
                   and r.get("machine") == "cnf_button" and r["to"] == "released"
                   and r["t"] > 7)
    reds = [(r["t"], r["led"]) for r in records if r["event"] == "led"
            and r["led"].endswith(".red") and r["pattern"] == "on" and r["t"] > release]
    assert [led for _, led in reds] == [f"{n}.red" for n in range(1, 8)]
    gaps = {round(b - a, 3) for (a, _), (b, _) in itertools.pairwise(reds)}
    assert gaps == {0.25}
    yellows = [r for r in records if r["event"] == "led" and r["led"].endswith(".yellow")
               and r["pattern"] == "blinking" and r["t"] > release]
    assert len(yellows) == 7 and min(y["t"] for y in yellows) > reds[-1][0]
    # the 1 s press at 5.5 s changed nothing but the button itself
    short = [r for r in records if 5.5 <= r["t"] < 7.0 and r["device"] == "fastcat"]
    assert {r.get("machine") for r in short} == {"cnf_button"}


def test_cnf_scan_scanning_picture_shows_the_scan_under_way(capsys, tmp_path) -> None:
    """The `scanning` checkpoint's picture illustrates its caption ("scanned again, one by
    one"): some modules probed (their red LEDs on), not all. At 11.2 s it showed "scan 0/7"
    and every module LED dark: the bus reset (1 s, docs/fastcat-coupler.md) was still on."""
    records = run("cnf_scan", capsys, tmp_path)
    at = next(r["t"] for r in records if r["event"] == "checkpoint"
              and r["name"] == "scanning")
    lit = {r["led"] for r in records if r["event"] == "led" and r["led"].endswith(".red")
           and r["pattern"] == "on" and 10.5 < r["t"] <= at}
    assert 2 <= len(lit) < 7, (at, sorted(lit))


def test_config_mismatch_at_power_up(capsys, tmp_path) -> None:
    records = run("config_mismatch", capsys, tmp_path)
    after_power = [r for r in records if r["t"] >= 14.0]
    emcy = next(r for r in after_power if r["event"] == "emergency")
    assert emcy["data"] == "02 00 00 01 00"  # module 2 differs: CO_E_MODULE_CHANGED
    assert {"led": "ERR", "pattern": "blinking"}.items() <= next(
        r for r in after_power if r["event"] == "led" and r["led"] == "ERR").items()
    at_checkpoint = [r for r in records if r["event"] == "state" and "machine" not in r
                     and r["device"] == "fastcat" and 14.0 <= r["t"] <= 20.0]
    assert ("SAFEOP", "OP") not in {(r["from"], r["to"]) for r in at_checkpoint}
    assert any(r["event"] == "al_status" and r["code"] == "0x0052" for r in after_power)
    relearnt = [r for r in records if r["t"] > 20.5 and r["event"] == "state"
                and "machine" not in r and r["device"] == "fastcat"]
    assert relearnt[-1]["to"] == "OP"


def test_config_mismatch_explains_the_drive_alarm_it_causes(capsys, tmp_path) -> None:
    """Powering the FastCAT off cuts the EtherCAT line behind it: drive_ec loses the master's
    process data and raises alarm 34 SYNC_TIMEOUT (Fault; Error LED double flash until the
    master restarts it) and keeps it at the mismatch checkpoint. No caption said so, and a
    customer asks; one must, while the caption on screen at the checkpoint still tells the
    scenario's point."""
    records = run("config_mismatch", capsys, tmp_path)
    at = next(r["t"] for r in records if r["event"] == "checkpoint" and r["name"] == "mismatch")
    alarms = {(r["device"], r["code"]): r for r in records
              if r["event"] == "alarm" and r["device"] != "fastcat" and r["t"] <= at}
    standing = [key for key, r in alarms.items() if r["active"]]
    assert standing == [("drive_ec", "34")]
    raised_t = alarms[("drive_ec", "34")]["t"]
    captions = [r for r in records if r["event"] == "caption" and raised_t <= r["t"] <= at]
    assert any("drive_ec" in c["text"] and "34 SYNC_TIMEOUT" in c["text"] for c in captions)
    shown = captions[-1]["text"]  # the caption above the line at the checkpoint
    assert "stored configuration" in shown and "drive_ec" in shown


def test_ax2_homing_sets_home_offset_and_done_bit(capsys, tmp_path) -> None:
    records = run("ax2_homing", capsys, tmp_path)
    status, position = [r for r in records if r["event"] == "read"]
    assert status["address"] == "0x6660:0" and status["value"] & 0x1000
    # homed at the first zero mark after 5.2 s, then counting on at 2048 pulses/rev, 60 rpm
    assert position["address"] == "0x6560:1" and 1000 <= position["value"] < 1000 + 2048 * 1.3
    assert not [r for r in records if r["event"] == "emergency"]
    # The picture at "homed" is of the module, under a caption saying what it shows: the
    # homing done bit of §6.27 (it showed the zero-cycle command's caption over the line).
    before = records[:records.index({"t": 6.5, "device": "scenario", "event": "checkpoint",
                                     "name": "homed"})]
    caption = [r["text"] for r in before if r["event"] == "caption"][-1]
    assert "homed" in caption and "0x6660" in caption and "bit 12" in caption, caption
    assert [r["target"] for r in before if r["event"] == "focus"][-1:] == ["fastcat:7"]


def test_ax2_zero_mark_missing_alarm_after_one_and_a_half_turns(capsys, tmp_path) -> None:
    records = run("ax2_zero_mark_missing", capsys, tmp_path)
    emcy = [r for r in records if r["event"] == "emergency"]
    assert [e["data"] for e in emcy] == ["07 00 14 00 00"]
    assert 6.5 <= emcy[0]["t"] <= 6.51  # 1.5 turns at 60 rpm after the command at 5.0 s
    assert any(r["event"] == "alarm" and not r["active"] for r in records)
    # A module alarm (§7.6) keeps OP: no AL status code, no state change, no master retry;
    # Reset fault in the process data clears it in OP (§7, §7.7).
    after = [r for r in records if r["t"] >= emcy[0]["t"]]
    assert not [r for r in after if r["event"] in ("al_status", "slave_state")
                or (r["event"] == "state" and r["device"] == "fastcat")]
    assert [(r["t"], r["active"]) for r in after if r["event"] == "alarm"] == \
        [(emcy[0]["t"], True), (8.5, False)]


def test_too_many_analog_modules(capsys, tmp_path) -> None:
    records = run("too_many_analog", capsys, tmp_path)
    emcy = [r for r in records if r["event"] == "emergency"]
    assert [e["data"] for e in emcy] == ["09 00 00 15 00"]  # 8th analog module at position 9


def test_bad_scenario_exits_2_with_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[scenario]\n[[step]]\nat = 1\ntarget = "fastcat"\naction = "fly"\n')
    proc = subprocess.run([sys.executable, "-m", "app", "scenario", "run", str(bad)],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert "step[0]" in proc.stderr and "no action 'fly'" in proc.stderr


def test_bad_rig_exits_2_with_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "rig.toml"
    bad.write_text('[[fastcat]]\nmodules = ["DB16", "XX9"]\n')
    proc = subprocess.run([sys.executable, "-m", "app", "--rig", str(bad), "--run-for", "0"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"fieldrig: error: {bad}: fastcat[0].modules[1]: unknown "
                                   "module type 'XX9' (known: DB16, DI16, DO82, DO16, AI8D, "
                                   "AI8C, AI8TC, AI8PT100, AI8PT1000, AB4P4, AB4D4, AB4C4, AI4D, "
                                   "AI4C, AO4, AO4H, AI4P, AI8M, AB4M4, AX2)")


def test_scenario_record_flag_writes_a_verified_recording(capsys, tmp_path) -> None:
    """``--record`` (issue 6) leaves the printed events unchanged and writes a valid .rrd."""
    plain = run("module_lost_in_op", capsys, tmp_path)
    rrd = tmp_path / "run.rrd"
    rc = main(["scenario", "run", str(ROOT / "static/scenarios/module_lost_in_op.toml"),
               "--record", str(rrd)])
    recorded = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert rc == 0 and recorded == plain
    verify = subprocess.run([sys.executable, "-m", "rerun", "rrd", "verify", str(rrd)],
                            capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr


def test_drive_jammed_load_raises_alarm_16_and_recovers(capsys, tmp_path) -> None:
    """Issue 3: scenario steps for drives (register write, move, jam, alarm reset) and the
    foundation's event schema; seed 004 ch. 3 alarm 16 (following error)."""
    records = [r for r in run("drive_jammed_load", capsys, tmp_path) if r["device"] == "drive"]
    alarms = [(r["t"], r["code"], r["active"]) for r in records if r["event"] == "alarm"]
    assert [(code, active) for _, code, active in alarms] == [("16", True), ("16", False)]
    assert 2.0 < alarms[0][0] < 4.0 and alarms[1][0] == 6.5
    states = [r["to"] for r in records if r["event"] == "state"]
    assert "Fault" in states and states[-1] == "Operation enabled"
    assert [r["value"] for r in records if r["event"] == "read"] == [24000]
