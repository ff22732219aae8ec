"""Where and how the rig serves its drives' Modbus line: kept by the runtime for the views.

The drive is a Modbus RTU slave (seed 004 ch. 2: its c9 chooses the bus, c7 its node), but
FieldRig serves the line on TCP (docs/modbus.md): MBAP framing ("socket", Modbus TCP, the
default) or the RTU frames over TCP ("rtu"). A trainee must see both, or reaches for an RTU
adapter the rig does not speak (the Drive tab's title says them, app/ui/drive/drive_state.py).
"""

from __future__ import annotations

from dataclasses import dataclass

# --modbus-framer's values (app.modbus.server.FRAMERS) in a trainee's words.
FRAMING_WORDS = {"socket": "Modbus TCP", "rtu": "Modbus RTU over TCP"}


@dataclass(frozen=True)
class ServedLine:
    framing: str  # "socket" or "rtu"
    port: int  # the port the server listens on (the real one: --modbus-port 0 picks any)

    def words(self) -> str:
        """``served as Modbus TCP on :5020``."""
        return f"served as {FRAMING_WORDS.get(self.framing, self.framing)} on :{self.port}"
