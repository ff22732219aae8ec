"""The servo drive in the dashboard (seed 004), in headless Chromium and without a browser.

Browser tests (marked ``browser``), on the default rig with the simulation paused and advanced
by the test: a trainee enables the axis, homes it and moves it from the panel (ch. 2's
positioner set-up: torque, homing method 34 = R18's default, then a point-to-point move); a
trainee switches the drive to CANopen (c9 = 5, save, power cycle: ch. 2 / ch. 4 "read at
power-up") and brings it to OPERATION ENABLED with the panel's master (NMT start, 0x6040 =
0x06, 0x07, 0x0F over SDO: the ch. 4 worked sequence), and the frame log shows the decoded
traffic. The other tests check what the views write, from snapshots and events.
"""

from __future__ import annotations

import itertools
from typing import Any

import pytest
from helpers import (
    LiveDashboard,
    choose,
    compare_screenshot,
    open_dashboard,
    wait_until,
)

from app.ui.drive import canopen_master as cm
from app.ui.drive.axis_scene import SEGMENT_OFF, SEGMENT_ON, Travel, display_segments, legend_text
from app.ui.drive.canopen_panel import frames_html, pdo_html, status_html
from app.ui.drive.drive_options import (
    FIELDBUS_OPTIONS,
    alarm_details,
    alarm_options,
    leading_int,
    mode_option,
)
from app.ui.drive.drive_state import (
    DriveLog,
    bit_grid,
    r05_names,
    state_rows,
    statusword_names,
    words_html,
)
from app.ui.drive.plots import SAMPLE_US
from app.ui.drive.view import companion
from devices.canopen import master_frames as mf
from devices.events import AlarmChanged, EmergencySent, LogLine, StateChanged
from devices.servo.alarms import alarm_table

BOOT_S = 4.0  # the coupler's power-up scan (test_dashboard.py); the drive boots in 50 ms
DRIVE = "drive"
NODE = "drive-can"


# ---- page helpers ---------------------------------------------------------------------------
def drive_value(page: Any, row: str) -> str:
    """A value of the Drive tab's state table, as the page shows it."""
    cell = page.locator("#fr-drive tr", has=page.locator("th", has_text=row)).locator("td")
    return str(cell.first.inner_text()).strip()


def expect_drive(page: Any, row: str, text: str) -> None:
    wait_until(lambda: text in drive_value(page, row), what=f"{row} to show {text!r}")


def wait_drive(live: LiveDashboard, predicate: Any, what: str) -> None:
    """Wait for a click to reach the drive model (the runtime is paused), then the view."""
    wait_until(lambda: predicate(live.snapshot(DRIVE)), what=what)
    live.settle()


def open_drive_tabs(page: Any, live: LiveDashboard) -> None:
    open_dashboard(page, live)
    live.advance(BOOT_S)
    page.get_by_role("tab", name="Servo drive").click()
    page.get_by_role("tab", name="Drive", exact=True).click()
    expect_drive(page, "CiA 402 state", "Switch on disabled")


def plots_drawn(live: LiveDashboard) -> None:
    drives = live.dashboard.drives
    assert drives is not None
    wait_until(drives.plots.caught_up, what="the plots to take the last samples")


# ---- browser ------------------------------------------------------------------------------
@pytest.mark.browser
def test_enable_home_and_move_from_the_panel(live: LiveDashboard, page) -> None:
    open_drive_tabs(page, live)
    drives = live.dashboard.drives
    assert drives is not None
    start_x = drives.scenes[DRIVE].carriage_x()
    assert drives.scenes[DRIVE].segment_colors()[0]["a"] == SEGMENT_ON  # "Fr": F lights a

    page.get_by_role("button", name="Enable", exact=True).click()
    wait_drive(live, lambda s: s["ds402_state"] == "Operation enabled", "torque on")
    expect_drive(page, "CiA 402 state", "Operation enabled")
    expect_drive(page, "CiA 402 state", "display En")

    # Homing with R18 = 34 (first marker in the positive direction), home offset 0: the axis
    # creeps at R21 = 100 u/s to the marker at 1500 and the position then reads 0 (ch. 4).
    page.get_by_role("button", name="Home", exact=True).click()
    wait_drive(live, lambda s: s["mode"] == 6, "homing started")
    live.advance(16.0)
    snap = live.snapshot(DRIVE)
    assert snap["homed"] and snap["status_bits"]["Homing_ok"]
    assert snap["position_counts"] == 0
    expect_drive(page, "Position", "homed")

    # A faster profile for the move: R12 profile_velocity = 60000 u/s (600 rpm, feed 6000).
    page.get_by_text("Registers and parameters").click()
    page.get_by_label("Register value", exact=True).fill("60000")
    page.get_by_role("button", name="Write register").click()
    wait_until(lambda: live.command(DRIVE, "read_register", {"register": 12}) == 60000,
               what="R12 = 60000")
    page.get_by_label("Target position", exact=True).fill("300000")
    page.get_by_role("button", name="Move", exact=True).click()
    wait_drive(live, lambda s: s["mode"] == 1 and s["target"] == 300000, "the move started")
    live.advance(6.0)
    snap = live.snapshot(DRIVE)
    assert snap["position_counts"] == 300000
    assert snap["status_bits"]["EOJ"] and snap["outputs"]["end_of_job"]
    expect_drive(page, "CiA 402 state", "Operation enabled")
    expect_drive(page, "Outputs", "End of Job on")
    expect_drive(page, "Position", "300000")
    assert drives.scenes[DRIVE].carriage_x() > start_x + 2.5  # half the travel to the right
    plots_drawn(live)
    assert drives.plots.drawn_points() >= 900  # 20 s of 20 ms samples
    compare_screenshot(page, "drive_moved")


@pytest.mark.browser
def test_canopen_from_the_ui(live: LiveDashboard, page) -> None:
    open_drive_tabs(page, live)
    # c9 = 5 and save (only without torque, ch. 2), then a power cycle: c9 is read at power-up.
    page.get_by_text("Fieldbus and flash").click()
    choose(page, "Fieldbus (c9)", "5 CANopen")
    page.get_by_role("button", name="Write c9 and c7").click()
    wait_until(lambda: live.command(DRIVE, "read_parameter", {"parameter": "c9"}) == 5,
               what="c9 = 5")
    page.get_by_role("button", name="Save to flash").click()
    wait_drive(live, lambda s: s["saving"], "the save")
    live.advance(3.5)
    assert not live.snapshot(DRIVE)["saving"]
    power = page.get_by_label("Drive power", exact=True)
    power.uncheck()
    wait_drive(live, lambda s: not s["powered"], "power off")
    power.check()
    wait_drive(live, lambda s: s["powered"] and s["fieldbus"] == "canopen", "CANopen at power-up")
    live.advance(0.2)  # 50 ms of Initialisation, then the boot-up message
    assert live.snapshot(NODE)["nmt"] == "Pre-operational"

    page.get_by_role("tab", name="CANopen").click()
    can = page.locator("#fr-can")
    wait_until(lambda: "Pre-operational" in can.inner_text(), what="Pre-operational")
    master = live.dashboard.drives.master
    assert master is not None

    def click(name: str) -> None:
        """A master button; its frame reaches the node before the simulation moves on."""
        sent = master.sent
        page.get_by_role("button", name=name, exact=True).click()
        wait_until(lambda: master.sent > sent, what=f"the frame of {name}")
        live.advance(0.05)  # a frame and its answer take well under 1 ms at 500 kbit/s

    page.get_by_label("Heartbeat (ms)", exact=True).fill("500")
    click("Set heartbeat")
    choose(page, "NMT command", "Start (0x01)")
    click("Send NMT")
    assert live.snapshot(NODE)["nmt"] == "Operational"
    for button in ("Shutdown", "Switch on", "Enable op."):
        click(button)
    assert live.snapshot(DRIVE)["ds402_state"] == "Operation enabled"
    live.advance(1.1)  # two heartbeats
    wait_until(lambda: "Operation enabled" in can.inner_text(), what="OPERATION ENABLED")
    log = page.locator("#fr-frames").inner_text()
    for text in ("Start remote node", "download 0x6040:00 = 0F 00", "TPDO1 0x6041:00=",
                 "download 0x1017:00 done"):
        assert text in log, text
    kinds = {f["kind"] for f in live.snapshot(NODE)["frames"]}
    assert {"NMT", "SDO", "PDO", "NMT-EC"} <= kinds
    compare_screenshot(page, "canopen_enabled")


# ---- the views, without a browser -----------------------------------------------------------
@pytest.mark.parametrize(("text", "lit"), [
    ("Fr", ["aefg", "eg"]), ("En", ["adefg", "ceg"]), ("--", ["g", "g"]),
    (" 9", ["", "abcdfg"]), ("16", ["bc", "acdefg"]), ("9", ["", "abcdfg"]), ("", ["", ""]),
])
def test_seven_segment_patterns(text: str, lit: list[str]) -> None:
    """Seed 004 ch. 5: "Fr" when disabled, two dashes while saving, the alarm code in alarm
    (right-aligned in the two digits, docs/servo-drive.md §Alarms)."""
    assert display_segments(text) == lit


def test_travel_maps_switch_positions_and_clamps() -> None:
    axis = {"neg_limit": -60000.0, "pos_limit": 660000.0, "home_switch": -3000.0}
    travel = Travel.of(axis, 10.6)
    nl, home, pl = travel.x(-60000), travel.x(-3000), travel.x(660000)
    assert travel.x0 < nl < home < pl < travel.x1
    assert travel.x(-10**9) == travel.x0 and travel.x(10**9) == travel.x1  # end stops
    assert travel.x(300000) == pytest.approx((nl + pl) / 2)


def test_state_rows_and_bits_of_a_moving_positioner() -> None:
    snap = {"powered": True, "ds402_state": "Operation enabled", "display": "En", "mode": 1,
            "position_counts": 6000, "target": 6000, "homed": True, "velocity": 0.0,
            "following_error": 0.0, "ten": True, "ien": True, "jammed": False,
            "outputs": {"end_of_job": True, "near_target": True, "brake": True},
            "limits": {"neg": False, "pos": False, "home": True}, "alarm": None,
            "status_register": 0x63, "statusword": 0x1637, "control_register": 0x23,
            "controlword": 0x1F}
    rows = dict(state_rows(snap))
    assert "Operation enabled" in rows["CiA 402 state"] and "En" in rows["CiA 402 state"]
    assert "End of Job on" in rows["Outputs"] and "released" in rows["Outputs"]
    assert "homed" in rows["Position"] and "none" in rows["Alarm"]
    # Ch. 1: R05 bit 6 is EOJ in the positioner, Homing_ok in homing.
    assert r05_names(1)[6][0] == "EOJ" and r05_names(6)[6][0] == "Homing_ok"
    assert statusword_names(6)[12][0] == "homing attained"
    assert statusword_names(1)[12][0] == "set-point acknowledge"
    html = words_html(snap)
    assert "0x63" in html and "0x1637" in html and "Pos_str" in html


def test_bit_grid_lights_the_set_bits() -> None:
    html = bit_grid("R05", 0x41, {0: ("Ten_st", "in torque"), 6: ("EOJ", "End of Job")}, 8)
    assert html.count('class="fr-on"') == 2 and "0x41" in html
    assert html.count("<tr>") == 2  # 8 bits, 4 per row


def test_alarm_row_shows_description_and_effect() -> None:
    spec = alarm_table("modbus")[16]
    snap = {"powered": True, "ds402_state": "Fault", "alarm": spec.as_dict(), "alarms": [16]}
    row = dict(state_rows(snap))["Alarm"]
    # the effect in a trainee's words (docs/dashboard.md, the Drive tab's Alarm row)
    assert "16 FOLLOWING_ERROR" in row and "— the axis is released at once (torque off)" in row


def test_alarm_choices_follow_the_fieldbus() -> None:
    """Ch. 3 / ch. 5 codes for Modbus; ch. 6 renames 30-33 for Profinet."""
    modbus, profinet = alarm_options("modbus"), alarm_options("profinet")
    assert len(modbus) == len(alarm_table("modbus"))
    assert "16 FOLLOWING_ERROR" in modbus  # the description is the box's hint
    assert alarm_details("modbus")["16 FOLLOWING_ERROR"].startswith(
        "16 FOLLOWING_ERROR: maximum position following error")
    assert any(o.startswith("31 PROFINET_INIT_1") for o in profinet)
    assert leading_int("-127 analog reference") == -127
    assert mode_option(-50) == "-50 save/load"
    assert [leading_int(o) for o in FIELDBUS_OPTIONS] == [3, 5, 11, 13]


def test_drive_log_words() -> None:
    log = DriveLog()
    log.add([StateChanged(1_000, DRIVE, "Switched on", "Operation enabled"),
             StateChanged(2_000, DRIVE, "Pre-operational", "Operational", machine="nmt"),
             AlarmChanged(3_000, DRIVE, "16", "FOLLOWING_ERROR", True),
             EmergencySent(3_000, DRIVE, 0x8611, 0x81, bytes([16])),
             LogLine(4_000, DRIVE, text="mode 6 (homing)"),
             LogLine(4_000, "other", text="not mine")])
    html = log.html(DRIVE)
    assert "CiA 402: Switched on -&gt; Operation enabled" in html
    assert "NMT: Pre-operational -&gt; Operational" in html
    assert "alarm 16 FOLLOWING_ERROR raised" in html and "EMCY 0x8611" in html
    assert html.index("mode 6") < html.index("CiA 402")  # newest first
    assert "not mine" not in html


# ---- the CANopen tab and its master ---------------------------------------------------------
def test_master_frames_byte_for_byte() -> None:
    """DS 301: NMT (command, node) on COB-ID 0; expedited SDO download with the size
    indicated (0x2B = 2 bytes, 0x2F = 1, 0x23 = 4), upload 0x40; index little-endian."""
    assert mf.nmt(0x01, 1) == mf.Frame(0x000, bytes([0x01, 0x01]))
    assert mf.sdo_download(1, 0x6040, 0, 0x0F, 2) == mf.Frame(
        0x601, bytes([0x2B, 0x40, 0x60, 0x00, 0x0F, 0x00, 0x00, 0x00]))
    assert mf.sdo_download(3, 0x6060, 0, -1, 1).data == bytes([0x2F, 0x60, 0x60, 0, 0xFF, 0,
                                                               0, 0])
    assert mf.sdo_download(1, 0x607A, 0, 6000, 4).data[:8] == bytes([0x23, 0x7A, 0x60, 0, 0x70,
                                                                     0x17, 0, 0])
    assert mf.sdo_upload(1, 0x1018, 1) == mf.Frame(0x601, bytes([0x40, 0x18, 0x10, 1, 0, 0, 0,
                                                                 0]))
    assert cm.parse_object("0x6041:0") == (0x6041, 0) and cm.parse_object("1018:4") == (0x1018,
                                                                                      4)
    with pytest.raises(ValueError):
        mf.sdo_download(1, 0x6040, 0, 1, 5)
    with pytest.raises(ValueError):
        cm.parse_object("zz")


def test_frame_log_newest_first_and_escaped() -> None:
    frames = [{"t": 0.05, "dir": "tx", "id": "0x701", "dlc": 1, "data": "00",
               "kind": "NMT-EC", "text": "boot-up"},
              {"t": 0.1, "dir": "rx", "id": "0x000", "dlc": 2, "data": "01 01", "kind": "NMT",
               "text": "Start remote node <1>"}]
    html = frames_html(frames)
    assert html.index("Start remote node") < html.index("boot-up")
    assert "&lt;1&gt;" in html and 'class="fr-rx ' in html
    assert "no frames yet" in frames_html([])


def test_frame_log_heartbeat_line() -> None:
    """Repeated heartbeats are one line above the log (devices/canopen/monitor.py): state,
    count, period, last time, as a CAN analyser's receive list shows a periodic frame."""
    beats = [{"t": 12.5, "dir": "tx", "id": "0x702", "dlc": 1, "data": "05",
              "kind": "NMT-EC", "text": "node 2: Operational", "count": 37, "period": 0.5}]
    html = frames_html([], heartbeats=beats)
    line = html[html.index('id="fr-can-hb"'):html.index("</p>")]
    for part in ("0x702", "node 2: Operational", "05", "37 in a row", "every 0.500 s",
                 "last 12.500"):
        assert part in line, (part, line)
    assert html.index('id="fr-can-hb"') < html.index('id="fr-frames"')
    first = frames_html([], heartbeats=[{**beats[0], "count": 1, "period": None}])
    assert "every" not in first and "1 in a row" in first
    assert 'id="fr-can-hb"' not in frames_html([])


def test_canopen_status_says_why_it_is_silent() -> None:
    html = status_html(NODE, {"active": False, "bitrate": 500000}, {"powered": True,
                                                                    "fieldbus": "modbus"})
    assert "Modbus RTU" in html and "c9 = 5" in html
    node = {"active": True, "nmt": "Operational", "heartbeat_ms": 500, "bitrate": 500000,
            "rpdo": [{"pdo": "RPDO1", "can_id": "0x201", "valid": True, "type": 255,
                      "mapping": ["0x6040:00/16"]}],
            "tpdo": [{"pdo": "TPDO2", "can_id": "0x281", "valid": False, "type": 255,
                      "event_timer_ms": 20, "mapping": []}]}
    html = status_html(NODE, node, {"ds402_state": "Operation enabled"})
    assert "Operational" in html and "0x1017 = 500 ms" in html
    pdos = pdo_html(node)
    assert "0x6040:00/16" in pdos and 'class="fr-off"' in pdos and "timer 20 ms" in pdos


def test_companion_finds_the_drives_node() -> None:
    snapshot = {"devices": {DRIVE: {"kind": "servo"}, NODE: {"kind": "canopen", "drive": DRIVE},
                            "ecat": {"kind": "coe", "drive": DRIVE, "leds": {"Status": "on"}}}}
    assert companion(snapshot, DRIVE, kind="canopen")[0] == NODE
    assert companion(snapshot, DRIVE, key="leds")[0] == "ecat"
    assert companion(snapshot, "other")[0] is None


# ---- the live view, without a browser ---------------------------------------------------------
def test_plots_sample_simulated_time(live: LiveDashboard) -> None:
    """A paused rig advanced in one go still gets one sample every 20 ms of simulated time."""
    drives = live.dashboard.drives
    assert drives is not None
    before = drives.sampler.columns()[0]
    live.advance(2.0)
    t = drives.sampler.columns()[0]
    new = t[len(before):] if len(before) else t
    assert len(new) == pytest.approx(2.0 / (SAMPLE_US / 1e6), abs=2)
    assert all(round((b - a) * 1e6) == SAMPLE_US for a, b in itertools.pairwise(new))


def test_axis_scene_follows_the_drive(live: LiveDashboard) -> None:
    """The display shows the alarm code in alarm (ch. 3), the carriage moves with the
    position, a limit switch lights when its input is active."""
    drives = live.dashboard.drives
    assert drives is not None
    scene = drives.scenes[DRIVE]
    live.advance(0.1)
    assert [c["a"] for c in scene.segment_colors()] == [SEGMENT_ON, SEGMENT_OFF]  # "Fr"
    live.command(DRIVE, "inject_alarm", {"code": "9"})
    live.advance(0.1)
    assert live.snapshot(DRIVE)["display"].strip() == "9"
    assert scene.segment_colors()[1] == {s: SEGMENT_ON if s in "abcdfg" else SEGMENT_OFF
                                        for s in "abcdefg"}
    live.command(DRIVE, "set_input", {"name": "neg_limit", "value": True})
    live.advance(0.1)
    assert live.snapshot(DRIVE)["limits"]["neg"]
    assert "NL" in legend_text(live.snapshot(DRIVE))


TWO_DRIVES = """
[rig]
name = "two drives on one Modbus line"
seed = 1
step_ms = 1

[[servo]]
id = "x"
node_id = 1

[[servo]]
id = "y"
node_id = 2
"""


def test_rig_with_two_drives_and_no_coupler(dashboard_for, tmp_path) -> None:
    """Drives without a FastCAT get the drive tabs alone; the picker chooses the drive the
    panels show, every drive keeps its axis, and the plots show the new drive's samples at
    once: every drive is sampled all along, each page showing its own pick's charts."""
    rig_file = tmp_path / "two.toml"
    rig_file.write_text(TWO_DRIVES)
    live = dashboard_for(rig_file)
    drives = live.dashboard.drives
    assert drives is not None and drives.drive_ids == ["x", "y"]
    assert set(drives.scenes) == {"x", "y"}
    live.advance(0.5)
    assert len(drives.sampler.columns()[0]) > 0
    live.command("y", "enable", {"on": True})
    before = len(drives.sampler.columns()[0])
    drives.select("y")
    assert len(drives.sampler.columns()[0]) > 0  # y's own samples, from the start
    live.advance(0.2)
    assert drives.selected == "y" and len(drives.sampler.columns()[0]) > before
    assert live.snapshot("y")["display"] == "En" and live.snapshot("x")["display"] == "Fr"
    assert drives.scenes["y"].segment_colors()[0]["a"] == SEGMENT_ON  # E
    assert drives.scenes["x"].segment_colors()[0]["a"] == SEGMENT_ON  # F
    assert drives.scenes["y"].segment_colors()[1]["c"] == SEGMENT_ON  # n
    assert drives.scenes["x"].segment_colors()[1]["c"] == SEGMENT_OFF  # r
