"""The dictionary a CoE master sees and the SDO services of the mailbox (seed 004 ch. 5 "SDO:
tipologia e dizionario oggetti", "Lettura / Scrittura parametri del drive", "Salvataggio in
flash dei parametri"; identity: ch. 5 vendor ID; DS 301 abort codes of ch. 4).
"""

from __future__ import annotations

import pytest
from coe_bench import make_bench

from devices.coe.objects import PRODUCT_CODE, REVISION
from devices.ethercat import AlState
from devices.servo.parameters import PARAMETERS

P = AlState.PREOP


def _preop():
    bench = make_bench()
    bench.go(P)
    return bench


def test_identity() -> None:
    """Ch. 5: "Il Vendor ID per il consorzio ETG è: 0x0000078F"."""
    bench = _preop()
    assert [bench.read(0x1018, s) for s in range(4)] == [4, 0x0000078F, PRODUCT_CODE, REVISION]
    assert bench.read(0x1018, 4) == bench.slave.serial
    assert bench.read(0x1000) == 0x00020192
    assert bench.slave.sdo_upload(0x1008, 0) == b"SDrive"


@pytest.mark.parametrize(("index", "sub", "present"), [
    (0x603F, 0, True),  # "L'unica differenza sta nell'aggiunta dell'oggetto 0x603F"
    (0x2007, 0, True),  # ch. 5 save object
    (0x2005, 1, True), (0x2006, 2, True), (0x2000, 1, True), (0x6504, 0, True),
    (0x1C12, 0, True), (0x1C13, 0, True), (0x1C00, 0, True), (0x1001, 0, True),
    (0x1017, 0, False), (0x100C, 0, False), (0x1005, 0, False), (0x1014, 0, False),
    (0x1400, 1, False), (0x1800, 1, False),  # CAN layer objects: no meaning on EtherCAT
    (0x1C32, 0, False),  # not given by the seed
])
def test_objects_present_on_coe(index: int, sub: int, present: bool) -> None:
    bench = _preop()
    found = bench.abort(lambda: bench.slave.sdo_info(index, sub))
    assert found == ("ok" if present else "0x06020000")


@pytest.mark.parametrize(("action", "code"), [
    (lambda b: b.read(0x5000), "0x06020000"),  # no object
    (lambda b: b.read(0x1018, 9), "0x06090011"),  # no sub-index
    (lambda b: b.read(0x60C1, 1), "0x06010001"),  # write-only
    (lambda b: b.write(0x6041, 0, 1, 2), "0x06010002"),  # read-only
    (lambda b: b.write(0x1018, 1, 1, 4), "0x06010002"),
    (lambda b: b.write(0x6040, 0, 0x0F, 4), "0x06070012"),  # longer than the object
    (lambda b: b.write(0x6060, 0, 5, 1), "0x06090030"),  # no mode 5
    (lambda b: b.write(0x6060, 0, -50, 1), "0x06090030"),  # -50 is Modbus R01's, not in 0x6502
    (lambda b: b.write(0x2007, 0, 0x12, 1), "0x06090030"),  # save takes 0x11 only
    (lambda b: b.write(0x1003, 0, 1, 1), "0x06090030"),  # sub 0 takes 0 only
    (lambda b: b.write(0x6040, 0, 0x06, 1), "ok"),  # shorter data is extended (ch. 4)
])
def test_sdo_aborts(action, code: str) -> None:
    bench = _preop()
    assert bench.abort(lambda: action(bench)) == code


def test_failed_sdo_is_logged_for_the_panel() -> None:
    bench = _preop()
    bench.abort(lambda: bench.read(0x5000))
    assert bench.slave.snapshot()["sdo"][-1]["abort"] == "0x06020000"


def test_sdo_info_lists_the_dictionary_and_describes_entries() -> None:
    """Ch. 5: "utilizzando la funzione SDO Info support è possibile visualizzare l'elenco
    aggiornato degli oggetti implementati nel dizionario"."""
    bench = _preop()
    listed = bench.slave.sdo_info()
    assert {0x1000, 0x1018, 0x1C12, 0x1C13, 0x1600, 0x1A03, 0x603F, 0x6040, 0x2007} <= \
        set(listed)
    assert 0x1400 not in listed
    assert bench.slave.sdo_info(0x6040, 0) == {
        "index": 0x6040, "sub": 0, "name": "Controlword", "data_type": 0x0006,
        "type": "UINT", "bit_length": 16, "access": "rw", "pdo_mappable": True}


def test_variable_read_and_write_by_address() -> None:
    """Ch. 5 0x2005 / 0x2006: "Il dato sarà presente in Variable Read Value almeno 3 ms dopo la
    scrittura dell'indirizzo"; the write takes effect after the same 3 ms (registers)."""
    bench = _preop()
    bench.write(0x2006, 2, 0x1770, 4)  # target position (R09 = 0x8009) = 6000
    bench.slave.sdo_download(0x2006, 1, (0x8009).to_bytes(2, "little"))
    assert bench.read(0x2006, 1) == 0x8009
    assert bench.drive.read_register(9) != 6000
    bench.run(3)
    assert (bench.read(0x2006, 1), bench.drive.read_register(9)) == (0, 6000)
    bench.slave.sdo_download(0x2005, 1, (0x0003).to_bytes(2, "little"))  # d3
    bench.run(3)
    assert (bench.read(0x2005, 1), bench.read(0x2005, 2)) == (0, 50)


def test_parameter_written_by_address_is_in_force_after_3_ms() -> None:
    """Ch. 5 "Lettura / Scrittura parametri del drive": 0x2006 writes "i parametri specifici
    del drive" (the table of their addresses follows) and "Affinché la scrittura sia effettiva
    occorre aspettare almeno 3ms". The "circa 20 ms" of ch. 4 is 0x2000's, not 0x2006's."""
    bench = _preop()
    bench.write(0x2006, 2, 60, 4)
    bench.slave.sdo_download(0x2006, 1, (0x0003).to_bytes(2, "little"))  # d3
    assert bench.drive.read_parameter(3) == 50
    bench.run(3)
    assert (bench.read(0x2006, 1), bench.drive.read_parameter(3)) == (0, 60)
    bench.slave.sdo_download(0x2005, 1, (0x0003).to_bytes(2, "little"))
    bench.run(3)
    assert bench.read(0x2005, 2) == 60


def test_variable_write_takes_the_value_sub_2_holds_when_the_address_is_written() -> None:
    """0x2006 as ch. 4 gives its procedure (l. 3244-3248: the value to sub 2, "Successivamente"
    the address to sub 1), which ch. 5's two lines (address, then value, no order) do not
    change (docs/ethercat-coe.md "0x2006: the value first"). The address written first
    carries the old sub 2: 0 is out of d1's range, an abort at once, and d1 stays."""
    bench = _preop()
    assert bench.abort(lambda: bench.slave.sdo_download(
        0x2006, 1, (0x0001).to_bytes(2, "little"))) == "0x06090030"
    bench.write(0x2006, 2, 30, 4)
    bench.run(5)
    assert (bench.read(0x2006, 1), bench.drive.read_parameter(1)) == (0, 20)


@pytest.mark.parametrize(("name", "address"), [
    ("c9", 22), ("c7", 20), ("e3", 58), ("e4", 55), ("i6", 90), ("i7", 99), ("n1", 40),
    ("o1", 81), ("o3", 83), ("a6", 53), ("h9", 67), ("f1", 11), ("p7", 47),
])
def test_parameter_addresses_of_the_ch5_table(name: str, address: int) -> None:
    """Ch. 5 "Lettura / Scrittura parametri del drive": "una tabella riassuntiva degli
    indirizzi per ogni parametro" (l. 4567-4589), read through 0x2005."""
    bench = _preop()
    bench.slave.sdo_download(0x2005, 1, address.to_bytes(2, "little"))
    bench.run(3)
    spec = next(s for s in PARAMETERS.values() if s.name == name)
    assert spec.address == address
    assert bench.read(0x2005, 2, signed=True) == bench.drive.read_parameter(address)


def test_save_with_0x2007() -> None:
    """Ch. 5 "Salvataggio in flash": axis disabled ("Fr"), 0x11 to 0x2007, two dashes while
    it saves, "Fr" again when done."""
    bench = _preop()
    assert bench.drive.display == "Fr"
    bench.write(0x2007, 0, 0x11, 1)
    assert bench.drive.display == "--"
    bench.run_until(lambda: bench.drive.display == "Fr", 5_000)
    assert bench.flash.load() is not None


def test_object_view_and_actions() -> None:
    bench = _preop()
    assert bench.slave.apply("read_object", {"index": 0x1018, "sub": 1}) == 0x78F
    bench.slave.apply("write_object", {"index": 0x6060, "sub": 0, "value": 3})
    assert bench.slave.apply("read_object", {"index": 0x6061}) == 3
    rows = {(e.index, e.sub) for e in bench.slave.od}
    assert (0x1C12, 1) in rows and (0x603F, 0) in rows
