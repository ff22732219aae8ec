"""The node's bus monitor (the dashboard's CANopen frame log): a heartbeat that repeats the
last one of its COB-ID is counted on a heartbeat line, not logged as a row, so the node's
heartbeats (one per 0x1017 period) do not push an SDO exchange, an NMT command or an EMCY out
of the log a moment after a trainee sent it (docs/dashboard.md)."""

from __future__ import annotations

from canopen_bench import make_bench

from devices.canopen.nmt import NmtCommand


def test_heartbeats_do_not_push_an_sdo_exchange_out_of_the_log() -> None:
    bench = make_bench()
    bench.ok(0x1017, 0, 20, 2)  # producer heartbeat every 20 ms
    bench.run(100)
    bench.nmt(NmtCommand.START)
    bench.run(100)
    assert bench.read(0x1018, 1) >= 0  # an upload a trainee sent from the CANopen master
    bench.run(3_000)  # 150 heartbeats: 2.5 times the rows the snapshot carries
    snap = bench.node.snapshot()
    texts = [f["text"] for f in snap["frames"]]
    kinds = [f["kind"] for f in snap["frames"]]
    assert any("upload 0x1018:01" in t for t in texts), texts[-5:]
    assert kinds.count("SDO") >= 2 and "NMT" in kinds  # request, answer; Start remote node
    # The heartbeats are there, once each state: boot-up, Pre-operational, Operational.
    states = [f["text"] for f in snap["frames"] if f["kind"] == "NMT-EC"]
    assert states == ["node 1: boot-up", "node 1: Pre-operational", "node 1: Operational"]
    beat = snap["heartbeats"][0]
    assert beat["id"] == "0x701" and beat["text"] == "node 1: Operational"
    assert beat["count"] >= 140 and abs(beat["period"] - 0.020) < 0.002
    assert abs(beat["t"] - bench.t_us / 1e6) <= 0.021  # the last one's time


def test_a_state_change_is_a_row_again() -> None:
    bench = make_bench()
    bench.ok(0x1017, 0, 20, 2)
    bench.run(200)
    bench.nmt(NmtCommand.STOP)
    bench.run(200)
    bench.nmt(NmtCommand.ENTER_PRE_OPERATIONAL)
    bench.run(200)
    states = [f["text"] for f in bench.node.snapshot()["frames"] if f["kind"] == "NMT-EC"]
    assert states == ["node 1: boot-up", "node 1: Pre-operational", "node 1: Stopped",
                      "node 1: Pre-operational"]


def test_a_short_frame_on_the_sdo_id_reads_malformed_not_as_a_request() -> None:
    """"Un messaggio SDO è sempre otto byte" (seed 004 ch. 4): the node does not answer a
    shorter frame, so the log must not read it as the request it would have been padded
    ("-> node 1: upload 0x1018:01" with no answer after it), and the Last SDO row keeps the
    previous exchange."""
    bench = make_bench()
    assert bench.read(0x1018, 1) >= 0
    before = bench.node.snapshot()["last_sdo_exchange"]
    bench.send(0x601, bytes.fromhex("40 18 10 01"))
    bench.run(5)
    snap = bench.node.snapshot()
    row = snap["frames"][-1]
    assert (row["kind"], row["text"]) == ("SDO", "-> node 1: malformed (4 bytes, an SDO is "
                                                 "always 8): not answered")
    assert snap["last_sdo_exchange"] == before
