"""What README.md and docs/*.md name exists under that name, so a rename shows up here and not
in a new engineer's grep.

Only what is shaped like one of the project's own names is checked, so prose never is:
- a path into the repository, in backticks or in the prose (``app/``, ``devices/``, ``bench/``,
  ``tests/``, ``static/``, ``docs/``, ``.ci/``), optionally ``::name`` (a ``def``, ``class`` or
  top-level name of that file); a ``*`` is a glob that must match, an upper-case or ``<...>``
  part is a placeholder and skipped, and what .gitignore lists is output that may not exist yet;
Fenced blocks are left out (commands and sample output, checked by running them). In backticks:
- a dotted name rooted at ``app``, ``devices`` or ``bench`` (``app.ui.commands.CommandSender``),
  which must import and resolve attribute by attribute;
- a bare ``test_*.py`` file (somewhere under tests/), a bare ``test_*`` name (a ``def`` in
  tests/) and a bare ``*.py`` file (somewhere in the project's code or tests);
A project file followed by a name (``devices/servo/alarms.py`` ``RESET_HINT``, in backticks
each) names something of that file. In a table row whose first cell is a project file
(``| `app/rig.py` | `Rig`, `describe()` |``), each class-like (``CamelCase``), constant-like
(``UPPER_CASE``) or called (``name()``) name of the row must occur in that file.
And in the prose, a section named in quotes after a doc (``docs/hardening.md "Soak"``) or as
``"X" below`` / ``"X" above``: a heading holding it, a bold label or a line (list item, table
cell) starting with it.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
CODE_DIRS = ("app", "devices", "bench", "tests")

FENCE = re.compile(r"^```.*?^```", re.M | re.S)
SPAN = re.compile(r"`([^`\n]+)`")
PATH = re.compile(r"(?:\./)?((?:app|devices|bench|tests|static|docs|\.ci)/[\w./*<>-]*)"
                  r"(?:::(\w+))?")
DOTTED = re.compile(r"((?:app|devices|bench)(?:\.\w+)+)(?:\(\))?")
SECTION_AFTER_DOC = re.compile(r"(?:docs/)?([a-z0-9-]+\.md)[)`]?,? \(?\"([^\"]+)\"")
FILE_ROW = re.compile(r"^\|\s*`((?:app|devices|bench|tests)/[\w/.-]+\.py)`\s*\|(.*)$")
CODE_NAME = re.compile(r"[A-Z][A-Za-z0-9]*[a-z][A-Za-z0-9]*|[A-Z][A-Z0-9_]{2,}")
FILE_THEN_NAME = re.compile(r"`((?:app|devices|bench|tests)/[\w/.-]+\.py)`,? `(\w+)(?:\(\))?`")
SECTION_HERE = re.compile(r"\"([^\"]+)\"\)? (?:below|above)")
PLACEHOLDER = re.compile(r"<|[A-Z]{3,}")
PROSE_PATH = re.compile(r"(?<![\w/.`-])((?:app|devices|bench|tests|static|docs|\.ci)/[\w/.*<>-]*"
                        r"[\w/>])")


def _unfenced(text: str) -> list[str]:
    """The lines outside fenced blocks; a fence is blanked, not removed, so the line numbers
    stay those of the file."""
    return FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text).splitlines()


def _spans(text: str) -> list[tuple[int, str]]:
    """(line number, backtick span) outside fenced blocks, and each path in the prose around
    them as a span of its own."""
    spans = []
    for n, line in enumerate(_unfenced(text), 1):
        spans += [(n, s.strip()) for s in SPAN.findall(line)]
        spans += [(n, p) for p in PROSE_PATH.findall(SPAN.sub("", line))]
    return spans


def _ignored(path: str) -> bool:
    patterns = [p.strip().strip("/") for p in (ROOT / ".gitignore").read_text().splitlines()]
    return any(p and "*" not in p and path.rstrip("/").startswith(p) for p in patterns)


def _path_exists(path: str, test: str | None) -> bool:
    if PLACEHOLDER.search(path) or _ignored(path):
        return True
    if "*" in path:
        return any(ROOT.glob(path))
    target = ROOT / path
    if not target.exists():
        return False
    defined = rf"^\s*(?:def|class) {test}\b|^{test}\b\s*[:=]"
    return test is None or re.search(defined, target.read_text(), re.M) is not None


def _resolves(dotted: str) -> bool:
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for name in parts[i:]:
            if not hasattr(obj, name):
                return False
            obj = getattr(obj, name)
        return True
    return False


def _code_names() -> tuple[set[str], set[str]]:
    files = [p for d in CODE_DIRS for p in (ROOT / d).rglob("*.py")]
    tests = "\n".join(p.read_text() for p in (ROOT / "tests").rglob("*.py"))
    return {p.name for p in files}, set(re.findall(r"def (test_\w+)", tests))


def _broken_names(doc: Path, files: set[str], test_defs: set[str]) -> list[str]:
    broken = []
    for n, span in _spans(doc.read_text(encoding="utf-8")):
        token = span.split()[0] if span.split() else span
        where = f"{doc.name}:{n}: `{span}`"
        path, dotted = PATH.fullmatch(token), DOTTED.fullmatch(token)
        if path:
            ok = _path_exists(path.group(1), path.group(2))
        elif dotted:
            ok = _resolves(dotted.group(1))
        elif re.fullmatch(r"test_\w+", token):
            ok = token in test_defs
        elif re.fullmatch(r"[\w-]+\.py", token):
            ok = token in files
        else:
            continue
        if not ok:
            broken.append(where)
    return broken


def _broken_rows(doc: Path) -> list[str]:
    broken = []
    for n, line in enumerate(_unfenced(doc.read_text(encoding="utf-8")), 1):
        for path, name in FILE_THEN_NAME.findall(line):
            file = ROOT / path
            if file.is_file() and not re.search(rf"\b{name}\b", file.read_text(encoding="utf-8")):
                broken.append(f"{doc.name}:{n}: {path} `{name}`")
        row = FILE_ROW.match(line)
        if not row or not (ROOT / row.group(1)).is_file():
            continue  # a missing file is the names check's
        source = (ROOT / row.group(1)).read_text(encoding="utf-8")
        for span in SPAN.findall(row.group(2)):
            name = span.split("(")[0]
            called = span.endswith(")") and re.fullmatch(r"\w+", name) is not None
            if (called or CODE_NAME.fullmatch(name)) and not re.search(rf"\b{name}\b", source):
                broken.append(f"{doc.name}:{n}: {row.group(1)} `{span}`")
    return broken


def _has_section(section: str, text: str) -> bool:
    wanted = section.lower()
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("#"):
            if wanted in stripped.lower():
                return True
            continue
        item = re.sub(r"^(?:[-*]|\d+\.|\|)\s*", "", stripped).replace("`", "").lower()
        if item.lstrip("*").startswith(wanted):
            return True
    return any(b.lower().startswith(wanted) for b in re.findall(r"\*\*([^*]+)\*\*", text))


def _broken_sections(doc: Path) -> list[str]:
    text = doc.read_text(encoding="utf-8")
    broken = []
    for n, line in enumerate(text.splitlines(), 1):
        where = f"{doc.name}:{n}"
        for m in SECTION_AFTER_DOC.finditer(line):
            target = ROOT / "docs" / m.group(1)
            if not target.exists() or not _has_section(m.group(2), target.read_text()):
                broken.append(f'{where}: {m.group(1)} "{m.group(2)}"')
        broken += [f'{where}: "{m.group(1)}"' for m in SECTION_HERE.finditer(line)
                   if not _has_section(m.group(1), text)]
    return broken


def test_every_named_file_module_and_test_exists() -> None:
    files, test_defs = _code_names()
    assert [b for doc in DOCS for b in _broken_names(doc, files, test_defs)] == []


def test_a_file_and_its_table_name_what_the_file_holds() -> None:
    assert [b for doc in DOCS for b in _broken_rows(doc)] == []


def test_every_section_a_doc_points_to_exists() -> None:
    assert [b for doc in DOCS for b in _broken_sections(doc)] == []


def test_the_checks_see_a_renamed_name(tmp_path: Path) -> None:
    """The checks flag what they are for (a test that cannot fail would pass an empty list)."""
    doc = tmp_path / "probe.md"
    doc.write_text('`devices/master.py` `app.ui.commands.Gone` `test_nothing_named_so` `gone.py`'
                   ' `app/ui/commands.py` `app.ui.commands.CommandSender` plain `prose.words`\n'
                   'as tests/app/gone_test.py says, and tests/app/ too\n'
                   '| `app/rig.py` | `Rig`, `GoneClass`, `GONE_TABLE`, `gone()`, `rig`, `Rig.x` |\n'
                   'in `app/rig.py` `describe`, and `app/rig.py` `gone_name`\n'
                   'docs/hardening.md "No such section" and docs/hardening.md "Soak"\n')
    files, test_defs = _code_names()
    names = _broken_names(doc, files, test_defs)
    sections = _broken_sections(doc)
    rows = _broken_rows(doc)
    assert [b.split(": ", 1)[1] for b in names] == [
        "`devices/master.py`", "`app.ui.commands.Gone`", "`test_nothing_named_so`", "`gone.py`",
        "`tests/app/gone_test.py`"]
    assert [b.split(": ", 1)[1] for b in sections] == ['hardening.md "No such section"']
    assert [b.split(": ", 1)[1] for b in rows] == [
        "app/rig.py `GoneClass`", "app/rig.py `GONE_TABLE`", "app/rig.py `gone()`",
        "app/rig.py `gone_name`"]


def _map_rows(text: str) -> set[str]:
    return set(re.findall(r"^\|\s*`((?:app|devices)/[\w/.]*)`\s*\|", text, re.M))


def _modules_to_map() -> set[str]:
    """Each module of app/ and devices/ (not their packages' insides) and each package at any
    depth: what a newcomer looks for in the module map."""
    found = set()
    for top in ("app", "devices"):
        found |= {f"{top}/{p.name}" for p in (ROOT / top).glob("*.py") if p.name != "__init__.py"}
        found |= {f"{p.parent.relative_to(ROOT).as_posix()}/"
                  for p in (ROOT / top).rglob("__init__.py") if p.parent != ROOT / top}
    return found


def test_the_architecture_module_map_names_every_module_and_package() -> None:
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert sorted(_modules_to_map() - _map_rows(text)) == []


def test_the_module_map_check_sees_a_module_left_out() -> None:
    text = "| `app/cli.py` | the commands |\n| `devices/servo/` | the drive |\n"
    assert {"app/cli.py", "devices/servo/"} == _map_rows(text)
    assert "app/cli.py" in _modules_to_map() and "app/ui/panels/" in _modules_to_map()


CLASS_ATTR = re.compile(r"([A-Z]\w+)\.(\w+)(?:\(\))?")


def _class_bodies() -> dict[str, list[tuple[str, str]]]:
    """Each class of app/ and devices/ by name: (its bases, its body)."""
    bodies: dict[str, list[tuple[str, str]]] = {}
    for path in (p for d in ("app", "devices") for p in (ROOT / d).rglob("*.py")):
        text = path.read_text(encoding="utf-8") + "\n."
        for m in re.finditer(r"^class (\w+)(?:\((.*?)\))?:(.*?)(?=^\S)", text, re.M | re.S):
            bodies.setdefault(m[1], []).append((m[2] or "", m[3]))
    return bodies


def _class_attr_known(cls: str, attr: str, bodies: dict[str, list[tuple[str, str]]],
                      seen: frozenset[str] = frozenset()) -> bool:
    """``Rig.touch``: class ``Rig`` of the project, or a base of it, has ``attr`` as a method,
    a field or a ``self.`` attribute. A class the project does not define (a library's) is
    not this check's."""
    if cls not in bodies:
        return not seen
    for bases, body in bodies[cls]:
        if re.search(rf"def {attr}\b|^\s+{attr}\s*[:=]|self\.{attr}\s*[:=]", body, re.M):
            return True
        if any(_class_attr_known(b, attr, bodies, seen | {cls}) for b in re.findall(r"\w+", bases)
               if b in bodies and b not in seen):
            return True
    return False


def _broken_class_attrs(doc: Path, bodies: dict[str, list[tuple[str, str]]]) -> list[str]:
    return [f"{doc.name}:{n}: `{span}`" for n, span in _spans(doc.read_text(encoding="utf-8"))
            if (m := CLASS_ATTR.fullmatch(span)) and not _class_attr_known(m[1], m[2], bodies)]


# The docs a newcomer reads first; elsewhere `Class.name` also names LED channels
# (`Run.orange`, docs/cpx-e-ec.md) and library classes.
FIRST_READ = [ROOT / "README.md", *(ROOT / "docs" / f"{name}.md"
                                    for name in ("architecture", "rig-file", "scenarios"))]


def test_a_class_and_attribute_a_doc_names_exist() -> None:
    bodies = _class_bodies()
    assert [b for doc in FIRST_READ for b in _broken_class_attrs(doc, bodies)] == []


def test_the_class_attribute_check_sees_a_renamed_one(tmp_path: Path) -> None:
    doc = tmp_path / "probe.md"
    doc.write_text("`Rig.touch` `Rig.revision` `Runtime.submit()` `FastCat.apply` `Rig.untouched`"
                   " `FastCat.gone` `Library.x`\n")
    assert [b.split(": ", 1)[1] for b in _broken_class_attrs(doc, _class_bodies())] == [
        "`Rig.untouched`", "`FastCat.gone`"]
