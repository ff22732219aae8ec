"""The Modular Device Profile's module ident check (ETG.5001), shared by the MDP slaves.

A master writes the modules it was configured with in 0xF030 (Configured Module Ident List)
during PRE-OP; the slave lists what it found in 0xF050 (Detected Module Ident List) and refuses
PREOP -> SAFEOP when they differ (AL status 0x0070). TRS-CAT: seed 001 §9.3.2; CPX-E-EC: seed
002 Tab. 17 Text-ID 0x3800; FastCAT: seed 000 §7.5 row 0x14. What a 0 entry means and which
list is checked differ per device (their docs/ files); the comparison is this one.
"""

from __future__ import annotations

from collections.abc import Sequence


def ident_mismatch(configured: Sequence[int], detected: Sequence[int],
                   zero_unchecked: bool = False) -> int | None:
    """The first position (0-based) where the lists differ, or None when they match.

    The lists hold the entries (subs 1..n, not the count). A position past a list's end holds
    no module, so a configured module that is not there and a detected one the master did not
    configure both differ. ``zero_unchecked``: a 0 configured entry accepts any module.
    """
    for pos in range(max(len(configured), len(detected))):
        want = configured[pos] if pos < len(configured) else None
        have = detected[pos] if pos < len(detected) else None
        if want != have and not (zero_unchecked and want == 0):
            return pos
    return None
