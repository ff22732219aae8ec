"""Where the served rigs will listen, checked before anything serves (issue 7, hardening).

viser 1.1.1 (``viser/infra/_infra.py``, ``start_server``) answers a failed bind by trying the
next port, 1,000 times; when none binds its thread ends without releasing the semaphore
``ViserServer()`` waits on, so a ``--host`` that does not resolve or is no address of this
machine hung the CLI for ever with no word, and a ``--port`` in use moved the dashboard to
another port. pymodbus raises a bare RuntimeError. So the CLI resolves the host and binds
every port first, as the servers will (every address the host resolves to, SO_REUSEADDR as
asyncio's ``create_server`` sets it, IPv6 sockets v6-only), then closes the sockets again.
"""

from __future__ import annotations

import errno
import socket
from collections.abc import Sequence


class ListenError(Exception):
    def __init__(self, flag: str, reason: str) -> None:
        self.flag, self.reason = flag, reason
        super().__init__(f"{flag}: {reason}")


def check_listen(host: str, ports: Sequence[tuple[str, int]]) -> None:
    """Raise ListenError(flag, reason) unless TCP can listen on ``host`` at each port; the
    flag is ``--host`` when the address is at fault, else the port's (``(flag, port)``)."""
    try:
        infos = socket.getaddrinfo(host or None, 0, type=socket.SOCK_STREAM,
                                   flags=socket.AI_PASSIVE)
    except UnicodeError:  # the idna codec: an empty label (bad..host) or one over 63 chars
        raise ListenError("--host", f"{host!r} is not a host name or address") from None
    except socket.gaierror as exc:
        raise ListenError("--host", f"cannot resolve {host}: {exc.strerror or exc}") from None
    addresses = list(dict.fromkeys((family, sockaddr[0]) for family, *_, sockaddr in infos))
    held: list[socket.socket] = []
    try:  # all held at once: two of our own servers on one port are a clash too
        for flag, port in ports:
            for family, address in addresses:
                try:
                    sock = socket.socket(family, socket.SOCK_STREAM)
                except OSError:  # a family this kernel lacks (IPv6 off): asyncio skips it too
                    continue
                held.append(sock)
                try:
                    _listen(sock, family, address, port)
                except OSError as exc:
                    where = f"[{address}]:{port}" if family == socket.AF_INET6 else \
                        f"{address}:{port}"
                    raise ListenError("--host" if exc.errno == errno.EADDRNOTAVAIL else flag,
                                      f"cannot listen on {where}: {exc.strerror or exc}") \
                        from None
    finally:
        for sock in held:
            sock.close()


def _listen(sock: socket.socket, family: int, address: str, port: int) -> None:
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    if family == socket.AF_INET6:
        sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
    sock.bind((address, port))
    # Listening, not only bound: two bound SO_REUSEADDR sockets may share a port on Linux,
    # two listening ones may not.
    sock.listen(1)
