"""What the bridge keeps per slave of the line: its face, CoE server, frame clock, and what
process B was last told of it (AL status, SM3 image, alias, ESC error counters) and the station
address B last reported."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from app.ethercat_wire.coe import CoeServer
from app.ethercat_wire.faces import Face
from app.ethercat_wire.frame_clock import FrameClock


@dataclass
class WireSlave:
    position: int
    model: Any
    face: Face
    coe: CoeServer
    status: tuple[int, int] | None = None  # last AL status / code sent
    inputs: bytes | None = None  # last SM3 image sent
    # (starts, configured station alias) B was last told (the description's, then sent): a new
    # start reloads 0x0012 (None: from the stored SII word 4)
    alias: tuple[int, int | None] | None = None
    # the configured station address (0x0010) the wire master last wrote, as B reported it
    # (None: none yet; B's ESC powers up with 0): given again to a model reset in place
    station: int | None = None
    inputs_due_us: int = 0
    esc_errors: bytes = bytes(20)  # 0x0300-0x0313 last sent (B powers on with zeros)
    clock: FrameClock = field(default_factory=lambda: FrameClock())

