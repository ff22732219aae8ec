"""The object-dictionary view: any device's objects with live values (FastCAT seed 000 §6,
TRS-CAT seed 001 §9.3, CPX-E-EC seed 002 Tab. 27, the drive's CoE side seed 004 ch. 5).

With several devices a "Device" dropdown picks one, each page its own (a click on a slave in
the 3D view picks it too, ``select``); every device with an ``od`` attribute and read / write
actions qualifies.

The table is read in the simulation thread (``runtime.submit``) from the model's ``od`` — on
"Refresh" and every few seconds — and rendered here, filtered by a text box. Writes go through
the device's ``write_object`` action like any master write, so access rights and value ranges
are enforced by the model, and an SdoAbort comes back as a notification to the writer.
"""

from __future__ import annotations

import logging
import re
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

import viser

from app.runtime import Runtime
from app.ui.commands import CommandSender, notify
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_pick import ClientHtml, ClientPick
from app.ui.panels.widgets import on_button
from app.ui.style import esc
from devices.device import CommandError
from devices.events import fmt_bytes
from devices.od import IEC_NAMES, OdEntry, SdoAbort

logger = logging.getLogger(__name__)

REFRESH_S = 2.0
MAX_SHOWN = 200
NO_OD = ("no object dictionary now: the FastCAT generates it at the end of the internal-bus "
         "scan (seed 000 §5); power it on and wait for the scan")
NO_OD_OTHER = "no object dictionary now: is the device powered?"


@dataclass(frozen=True)
class OdRow:
    index: int
    sub: int
    name: str
    dtype: str
    access: str
    value: Any
    said: str = ""  # the model's words for the value (OdEntry.explain), shown instead of it
    # The type as the device's manual prints it (DeviceModel.TYPE_NAMES: "U32" for the
    # CPX-E-EC); ``dtype`` stays seed 000's name, which the value's formatting keys on.
    type_name: str = ""

    @property
    def shown_type(self) -> str:
        return self.type_name or self.dtype

    @property
    def address(self) -> str:
        return f"0x{self.index:04X}:{self.sub}"


def read_rows(device: Any) -> list[OdRow]:
    """All entries of ``device.od`` with their current values (simulation thread only);
    empty while the device has no dictionary (a FastCAT builds it after its first scan)."""
    od = getattr(device, "od", None)
    rows: list[OdRow] = []
    if od is None:
        return rows
    names = getattr(device, "TYPE_NAMES", IEC_NAMES)
    for e in od:
        try:
            value = od.peek(e.index, e.sub)
        except Exception as exc:  # a getter failing must not hide the rest of the table
            value = f"<{type(exc).__name__}>"
        said = e.explain(value) if e.explain is not None and not isinstance(value, str) else ""
        rows.append(OdRow(e.index, e.sub, e.name, e.dtype.short, access_text(e), value, said,
                          names.of(e)))
    return rows


def access_text(entry: OdEntry) -> str:
    """The access column: ro / rw / wo, with "P" for a PDO-mappable entry, as seed 002
    Tab. 27 prints "RO P" / "RW P" (0x10F3:4, 0x60xx, 0x70xx) and a configuration tool's
    flags column shows it: without it a trainee could not tell what may go into a PDO."""
    return f"{entry.access.value} P" if entry.pdo_mappable else entry.access.value


def format_value(value: Any, dtype: str) -> str:
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, int):
        if dtype in ("UDINT", "UINT") and value > 9:
            return f"{value} (0x{value:0{8 if dtype == 'UDINT' else 4}X})"
        return str(value)
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bytes | bytearray):  # OCTET_STRING: the bytes in hex, byte 0 first
        return fmt_bytes(value)
    return str(value)


HEX_DIGITS = {"UINT": 4, "UDINT": 8}  # the types the table also shows in hex


def read_box(value: Any, dtype: str) -> str:
    """A Read's value as the Value box takes it back for a Write: unsigned 16/32-bit in hex
    (0x04000003, as the State panel shows 0x5400), other numbers in decimal, a string as it
    is, an OCTET_STRING in hex bytes as the table shows it."""
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, int):
        digits = HEX_DIGITS.get(dtype)
        return f"0x{value:0{digits}X}" if digits is not None and value >= 0 else str(value)
    if isinstance(value, bytes | bytearray):
        return fmt_bytes(value)
    return str(value)


def read_text(value: Any, dtype: str) -> str:
    """A Read button's answer: unsigned 16/32-bit in hex then decimal ("0x04000003
    (67108867)"), the rest as the table shows it."""
    if isinstance(value, int) and not isinstance(value, bool) and dtype in HEX_DIGITS:
        return f"{read_box(value, dtype)} ({value})"
    return format_value(value, dtype)


def matches(row: OdRow, needle: str) -> bool:
    """Substring of ``index:sub`` or of the name; ``0x2104`` (0x + four hex digits) also
    finds the per-module family base + 0x10 * (N - 1) (seed 000 §6: "0x2104-0x21F4")."""
    if not needle:
        return True
    n = needle.lower()
    if re.fullmatch(r"0x[0-9a-f]{4}", n):
        base = int(n, 16)
        if base <= row.index <= base + 0xF0 and (row.index - base) % 0x10 == 0:
            return True
    n = n.removeprefix("0x")
    return n in f"{row.index:04x}:{row.sub}" or n in row.name.lower()


def render(rows: Sequence[OdRow], needle: str, empty: str = NO_OD) -> str:
    shown = [r for r in rows if matches(r, needle.strip())]
    body = "".join(
        f"<tr><td>{esc(r.address)}</td><td>{esc(r.name)}</td><td>{esc(r.shown_type)}</td>"
        f"<td>{esc(r.access)}</td><td>{esc(r.said or format_value(r.value, r.dtype))}</td></tr>"
        for r in shown[:MAX_SHOWN])
    more = ""
    if len(shown) > MAX_SHOWN:
        more = (f'<p class="fr-muted">{len(shown) - MAX_SHOWN} more objects: '
                "narrow the filter.</p>")
    if not shown:
        why = "no object matches" if rows else empty
        body = f'<tr><td colspan="5" class="fr-muted">{esc(why)}</td></tr>'
    return ('<div class="fr-od-wrap"><table class="fr-od" id="fr-od"><thead><tr>'
            "<th>Index:Sub</th><th>Name</th><th>Type</th><th>Access</th><th>Value</th>"
            f"</tr></thead><tbody>{body}</tbody></table></div>{more}")


def parse_address(text: str) -> tuple[int, int]:
    """``0x5200:1`` / ``5200:1`` / ``0x5400`` (sub 0) -> (index, sub); hex index, decimal sub."""
    index_text, _, sub_text = text.strip().partition(":")
    try:
        index = int(index_text.strip().removeprefix("0x").removeprefix("0X"), 16)
        sub = int(sub_text.strip() or "0", 0)
    except ValueError:
        raise CommandError(f"object {text!r} is not INDEX:SUB (e.g. 0x5200:1)") from None
    return index, sub


def parse_value(text: str) -> int | str:
    text = text.strip()
    if text.lower() in ("true", "false"):
        return int(text.lower() == "true")
    try:
        return int(text, 0)
    except ValueError:
        return text  # VISIBLE_STRING objects; the model answers a type mismatch otherwise


class ObjectDictionaryPanel:
    """With several devices, each page reads the dictionary it picked (its Device picker,
    its click in the 3D view: app/ui/panels/client_pick.py); one read in the simulation
    thread takes every dictionary some page shows."""

    def __init__(self, server: viser.ViserServer, runtime: Runtime, sender: CommandSender,
                 device_id: str, device_ids: Sequence[str] = ()) -> None:
        self._server = server
        self._runtime = runtime
        self._sender = sender
        self._lock = threading.Lock()
        self._rows: dict[str, list[OdRow]] = {}  # per device, the last read
        self._dirty = False
        self._pending = False
        self._next_refresh = 0.0
        gui = server.gui
        self._home = device_id  # the FastCAT: its dictionary waits for the first scan
        self._default = device_id
        self._pick: ClientPick | None = None
        if len(device_ids) > 1:
            self._pick = ClientPick(server, gui.add_dropdown(
                "Device", tuple(device_ids), initial_value=device_id))
            self._pick.on_pick(lambda client, device: self._picked())

        self._filter = gui.add_text("Filter", "", hint="index (5400, 0x2104) or name")
        refresh = gui.add_button("Refresh", icon=viser.Icon.REFRESH)
        self._address = gui.add_text("Object", "0x5200:1", hint="INDEX:SUB, index in hex")
        self._value = gui.add_text("Value", "1", hint="decimal, 0x.. hex, true/false")
        buttons = gui.add_button_group("Access", ("Read", "Write"))
        self._table = gui.add_html(render([], ""))
        self._tables = ClientHtml(server, self._table)
        # Each page filters, types and reads its own, on every rig: shared, a trainee's typed
        # object index and read value showed on every page (one dictionary too, no picker).
        self._forms = {
            "filter": ClientForm(server, self._filter, lambda _c, _v: self._refilter()),
            "object": ClientForm(server, self._address),
            "value": ClientForm(server, self._value)}

        @refresh.on_click
        def _(event: viser.GuiEvent) -> None:
            self.request(event.client)

        # The clicked button as the click arrives: read in viser's thread pool, the group's
        # value could be another page's next click (A's Write done as a Read).
        on_button(buttons, lambda event, button: self._access(event.client, button))

    def _refilter(self) -> None:
        with self._lock:
            self._dirty = True

    def _typed(self, name: str, client_id: int | None) -> str:
        """What ``client_id``'s page holds in a box."""
        return str(self._forms[name].value_for(client_id))

    @property
    def device_id(self) -> str:
        """The device a new page starts at (the last pick for every page)."""
        return self._default

    def device_for(self, client: Any) -> str:
        """The device ``client``'s page shows."""
        return self._device_of(getattr(client, "client_id", None))

    def _device_of(self, client_id: int | None) -> str:
        return self._default if self._pick is None else self._pick.value_for(client_id)

    def select(self, device_id: str, client: viser.ClientHandle | None = None) -> None:
        """Show ``device_id``'s dictionary on ``client``'s page (a click on it in the 3D
        view), on every page when None (a scenario's focus)."""
        if self._pick is None or device_id not in self._pick.options:
            return
        if client is None:
            self._default = device_id
        if self._pick.pick(device_id, client):
            self._picked()

    def _picked(self) -> None:
        """A page shows another dictionary: read it now."""
        with self._lock:
            self._dirty = True
        self._next_refresh = 0.0
        self.request(None)

    def _empty(self, device_id: str) -> str:
        return NO_OD if device_id == self._home else NO_OD_OTHER

    def _access(self, client: viser.ClientHandle | None, verb: str) -> None:
        client_id = getattr(client, "client_id", None)
        try:
            index, sub = parse_address(self._typed("object", client_id))
        except CommandError as exc:
            notify(client, "Object address", str(exc), error=True)
            return
        address = f"0x{index:04X}:{sub}"
        device_id = self.device_for(client)
        if verb == "Read":
            self._sender.send(client, device_id, "read_object", {"index": index, "sub": sub},
                              done=lambda v: self._read(client, device_id, index, sub, v))
            return
        value = parse_value(self._typed("value", client_id))
        self._sender.send(client, device_id, "write_object",
                          {"index": index, "sub": sub, "value": value},
                          done=lambda _r: (notify(client, f"{address} written",
                                                  f"value = {value!r}"),
                                           self.request(None)))

    def _read(self, client: viser.ClientHandle | None, device_id: str, index: int, sub: int,
              value: Any) -> None:
        """A Read's answer: into the reading page's Value box (a Write starts from it) and
        the notice."""
        dtype = self._dtype(device_id, index, sub)
        if client is not None:
            self._forms["value"].set_for(client, read_box(value, dtype))
        explain = self._explain(device_id, index, sub)
        said = explain(value) if explain is not None else read_text(value, dtype)
        notify(client, f"0x{index:04X}:{sub} read", f"value = {said}")

    def _entry(self, device_id: str, index: int, sub: int) -> OdEntry | None:
        try:
            return self._runtime.rig.device(device_id).od.entry(index, sub)
        except (CommandError, SdoAbort, AttributeError):  # no such device / object / od
            return None

    def _dtype(self, device_id: str, index: int, sub: int) -> str:
        """The object's type, from the rows read (or from the model when they are not there
        yet: the entry's type never changes); "" when unknown."""
        with self._lock:
            rows = self._rows.get(device_id)
        for row in rows or ():
            if (row.index, row.sub) == (index, sub):
                return row.dtype
        entry = self._entry(device_id, index, sub)
        return str(entry.dtype.short) if entry is not None else ""

    def _explain(self, device_id: str, index: int, sub: int) -> Callable[[Any], str] | None:
        """The model's words for the object's values (a pure function of the value)."""
        entry = self._entry(device_id, index, sub)
        return entry.explain if entry is not None else None

    def _shown(self) -> list[str]:
        """The dictionaries some page shows, the new pages' first."""
        shown = [self._default]
        if self._pick is not None:
            for client_id in self._server.get_clients():
                device = self._device_of(client_id)
                if device not in shown:
                    shown.append(device)
        return shown

    def request(self, client: viser.ClientHandle | None) -> None:
        """Read the dictionaries in the simulation thread; the table updates on the next
        tick."""
        with self._lock:
            if self._pending:
                return
            self._pending = True
        devices = self._shown()

        def read() -> dict[str, list[OdRow]]:
            return {d: read_rows(self._runtime.rig.device(d)) for d in devices}

        future = self._runtime.submit(read)
        future.add_done_callback(lambda f: self._received(client, f, devices))

    def _received(self, client: viser.ClientHandle | None,
                  future: Future[dict[str, list[OdRow]]], devices: list[str]) -> None:
        exc = future.exception()
        with self._lock:
            self._pending = False
            if exc is None:
                self._rows, self._dirty = future.result(), True
                if set(self._shown()) - set(devices):  # a page picked another meanwhile
                    self._next_refresh = 0.0
        if exc is not None:
            logger.warning("reading the object dictionary of %s failed: %s", devices, exc)
            notify(client, "Object dictionary", f"could not read it: {exc}", error=True)

    def tick(self, now: float | None = None) -> None:
        """From the dashboard thread: periodic refresh, and re-render when rows or filter
        changed (rendering stays out of the simulation thread)."""
        now = time.monotonic() if now is None else now
        # Nobody to show it to: no read (work for the simulation thread, which then keeps 1 ms
        # naps for a while). The first browser to connect gets a read at the next tick.
        if now >= self._next_refresh and self._server.get_clients():
            self._next_refresh = now + REFRESH_S
            self.request(None)
        with self._lock:
            if not self._dirty or not self._rows:
                return
            rows, self._dirty = dict(self._rows), False
        rendered: dict[tuple[str, str], str] = {}

        def content_for(client_id: int | None) -> str:
            device = self._device_of(client_id)
            needle = self._typed("filter", client_id)
            if (device, needle) not in rendered:
                rendered[device, needle] = render(rows[device], needle, self._empty(device)) \
                    if device in rows else render([], "", "reading the dictionary ...")
            return rendered[device, needle]

        self._tables.show(content_for)

    def rows(self) -> list[OdRow]:
        """The rows last read of the device a new page starts at (tests)."""
        with self._lock:
            return list(self._rows.get(self._default) or [])

    def row_count(self) -> int:
        with self._lock:
            return len(self._rows.get(self._default) or [])

