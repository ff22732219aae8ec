"""Benchmark 2 (issue 7): click to screen, measured inside the page.

Headless Chromium (Debian's, through Playwright) clicks and measures in the page itself:
``performance.now()`` just before the click, a ``MutationObserver`` seeing the change in the
DOM; p50 and p95 over the clicks. Three servers, each a process of its own, measured in
alternating rounds in one run:

- **floor**: a bare viser server with one button whose callback updates one markdown (what
  viser costs: websocket in, callback thread, message out, React render);
- **dashboard**: the default rig live at real-time speed (``app.runtime.Runtime``) behind the
  dashboard as shipped; the click is the "Hold CNF" checkbox (seed 000 §2: CNF pressed), the
  change the "CNF" row of the state panel (pressed, then released again by the next click);
- **dashboard, woken**: the same with the update thread woken by each frame the runtime
  publishes (``Runtime.add_frame_listener``) and ``server.flush()`` after each update, the
  change proposed for app/ui/dashboard.py (docs/performance.md); measured here by a subclass;
- **dashboard, woken and lean**: also without the simulated time in the state panels' titles
  (patched in the bench process), so their HTML is resent only when a value changes: the
  page's share of the latency (proposal 3 of docs/performance.md).

Target: the dashboard's p95 within 1.1x the floor's p95.

    python -m bench click [--quick] [--clicks 100]
"""

from __future__ import annotations

import argparse
import socket
import statistics
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = "/usr/bin/chromium"
LAUNCH_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
    "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
]
TARGET = 1.1  # dashboard p95 / floor p95
KINDS = ("floor", "dashboard", "woken", "lean")
PAUSE_MS = 150  # between clicks: the page settles, the CNF hold stays far below 3 s
TIMEOUT_S = 60.0

# In the page: click, then wait until the watched text satisfies the test; the times in ms.
MEASURE_JS = """
async ([kind, n, pause]) => {
  const byLabel = (text) => {
    const label = [...document.querySelectorAll('label')].find(
      (l) => l.textContent.trim() === text);
    return label && document.getElementById(label.htmlFor);
  };
  const cnfCell = () => {
    const row = [...document.querySelectorAll('#fr-state tr')].find(
      (r) => (r.querySelector('th') || {}).textContent === 'CNF');
    return row ? row.querySelector('td').textContent.trim() : '';
  };
  const floorText = () => {
    const md = [...document.querySelectorAll('p')].find((p) => p.textContent.startsWith('clicks'));
    return md ? md.textContent : '';
  };
  const target = kind === 'floor'
    ? [...document.querySelectorAll('button')].find((b) => b.textContent.trim() === 'Click')
    : byLabel('Hold CNF');
  const out = [];
  for (let i = 0; i < n; i++) {
    let done;
    if (kind === 'floor') {
      const before = floorText();
      done = () => floorText() !== before;
    } else {
      const pressing = !target.checked;
      done = () => cnfCell().startsWith('pressed') === pressing;
    }
    const dt = await new Promise((resolve) => {
      let t0 = 0;
      const obs = new MutationObserver(() => {
        if (done()) { obs.disconnect(); resolve(performance.now() - t0); }
      });
      obs.observe(document.body, {subtree: true, childList: true, characterData: true});
      t0 = performance.now();
      target.click();
    });
    out.push(dt);
    await new Promise((r) => setTimeout(r, pause));
  }
  return out;
}
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


# ---- the servers (child processes) -----------------------------------------------------------
def _serve_floor(port: int) -> None:
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    button = server.gui.add_button("Click")
    text = server.gui.add_markdown("clicks 0")
    count = [0]

    @button.on_click
    def _(_event: Any) -> None:
        count[0] += 1
        text.content = f"clicks {count[0]}"

    print("ready", flush=True)
    sys.stdin.read()
    server.stop()


def _serve_dashboard(port: int, woken: bool, lean: bool = False) -> None:
    import viser

    if lean:  # the titles without "t = ... s": patched where the panels look them up
        from app.ui.drive import drive_state
        from app.ui.panels import state

        panel_title, drive_title = state.title, drive_state.title
        state.title = lambda snap, master, _t: panel_title(snap, master, 0)  # type: ignore
        drive_state.title = lambda i, snap, _t: drive_title(i, snap, 0)  # type: ignore

    from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
    from app.runtime import Runtime
    from app.ui import dashboard as ui

    class WokenDashboard(ui.Dashboard):
        """The proposal: update when a frame is published, and send it at once."""

        def _run(self) -> None:
            wake = threading.Event()
            self.runtime.add_frame_listener(lambda _frame: wake.set())
            period = 1.0 / ui.UPDATE_HZ
            while not self._stop.is_set():
                wake.wait(period)
                wake.clear()
                try:
                    self.tick()
                    self.server.flush()
                except Exception:
                    ui.logger.exception("dashboard update failed")

    rig = build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None)
    runtime = Runtime(rig)
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    dashboard = (WokenDashboard if woken else ui.Dashboard)(server, runtime)
    runtime.start()
    dashboard.start()
    for device_id, info in rig.describe().items():  # powered, as `python -m app` starts it
        if "power" in info["actions"]:
            runtime.command(device_id, "power", {"on": True}).result(10)
    print("ready", flush=True)
    sys.stdin.read()
    dashboard.stop()
    runtime.stop()
    server.stop()


class Server:
    def __init__(self, kind: str) -> None:
        self.kind, self.port = kind, _free_port()
        self.proc = subprocess.Popen([sys.executable, "-m", "bench.click", "serve", kind,
                                      str(self.port)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, cwd=ROOT)
        assert self.proc.stdout is not None
        for line in self.proc.stdout:  # viser prints its banner first
            if line.strip() == "ready":
                break
        else:
            self.close()
            raise RuntimeError(f"{kind} server did not start")

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}/?fixedDpr=1"

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        try:
            self.proc.wait(15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


# ---- the measurement -------------------------------------------------------------------------
def open_page(browser: Any, server: Server) -> Any:
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.goto(server.url, timeout=TIMEOUT_S * 1000)
    ready = "Click" if server.kind == "floor" else "ESM state"
    page.get_by_text(ready, exact=False).first.wait_for(timeout=TIMEOUT_S * 1000)
    if server.kind != "floor":  # the first frame with a CNF phase in the state panel
        page.wait_for_function("() => [...document.querySelectorAll('#fr-state th')]"
                               ".some((th) => th.textContent === 'CNF')",
                               timeout=TIMEOUT_S * 1000)
    page.wait_for_timeout(1000)
    return page


def measure(clicks: int, rounds: int) -> dict[str, list[float]]:
    from playwright.sync_api import sync_playwright

    if not Path(CHROMIUM).exists():
        raise RuntimeError(f"{CHROMIUM} is missing (apt-get install chromium)")
    times: dict[str, list[float]] = {kind: [] for kind in KINDS}
    servers = {kind: Server(kind) for kind in KINDS}
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_ARGS)
            try:
                pages = {kind: open_page(browser, server) for kind, server in servers.items()}
                per_round = max(1, clicks // rounds)
                for _ in range(rounds):  # alternate: load changes hit every kind alike
                    for kind in KINDS:
                        pages[kind].bring_to_front()
                        times[kind] += pages[kind].evaluate(MEASURE_JS,
                                                            [kind, per_round, PAUSE_MS])
            finally:
                browser.close()
    finally:
        for server in servers.values():
            server.close()
    return times


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def report(times: dict[str, list[float]]) -> list[str]:
    p95 = {kind: percentile(v, 0.95) for kind, v in times.items()}
    out = [f"Click to screen, in the page (performance.now at the click -> MutationObserver), "
           f"{len(times['floor'])} clicks each, headless Chromium"]
    labels = {"floor": "floor: bare viser, button -> markdown",
              "dashboard": "dashboard as shipped: Hold CNF -> state panel",
              "woken": "dashboard, update woken + flush (proposal)",
              "lean": "dashboard, woken + no time in panel HTML"}
    for kind, values in times.items():
        line = (f"  {labels[kind]:<48} p50 {statistics.median(values):6.1f} ms  "
                f"p95 {p95[kind]:6.1f} ms")
        if kind != "floor":
            ratio = p95[kind] / p95["floor"]
            line += f"  p95 / floor {ratio:4.2f}  (target <= {TARGET:g}) " \
                    f"{'PASS' if ratio <= TARGET else 'FAIL'}"
        out.append(line)
    return out


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["serve"]:
        kind, port = argv[1], int(argv[2])
        if kind == "floor":
            _serve_floor(port)
        else:
            _serve_dashboard(port, woken=kind in ("woken", "lean"), lean=kind == "lean")
        return 0
    p = argparse.ArgumentParser(prog="python -m bench click",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true", help="10 clicks each (a smoke test)")
    p.add_argument("--clicks", type=int, default=100)
    args = p.parse_args(argv)
    clicks = 10 if args.quick else args.clicks
    print("\n".join(report(measure(clicks, 2 if args.quick else 4))), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
