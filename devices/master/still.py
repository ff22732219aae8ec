"""What the master may leave out of a step, and the count of what it left out.

The master cannot skip whole steps: every cycle each reachable slave gets its frame
(``exchange_frame``: the slaves count frames and SM events), each slave's mailbox is emptied
(``take_emergencies``) and the DC unit draws its deviation from ``rng``. What it leaves out are
the parts that would change nothing (docs/ethercat-master.md "Still steps"):

- the line: the physical links and the reach of each position are a function of the cables and
  the slaves' power; with both as the last time they were applied, applying them again sets no
  link and gives the same reach;
- serving a slave (``startup._serve``) that has no emergency, no request pending, is in the
  state the master last confirmed, and is at its target or not due for a retry: ``_serve`` would
  do nothing (the test is inlined in ``EtherCatMaster.step``, the hot path); nor would it for a
  slave with no emergency whose request is still under way (``_check``: before the check delay,
  or not yet in the requested state, without the AL status error flag and before the state
  timeout, as while the FastCAT scans its internal bus at power-on), unless it is below both
  states of the request (``startup._left_pending``: it left on its own). Such a slave leaves the
  cycle quiet if its state is the watched one;
- watching the slaves' states (``_watch_states``) when every slave is present or absent and in
  the state it was the last time they were watched, and nothing reset what the watch keeps
  (``seen``, ``reached_op``, ``network_op``, presence): the watch would emit nothing;
- asking whether the DC slaves are in SAFEOP / OP outside WAITING_START_TIME, the one DC state
  whose trigger reads the answer;
- in a *quiet* cycle (every slave reachable, present and left unserved, each in the state the
  last watch kept, read right after its own frame and mailbox): building the watch's state list
  (it would be the kept one), and the DC unit's general step when it is COMPENSATING without a
  fault and the deviation falls in the window (``DcUnit.compensate`` does what ``measure`` and
  ``trigger`` would: one draw, ``outside`` back to 0).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class StillCounts:
    """How often each part was left out (tests check that skipping happened)."""

    line: int = 0
    serve: int = 0
    watch: int = 0
    dc: int = 0

