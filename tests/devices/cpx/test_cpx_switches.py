"""Rotary and DIL switches (seed 002 §2.1.7, Tab. 5, Tab. 6): read only at a restart."""

from __future__ import annotations

import pytest
from cpx_bench import TAB9_MODULES, Bench

from devices.cpx.catalog import BUS_IO_DIAGNOSIS, BUS_PLAIN, BUS_STATUS_BITS
from devices.cpx.switches import BUS_MODULE, DIL_MODES, DiagMode, Switches, check_rotary
from devices.device import CommandError
from devices.ethercat import AlState

TAB6 = [((False, False), DiagMode.NONE), ((False, True), DiagMode.STATUS_BITS),
        ((True, False), DiagMode.IO_DIAGNOSIS), ((True, True), DiagMode.BOOTLOADER)]


@pytest.mark.parametrize(("dil", "mode"), TAB6)
def test_dil_table(dil: tuple[bool, bool], mode: DiagMode) -> None:
    """Tab. 6: DIL 1 / DIL 2 -> diagnosis mode."""
    assert DIL_MODES[dil] is mode
    assert Switches(dil1=dil[0], dil2=dil[1]).mode is mode


def test_factory_settings() -> None:
    """Tab. 5 / Tab. 6: rotary 0, DIL OFF / OFF (no diagnosis)."""
    switches = Switches()
    assert (switches.rotary, switches.mode) == (0, DiagMode.NONE)


@pytest.mark.parametrize("value", [0, 1, 0x7FF, 4095])
def test_rotary_range(value: int) -> None:
    """Tab. 5: 0 ... 4095 (0x000 ... 0xFFF)."""
    assert check_rotary(value) == value


@pytest.mark.parametrize("value", [-1, 4096])
def test_rotary_out_of_range(value: int) -> None:
    with pytest.raises(ValueError, match="4095"):
        check_rotary(value)
    bench = Bench(master=False)
    with pytest.raises(CommandError):
        bench.apply("set_rotary", value=value)


def test_bus_module_variant_per_mode() -> None:
    """§2.3.1: no diagnosis 0/0, status bits 16 in, I/O diagnostic interface 16/16."""
    assert BUS_MODULE[DiagMode.NONE] is BUS_PLAIN
    assert (BUS_STATUS_BITS.input_bits, BUS_STATUS_BITS.output_bits) == (16, 0)
    assert (BUS_IO_DIAGNOSIS.input_bits, BUS_IO_DIAGNOSIS.output_bits) == (16, 16)
    assert (BUS_PLAIN.input_bits, BUS_PLAIN.output_bits) == (0, 0)


def test_rotary_takes_effect_only_after_a_restart() -> None:
    """§2.1.7: 0 = the master assigns the address; 1 ... 4095 = Explicit Device ID."""
    bench = Bench(master=False)
    assert bench.cpx.explicit_device_id == 0
    bench.apply("set_rotary", value=0x123)
    bench.run(0.1)
    assert bench.cpx.explicit_device_id == 0
    assert bench.cpx.snapshot()["switches"]["pending"] is True
    bench.apply("restart")
    assert bench.cpx.explicit_device_id == 0x123
    assert bench.cpx.snapshot()["switches"]["pending"] is False


def test_dil_takes_effect_only_after_a_power_cycle() -> None:
    """§2.1.7: the bus module's ident (0xF050:1) and process data change at the next start."""
    bench = Bench(TAB9_MODULES, master=False)
    assert bench.apply("read_object", index=0xF050, sub=1) == BUS_PLAIN.ident
    bench.apply("set_dil", dil1=False, dil2=True)
    bench.run(0.1)
    assert bench.apply("read_object", index=0xF050, sub=1) == BUS_PLAIN.ident
    bench.apply("power", on=False)
    bench.run(0.05)
    assert not bench.cpx.powered
    bench.apply("power", on=True)
    assert bench.apply("read_object", index=0xF050, sub=1) == BUS_STATUS_BITS.ident
    assert bench.apply("read_object", index=0x1A00, sub=0) == 9  # 8 status bits + gap


def test_bootloader_mode_runs_no_application() -> None:
    """Tab. 6 on/on: OS bootloader; Tab. 11/12: Run and Error orange; no PREOP."""
    bench = Bench(dil1=True, dil2=True)
    bench.run(0.5)
    assert bench.cpx.al_state is AlState.INIT
    assert bench.cpx.al_status_code == 0x0014
    assert bench.led_state("Run") == ("on", "orange")
    assert bench.led_state("Error") == ("on", "orange")
    assert bench.led("Run.orange") == "on" and bench.led("Run") == "off"
