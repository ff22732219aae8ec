"""Run the benchmarks of issue 7: ``python -m bench`` runs them all, ``python -m bench NAME
[options]`` one of them (options go to that benchmark; ``python -m bench NAME --help``).

A benchmark is a module ``bench/NAME.py`` with ``main(argv: list[str] | None) -> int`` that
prints its figures, each with its target. The ones of issue 7 run in the issue's order; any
other module with a ``main`` is found and runs after them, so a new benchmark plugs in by
being added to this folder. One that fails is reported and the others still run.
Method and latest figures: docs/performance.md.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import time
import traceback
from collections.abc import Callable
from pathlib import Path

# Issue 7 "Benchmarks", in its order; a name without a module yet is listed as missing.
ISSUE_ORDER = ("kernel", "click", "streaming", "modbus", "canopen", "startup")
HERE = Path(__file__).resolve().parent


def available() -> list[str]:
    """Benchmark modules in this folder: issue order first, then the others by name."""
    found = {m.name for m in pkgutil.iter_modules([str(HERE)])
             if not m.name.startswith("_") and not m.ispkg}
    return [n for n in ISSUE_ORDER if n in found] + sorted(found - set(ISSUE_ORDER))


def entry(name: str) -> Callable[[list[str] | None], int] | None:
    module = importlib.import_module(f"bench.{name}")
    main = getattr(module, "main", None)
    return main if callable(main) else None


def run_one(name: str, argv: list[str]) -> int:
    main = entry(name)
    if main is None:
        print(f"bench/{name}.py has no main(argv): not a benchmark", file=sys.stderr)
        return 2
    return main(argv)


def run_all() -> int:
    names = available()
    missing = [n for n in ISSUE_ORDER if n not in names]
    failed: list[str] = []
    for name in names:
        print(f"=== {name} " + "=" * (70 - len(name)), flush=True)
        start = time.monotonic()
        try:
            main = entry(name)
            if main is None:
                continue
            code = main([])
        except Exception:  # one broken benchmark must not hide the others' figures
            traceback.print_exc()
            code = 1
        if code:
            failed.append(name)
        print(f"--- {name}: {time.monotonic() - start:.0f} s wall", flush=True)
    if missing:
        print(f"not written yet: {', '.join(missing)}")
    if failed:
        print(f"failed to run: {', '.join(failed)}")
    return 1 if failed else 0


def main(argv: list[str]) -> int:
    if not argv:
        return run_all()
    name, rest = argv[0], argv[1:]
    if name in ("-h", "--help"):
        print(__doc__)
        print(f"benchmarks: {', '.join(available())}")
        return 0
    if name not in available():
        print(f"no benchmark {name!r} (have: {', '.join(available())})", file=sys.stderr)
        return 2
    return run_one(name, rest)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
