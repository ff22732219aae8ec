"""The README's promises about itself (issue 7 acceptance: "the README links to
docs/performance.md"): the link is a Markdown link that resolves, and the two opening commands
stay as they are."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
OPENING = ("```bash\n"
           "bash .ci/setup && python3 -m app                     # set up, then the dashboard on "
           "http://127.0.0.1:8080\n"
           "bash .ci/setup --test && python3 -m pytest           # set up (with Debian's "
           "Chromium), then every test\n"
           "```")


def test_the_readme_links_to_the_performance_figures() -> None:
    assert "](docs/performance.md)" in README


def test_every_relative_link_resolves() -> None:
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README)
    relative = [t for t in targets if "://" not in t]
    assert relative
    assert [t for t in relative if not (ROOT / t).exists()] == []


def test_the_opening_commands_are_unchanged() -> None:
    assert README.split("\n", 2)[2].startswith(OPENING + "\n")


def test_a_flag_given_several_times_says_so() -> None:
    """``--rig`` may be given again for another rig (docs/classroom.md): the README's flag
    list said ``--rig PATH`` only, so a reader took it for one rig file."""
    import argparse

    from app.cli import _serve_parser

    repeatable = [o for a in _serve_parser()._actions if isinstance(a, argparse._AppendAction)
                  for o in a.option_strings if o.startswith("--")]
    assert repeatable
    said = [f for f in repeatable
            if re.search(rf"`{f}[^`]*`[^;.]{{0,40}}\b(again|several times)\b", README) is None]
    assert said == []


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, re.M | re.S)


def test_the_app_testing_example_is_the_one_docs_scenarios_shows() -> None:
    """Both docs show it; tests/browser/test_screenshots_cli.py runs the README's as written."""
    scenarios = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    example = [b for b in python_blocks(README) if "rig_session" in b]
    assert len(example) == 1 and example[0] in python_blocks(scenarios)
