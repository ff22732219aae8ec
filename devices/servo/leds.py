"""The drive's network LEDs (seed 004 ch. 5 "Connessioni e Leds Drive EtherCAT").

"L/A verde: Link Active rete ethernet"; "Status verde: segnalazione dello stato ethercat";
"Error rosso: segnalazione warning/allarmi in ethercat". They are on the drive's front, so the
drive owns them and shows them in its snapshot (``leds``) whatever its fieldbus; only its
EtherCAT slave (devices/coe/drive_slave.py) drives them: on Modbus or CANopen they stay dark.
"""

from __future__ import annotations

from devices.leds import LedBank, LedPattern

LINK = "L/A"
STATUS = "Status"
ERROR = "Error"
NETWORK_LEDS = (LINK, STATUS, ERROR)


def network_leds(device_id: str) -> LedBank:
    """The bank of a drive's network LEDs, every one dark (no event: dark is the default)."""
    return LedBank(device_id, dict.fromkeys(NETWORK_LEDS, LedPattern.OFF))
