"""Non-volatile memory as the models see it: a blob that is either the old or the new content.

Models never touch files. The runtime gives them a store; `app/flash_file.py` keeps it in a
file written atomically, tests use :class:`MemoryFlash`.
"""

from __future__ import annotations

from typing import Protocol


class FlashError(OSError):
    """The store could not be written (the device reports its flash-save alarm)."""


class FlashStore(Protocol):
    def load(self) -> bytes | None:
        """The stored content, or None when nothing was ever stored."""

    def save(self, data: bytes) -> None:
        """Replace the content atomically; raise FlashError when it cannot."""


class MemoryFlash:
    """A store in memory, for tests and for rigs configured without a flash file."""

    def __init__(self, data: bytes | None = None, fail: bool = False) -> None:
        self.data = data
        self.fail = fail
        self.writes = 0

    def load(self) -> bytes | None:
        return self.data

    def save(self, data: bytes) -> None:
        if self.fail:
            raise FlashError("flash write failed")
        self.data = bytes(data)
        self.writes += 1
