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
