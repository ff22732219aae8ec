"""The drive's Modbus application layer, request bytes -> outcome (seed 004 ch.2).

Scripted tables per quirk, on a fake drive that isolates the access rules, then the seed's
examples on the real drive model. PDUs are written without node number and CRC (the framer's
business); the seed's ADUs are ``node + PDU + CRC``.
"""

from __future__ import annotations

import random

import pytest
from sim_helpers import FakeDrive

from app.modbus.pdu import Exception02, Reply, Silence, serve_line, serve_pdu
from devices.flash import MemoryFlash
from devices.servo.drive import DriveConfig, ServoDrive

h = bytes.fromhex


@pytest.fixture
def drive() -> FakeDrive:
    d = FakeDrive.default(node_id=5)
    d.registers[0].value = 0x1122
    d.registers[9].value = 0x12345678
    return d


def run(drive: FakeDrive, request: str):
    return serve_pdu(drive, h(request))


# ---- ch.2 "Esempi": the printed requests and replies -----------------------------------------
def test_seed_read_d1_d3(drive: FakeDrive) -> None:
    """ch.2 "Codice 0x03": 05 03 00 01 00 03 -> 05 03 06 00 14 00 32 00 32."""
    assert run(drive, "03 0001 0003") == Reply(h("03 06 0014 0032 0032"))


def test_seed_read_r00_r01_as_four_words(drive: FakeDrive) -> None:
    """ch.2 "Codice 0x03" on registers: 05 03 80 00 00 04, "2 registri a 32 bit = 4 registri a
    16 bit", high part first. The printed reply (byte count 04, two words) cannot carry four
    words: we answer 8 bytes, R00 then R01, each high word first (docs/modbus.md)."""
    drive.registers[1].value = 0x3344
    assert run(drive, "03 8000 0004") == Reply(h("03 08 0000 1122 0000 3344"))


def test_seed_write_d3(drive: FakeDrive) -> None:
    """ch.2 "Codice 0x06": 05 06 00 03 00 0A, reply identical."""
    assert run(drive, "06 0003 000A") == Reply(h("06 0003 000A"))
    assert drive.read_parameter(3) == 10


def test_seed_write_target_position(drive: FakeDrive) -> None:
    """ch.2 "Codice 0x10": 05 10 80 09 00 02 04 00 00 03 E8 -> 05 10 80 09 00 02."""
    assert run(drive, "10 8009 0002 04 0000 03E8") == Reply(h("10 8009 0002"))
    assert drive.read_register(9) == 1000


@pytest.mark.parametrize("request_, reply", [
    ("06 3802 0011", "06 3802 0011"),  # second method, 16 bit: reply identical
    ("10 3802 0002 04 0000 0011", "10 3802 0002"),  # second method, 32 bit
    ("10 3802 0001 02 0011", "10 3802 0001"),
])
def test_seed_save_second_method_answers_at_once(drive: FakeDrive, request_: str,
                                                 reply: str) -> None:
    """ch.2 "Salvataggio su flash": 0x0011 at 0x3802; the drive answers immediately, then
    saves and does not answer for a few seconds."""
    outcome = run(drive, request_)
    assert outcome == Reply(h(reply), after_save=False)
    assert drive.saves == 1 and not drive.responding


def test_seed_save_first_method_answers_at_the_end(drive: FakeDrive) -> None:
    """ch.2 "Primo metodo di salvataggio": mode -50 then control word 0x20; the reply "viene
    inviata al termine dell'operazione"."""
    assert run(drive, "10 8001 0002 04 FFFF FFCE") == Reply(h("10 8001 0002"))
    assert drive.read_register(1) == -50
    assert run(drive, "10 8000 0002 04 0000 0020") == Reply(h("10 8000 0002"), after_save=True)


# ---- quantity 1 vs 2 -------------------------------------------------------------------------
@pytest.mark.parametrize("value, quantity, words", [
    (0x12345678, 1, "5678"),  # quantity 1: the 16 least significant bits
    (0x12345678, 2, "1234 5678"),  # quantity 2: the whole register, high word first
    (-2, 1, "FFFE"),
    (-2, 2, "FFFF FFFE"),
    (-0x8000_0000, 2, "8000 0000"),
    (0x7FFF_FFFF, 2, "7FFF FFFF"),
])
def test_register_read_quantity(drive: FakeDrive, value: int, quantity: int, words: str) -> None:
    """ch.2 "Codice 03": quantity 1 reads the low 16 bits, quantity 2 high word then low."""
    drive.registers[9].value = value
    data = h(words)
    assert run(drive, f"03 8009 {quantity:04X}") == Reply(bytes((3, len(data))) + data)


def test_register_block_spans_k_registers(drive: FakeDrive) -> None:
    """Quantity 2k from 0x8000 + n reads Rn .. Rn+k-1 (the R00/R01 example, generalised)."""
    for n in range(3):
        drive.registers[n].value = -n - 1 if n != 0 else 0x0102
    outcome = run(drive, "03 8000 0006")
    assert outcome == Reply(h("03 0C 0000 0102 FFFF FFFE FFFF FFFD"))


@pytest.mark.parametrize("request_", [
    "03 8000 0003",  # odd quantity > 1 would split a register
    "03 8009 0005",
    "03 8000 007D",  # 125 is odd
])
def test_register_odd_quantity_is_discarded(drive: FakeDrive, request_: str) -> None:
    assert isinstance(run(drive, request_), Silence)


def test_register_block_of_62_is_the_largest(drive: FakeDrive) -> None:
    """125 words at most (ch.2 "Codice 03"), so 62 registers per read."""
    outcome = run(drive, "03 8000 007C")
    assert isinstance(outcome, Reply) and outcome.pdu[1] == 248


# ---- sign extension --------------------------------------------------------------------------
@pytest.mark.parametrize("register, word, stored", [
    (9, 0x000A, 10),
    (9, 0x7FFF, 0x7FFF),
    (9, 0x8000, -0x8000),  # the high 16 bits take the sign of the low 16
    (9, 0xFFFF, -1),
    (9, 0xFFCE, -50),
    (3, 0xFFFF, 0xFFFF_FFFF),  # an unsigned register: 0xFFFF extends to 0xFFFFFFFF
    (3, 0x1234, 0x1234),
])
@pytest.mark.parametrize("fc", ["06", "10"])
def test_16_bit_register_write_sign_extends(drive: FakeDrive, fc: str, register: int,
                                            word: int, stored: int) -> None:
    """ch.2 "Codice 06": a register written as 16 bits gets the value in its low half and the
    sign extension in its high half. FC 16 with quantity 1 writes a register the same way
    (ch.2 "Codici funzione": registers "intesi come se fossero a 16 bit")."""
    address = 0x8000 + register
    request_ = (f"06 {address:04X} {word:04X}" if fc == "06"
                else f"10 {address:04X} 0001 02 {word:04X}")
    outcome = run(drive, request_)
    assert isinstance(outcome, Reply)
    assert outcome.pdu == h(request_)[:5]
    assert drive.read_register(register) == stored


def test_sign_extension_can_put_a_value_out_of_range(drive: FakeDrive) -> None:
    """0x8000 written as 16 bits to the control word (0..0xFFFF) becomes 0xFFFF8000: out of
    range, so discarded and the control word keeps its value."""
    before = drive.state()
    assert isinstance(run(drive, "06 8000 8000"), Silence)
    assert drive.state() == before


# ---- FC 16 limits ----------------------------------------------------------------------------
@pytest.mark.parametrize("request_", [
    "10 8009 0000 00",  # quantity 0
    "10 8009 0003 06 0000 0000 0001",  # quantity 3: "al massimo due registri contigui"
    "10 0001 0004 08 0001 0001 0001 0001",
    "10 8009 0002 02 0000 03E8",  # byte count says 2 for quantity 2
    "10 8009 0002 04 0000 03",  # one byte short
    "10 8009 0002 04 0000 03E8 00",  # one byte too many
    "10 8009 0001 04 0000 03E8",  # byte count 4 for quantity 1
    "10 8009 0002",  # no byte count
    "10 80",
])
def test_fc16_limits_are_discarded(drive: FakeDrive, request_: str) -> None:
    before = drive.state()
    assert isinstance(run(drive, request_), Silence)
    assert drive.state() == before


def test_fc16_two_contiguous_parameters(drive: FakeDrive) -> None:
    """FC 16 quantity 2 on a parameter address writes it and the next one ("scrivere al
    massimo due registri contigui")."""
    assert run(drive, "10 0001 0002 04 0019 001E") == Reply(h("10 0001 0002"))
    assert (drive.read_parameter(1), drive.read_parameter(2)) == (25, 30)


def test_fc16_two_parameters_all_or_nothing(drive: FakeDrive) -> None:
    before = drive.state()
    assert isinstance(run(drive, "10 0001 0002 04 0019 0064"), Silence)  # d2 = 100 > 99
    assert drive.state() == before
    assert run(drive, "10 0016 0002 04 0003 0003") == Exception02(0x10)  # 23 is no parameter
    assert drive.state() == before


def test_fc16_parameter_quantity_1(drive: FakeDrive) -> None:
    assert run(drive, "10 0003 0001 02 000A") == Reply(h("10 0003 0001"))
    assert drive.read_parameter(3) == 10


# ---- exception 02 only, and only for addresses -----------------------------------------------
@pytest.mark.parametrize("request_, fc", [
    ("03 0000 0001", 0x03),  # no parameter 0
    ("03 0017 0001", 0x03),  # 23: a gap between c9 (22) and i1 (35)
    ("03 0001 0017", 0x03),  # d1 .. 23: the block runs into the gap
    ("03 0001 007D", 0x03),
    ("03 8086 0001", 0x03),  # R134 does not exist (R133 = 0x8085 is the last)
    ("03 8085 0004", 0x03),  # R133, R134
    ("03 FFFF 0002", 0x03),
    ("03 3802 0001", 0x03),  # the save command address is write-only
    ("03 7FFF 0002", 0x03),
    ("06 0000 0001", 0x06),
    ("06 0064 0001", 0x06),
    ("06 8086 0001", 0x06),
    ("10 8086 0002 04 0000 0001", 0x10),
    ("10 0017 0001 02 0001", 0x10),
])
def test_illegal_address_answers_exception_02(drive: FakeDrive, request_: str, fc: int) -> None:
    """ch.2 "Eccezioni": "Nel drive è implementato solo il codice d'errore 02 Illegal Data
    Address"."""
    before = drive.state()
    outcome = run(drive, request_)
    assert outcome == Exception02(fc)
    assert outcome.pdu == bytes((fc | 0x80, 0x02))
    assert drive.state() == before


@pytest.mark.parametrize("request_", [
    "03 0001 0000",  # quantity 0
    "03 0001 007E",  # quantity 126 > 125
    "03 8000 FFFF",
    "03 0001 00",  # short
    "03 0001 0003 00",  # long
    "06 0003 00",
    "06 0003 000A 00",
    "06 0003 0064",  # d3 = 100, range 1..99
    "06 0003 0000",
    "06 0014 005B",  # c7 = 91: node numbers are 1..90
    "06 0051 0001",  # o1 is read-only
    "06 8005 0001",  # status word: read-only
    "10 8006 0002 04 0000 0001",  # position_actual_value: read-only
    "06 8001 0080",  # mode 0x80 = 128 > 0x7f
    "06 3802 0012",  # the save address takes 0x0011 only
    "10 3802 0002 04 0001 0011",
])
def test_other_errors_get_no_reply_and_change_nothing(drive: FakeDrive, request_: str) -> None:
    """ch.2 "Eccezioni": "In tutti gli altri casi di errore il messaggio viene scartato"."""
    before = drive.state()
    assert isinstance(run(drive, request_), Silence)
    assert drive.state() == before


@pytest.mark.parametrize("fc", [0x00, 0x01, 0x02, 0x04, 0x05, 0x07, 0x08, 0x0F, 0x11, 0x14,
                                0x16, 0x17, 0x2B, 0x7F, 0x83, 0x86, 0x90, 0xFF])
def test_unimplemented_function_codes_are_discarded(drive: FakeDrive, fc: int) -> None:
    """ch.2 "Codici funzione": 03, 06 and 16 only; ch.2 "Composizione del frame": 0 is invalid
    and 128..255 are exception codes."""
    before = drive.state()
    assert isinstance(serve_pdu(drive, bytes((fc,)) + h("0001 0001")), Silence)
    assert drive.state() == before


def test_empty_pdu_is_discarded(drive: FakeDrive) -> None:
    assert isinstance(serve_pdu(drive, b""), Silence)


def test_random_garbage_never_raises_nor_changes_state_without_reply() -> None:
    rng = random.Random(4)
    drive = FakeDrive.default()
    for _ in range(5000):
        fc = rng.choice([3, 6, 16, rng.randrange(256)])
        pdu = bytes((fc,)) + rng.randbytes(rng.randrange(0, 12))
        before = drive.state()
        outcome = serve_pdu(drive, pdu)
        if not isinstance(outcome, Reply) or pdu[0] == 3:
            assert drive.state() == before, pdu.hex()
        drive.responding = True


# ---- the line: broadcast, node numbers -------------------------------------------------------
@pytest.fixture
def line() -> list[FakeDrive]:
    return [FakeDrive.default(node_id=1), FakeDrive.default(node_id=5)]


@pytest.mark.parametrize("request_", ["06 0003 000A", "10 0003 0001 02 000A"])
def test_broadcast_write_reaches_every_drive_without_reply(line: list[FakeDrive],
                                                           request_: str) -> None:
    """ch.2 "Modo BROADCAST": address 0, every drive processes it, no reply."""
    assert isinstance(serve_line(line, 0, h(request_)), Silence)
    assert [d.read_parameter(3) for d in line] == [10, 10]


def test_broadcast_read_is_not_allowed(line: list[FakeDrive]) -> None:
    """ch.2 "Codice 03": "Con questa funzione non è ammesso il broadcast"."""
    assert isinstance(serve_line(line, 0, h("03 0001 0003")), Silence)


def test_broadcast_bad_value_changes_nothing(line: list[FakeDrive]) -> None:
    before = [d.state() for d in line]
    assert isinstance(serve_line(line, 0, h("06 0003 0064")), Silence)
    assert [d.state() for d in line] == before


def test_broadcast_skips_a_drive_that_is_saving(line: list[FakeDrive]) -> None:
    line[0].responding = False
    serve_line(line, 0, h("06 0003 000A"))
    assert [d.read_parameter(3) for d in line] == [50, 10]


@pytest.mark.parametrize("unit, answers", [(1, 0), (5, 1), (2, None), (90, None), (91, None),
                                           (247, None), (255, None)])
def test_unit_id_picks_the_drive_with_that_node_number(line: list[FakeDrive], unit: int,
                                                       answers: int | None) -> None:
    """ch.2: node numbers 1..90; 91..255 reserved; a unit id of no drive gets no reply."""
    line[1].parameters[1].value = 33
    outcome = serve_line(line, unit, h("03 0001 0001"))
    if answers is None:
        assert isinstance(outcome, Silence)
    else:
        assert outcome == Reply(h("03 02 00") + bytes((line[answers].read_parameter(1),)))


@pytest.mark.parametrize("unit", [91, 95, 99, 247, 255])
def test_reserved_unit_ids_are_never_answered(line: list[FakeDrive], unit: int) -> None:
    """ch.2 "Composizione del frame": "Gli indirizzi da 91 a 255 sono riservati". A drive whose
    node number ended up there (c7 is 1..99 for CANopen, ch.4) stays silent on a Modbus line."""
    line[1].node_id = unit
    assert isinstance(serve_line(line, unit, h("03 0001 0001")), Silence)
    before = line[1].state()
    assert isinstance(serve_line(line, unit, h("06 0003 000A")), Silence)
    assert line[1].state() == before


def test_a_drive_that_is_saving_does_not_answer(line: list[FakeDrive]) -> None:
    """ch.2 "Salvataggio su flash": "il drive non risponde" during the save."""
    line[1].responding = False
    assert isinstance(serve_line(line, 5, h("03 0001 0001")), Silence)


def test_two_drives_with_one_node_number_collide(line: list[FakeDrive]) -> None:
    line[1].node_id = 1
    assert isinstance(serve_line(line, 1, h("03 0001 0001")), Silence)


# ---- e3 = 9: the Siemens address map ---------------------------------------------------------
@pytest.mark.parametrize("request_, reply", [
    ("03 9C42 0003", "03 06 0014 0032 0032"),  # d1 at 40001 + 1 = 0x9C42
    ("06 9C44 000A", "06 9C44 000A"),  # d3 at 40004 = 0x9C44
    ("03 AC41 0004", "03 08 0000 1122 0000 3344"),  # R00 at 44097 + 0 = 0xAC41
    ("10 AC4A 0002 04 0000 03E8", "10 AC4A 0002"),  # R09 at 44097 + 9 = 0xAC4A
    ("06 3802 0011", "06 3802 0011"),  # the save command keeps its address
])
def test_siemens_map(drive: FakeDrive, request_: str, reply: str) -> None:
    """ch.2 "Estensione della mappatura degli indirizzi per PLC Siemens" (E3 = 9) and its
    examples."""
    drive.parameters[58].value = 9
    drive.registers[1].value = 0x3344
    assert run(drive, request_) == Reply(h(reply))


@pytest.mark.parametrize("request_", ["03 0001 0001", "03 8000 0002", "03 9C41 0001",
                                      "03 AC40 0002", "06 8009 0001"])
def test_siemens_map_replaces_the_normal_one(drive: FakeDrive, request_: str) -> None:
    drive.parameters[58].value = 9
    assert run(drive, request_) == Exception02(h(request_)[0])


def test_a_drive_on_another_fieldbus_is_not_on_the_line(line: list[FakeDrive]) -> None:
    """c9 picks the fieldbus at power-up; only c9 = 3 speaks Modbus (ch.2 "Configurazione")."""
    line[1].fieldbus = "canopen"
    assert isinstance(serve_line(line, 5, h("03 0001 0001")), Silence)
    serve_line(line, 0, h("06 0003 000A"))
    assert [d.read_parameter(3) for d in line] == [10, 50]


# ---- the same rules on the real drive model -----------------------------------------------------
class Clock:
    """Steps one drive 1 ms at a time, as the runtime does."""

    def __init__(self, drive: ServoDrive) -> None:
        self.drive, self.now_us = drive, 0

    def run(self, us: int) -> None:
        for _ in range(us // 1000):
            self.now_us += 1000
            self.drive.step(self.now_us)

    def until(self, predicate, within_us: int) -> int:
        start = self.now_us
        while not predicate():
            assert self.now_us - start < within_us, "condition not met in time"
            self.run(1000)
        return self.now_us - start


@pytest.fixture
def servo() -> tuple[ServoDrive, Clock]:
    d = ServoDrive("servo", random.Random(1), DriveConfig(node_id=1), MemoryFlash())
    clock = Clock(d)
    clock.run(100_000)  # past the power-on self test
    return d, clock


def ask(d: ServoDrive, request_: str):
    return serve_line([d], 1, h(request_))


def test_real_drive_answers_the_seed_read_of_d1_d3(servo) -> None:
    """ch.2 "Codice 0x03": the defaults of d1..d3 are the example's 20, 50, 50."""
    d, _ = servo
    assert ask(d, "03 0001 0003") == Reply(h("03 06 0014 0032 0032"))


@pytest.mark.parametrize("request_, register, stored", [
    ("06 8009 FFCE", 9, -50),  # target_position (S32): sign extension
    ("06 8009 7FFF", 9, 0x7FFF),
    ("10 8009 0002 04 FFFF FFCE", 9, -50),
    ("10 8009 0002 04 8000 0000", 9, -0x8000_0000),
    ("06 8003 FFFF", 3, 0xFFFF_FFFF),  # following_error_window: 0xFFFFFFFF disables the check
    ("10 8003 0002 04 FFFF FFFF", 3, 0xFFFF_FFFF),
    ("06 8001 FFCE", 1, -50),  # mode -50 by FC 06: 0xFFCE sign-extends to -50
    ("10 8001 0001 02 0003", 1, 3),
])
def test_real_drive_register_writes(servo, request_: str, register: int, stored: int) -> None:
    d, _ = servo
    assert isinstance(ask(d, request_), Reply)
    assert d.read_register(register) == stored


@pytest.mark.parametrize("request_", [
    "06 8000 8000",  # control word: 0xFFFF8000 after sign extension is out of 0..0xFFFF
    "06 8005 0000",  # status word: read-only
    "10 8006 0002 04 0000 0001",  # position_actual_value: read-only
    "10 802E 0002 04 0000 0000",  # alarm_code: read-only
    "06 8001 0002",  # mode 2 does not exist
    "10 8002 0002 04 0004 0000",  # feed_constant above 0x3FFFF
    "06 0003 0064",  # d3 = 100
    "06 0051 0000",  # o1: read-only
    "06 3802 0012",
    "10 3802 0002 04 0001 0011",
    "10 8009 0003 06 0000 0000 0000",
    "06 0014 005B",  # c7 = 91: a Modbus node number is 1..90 (ch.2 "Configurazione della rete")
    "06 0014 0063",  # c7 = 99
    "10 0014 0001 02 005F",  # c7 = 95 by FC 16
])
def test_real_drive_refusals_are_silent_and_change_nothing(servo, request_: str) -> None:
    d, _ = servo
    before = d.snapshot()
    assert isinstance(ask(d, request_), Silence)
    assert d.snapshot() == before


@pytest.mark.parametrize("request_", ["03 0000 0001", "03 0017 0001", "03 8086 0002",
                                      "06 0064 0001", "10 8086 0002 04 0000 0000"])
def test_real_drive_illegal_addresses(servo, request_: str) -> None:
    d, _ = servo
    before = d.snapshot()
    assert ask(d, request_) == Exception02(h(request_)[0])
    assert d.snapshot() == before


def test_real_drive_on_canopen_is_not_on_the_modbus_line() -> None:
    """c9 = 5 (CANopen) at power-up: the drive does not speak Modbus."""
    d = ServoDrive("servo", random.Random(1), DriveConfig(node_id=1, fieldbus="canopen"),
                   MemoryFlash())
    Clock(d).run(100_000)
    assert isinstance(ask(d, "03 0001 0003"), Silence)


def test_real_drive_read_r00_r01(servo) -> None:
    """ch.2: quantity 4 from 0x8000 = R00 then R01, high words first."""
    d, _ = servo
    ask(d, "10 8000 0002 04 0000 0008")
    ask(d, "10 8001 0002 04 0000 0006")
    assert ask(d, "03 8000 0004") == Reply(h("03 08 0000 0008 0000 0006"))


def test_real_drive_seed_positioner_example(servo) -> None:
    """ch.2 "Esempio di configurazione dell'asse in modalità posizionatore", node 01: set-up,
    homing (method 0x21), then a move to 0x1770: position_actual_value 6000, End of Job."""
    d, clock = servo
    setup = ["8002 0000 003C", "800A 0000 0064", "800B 0000 0064", "800C 0000 03E8",
             "801B 0000 0000", "8012 0000 0021", "8013 0000 0000", "8015 0000 000A",
             "8016 0000 0064", "8000 0000 0008", "8001 0000 0006", "8000 0000 0003",
             "8000 0000 0043"]
    for item in setup:
        address, value = item[:4], item[5:]
        assert ask(d, f"10 {address} 0002 04 {value}") == Reply(h(f"10 {address} 0002"))
    clock.until(lambda: d.read_register(5) & 0x40, 60_000_000)  # bit 6: homing OK
    assert ask(d, "03 8006 0002") == Reply(h("03 04 0000 0000"))  # home offset 0
    for item in ["8000 0000 0000", "8001 0000 0001", "8009 0000 1770", "8000 0000 0003",
                 "8000 0000 0023"]:
        address, value = item[:4], item[5:]
        assert ask(d, f"10 {address} 0002 04 {value}") == Reply(h(f"10 {address} 0002"))
    clock.run(10_000)
    clock.until(lambda: d.read_register(5) & 0x40, 60_000_000)  # bit 6: End of Job
    assert ask(d, "03 8006 0002") == Reply(h("03 04 0000 1770"))
    assert d.outputs()["end_of_job"]


@pytest.mark.parametrize("request_, reply", [
    ("06 3802 0011", "06 3802 0011"),
    ("10 3802 0002 04 0000 0011", "10 3802 0002"),
])
def test_real_drive_save_second_method(servo, request_: str, reply: str) -> None:
    """ch.2: the reply comes at once, then the drive is silent for the few seconds of the save,
    and the flash holds the new d3 afterwards."""
    d, clock = servo
    ask(d, "06 0003 000A")
    assert ask(d, request_) == Reply(h(reply))
    assert isinstance(ask(d, "03 0003 0001"), Silence)
    took = clock.until(lambda: d.responding, 10_000_000)
    assert 1_000_000 <= took <= 5_000_000  # "qualche secondo", "inferiore ai 5 secondi"
    assert d.flash.load() is not None and b'"d3": 10' in d.flash.load()


def test_real_drive_save_first_method(servo) -> None:
    """ch.2 "Primo metodo": mode -50 then control word 0x20 (torque off); the reply waits for
    the end of the save."""
    d, clock = servo
    assert ask(d, "10 8001 0002 04 FFFF FFCE") == Reply(h("10 8001 0002"))
    assert ask(d, "10 8000 0002 04 0000 0020") == Reply(h("10 8000 0002"), after_save=True)
    clock.until(lambda: d.responding, 10_000_000)
    assert d.flash.load() is not None


def test_real_drive_second_first_method_save_needs_bit_5_low_first(servo) -> None:
    """ch.1 R00 "Save ... 0 -> 1: salvataggio": the save is bit 5's edge. The same two writes
    again (R01 and R00 unchanged) save nothing and are answered at once; R00 = 0, then 0x20
    saves (docs/modbus.md "Save to flash")."""
    d, clock = servo
    assert ask(d, "10 8001 0002 04 FFFF FFCE") == Reply(h("10 8001 0002"))
    assert ask(d, "10 8000 0002 04 0000 0020") == Reply(h("10 8000 0002"), after_save=True)
    clock.until(lambda: d.responding, 10_000_000)
    assert ask(d, "10 8001 0002 04 FFFF FFCE") == Reply(h("10 8001 0002"))
    assert ask(d, "10 8000 0002 04 0000 0020") == Reply(h("10 8000 0002"))
    assert d.responding
    assert ask(d, "10 8000 0002 04 0000 0000") == Reply(h("10 8000 0002"))
    assert ask(d, "10 8000 0002 04 0000 0020") == Reply(h("10 8000 0002"), after_save=True)
