"""A device's flash kept in a file: a crash mid-write leaves the old or the new content.

The content is written to a temporary file in the same directory, flushed and fsynced, then
renamed over the old file (``os.replace`` is atomic on POSIX), and the directory is fsynced so
the rename itself survives a power cut. A small header with a length and a CRC-32 lets a reader
tell a complete file from a damaged one (e.g. a disk that lied about fsync): a damaged file is
reported, never silently used.
"""

from __future__ import annotations

import os
import struct
import tempfile
import zlib
from pathlib import Path

from devices.flash import FlashError

MAGIC = b"FRFL"
_HEADER = struct.Struct("<4sII")  # magic, payload length, CRC-32 of the payload


class CorruptFlash(FlashError):
    """The file exists but is not a complete flash image."""


class FileFlash:
    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)

    def load(self) -> bytes | None:
        try:
            blob = self.path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise FlashError(f"{self.path}: cannot read flash: {exc}") from exc
        if len(blob) < _HEADER.size:
            raise CorruptFlash(f"{self.path}: flash file truncated ({len(blob)} bytes)")
        magic, length, crc = _HEADER.unpack_from(blob)
        payload = blob[_HEADER.size:]
        if magic != MAGIC or length != len(payload) or zlib.crc32(payload) != crc:
            raise CorruptFlash(f"{self.path}: flash file damaged (bad header or checksum)")
        return payload

    def save(self, data: bytes) -> None:
        blob = _HEADER.pack(MAGIC, len(data), zlib.crc32(data)) + data
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # A writer killed mid-save leaves its temporary file; one device has one writer,
            # so any such file is stale: remove it rather than let them pile up.
            for stale in self.path.parent.glob(f".{self.path.name}.*"):
                stale.unlink(missing_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", dir=self.path.parent)
            try:
                with os.fdopen(fd, "wb") as fh:
                    fh.write(blob)
                    fh.flush()
                    os.fsync(fh.fileno())
                os.replace(tmp, self.path)
            except BaseException:
                Path(tmp).unlink(missing_ok=True)
                raise
            dir_fd = os.open(self.path.parent, os.O_RDONLY)
            try:
                os.fsync(dir_fd)
            finally:
                os.close(dir_fd)
        except OSError as exc:
            raise FlashError(f"{self.path}: cannot write flash: {exc}") from exc
