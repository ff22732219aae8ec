"""Heartbeat producer and node guarding, as the drive does them (seed 004 ch. 4).

"Note sui servizi di Guard": the heartbeat is active when 0x1017 is not zero; a remote request
on the guarding COB-ID is then answered with the state but without toggling. Node guarding is
active when 0x100C (guard time) is not zero: every remote request is answered, toggling each
time, even one with DLC = 0. With 0x100D (life time factor) not zero as well the drive watches
the requests: when none came for life time factor x guard time it raises a flag that sends an
EMCY; when the requests resume the flag drops and the drive answers again. The EMCY is not
reset. Heartbeat and guarding frames carry the NMT state byte, bit 7 = toggle (guarding) or 0.
"""

from __future__ import annotations

from dataclasses import dataclass

MS = 1_000


@dataclass
class Heartbeat:
    """0x1017 producer: the state byte every ``period_ms`` (0 = off)."""

    period_ms: int = 0
    next_us: int | None = None

    def set_period(self, period_ms: int, now_us: int) -> None:
        """A new time restarts the cycle: the next heartbeat one period from now."""
        self.period_ms = period_ms
        self.next_us = now_us + period_ms * MS if period_ms else None

    def due(self, now_us: int) -> int | None:
        """The instant of a heartbeat that fell due by ``now_us`` (the cycle moves on)."""
        if self.next_us is None or self.next_us > now_us:
            return None
        at = self.next_us
        self.next_us = at + self.period_ms * MS
        if self.next_us <= now_us:  # the clock slipped: no burst of late heartbeats
            self.next_us = now_us + self.period_ms * MS
        return at


@dataclass
class NodeGuard:
    """0x100C / 0x100D: answers to remote requests, and life guarding."""

    guard_time_ms: int = 0
    life_time_factor: int = 0
    toggle: int = 0  # DS 301: the first answer has the toggle bit 0
    last_request_us: int | None = None  # life guarding starts with the first request
    expired: bool = False  # the flag of ch. 4

    @property
    def active(self) -> bool:
        return self.guard_time_ms != 0

    @property
    def life_time_us(self) -> int:
        return self.guard_time_ms * self.life_time_factor * MS

    def answer_bit(self, heartbeat_on: bool) -> int | None:
        """Bit 7 of the answer to a remote request, or None when the drive stays silent.

        With the heartbeat on the bit stays 0; with guarding on it toggles.
        """
        if heartbeat_on:
            return 0
        if not self.active:
            return None
        bit, self.toggle = self.toggle, self.toggle ^ 0x80
        return bit

    def request(self, now_us: int) -> bool:
        """A remote request arrived; True when it ends an expired life time (flag drops).

        Only a request made while guarding is on (0x100C != 0) counts: one made before is
        no guarding request, and life guarding starts with the first one after."""
        if not self.active:
            return False
        self.last_request_us = now_us
        was, self.expired = self.expired, False
        return was

    def expires_by(self, now_us: int) -> bool:
        """Would :meth:`check` report an expiry at ``now_us``? (It changes nothing.)"""
        if self.expired or not self.active or not self.life_time_factor \
                or self.last_request_us is None:
            return False
        return now_us > self.last_request_us + self.life_time_us

    def expiry_at(self) -> int | None:
        """The first instant at which :meth:`expires_by` says True, as things stand (None:
        none); instants are whole microseconds."""
        if self.expired or not self.active or not self.life_time_factor \
                or self.last_request_us is None:
            return None
        return self.last_request_us + self.life_time_us + 1

    def check(self, now_us: int) -> int | None:
        """The instant the life time ran out, once per expiry; None otherwise."""
        if self.expired or not self.active or not self.life_time_factor \
                or self.last_request_us is None:
            return None
        deadline = self.last_request_us + self.life_time_us
        if now_us <= deadline:
            return None
        self.expired = True
        return deadline

    def restart_life_time(self) -> None:
        """A new 0x100C or 0x100D: life guarding starts over and watches the new life time
        from the next request (docs/canopen.md §Heartbeat). The toggle goes on: the answers
        to the requests never stopped."""
        self.last_request_us = None
        self.expired = False

    def reset(self) -> None:
        self.toggle = 0
        self.restart_life_time()
