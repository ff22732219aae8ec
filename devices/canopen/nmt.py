"""The NMT slave state machine as data (seed 004 ch. 4 "Stati e Cambiamento di stato").

Power-on -> Initialisation (Reset-Application -> Reset-Communication -> Initializing) ->
boot-up message -> Pre-operational <-> Operational <-> Stopped. Commands come on CAN-ID 0:
two bytes, the command and the node-ID (0 = every node). Which services a state allows is a
table too: Pre-operational has SDO, EMCY, SYNC and NMT but no PDO; Operational has PDOs as
well; Stopped answers only NMT and node guarding / heartbeat ("non può trasmettere o
ricevere qualsiasi altro messaggio che il node guarding o l'heartbeat").
"""

from __future__ import annotations

import enum

NMT_COB_ID = 0x000
HEARTBEAT_BASE = 0x700  # "1792 + node-ID" (ch. 4); printed "701 + NodeID" in the drive notes


class NmtState(enum.Enum):
    INITIALISATION = "Initialisation"
    PRE_OPERATIONAL = "Pre-operational"
    OPERATIONAL = "Operational"
    STOPPED = "Stopped"

    @property
    def label(self) -> str:
        return self.value

    @property
    def code(self) -> int:
        """The state byte of heartbeat and guarding answers (ch. 4)."""
        return STATE_CODE[self]


# "0x00 - Bootup; 0x04 - Arrestato; 0x05 - Operational; 0x7F - Pre-Operational"
BOOT_UP_CODE = 0x00
STATE_CODE: dict[NmtState, int] = {
    NmtState.INITIALISATION: BOOT_UP_CODE,
    NmtState.STOPPED: 0x04,
    NmtState.OPERATIONAL: 0x05,
    NmtState.PRE_OPERATIONAL: 0x7F,
}


# Each state in seed 004 ch. 4's words ("Stati e Cambiamento di stato"); the Codes tab reads
# them with the state byte above (app/decoder_states.py).
STATE_TEXT: dict[NmtState, str] = {
    NmtState.INITIALISATION: "after power-on or a reset (Reset-Application, Reset-Communication, "
                             "Initializing); the node then sends its boot-up message (0x00) "
                             "and goes to Pre-operational",
    NmtState.PRE_OPERATIONAL: "the configuration state: SDO, emergency, SYNC / time and NMT "
                              "messages, no process data (PDO); Start-Remote-node makes it "
                              "Operational",
    NmtState.OPERATIONAL: "process data (PDO) are exchanged as well",
    NmtState.STOPPED: "the node sends and receives nothing but NMT and node guarding / "
                      "heartbeat",
}
GUARDING_TOGGLE = 0x80  # the top bit of the state byte: toggles with node guarding, 0 heartbeat


class NmtCommand(enum.IntEnum):
    START = 0x01  # Start remote node
    STOP = 0x02  # Stop remote node
    ENTER_PRE_OPERATIONAL = 0x80
    RESET_NODE = 0x81  # Reset-Application, then Reset-Communication
    RESET_COMMUNICATION = 0x82


# What a reset does, in seed 004 ch. 4's words ("Reset-Application", "Reset-Communication");
# the other commands' effect is the state they lead to (TRANSITIONS, STATE_TEXT). The Codes
# tab reads them (app/decoder_nmt.py).
RESET_TEXT: dict[NmtCommand, str] = {
    NmtCommand.RESET_NODE: "Reset-Application: the manufacturer-specific and device-profile "
                           "parameters back to their power-on values (the last saved), then "
                           "Reset-Communication and Initializing: the node sends its boot-up "
                           "message (0x00) and goes to Pre-operational",
    NmtCommand.RESET_COMMUNICATION: "Reset-Communication: the communication profile's "
                                    "parameters back to their power-on values, then "
                                    "Initializing: the node sends its boot-up message (0x00) "
                                    "and goes to Pre-operational",
}
NODE_ID_ALL = 0  # byte 1 of the command: "il nodo virtuale-ID 0" addresses every node
MAX_NODE_ID = 127


class Service(enum.Enum):
    SDO = "SDO"
    PDO = "PDO"
    SYNC = "SYNC"
    EMCY = "EMCY"
    GUARDING = "node guarding / heartbeat"


S = NmtState
C = NmtCommand
# (state, command) -> new state. Reset commands go through Initialisation in every state.
TRANSITIONS: dict[tuple[NmtState, NmtCommand], NmtState] = {
    (S.PRE_OPERATIONAL, C.START): S.OPERATIONAL,
    (S.PRE_OPERATIONAL, C.STOP): S.STOPPED,
    (S.PRE_OPERATIONAL, C.ENTER_PRE_OPERATIONAL): S.PRE_OPERATIONAL,
    (S.OPERATIONAL, C.START): S.OPERATIONAL,
    (S.OPERATIONAL, C.STOP): S.STOPPED,
    (S.OPERATIONAL, C.ENTER_PRE_OPERATIONAL): S.PRE_OPERATIONAL,
    (S.STOPPED, C.START): S.OPERATIONAL,
    (S.STOPPED, C.STOP): S.STOPPED,
    (S.STOPPED, C.ENTER_PRE_OPERATIONAL): S.PRE_OPERATIONAL,
    **{(s, c): S.INITIALISATION for s in (S.PRE_OPERATIONAL, S.OPERATIONAL, S.STOPPED)
       for c in (C.RESET_NODE, C.RESET_COMMUNICATION)},
}

ALLOWED: dict[NmtState, frozenset[Service]] = {
    S.INITIALISATION: frozenset(),
    S.PRE_OPERATIONAL: frozenset({Service.SDO, Service.SYNC, Service.EMCY, Service.GUARDING}),
    S.OPERATIONAL: frozenset(Service),
    S.STOPPED: frozenset({Service.GUARDING}),
}
del S, C


def next_state(state: NmtState, command: NmtCommand) -> NmtState | None:
    """The state a command leads to, or None where it has no effect (during Initialisation)."""
    return TRANSITIONS.get((state, command))


def allows(state: NmtState, service: Service) -> bool:
    return service in ALLOWED[state]


def parse_command(data: bytes, node_id: int) -> NmtCommand | None:
    """The command of an NMT frame addressed to ``node_id`` (or to all), else None.

    Exactly two bytes; an unknown command byte is ignored, as DS 301 wants.
    """
    if len(data) != 2 or data[1] not in (0, node_id):
        return None
    try:
        return NmtCommand(data[0])
    except ValueError:
        return None
