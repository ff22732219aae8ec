"""A real EtherCAT master (SOEM through pysoem) drives the virtual line over a veth pair.

Issue 8 acceptance, end to end: this test process is process A (rig + runtime + the bridge,
which spawns process B, the emulated ESCs, on one end of a veth pair); pysoem runs in a third
process on the other end (it holds the GIL during its calls: ethercat-wire-notes.md). Checked:
config_init finds every slave with its name and 0x1018 identity; config_map (the TRS-CAT's
mapping by complete access, seed 001 §9.3); PREOP -> SAFEOP ->
OP; cycles at 4 ms with no working-counter error (10,000 with --full, CI_CYCLES without);
outputs written by the master reach the model (seed 000 §6.28, DO16) and inputs changed in the
model reach the master (§6.24, DI16); sdo_read 0x1018 on every slave; the FastCAT fault of
seed 000 §7.1 arrives as "FF00 / 81 / 02 00 00 04 00"; a TRS-CAT expansion mismatch written
to 0xF030 makes SAFEOP fail with 0x0070 (seed 001 §9.3.2).

Skipped with the reason when the machine cannot: not root, no pysoem, `ip link add` refused.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import NamedTuple

import pytest

pysoem = pytest.importorskip("pysoem", reason="pysoem (the SOEM master) is not installed")

from soem_bringup import (  # noqa: E402
    EXPECTED_WKC,
    STATE_TIMEOUT_S,
    TRSCAT_STARTUP,
    SoemLine,
    Stage,
)
from wire_line import line_spec, veth_pair  # noqa: E402

from app.ethercat_wire.bridge import start_wire  # noqa: E402
from app.ethercat_wire.wire_process import lock_memory  # noqa: E402
from app.rig_config import build_rig, load_rig_spec, parse_rig_spec  # noqa: E402
from app.runtime import Runtime  # noqa: E402
from devices.ethercat import AlState  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
CI_CYCLES = 1_000  # 4 s; the long form (--full) runs the 10,000 (40 s)
FULL_CYCLES = 10_000
PERIOD_S = 0.004
SDO_TIMEOUT_US = 3_000_000
A_NICE = -10
# Lost frames (not back within SOEM's 2 ms receive timeout) tolerated per 1,000 cycles in the
# CI form only: on a shared, non-real-time host a stall of process B or of the veth softirq
# beyond 2 ms loses a frame whatever the emulation does (docs/ethercat-wire.md, "Lost frames").
# Wrong working counters are never tolerated; --full tolerates neither.
CI_LOST_PER_1000 = 5
DEADLINE_S = 20.0  # for what A and B do meanwhile: generous, a loaded host stalls both


# ---- the veth pair ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def veth():
    with veth_pair("l") as pair:
        yield pair


class Cycles(NamedTuple):
    wrong: list[tuple[int, int]]  # (cycle, WKC) of frames back with another working counter
    lost: list[int]  # cycles whose frame was not back within the receive timeout
    late: int  # cycles the master itself started late (its own scheduling)
    inputs: list[bytes]


def check_cycles(c: Cycles, n: int, expected: int, full: bool) -> None:
    assert c.wrong == [], (f"{len(c.wrong)} wrong working counters in {n} cycles (expected "
                           f"{expected}; first (cycle, wkc): {c.wrong[:10]}; {c.late} late)")
    budget = 0 if full else n * CI_LOST_PER_1000 // 1000
    assert len(c.lost) <= budget, (f"{len(c.lost)} frames lost in {n} cycles, at {c.lost[:20]}"
                                   f" ({c.late} late)")


# ---- the master process -----------------------------------------------------------------
def master_main(iface: str, conn) -> None:
    """Runs in its own process: executes the test's commands with pysoem, one at a time."""
    import pysoem as ps

    with contextlib.suppress(OSError):  # like process B: keep time on a loaded machine
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
    lock_memory()  # like process B: no page of ours faulted back in mid-cycle
    master = ps.Master()
    master.open(iface)
    # mailbox answers go through process A's simulation thread: allow for a busy machine
    master.sdo_read_timeout = SDO_TIMEOUT_US
    master.sdo_write_timeout = SDO_TIMEOUT_US

    emergencies: list[tuple[int, int, int, int, int, int]] = []

    def init():
        # SOEM names a slave whose SII it could not read in time "? M:..". On a loaded shared
        # host process B can miss SOEM's EEPROM timeout on the first reads (CI, 2026-11-26:
        # slave 0 only); a master scans again, as a field engineer would press "scan" again.
        for _ in range(3):
            n = master.config_init()
            if not any(s.name.startswith("? M:") for s in master.slaves):
                break
        # config_init asks PRE-OP and returns without waiting; the mailbox runs from PRE-OP
        # (a slave in INIT answers no SDO), so wait as a master does before its first
        # mailbox access (the FastCAT reaches PRE-OP after its module scan)
        master.state_check(ps.PREOP_STATE, int(STATE_TIMEOUT_S * 1e6))
        for pos, slave in enumerate(master.slaves):
            slave.add_emergency_callback(lambda e, pos=pos: emergencies.append(
                (pos, e.error_code, e.error_reg, e.b1, e.w1, e.w2)))
        return n, [(s.name, s.man, s.id, s.rev) for s in master.slaves]

    def drain():
        """Read what the slaves' mailboxes hold (emergencies sent before this master came)."""
        for slave in master.slaves:
            for _ in range(8):
                if slave.mbx_receive() <= 0:
                    break
        taken = list(emergencies)
        emergencies.clear()
        return taken

    def dc(dc_positions):
        """SYNC0 every cycle, as a DC master configures it (0x0981 / 0x0990 / 0x09A0). Before
        config_map, which asks each slave for SAFE-OP as it maps it: the TRS-CAT takes its mode
        from these registers at PREOP -> SAFEOP (seed 001 §9.1.1, §9.2; config_init cleared
        them: left so, it would run FREE-RUN)."""
        master.config_dc()
        for pos in dc_positions:
            master.slaves[pos].dc_sync(True, int(PERIOD_S * 1e9))

    def map_(dc_positions, startup=()):
        """``startup``: (position, index, sub, data) written in PRE-OP first, as a SOEM
        application writes its slaves' start-up objects (its PO2SO hook) before mapping."""
        for pos, index, sub, data in startup:
            master.slaves[pos].sdo_write(index, sub, data)
        dc(dc_positions)
        try:
            master.config_map()
            errors = []
        except ps.ConfigMapError as exc:  # SOEM mapped anyway (SII fallback): report, go on
            errors = [repr(e) for e in exc.error_list]
        return master.expected_wkc, errors

    def exchange():
        master.send_processdata()
        return master.receive_processdata(2000)

    def state(target, timeout_s):
        """Request `target` for all and wait for it, the process data going every 4 ms
        meanwhile (a DC slave counts every SYNC0 without a frame as a missed SM event).
        `target` may carry EC_STATE_ACK (0x10); the state read is compared without it."""
        t = time.perf_counter()
        for k in range(int(timeout_s / PERIOD_S) + 50):
            exchange()
            if k == 50:  # valid outputs for a while before the request, as a PLC does
                master.state = target
                master.write_state()
            elif k > 50 and k % 10 == 0 and master.read_state() == target & 0x0F:
                break
            t += PERIOD_S
            time.sleep(max(0.0, t - time.perf_counter()))
        master.read_state()
        return [(s.state, s.al_status) for s in master.slaves]

    def slave_state(pos, target, timeout_s):
        slave = master.slaves[pos]
        slave.state = target
        slave.write_state()
        # bits 0-3: SOEM's ec_statecheck compares the state, a request may carry EC_STATE_ACK
        slave.state_check(target & 0x0F, int(timeout_s * 1e6))
        master.read_state()
        return slave.state, slave.al_status

    def cycles(n, period, outputs):
        """n exchanges `period` apart. A frame that came back with another working counter
        is a WKC error; one that did not come back within the receive timeout (SOEM's
        EC_NOFRAME, -1) is a lost frame, counted apart as TwinCAT and the master panel do."""
        for pos, data in outputs.items():
            master.slaves[pos].output = data
        wrong, lost, late, t = [], [], 0, time.perf_counter()
        for i in range(n):
            wkc = exchange()
            if wkc < 0:
                lost.append(i)
            elif wkc != master.expected_wkc:
                wrong.append((i, wkc))
            t += period
            rest = t - time.perf_counter()
            if rest > 0:
                time.sleep(rest)
            else:
                late += 1
        return Cycles(wrong, lost, late, [bytes(s.input) for s in master.slaves])

    def sdo_read(pos, index, sub, ca=False):
        return bytes(master.slaves[pos].sdo_read(index, sub, ca=ca))

    def sdo_write(pos, index, sub, data, ca=False):
        master.slaves[pos].sdo_write(index, sub, data, ca=ca)

    def emergency(pos, timeout_s):
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            exchange()
            master.slaves[pos].mbx_receive()
            for e in emergencies:
                if e[0] == pos:
                    emergencies.remove(e)
                    return e[1:]
            time.sleep(PERIOD_S)
        return None

    handlers = {"init": init, "dc": dc, "map": map_, "state": state, "slave_state": slave_state,
                "cycles": cycles, "sdo_read": sdo_read, "sdo_write": sdo_write,
                "emergency": emergency, "drain": drain}
    while True:
        cmd, *args = conn.recv()
        if cmd == "close":
            master.close()
            return
        try:
            conn.send(("ok", handlers[cmd](*args)))
        except Exception as exc:  # reported to the test, which fails with it
            conn.send(("error", repr(exc)))


class Master:
    def __init__(self, iface: str) -> None:
        ctx = multiprocessing.get_context("spawn")
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=master_main, args=(iface, child), daemon=True)
        self.proc.start()

    def __call__(self, *cmd, timeout: float = 120.0):
        self.conn.send(cmd)
        if not self.conn.poll(timeout):
            raise AssertionError(f"master command {cmd[0]} timed out")
        status, result = self.conn.recv()
        assert status == "ok", f"{cmd[0]}: {result}"
        return result

    def close(self) -> None:
        self.conn.send(("close",))
        self.proc.join(timeout=10)
        if self.proc.is_alive():
            self.proc.terminate()


def powered_runtime(rig) -> Runtime:
    for device in rig.devices.values():
        if "power" in device.ACTIONS:
            device.apply("power", {"on": True}, None)
    runtime = Runtime(rig)
    runtime.start()
    return runtime


@contextlib.contextmanager
def favoured(pid: int = 0):
    """Process A ahead of batch work (nice -10; threads started meanwhile inherit it): on a
    machine running a dozen other jobs the simulation must keep real time, or the models see
    the master's frames late (SM watchdog, DC sync errors) for reasons that are not the wire's."""
    old = os.getpriority(os.PRIO_PROCESS, pid)
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, pid, A_NICE)
    try:
        yield
    finally:
        with contextlib.suppress(OSError, ProcessLookupError):
            os.setpriority(os.PRIO_PROCESS, pid, old)


@pytest.fixture(scope="module")
def session(veth) -> Iterator[SoemLine]:
    with favoured():
        yield from _session(veth)


def _session(veth) -> Iterator[SoemLine]:
    master_if, slave_if = veth
    runtime = powered_runtime(build_rig(parse_rig_spec(line_spec("wire line", seed=8))))
    bridge = start_wire(runtime, slave_if)
    master = Master(master_if)
    yield SoemLine(runtime, bridge, master)
    master.close()
    bridge.stop()
    runtime.stop()


def model_call(runtime: Runtime, fn):
    return runtime.submit(fn).result(timeout=10)


# ---- the acceptance ---------------------------------------------------------------------
# In bring-up order, but each test brings the line to the stage it needs (SoemLine), so each
# passes alone and in any order; in this order no step runs twice.
def test_config_init_finds_every_slave_with_name_and_identity(session: SoemLine):
    n, slaves = session.init()
    assert n == 4
    assert [s[0] for s in slaves] == ["FastCAT", "TRS-CAT", "CPX-E-EC", "SelemaDriveECAT"]
    idents = [(d.vendor_id, d.product_code, d.revision) for d in session.bridge.descriptions]
    assert [tuple(s[1:]) for s in slaves] == idents


def test_sdo_read_0x1018_on_every_slave(session: SoemLine):
    bridge, master = session.at_least(Stage.SCANNED).bridge, session.master
    for pos, desc in enumerate(bridge.descriptions):
        assert struct.unpack("<I", master("sdo_read", pos, 0x1018, 1))[0] == desc.vendor_id
        assert struct.unpack("<I", master("sdo_read", pos, 0x1018, 2))[0] == desc.product_code


def test_trscat_refuses_safeop_before_its_process_data_sms_are_set_up(session: SoemLine):
    """Seed 001 §9.2 PS (l. 501-502): the TRS-CAT checks the SM channels of the process data.
    SOEM writes SM2 / SM3 only in config_map: asked for SAFE-OP before, the TRS-CAT finds SM2
    disabled while 0x1C12 assigns outputs -> 0x001D (checked before the DC and 0xF030)."""
    master = session.scanned().master
    session.left(Stage.NONE)  # the TRS-CAT in error until acknowledged below
    master("dc", [1])
    state, al_status = master("slave_state", 1, AlState.SAFEOP, 3.0)
    assert (state & 0x0F, state & 0x10) == (AlState.PREOP, 0x10)
    assert al_status == 0x001D
    # acknowledge the error
    state, _ = master("slave_state", 1, AlState.PREOP | 0x10, STATE_TIMEOUT_S)
    assert state & 0x0F == AlState.PREOP
    session.stage = Stage.SCANNED


def test_trscat_objects_read_and_written_whole_by_complete_access(session: SoemLine):
    """Seed 001 §9.3: the TRS-CAT serves complete access (and announces it, so config_map
    below reads its mapping with ecx_readPDOmapCA). SOEM's own requests: 0x1C12 / 0x1C13 whole
    = sub 0 padded to 16 bits + the subs; 0xF030 written whole in PRE-OP (the expansion left
    out), 0x1C12 follows (§9.3.2), then the list put back."""
    master = session.scanned().master  # 0xF030 is written in PRE-OP
    session.left(Stage.NONE)  # until the expansion list is put back
    for pos, index, sub, data in TRSCAT_STARTUP:  # the list, as map_to_op's start-up writes it
        master("sdo_write", pos, index, sub, data)
    for index in (0x1C12, 0x1C13):
        n = master("sdo_read", 1, index, 0)[0]
        subs = b"".join(master("sdo_read", 1, index, s) for s in range(1, n + 1))
        assert master("sdo_read", 1, index, 0, True) == bytes((n, 0)) + subs
    f030 = master("sdo_read", 1, 0xF030, 0, True)
    assert f030[:2] == b"\x02\x00"
    master("sdo_write", 1, 0xF030, 0, b"\x01\x00" + f030[2:6], True)  # the integrated module
    assert master("sdo_read", 1, 0x1C12, 0, True) == struct.pack("<BBH", 1, 0, 0x1600)
    master("sdo_write", 1, 0xF030, 0, f030, True)
    assert master("sdo_read", 1, 0xF030, 0, True) == f030
    session.stage = Stage.SCANNED


def test_map_and_bring_the_line_to_op(session: SoemLine):
    """config_map (expected WKC 3 per slave), SAFE-OP, OP: the checks are map_to_op's."""
    session.scanned().map_to_op()
    assert session.stage == Stage.OP


def test_cycles_at_4_ms_without_wkc_errors_and_data_both_ways(session: SoemLine, full):
    runtime, master = session.at_least(Stage.OP).runtime, session.master
    n = FULL_CYCLES if full else CI_CYCLES
    model_call(runtime, lambda: runtime.rig.apply("fastcat/1", "set_input",
                                                  {"channel": 5, "value": True}))
    do16_ch3 = (1 << (8 + 2)).to_bytes(3, "little")  # after 0x16FF's byte (§6.17)
    c = master("cycles", n, PERIOD_S, {0: do16_ch3}, timeout=n * 0.02 + 60)
    check_cycles(c, n, EXPECTED_WKC, full)
    do = model_call(runtime, lambda: runtime.rig.snapshot()["devices"]["fastcat"]["rail"][1])
    assert do["type"] == "DO16" and do["do"] == [ch == 2 for ch in range(16)]
    assert int.from_bytes(c.inputs[0], "little") & 1 << (8 + 4)  # DI16 channel 5 (§6.24)
    snap = model_call(runtime, lambda: runtime.rig.snapshot()["devices"]["master"])
    assert snap["external"] and snap["stats"]["frames"] > 0


def test_config_map_reads_every_mapping_without_an_sdo_abort(session: SoemLine):
    """pysoem's config_map() raises ConfigMapError for any abort SOEM logged while it read the
    CoE mapping (0x1C00, 0x1C12 / 0x1C13, 0x16xx / 0x1Axx), even when it then fell back to the
    SII PDOs; a master should find every mapping it asks for."""
    assert session.at_least(Stage.MAPPED).map_errors == []


def test_trscat_expansion_mismatch_refuses_safeop_with_0x0070(session: SoemLine):
    """Seed 001 §9.3.2: 0xF030 (configured) differs from 0xF050 (detected) -> 0x0070. A TRS-XX-E
    in place of the TRS-IO-E keeps the image sizes (one word each way), so the sync managers
    config_map set up still fit and the check reached is the modules'."""
    master = session.at_least(Stage.OP).master
    session.left(Stage.MAPPED)  # back in OP at the end
    # Without process data since the last test the TRS-CAT falls from OP to SAFE-OP with an
    # error (SM watchdog, sync), sooner or later as the machine's load has it: PRE-OP with
    # EC_STATE_ACK, as a SOEM program asks where the flag may be set (ETG.1000.6).
    state, _ = master("slave_state", 1, AlState.PREOP | 0x10, STATE_TIMEOUT_S)
    assert state & 0x1F == AlState.PREOP  # no flag left: the refusal below is the mismatch's
    original = master("sdo_read", 1, 0xF030, 2)
    master("sdo_write", 1, 0xF030, 2, struct.pack("<I", 0x58582D45))  # "TRS-XX-E" ident
    state, al_status = master("slave_state", 1, AlState.SAFEOP, 3.0)
    assert (state & 0x0F, state & 0x10) == (AlState.PREOP, 0x10)
    assert al_status == 0x0070
    master("sdo_write", 1, 0xF030, 2, original)
    # The list put back: SAFE-OP again, acknowledging the error flag (EC_STATE_ACK, AL control
    # bit 4, ETG.1000.6); without it the slave ignores the request.
    state, al_status = master("slave_state", 1, AlState.SAFEOP | 0x10, STATE_TIMEOUT_S)
    assert (state & 0x1F, al_status) == (AlState.SAFEOP, 0)
    # The CPX-E-EC and the drive fell to SAFE-OP with 0x001B meanwhile (slave_state sends no
    # process data: SM watchdog): OP with EC_STATE_ACK, or they ignore the request (ETG.1000.6)
    states = master("state", AlState.OP | 0x10, 10.0)
    assert [s & 0x1F for s, _ in states] == [AlState.OP] * 4, states
    session.stage = Stage.OP


def test_fastcat_fault_reaches_the_master_as_the_seed_emergency(session: SoemLine):
    """Seed 000 §7.1: 'CoE - Emergency (Hex: ff00, 81, 02 00 00 04 00)'."""
    runtime, master = session.at_least(Stage.OP).runtime, session.master
    session.left(Stage.MAPPED)  # the FastCAT in fault: a test that needs OP brings it up again
    model_call(runtime, lambda: runtime.rig.apply("fastcat/2", "module_failure",
                                                  {"active": True}))
    try:
        got = master("emergency", 0, 5.0)
    finally:  # a sound module for the tests after: one that needs OP brings the line up again
        model_call(runtime, lambda: runtime.rig.apply("fastcat/2", "module_failure",
                                                      {"active": False}))
    assert got == (0xFF00, 0x81, 0x02, 0x0000, 0x0004)


def test_fastcat_address_check_compares_the_station_address_soem_gave_it(session: SoemLine):
    """Seed 000 §6.19: with 0x5301 = 1 the coupler compares its rotary switch (1 here, as the
    rig file's master_address) with «l'indirizzo logico assegnato dal master Ethercat», the
    configured station address SOEM's config_init wrote (0x1001): different, so OP is refused
    with CO_E_ADDRESS_MASTER_NOT_OK, emergency data 0x12000000 and AL status code 0x8012
    (§7.5, §7.7). SOEM cannot give a slave another address (its configadr is 0x1000 + n): the
    equal case is tests/wire/test_fastcat_address_wire.py's."""
    runtime, master = session.at_least(Stage.OP).runtime, session.master
    session.left(Stage.MAPPED)  # the FastCAT in PRE-OP with 0x12: brought up again from a scan
    master("drain")
    state, _ = master("slave_state", 0, AlState.SAFEOP | 0x10, STATE_TIMEOUT_S)
    assert state & 0x1F == AlState.SAFEOP
    master("sdo_write", 0, 0x5301, 0, b"\x01")
    try:
        state, al_status = master("slave_state", 0, AlState.OP, 3.0)
        got = master("emergency", 0, 5.0)
    finally:  # the check off again for the tests after
        master("sdo_write", 0, 0x5301, 0, b"\x00")
    assert (state & 0x0F, state & 0x10, al_status) == (AlState.PREOP, 0x10, 0x8012)
    assert got == (0xFF00, 0x81, 0x00, 0x0000, 0x0012)  # data 00 00 00 12 00
    alarm = model_call(runtime, lambda: runtime.rig.snapshot()["devices"]["fastcat"]["alarm"])
    assert (alarm["code"], alarm["name"]) == (0x12, "ADDRESS_MASTER_NOT_OK")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_app_serves_the_default_rig_on_the_wire(tmp_path):
    """`python -m app --ethercat-if IFACE --rig static/rigs/default.toml`: every slave of the
    default line found with its name and identity, mapped, in OP, cycling without errors."""
    rig = ROOT / "static" / "rigs" / "default.toml"
    descriptions = esi_descriptions(rig)
    names = [d.name for d in descriptions]
    with veth_pair("d") as (master_if, slave_if):
        app = subprocess.Popen(
            [sys.executable, "-m", "app", "--ethercat-if", slave_if, "--rig", str(rig),
             "--port", str(free_port()), "--modbus-port", str(free_port()), "--no-record",
             "--state-dir", str(tmp_path), "--run-for", "120"],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        with contextlib.suppress(OSError):  # see favoured(): before the app starts threads
            os.setpriority(os.PRIO_PROCESS, app.pid, A_NICE)
        master = None
        try:
            wait_for_line(app, "EtherCAT wire on", 60)
            master = Master(master_if)
            n, slaves = master("init")
            assert (n, [s[0] for s in slaves]) == (len(names), names)
            states = master("state", AlState.PREOP, 20.0)  # the FastCAT may still be scanning
            assert [s & 0x1F for s, _ in states] == [AlState.PREOP] * n, states
            master("drain")  # e.g. the drive's 0x8700 sync timeout, sent before we came
            # The TRS-CAT's 0xF030 (integrated, TRS-IO-E, TRS-AN-E): the master's start-up
            # writes it (seed 001 §9.2 PS); the rig file's `configured` is the built-in one's.
            trs_list = [(1, 0xF030, sub, data) for sub, data in enumerate(
                (b"\x03", *(struct.pack("<I", i) for i in (0x494F2D42, 0x494F2D45, 0x414E2D45))))]
            expected, errors = master("map", [i for i, d in enumerate(descriptions)
                                              if d.dc_supported], trs_list)
            assert errors == [] and expected == 3 * n
            states = master("state", AlState.OP, 10.0)
            assert [s & 0x1F for s, _ in states] == [AlState.OP] * n, states
            check_cycles(master("cycles", CI_CYCLES, PERIOD_S, {}), CI_CYCLES, expected, False)
        finally:
            if master is not None:
                master.close()
            app.terminate()
            app.wait(timeout=20)


def esi_descriptions(rig_path: Path):
    from app.ethercat_wire.esi import rig_descriptions

    return rig_descriptions(build_rig(load_rig_spec(rig_path)))


def wait_for_line(proc: subprocess.Popen, text: str, timeout_s: float) -> None:
    end, seen = time.monotonic() + timeout_s, []
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line and proc.poll() is not None:
            break
        seen.append(line)
        if text in line:
            return
    raise AssertionError(f"the app did not print {text!r}: {''.join(seen)[-2000:]}")


def until(check: Callable[[], object], what: str, timeout_s: float = DEADLINE_S) -> object:
    """Poll ``check`` until it gives something true, and return it. What A sends B goes at A's
    next simulation step and B's counts come back in batches: on a loaded machine either may
    take long, so the test waits for the sign, never for a fixed time."""
    deadline = time.monotonic() + timeout_s
    while not (got := check()):
        assert time.monotonic() < deadline, f"not within {timeout_s} s: {what}"
        time.sleep(0.02)
    return got


def counted(runtime: Runtime) -> tuple[list[dict], int]:
    """The ESC counters of every slave and the frames B reported spoiled, read in one step."""
    def read() -> tuple[list[dict], int]:
        panel = runtime.rig.snapshot()["devices"]["master"]
        return [s["esc_errors"] for s in panel["slaves"]], runtime.rig.devices["master"].lost_frames
    return model_call(runtime, read)


def test_a_damaged_cable_loses_the_masters_frames_and_the_escs_count_them(session: SoemLine):
    """The dashboard damages cable 1 (into the TRS-CAT), every crossing spoiled: none of the
    master's frames comes back and the ESC counters count each as in embedded mode
    (docs/ethercat-master.md "Damaged cable": the TRS-CAT first to receive it, invalid on
    port 0 and marked; the slaves after it forwarded on port 0, the processing units of
    positions 1-3; forwarded on port 1 on the way back). Repaired: the frames come back.
    The outage is long enough for the slaves to react (the TRS-CAT's missed SM events, seed
    001 §9.3.7): only lost frames are checked after it, not working counters."""
    runtime, master = session.at_least(Stage.MAPPED).runtime, session.master
    session.left(Stage.MAPPED)  # the slaves may leave OP during the outage
    before, lost = counted(runtime)
    model_call(runtime, lambda: runtime.rig.apply("master", "damage_cable",
                                                  {"cable": 1, "percent": 100}))

    def spoiling() -> bool:  # B has the damage once it reports a spoiled frame
        master("cycles", 5, PERIOD_S, {})
        return counted(runtime)[1] > lost

    try:
        until(spoiling, "B spoils the frames crossing cable 1")
        c = master("cycles", 20, PERIOD_S, {})
    finally:  # repaired whatever happened: a cable left damaged would fail every test after
        model_call(runtime, lambda: runtime.rig.apply("master", "repair_cable", {"cable": 1}))
    assert len(c.lost) == 20 and c.wrong == [], c

    def all_counted() -> tuple[list[dict], int] | None:
        """B's batches (every 10 ms) and its statistics (every 100 ms) agree on the spoiled
        frames, the cycles' 20 among them."""
        after, now_lost = counted(runtime)
        n = after[1]["invalid"][0] - before[1]["invalid"][0]
        return (after, n) if n >= 20 and now_lost - lost == n else None

    after, n = until(all_counted, "B's counts of the spoiled frames reach the model")
    delta = [{k: [a - b for a, b in zip(x[k], y[k], strict=True)] for k in
              ("invalid", "forwarded")} | {"epu": x["epu"] - y["epu"]}
             for x, y in zip(after, before, strict=True)]
    assert [d["invalid"] for d in delta] == [[0, 0], [n, 0], [0, 0], [0, 0]]
    assert [d["forwarded"] for d in delta] == [[0, n], [0, n], [n, n], [n, 0]]
    assert [d["epu"] for d in delta] == [0, n, n, n]
    c = master("cycles", 200, PERIOD_S, {})
    assert len(c.lost) <= 200 * CI_LOST_PER_1000 // 1000, c.lost


def wkc_errors(runtime: Runtime) -> int:
    """B's count of short working counters, as the master panel shows it (its first slave)."""
    panel = model_call(runtime, lambda: runtime.rig.snapshot()["devices"]["master"])
    return panel["slaves"][0]["counters"]["wkc_errors"]


def test_a_pulled_cable_makes_slaves_vanish_from_the_wire(session: SoemLine):
    """The dashboard pulls cable 2 (into the CPX-E-EC): the CPX-E-EC and the drive vanish, the
    master's working counter falls short and the master panel counts the WKC errors; plugged
    back, the frames are whole again. It leaves the line scanned again, not mapped."""
    runtime, master = session.at_least(Stage.MAPPED).runtime, session.master
    session.left(Stage.NONE)  # two slaves gone: a test that needs the line scans it again
    before = wkc_errors(runtime)
    model_call(runtime, lambda: runtime.rig.apply("master", "pull_cable", {"cable": 2}))
    try:  # B has the cut once a frame comes back short
        until(lambda: master("cycles", 1, PERIOD_S, {}).wrong, "B cuts the line at cable 2")
        c = master("cycles", 50, PERIOD_S, {})
        # B's count of every short frame it answered, on the panel (reported every 100 ms)
        until(lambda: wkc_errors(runtime) - before >= 50, "B's WKC errors reach the panel")
    finally:  # plugged back whatever happened: the tests after need the whole line
        model_call(runtime, lambda: runtime.rig.apply("master", "plug_cable", {"cable": 2}))
    assert len(c.wrong) + len(c.lost) == 50 and c.wrong, c  # short WKC: the slaves behind are gone
    assert all(wkc < EXPECTED_WKC for _, wkc in c.wrong)
    # a master re-scans after a topology change, again until B has the cable back
    until(lambda: master("init")[0] == 4, "the scan finds the 4 slaves with cable 2 plugged")
    n, _ = session.init()
    assert n == 4
