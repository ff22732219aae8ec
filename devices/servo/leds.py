"""The drive's network LEDs (seed 004 ch. 5 "Connessioni e Leds Drive EtherCAT").

"L/A verde: Link Active rete ethernet"; "Status verde: segnalazione dello stato ethercat";
"Error rosso: segnalazione warning/allarmi in ethercat". The front view, "L/A Status L/A Error"
over "Ingresso RJ45 Uscita RJ45": an L/A per port, Status by the IN port, Error by the OUT
port. Both L/A are printed "L/A"; the model names them by their port ("L/A IN", "L/A OUT", as
the TRS-CAT's "LINK-ACT IN" / "LINK-ACT OUT"). They are on the drive's front, so the drive
owns them and shows them in its snapshot (``leds``, in the front's order) whatever its
fieldbus; only its EtherCAT slave (devices/coe/drive_slave.py) drives them: on Modbus or
CANopen they stay dark, but for the L/A of a drive cabled on the EtherCAT line, which are its
ESC's and show link and traffic whatever c9 (devices/coe/leds.py).

Which of them a drive has on each fieldbus (:data:`BUS_LEDS`): the seed prints them only in
ch. 5, by the EtherCAT drive's two RJ45; ch. 2 (Modbus RTU), ch. 4 (CANopen) and ch. 6
(Profinet) print no network LED. So the views draw them on a drive whose c9 selected EtherCAT
at power-up and none otherwise (docs/dashboard.md "The 3D axis").
"""

from __future__ import annotations

from devices.leds import LedBank, LedPattern

LINK_IN = "L/A IN"
STATUS = "Status"
LINK_OUT = "L/A OUT"
ERROR = "Error"
NETWORK_LEDS = (LINK_IN, STATUS, LINK_OUT, ERROR)
# The network LEDs a drive has on each fieldbus (its snapshot's ``fieldbus``); a fieldbus not
# listed has none.
BUS_LEDS: dict[str, tuple[str, ...]] = {"ethercat": NETWORK_LEDS}


def network_leds(device_id: str) -> LedBank:
    """The bank of a drive's network LEDs, every one dark (no event: dark is the default)."""
    return LedBank(device_id, dict.fromkeys(NETWORK_LEDS, LedPattern.OFF))
