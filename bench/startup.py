"""Benchmark 6 (issue 7, first half): ``python -m app`` to the first rendered page.

Headless Chromium (Debian's, through Playwright) is launched first, so that its own start is
not counted. Then, per run: the clock starts, ``python -m app`` is spawned on free ports with a
fresh state directory; as soon as the dashboard's port accepts a connection the page is opened,
and the clock stops when the page shows the FastCAT state text (the "ESM state" row of the
state panel holds a state instead of its "-" placeholder). Two figures per run: spawn to
listening, spawn to rendered; the median over the runs is printed. The test suite's wall time
(the other half of benchmark 6) is measured by CI.

    python -m bench startup [--quick] [--runs 3]
"""

from __future__ import annotations

import argparse
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench._browser import ROOT, VIEWPORT, chromium, free_port

PLACEHOLDER = "-"
TIMEOUT_S = 60.0
STATE_CELL = "#fr-state td"  # the first value cell: the "ESM state" row


def _listening(port: int) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=0.2):
            return True
    except OSError:
        return False


@dataclass
class Run:
    listening_s: float
    loaded_s: float  # the page's load event (viser's client bundle fetched and run)
    rendered_s: float
    state: str


def one_run(browser: Any) -> Run:
    port, modbus_port = free_port(), free_port()
    with tempfile.TemporaryDirectory(prefix="fieldrig-startup-") as state_dir:
        context = browser.new_context(viewport=VIEWPORT)
        page = context.new_page()
        log = Path(state_dir) / "stderr.txt"
        t0 = time.monotonic()
        with log.open("w") as stderr:  # a file, not a pipe nobody reads while it runs
            proc = subprocess.Popen(
                [sys.executable, "-m", "app", "--port", str(port), "--modbus-port",
                 str(modbus_port), "--state-dir", state_dir, "--run-for", str(TIMEOUT_S),
                 "--can-channel", f"startup-{port}"],
                cwd=ROOT, stdout=subprocess.DEVNULL, stderr=stderr)
        try:
            while not _listening(port):
                if proc.poll() is not None:
                    raise RuntimeError(f"python -m app exited: {log.read_text()}")
                if time.monotonic() - t0 > TIMEOUT_S:
                    raise RuntimeError("python -m app did not listen")
                time.sleep(0.01)
            listening = time.monotonic() - t0
            page.goto(f"http://127.0.0.1:{port}/", timeout=TIMEOUT_S * 1000)
            loaded = time.monotonic() - t0
            page.wait_for_function(
                "([sel, ph]) => { const c = document.querySelector(sel);"
                " return c && c.innerText.trim() && c.innerText.trim() !== ph; }",
                arg=[STATE_CELL, PLACEHOLDER], timeout=TIMEOUT_S * 1000, polling=10)
            rendered = time.monotonic() - t0
            state = page.locator(STATE_CELL).first.inner_text().strip()
        finally:
            context.close()
            proc.terminate()
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    return Run(listening, loaded, rendered, state)


def run(runs: int) -> list[Run]:
    with chromium() as browser:
        return [one_run(browser) for _ in range(runs)]


def report(results: list[Run]) -> list[str]:
    listening = statistics.median(r.listening_s for r in results)
    loaded = statistics.median(r.loaded_s for r in results)
    rendered = statistics.median(r.rendered_s for r in results)
    worst = max(r.rendered_s for r in results)
    return [f"Start-up: python -m app to the first rendered page ({len(results)} runs, "
            f"headless Chromium)",
            f"  spawn -> dashboard port listening  median {listening:6.2f} s",
            f"  spawn -> page load event           median {loaded:6.2f} s",
            f"  spawn -> FastCAT state shown       median {rendered:6.2f} s  worst "
            f"{worst:.2f} s  (first state: {results[-1].state!r})",
            "  target: none set in issue 7 (reported for trend); suite wall time: see CI"]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench startup",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true", help="one run (a smoke test)")
    p.add_argument("--runs", type=int, default=3)
    args = p.parse_args(argv)
    print("\n".join(report(run(1 if args.quick else args.runs))), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
