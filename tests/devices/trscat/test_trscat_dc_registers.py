"""DC-SYNC on the master's DC registers (seed 001 §9.1.1: SYNC0 from the reference clock, the
ESC's sync registers 0x980 / 0x981; §9.2 IP "il master inizializza il DC clock sync", PS
"verifica la correttezza ... del DC"; §9.3.1 0x1C32:2 / :5; §9.3.7 0x10F1:2 = 3).

SYNC0 runs on 0x09A0 as written by the master, not on the gaps between the frames: frames that
come irregularly (a lagging simulation hands two in consecutive steps, then none) do not change
the cycle; frames that really miss SYNC0 events still make the sync error."""

from __future__ import annotations

import itertools

import pytest
from trscat_bench import Bench

from devices.ethercat import AlState
from devices.trscat.sync import SYNC0_ACTIVE, SYNC_ERROR_LIMIT, SyncState

CYCLE_4MS_NS = 4_000_000


class Irregular(Bench):
    """A master cycling every ``cycle_us`` whose frames reach the device at chosen times."""

    def __init__(self, cycle_us: int, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.cycle_us = cycle_us
        self.pattern: list[int] = []  # offsets (us) of the frames in each cycle, or []
        self.frames = False  # this bench hands the frames itself

    def request(self, target: AlState) -> None:
        if target in (AlState.PREOP, AlState.SAFEOP):
            self.configure_dc(SYNC0_ACTIVE, self.cycle_us * 1000)
        self.trs.request_state(target)
        self._collect()

    def to_state(self, target: AlState) -> None:
        """Up to ``target`` with valid outputs for a while before SO, as a PLC does."""
        self.settle()
        for state in (AlState.PREOP, AlState.SAFEOP, AlState.OP):
            self.request(state)
            self.run(0.05)
            assert self.trs.al_state is state, f"0x{self.trs.al_status_code:04X}"
            if state is target:
                return

    def step(self) -> None:
        super().step()
        phase = self.now % self.cycle_us
        for offset in self.pattern or [0]:
            if phase == offset:
                self.trs.exchange_frame(self.now)
        self._collect()


def test_sync0_follows_0x09a0_not_the_frame_gaps() -> None:
    """The wire's case: the master cycles at 4 ms, but the frames reached the model in two
    consecutive 1 ms steps before PS. SYNC0 and 0x1C32:2 are 4 ms; OP is reached and kept."""
    bench = Irregular(4000)
    bench.settle()
    bench.request(AlState.PREOP)
    bench.pattern = [0, 1000]  # two frames 1 ms apart in each cycle ...
    bench.run(0.02)
    bench.run_until(lambda: bench.now % 4000 == 1000)
    bench.request(AlState.SAFEOP)  # ... and PS right after the second
    bench.pattern = [0]
    assert bench.trs.al_state is AlState.SAFEOP
    assert bench.read(0x1C32, 2) == bench.read(0x1C33, 2) == CYCLE_4MS_NS
    bench.run(0.05)
    bench.request(AlState.OP)
    bench.run(0.5)
    assert bench.trs.al_state is AlState.OP and bench.read(0x1C32, 11) == 0
    assert [t2 - t1 for t1, t2 in _sync0_times(bench, 0.02)] == [4000] * 4


def _sync0_times(bench: Bench, seconds: float) -> list[tuple[int, int]]:
    times = []
    unit = bench.trs.sync
    end = bench.now + round(seconds * 1_000_000)
    while bench.now < end:
        before = unit.next_sync0_us
        bench.step()
        if unit.next_sync0_us != before:
            times.append(before)
    return list(itertools.pairwise(times))


@pytest.mark.parametrize(("pattern", "falls"), [
    ([0], False),  # one frame per cycle
    ([0, 1000], False),  # two in each cycle (a burst)
    ([3000], False),  # late in the cycle, still > calc+copy before SYNC0
])
def test_irregular_frames_within_each_cycle_keep_op(pattern: list[int], falls: bool) -> None:
    """§9.1.1: one SM2 event per SYNC0 is all DC-SYNC needs, wherever in the cycle it comes."""
    bench = Irregular(4000)
    bench.pattern = pattern
    bench.to_state(AlState.OP)
    bench.run(0.5)
    assert (bench.trs.al_state is AlState.SAFEOP) is falls
    assert bench.read(0x1C32, 2) == CYCLE_4MS_NS


@pytest.mark.parametrize("cycle_us", [1000, 4000])
@pytest.mark.parametrize("missed", [SYNC_ERROR_LIMIT - 1, SYNC_ERROR_LIMIT])
def test_frames_that_miss_sync0_still_make_the_sync_error(cycle_us: int, missed: int) -> None:
    """§9.3.1 0x1C32:11 / §9.3.7 0x10F1:2 = 3: with SYNC0 on the configured cycle, 3 cycles
    without a frame are 3 missed SM events: OP -> SAFE-OP, AL 0x001A; 2 are not."""
    bench = Irregular(cycle_us)
    bench.to_state(AlState.OP)
    bench.run(0.1)
    bench.apply("drop_frames", count=missed)
    bench.run(cycle_us * (missed + 2) / 1e6)
    if missed < SYNC_ERROR_LIMIT:
        assert bench.trs.al_state is AlState.OP
    else:
        assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.SAFEOP, 0x001A)


def _ps_with(bench: Bench, activation: int, cycle_ns: int) -> None:
    """A master that writes the Sync Control register (0x0981, high byte of the 0x0980 word)
    and the SYNC0 cycle in PRE-OP, then asks for SAFE-OP."""
    bench.settle()
    bench.request(AlState.PREOP)
    bench.configure_dc(activation, cycle_ns)
    bench.request(AlState.SAFEOP)


@pytest.mark.parametrize(("activation", "cycle_ns", "code"), [
    (0x00, CYCLE_4MS_NS, None),  # 0x0980 = 0x0000: FREE-RUN (the cycle is not used)
    (0x01, CYCLE_4MS_NS, 0x0030),  # cyclic operation without SYNC0
    (0x02, CYCLE_4MS_NS, 0x0030),  # SYNC0 without cyclic operation
    (SYNC0_ACTIVE, 0, 0x0030),  # SYNC0 activated without a cycle
    (SYNC0_ACTIVE, 499_000, 0x002E),  # below 0x1C32:5 = 500000 ns
    (SYNC0_ACTIVE, 500_000, None),
    (SYNC0_ACTIVE | 0x04, CYCLE_4MS_NS, 0x0030),  # 0x0700: SYNC1 too, not in 0x1C32:4
])
@pytest.mark.parametrize("rig_mode", ["dc", "free_run"])
def test_ps_checks_the_dc_registers(rig_mode: str, activation: int, cycle_ns: int,
                                    code: int | None) -> None:
    """§9.2 PS: "TRS-CAT verifica la correttezza ... del DC"; §9.1.1: 0x980 = 0x0300 is
    DC-SYNC, 0x0000 FREE-RUN, whatever the rig's master option (``sync_mode``) says."""
    bench = Bench(dc=False, sync_mode=rig_mode)
    _ps_with(bench, activation, cycle_ns)
    if code is None:
        assert bench.trs.al_state is AlState.SAFEOP
        assert bench.read(0x1C32, 2) == (cycle_ns if activation else 500_000)
    else:
        assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.PREOP, code)
        assert bench.messages()[-1]["code"] == f"0x{code:04X}"


@pytest.mark.parametrize("rig_mode", ["dc", "free_run"])
@pytest.mark.parametrize(("activation", "mode", "sync_control", "label", "cycle_ns"), [
    (SYNC0_ACTIVE, 0x0002, 0x0300, "DC-SYNC", CYCLE_4MS_NS),
    (0x00, 0x0000, 0x0000, "FREE-RUN", 500_000),
])
def test_the_sync_control_register_sets_the_mode(rig_mode: str, activation: int, mode: int,
                                                 sync_control: int, label: str,
                                                 cycle_ns: int) -> None:
    """§9.1.1: "Il modo di sincronizzazione può essere cambiato mediante il Sync Control
    Register del ESC (registri 0x980 e 0x981). Tale modalità è riportata negli oggetti 0x1C32 e
    0x1C33": the mode taken at PS is the register's, shown in 0x1C32:1 / 0x1C33:1 and in the
    snapshot next to the register (0x0981 is the high byte of the 0x0980 word)."""
    bench = Bench(dc=False, sync_mode=rig_mode)
    _ps_with(bench, activation, CYCLE_4MS_NS)
    assert bench.trs.al_state is AlState.SAFEOP
    assert bench.read(0x1C32, 1) == bench.read(0x1C33, 1) == mode
    assert bench.read(0x1C32, 2) == bench.read(0x1C33, 2) == cycle_ns
    sync = bench.trs.snapshot()["sync"]
    assert (sync["mode"], sync["sync_control"], sync["dc_activation"]) == \
        (label, sync_control, activation)
    assert bench.trs.sync.running is (mode == 0x0002)


def test_the_mode_is_taken_again_at_every_ps() -> None:
    """A master that changes its configuration between two start-ups: SAFE-OP -> PRE-OP, the
    register rewritten, PS again: the new mode."""
    bench = Bench(dc=False)
    _ps_with(bench, SYNC0_ACTIVE, CYCLE_4MS_NS)
    assert bench.read(0x1C32, 1) == 0x0002
    bench.request(AlState.PREOP)
    bench.configure_dc(0x00, 0)
    bench.request(AlState.SAFEOP)
    assert bench.trs.al_state is AlState.SAFEOP
    assert (bench.read(0x1C32, 1), bench.read(0x1C32, 2)) == (0x0000, 500_000)
    bench.run(0.05)
    bench.request(AlState.OP)
    bench.run(0.2)
    assert bench.trs.al_state is AlState.OP and bench.trs.sync.state is SyncState.FREE_RUN


def test_power_up_mode_is_dc_sync_whatever_the_rig() -> None:
    """§9.1.1 "La modalità DC-SYNC ... è quella di default": before the first PS 0x1C32:1 reads
    0x0002 (the register, 0 at power-up, is taken at PS)."""
    for rig_mode in ("dc", "free_run"):
        bench = Bench(sync_mode=rig_mode)
        bench.settle()
        assert bench.read(0x1C32, 1) == bench.read(0x1C33, 1) == 0x0002


@pytest.mark.parametrize(("written", "activation", "code"), [
    (0x0002, SYNC0_ACTIVE, None), (0x0000, 0x00, None),
    (0x0000, SYNC0_ACTIVE, 0x0030),  # FREE-RUN asked in 0x1C32:1, SYNC0 activated
    (0x0002, 0x00, 0x0030),  # DC-SYNC asked, 0x0980 left at 0x0000
])
@pytest.mark.parametrize("index", [0x1C32, 0x1C33])
def test_a_written_sync_mode_must_agree_with_the_register(index: int, written: int,
                                                          activation: int,
                                                          code: int | None) -> None:
    """0x1C32:1 / 0x1C33:1 are RW (§9.3.1): a master may write the mode it configured in
    PRE-OP; PS then checks it against the Sync Control register (ETG.1020, as the ETG slave
    stack does), 0x0030 when they disagree."""
    bench = Bench(dc=False)
    bench.settle()
    bench.request(AlState.PREOP)
    bench.write(index, 1, written)
    bench.configure_dc(activation, CYCLE_4MS_NS)
    bench.request(AlState.SAFEOP)
    if code is None:
        assert bench.trs.al_state is AlState.SAFEOP and bench.read(0x1C32, 1) == written
    else:
        assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.PREOP, code)
        assert bench.read(0x1C32, 1) == written  # what the master wrote stays readable
        text = bench.messages()[-1]["text"]
        assert f"0x1C32:1 = 0x{written:04X}" in text
        assert f"0x0980 = 0x{activation << 8:04X}" in text


def test_a_written_sync_mode_is_forgotten_in_init() -> None:
    """Back in INIT the master's PRE-OP settings are gone: the register alone decides again."""
    bench = Bench(dc=False)
    bench.settle()
    bench.request(AlState.PREOP)
    bench.write(0x1C32, 1, 0x0000)
    bench.request(AlState.INIT)
    bench.request(AlState.PREOP)
    bench.run(0.01)
    _ps_with(bench, SYNC0_ACTIVE, CYCLE_4MS_NS)
    assert bench.trs.al_state is AlState.SAFEOP and bench.read(0x1C32, 1) == 0x0002


@pytest.mark.parametrize("first_ps", [False, True])
def test_a_forgotten_sync_mode_is_no_longer_reported(first_ps: bool) -> None:
    """§9.3.1 0x1C32:1 / 0x1C33:1 "Stato corrente del DC mode": once INIT has dropped the
    mode the master wrote in PRE-OP, they report the mode last taken at a PS again (DC-SYNC,
    the §9.1.1 default, before the first one), not the forgotten request."""
    bench = Bench(dc=False)
    bench.settle()
    bench.request(AlState.PREOP)
    if first_ps:  # FREE-RUN taken at a PS, then the master asks for DC-SYNC
        _ps_with(bench, 0x00, 0)
        assert bench.trs.al_state is AlState.SAFEOP
        bench.request(AlState.PREOP)
    taken = 0x0000 if first_ps else 0x0002
    bench.write(0x1C32, 1, 0x0002 - taken)
    assert bench.read(0x1C33, 1) == 0x0002 - taken  # reported at once
    bench.request(AlState.INIT)
    assert [bench.read(0x1C32, 1), bench.read(0x1C33, 1)] == [taken, taken]
    assert bench.trs.snapshot()["sync"]["mode"] == ("FREE-RUN" if first_ps else "DC-SYNC")


def test_sync0_switched_off_in_op_is_a_fatal_sync_error() -> None:
    """0x0981 = 0 while DC-SYNC runs: the SM events come without SYNC0; at 0x10F1:2 -> 0x002C
    (as lose_sync0)."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.configure_dc(0x00, 1_000_000)
    bench.run(0.01)
    assert (bench.trs.al_state, bench.trs.al_status_code) == (AlState.SAFEOP, 0x002C)
    assert bench.trs.sync.state is SyncState.SYNC0_LOST


def test_soem_reprogramming_keeps_op() -> None:
    """SOEM's dcsync0 writes 0x0981 = 0, then 0x0990 / 0x09A0, then 0x0981 = 3: a brief gap
    (fewer than 3 SM events) and SYNC0 runs on the new cycle."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.configure_dc(0x00, 1_000_000)
    bench.step()
    bench.configure_dc(SYNC0_ACTIVE, 2_000_000)
    bench.run(0.2)
    assert bench.trs.al_state is AlState.OP and bench.read(0x1C32, 2) == 2_000_000


def test_power_cycle_clears_the_registers() -> None:
    """The ESC's registers are 0 after power-up: the master writes them again on the way up."""
    bench = Bench()
    bench.to_state(AlState.OP)
    bench.apply("power", on=False)
    bench.apply("power", on=True)
    assert (bench.trs.sync.dc_activation, bench.trs.sync.dc_cycle_ns) == (0, 0)
    assert bench.trs.snapshot()["sync"]["sync0_cycle_ns"] == 0


@pytest.mark.parametrize("cycle_us", [1000, 4000])
def test_the_built_in_master_writes_its_cycle(cycle_us: int) -> None:
    """The built-in master configures a DC slave's registers from its own cycle (SYNC0 on,
    0x09A0 = the cycle) and the line reaches OP on it."""
    bench = Bench(master=True)
    assert bench.master is not None
    bench.master.cycle_us = cycle_us
    bench.run_until(lambda: bench.trs.al_state is AlState.OP)
    bench.run(0.5)
    assert bench.trs.al_state is AlState.OP
    assert (bench.trs.sync.dc_activation, bench.read(0x1C32, 2)) == (SYNC0_ACTIVE,
                                                                      cycle_us * 1000)


@pytest.mark.parametrize(("rig_mode", "master_dc", "mode"), [
    ("dc", False, 0x0000), ("free_run", True, 0x0002)])
def test_the_masters_dc_option_decides(rig_mode: str, master_dc: bool, mode: int) -> None:
    """§9.3 "Altre opzioni da settare nel master: ... la modalità in cui TRS-CAT deve
    funzionare": a master whose description does not use DC leaves 0x0981 = 0 and the line
    reaches OP in FREE-RUN; one that activates SYNC0 gets DC-SYNC (the rig's ``sync_mode`` is
    only what the built-in master does when no description says otherwise)."""
    bench = Bench(master=True, dc=master_dc, sync_mode=rig_mode)
    bench.run(3.0)
    assert bench.trs.al_state is AlState.OP
    assert bench.read(0x1C32, 1) == bench.read(0x1C33, 1) == mode
    assert bench.trs.snapshot()["sync"]["sync_control"] == (0x0300 if master_dc else 0)
