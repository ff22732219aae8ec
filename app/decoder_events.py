"""Seed 003's events by name for the Codes tab: "the status change of slaves", ..., "the
network recovery event", as the seed lists them, and the PLC tasks ECAT_Notify / ECAT_Resync.

The names and words are the master's table (``devices.master.hooks.SEED_EVENTS``,
``NOTIFY_TEXT``); this module only finds one in what a trainee types: the seed's name with or
without its article and "event(s)" ("network recovery", "resync", "communication error"), or
the event's name in FieldRig's log and ``[[on]]`` tables ("network_recovery", "dc_state").
"""

from __future__ import annotations

import re

from app.decoder_meaning import Meaning
from app.decoder_states import MASTER
from devices.master.hooks import NOTIFY_TEXT, SEED_EVENTS, SeedEvent

SOURCE = "seed 003"
NOTIFY = "ECAT_Notify"


def _key(text: str) -> str:
    """``The network recovery event`` -> ``network recovery``; ``comm_error`` -> ``comm
    error``; a plural's ``s`` goes on every word, so ``errors`` and ``error`` meet."""
    words = re.sub(r"[\s_'\"]+", " ", text).strip().lower().split()
    for lead in (["and", "finally"], ["the"]):
        if words[:len(lead)] == lead:
            words = words[len(lead):]
    if words and words[-1] in ("event", "events"):
        words = words[:-1]
    if words[:1] == ["ecat"]:  # ECAT_Resync, the task of the resync events
        words = words[1:]
    return " ".join(w.removesuffix("s") for w in words)


_BY_KEY: dict[str, SeedEvent] = {
    **{_key(e.kind): e for e in SEED_EVENTS},
    **{_key(e.name): e for e in SEED_EVENTS},
}


def event_readings(text: str) -> list[Meaning]:
    """The seed 003 event ``text`` names; [] when it names none."""
    key = _key(text)
    if not key:
        return []
    if key == _key(NOTIFY):
        return [Meaning(MASTER, NOTIFY, f"{NOTIFY_TEXT[:1].upper()}{NOTIFY_TEXT[1:]}. The "
                        f"events: {'; '.join(e.name for e in SEED_EVENTS)}.", SOURCE)]
    event = _BY_KEY.get(key)
    if event is None:
        return []
    return [Meaning(MASTER, f'Master event "{event.name}"',
                    f"{event.name}: {event.text}. {_where(event)}; it runs the PLC task "
                    f"{NOTIFY}.", SOURCE)]


def _where(event: SeedEvent) -> str:
    if event.logged:
        return f"In the event log: `{event.logged}`; in an [[on]] table: `{event.kind}`"
    return f"In the event log and an [[on]] table: `{event.kind}`"
