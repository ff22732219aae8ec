"""The master on the line rig: start-up, addressing, line faults (seed 003; seed 000 §7)."""

from __future__ import annotations

from pathlib import Path

import pytest
from line_bench import IN_OP_US, LINE_RIG, US, line_in_op, master_view, records

from app.rig_config import build_rig, load_rig_spec
from devices.device import CommandError
from devices.ethercat import AlState

POSITIONS = {"fastcat": 0, "trscat": 1, "cpx": 2, "drive_ec-ecat": 3}


def test_start_up_waits_for_link_then_brings_every_slave_to_op() -> None:
    """Seed 003: the master waits for link on its port, then steps each slave INIT -> PREOP
    -> SAFEOP -> OP; ECAT_Resync for each node and then for the whole network."""
    rig = build_rig(load_rig_spec(LINE_RIG))
    rig.apply("master", "pull_cable", {"cable": 0})
    events = rig.run_until(US)
    view = master_view(rig)
    assert (view["phase"], view["link"], view["stats"]["frames"]) == ("waiting_link", False, 0)
    assert not any(s["present"] for s in view["slaves"])
    assert not records(events, "slave_state")
    rig.apply("master", "plug_cable", {"cable": 0})
    phases, events = set(), []
    while rig.clock.now_us < 6 * US:
        events += rig.step()
        phases.add(rig.devices["master"].phase)
    assert {"init_commands", "starting", "running"} <= phases
    view = master_view(rig)
    assert [s["state"] for s in view["slaves"]] == ["OP"] * 4
    resyncs = records(events, "resync")
    assert sorted(r["position"] for r in resyncs) == [-1, 0, 1, 2, 3]
    assert resyncs[-1]["position"] == -1  # the network after its last node
    ups = [(r["position"], r["from"], r["to"]) for r in records(events, "slave_state")]
    for pos in range(4):
        mine = [(f, t) for p, f, t in ups if p == pos]
        assert mine[-1][1] == "OP"


def test_init_commands_write_the_configured_lists_in_preop() -> None:
    """The description's PS init commands: the TRS-CAT's 0xF030 equals its 0xF050 (seed 001
    §9.3.2), the CPX-E-EC's 0xF030 is written (Text-ID 0x3801 not raised)."""
    rig = line_in_op()
    trs, cpx = rig.devices["trscat"], rig.devices["cpx"]
    assert trs.f030 == trs.f050
    assert cpx.f030_written


def test_diagnostic_structure_by_position_and_by_address() -> None:
    rig = line_in_op()
    master = rig.devices["master"]
    for device, pos in POSITIONS.items():
        by_pos = master.slave_at(pos)
        assert by_pos["device"] == device and by_pos["position"] == pos
        assert master.slave_by_address(by_pos["station_address"]) == by_pos
        assert by_pos["state"] == "OP" and by_pos["al_status"] == 0x08
        assert by_pos["al_status_text"] == "No error"
    with pytest.raises(CommandError, match="no slave at position 4"):
        master.slave_at(4)
    with pytest.raises(CommandError, match="physical address 9"):
        master.slave_by_address(9)


@pytest.mark.parametrize("cable", [0, 1, 2, 3])
def test_pulled_cable_cuts_off_every_slave_behind_it(cable: int) -> None:
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": cable})
    events = rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [p < cable for p in range(4)]
    assert view["cables"][cable]["plugged"] is False
    lost = records(events, "comm_error")
    assert [(r["position"], r["reason"]) for r in lost] == [
        (p, "link_lost") for p in range(cable, 4)]
    # Seed 003 diagnostic structure: what the master sees (no answer from there on, the link
    # where its frames stop); the cable is the instructor's injected cause.
    where = "link down on the master port" if cable == 0 else \
        f"no link on port 1 (OUT) of position {cable - 1}"
    assert view["slaves"][cable]["diagnosis"] == f"no answer from position {cable} on ({where})"
    assert view["injected"]["lost"][0] == {"position": cable, "cause": f"cable {cable} pulled"}
    if cable in (1, 3):
        return  # the recovery is the same for every cable: checked on 0 and 2
    if cable == 0:  # FastCAT seed 000 §7.5: 0x13 CO_E_LINK_LOSS "Cavo ethercat non connesso"
        assert rig.devices["fastcat"].alarm is not None
        assert rig.devices["fastcat"].alarm.code == 0x13
    rig.apply("master", "plug_cable", {"cable": cable})
    events = rig.run_until(IN_OP_US + 6 * US)
    recovery = records(events, "network_recovery")
    assert [r["positions"] for r in recovery] == [list(range(cable, 4))]
    # Seed 003: the recovery restarts communication: each recovered slave goes through INIT
    # (which also clears the FastCAT's 0x13 once the cable is back, seed 000 §7).
    for pos in range(cable, 4):
        downs = [r for r in records(events, "slave_state") if r["position"] == pos]
        assert "INIT" in [r["to"] for r in downs]
    assert [s["state"] for s in master_view(rig)["slaves"]] == ["OP"] * 4


def test_cable_2_leds_and_watchdogs() -> None:
    """Between TRS-CAT and CPX-E-EC: the TRS-CAT's OUT port and the CPX-E-EC's IN port lose
    link; the CPX-E-EC and the drive stop getting frames and their SM watchdog takes them to
    SAFEOP (AL status code 0x001B)."""
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": 2})
    events = rig.run_until(IN_OP_US + US // 2)
    assert rig.devices["trscat"].link_out is False and rig.devices["trscat"].link_in is True
    assert rig.devices["cpx"].link_in is False
    assert rig.devices["cpx"].al_state is AlState.SAFEOP
    assert "0x001B" in [r["code"] for r in records(events, "al_status", "cpx")]
    assert rig.devices["trscat"].al_state is AlState.OP  # still served


def test_slave_powered_off_and_on() -> None:
    rig = line_in_op()
    rig.apply("master", "power_slave", {"position": 2, "on": False})
    rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert [s["present"] for s in view["slaves"]] == [True, True, False, False]
    assert view["injected"]["powered"][2] is False
    assert view["slaves"][3]["diagnosis"] == \
        "no answer from position 2 on (no link on port 1 (OUT) of position 1)"
    assert view["injected"]["lost"][1] == {"position": 3,
                                           "cause": "the slave at position 2 is off"}
    rig.apply("master", "power_slave", {"position": 2, "on": True})
    events = rig.run_until(IN_OP_US + 6 * US)
    assert records(events, "network_recovery")[0]["positions"] == [2, 3]
    assert [s["state"] for s in master_view(rig)["slaves"]] == ["OP"] * 4


def test_lost_frames_are_counted_and_the_slaves_watchdogs_react() -> None:
    """Seed 003 communication error; the TRS-CAT misses 3 SM events (0x10F1:2) and falls to
    SAFEOP with a sync error (seed 001 §9.3.7). The master reports what it has seen: the first
    lost frame at once, the rest when its frames come back (as a damaged cable's). It said
    "20 frame(s) lost." at the first one, which no master can know then."""
    rig = line_in_op()
    rig.apply("master", "lose_frames", {"count": 20})
    events = rig.run_until(IN_OP_US + US // 2)
    view = master_view(rig)
    assert view["stats"]["lost_frames"] == 20
    assert [s["counters"]["lost_frames"] for s in view["slaves"]] == [20] * 4
    errors = records(events, "comm_error")
    first = errors[0]["t"]
    assert [(round(r["t"] - first, 6), r["position"], r["reason"], r["count"])
            for r in errors] == [(0, p, "lost_frames", 1) for p in range(4)] + [
                (0.02, p, "lost_frames", 19) for p in range(4)]
    lines = [r["text"] for r in records(events, "log", "master") if "lost." in r["text"]]
    assert lines == ["'Device 1 (EtherCAT)': 1 frame(s) lost.",
                     "'Device 1 (EtherCAT)': 19 frame(s) lost."]
    trs = view["slaves"][1]
    assert (trs["state"], trs["al_status_code"]) == ("SAFEOP", 0x001A)
    assert trs["al_status_text"] == "Synchronization error"
    assert trs["counters"]["wkc_errors"] == 1


def test_a_slave_brought_back_at_once_still_raises_its_state_changes() -> None:
    """Seed 003: "the status change of slaves" is an event (diagnostic structures, callbacks,
    ECAT_Notify). 150 lost frames: the CPX-E-EC and the drive fall OP -> SAFEOP on their SM
    watchdog (0x001B); the master reads SAFEOP, logs the abnormal state change and requests OP,
    which they take in the same cycle. Both changes are events, in the structure's counter
    and on the hook, each after its slave's log line."""
    rig = line_in_op()
    master = rig.devices["master"]
    before = [s["counters"]["state_changes"] for s in master_view(rig)["slaves"]]
    notified: list[tuple[int, str, str]] = []
    master.on_notify(lambda e: notified.append((e.position, e.from_state, e.to_state))
                     if e.kind == "slave_state" else None)
    rig.apply("master", "lose_frames", {"count": 150})
    events = rig.run_until(IN_OP_US + US)
    for name in ("cpx", "drive_ec-ecat"):
        p = POSITIONS[name]
        mine = [r for r in (e.to_record() for e in events) if r["device"] == "master"
                and (r.get("position") == p or (r["event"] == "log"
                     and f"(100{p + 1}): abnormal" in r["text"]))
                and r["event"] in ("log", "slave_state")]
        assert [(r["event"], r.get("from"), r.get("to"), r.get("code")) for r in mine] == [
            ("log", None, None, None),
            ("slave_state", "OP", "SAFEOP", "0x001B"),
            ("slave_state", "SAFEOP", "OP", "0x0000")], name
        assert mine[0]["t"] == mine[1]["t"] == mine[2]["t"]
        assert [n for n in notified if n[0] == p] == [(p, "OP", "SAFEOP"), (p, "SAFEOP", "OP")]
        after = master_view(rig)["slaves"][p]
        assert (after["state"], after["counters"]["state_changes"]) == ("OP", before[p] + 2)


@pytest.mark.parametrize("skip_still", [True, False])
def test_one_slave_back_at_once_gives_both_changes_on_the_still_path(skip_still: bool) -> None:
    """The same with every other slave unchanged: the master's kept states (its still watch)
    must not hide the change back to OP (it did, with the event raised 0.5 s later)."""
    rig = line_in_op()
    rig.devices["master"].SKIP_STILL = skip_still
    rig.devices["cpx"].request_state(AlState.SAFEOP)
    events = rig.run_until(IN_OP_US + US // 2)
    changes = [(r["t"], r["position"], r["from"], r["to"]) for r in (e.to_record() for e in events)
               if r["device"] == "master" and r["event"] == "slave_state"]
    t = changes[0][0] if changes else None
    p = POSITIONS["cpx"]
    assert changes == [(t, p, "OP", "SAFEOP"), (t, p, "SAFEOP", "OP")]


def _rig_with_eni(tmp_path: Path, old: str, new: str) -> Path:
    from line_bench import ROOT

    eni = (ROOT / "static/networks/ethercat_line.eni.xml").read_text()
    assert old in eni
    (tmp_path / "bad.eni.xml").write_text(eni.replace(old, new, 1))
    text = LINE_RIG.read_text().replace("../networks/ethercat_line.eni.xml",
                                        str(tmp_path / "bad.eni.xml"))
    text = text.replace("../networks/ethercat_line.mapping.xml",
                        str(LINE_RIG.parent.parent / "networks/ethercat_line.mapping.xml"))
    text = "\n".join(line for line in text.splitlines() if not line.startswith("flash ="))
    (tmp_path / "rig.toml").write_text(text)
    return tmp_path / "rig.toml"


def test_identity_mismatch_leaves_the_slave_in_preop(tmp_path: Path) -> None:
    """A description whose product code differs from the slave's 0x1018: the master logs it
    and does not request SAFEOP (the slave stays in PREOP)."""
    rig = build_rig(load_rig_spec(_rig_with_eni(
        tmp_path, "<ProductCode>#x54525343</ProductCode>",
        "<ProductCode>#x54525344</ProductCode>")))
    events = rig.run_until(5 * US)
    trs = master_view(rig)["slaves"][1]
    assert trs["state"] == "PREOP"
    assert "identity mismatch" in trs["diagnosis"] and "0x54525344" in trs["diagnosis"]
    assert [r["reason"] for r in records(events, "comm_error")] == ["identity"]
    assert any("identity check failed" in r["text"] for r in records(events, "log", "master"))
    assert [s["state"] for s in master_view(rig)["slaves"]] == ["OP", "PREOP", "OP", "OP"]
    # START_TIME did not wait for the refused DC slave: the CPX-E-EC (DC) went on to OP
    assert master_view(rig)["dc"]["state"] == "COMPENSATING"


def test_an_identity_read_without_answer_is_a_reported_communication_error() -> None:
    """The CPX-E-EC's application controller (its CoE) fails in PREOP: the master's 0x1018
    upload before PREOP -> SAFEOP gets no answer (SDO timeout 0x05040000), as an init command
    would. Seed 003: a communication error is an event that updates the slave's diagnostic
    structure; the master logs it, raises comm_error, stops the transition and retries it every
    retry interval. START_TIME does not wait for a slave whose start-up failed (the TRS-CAT, DC,
    goes on to OP); once the controller answers the CPX-E-EC goes up and the diagnosis clears."""
    rig = build_rig(load_rig_spec(LINE_RIG))
    rig.run_until(50_000)  # the CPX-E-EC is in PREOP, its PREOP -> SAFEOP not yet requested
    rig.apply("cpx", "inject_fault", {"fault": "ac_failure"})
    events = rig.run_until(3 * US)
    cpx = master_view(rig)["slaves"][2]
    assert cpx["state"] == "PREOP"
    assert cpx["diagnosis"] == ("identity not read: SDO upload 0x1018:01 aborted with "
                                "0x05040000 (SDO protocol timed out): the slave stays in PREOP")
    errors = [(r["position"], r["reason"]) for r in records(events, "comm_error")]
    assert errors == [(2, "identity")] * 2  # at 0.142 s and at the retry 2 s later
    assert [r["text"] for r in records(events, "log", "master") if "1018" in r["text"]] == [
        "'Box 3 (CPX-E-EC)' (1003): identity check failed: SDO upload 0x1018:01 aborted with "
        "0x05040000."] * 2
    assert master_view(rig)["dc"]["state"] == "COMPENSATING"
    assert master_view(rig)["slaves"][1]["state"] == "OP"
    rig.apply("cpx", "clear_fault", {"fault": "ac_failure"})
    rig.run_until(10 * US)
    view = master_view(rig)
    assert [s["state"] for s in view["slaves"]] == ["OP"] * 4
    assert view["slaves"][2]["diagnosis"] == ""


def test_unknown_positions_are_refused() -> None:
    rig = line_in_op()
    with pytest.raises(CommandError, match="cable 4"):
        rig.apply("master", "pull_cable", {"cable": 4})
    with pytest.raises(CommandError, match="position 9"):
        rig.apply("master", "power_slave", {"position": 9, "on": False})


def test_snapshot_has_the_contract_keys() -> None:
    view = master_view(line_in_op())
    assert set(view) >= {"kind", "id", "target", "external", "link", "phase", "log_style",
                         "log_styles", "dc", "cables", "slaves", "stats", "log", "injected"}
    assert set(view["dc"]) == {"state", "deviation_ns", "window_ns"}
    assert set(view["injected"]) == {"lost", "powered", "link", "dc_fault"}
    assert view["cables"][0] == {"index": 0, "from": "master", "to": "fastcat", "plugged": True,
                                 "master_pulled": False, "pulled_at": [], "damaged": None}
    assert view["cables"][3]["from"] == "cpx"
    assert set(view["slaves"][0]) >= {"position", "device", "name", "station_address",
                                      "present", "state", "requested",
                                      "al_status", "al_status_code", "al_status_text", "dc",
                                      "counters", "esc_errors"}
    assert set(view["slaves"][0]["esc_errors"]) == {"invalid", "rx", "forwarded", "lost_link",
                                                    "epu"}
    assert set(view["stats"]) == {"frames", "lost_frames", "cycle_us"}
    assert view["log_styles"] == ["twincat", "sirio", "pegaso", "aitraceprint"]


@pytest.mark.parametrize("data", ("01000000", "0100"))
def test_a_refused_init_command_stops_the_transition(tmp_path: Path, data: str) -> None:
    """An init command the slave aborts (here a write of the read-only 0x1018:1): logged with
    the SDO abort code, comm_error, the slave stays in PREOP. Sent with a wrong length (two
    bytes for the UDINT) it is still "read only", for 0x1018:1, as on the wire: the access is
    checked before the length (devices/esm.py CoeMailbox.sdo_download)."""
    rig = build_rig(load_rig_spec(_rig_with_eni(
        tmp_path, "<Index>#xF030</Index>\n              <SubIndex>0</SubIndex>\n"
                  "              <Data>0500</Data>",
        "<Index>#x1018</Index>\n              <SubIndex>1</SubIndex>\n"
        f"              <Data>{data}</Data>")))
    events = rig.run_until(2 * US)
    cpx = master_view(rig)["slaves"][2]
    assert cpx["state"] == "PREOP"
    assert cpx["diagnosis"].startswith("init command 'CPX-E-EC: configured module list, count'")
    assert cpx["diagnosis"].endswith(
        "0x1018:1 -> abort 0x06010002 (Attempt to write a read only object)")
    assert [r["reason"] for r in records(events, "comm_error")] == ["init_command"]
    assert any("SDO download 0x1018:01 aborted with 0x06010002" in r["text"]
               for r in records(events, "log", "master"))


@pytest.mark.parametrize(("out_us", "found_in", "code"), [(US, "SAFEOP", "0x001B"),
                                                          (30_000, "OP", "0x0000")])
def test_a_slave_found_again_reports_the_state_it_is_found_in(out_us: int, found_in: str,
                                                              code: str) -> None:
    """Seed 003: "the status change of slaves" is an event. A slave found again after a loss
    is read in the state it is in (SAFEOP with the SM watchdog's 0x001B after a second cut
    off, still OP after 30 ms), as its "found on the line again in '...'" line says; then the
    recovery takes it to INIT. The event reported INIT only: the state and the AL status code
    the master read never reached ECAT_Notify. ECAT_Resync comes once, when the restarted
    slave reaches OP, not at the OP it was found in."""
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.run_until(IN_OP_US + out_us)
    rig.apply("master", "plug_cable", {"cable": 2})
    events = rig.run_until(IN_OP_US + out_us + 3 * US)
    for name in ("cpx", "drive_ec-ecat"):
        p = POSITIONS[name]
        mine = [r for r in (e.to_record() for e in events) if r["device"] == "master"
                and r.get("position") == p and r["event"] in ("slave_state", "resync")]
        assert [(r["event"], r.get("from"), r.get("to"), r.get("code")) for r in mine] == [
            ("slave_state", "", found_in, code),
            ("slave_state", found_in, "INIT", "0x0000"),
            ("slave_state", "INIT", "PREOP", "0x0000"),
            ("slave_state", "PREOP", "SAFEOP", "0x0000"),
            ("slave_state", "SAFEOP", "OP", "0x0000"),
            ("resync", None, None, None)], name
        found = [r["text"] for r in records(events, "log", "master")
                 if f"(100{p + 1}): found on the line again" in r["text"]]
        assert found == [f"'{rig.devices[name].box_name}' (100{p + 1}): found on the line "
                         f"again in '{found_in}'."]


def test_a_slave_lost_with_process_data_counts_a_wkc_error() -> None:
    """The structure's ``wkc_errors`` counts a slave in SAFEOP / OP that stopped answering
    process data (docs/ethercat-master.md): one lost behind a pulled cable in OP did (the
    cyclic frame's working counter falls short of it), and counted nothing. One lost before
    SAFEOP had no process data to miss."""
    rig = line_in_op()
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.run_until(IN_OP_US + US // 2)
    assert [s["counters"]["wkc_errors"] for s in master_view(rig)["slaves"]] == [0, 0, 1, 1]
    rig = build_rig(load_rig_spec(LINE_RIG))
    rig.run_until(50_000)  # the CPX-E-EC and the drive in PREOP
    assert [s["state"] for s in master_view(rig)["slaves"]][2:] == ["PREOP", "PREOP"]
    rig.apply("master", "pull_cable", {"cable": 2})
    rig.run_until(100_000)
    assert [s["counters"]["wkc_errors"] for s in master_view(rig)["slaves"]] == [0, 0, 0, 0]


def test_a_long_burst_of_lost_frames_is_reported_as_it_goes() -> None:
    """1500 frames lost: the master reports the first at once, then at most once a second
    the frames lost since (1000), and the rest (499) with the first frame that comes back;
    one event per answering slave each time, the counters at 1500."""
    rig = line_in_op()
    rig.apply("master", "lose_frames", {"count": 1500})
    events = rig.run_until(IN_OP_US + 2 * US)
    counts = [r["count"] for r in records(events, "comm_error") if r["position"] == 0
              and r["reason"] == "lost_frames"]
    assert counts == [1, 1000, 499]
    assert master_view(rig)["stats"]["lost_frames"] == 1500
