"""The TRS-CAT's and the CPX-E-EC's process data are recorded, as the FastCAT's are.

docs/recording.md promises "process data" and the brief "every signal": an audit of the example
scenarios' recordings found the FastCAT's rail under ``rig/fastcat/io/...`` but nothing of the
TRS-CAT's slots (inputs, the outputs the lines drive and the ones the PLC wrote: what
trscat_outputs_fallback is about, analog volts) nor of the CPX-E-EC's modules (inputs,
outputs written and driven, analog values). Each is now one entity per slot / module and key,
channels numbered as each device's actions take them (TRS-CAT from 1, CPX-E-EC from 0).
"""

from __future__ import annotations

from typing import Any

import pytest
from test_recording import Chunks, Run, load, rows

from app.recording.signals import device_path

S = 1_000_000


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    r = Run(tmp_path_factory.mktemp("rec") / "pd.rrd")
    r.hook(r.rig, r.rig.take_events())  # t = 0, as run_scenario starts
    r.run_until(3 * S)  # the line in OP
    r.do("trscat", "set_input", channel=3, on=True)
    r.do("trscat", "set_output", channel=2, value=1)
    r.do("trscat/2", "set_analog_input", channel=1, volts=5.0)
    r.do("cpx/1", "set_input", channel=4, on=True)
    r.do("cpx/3", "set_analog", channel=0, value=2.5)
    r.run_until(3_500_000)
    r.recorder.close()
    return r


@pytest.fixture(scope="module")
def chunks(run: Run) -> Chunks:
    return load(run.path)


def expected(snapshot: dict[str, Any]) -> dict[str, tuple[list[float], str]]:
    """entity -> (the snapshot's values, the first series name)."""
    out: dict[str, tuple[list[float], str]] = {}
    for slot in snapshot["trscat"]["slots"]:
        for key in ("inputs", "outputs", "outputs_plc", "analog_in_v", "analog_out_v"):
            if slot.get(key):
                out[device_path("trscat", "io", slot["slot"], key)] = (slot[key], f"{key} 1")
    cpx = snapshot["cpx"]
    for module in (cpx["bus_module"], *cpx["modules"]):
        for key in ("inputs", "outputs", "driven", "analog_in", "analog_out"):
            if module.get(key):
                out[device_path("cpx", "io", module["module"], key)] = (module[key], f"{key} 0")
    return out


def test_every_process_data_list_is_an_entity_that_ends_as_the_snapshot(
        run: Run, chunks: Chunks) -> None:
    entities = expected(run.rig.snapshot()["devices"])
    assert len(entities) >= 12
    for path, (values, first) in entities.items():
        recorded = rows(chunks, path, "Scalars:scalars")
        assert recorded and recorded[0][0] == 0, path
        last = recorded[-1][1]
        assert [float(v) for v in values] == (last if isinstance(last, list) else [last]), path
        names = rows(chunks, path, "SeriesLines:names") or [
            (0, n) for b in chunks[path] if "SeriesLines:names" in b.schema.names
            for n in b.column("SeriesLines:names").to_pylist()]
        assert names and (names[0][1][0] if isinstance(names[0][1], list)
                          else names[0][1]) == first, (path, names[:1])


def test_the_commands_show_in_the_recording(run: Run, chunks: Chunks) -> None:
    def last(path: str) -> list[float]:
        return rows(chunks, path, "Scalars:scalars")[-1][1]
    assert last(device_path("trscat", "io", 0, "inputs"))[2] == 1.0
    assert last(device_path("trscat", "io", 0, "outputs_plc"))[1] == 1.0
    assert last(device_path("trscat", "io", 2, "analog_in_v"))[0] == 5.0
    assert last(device_path("cpx", "io", 1, "inputs"))[4] == 1.0
    assert last(device_path("cpx", "io", 3, "analog_in"))[0] == 2.5
