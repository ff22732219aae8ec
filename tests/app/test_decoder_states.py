"""State names in the Codes tab: the EtherCAT states and the master's distributed-clock phases
of seed 003, the CANopen NMT states and their heartbeat / guarding byte of seed 004 ch. 4.

A trainee reads them in the State tab, the master's log ("distributed clocks: COMPENSATING ->
NOT_SYNCHRONIZED") and the CAN monitor ("node 2: Pre-operational (toggle 1)") and pastes them
here; the tab answered "no code and no alarm name the tables know"."""

from __future__ import annotations

import pytest

from app.decoder import CANOPEN, ETHERCAT, MASTER, DecodeError, decode
from devices.canopen.nmt import STATE_CODE, STATE_TEXT, NmtState
from devices.ethercat import AL_STATE_TEXT, AlState
from devices.master.dc import DC_STATE_TEXT, DcState


def _one(query: str, family: str) -> str:
    found = [m for m in decode(query) if m.family == family]
    assert len(found) == 1, (query, decode(query))
    return found[0].title + " | " + found[0].text


@pytest.mark.parametrize(("query", "state", "seed_words"), [
    ("INIT", AlState.INIT, "nitialization phase"),
    ("PREOP", AlState.PREOP, "no data-exchange"),
    ("Pre-Op", AlState.PREOP, "no data-exchange"),
    ("SAFEOP", AlState.SAFEOP, "only input data"),
    ("SAFE_OP", AlState.SAFEOP, "only input data"),
    ("OP", AlState.OP, "full data-exchange"),
])
def test_an_ethercat_state_by_name(query: str, state: AlState, seed_words: str) -> None:
    """Seed 003: "INIT: initialization phase", "PREOP: pre operational, no data-exchange ...",
    "SAFEOP: ... only input data ...", "OP: operational, full data-exchange can happen"."""
    text = _one(query, ETHERCAT)
    assert AL_STATE_TEXT[state].lower() in text.lower() and seed_words in text
    assert f"0x{int(state):02X}" in text  # the AL status register's encoding


@pytest.mark.parametrize(("query", "state", "seed_words"), [
    ("IDLE", DcState.IDLE, "independent"),
    ("SYNCHRONIZING", DcState.SYNCHRONIZING, "preliminary measurements"),
    ("WAITING_START_TIME", DcState.WAITING_START_TIME, "START_TIME"),
    ("COMPENSATING", DcState.COMPENSATING, "tracking"),
    ("not synchronized", DcState.NOT_SYNCHRONIZED, "SAFE_OP"),
])
def test_a_dc_phase_of_the_master(query: str, state: DcState, seed_words: str) -> None:
    text = _one(query, MASTER)
    assert DC_STATE_TEXT[state].lower() in text.lower() and seed_words in text


def test_the_masters_dc_log_line_reads_both_phases() -> None:
    line = ("distributed clocks: COMPENSATING -> NOT_SYNCHRONIZED (deviation 1800 ns, sync "
            "window 1000 ns).")
    found = [m for m in decode(line) if m.family == MASTER]
    assert [m.title for m in found] == ["DC phase COMPENSATING (from)",
                                        "DC phase NOT_SYNCHRONIZED (to)"], found


@pytest.mark.parametrize("line", [
    "distributed clocks: COMPENSATING -> NOT-SYNCHRONIZED (deviation 1800 ns).",
    "distributed clocks: compensating -> not synchronized.",
])
def test_a_dc_line_with_the_phases_spelt_otherwise(line: str) -> None:
    found = [m.title for m in decode(line) if m.family == MASTER]
    assert found == ["DC phase COMPENSATING (from)", "DC phase NOT_SYNCHRONIZED (to)"], found


@pytest.mark.parametrize(("line", "said"), [
    ("distributed clocks: FOO -> BAR", "'FOO' (from) and 'BAR' (to) are no DC phases"),
    ("distributed clocks: FOO -> COMPENSATING (sync window 1000 ns).",
     "'FOO' (from) is no DC phase"),
    ("distributed clocks: IDLE -> BAR-BAZ", "'BAR-BAZ' (to) is no DC phase"),
])
def test_a_dc_line_with_a_word_no_phase_names_it(line: str, said: str) -> None:
    """Before: "no code and no alarm name the tables know", the line's words unnamed."""
    with pytest.raises(DecodeError) as caught:
        decode(line)
    message = str(caught.value)
    assert said in message, message
    assert all(s.value in message for s in DcState), message  # the phases seed 003 names


def test_a_dc_line_without_its_arrow() -> None:
    with pytest.raises(DecodeError, match="FROM -> TO"):
        decode("distributed clocks: COMPENSATING")


@pytest.mark.parametrize(("query", "state"), [
    ("Stopped", NmtState.STOPPED), ("Arrestato", NmtState.STOPPED),
    ("Pre-operational", NmtState.PRE_OPERATIONAL), ("Operational", NmtState.OPERATIONAL),
    ("Initialisation", NmtState.INITIALISATION),
])
def test_an_nmt_state_by_name(query: str, state: NmtState) -> None:
    text = _one(query, CANOPEN)
    assert STATE_TEXT[state].lower() in text.lower() and f"0x{STATE_CODE[state]:02X}" in text


@pytest.mark.parametrize(("query", "state", "toggle"), [
    ("heartbeat 7F", NmtState.PRE_OPERATIONAL, None),
    ("heartbeat 0x05", NmtState.OPERATIONAL, None),
    ("heartbeat 04", NmtState.STOPPED, None),
    ("heartbeat 00", NmtState.INITIALISATION, None),  # the boot-up message
    ("guarding 85", NmtState.OPERATIONAL, 1),
    ("node guarding 0x7F", NmtState.PRE_OPERATIONAL, 0),
    ("node 2: Pre-operational (toggle 1)", NmtState.PRE_OPERATIONAL, 1),
    ("node 2: boot-up", NmtState.INITIALISATION, None),
])
def test_the_heartbeat_byte(query: str, state: NmtState, toggle: int | None) -> None:
    """Seed 004 ch. 4: "0x00 - Bootup; 0x04 - Arrestato; 0x05 - Operational; 0x7F -
    Pre-Operational"; the top bit toggles with node guarding and is 0 with heartbeat."""
    text = _one(query, CANOPEN)
    assert STATE_TEXT[state].lower() in text.lower(), text
    if toggle is not None:
        assert f"toggle bit {toggle}" in text, text


@pytest.mark.parametrize("query", ["heartbeat 85", "heartbeat 0x33", "guarding 33"])
def test_a_heartbeat_byte_the_seed_does_not_list(query: str) -> None:
    """A heartbeat's top bit is 0 (ch. 4), and 0x33 is no state: one clear message."""
    with pytest.raises(DecodeError, match="0x00, 0x04, 0x05, 0x7F"):
        decode(query)


def test_the_trace_state_change_reads_its_states() -> None:
    """Seed 000 §7.4: "ECAT_EVENT SlaveStateChange slave = 11 from 8 to 2", the states as
    their AL status values (8 OP, 2 PREOP). The tab refused the line ("carries no code");
    it now reads both states and still says where the AL status code is."""
    line = "380808 - 00000001 - ECAT_EVENT SlaveStateChange slave = 11 from 8 to 2"
    found = decode(line)
    assert [m.title for m in found] == ["EtherCAT state OP (from, slave 11)",
                                        "EtherCAT state PREOP (to, slave 11)"], found
    assert "EcatManagerSlaveStateCallback" in found[1].text


def test_a_trace_state_change_to_no_state_is_one_message() -> None:
    with pytest.raises(DecodeError, match="from 8 to 7"):
        decode("ECAT_EVENT SlaveStateChange slave = 11 from 8 to 7")
