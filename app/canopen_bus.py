"""The CANopen adapter: python-can on one side, the drives' CANopen nodes on the other.

Thin on purpose: every CANopen behaviour lives in devices/canopen (pure, clock-driven). This
module only moves frames:

- in: a python-can ``Notifier`` thread receives a frame and hands it to the simulation thread
  with ``submit(fn)`` (the runtime runs it at the next step boundary); there the nodes'
  ``receive`` queue it on their bus line.
- out: :meth:`CanOpenBus.on_step` runs in the simulation thread after every step (a runtime
  step listener) and sends what the nodes finished transmitting by then, so a frame leaves
  when its simulated time has come; several nodes on one adapter also hear each other.

Interfaces (``--can-interface``): ``virtual`` (python-can's in-process bus, the default),
``udp_multicast`` (other processes on this machine: ``--can-channel GROUP[:PORT][@ADDRESS]``,
default 239.74.163.2:43113), ``socketcan`` (a real or vcan interface where the host has one,
e.g. ``can0``). udp_multicast delivers a sender's own datagrams back to it; the adapter drops
those echoes. docs/canopen.md has the details.

udp_multicast stays on this machine unless asked otherwise (issue 7, security defaults): the
socket is bound to the group address (not 0.0.0.0) and joins the group, and sends, on the
loopback interface 127.0.0.1 with a TTL of 1, so no other host can inject or hear a frame.
``@ADDRESS`` picks the interface by one of its IPv4 addresses (``@192.168.1.20``: the LAN);
``@any`` is python-can's own socket (bound to 0.0.0.0, the group joined on the default
interface). A master in another process must use the same interface: ``open_bus`` gives it
the bus (docs/hardening.md, README).
"""

from __future__ import annotations

import ipaddress
import logging
import re
import socket
import struct
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from typing import Any, Protocol

import can
from can.interfaces.udp_multicast.bus import (
    SO_TIMESTAMPNS,
    GeneralPurposeUdpMulticastBus,
    UdpMulticastBus,
)

from app.rig import FAR_US, ObserverSpan
from devices.canopen.bus_timing import CanFrame
from devices.canopen.node import CanOpenNode

logger = logging.getLogger(__name__)

INTERFACES = ("virtual", "udp_multicast", "socketcan")
DEFAULT_CHANNEL = {"virtual": "fieldrig-can", "udp_multicast": "239.74.163.2",
                   "socketcan": "can0"}
UDP_DEFAULT_PORT = 43113  # python-can's default
UDP_DEFAULT_INTERFACE = "127.0.0.1"  # loopback: nothing leaves or enters this machine
ANY_INTERFACE = "any"  # python-can's own socket: 0.0.0.0, the group on the default interface
ECHO_TTL_S = 2.0  # an own datagram not seen back by then is forgotten
_IPV4 = r"\d+\.\d+\.\d+\.\d+"
_CHANNEL = re.compile(rf"^(?P<group>{_IPV4})(?::(?P<port>\d+))?(?:@(?P<iface>{_IPV4}|any))?$")


class CanBusError(RuntimeError):
    """The CAN interface cannot be opened (a message for the command line)."""


class StepSource(Protocol):
    def add_step_listener(self, fn: Callable[[int], None], realtime: bool = False,
                          quiet_until: ObserverSpan | None = None) -> None: ...


def open_bus(interface: str, channel: str | None = None) -> can.BusABC:
    """A python-can bus for ``--can-interface`` / ``--can-channel``.

    A CANopen master in another process opens its side the same way, so both meet on the
    same interface: ``canopen.Network(open_bus("udp_multicast", CHANNEL)).connect()``.
    """
    channel = check_channel(interface, channel)
    try:
        if interface == "udp_multicast":
            return _open_udp(channel)
        return can.Bus(interface=interface, channel=channel)
    except (can.CanError, OSError, ImportError, ValueError) as exc:
        raise CanBusError(f"cannot open CAN interface {interface} channel {channel}: {exc}") \
            from exc


def check_channel(interface: str, channel: str | None = None) -> str:
    """The channel ``open_bus`` will use, refused (CanBusError) when it cannot be one: the
    command line checks it before anything serves."""
    if interface not in INTERFACES:
        raise CanBusError(f"CAN interface {interface!r} is not one of {', '.join(INTERFACES)}")
    channel = channel or DEFAULT_CHANNEL[interface]
    if interface == "udp_multicast":
        try:
            _udp_channel(channel)
        except ValueError as exc:
            raise CanBusError(f"cannot open CAN interface {interface} channel {channel}: "
                              f"{exc}") from None
    return channel


def _udp_channel(channel: str) -> tuple[str, int, str]:
    """(group, port, interface address or "any") of GROUP[:PORT][@ADDRESS|@any]; ValueError
    for what the socket calls would refuse with a traceback (OverflowError for a port beyond
    65535) or turn into something else (port 0: a port the kernel picks, no one to meet)."""
    match = _CHANNEL.match(channel)
    if match is None:
        raise ValueError("the channel is GROUP[:PORT][@ADDRESS], e.g. 239.74.163.2:43113 "
                         "(an IPv4 multicast group; @ADDRESS: an IPv4 address of this host's "
                         "interface to use, or @any; default 127.0.0.1)")
    group, port = match["group"], int(match["port"] or UDP_DEFAULT_PORT)
    iface = match["iface"] or UDP_DEFAULT_INTERFACE
    if not 0 < port < 65536:
        raise ValueError(f"port {port} is not a UDP port (1..65535)")
    if not _ipv4(group) or not ipaddress.IPv4Address(group).is_multicast:
        raise ValueError(f"{group} is not an IPv4 multicast group (224.0.0.0 to "
                         "239.255.255.255)")
    if iface != ANY_INTERFACE and not _ipv4(iface):
        raise ValueError(f"{iface} is not an IPv4 address (@ADDRESS: one of this host's)")
    return group, port, iface


def _ipv4(text: str) -> bool:
    try:
        ipaddress.IPv4Address(text)
    except ValueError:
        return False
    return True


def _open_udp(channel: str) -> can.BusABC:
    group, port, iface = _udp_channel(channel)
    if iface == ANY_INTERFACE:
        return can.Bus(interface="udp_multicast", channel=group, port=port, fd=False)
    return InterfaceUdpMulticastBus(group, port, iface)


class _InterfaceMulticast(GeneralPurposeUdpMulticastBus):
    """python-can's multicast socket, on one interface: bound to the group address, joined
    and sending on the interface of ``address``, TTL 1 (the wire format is python-can's)."""

    def __init__(self, group: str, port: int, address: str) -> None:
        self.address = address
        super().__init__(group, port, hop_limit=1)

    def _create_socket(self, address_family: socket.AddressFamily) -> socket.socket:
        if address_family != socket.AF_INET:
            raise can.CanInitializationError("an IPv4 multicast group is needed")
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            here = socket.inet_aton(self.address)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL,
                            struct.pack("@I", self.hop_limit))
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, here)
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if hasattr(socket, "SO_REUSEPORT"):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
            try:
                sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
                self.timestamp_nanosecond = True
            except OSError:
                self.timestamp_nanosecond = False
            # The group address, not 0.0.0.0: only datagrams sent to the group arrive.
            sock.bind((self.group, self.port))
            sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
                            socket.inet_aton(self.group) + here)
            return sock
        except OSError as exc:
            sock.close()
            raise can.CanInitializationError(
                f"cannot join {self.group}:{self.port} on {self.address}: {exc}") from exc


class InterfaceUdpMulticastBus(UdpMulticastBus):
    """python-can's ``udp_multicast`` bus on one interface (loopback unless told otherwise)."""

    def __init__(self, channel: str, port: int = UDP_DEFAULT_PORT,
                 address: str = UDP_DEFAULT_INTERFACE, **kwargs: Any) -> None:
        can.BusABC.__init__(self, channel, **kwargs)  # UdpMulticastBus's own would open 0.0.0.0
        self._multicast = _InterfaceMulticast(channel, port, address)
        self._can_protocol = can.CanProtocol.CAN_20
        self.channel_info = f"udp_multicast {channel}:{port} on {address}"


class CanOpenBus:
    """One CAN bus shared by some CANopen nodes of the rig."""

    def __init__(self, nodes: Sequence[CanOpenNode],
                 submit: Callable[[Callable[[], Any]], Future[Any]],
                 interface: str = "virtual", channel: str | None = None) -> None:
        self.nodes = list(nodes)
        self.submit = submit
        self.interface = interface
        self.channel = channel or DEFAULT_CHANNEL.get(interface, "")
        self.bus: can.BusABC | None = None
        self._notifier: can.Notifier | None = None
        self._echo = interface == "udp_multicast"
        self._echo_lock = threading.Lock()
        self._echoes: deque[tuple[float, tuple[int, bool, bytes]]] = deque()
        self.sent = self.received = self.send_errors = 0

    # ---- life cycle ----------------------------------------------------------------------
    def attach(self, runtime: StepSource) -> None:
        runtime.add_step_listener(self.on_step, quiet_until=self.quiet_until)

    def start(self) -> None:
        self.bus = open_bus(self.interface, self.channel)
        self._notifier = can.Notifier(self.bus, [self._on_message], timeout=0.1)

    def stop(self) -> None:
        if self._notifier is not None:
            self._notifier.stop(timeout=1.0)
            self._notifier = None
        if self.bus is not None:
            self.bus.shutdown()
            self.bus = None

    # ---- simulation thread ---------------------------------------------------------------
    def quiet_until(self, now_us: int, step_us: int) -> int:
        """Nothing to send while no node has a finished frame (a quiet node sends none)."""
        return now_us if any(node.outbox for node in self.nodes) else FAR_US

    def on_step(self, now_us: int) -> None:
        """Send what the nodes finished transmitting by ``now_us`` (simulation thread)."""
        for node in self.nodes:
            for frame in node.take_frames():
                for other in self.nodes:
                    if other is not node:
                        other.receive(frame.can_id, frame.data, frame.rtr)
                self._send(frame)

    def _send(self, frame: CanFrame) -> None:
        if self.bus is None:
            return
        msg = can.Message(arbitration_id=frame.can_id, data=frame.data,
                          is_remote_frame=frame.rtr, is_extended_id=False,
                          dlc=frame.length)
        if self._echo:
            key = (frame.can_id, frame.rtr, bytes(frame.data))
            with self._echo_lock:
                self._echoes.append((time.monotonic(), key))
        try:
            self.bus.send(msg, timeout=0.05)
            self.sent += 1
        except can.CanError as exc:
            self.send_errors += 1
            logger.warning("CAN send failed (%s): %s", self.interface, exc)

    # ---- receiving thread ----------------------------------------------------------------
    def _on_message(self, msg: can.Message) -> None:
        if msg.is_error_frame or msg.is_extended_id or msg.is_fd:
            return  # CANopen here is CAN 2.0A: 11-bit identifiers only
        data = bytes(msg.data)
        if self._echo and self._own_echo((msg.arbitration_id, msg.is_remote_frame, data)):
            return
        self.received += 1
        can_id, rtr, dlc = msg.arbitration_id, msg.is_remote_frame, msg.dlc
        self.submit(lambda: self._deliver(can_id, data, rtr, dlc))

    def _deliver(self, can_id: int, data: bytes, rtr: bool, dlc: int) -> None:
        for node in self.nodes:
            node.receive(can_id, data, rtr, dlc)

    def _own_echo(self, key: tuple[int, bool, bytes]) -> bool:
        """True (once) for a datagram this adapter sent: the oldest matching one is used up."""
        with self._echo_lock:
            now = time.monotonic()
            while self._echoes and now - self._echoes[0][0] > ECHO_TTL_S:
                self._echoes.popleft()
            for i, (_, sent) in enumerate(self._echoes):
                if sent == key:
                    del self._echoes[i]
                    return True
            return False
