"""CANopen in the dashboard: the CANopen tab (NMT state, heartbeat, a decoded frame log like a
bus monitor, the PDO mapping) and a small master in the control panel, so a trainee can bring
the drive up from the browser.

Everything shown comes from the CANopen node's snapshot (devices/canopen/node.py,
docs/canopen.md): ``nmt``, ``heartbeat_ms``, guarding, ``error_register``, ``rpdo`` /
``tpdo`` with their mappings, ``last_sdo`` / ``last_pdo`` and the last decoded frames. The
master's frames (devices/canopen/master_frames.py) go to the node in the simulation thread, as
if they came off the bus; the node answers on its line at the n1 bit rate, and both directions
appear in the log. They do not leave the process: a master on ``--can-interface
udp_multicast`` does not see them (docs/dashboard.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import viser

from app.runtime import Runtime
from app.ui.commands import CommandSender, notify
from app.ui.drive import canopen_master as cm
from app.ui.drive.bus_state import nmt_badge
from app.ui.panels.client_form import ClientForm
from app.ui.panels.client_input import ClientMirror
from app.ui.panels.client_pick import PickedHtml
from app.ui.panels.widgets import on_button
from app.ui.style import esc, kv_table
from devices.canopen import master_frames as mf
from devices.canopen.emcy import REGISTER_WORDS
from devices.device import CommandError
from devices.od import SdoAbort
from devices.servo.parameters import FIELDBUS_NAMES

FRAME_ROWS = 60
KIND_CLASS = {"EMCY": "fr-emcy"}

# The CANopen node (device id), if any, of the drive a page shows (None: a new page's)
NodeId = Callable[[viser.ClientHandle | None], str | None]


SDO_SERVICES = {"download": "Download (write)", "upload": "Upload (read)"}


def _sdo_result(request: Mapping[str, Any], response: Mapping[str, Any] | None) -> str:
    if response is None:
        return "no answer yet"
    service = response.get("service")
    if service == "abort":
        return f"aborted by the node, {response.get('abort', '')}"
    if service == "download":  # a segmented download's first answer only opens it
        return "done" if request.get("size") is None else "accepted, segments follow"
    if service == "upload":
        if response.get("value"):
            return f"value {response['value']}"
        return f"{response.get('size', '?')} bytes follow in segments"
    if service == "upload segment":
        return "last segment received" if response.get("last") else "segments under way"
    if service == "download segment":  # the answer carries no "last" bit
        return "segment acknowledged"
    return str(service)


def sdo_sentence(exchange: Mapping[str, Any] | None, fallback: str = "") -> str:
    """The last SDO exchange in words (node snapshot ``last_sdo_exchange``): service and
    direction, object, value written, result. "Download (write) 0x6040:00 = 0F 00 to node 1:
    done." (the frame log's "node 1 ->: download 0x6040:00 done" read as a puzzle)."""
    request = (exchange or {}).get("request")
    response = (exchange or {}).get("response")
    if request is None:
        return fallback or "-"
    node = request.get("node")
    where = request.get("object", "")
    if request.get("service") == "abort":
        return f"The master aborted the transfer of {where} with node {node}: " \
               f"{request.get('abort', '')}."
    if request.get("service") == "download":
        value = f" = {request['value']}" if request.get("value") else (
            f", {request['size']} bytes" if request.get("size") is not None else "")
        what = f"{SDO_SERVICES['download']} {where}{value} to node {node}"
    elif request.get("service") == "upload":
        what = f"{SDO_SERVICES['upload']} {where} from node {node}"
    else:
        what = f"SDO {request.get('service')} with node {node}"
    return f"{what}: {_sdo_result(request, response)}."


def register_text(value: int) -> str:
    """0x1001 as the row shows it: "0x21 (Generic Error, Device Profile Specific)", the bits
    in seed 004 ch. 4's words (the table the Objects, Codes and Slave tabs read). The hex alone
    left a trainee to recall DS 301's bit order."""
    return f"0x{value:02X} ({REGISTER_WORDS.text(value)})"


def status_rows(node: Mapping[str, Any], drive: Mapping[str, Any]) -> list[tuple[str, str]]:
    heartbeat = int(node.get("heartbeat_ms", 0))
    guard, factor = int(node.get("guard_time_ms", 0)), int(node.get("life_time_factor", 0))
    guarding = f"{guard} ms x {factor}" if guard else "off"
    if node.get("life_guard_error"):
        guarding += " · life guard error"
    bus = node.get("bus") or {}
    history = ", ".join(node.get("error_history") or []) or "empty"
    return [
        ("NMT state", nmt_badge(str(node.get("nmt", "Off")))),
        ("CiA 402 state", esc(drive.get("ds402_state", "?"))),
        ("Heartbeat", esc((f"0x1017 = {heartbeat} ms" if heartbeat else "0x1017 = 0 (off)")
                          + f" · guarding {guarding}")),
        ("Error register", esc(f"{register_text(int(node.get('error_register', 0)))} · "
                               f"0x1003: {history}")),
        ("Bus", esc(f"rx {bus.get('rx', 0)} · tx {bus.get('tx', 0)} · SYNC "
                    f"{bus.get('syncs', 0)} · load {100 * float(bus.get('load', 0.0)):.1f}%")),
        ("Last SDO", esc(sdo_sentence(node.get("last_sdo_exchange"),
                                      node.get("last_sdo") or ""))),
        ("Last PDO", esc(node.get("last_pdo") or "-")),
    ]


def on_canopen(devices: Mapping[str, Any], nodes: Mapping[str, str]) -> list[tuple[str, Any]]:
    """(drive, node-ID) of each drive whose CANopen node speaks (c9 = CANopen at power-up);
    ``nodes``: each drive's node device id."""
    return [(drive, (devices.get(node) or {}).get("node_id")) for drive, node in nodes.items()
            if node and (devices.get(node) or {}).get("active")]


def status_html(node_id: str, node: Mapping[str, Any], drive: Mapping[str, Any],
                speaking: Sequence[tuple[str, Any]] = ()) -> str:
    """``speaking``: the drives on CANopen (:func:`on_canopen`), which a silent node's note
    points at: the tab shows the drive picked in *Servo drive*, on the default rig first the
    Modbus one, and its note alone sent a trainee to reconfigure it while drive_co was on
    CANopen all along."""
    rate = int(node.get("bitrate", 0)) // 1000
    head = (f'<p class="fr-title"><b>{esc(node_id)}</b> · node {esc(node.get("node_id"))} · '
            f"{rate} kbit/s (n1)</p>")
    if not node.get("active"):
        bus = str(drive.get("fieldbus", "?"))
        reason = "the drive is powered off" if not drive.get("powered") else \
            f"the drive speaks {FIELDBUS_NAMES.get(bus, bus)} (c9 read at power-up)"
        others = "".join(f"{other} is on CANopen (node {number}): pick it in Servo drive. "
                         for other, number in speaking)
        fix = "Or set" if others else "Set"
        return head + ('<p class="fr-muted fr-note" id="fr-can-off">CANopen is silent: '
                       f"{esc(reason)}. {esc(others)}{fix} c9 = 5 (CANopen), save to flash and "
                       "switch the drive off and on.</p>")
    return head + kv_table(status_rows(node, drive), "fr-can")


def heartbeat_html(beats: Sequence[Mapping[str, Any]]) -> str:
    """The heartbeat lines above the log (the node's ``heartbeats``): a heartbeat repeating
    its COB-ID's state is counted there, not logged (devices/canopen/monitor.py)."""
    lines = []
    for b in beats:
        period = b.get("period")
        every = f" · every {float(period):.3f} s" if period else ""
        lines.append(f"Heartbeat {esc(b.get('id', ''))} {esc(b.get('dir', ''))} · "
                     f"{esc(b.get('text', ''))} ({esc(b.get('data', ''))}) · "
                     f"{int(b.get('count', 0))} in a row{every} · "
                     f"last {float(b.get('t', 0.0)):.3f}")
    if not lines:
        return ""
    return f'<p class="fr-note fr-hb" id="fr-can-hb">{"<br>".join(lines)}</p>'


def frames_html(frames: Sequence[Mapping[str, Any]], rows: int = FRAME_ROWS,
                heartbeats: Sequence[Mapping[str, Any]] = ()) -> str:
    """The bus monitor, newest first: time | dir | COB-ID | type | data | meaning; repeated
    heartbeats on their line above (:func:`heartbeat_html`)."""
    body = "".join(
        f'<tr class="{"fr-rx" if f.get("dir") == "rx" else ""} '
        f'{KIND_CLASS.get(str(f.get("kind")), "")}">'
        f'<td class="fr-t">{float(f.get("t", 0.0)):.3f}</td>'
        f'<td>{esc(f.get("dir", ""))}</td><td>{esc(f.get("id", ""))}</td>'
        f'<td>{esc(f.get("kind", ""))}</td><td>{esc(f.get("data", ""))}</td>'
        f'<td>{esc(f.get("text", ""))}</td></tr>'
        for f in list(frames)[::-1][:rows])
    if not body:
        body = '<tr><td colspan="6" class="fr-muted">no frames yet</td></tr>'
    return (heartbeat_html(heartbeats) +
            '<div class="fr-frames-wrap"><table class="fr-frames" id="fr-frames"><colgroup>'
            '<col style="width:5.4em"><col style="width:2em"><col style="width:3.9em">'
            '<col style="width:4.5em"><col style="width:8.2em"><col></colgroup><thead><tr>'
            '<th>time</th><th title="rx: to the drive, tx: from the drive">dir</th>'
            '<th>COB-ID</th><th>type</th><th>data</th><th>meaning</th></tr></thead>'
            f"<tbody>{body}</tbody></table></div>")


def pdo_html(node: Mapping[str, Any]) -> str:
    rows = []
    for pdo in [*(node.get("rpdo") or []), *(node.get("tpdo") or [])]:
        extra = ""
        if pdo.get("event_timer_ms"):
            extra = f", timer {pdo['event_timer_ms']} ms"
        if pdo.get("inhibit_100us"):
            extra += f", inhibit {int(pdo['inhibit_100us']) / 10:g} ms"
        cls = "" if pdo.get("valid") else "fr-off"
        rows.append(f'<tr class="{cls}"><td>{esc(pdo.get("pdo", ""))}</td>'
                    f'<td>{esc(pdo.get("can_id", ""))}{"" if pdo.get("valid") else " off"}</td>'
                    f'<td>{esc(pdo.get("type", ""))}{esc(extra)}</td>'
                    f'<td>{esc(" ".join(pdo.get("mapping") or []) or "-")}</td></tr>')
    return ('<table class="fr-pdo" id="fr-pdo"><thead><tr><th>PDO</th><th>COB-ID</th>'
            f'<th>type</th><th>mapping (index:sub/bits)</th></tr></thead><tbody>{"".join(rows)}'
            "</tbody></table>")


class CanOpenMaster:
    """The master's controls (in the control panel): NMT, 0x6040 over SDO, heartbeat, SDO.
    Its boxes are each page's own (docs/dashboard.md "Several browsers"): a button sends
    what the clicking page's boxes hold, to the node of the drive that page shows."""

    def __init__(self, server: viser.ViserServer, runtime: Runtime, sender: CommandSender,
                 node_id: NodeId) -> None:
        self._runtime = runtime
        self._sender = sender
        self._node_id = node_id
        self.sent = 0  # frames handed to the node so far (tests wait on it)
        gui = server.gui
        with gui.add_folder("CANopen master"):
            self._nmt = gui.add_dropdown("NMT command", tuple(cm.NMT_COMMANDS))
            send_nmt = gui.add_button("Send NMT", hint="COB-ID 0: command, node-ID")
            names = list(cm.CONTROLWORD_COMMANDS)
            cw_a = gui.add_button_group("0x6040 (SDO)", tuple(names[:3]))
            cw_b = gui.add_button_group("0x6040 more", tuple(names[3:]))
            # Pre-filled from the node's 0x1017 (update()): the initial 1000 used to sit there
            # while the object was 0, as if the heartbeat had been set already.
            self._heartbeat = gui.add_number("Heartbeat (ms)", 0, min=0, max=65535, step=1,
                                             hint="the node's 0x1017 (producer heartbeat "
                                                  "time); type a new period, then Set")
            self._heartbeat_mirror = ClientMirror(server, self._heartbeat)
            set_hb = gui.add_button("Set heartbeat", hint="SDO download 0x1017:0")
            self._object = gui.add_text("SDO object", "0x6041:0")
            self._value = gui.add_text("SDO value", "0")
            sdo = gui.add_button_group("SDO", ("Upload", "Download"))
        # Shared, one trainee's typed object and value were every page's, and its Download
        # another page's click (one drive too: there is no picker to make them per page).
        self._forms = {name: ClientForm(server, handle) for name, handle in (
            ("nmt", self._nmt), ("object", self._object), ("value", self._value))}

        @send_nmt.on_click
        def _(event: viser.GuiEvent) -> None:
            command = cm.NMT_COMMANDS.get(str(self._forms["nmt"].value_of(event.client)))
            if command is not None:
                self._send(event.client, "NMT", lambda node: mf.nmt(command, node))

        def controlword(event: viser.GuiEvent, value: str) -> None:
            cw = cm.CONTROLWORD_COMMANDS[value]
            index, sub = cm.CONTROLWORD
            self._send(event.client, f"0x6040 = 0x{cw:04X}",
                       lambda node: mf.sdo_download(node, index, sub, cw, 2))

        # The clicked button as the click arrives (on_button): read later in viser's thread
        # pool, the group's value could be another page's next click.
        on_button(cw_a, controlword)
        on_button(cw_b, controlword)

        @set_hb.on_click
        def _(event: viser.GuiEvent) -> None:
            ms = int(self._heartbeat_mirror.value_for(event.client_id))
            index, sub = cm.HEARTBEAT
            self._send(event.client, "0x1017",
                       lambda node: mf.sdo_download(node, index, sub, ms, 2))

        on_button(sdo, self._sdo)

    def _sdo(self, event: viser.GuiEvent, button: str) -> None:
        """Upload or Download the clicking page's SDO object (and value)."""
        client = event.client
        try:
            index, sub = cm.parse_object(str(self._forms["object"].value_of(client)))
            value = cm.parse_int(str(self._forms["value"].value_of(client))) \
                if button == "Download" else 0
        except ValueError as exc:
            notify(client, "SDO", f"bad input: {exc}", error=True)
            return
        if button == "Upload":
            self._send(client, "SDO upload", lambda node: mf.sdo_upload(node, index, sub))
        else:
            self._send(client, "SDO download",
                       lambda node: mf.sdo_download(node, index, sub, value,
                                                    self._object_size(client, index, sub)))

    @property
    def heartbeat_box(self) -> Any:
        return self._heartbeat

    def update(self, node_of: Callable[[int | None], Mapping[str, Any]]) -> None:
        """``node_of(client_id)``: the snapshot of that page's node (None: a new page's;
        dashboard thread): each page's box follows its node's 0x1017 when it changes (this
        master's SDO, another master's, a reset), and keeps what that page typed until
        then."""
        def heartbeat(client_id: int | None) -> int | None:
            node = node_of(client_id)
            return int(node["heartbeat_ms"]) if "heartbeat_ms" in node else None

        self._heartbeat_mirror.follow_each(heartbeat)

    def forget(self, client_id: int | None = None) -> None:
        """Another drive picked (on ``client_id``'s page, or every page's): take its 0x1017
        at the next frame."""
        self._heartbeat_mirror.forget(client_id)

    # ---- sending (simulation thread) --------------------------------------------------------
    def _device(self, client: viser.ClientHandle | None) -> Any:
        device_id = self._node_id(client)
        return self._runtime.rig.devices.get(device_id) if device_id else None

    def _object_size(self, client: viser.ClientHandle | None, index: int, sub: int) -> int:
        """Bytes of an object (simulation thread); 4 for one the node does not have, so that
        the node answers with its abort."""
        node = self._device(client)
        try:
            size = node.dictionary.entry(index, sub).bit_length // 8
        except (AttributeError, SdoAbort):
            return 4
        return size if 1 <= size <= 4 else 4

    def _send(self, client: viser.ClientHandle | None, label: str,
              build: Callable[[int], mf.Frame]) -> None:
        def run() -> None:
            node = self._device(client)
            if node is None or not getattr(node, "active", False):
                raise CommandError("the drive's CANopen node is silent (c9 is not CANopen, "
                                   "or the drive is off)")
            frame = build(int(node.node_id))
            node.receive(frame.can_id, frame.data)
            self.sent += 1

        self._sender.submit(client, f"CANopen {label}", run)


class CanOpenMonitor:
    """The CANopen tab (left panel): status, the frame log, the PDO mapping; ``per_page``:
    each page shows the node of the drive it picked."""

    def __init__(self, server: viser.ViserServer, per_page: bool = False) -> None:
        gui = server.gui
        self._status = PickedHtml(server, status_html("", {}, {}), per_page)
        gui.add_markdown("**Frame log** (newest first)")
        self._frames = PickedHtml(server, frames_html([]), per_page)
        gui.add_markdown("**PDO mapping**")
        self._pdos = PickedHtml(server, pdo_html({}), per_page)

    def update(self, pick_of: Callable[[int | None], str],
               node_of: Callable[[str], tuple[str, Mapping[str, Any], Mapping[str, Any]]],
               speaking: Sequence[tuple[str, Any]] = ()) -> None:
        """``pick_of``: a page's drive; ``node_of(drive)``: (node id, node, drive);
        ``speaking``: the drives on CANopen (:func:`on_canopen`)."""
        self._status.show(lambda d: status_html(*node_of(d), speaking), pick_of)
        self._frames.show(lambda d: frames_html(node_of(d)[1].get("frames") or [],
                                                heartbeats=node_of(d)[1].get("heartbeats")
                                                or []), pick_of)
        self._pdos.show(lambda d: pdo_html(node_of(d)[1]), pick_of)
