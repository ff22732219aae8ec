"""The shared ETG.5001 module ident comparison (devices/mdp.py)."""

from __future__ import annotations

import pytest

from devices.mdp import ident_mismatch


@pytest.mark.parametrize(("configured", "detected", "zero_unchecked", "pos"), [
    ([1, 2], [1, 2], False, None),
    ([1, 3], [1, 2], False, 1),
    ([1], [1, 2], False, 1),  # a module the master did not configure
    ([1, 2, 3], [1, 2], False, 2),  # a configured module that is not there
    ([1, 0], [1, 2], False, 1),  # TRS-CAT / CPX-E-EC: 0 is compared as it is
    ([1, 0], [1, 2], True, None),  # FastCAT: 0 leaves the position unchecked
    ([1, 2, 0], [1, 2], True, None),
    ([], [], False, None),
])
def test_first_position_that_differs(configured: list[int], detected: list[int],
                                     zero_unchecked: bool, pos: int | None) -> None:
    assert ident_mismatch(configured, detected, zero_unchecked) == pos
