"""Explicit Device ID (seed 002 §2.1.7 Tab. 5, l. 253; §2.1 l. 173 "Hot Connect") as a master
reads it: ETG.1000.6 AL control bit 5 "ID request" -> AL status bit 5 "ID loaded" and the ID
in the AL status code (0x0134), until an AL control without the bit (ETG.1020 "Requesting ID
mechanism"); the ID in force is the one read at the last start (docs/cpx-e-ec.md choice 35)."""

from __future__ import annotations

from cpx_bench import Bench

from devices.cpx.esm import AL_STATUS_ID_LOADED
from devices.ethercat import AlState


def wire(bench: Bench) -> tuple[int, int]:
    """0x0130 / 0x0134 as the wire shows them (the face's al_status)."""
    return bench.cpx.al_status_on_wire()


def al_control(bench: Bench, state: AlState, id_request: bool = False) -> None:
    """One AL control write as the wire forwards it: the state and bit 5."""
    bench.cpx.request_state(state)
    bench.cpx.request_id(id_request)


def _preop(bench: Bench) -> Bench:
    bench.cpx.request_state(AlState.PREOP)
    assert bench.cpx.al_state is AlState.PREOP
    return bench


def test_id_request_answers_the_rotary_value_in_the_al_status_code() -> None:
    bench = _preop(Bench(master=False, rotary_switch=0x123))
    assert wire(bench) == (0x02, 0x0000)
    al_control(bench, AlState.PREOP, True)
    assert wire(bench) == (0x02 | AL_STATUS_ID_LOADED, 0x0123) == (0x22, 0x0123)
    bench.run(0.05)  # stays while the master keeps the bit set
    assert wire(bench) == (0x22, 0x0123)
    al_control(bench, AlState.PREOP)  # the next AL control without the bit
    assert wire(bench) == (0x02, 0x0000)


def test_switch_at_zero_answers_id_loaded_with_zero() -> None:
    """Tab. 5: 0 = no Explicit Device ID (the master assigns the address): the request is
    answered, with the ID 0 ETG.1020 reads as "no ID set"."""
    bench = _preop(Bench(master=False, rotary_switch=0))
    al_control(bench, AlState.PREOP, True)
    assert wire(bench) == (0x22, 0x0000)


def test_the_id_in_force_is_the_one_read_at_the_last_start() -> None:
    """§2.1.7 / Tab. 5: a switch moved since the start is not the ID until a restart."""
    bench = _preop(Bench(master=False, rotary_switch=0x0A5))
    bench.apply("set_rotary", value=0xFFF)
    al_control(bench, AlState.PREOP, True)
    assert wire(bench)[1] == 0x0A5
    assert bench.cpx.station_alias == 0x0A5
    bench.apply("restart")
    assert bench.cpx.station_alias == 0xFFF
    assert wire(bench) == (0x01, 0)  # the restart forgot the request (RAM)
    al_control(bench, AlState.INIT, True)
    assert wire(bench) == (0x21, 0x0FFF)


def test_an_error_code_is_not_overwritten_by_the_id() -> None:
    """ETG.1020 / SSC: with the error flag up the AL status code keeps the error."""
    bench = Bench(master=False, rotary_switch=0x123)
    al_control(bench, AlState.SAFEOP, True)  # INIT -> SAFEOP: 0x0011
    assert wire(bench) == (0x11, 0x0011)
    al_control(bench, AlState.INIT, True)  # acknowledged: ID shown
    assert wire(bench) == (0x21, 0x0123)


def test_no_application_no_id() -> None:
    """Application controller failure (Tab. 12 red on): AL control is not answered."""
    bench = _preop(Bench(master=False, rotary_switch=0x123))
    bench.apply("inject_fault", fault="ac_failure")
    al_control(bench, AlState.PREOP, True)
    assert not wire(bench)[0] & AL_STATUS_ID_LOADED
    assert wire(bench)[1] != 0x0123


def test_the_model_al_status_stays_the_esm_s_for_the_built_in_master() -> None:
    """The ID is what the wire shows at 0x0130 / 0x0134, not an ESM error: the model's
    al_status / al_status_code (which the built-in master's diagnostic, its state change
    events and its log read) stay the ESM's. Before, ID 0x11 was named "Invalid requested
    state change" in the master's slave diagnostic."""
    bench = Bench(rotary_switch=0x011)
    assert bench.master is not None
    bench.master.set_external(True)
    bench.cpx.request_state(AlState.PREOP)
    al_control(bench, AlState.PREOP, True)
    bench.run(0.02)
    assert wire(bench) == (0x22, 0x0011)
    assert (bench.cpx.al_status, bench.cpx.al_status_code) == (0x02, 0x0000)
    slave = bench.master.snapshot()["slaves"][0]
    assert (slave["al_status"], slave["al_status_code"]) == (0x02, 0)
    assert "Invalid requested state change" not in slave["al_status_text"]
    bench.events.clear()
    bench.cpx.request_state(AlState.SAFEOP)
    bench.run(0.05)
    changes = [e for e in bench.events if type(e).__name__ == "SlaveStateChange"]
    assert changes and all(getattr(e, "code", 0) == 0 for e in changes)


def test_switch_at_zero_keeps_the_stored_address() -> None:
    """Tab. 5 l. 253: «0 = сохраненный адрес EtherCAT, "Explicit Device ID" не задан»: at 0
    the model gives no station alias (None: the wire keeps SII word 4 as stored and loads
    0x0012 from it at each start, docs/cpx-e-ec.md choice 35); an ID request answers 0."""
    bench = _preop(Bench(master=False, rotary_switch=0x123))
    assert bench.cpx.station_alias == 0x123
    ups = bench.cpx.power_ups
    bench.apply("set_rotary", value=0)
    bench.apply("restart")
    assert bench.cpx.station_alias is None and bench.cpx.explicit_device_id == 0
    assert bench.cpx.power_ups == ups + 1  # a start: the ESC reloads 0x0012 from its SII
    bench.cpx.request_state(AlState.PREOP)
    al_control(bench, AlState.PREOP, True)
    assert wire(bench) == (0x22, 0x0000)
