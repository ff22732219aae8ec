"""The master's cheaper step is the same step (docs/ethercat-master.md "Step cost", issue 7).

Three shortcuts: the step's loop uses rows made once (each slave's bound ``reachable``,
``exchange_frame``, ``take_emergencies``, its position and DC use) instead of looking them up
on every link each cycle, it reads ``slave.esm.state`` for a slave whose ``al_state`` is
AlStatusView's property (what the property returns, without its call), and ``_line`` reads
the slaves' power with ``map(getattr, ...)`` instead of a list comprehension. Differential: a
master that rebuilds the rows from its links before every step (al_state read through the
property) and reads the power with the comprehension (the plain path) against the normal one,
on two default rigs driven by the same seeded random commands; every step's events, the
snapshots, the master's counters and its rng compared.
"""

from __future__ import annotations

import random
from typing import Any

import pytest

from app.rig import Rig
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from devices.device import CommandError
from devices.master import EtherCatMaster

BOOT_STEPS = 4500  # power-on to every slave in OP takes about 3.5 s


class PlainMaster(EtherCatMaster):
    """Every lookup made anew each step, as before the shortcuts."""

    def step(self, now_us: int) -> None:
        self._rows = tuple((link, link.position, link.slave, link.slave.reachable,
                            link.slave.exchange_frame, link.slave.take_emergencies, link.dc,
                            False)  # al_state through the slave's property
                           for link in self.links)
        super().step(now_us)

    def _line(self, skip: bool) -> list[bool]:
        powered = [getattr(slave, "powered", True) for slave in self._slaves]
        plugs = [getattr(slave, "plugs", (True, True)) for slave in self._slaves]
        if skip and powered == self._line_powered and plugs == self._line_plugs \
                and self.cables == self._line_cables:
            self.skipped.line += 1
            return self._line_reach
        self._apply_physical_links([bool(on) for on in powered], plugs)
        return self._line_reach


def rig(plain: bool) -> Rig:
    out = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    if plain:
        out.devices["master"].__class__ = PlainMaster
    return out


def master_state(r: Rig) -> dict[str, Any]:
    m = r.devices["master"]
    assert isinstance(m, EtherCatMaster)
    return {"snapshot": m.snapshot(), "skipped": m.skipped, "frames": m.frames,
            "rng": m.rng.getstate(), "phys": (m.phys_in, m.phys_out),
            "dc": m.dc, "watched": m._watched,
            "links": [(link.present, link.believed, link.pending, link.next_try_us,
                       link.seen, link.reached_op, link.counters) for link in m.links]}


OPERATIONS = (
    ("master", "pull_cable", lambda g: {"cable": g.randrange(4)}),
    ("master", "plug_cable", lambda g: {"cable": g.randrange(4)}),
    ("master", "power_slave", lambda g: {"position": g.randrange(4), "on": g.random() < 0.6}),
    ("master", "lose_frames", lambda g: {"count": g.randrange(1, 20)}),
    ("master", "dc_fault", lambda g: {"kind": g.choice(("drift", "jitter", "sync0_lost"))}),
    ("master", "clear_dc_fault", lambda g: {}),
    ("master", "resync", lambda g: {}),
    ("master", "set_target", lambda g: {"state": g.choice(("PREOP", "SAFEOP", "OP", "OP"))}),
    # The slaves' own plugs, folded into the line (and into _line's skip key).
    ("trscat", "link", lambda g: {"port": g.choice(("in", "out")), "connected": g.random() < .6}),
    ("cpx", "cable", lambda g: {"port": g.choice(("in", "out")), "connected": g.random() < .6}),
)


@pytest.mark.parametrize("seed", [1, 2])
def test_rows_and_mapped_power_match_the_plain_step(seed: int) -> None:
    """Random master commands (seed 003 line faults, DC faults, resync, targets) with idle
    stretches: the fast and the plain master give the same events at every step."""
    fast, plain = rig(False), rig(True)
    for _ in range(BOOT_STEPS):
        assert fast.step() == plain.step()
    g = random.Random(seed)
    for _ in range(40):
        device, action, args = g.choice(OPERATIONS)
        values = args(g)
        outcomes = []
        for r in (fast, plain):
            try:
                r.apply(device, action, values)
                outcomes.append(None)
            except CommandError as error:
                outcomes.append(str(error))
        assert outcomes[0] == outcomes[1]
        for _ in range(g.choice((1, 5, 50, 300))):
            assert fast.step() == plain.step()
        assert master_state(fast) == master_state(plain)
    skipped = fast.devices["master"].skipped
    assert skipped.serve and skipped.line and skipped.watch  # the shortcuts were taken


class NoPower:
    """A slave without a ``powered`` attribute: getattr's default (True) applies."""


class IntPower:
    powered = 1  # == True, compared by value as the comprehension compares it


@pytest.mark.parametrize("slaves", [(NoPower(),), (IntPower(), NoPower()), ()])
def test_mapped_getattr_equals_the_comprehension(slaves: tuple[object, ...]) -> None:
    names, defaults = ("powered",) * len(slaves), (True,) * len(slaves)
    mapped = list(map(getattr, slaves, names, defaults))
    assert mapped == [getattr(s, "powered", True) for s in slaves]
    assert [type(v) for v in mapped] == [type(getattr(s, "powered", True)) for s in slaves]


def test_every_default_slave_reads_its_state_without_the_property() -> None:
    """The ESM read applies to the four slaves of the default line (the shortcut is taken),
    and gives what the property gives."""
    r = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    m = r.devices["master"]
    assert isinstance(m, EtherCatMaster)
    assert [row[7] for row in m._rows] == [True] * 4
    for _ in range(BOOT_STEPS):
        r.step()
        assert [link.slave.esm.state for link in m.links] == [  # type: ignore[attr-defined]
            link.slave.al_state for link in m.links]
