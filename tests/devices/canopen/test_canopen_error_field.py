"""The CANopen panel's 0x1003 history names the alarm in bits 16-31 of the entry (docs/canopen.md,
seed 004 ch. 4 "Emergency Message"): 0x00108611 is alarm 16, not "10"."""

from __future__ import annotations

from canopen_bench import make_bench

from app.ui.drive.canopen_panel import status_rows


def test_canopen_panel_names_the_alarm_in_the_history() -> None:
    bench = make_bench()
    bench.drive.apply("inject_alarm", {"code": "16"})
    bench.run(5)
    rows = dict(status_rows(bench.node.snapshot(), bench.drive.snapshot()))
    assert "0x1003: 0x00108611 = alarm 16 FOLLOWING_ERROR, code 0x8611" in rows["Error register"]
