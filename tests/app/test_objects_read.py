"""The Objects tab's Read: the value read goes into the Value box (so Write starts from it)
and the notice shows it as the table and the State panel do, unsigned integers in hex with
the width of their type (0x5400 UDINT = 0x04000003, seed 000 §6.19), then in decimal;
byte strings (0x10F3 messages) in hex, byte 0 first."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from objects_tab_fakes import FakeRuntime, FakeServer

from app.ui.panels import object_dictionary
from app.ui.panels.object_dictionary import ObjectDictionaryPanel, OdRow


class _Sender:
    """Answers read_object at once with ``value``."""

    def __init__(self, value: Any) -> None:
        self.value = value
        self.sent: list[tuple[str, str, dict[str, Any]]] = []

    def send(self, client: Any, target: str, action: str, args: dict[str, Any], *,
             done: Callable[[Any], Any] | None = None, confirm: bool = False) -> None:
        self.sent.append((target, action, args))
        if done is not None:
            done(self.value)


ROWS = [OdRow(0x5400, 0, "Alarm status", "UDINT", "RO", 0x04000003),
        OdRow(0x2104, 0, "Module 1 settings", "UINT", "RW", 0x0007),
        OdRow(0x5000, 1, "Box name", "STRING", "RW", "Box 1"),
        OdRow(0x10F3, 6, "Diagnosis message 1", "ARRAY OF BYTE", "RO", bytes([0x00, 0xE8, 0x01]))]


@pytest.mark.parametrize(("address", "value", "box", "shown"), [
    ("0x5400", 0x04000003, "0x04000003", "0x04000003 (67108867)"),
    ("0x2104:0", 7, "0x0007", "0x0007 (7)"),
    ("0x5000:1", "Box 1", "Box 1", '"Box 1"'),
    ("0x10F3:6", bytes([0x00, 0xE8, 0x01]), "00 E8 01", "00 E8 01"),
])
def test_read_fills_the_value_box_and_shows_hex(
        monkeypatch: pytest.MonkeyPatch, address: str, value: Any, box: str,
        shown: str) -> None:
    notes: list[tuple[str, str]] = []
    monkeypatch.setattr(object_dictionary, "notify",
                        lambda client, title, body, error=False: notes.append((title, body)))
    sender = _Sender(value)
    server = FakeServer()
    panel = ObjectDictionaryPanel(server, FakeRuntime(ROWS), sender,  # type: ignore[arg-type]
                                  "fastcat")
    panel.request(None)  # the table's rows: the types come from them
    page = server.connect(1)
    server.message(1, panel._address, address)
    server.message(1, panel._value, "1")  # what was typed before
    panel._access(page, "Read")  # type: ignore[arg-type]
    assert sender.sent[0][1] == "read_object"
    assert page.sent(panel._value._impl.uuid, "value") == [box]  # the reading page's box
    [(title, body)] = notes
    assert title.endswith("read") and body == f"value = {shown}"


class _Rig:
    """One device whose dictionary holds 0x1003:1 with the drive's words for it."""

    def __init__(self, entry: Any) -> None:
        self.od = self
        self._entry = entry

    def device(self, device_id: str) -> Any:
        return self

    def entry(self, index: int, sub: int) -> Any:
        return self._entry


def test_read_of_0x1003_names_the_alarm(monkeypatch: pytest.MonkeyPatch) -> None:
    """0x1003:1 = 0x00108611 is alarm 16 (bits 16-31), code 0x8611: the notice says so, as
    the table does (docs/canopen.md); the Value box keeps the number for a Write."""
    from devices.od import Access, DataType, OdEntry
    from devices.servo.alarms import alarm_table, error_field_text
    notes: list[tuple[str, str]] = []
    monkeypatch.setattr(object_dictionary, "notify",
                        lambda client, title, body, error=False: notes.append((title, body)))
    runtime = FakeRuntime([], "drive_ec")
    runtime.rig = _Rig(OdEntry(  # type: ignore[attr-defined]
        0x1003, 1, "Standard error field", DataType.UNSIGNED32, Access.RO,
        explain=lambda v: error_field_text(v, alarm_table("ethercat"))))
    server = FakeServer()
    panel = ObjectDictionaryPanel(server, runtime, _Sender(0x0010_8611),  # type: ignore[arg-type]
                                  "drive_ec")
    page = server.connect(1)
    server.message(1, panel._address, "0x1003:1")
    panel._access(page, "Read")  # type: ignore[arg-type]
    assert page.sent(panel._value._impl.uuid, "value") == ["0x00108611"]
    assert notes == [("0x1003:1 read",
                      "value = 0x00108611 = alarm 16 FOLLOWING_ERROR, code 0x8611")]
