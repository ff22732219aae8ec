"""Table cells wrap between words, never inside one, at the browser tests' 1280 x 720.

The UI audit found the master's slave table showing "powe" / "r off" in the Link column,
"(SelemaDriveECAT" / ")" in the name column and "10/2/1/1" / "3" in the counters, and the
CANopen frame log's time column breaking "10.250" after five characters. A word broken across
two lines has two client rectangles (a Range over its characters): the test looks at every
word of every cell of those tables as Chromium lays them out.
"""

from __future__ import annotations

from typing import Any

import pytest
from helpers import LiveDashboard, choose, open_dashboard, wait_until

from app.ui.drive import canopen_master as cm

pytestmark = pytest.mark.browser

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
    assert slaves[1]["powered"] is False
    for tab in page.get_by_role("tab", name="Line").all():
        tab.click()
    table = page.locator("#fr-line-slaves")
    wait_until(lambda: "power off" in table.inner_text(), what="the TRS-CAT powered off")
    assert split_words(page, "#fr-line-slaves td") == []


def test_canopen_time_column_keeps_its_numbers_whole(live: LiveDashboard, page: Any) -> None:
    open_dashboard(page, live)
    live.advance(BOOT_S)
    node_id = "drive_co-can"
    node = live.rig.devices[node_id]
    heartbeat = cm.sdo_download(int(node.node_id), *cm.HEARTBEAT, 500, 2)
    live.runtime.submit(lambda: node.receive(heartbeat.can_id, heartbeat.data)).result(10)
    live.advance(3.0)  # past 10 s: times of six characters ("10.250")
    page.get_by_role("tab", name="Servo drive").click()
    choose(page, "Servo drive", "drive_co")
    page.get_by_role("tab", name="CANopen").click()
    frames = page.locator("#fr-frames")
    wait_until(lambda: "10." in frames.inner_text(), what="frames after 10 s")
    assert split_words(page, "#fr-frames td") == []


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
    # the drive's), and the longest id of static/rigs/, ethercat_line's "drive_ecat", as a
    # caption's device (the log keeps captions from any device).
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
