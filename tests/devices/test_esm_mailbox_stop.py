"""The ESM stops the slave's mailbox on every move to INIT from another state (ETG.1000.6:
the mailbox runs from PREOP only; Beckhoff's slave stack calls MBX_StopMailboxHandler on
PREOP / SAFEOP / OP -> INIT, which frees the send queue): ``Esm.stop_mailbox``."""

from __future__ import annotations

from devices.coe.esm import ErrorKind, Esm
from devices.ethercat import AlState


def esm_with_counter() -> tuple[Esm, list[int]]:
    stops: list[int] = []
    esm = Esm(lambda _event: None, "slave", stop_mailbox=lambda: stops.append(1))
    return esm, stops


def test_a_requested_init_stops_the_mailbox() -> None:
    esm, stops = esm_with_counter()
    esm.accept(AlState.PREOP, 1)
    esm.accept(AlState.SAFEOP, 2)
    assert stops == []
    esm.accept(AlState.INIT, 3)
    assert stops == [1]


def test_a_restart_or_a_fall_to_init_stops_it_too() -> None:
    esm, stops = esm_with_counter()
    esm.accept(AlState.PREOP, 1)
    esm.reset(2)  # power loss, restart
    assert stops == [1]
    esm.accept(AlState.PREOP, 3)
    esm.fall_to(AlState.INIT, ErrorKind.LOCAL, 0x0001, 4)
    assert stops == [1, 1]


def test_staying_in_init_stops_nothing() -> None:
    """Already in INIT (power-up, a repeated INIT request) there is no mailbox to stop."""
    esm, stops = esm_with_counter()
    esm.reset(1)
    esm.accept(AlState.INIT, 2)
    esm.accept(AlState.PREOP, 3)
    esm.fall_to(AlState.PREOP, ErrorKind.LOCAL, 0x0001, 4)
    assert stops == []
