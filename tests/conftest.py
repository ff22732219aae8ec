"""Suite-wide options: ``--full`` runs the fuzz, soak and persistence tests in their long form.

Without it (CI) those tests run reduced; the sizes of both forms are in each test module.
Tests marked ``@pytest.mark.full`` exist only in the long form and are skipped without it.
"""

from __future__ import annotations

import pytest


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--full", action="store_true", default=False,
                     help="run fuzz, soak and persistence tests in full (issue 7), not reduced")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--full"):
        return
    skip = pytest.mark.skip(reason="long form only: run with --full")
    for item in items:
        if "full" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def full(request: pytest.FixtureRequest) -> bool:
    """True with ``--full``: tests pick their long-form sizes."""
    return bool(request.config.getoption("--full"))
