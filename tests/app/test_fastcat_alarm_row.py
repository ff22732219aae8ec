"""The FastCAT State tab's Alarm row says which of seed 000's tables the alarm is from.

§7.5 "Codici d'allarme relativi al coupler" and §7.6 "Codici d'allarme relativi ai moduli"
number their codes independently (0x04 is MISSING_NODE_ANSWER in one, ALARM_IO_FAULT in the
other). Before, the row printed the model's table key as it is: "0x04 MISSING_NODE_ANSWER
coupler, module 2", and for an AX2 zero-cycle alarm "0x14 ENC1_ZERO_CYCLE module, module 7"
(ax2_zero_mark_missing's picture), which a trainee read as a slip.
"""

from __future__ import annotations

import re

import pytest
from test_title_clock import nowrap_classes

from app.ui.panels.state import alarm_text


def plain(html: str) -> str:
    return " ".join(re.sub(r"<[^>]+>", " ", html).split())


@pytest.mark.parametrize(("table", "code", "name", "module", "said"), [
    ("coupler", 0x04, "MISSING_NODE_ANSWER", 2,
     "0x04 MISSING_NODE_ANSWER coupler alarm (§7.5), module 2"),
    ("module", 0x14, "ENC1_ZERO_CYCLE", 7,
     "0x14 ENC1_ZERO_CYCLE module alarm (§7.6), module 7"),
    ("coupler", 0x13, "LINK_LOSS", 0, "0x13 LINK_LOSS coupler alarm (§7.5) "),
])
def test_the_alarm_row_names_the_seed_table(table: str, code: int, name: str, module: int,
                                            said: str) -> None:
    text = plain(alarm_text({"table": table, "code": code, "name": name, "module": module,
                             "description": "d", "resettable": True, "cause_present": True}))
    assert text.startswith(said)
    assert "module, module" not in text and "coupler, module" not in text


def test_the_table_words_wrap_whole() -> None:
    """In the 400 px panel "coupler" fitted after the badge to the last pixel, its "r" under
    the panel's scrollbar, and "alarm (§7.5), module 2" went on the next line (in_alarm at
    1280 x 720): the words are one unit, on the badge's line or under it."""
    html = alarm_text({"table": "coupler", "code": 4, "name": "MISSING_NODE_ANSWER",
                       "module": 2, "description": "d", "resettable": True,
                       "cause_present": True})
    spans = re.findall(r'<span class="([^"]*)">([^<]*)</span>', html)
    assert any(set(classes.split()) & nowrap_classes()
               and text == "coupler alarm (§7.5), module 2" for classes, text in spans), html
