"""Operator and scenario actions of the drive's EtherCAT side, declared as data.

Everything goes the way a master would: objects through the mailbox (SDO upload / download,
so access, range and ESM state are enforced), a slot as TwinCAT's Slots tab writes it
(ch. 5 "Usando gli slots con Twincat": 0x1C12 / 0x1C13, plus 0x6060 "una volta sola allo
startup"), and an outputs image as a PLC's variables.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from devices.coe.assignment import SLOTS, slot_of
from devices.device import Action, CommandError, Param
from devices.ethercat import AlState
from devices.od import AbortCode, SdoAbort, decode, encode

if TYPE_CHECKING:
    from devices.coe.drive_slave import DriveEcatSlave

U16 = 0xFFFF
_INDEX = Param("index", int, low=0, high=U16)
_SUB = Param("sub", int, False, 0, 0, 0xFF)

ACTIONS: dict[str, Action] = {a.name: a for a in (
    Action("read_object", "SDO upload through the mailbox (PREOP and up)", (_INDEX, _SUB)),
    Action("write_object", "SDO download through the mailbox (PREOP and up)", (
        _INDEX, _SUB, Param("value", int))),
    Action("select_slot", "TwinCAT slot: PDO assignment 0x1C12 / 0x1C13 and 0x6060 (PREOP)", (
        Param("slot", str, choices=tuple(SLOTS)),)),
    Action("set_outputs", "the outputs image the master sends every cycle, hex bytes", (
        Param("data", str, doc="e.g. '1F 00 E8 03 00 00' (controlword, set-point)"),)),
    # Ch. 5 "Connessioni e Leds Drive EtherCAT": an RJ45 IN and an RJ45 OUT, each with its
    # L/A. The port defaults to IN, the only one the action used to pull.
    Action("link", "plug or pull the EtherCAT cable at IN or OUT (L/A IN / L/A OUT)", (
        Param("connected", bool),
        Param("port", str, False, "in", choices=("in", "out")))),
)}


class SlaveActions:
    """Mixin of :class:`~devices.coe.drive_slave.DriveEcatSlave`."""

    ACTIONS: ClassVar[Mapping[str, Action]] = ACTIONS

    def cmd_read_object(self: DriveEcatSlave, index: int, sub: int) -> Any:
        data = self.sdo_upload(index, sub)
        return decode(self.dictionary.entry(index, sub).dtype, data)

    def cmd_write_object(self: DriveEcatSlave, index: int, sub: int, value: int) -> None:
        od = self._mailbox()
        try:
            entry = od.entry(index, sub)
            if not entry.access.writable:
                raise SdoAbort(AbortCode.READ_ONLY, index, sub)
            data = encode(entry.dtype, entry.check_value(value))
        except SdoAbort as exc:
            self._log_sdo("download", index, sub, abort=exc)
            raise
        self.sdo_download(index, sub, data)

    def cmd_select_slot(self: DriveEcatSlave, slot: str) -> None:
        od = self._mailbox()
        if self.esm.state is not AlState.PREOP:
            raise CommandError(f"'{self.box_name}' is in {self.esm.state.label}: the PDO "
                               "assignment is written in PREOP (ch. 5, P -> S)")
        chosen = SLOTS[slot]
        for index, pdo in ((0x1C12, chosen.rx), (0x1C13, chosen.tx)):
            od.write(index, 0, 0)
            od.write(index, 1, pdo)
            od.write(index, 0, 1)
        od.write(0x6060, 0, chosen.mode)
        self._refresh()

    def cmd_set_outputs(self: DriveEcatSlave, data: str) -> None:
        try:
            raw = bytes.fromhex(data)
        except ValueError:
            raise CommandError(f"outputs must be hex bytes, got {data!r}") from None
        self.write_outputs(raw)

    def cmd_link(self: DriveEcatSlave, connected: bool, port: str = "in") -> None:
        """The operator's own plug at a port; the master folds ``plugs`` into its line
        model, so an OUT pull cuts the line behind the drive (docs/ethercat-master.md)."""
        inp, out = self.plugs
        self.plugs = (connected, out) if port == "in" else (inp, connected)
        self.link = self.line_in and self.plugs[0]
        self.link_out = self.line_out and self.plugs[1]
        self._refresh()

    def slot(self: DriveEcatSlave) -> str | None:
        return slot_of(self.rx_assign, self.tx_assign, self.csp.mode_display())
