"""The menus and text boxes of the dashboard's small CANopen master.

Labels the panel offers and the objects its buttons write; the codes come from the devices'
tables (NMT command specifiers: devices/canopen/nmt.py, CiA 402 controlwords:
devices/servo/ds402.py) and the frames from devices/canopen/master_frames.py.
"""

from __future__ import annotations

from devices.canopen.nmt import NmtCommand
from devices.servo.ds402 import COMMAND_WORDS, Command

# The seed's table of NMT services, each label with its command specifier.
NMT_COMMANDS: dict[str, int] = {
    f"{label} (0x{command:02X})": int(command) for label, command in (
        ("Start", NmtCommand.START),
        ("Stop", NmtCommand.STOP),
        ("Enter pre-operational", NmtCommand.ENTER_PRE_OPERATIONAL),
        ("Reset node", NmtCommand.RESET_NODE),
        ("Reset communication", NmtCommand.RESET_COMMUNICATION),
    )
}

# Button labels in the panel's order (ch. 4 worked sequence first: 0x06, 0x07, 0x0F).
CONTROLWORD_COMMANDS: dict[str, int] = {
    label: COMMAND_WORDS[command] for label, command in (
        ("Shutdown", Command.SHUTDOWN),
        ("Switch on", Command.SWITCH_ON),
        ("Enable op.", Command.ENABLE_OPERATION),
        ("Disable", Command.DISABLE_VOLTAGE),
        ("Quick stop", Command.QUICK_STOP),
        ("Fault reset", Command.FAULT_RESET),
    )
}
CONTROLWORD = (0x6040, 0)
HEARTBEAT = (0x1017, 0)


def parse_object(text: str) -> tuple[int, int]:
    """``0x6041:0`` / ``6041`` / ``0x1018:1`` -> (index, sub); hex index, decimal sub."""
    head, _, sub = text.strip().partition(":")
    index = int(head, 16)
    sub_no = int(sub, 0) if sub.strip() else 0
    if not (0 <= index <= 0xFFFF and 0 <= sub_no <= 0xFF):
        raise ValueError(f"{text!r} is not an object address (0x0000:0 .. 0xFFFF:255)")
    return index, sub_no


def parse_int(text: str) -> int:
    """A decimal, 0x hex or negative value."""
    return int(text.strip(), 0)
