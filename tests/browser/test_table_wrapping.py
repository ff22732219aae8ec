"""Table cells wrap between words, never inside one, at the browser tests' 1280 x 720.

The UI audit found the master's slave table showing "powe" / "r off" in the Link column,
"(SelemaDriveECAT" / ")" in the name column and "10/2/1/1" / "3" in the counters, and the
CANopen frame log's time column breaking "10.250" after five characters. A word broken across
two lines has two client rectangles (a Range over its characters): the test looks at every
word of every cell of those tables as Chromium lays them out.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from helpers import LiveDashboard, choose, open_dashboard, wait_until

from app.ui.drive import canopen_master as cm
from devices.canopen import master_frames as mf

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[2]

BOOT_S = 8.0

# Every whitespace-separated word of the cells under ``sel`` that the layout splits over more
# than one line (a wrap inside the word), with its cell's text.
SPLIT_WORDS_JS = """
sel => {
  const split = [];
  for (const cell of document.querySelectorAll(sel)) {
    const walker = document.createTreeWalker(cell, NodeFilter.SHOW_TEXT);
    for (let node = walker.nextNode(); node; node = walker.nextNode()) {
      const re = /\\S+/g;
      let m;
      while ((m = re.exec(node.data)) !== null) {
        const range = document.createRange();
        range.setStart(node, m.index);
        range.setEnd(node, m.index + m[0].length);
        const tops = new Set([...range.getClientRects()].filter(r => r.width > 0)
                                                      .map(r => Math.round(r.top)));
        if (tops.size > 1) split.push(m[0] + "  in  " + cell.innerText.replace(/\\n/g, " | "));
      }
    }
  }
  return split;
}
"""


def split_words(page: Any, selector: str) -> list[str]:
    return list(page.evaluate(SPLIT_WORDS_JS, selector))


def test_master_slave_table_wraps_between_words(live: LiveDashboard, page: Any) -> None:
    open_dashboard(page, live)
    live.advance(BOOT_S)
    live.command("master", "power_slave", {"position": 1, "on": False})  # the TRS-CAT
    live.command("master", "lose_frames", {"count": 10})
    live.advance(2.0)
    slaves = live.snapshot("master")["slaves"]
    assert slaves[1]["present"] is False
    for tab in page.get_by_role("tab", name="Line").all():
        tab.click()
    table = page.locator("#fr-line-slaves")
    wait_until(lambda: "not seen" in table.inner_text(), what="the TRS-CAT lost")
    assert split_words(page, "#fr-line-slaves td") == []



@pytest.mark.parametrize("fault", ["sync0_lost", "module_lost"])
def test_master_slave_table_keeps_al_code_words_whole(live: LiveDashboard, page: Any,
                                                      fault: str) -> None:
    """The AL status code column broke "Synchronization" after "Synchronizat"
    (dc_sync_lost's 0x001A at the TRS-CAT and the CPX-E-EC) and the FastCAT's coupler code
    names ("MISSING_NODE_ANSWER", module_lost_in_op's 0x8204) inside a letter run: a name may
    break only after an underscore (<wbr>)."""
    open_dashboard(page, live)
    live.advance(BOOT_S)
    if fault == "sync0_lost":
        live.command("master", "dc_fault", {"kind": "sync0_lost"})
        expected = "Synchronization"
    else:
        live.command("fastcat/2", "unplug")
        expected = "MISSING_NODE_ANSWER"
    live.advance(0.5)
    for tab in page.get_by_role("tab", name="Line").all():
        tab.click()
    table = page.locator("#fr-line-slaves")
    wait_until(lambda: expected in table.inner_text().replace("\n", ""), what=expected)
    assert split_words(page, "#fr-line-slaves td") == []

# The badges under ``sel`` whose text the layout spreads over more than one line.
BROKEN_BADGES_JS = """
sel => [...document.querySelectorAll(sel + ' .fr-badge')].filter(badge => {
  const range = document.createRange();
  range.selectNodeContents(badge);
  return new Set([...range.getClientRects()].filter(r => r.width > 0)
                                            .map(r => Math.round(r.top))).size > 1;
}).map(badge => badge.innerText)
"""


def test_master_phase_badge_stays_on_one_line(live: LiveDashboard, page: Any) -> None:
    """The master panel's Phase badge "running, 2 DC slaves held in SAFEOP" broke over two
    lines at the 400 px panel (the review; "running, 2 slaves lost" with cable_pulled's 2
    slaves too in a narrower one): the badge holds the phase, the note follows it."""
    open_dashboard(page, live)
    live.advance(BOOT_S)
    for tab in page.get_by_role("tab", name="Line").all():
        tab.click()
    status = page.locator("#fr-line-master-status")
    live.command("master", "pull_cable", {"cable": 2})  # static/scenarios/cable_pulled.toml
    live.advance(1.0)
    wait_until(lambda: "2 slaves lost" in status.inner_text(), what="2 slaves lost")
    assert page.evaluate(BROKEN_BADGES_JS, "#fr-line-master-status") == []
    live.command("master", "plug_cable", {"cable": 2})
    live.advance(6.0)
    live.command("master", "dc_fault", {"kind": "drift"})  # static/scenarios/dc_sync_lost.toml
    live.advance(3.0)
    wait_until(lambda: "2 DC slaves held in SAFEOP" in status.inner_text(),
               what="2 DC slaves held in SAFEOP")
    assert page.evaluate(BROKEN_BADGES_JS, "#fr-line-master-status") == []


def test_canopen_time_column_keeps_its_numbers_whole(live: LiveDashboard, page: Any) -> None:
    open_dashboard(page, live)
    live.advance(BOOT_S)
    node_id = "drive_co-can"
    node = live.rig.devices[node_id]
    heartbeat = mf.sdo_download(int(node.node_id), *cm.HEARTBEAT, 500, 2)
    live.runtime.submit(lambda: node.receive(heartbeat.can_id, heartbeat.data)).result(10)
    live.advance(3.0)  # past 10 s: times of six characters ("10.250")
    # Repeated heartbeats are no rows (one heartbeat line above the log): an SDO upload
    # after 10 s puts rows with such times in the log.
    read = mf.sdo_upload(int(node.node_id), *cm.HEARTBEAT)
    live.runtime.submit(lambda: node.receive(read.can_id, read.data)).result(10)
    live.advance(0.1)
    page.get_by_role("tab", name="Servo drive").click()
    choose(page, "Servo drive", "drive_co")
    page.get_by_role("tab", name="CANopen").click()
    frames = page.locator("#fr-frames")
    wait_until(lambda: "11.0" in frames.inner_text(), what="frames after 10 s")
    assert split_words(page, "#fr-frames td") == []


def test_slave_io_tables_keep_their_bit_groups_whole(live: LiveDashboard,
                                                     page: Any) -> None:
    """The review (22_cpx_form.png): the CPX-E-EC module table broke the 16DI's sixteen
    input bits as "00000000000" / "00000"; they are grouped by 8 (app/ui/line/slave_panel.py
    bits), so the cell wraps between the groups."""
    open_dashboard(page, live)
    live.advance(BOOT_S)
    view = live.dashboard.line
    assert view is not None
    view.focus(None, "cpx")
    for tab in page.get_by_role("tab", name="Slave").all():
        tab.click()
    table = page.locator("#fr-slave-io")
    wait_until(lambda: "16DI" in table.inner_text(), what="the CPX-E-EC module table")
    assert split_words(page, "#fr-slave-io td") == []
    # The held-off note under the 8DO's output image (docs/cpx-e-ec.md choice 40) too.
    live.command("cpx", "write_object", {"index": 0x7002, "sub": 4, "value": 1})
    live.command("cpx/2", "short_circuit", {"channel": 3, "on": True})
    live.advance(0.1)
    try:
        wait_until(lambda: "held off: 3 (short)" in table.inner_text(), what="the note")
        assert split_words(page, "#fr-slave-io td") == []
    finally:
        live.command("cpx/2", "short_circuit", {"channel": 3, "on": False})
        live.command("cpx", "write_object", {"index": 0x7002, "sub": 4, "value": 0})
        live.advance(0.1)


# The Server cells whose text the column clips (overflow hidden: wider content than cell).
CLIPPED_JS = """
sel => [...document.querySelectorAll(sel)]
  .filter(cell => cell.scrollWidth > cell.clientWidth).map(cell => cell.innerText)
"""


def test_event_log_server_column_shows_every_name_whole(live: LiveDashboard, page: Any) -> None:
    """The Server column (4.8em) showed "scenari" for a caption's "scenario"; every device id
    that reaches the log, the master's "(65535)" and "scenario" must fit."""
    from devices.events import Caption, StateChanged

    open_dashboard(page, live)
    live.advance(1.0)
    t_us = live.runtime.frame.t_us
    # The devices that emit under their own id (a drive's -can / -ecat companions emit under
    # the drive's), and a 10-character id ("drive_ecat", ethercat_line's drive until it took
    # the default rig's "drive_ec"), as a caption's device (the log keeps captions from any).
    names = ["fastcat", "trscat", "cpx", "drive", "drive_co", "drive_ec"]
    live.runtime.journal([StateChanged(t_us, d, "A", "B", machine="test") for d in names]
                         + [Caption(t_us, "drive_ecat", text="longest id"),
                            Caption(t_us, "scenario", text="a caption")])
    live.advance(0.1)
    log = page.locator("#fr-log")
    wait_until(lambda: "a caption" in log.inner_text(), what="the caption in the event log")
    shown = {str(s) for s in page.evaluate(
        "() => [...document.querySelectorAll('#fr-log td.fr-srv')].map(c => c.innerText)")}
    assert {"scenario", "drive_ecat", "(65535)", *names} <= shown
    assert page.evaluate(CLIPPED_JS, "#fr-log td.fr-srv") == []


# The widths (px) of ``texts`` in the font of the dropdown ``label`` (viser's Select, with its
# letter spacing), and the room its box leaves for the value (the chevron taken off).
FIT_JS = """
([label, texts]) => {
  const input = [...document.querySelectorAll('input[role=combobox]')]
    .find(i => i.offsetParent !== null && i.labels.length
               && i.labels[0].innerText.trim() === label);
  if (!input) return null;
  const cs = getComputedStyle(input);
  const ctx = document.createElement('canvas').getContext('2d');
  ctx.font = cs.font;
  ctx.letterSpacing = cs.letterSpacing;
  const chevron = input.parentElement.querySelector('[data-position=right]');
  const room = input.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight)
    - (chevron ? chevron.getBoundingClientRect().width : 0);
  return {room, widths: texts.map(t => ctx.measureText(t).width)};
}
"""


def cut_options(page: Any, label: str, options: list[str], slack: float = 1.0) -> list[str]:
    """The options of the dropdown ``label`` wider than ``slack`` times its box's room."""
    fit = page.evaluate(FIT_JS, [label, options])
    assert fit is not None, f"no visible dropdown {label!r}"
    return [f"{o} ({w:.0f} px > {fit['room']:.0f})"
            for o, w in zip(options, fit["widths"], strict=True) if w > slack * fit["room"]]


# The longest manual names ("0x0B UNKNOWN_SDO_WR_ANSWER", "24 ABS_ENCODER_COMMUNICATION",
# 184 / 187 px) are wider than the control panel's 152 px box by themselves: the box may lose
# their last characters, which the hint (hover) and the open list show whole.
NAME_SLACK = 1.25


def test_fault_and_alarm_choices_show_whole_in_their_boxes(live: LiveDashboard,
                                                           page: Any) -> None:
    """The Fault box read "0x01 MODULE_CHANGED — A mod" (the description glued to the
    label, 547 px in a 152 px box): the labels are the code and the manual's name, and the
    description goes to the box's hint. The drive's Alarm list is built the same way."""
    from app.ui.dashboard import fault_options
    from app.ui.drive.drive_options import alarm_options
    from app.ui.panels.control import FaultOption

    open_dashboard(page, live)
    faults = [FaultOption(o.table, o.code, o.name, o.description).label
              for o in fault_options()]
    assert cut_options(page, "Fault", faults, NAME_SLACK) == []
    choose(page, "Fault", "0x12 ADDRESS_MASTER_NOT_OK")
    panels = live.dashboard._panels
    assert panels is not None
    control = panels.control
    (client_id,) = live.dashboard.server.get_clients()
    # Each page's own pick, and the hint its page was sent (an open rig's Fault: ClientPick)
    wait_until(lambda: control._fault.value_for(client_id) == "0x12 ADDRESS_MASTER_NOT_OK",
               what="the pick")
    wait_until(lambda: str(control._fault_hints.sent(client_id)).startswith(
        "0x12 ADDRESS_MASTER_NOT_OK: The address set with the rotary switch does not match"),
        what="the page's hint")
    page.get_by_role("tab", name="Servo drive").click()
    alarms = sorted({o for bus in ("modbus", "canopen", "ethercat", "profinet")
                     for o in alarm_options(bus)})
    assert cut_options(page, "Alarm", alarms, NAME_SLACK) == []


def test_player_time_stays_on_one_line(live: LiveDashboard, page: Any) -> None:
    """The player's "t = 7.0 s of 16 s" broke after "7.0 s" in the panel's width."""
    from app.scenario import load_scenario
    from app.ui.panels.scenario_player import STATUS_ID

    scenario = load_scenario(ROOT / "static" / "scenarios" / "module_lost_in_op.toml")
    open_dashboard(page, live)
    page.get_by_role("tab", name="Scenario", exact=True).click()
    panel = live.dashboard.scenario_player
    panel.load(scenario)
    while live.runtime.frame.t_us < 7_000_000:
        panel.player.step()
    live.settle()
    status = page.locator(f"#{STATUS_ID}")
    wait_until(lambda: "t = 7.0 s of 16 s" in status.inner_text(), what="t = 7.0 s shown")
    assert phrase_lines(page, f"#{STATUS_ID}", "t = 7.0 s of 16 s") == 1


# How many lines the layout spreads ``phrase`` over (0: not found) inside ``sel``.
PHRASE_LINES_JS = """
([sel, phrase]) => {
  const root = document.querySelector(sel);
  const walker = document.createTreeWalker(root, NodeFilter.SHOW_TEXT);
  for (let node = walker.nextNode(); node; node = walker.nextNode()) {
    const at = node.data.indexOf(phrase);
    if (at < 0) continue;
    const range = document.createRange();
    range.setStart(node, at);
    range.setEnd(node, at + phrase.length);
    return new Set([...range.getClientRects()].filter(r => r.width > 0)
                                              .map(r => Math.round(r.top))).size;
  }
  return 0;
}
"""


def phrase_lines(page: Any, selector: str, phrase: str) -> int:
    return int(page.evaluate(PHRASE_LINES_JS, [selector, phrase]))


def test_reported_codes_list_starts_on_the_newest_code(live: LiveDashboard,
                                                       page: Any) -> None:
    """The Codes tab's Reported list opened on its placeholder row "(pick a reported
    code)"; it now starts on the newest code, decoded, and every entry fits the box."""
    open_dashboard(page, live)
    live.advance(4.0)
    live.command("fastcat/2", "unplug")  # seed 000 §7.7: emergency, AL status code, alarm
    live.advance(1.0)
    page.get_by_role("tab", name="Codes", exact=True).click()
    box = page.get_by_role("combobox", name="Reported")
    wait_until(lambda: "MISSING_NODE_ANSWER" in box.input_value()
               or "8204" in box.input_value() or "FF00" in box.input_value(),
               what="the newest reported code in the box")
    box.click()
    rows = [str(t) for t in page.get_by_role("option").all_inner_texts()]
    assert rows and not rows[0].startswith("("), rows
    assert cut_options(page, "Reported", rows) == []
    result = page.locator("#fr-decoded")
    wait_until(lambda: "MISSING_NODE_ANSWER" in result.inner_text(),
               what="the newest code decoded")


def test_every_scenario_shows_whole_in_the_picker(live: LiveDashboard, page: Any) -> None:
    """The closed Scenario box read "CANopen drive: motor overtemperatu": a long name has a
    short ``label`` in its file ([scenario] label, docs/scenarios.md), the whole name is the
    box's hint and the status block's "Picked:" line. Every option fits with a tenth to spare
    (a font a little wider than Chromium's here still shows it whole)."""
    open_dashboard(page, live)
    page.get_by_role("tab", name="Scenario", exact=True).click()
    options = list(live.dashboard.scenario_player._pick.options)
    assert len(options) > 10  # every shipped scenario, and "(choose a scenario)"
    wait_until(lambda: page.evaluate(FIT_JS, ["Scenario", options]) is not None,
               what="the Scenario box")
    assert cut_options(page, "Scenario", options, 0.9) == []
