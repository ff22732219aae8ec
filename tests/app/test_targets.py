import pytest

from app.targets import parse_target
from devices.device import CommandError


@pytest.mark.parametrize(("text", "expected"), [
    ("fastcat", ("fastcat", None)), ("fastcat/2", ("fastcat", 2)), ("drive-1/16", ("drive-1", 16)),
])
def test_targets(text, expected):
    assert parse_target(text) == expected


@pytest.mark.parametrize("text", ["", "fastcat/", "fastcat/0", "/2", "fast cat", "a/b", 3])
def test_bad_targets(text):
    with pytest.raises(CommandError):
        parse_target(text)
