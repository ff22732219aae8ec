"""The node's scenario/UI action: a frame from a master, as a command (issue 4)."""

import pytest
from canopen_bench import hexs, make_bench

from devices.device import CommandError


def test_frame_action_is_an_sdo_request_like_any_other() -> None:
    """Seed 004 ch. 4: "2B 17 10 00 A0 0F 00 00" -> "60 17 10 00 00 00 00 00"."""
    bench = make_bench()
    bench.take()
    bench.node.apply("frame", {"cob_id": 0x600 + bench.node.node_id,
                               "data": "2B 17 10 00 A0 0F 00 00"})
    bench.run(5)
    answers = [f for f in bench.take() if f.can_id == 0x580 + bench.node.node_id]
    assert [hexs(f.data) for f in answers] == ["60 17 10 00 00 00 00 00"]


@pytest.mark.parametrize("args", [
    {"cob_id": 0x800, "data": ""}, {"cob_id": 0x601, "data": "zz"},
    {"cob_id": 0x601, "data": "00 " * 9},
])
def test_bad_frames_are_refused(args: dict) -> None:
    bench = make_bench()
    with pytest.raises(CommandError):
        bench.node.apply("frame", args)
