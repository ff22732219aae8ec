"""SDO access to a module's own objects while that module does not answer on the internal bus
(seed 000 §6.6-§6.15 objects, §7.5 0x07 / 0x08, 0x0A-0x0E: the coupler reads and writes them
in the module with SDORX commands). Choices: docs/fastcat-modules.md "Per-module objects"."""

from __future__ import annotations

import pytest
from fastcat_bench import Bench

from devices.ethercat import AlState
from devices.od import AbortCode, SdoAbort

AI8D_FILTER = 0x2114  # module 2's 0x2104 (§6.9)
AO4_RAMP = 0x202A  # module 3's 0x200A (§6.7)


def op_bench() -> Bench:
    bench = Bench(["DB16", "AI8D", "AO4"])
    bench.to_state(AlState.OP)
    return bench


def hardware_error(call) -> None:
    with pytest.raises(SdoAbort) as info:
        call()
    assert info.value.code is AbortCode.HARDWARE_ERROR


def test_a_pulled_modules_parameters_answer_an_sdo_abort() -> None:
    """The module is not there to answer the coupler's SDORX: every way in (the master's
    mailbox, an operator's read / write) gets abort 0x06060000 "Access failed due to a
    hardware error", and a write changes nothing. Its process data (0x6410) is the coupler's
    image and still reads; the other modules' objects are untouched."""
    bench = op_bench()
    bench.write(AI8D_FILTER, 0, 1234)
    bench.apply("unplug", module=2)
    bench.run(0.01)
    emergencies = bench.emergencies()
    fc = bench.fc
    hardware_error(lambda: fc.sdo_upload(AI8D_FILTER, 0))
    hardware_error(lambda: fc.sdo_download(AI8D_FILTER, 0, (500).to_bytes(2, "little")))
    hardware_error(lambda: bench.read(AI8D_FILTER, 0))
    hardware_error(lambda: bench.write(AI8D_FILTER, 0, 500))
    fc.sdo_upload(0x6410, 1)  # the process image
    bench.write(AO4_RAMP, 1, 5)
    assert bench.read(AO4_RAMP, 1) == 5
    assert bench.emergencies() == emergencies  # the 0x04 of the pull, nothing more
    bench.apply("plug", module=2, type="AI8D")  # back, powered up again from the Tbus
    bench.step()
    assert bench.read(AI8D_FILTER, 0) == 4000  # it answers: its §6.9 default after the reset


@pytest.mark.parametrize("how", ["module_power", "module_failure"])
def test_a_silent_modules_parameters_answer_an_sdo_abort(how: str) -> None:
    bench = op_bench()
    if how == "module_power":
        bench.apply("module_power", module=3, on=False)
    else:
        bench.apply("module_failure", module=3, active=True)
    bench.step()
    hardware_error(lambda: bench.write(AO4_RAMP, 1, 5))
    assert bench.fc.od.peek(AO4_RAMP, 1) == 0  # the view's value: the module's, unchanged
    assert bench.read(0x2114, 0) == 4000  # module 2 answers
