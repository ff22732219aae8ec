"""Before the wire runs: the interface check and process B's start (``--ethercat-if``)."""

from __future__ import annotations

import multiprocessing
import socket
from collections.abc import Callable, Sequence
from typing import Any

from app.ethercat_wire.description import SlaveDescription
from app.rig_config import RigConfigError

ETHERTYPE_ECAT = 0x88A4
OPTION = "--ethercat-if"

Spawn = Callable[[str, Sequence[SlaveDescription], Any], Any]


def check_interface(iface: str) -> None:
    """The interface exists and this process may open a raw EtherCAT socket on it."""
    try:
        socket.if_nametoindex(iface)
    except OSError:
        names = ", ".join(name for _i, name in socket.if_nameindex()) or "none"
        raise RigConfigError(OPTION, "", f"no network interface '{iface}' (interfaces: "
                                         f"{names})") from None
    try:
        sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHERTYPE_ECAT))
    except PermissionError:
        raise RigConfigError(OPTION, "", "a raw EtherCAT socket needs CAP_NET_RAW: run as "
                                         "root, or give Python the capability (sudo setcap "
                                         "cap_net_raw+ep <the python binary>)") from None
    sock.close()


def spawn_wire_process(iface: str, descriptions: Sequence[SlaveDescription], conn: Any) -> Any:
    """Process B in a fresh interpreter (the ``spawn`` start method of the wire contract)."""
    from app.ethercat_wire import wire_process

    ctx = multiprocessing.get_context("spawn")
    proc = ctx.Process(target=wire_process.run, args=(iface, list(descriptions), conn),
                       name="fieldrig-ethercat-wire", daemon=True)
    proc.start()
    return proc

