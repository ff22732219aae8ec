"""Give the memory a recording frees back to the operating system (issue 7, the soak).

The recorder's sends allocate in three allocators that keep what is freed: rerun-sdk's Rust
side (mimalloc, linked into ``rerun_bindings``), pyarrow's default pool (its own mimalloc,
where rerun's Python side builds the Arrow columns) and glibc's malloc (numpy copies, the
buffers' arrays; per-thread arenas). Each periodic flush of a long session sends minutes of
buffered rows at once, and each allocator kept its peak: the soak's RSS rose ~3 MB at the
first 300 s flush and ~2 MB at the next (docs/hardening.md "Soak"). So: before rerun is
imported (:func:`configure`), rerun's mimalloc is told to purge freed pages at once; when a
recorder is made (:func:`use_system_pool`), the Arrow columns come from the system
allocator; after each periodic flush (:func:`release_freed`) glibc gives its free pages back
(``malloc_trim``). Measured on the soak driver: docs/recording.md "Memory given back".

pyarrow's default pool is the whole process's: a library user's own Arrow work shares it. So
it is switched only once a recorder exists, never by an import, and a pool the user chose
(``ARROW_DEFAULT_MEMORY_POOL``) is kept, as a user's ``MIMALLOC_PURGE_DELAY`` is.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys
from collections.abc import Callable

# mimalloc (rerun_bindings) reads its options from the environment when the library loads:
# 0 = return freed pages to the OS at once instead of after 10 ms of later allocator calls,
# which a thread that sends every few simulated minutes never makes in time.
MIMALLOC_PURGE_DELAY = ("MIMALLOC_PURGE_DELAY", "0")
ARROW_POOL_ENV = "ARROW_DEFAULT_MEMORY_POOL"  # pyarrow's own choice of its default pool


def configure() -> None:
    """Tell rerun's mimalloc to give freed pages back at once; call before ``import rerun``
    (it reads the environment only when it loads). A value the user put there is kept."""
    name, value = MIMALLOC_PURGE_DELAY
    if "rerun_bindings" not in sys.modules:  # loaded already: too late, and harmless
        os.environ.setdefault(name, value)


def use_system_pool() -> None:
    """pyarrow's default pool becomes the system allocator, unless the user picked one
    (``ARROW_DEFAULT_MEMORY_POOL``). Called by each recorder made: rerun builds its columns
    with that pool, and the system pool frees into glibc, which release_freed() trims."""
    if os.environ.get(ARROW_POOL_ENV):
        return
    import pyarrow as pa

    pa.set_memory_pool(pa.system_memory_pool())


def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim``, or None (musl, macOS, Windows: nothing to call)."""
    name = ctypes.util.find_library("c")
    if name is None:
        return None
    try:
        trim = ctypes.CDLL(name).malloc_trim
    except (OSError, AttributeError):
        return None
    trim.argtypes = [ctypes.c_size_t]
    trim.restype = ctypes.c_int
    return trim


_TRIM = _malloc_trim()


def release_freed() -> bool:
    """Give glibc's free pages (every arena) back to the OS; False where there is no glibc.
    Costs ~1 ms on the served default rig (docs/recording.md); called once per flush period."""
    if _TRIM is None:
        return False
    _TRIM(0)
    return True
