"""The Codes tab's Reported list after a scenario load (review item: the page went white for
good during the second Play of "Module 2 stops answering in OP").

A load puts the clock back to 0 and the scenario reports the same codes at the same times, so
the list held "6.0 s fastcat emergency FF00 81 02 00 00 04 00" twice. viser's dropdown is a
Mantine Select, which throws on duplicate options ("[@mantine/core] Duplicate options are not
supported") once the Codes tab has been shown: React unmounts the whole page. Now the list
starts afresh at every load, as the event log does, and never holds a label twice. The load
is signalled by the player (its generation and the journal's number at the load), not read
from the clock going back: a load at 0 s (Restart before Play) put nothing back and the old
run's codes stayed (the tests below load with ``_Runtime.load``, what Player.load does).
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import viser

from app.screenshots import free_port
from app.ui.panels.decoder import DecoderPanel
from devices.events import AlStatusChanged, EmergencySent, Event

EMCY = EmergencySent(6_000_000, "fastcat", code=0xFF00, register=0x81, data=b"\x02\0\0\x04\0")
LABEL = "6.0 s fastcat emergency FF00 81 02 00 00 04 00"


class _Runtime:
    """What the panel reads of a runtime: the journal."""

    def __init__(self) -> None:
        self.journal: list[Event] = []
        self.generation = 0
        self.load_seq = 0

    def events_since(self, seq: int) -> tuple[int, list[Event]]:
        return len(self.journal), self.journal[seq:]

    def load(self) -> None:
        """A scenario load (Player.load): the events journalled from now on are its run."""
        self.generation += 1
        self.load_seq = len(self.journal)

    def last_load(self) -> tuple[int, int]:
        return self.generation, self.load_seq


@pytest.fixture
def panel() -> Iterator[tuple[DecoderPanel, _Runtime]]:
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    runtime = _Runtime()
    try:
        yield (DecoderPanel(server, runtime, None, runtime.last_load),  # type: ignore[arg-type]
               runtime)
    finally:
        server.stop()


def test_a_replayed_run_never_lists_a_code_twice(panel: tuple[DecoderPanel, _Runtime]) -> None:
    decoder, runtime = panel
    runtime.journal += [EMCY, AlStatusChanged(6_000_000, "fastcat", code=0x8204)]
    decoder.update()
    assert decoder._picker.options[0] == "6.0 s fastcat AL status code 0x8204"
    # The scenario loaded again: the clock back at 0, the same codes at the same times.
    runtime.load()
    runtime.journal += [AlStatusChanged(100_000, "trscat", code=0x001B), EMCY]
    decoder.update()
    options = list(decoder._picker.options)
    assert len(options) == len(set(options)), options
    # Only the new run's codes, newest first.
    assert options == [LABEL, "0.1 s trscat AL status code 0x001B"]
    assert decoder._picker.value == LABEL


def test_the_same_label_twice_in_one_run_is_listed_once(
        panel: tuple[DecoderPanel, _Runtime]) -> None:
    """Two emergencies within a tenth of a second read the same label: one option, newest."""
    decoder, runtime = panel
    runtime.journal += [EMCY, EmergencySent(6_040_000, "fastcat", code=0xFF00, register=0x81,
                                            data=b"\x02\0\0\x04\0")]
    decoder.update()
    assert list(decoder._picker.options) == [LABEL]


def test_a_new_run_without_codes_yet_empties_the_list(
        panel: tuple[DecoderPanel, _Runtime]) -> None:
    from app.ui.panels.decoder import NONE
    from devices.events import Caption

    decoder, runtime = panel
    runtime.journal.append(EMCY)
    decoder.update()
    runtime.load()
    runtime.journal.append(Caption(0, "scenario", text="The rig is switched on."))
    decoder.update()
    assert list(decoder._picker.options) == [NONE] and decoder._picker.value == NONE


def test_a_load_at_0_s_starts_the_list_afresh(panel: tuple[DecoderPanel, _Runtime]) -> None:
    """A code reported at 0 s, then another scenario loaded before the clock moved: no time
    went back, and the first run's code stayed listed under the new run."""
    from app.ui.panels.decoder import NONE
    from devices.events import Caption

    decoder, runtime = panel
    runtime.journal.append(AlStatusChanged(0, "trscat", code=0x001B))
    decoder.update()
    assert list(decoder._picker.options) == ["0.0 s trscat AL status code 0x001B"]
    runtime.load()
    runtime.journal.append(Caption(0, "scenario", text="The rig is switched on."))
    decoder.update()
    assert list(decoder._picker.options) == [NONE] and decoder._picker.value == NONE


def test_the_old_runs_codes_in_the_same_batch_stay_out(
        panel: tuple[DecoderPanel, _Runtime]) -> None:
    """The old run's last code and the new run's first taken in one update: the load splits
    the batch where it happened (Restart before Play, all at 0 s)."""
    decoder, runtime = panel
    runtime.journal.append(AlStatusChanged(0, "trscat", code=0x001B))
    runtime.load()
    runtime.journal.append(AlStatusChanged(0, "fastcat", code=0x8204))
    decoder.update()
    assert list(decoder._picker.options) == ["0.0 s fastcat AL status code 0x8204"]
