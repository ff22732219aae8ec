"""A powered slave that does not answer (a drive whose c9 did not select EtherCAT at power-up,
seed 004 ch. 2) passes the frames on (its ESC forwards them whatever its application does):
the frames' physical path, not the chain of answers, decides which cables they cross
(docs/ethercat-master.md "Damaged cable"), and the master reports a configured slave that
never answered at start-up (seed 003: the master interprets the ENI, opens its port, waits for
link, then sends frames; "What the master knows")."""

from __future__ import annotations

from line_bench import US, master_view
from test_master_port_link import _drive_first

from app.rig_config import build_rig, parse_rig_spec

DRIVE = "'Drive 1 (SelemaDriveECAT)' (1001)"


def test_a_damaged_cable_behind_a_silent_first_slave_spoils_frames() -> None:
    """Cable 1 (drive -> FastCAT) damaged: the frames still cross it (the silent drive at
    position 0 forwards them), so the master loses frames and the ESCs count."""
    rig = _drive_first(c9=3)
    rig.run_until(4 * US)
    master = rig.devices["master"]
    before = master.lost_frames
    rig.apply("master", "damage_cable", {"cable": 1, "percent": 100})
    rig.run_until(4 * US + 50_000)
    assert master.lost_frames - before >= 40
    esc = [s["esc_errors"] for s in master_view(rig)["slaves"]]
    assert esc[1]["invalid"][0] > 0  # the FastCAT's IN port: the first to see it spoiled
    assert esc[0]["forwarded"][1] > 0  # the drive's ESC forwards it back, marked


def test_a_slave_never_found_is_logged_and_diagnosed() -> None:
    """The FastCAT behind the silent drive answers: the master reads no answer from position
    0 only, not "from position 0 on" (before, the run of silent slaves was taken to the end
    of the line whatever answered behind it)."""
    rig = _drive_first(c9=3)
    rig.run_until(2 * US)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [False, True]
    assert [s["diagnosis"] for s in view["slaves"]] == [
        "no answer from position 0, position 1 answers", ""]
    texts = [row["text"] for row in rig.devices["master"].log]
    assert f"{DRIVE}: slave not found: no answer from position 0, position 1 answers." in texts
    assert ("'Device 1 (EtherCAT)': slave(s) at position(s) 0 not found: no answer from "
            "position 0, position 1 answers (working counter 1, 2 expected).") in texts
    assert sum("not found" in t for t in texts) == 2  # once, not every cycle


def test_a_never_found_slave_is_a_communication_error_once() -> None:
    rig = _drive_first(c9=3)
    master = rig.devices["master"]
    seen = []
    master.on_notify(seen.append)
    rig.run_until(2 * US)
    found = [e.to_record() for e in seen if e.to_record()["event"] == "comm_error"]
    assert [(r["position"], r["reason"]) for r in found] == [(0, "not_found")]


def test_no_slave_is_reported_missing_while_the_port_has_no_link() -> None:
    """Cable 0 out from the start: no frames go out, the master waits for link (seed 003)
    and reports nothing missing; with link, the silent drive is reported."""
    rig = _drive_first(c9=3)
    rig.apply("master", "pull_cable", {"cable": 0})
    rig.run_until(1 * US)
    master = rig.devices["master"]
    assert not any("not found" in row["text"] for row in master.log)
    rig.apply("master", "plug_cable", {"cable": 0})
    rig.run_until(3 * US)
    assert sum("not found" in row["text"] for row in master.log) == 2


def test_a_slave_found_after_being_reported_missing_is_logged_found() -> None:
    """The drive, reported not found, set to c9 = 11, saved and power-cycled: it answers, the
    master logs it found and its diagnosis clears; it is in no network recovery (it was never
    lost; the FastCAT behind it was, while the drive was off)."""
    rig = _drive_first(c9=3)
    master = rig.devices["master"]
    seen = []
    master.on_notify(seen.append)
    rig.run_until(4 * US)
    rig.apply("drive_ec", "write_parameter", {"parameter": "c9", "value": 11})
    rig.apply("drive_ec", "save", {})
    rig.run_until(8 * US)
    rig.apply("drive_ec", "power", {"on": False})
    rig.run_until(9 * US)
    rig.apply("drive_ec", "power", {"on": True})
    rig.run_until(14 * US)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [True, True]
    assert view["slaves"][0]["diagnosis"] == ""
    texts = [row["text"] for row in master.log]
    assert f"{DRIVE}: found on the line in 'INIT'." in texts
    recoveries = [e.to_record() for e in seen if e.to_record()["event"] == "network_recovery"]
    assert [r["positions"] for r in recoveries] == [[1]]  # the FastCAT, lost with the drive off


SILENT = "powered and reached by the frames: it does not answer"


def test_a_slave_powered_again_and_silent_loses_its_stale_power_off_cause() -> None:
    """The drive switched off (cause "powered off"), then on with c9 = 3 latched: the frames
    reach it and it stays silent. Its cause in the instructor's view followed the line only
    while the line did not reach it, so it kept "powered off" with the drive on (and a slave
    lost while reached read "no link on its IN port", its IN port plugged)."""
    rig = _drive_first()
    rig.run_until(4 * US)
    rig.apply("drive_ec", "write_parameter", {"parameter": "c9", "value": 3})
    rig.apply("drive_ec", "save", {})
    rig.run_until(8 * US)
    rig.apply("master", "power_slave", {"position": 0, "on": False})
    rig.run_until(9 * US)
    assert master_view(rig)["injected"]["lost"][0] == {"position": 0, "cause": "powered off"}
    rig.apply("master", "power_slave", {"position": 0, "on": True})
    rig.run_until(12 * US)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [False, True]
    assert view["injected"]["lost"] == [{"position": 0, "cause": SILENT}]


def test_a_slave_never_found_has_its_cause_in_the_instructor_s_view() -> None:
    """A slave reported not found gets the instructor's cause as a lost one does: the silent
    drive's, and the FastCAT's cable pulled before the master had link (before, none: the
    Causes row had nothing for a slave missing from the start)."""
    rig = _drive_first(c9=3)
    rig.run_until(2 * US)
    assert master_view(rig)["injected"]["lost"] == [{"position": 0, "cause": SILENT}]
    rig = _drive_first()
    rig.apply("master", "pull_cable", {"cable": 1})
    rig.run_until(2 * US)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [True, False]
    assert view["injected"]["lost"] == [{"position": 1, "cause": "cable 1 pulled"}]
    rig.apply("master", "plug_cable", {"cable": 1})
    rig.run_until(4 * US)
    assert master_view(rig)["injected"]["lost"] == []


def test_a_run_of_silent_slaves_before_one_that_answers_is_named_as_a_run() -> None:
    """Two drives on Modbus (c9 = 3) ahead of a FastCAT: both pass the frames on, the FastCAT
    answers. The master reads no answer from positions 0 to 1 and an answer at 2."""
    text = ('[rig]\nname = "two silent"\nseed = 1\nstep_ms = 1\n[master]\n'
            'line = ["d1-ecat", "d2-ecat", "fastcat"]\n'
            + "".join(f'[[servo]]\nid = "{d}"\nfieldbus = "ethercat"\nnode_id = {n}\n'
                      'parameters = { c9 = 3 }\n' for n, d in ((3, "d1"), (4, "d2")))
            + '[[fastcat]]\nid = "fastcat"\nmodules = ["DI16"]\n')
    rig = build_rig(parse_rig_spec(text))
    rig.run_until(2 * US)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [False, False, True]
    finding = "no answer from positions 0 to 1, position 2 answers"
    assert [s["diagnosis"] for s in view["slaves"]] == [finding, finding, ""]
    texts = [row["text"] for row in rig.devices["master"].log]
    assert ("'Device 1 (EtherCAT)': slave(s) at position(s) 0, 1 not found: "
            f"{finding} (working counter 1, 3 expected).") in texts


def test_two_silent_runs_get_a_summary_line_each() -> None:
    """Silent drives at 0 and 2 around an answering FastCAT: the master's summary named both
    positions with the first run's words ("no answer from position 0, position 1 answers"),
    wrong for position 2, behind which nothing answers."""
    text = ('[rig]\nname = "two runs"\nseed = 1\nstep_ms = 1\n[master]\n'
            'line = ["d1-ecat", "fastcat", "d2-ecat"]\n'
            + "".join(f'[[servo]]\nid = "{d}"\nfieldbus = "ethercat"\nnode_id = {n}\n'
                      'parameters = { c9 = 3 }\n' for n, d in ((3, "d1"), (4, "d2")))
            + '[[fastcat]]\nid = "fastcat"\nmodules = ["DI16"]\n')
    rig = build_rig(parse_rig_spec(text))
    rig.run_until(2 * US)
    view = master_view(rig)
    assert [s["diagnosis"] for s in view["slaves"]] == [
        "no answer from position 0, position 1 answers", "", "no answer from position 2 on"]
    summary = [row["text"] for row in rig.devices["master"].log
               if row["text"].startswith("'Device 1 (EtherCAT)': slave(s)")]
    assert summary == [
        "'Device 1 (EtherCAT)': slave(s) at position(s) 0 not found: no answer from position 0, "
        "position 1 answers (working counter 1, 3 expected).",
        "'Device 1 (EtherCAT)': slave(s) at position(s) 2 not found: no answer from position 2 "
        "on (working counter 1, 3 expected)."]
