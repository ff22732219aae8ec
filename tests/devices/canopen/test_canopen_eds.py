"""The EDS file in static/eds: generated from the node's own dictionary, loadable by the
``canopen`` library, and up to date (seed 004 ch. 4 "Object Dictionary (OD) & Electronic
Data Sheet (EDS)", "Oggetti implementati").
"""

from __future__ import annotations

import canopen
import pytest
from canopen_bench import make_bench

from app.canopen_eds import EDS_PATH, generate, main


@pytest.fixture(scope="module")
def eds_od() -> canopen.ObjectDictionary:
    return canopen.import_od(str(EDS_PATH), node_id=7)


def test_committed_file_is_up_to_date() -> None:
    assert EDS_PATH.read_text(encoding="utf-8") == generate(), \
        "static/eds/servo_drive.eds is stale: run python -m app.canopen_eds"
    assert main(["--check"]) == 0


def test_every_object_the_node_serves_is_in_the_eds(eds_od) -> None:
    bench = make_bench(boot=False)
    for entry in bench.node.dictionary:
        obj = eds_od[entry.index]
        var = obj if isinstance(obj, canopen.objectdictionary.ODVariable) else obj[entry.sub]
        assert (var.data_type, var.access_type, var.pdo_mappable) == \
            (int(entry.dtype), entry.access.value, entry.pdo_mappable), hex(entry.index)
    served = set(bench.node.dictionary.indices())
    listed = {i for i in eds_od.indices if i >= 0x1000}
    assert served == listed


@pytest.mark.parametrize("index", [0x603F, 0x2007])
def test_ethercat_only_objects_are_not_listed(eds_od, index: int) -> None:
    assert index not in eds_od


def test_node_id_relative_cob_ids(eds_od) -> None:
    """$NODEID defaults: RPDO1 = 0x200 + 7, TPDO2 invalid (bit 31) = 0x80000280 + 7."""
    assert eds_od[0x1400][1].default == 0x207
    assert eds_od[0x1801][1].default == 0x8000_0287
    assert eds_od[0x1014].default == 0x87


def test_device_information(eds_od) -> None:
    info = eds_od.device_information
    assert (info.vendor_number, info.nr_of_RXPDO, info.nr_of_TXPDO) == (0x078F, 4, 4)
    # canopen 2.4 reads Granularity as a boolean: check the file itself (byte granularity)
    assert "\nGranularity=8\n" in EDS_PATH.read_text(encoding="utf-8")
    assert info.allowed_baudrates == {10e3, 20e3, 50e3, 125e3, 250e3, 500e3, 800e3, 1000e3}
