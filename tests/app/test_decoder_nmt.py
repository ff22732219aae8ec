"""NMT commands in the Codes tab (seed 004 ch. 4: CAN-ID 0, two bytes, the command then the
node-ID, 0 = every node; DS 301's command bytes 01 start, 02 stop, 80 pre-operational, 81 reset
node, 82 reset communication), as typed and as the CANopen tab's frame log shows the frame.
Before, "NMT 01 02" read "give hex bytes" and a frame log row "no code and no alarm name".
"""

from __future__ import annotations

import pytest

from app.decoder import CANOPEN, DecodeError, decode
from devices.canopen.decode import Context, describe
from devices.canopen.nmt import NmtCommand


def _frame_row(command: int, node: int) -> str:
    """A frame log row as a browser copies it: time, dir, COB-ID, type, data, meaning."""
    kind, text = describe(0x000, bytes((command, node)), False, Context())
    return f"0.500\trx\t0x000\t{kind}\t{command:02X} {node:02X}\t{text}"


@pytest.mark.parametrize(("command", "words"), [
    (0x01, ["Start remote node", "Operational", "process data"]),
    (0x02, ["Stop remote node", "Stopped"]),
    (0x80, ["Enter pre-operational", "Pre-operational"]),
    (0x81, ["Reset node", "Reset-Application", "boot-up"]),
    (0x82, ["Reset communication", "Reset-Communication", "boot-up"]),
])
def test_each_command_byte(command: int, words: list[str]) -> None:
    for query in (f"NMT {command:02X}", f"nmt command 0x{command:02X}", _frame_row(command, 2)):
        found = [m for m in decode(query) if m.family == CANOPEN]
        assert len(found) == 1, (query, decode(query))
        m = found[0]
        assert m.title.startswith(f"NMT command 0x{command:02X} {words[0]}"), m.title
        assert all(w in m.text for w in words[1:]), m.text
        assert "seed 004 ch. 4" in m.source


def test_the_frame_names_its_node() -> None:
    (m,) = decode(_frame_row(0x01, 2))
    assert m.title == "NMT command 0x01 Start remote node -> node 2", m.title
    (m,) = decode(_frame_row(0x82, 0))
    assert m.title == "NMT command 0x82 Reset communication -> all nodes", m.title


@pytest.mark.parametrize("query", ["Start remote node -> node 2", "start remote node",
                                   "Reset communication -> all nodes"])
def test_the_frame_logs_meaning_alone(query: str) -> None:
    (m,) = decode(query)
    assert m.title.startswith("NMT command 0x"), m.title


def test_every_command_of_the_model_decodes() -> None:
    for command in NmtCommand:
        assert decode(f"NMT {int(command):02X} 00")


@pytest.mark.parametrize(("query", "hint"), [
    ("NMT 03", "01 Start remote node, 02 Stop remote node, 80"),
    ("NMT 7F", "state byte of Pre-operational"),  # a heartbeat's byte, no command
    ("NMT 01 02 03", "two bytes"),
    ("NMT 01 80", "node-ID"),
    ("0.500\trx\t0x000\tNMT\t01 02 03\tmalformed (3 bytes)", "two bytes"),
])
def test_a_bad_nmt_frame_is_one_message(query: str, hint: str) -> None:
    with pytest.raises(DecodeError, match=hint):
        decode(query)
