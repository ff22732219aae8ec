"""Rig files and scenarios under broken TOML and wrong values: one clear error, never a traceback.

Issue 7 "Hardening". Hypothesis feeds
- the shipped rig and scenario files with random edits (spans deleted, characters inserted,
  lines duplicated, values swapped for other TOML values),
- their parsed structure with wrong values put back as TOML (every type TOML has, huge and
  negative numbers, nan, empty and odd strings, nested tables, unknown keys, keys removed),

to ``parse_rig_spec`` + ``build_rig`` (RigConfigError only) and ``parse_scenario`` +
``check_against`` the default rig (ScenarioError / RigConfigError only); every message is one
line. Files that are refused also go to the CLI, in process (``app.cli.main``): exit 2 and one
line on stderr. A few go to a real ``python -m app`` process. The shipped files also go as
bytes (in another encoding, bytes inserted, overwritten or cut) to ``load_rig_spec`` /
``load_scenario``: a file that is not UTF-8 is refused at its first bad byte. Examples: 120 per
property in CI, 1,500 with ``--full``.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import io
import json
import math
import subprocess
import sys
import tomllib
import traceback
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.cli import main as cli_main
from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec, parse_rig_spec
from app.scenario import ScenarioError, check_against, load_scenario, parse_scenario

ROOT = Path(__file__).resolve().parents[2]
RIG_FILES = sorted((ROOT / "static" / "rigs").glob("*.toml"))
SCENARIO_FILES = sorted((ROOT / "static" / "scenarios").glob("*.toml"))
REFUSALS = (RigConfigError, ScenarioError)


def _examples(full: bool) -> settings:
    return settings(max_examples=1_500 if full else 120, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


# ---- TOML values and a small writer (tomllib reads only) -------------------------------------
SCALARS = st.one_of(
    st.integers(), st.integers(-5, 100), st.sampled_from([0, -1, 2**63, -(2**63) - 1, 2**64]),
    st.floats(allow_nan=True, allow_infinity=True), st.booleans(),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, -0.0, 0.5, 1e9]),
    st.text(max_size=12), st.sampled_from(["", "fastcat", "drive", "DI16", "0x8000", "nan",
                                            "../../etc/passwd", "a\nb", "∞"]),
    st.datetimes(min_value=dt.datetime(1, 1, 1), max_value=dt.datetime(9999, 1, 1)),
    st.dates(),
)
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(min_size=1, max_size=6), inner,
                                                 max_size=3)), max_leaves=8)


def toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") \
            if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, dt.datetime | dt.date | dt.time):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_string(k)} = {toml_value(v)}" for k, v in value.items()) \
            + "}"
    raise TypeError(type(value))


def toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    def escape(ch: str) -> str:
        if ch in '"\\':
            return "\\" + ch
        return f"\\u{ord(ch):04x}" if ord(ch) < 0x20 or ord(ch) == 0x7F else ch

    return '"' + "".join(escape(ch) for ch in text) + '"'


def toml_document(data: dict[str, Any]) -> str:
    """Top-level scalars, then ``[table]`` and ``[[array of tables]]`` sections."""
    lines, later = [], []
    for key, value in data.items():
        name = toml_string(key)
        if isinstance(value, dict):
            later += [f"[{name}]"] + [f"{toml_string(k)} = {toml_value(v)}"
                                      for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for table in value:
                later += [f"[[{name}]]"] + [f"{toml_string(k)} = {toml_value(v)}"
                                            for k, v in table.items()]
        else:
            lines.append(f"{name} = {toml_value(value)}")
    return "\n".join(lines + later) + "\n"


# ---- edits -----------------------------------------------------------------------------------
TOML_CHARS = "[]{}=\"'.,#\n \t0123456789-+:TZabcdefxyz_\\"


@st.composite
def edited_text(draw: st.DrawFn, texts: list[str]) -> str:
    text = draw(st.sampled_from(texts))
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["delete", "insert", "duplicate", "value"]))
        i = draw(st.integers(0, len(text)))
        if kind == "delete":
            text = text[:i] + text[i + draw(st.integers(1, 40)):]
        elif kind == "insert":
            text = text[:i] + draw(st.text(TOML_CHARS, min_size=1, max_size=8)) + text[i:]
        elif kind == "duplicate":
            lines = text.splitlines(keepends=True) or [""]
            j = draw(st.integers(0, len(lines) - 1))
            text = "".join(lines[:j + 1] + lines[j:])
        else:  # swap the value of one "key = value" line for another TOML value
            lines = text.splitlines()
            keyed = [j for j, line in enumerate(lines) if "=" in line and
                     not line.lstrip().startswith("#")]
            if keyed:
                j = draw(st.sampled_from(keyed))
                lines[j] = lines[j].split("=", 1)[0] + "= " + toml_value(draw(VALUES))
                text = "\n".join(lines) + "\n"
    return text


@st.composite
def wrong_values(draw: st.DrawFn, documents: list[dict[str, Any]]) -> str:
    """A parsed document with some values replaced, removed or added, written back as TOML."""
    data = json.loads(json.dumps(draw(st.sampled_from(documents)), default=str))
    for _ in range(draw(st.integers(1, 3))):
        tables = _tables(data)
        table = draw(st.sampled_from(tables))
        kind = draw(st.sampled_from(["replace", "replace", "remove", "add"]))
        if kind == "add" or not table:
            table[draw(st.sampled_from(["x", "id", "type", "at", "speed", "registers"]))] = \
                draw(VALUES)
        elif kind == "remove":
            del table[draw(st.sampled_from(sorted(table)))]
        else:
            table[draw(st.sampled_from(sorted(table)))] = draw(VALUES)
    return toml_document(data)


def _tables(data: Any) -> list[dict[str, Any]]:
    found = []
    if isinstance(data, dict):
        found.append(data)
        for value in data.values():
            found += _tables(value)
    elif isinstance(data, list):
        for value in data:
            found += _tables(value)
    return found


RIG_TEXTS = [p.read_text(encoding="utf-8") for p in RIG_FILES]
SCENARIO_TEXTS = [p.read_text(encoding="utf-8") for p in SCENARIO_FILES]
RIG_DOCS = [tomllib.loads(t) for t in RIG_TEXTS]
SCENARIO_DOCS = [tomllib.loads(t) for t in SCENARIO_TEXTS]
_RIG = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)  # scenarios are checked against it


# ---- known escapes -----------------------------------------------------------------------------
# Inputs that still end in a traceback, reported to the lead with their fix (issue 7 hardening,
# docs/hardening.md). Keyed by (exception, file, function) where it escapes. The
# systematic tests below report them as xfail while any is seen, and pass once none is left;
# the random properties let them through so that they look for new ones. Remove an entry when
# its fix lands.
# Tracebacks the fuzz once found (non-finite times in scenarios, a CPX module item of the wrong
# type) are fixed; add an entry here only for a new one that is reported and not yet fixed.
KNOWN_ESCAPES: dict[tuple[str, str, str], str] = {}


def _escape(exc: BaseException) -> tuple[str, str, str]:
    """(exception, file, function) of the innermost frame of app/ or devices/."""
    ours = [f for f in traceback.extract_tb(exc.__traceback__)
            if not f.name.startswith("<") and (f.filename.startswith(str(ROOT / "app")) or
                                                f.filename.startswith(str(ROOT / "devices")))]
    where = ours[-1] if ours else None
    return (type(exc).__name__, str(Path(where.filename).relative_to(ROOT)) if where else "?",
            where.name if where else "?")


# ---- the properties --------------------------------------------------------------------------
def _one_line(exc: BaseException) -> None:
    message = str(exc)
    # splitlines, not "\n": NEL, U+2028 and the other line ends split the CLI's line too
    assert len(message.splitlines()) == 1 and "Traceback" not in message, repr(message)


def _rig(text: str) -> None:
    try:
        build_rig(parse_rig_spec(text, "fuzz.toml"), state_dir=None)
    except RigConfigError as exc:
        _one_line(exc)
        assert str(exc).startswith("fuzz.toml"), str(exc)  # it names the file


def _scenario(text: str) -> bool:
    """True when the scenario is refused (with one clear error)."""
    try:
        scenario = parse_scenario(text, "fuzz.toml")
        if scenario.rig is None:
            check_against(scenario, _RIG)
        else:
            load_rig_spec(scenario.rig)
    except REFUSALS as exc:
        _one_line(exc)
        return True
    return False


def _tolerating_known(check: Any, text: str) -> Any:
    try:
        return check(text)
    except (AssertionError, *REFUSALS):
        raise
    except Exception as exc:
        if _escape(exc) in KNOWN_ESCAPES:
            return None
        raise


def _cli_refuses(tmp: Path, text: str) -> None:
    path = tmp / "fuzz.toml"
    path.write_text(text, encoding="utf-8")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli_main(["scenario", "run", str(path), "--quiet"])
    lines = err.getvalue().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("fieldrig: error: "), \
        (code, err.getvalue())


def test_rig_files_with_random_edits(full: bool) -> None:
    @_examples(full)
    @given(edited_text(RIG_TEXTS))
    def prop(text: str) -> None:
        _tolerating_known(_rig, text)

    prop()


def test_rig_files_with_wrong_values(full: bool) -> None:
    @_examples(full)
    @given(wrong_values(RIG_DOCS))
    def prop(text: str) -> None:
        _tolerating_known(_rig, text)

    prop()


def test_scenarios_with_random_edits(full: bool, tmp_path: Path) -> None:
    @_examples(full)
    @given(edited_text(SCENARIO_TEXTS))
    def prop(text: str) -> None:
        if _tolerating_known(_scenario, text):
            _cli_refuses(tmp_path, text)

    prop()


def test_scenarios_with_wrong_values(full: bool, tmp_path: Path) -> None:
    @_examples(full)
    @given(wrong_values(SCENARIO_DOCS))
    def prop(text: str) -> None:
        if _tolerating_known(_scenario, text):
            _cli_refuses(tmp_path, text)

    prop()


# ---- bytes: files an editor saved in another encoding, or damaged -------------------------------
ENCODINGS = ("latin-1", "cp1252", "utf-16", "utf-16-be", "utf-8-sig", "utf-8")


@st.composite
def edited_bytes(draw: st.DrawFn, texts: list[str]) -> bytes:
    """A shipped file in another encoding (most of them hold a non-ASCII character: a §, an
    arrow), then bytes inserted, overwritten with a non-ASCII byte, or cut off (mid-character)."""
    encoding = draw(st.sampled_from(ENCODINGS))
    data = draw(st.sampled_from(texts)).encode(encoding, errors="replace")
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.sampled_from(["insert", "overwrite", "cut"]))
        i = draw(st.integers(0, len(data)))
        if kind == "insert":
            data = data[:i] + draw(st.binary(min_size=1, max_size=4)) + data[i:]
        elif kind == "overwrite":
            data = data[:i] + bytes([draw(st.integers(0x80, 0xFF))]) + data[i + 1:]
        else:
            data = data[:i]
    return data


def _file_tree(tmp: Path) -> Path:
    """tmp/rigs and tmp/networks are the shipped ones, so that the relative paths of a rig
    (``../networks/...``) and of a scenario (``../rigs/...``) in tmp/fuzz/ still resolve."""
    for name in ("rigs", "networks"):
        if not (tmp / name).exists():
            (tmp / name).symlink_to(ROOT / "static" / name, target_is_directory=True)
    (tmp / "fuzz").mkdir(exist_ok=True)
    return tmp / "fuzz" / "fuzz.toml"


def _not_utf8_is_named(data: bytes, exc: BaseException, path: Path) -> None:
    """A file that is not UTF-8 is refused for that, at its first bad byte."""
    _one_line(exc)
    assert str(exc).startswith(str(path)), str(exc)
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as bad:
        assert str(exc).endswith(f"not UTF-8 text: byte 0x{data[bad.start]:02x} at offset "
                                 f"{bad.start}"), str(exc)


def test_rig_files_as_bytes(full: bool, tmp_path: Path) -> None:
    path = _file_tree(tmp_path)

    @_examples(full)
    @given(edited_bytes(RIG_TEXTS))
    def prop(data: bytes) -> None:
        path.write_bytes(data)
        try:
            build_rig(load_rig_spec(path), state_dir=None)
        except RigConfigError as exc:
            _not_utf8_is_named(data, exc, path)

    prop()


def test_scenario_files_as_bytes(full: bool, tmp_path: Path) -> None:
    path = _file_tree(tmp_path)

    @_examples(full)
    @given(edited_bytes(SCENARIO_TEXTS))
    def prop(data: bytes) -> None:
        path.write_bytes(data)
        try:
            scenario = load_scenario(path)
            check_against(scenario, build_rig(load_rig_spec(scenario.rig or DEFAULT_RIG),
                                              state_dir=None))
        except REFUSALS as exc:
            _not_utf8_is_named(data, exc, path)
            out, err = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                code = cli_main(["scenario", "run", str(path), "--quiet"])
            assert code == 2 and err.getvalue() == f"fieldrig: error: {exc}\n", \
                (code, err.getvalue())

    prop()


# ---- every key, every edge value (systematic) -------------------------------------------------
EDGE_VALUES = (math.nan, math.inf, -math.inf, 1e308, -1.0, 0.5, 0, -1, 2**63 - 1, 2**63,
               -(2**63), True, "", "x", "../../x", [], [1, "a"], {}, {"a": 1},
               dt.datetime(2020, 1, 1, 12, 0), dt.date(2020, 1, 1), dt.time(12, 0))


def _variants(doc: dict[str, Any]) -> list[str]:
    """The document with one key at a time set to each edge value (each key pattern once)."""
    seen: set[tuple[str, str]] = set()
    texts = []
    for path, table in _tables_with_paths(doc, ""):
        for key in list(table):
            if (path, key) in seen:
                continue
            seen.add((path, key))
            for value in EDGE_VALUES:
                old = table[key]
                table[key] = value
                texts.append(toml_document(doc))
                table[key] = old
    return texts


def _tables_with_paths(data: Any, path: str) -> list[tuple[str, dict[str, Any]]]:
    """Every table with its key path, list indices dropped (``step[].target`` for all steps)."""
    found: list[tuple[str, dict[str, Any]]] = []
    if isinstance(data, dict):
        found.append((path, data))
        for key, value in data.items():
            found += _tables_with_paths(value, f"{path}.{key}")
    elif isinstance(data, list):
        for value in data:
            found += _tables_with_paths(value, f"{path}[]")
    return found


def _systematic(texts: list[str], check: Any) -> None:
    known: dict[tuple[str, str, str], str] = {}
    for text in texts:
        try:
            check(text)
        except (AssertionError, *REFUSALS):
            raise
        except Exception as exc:
            escape = _escape(exc)
            if escape not in KNOWN_ESCAPES:
                raise
            known[escape] = KNOWN_ESCAPES[escape]
    if known:
        pytest.xfail("known tracebacks, reported: " + "; ".join(
            f"{e[0]} in {e[1]} {e[2]}() ({why})" for e, why in sorted(known.items())))


CLI_EVERY = 25  # reduced form: every 25th refused scenario also goes through the CLI


def _all_variants(docs: list[dict[str, Any]]) -> list[str]:
    return [text for doc in docs for text in _variants(json.loads(json.dumps(doc, default=str)))]


def test_every_rig_key_takes_every_edge_value() -> None:
    _systematic(_all_variants(RIG_DOCS), _rig)


def test_every_scenario_key_takes_every_edge_value(tmp_path: Path, full: bool) -> None:
    refused = 0

    def check(text: str) -> None:
        nonlocal refused
        if _scenario(text):
            refused += 1
            if full or refused % CLI_EVERY == 0:  # the CLI builds a rig: ~10 ms a call
                _cli_refuses(tmp_path, text)

    _systematic(_all_variants(SCENARIO_DOCS), check)


# ---- the real command line ---------------------------------------------------------------------
BROKEN = {
    "scenario_not_toml": ("scenario", "[[step]\nat = 1\n"),
    "scenario_wrong_type": ("scenario", "[[step]]\nat = \"soon\"\ncaption = \"x\"\n"),
    "scenario_unknown_action": ("scenario", "[[step]]\nat = 1\ntarget = \"fastcat\"\n"
                                            "action = \"explode\"\n"),
    "rig_wrong_value": ("rig", "[[fastcat]]\nmodules = [\"DI16\"]\nrotary_switch = 99\n"),
}


def test_the_real_cli_prints_one_line_and_exits_2(tmp_path: Path) -> None:
    for name, (kind, text) in BROKEN.items():
        path = tmp_path / f"{name}.toml"
        path.write_text(text, encoding="utf-8")
        args = ["scenario", "run", str(path)] if kind == "scenario" else \
            ["--rig", str(path), "--state-dir", str(tmp_path / "state"), "--run-for", "0"]
        proc = subprocess.run([sys.executable, "-m", "app", *args], cwd=ROOT,
                              capture_output=True, text=True, timeout=120)
        lines = proc.stderr.splitlines()
        assert proc.returncode == 2, (name, proc.returncode, proc.stderr)
        assert len(lines) == 1 and lines[0].startswith("fieldrig: error: "), (name, proc.stderr)
        assert str(path) in lines[0], (name, lines[0])  # it names the file
