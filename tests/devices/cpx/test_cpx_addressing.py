"""Address assignment of the CPX-E-EC (seed 002 §2.2, §2.3.1, §2.3.2 Tab. 9)."""

from __future__ import annotations

import pytest
from cpx_bench import TAB9_MODULES, Bench

from devices.cpx.addressing import AddressSpace, assign_addresses, check_configuration
from devices.cpx.catalog import (
    BUS_IO_DIAGNOSIS,
    BUS_PLAIN,
    BUS_STATUS_BITS,
    IO_MODULES,
    MAX_IO_MODULES,
    module_type,
)
from devices.ethercat import AlState

# §2.3.2 Tab. 9 exactly (the OCR's "10 ... 17" is I0 ... I7, "064 ... 071" is O64 ... O71).
TAB9 = [
    (0, "CPX-E-EC", "I0 ... I7", "-"),
    (1, "CPX-E-16DI", "I72 ... I87", "-"),
    (2, "CPX-E-8DO", "-", "O64 ... O71"),
    (3, "CPX-E-8DO", "-", "O72 ... O79"),
    (4, "CPX-E-4AI-U-I", "I8 ... I71", "-"),
    (5, "CPX-E-4AO-U-I", "-", "O0 ... O63"),
]


def tab9_types() -> list:
    return [module_type(name) for name in TAB9_MODULES]


@pytest.mark.parametrize(("number", "name", "inputs", "outputs"), TAB9)
def test_tab9_example_reproduced(number: int, name: str, inputs: str, outputs: str) -> None:
    """§2.3.2: every address of the example system, bus module with status bits."""
    rows = [a.row() for a in assign_addresses(BUS_STATUS_BITS, tab9_types())]
    assert rows[number] == {"module": number, "name": name, "inputs": inputs,
                            "outputs": outputs}


def test_tab9_example_on_the_device() -> None:
    """The same table from the running model, DIL 2 on (status bits, Tab. 6)."""
    bench = Bench(TAB9_MODULES, master=False, dil2=True)
    rows = bench.cpx.snapshot()["addresses"]
    assert [(r["module"], r["name"], r["inputs"], r["outputs"]) for r in rows] == TAB9


def test_bus_module_without_diagnosis_has_no_addresses() -> None:
    """§2.3.1: the bus module counts as 0 inputs / 0 outputs without diagnosis."""
    rows = assign_addresses(BUS_PLAIN, tab9_types())
    assert rows[0].inputs is None and rows[0].outputs is None
    assert rows[4].inputs.text("I") == "I0 ... I63"  # the analog input module moves to I0
    assert rows[1].inputs.text("I") == "I64 ... I79"


def test_io_diagnostic_interface_takes_16_inputs_and_16_outputs() -> None:
    """§2.3.1 / §2.4.3: the interface occupies 16 inputs and 16 outputs, first of all."""
    rows = assign_addresses(BUS_IO_DIAGNOSIS, tab9_types())
    assert rows[0].inputs.text("I") == "I0 ... I15"
    assert rows[0].outputs.text("O") == "O0 ... O15"
    assert rows[4].inputs.text("I") == "I16 ... I79"
    assert rows[5].outputs.text("O") == "O16 ... O79"
    assert rows[2].outputs.text("O") == "O80 ... O87"


def test_inputs_and_outputs_are_counted_independently() -> None:
    """§2.3.1: an output module does not move the next input module's addresses."""
    types = [module_type("8DO"), module_type("16DI")]
    rows = assign_addresses(BUS_PLAIN, types)
    assert rows[1].outputs.text("O") == "O0 ... O7"
    assert rows[2].inputs.text("I") == "I0 ... I15"


def test_ascending_module_number_within_a_type() -> None:
    """§2.3.1: left to right within a module type, whatever comes between."""
    types = [module_type(n) for n in ("16DI", "4AI-U-I", "16DI", "4AI-U-I")]
    rows = assign_addresses(BUS_PLAIN, types)
    assert [rows[n].inputs.first for n in (2, 4, 1, 3)] == [0, 64, 128, 144]


def test_status_bits_count_two_bytes_of_the_address_space() -> None:
    """§2.3.1 / Tab. 28 note 4: 16 inputs occupied, 8 used."""
    plain = AddressSpace.of(BUS_PLAIN, tab9_types())
    status = AddressSpace.of(BUS_STATUS_BITS, tab9_types())
    assert status.input_bytes - plain.input_bytes == 2
    assert status.output_bytes == plain.output_bytes
    sti = AddressSpace.of(BUS_IO_DIAGNOSIS, tab9_types())
    assert (sti.input_bytes - plain.input_bytes, sti.output_bytes - plain.output_bytes) == (2, 2)
    assert (status.input_bytes, status.output_bytes) == (12, 10)


def test_at_most_ten_io_modules() -> None:
    """§2.2: 10 I/O modules + the bus module."""
    check_configuration(BUS_PLAIN, [module_type("8DO")] * MAX_IO_MODULES)
    with pytest.raises(ValueError, match="at most 10"):
        check_configuration(BUS_PLAIN, [module_type("8DO")] * (MAX_IO_MODULES + 1))
    with pytest.raises(ValueError, match="at most 10"):
        Bench(["8DO"] * 11, master=False)


def test_64_byte_address_space_includes_diagnosis() -> None:
    """§2.2: 64 input bytes; activated diagnosis reduces what is left for the modules."""
    eight_ai = [module_type("4AI-U-I")] * 8  # 8 x 8 = 64 input bytes
    assert check_configuration(BUS_PLAIN, eight_ai).input_bytes == 64
    with pytest.raises(ValueError, match="64 input bytes"):
        check_configuration(BUS_STATUS_BITS, eight_ai)
    with pytest.raises(ValueError, match="64 output bytes"):
        check_configuration(BUS_IO_DIAGNOSIS, [module_type("4AO-U-I")] * 8)


@pytest.mark.parametrize("name", sorted(IO_MODULES))
def test_catalog_sizes_are_whole_bytes(name: str) -> None:
    mtype = IO_MODULES[name]
    assert mtype.input_bits % 8 == 0 and mtype.output_bits % 8 == 0


def test_the_seed_modules_are_in_the_catalog() -> None:
    """§2.3.2 and §2.1.4 name these modules; DC capable: 16DI, 8DO, 1CI."""
    assert {"CPX-E-16DI", "CPX-E-8DO", "CPX-E-4AI-U-I", "CPX-E-4AO-U-I",
            "CPX-E-1CI"} <= set(IO_MODULES)
    assert {n for n, m in IO_MODULES.items() if m.dc_capable} == {
        "CPX-E-16DI", "CPX-E-8DO", "CPX-E-1CI"}
    assert BUS_PLAIN.module_code == "222/37" and BUS_PLAIN.short == "E-EC"  # Tab. 28
    assert BUS_PLAIN.ident >> 16 == 222 << 8 | 37


def test_a_dil_change_past_64_bytes_refuses_safeop() -> None:
    """§2.2: diagnosis switched on at the DIL switches can push a full terminal past the
    64-byte space; the bus module then refuses PREOP -> SAFEOP (docs/cpx-e-ec.md)."""
    bench = Bench(["4AI-U-I"] * 8, master=False)
    bench.apply("set_dil", dil1=False, dil2=True)
    bench.apply("restart")
    assert "64 input bytes" in bench.cpx.snapshot()["space_error"]
    bench.cpx.request_state(AlState.PREOP)
    bench.cpx.request_state(AlState.SAFEOP)
    assert (bench.cpx.al_state, bench.cpx.al_status_code) == (AlState.PREOP, 0x001E)
