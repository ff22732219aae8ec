"""CPU instructions per in-motion step of the default rig, under callgrind (issue 7 benchmark
1; docs/performance.md "Session 22", "Session 23"): the figure sessions 20-23 compare, as the
wall clock on this shared host moves the in-motion speed by up to 2x.

The rig is built and booted (``bench.kernel.boot``), the bench's ``motion()`` workload set up
and run 1 s, the collector run and switched off; then callgrind counts only the window of N
more motion steps, switched on and off around it by ``CALLGRIND_TOGGLE_COLLECT`` (a two-line C
helper built with ``cc`` into a temporary directory, called through ``ctypes``). Needs
valgrind and a C compiler; run it from a tree's root (it measures that tree). Its figures
compare with its own only: the same window in another script gave ~2 % apart on one tree
(docs/performance.md "Session 23").

    python -m bench.callgrind_window [--steps N] [--out FILE]
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

HELPER = "#include <valgrind/callgrind.h>\nvoid toggle(void) { CALLGRIND_TOGGLE_COLLECT; }\n"
INNER = "FIELDRIG_CALLGRIND_HELPER"  # set for the run under valgrind: the helper's path


def window(steps: int, helper: str) -> None:
    """The measured run (under valgrind): boot, 1 s of motion, then ``steps`` counted."""
    from app.rig_config import build_rig
    from bench import kernel

    toggle = ctypes.CDLL(helper).toggle
    rig = build_rig(kernel.default_spec(), state_dir=None)
    kernel.boot([rig])
    each = kernel.motion(rig)
    for i in range(1000):
        each(i)
        rig.step()
    gc.collect()
    gc.disable()  # the collector's passes fall where they will: not the step's own work
    step = rig.step
    toggle()
    for i in range(1000, 1000 + steps):
        each(i)
        step()
    toggle()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.callgrind_window")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--out", help="keep callgrind's output here (callgrind_annotate it)")
    args = parser.parse_args(argv)
    if INNER in os.environ:
        window(args.steps, os.environ[INNER])
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        source, helper = Path(tmp, "toggle.c"), Path(tmp, "toggle.so")
        source.write_text(HELPER)
        subprocess.run(["cc", "-shared", "-fPIC", "-o", str(helper), str(source)], check=True)
        out = args.out or str(Path(tmp, "callgrind.out"))
        # String hashes decide dict probes and set orders; setarch -R fixes the addresses.
        env = {**os.environ, INNER: str(helper), "PYTHONHASHSEED": "0"}
        subprocess.run(["setarch", "-R", "valgrind", "--tool=callgrind",
                        "--collect-atstart=no", f"--callgrind-out-file={out}",
                        sys.executable, "-m", "bench.callgrind_window",
                        "--steps", str(args.steps)], check=True, env=env,
                       stderr=subprocess.DEVNULL)
        totals = re.search(r"^totals: (\d+)", Path(out).read_text(), re.MULTILINE)
    if totals is None:
        print("no totals in callgrind's output", file=sys.stderr)
        return 1
    print(f"{int(totals.group(1)) / args.steps:,.0f} instructions a step "
          f"(default rig in motion, {args.steps} steps)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
