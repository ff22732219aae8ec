"""Benchmark 2 (issue 7): click to screen, measured inside the page.

Headless Chromium (Debian's, through Playwright) clicks and measures in the page itself:
``performance.now()`` just before the click, a ``MutationObserver`` seeing the change in the
DOM; p50 and p95 over the clicks. Two servers, each a process of its own, measured in
alternating rounds in one run:

- **floor**: a bare viser server with one button whose callback updates one markdown (what
  viser costs: websocket in, callback thread, message out, React render);
- **dashboard**: the default rig live at real-time speed (``app.runtime.Runtime``) behind the
  dashboard as shipped; the click is the "Hold CNF" checkbox (seed 000 §2: CNF pressed), the
  change the "CNF" row of the state panel (pressed, then released again by the next click).

Where the time goes: an init script wraps the page's websocket worker and notes when the
window carrying the answer reaches the page's main thread. "to the page" is click -> that
instant (browser -> server -> browser, plus any wait for a busy main thread); "in the page"
is that instant -> the DOM change (viser's message queue and React).

By default only the page being measured is open: every page of one browser shares one GPU
process, and a dashboard's software-WebGL frames there would slow the other pages' canvas
read-backs (the floor's too). ``--together`` keeps all pages open for the whole run (the
method of the first figures in docs/performance.md).

Target: the dashboard's p95 within 1.1x the floor's p95.

    python -m bench click [--quick] [--clicks 100] [--together]
"""

from __future__ import annotations

import argparse
import statistics
import sys
from typing import Any

from bench._browser import (
    VIEWPORT,
    ServerProcess,
    chromium,
    serve_dashboard,
    serve_until_stdin_closes,
)

TARGET = 1.1  # dashboard p95 / floor p95
KINDS = ("floor", "dashboard")
PAUSE_MS = 150  # between clicks: the page settles, the CNF hold stays far below 3 s
SETTLE_MS = 1000  # after a page shows its first state: the connection's backlog is applied
TIMEOUT_S = 60.0
QUERY = "?fixedDpr=1"  # as the screenshots: viser does not lower the canvas resolution

# Before any page script: note when each window of messages reaches the main thread, and
# whether it carries what window.__watch looks for.
INIT_JS = """
(() => {
  const Real = window.Worker;
  window.__arrivals = [];
  window.__watch = () => false;
  window.Worker = class extends Real {
    set onmessage(fn) {
      super.onmessage = (event) => {
        const data = event.data;
        if (data && data.type === 'message_batch' && data.messages.some(window.__watch)) {
          window.__arrivals.push(performance.now());
        }
        fn(event);
      };
    }
    get onmessage() { return super.onmessage; }
  };
})();
"""

# In the page: click, then wait until the watched text satisfies the test. Per click, ms from
# the click to the answer's window at the main thread and to the DOM change.
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
  const content = (m) => {  // an HTML handle's update carries content, a markdown's _markdown
    const u = m.type === 'GuiUpdateMessage' && m.updates;
    const text = u && (u.content !== undefined ? u.content : u._markdown);
    return typeof text === 'string' ? text : '';
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
      window.__watch = (m) => content(m).startsWith('clicks');
    } else {
      const pressing = !target.checked;
      done = () => cnfCell().startsWith('pressed') === pressing;
      window.__watch = (m) => content(m).includes('>CNF<')
        && content(m).includes('>pressed') === pressing;
    }
    window.__arrivals.length = 0;
    const [t0, t1] = await new Promise((resolve) => {
      let start = 0;
      const obs = new MutationObserver(() => {
        if (done()) { obs.disconnect(); resolve([start, performance.now()]); }
      });
      obs.observe(document.body, {subtree: true, childList: true, characterData: true});
      start = performance.now();
      target.click();
    });
    const arrived = window.__arrivals.find((t) => t >= t0);
    out.push([t1 - t0, arrived === undefined ? null : arrived - t0]);
    await new Promise((r) => setTimeout(r, pause));
  }
  return out;
}
"""


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

    serve_until_stdin_closes(server.stop)


# ---- the measurement -------------------------------------------------------------------------
def open_page(browser: Any, kind: str, server: ServerProcess) -> Any:
    context = browser.new_context(viewport=VIEWPORT)
    context.add_init_script(INIT_JS)
    page = context.new_page()
    page.goto(server.url(QUERY), timeout=TIMEOUT_S * 1000)
    ready = "Click" if kind == "floor" else "ESM state"
    page.get_by_text(ready, exact=False).first.wait_for(timeout=TIMEOUT_S * 1000)
    if kind != "floor":  # the first frame with a CNF phase in the state panel
        page.wait_for_function("() => [...document.querySelectorAll('#fr-state th')]"
                               ".some((th) => th.textContent === 'CNF')",
                               timeout=TIMEOUT_S * 1000)
    page.wait_for_timeout(SETTLE_MS)
    return page


Sample = tuple[float, float | None]  # (click -> DOM, click -> answer at the main thread) ms


def measure(clicks: int, rounds: int, together: bool) -> dict[str, list[Sample]]:
    samples: dict[str, list[Sample]] = {kind: [] for kind in KINDS}
    servers = {kind: ServerProcess("bench.click", kind, what=f"{kind} server")
               for kind in KINDS}
    try:
        with chromium() as browser:
            pages = ({kind: open_page(browser, kind, servers[kind]) for kind in KINDS}
                     if together else {})
            per_round = max(1, clicks // rounds)
            for _ in range(rounds):  # alternate: load changes hit every kind alike
                for kind in KINDS:
                    page = pages.get(kind) or open_page(browser, kind, servers[kind])
                    page.bring_to_front()
                    samples[kind] += [(total, arrived) for total, arrived in page.evaluate(
                        MEASURE_JS, [kind, per_round, PAUSE_MS])]
                    if not together:
                        page.context.close()
    finally:
        for server in servers.values():
            server.close()
    return samples


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def report(samples: dict[str, list[Sample]], together: bool) -> list[str]:
    p95 = {kind: percentile([t for t, _ in s], 0.95) for kind, s in samples.items()}
    n = len(samples["floor"])
    out = [f"Click to screen, in the page (performance.now at the click -> MutationObserver), "
           f"{n} clicks each, headless Chromium, "
           f"{'all pages open together' if together else 'one page open at a time'}"]
    labels = {"floor": "floor: bare viser, button -> markdown",
              "dashboard": "dashboard: Hold CNF -> state panel"}
    for kind, values in samples.items():
        totals = [t for t, _ in values]
        line = (f"  {labels[kind]:<38} p50 {statistics.median(totals):6.1f} ms  "
                f"p95 {p95[kind]:6.1f} ms")
        if kind != "floor":
            ratio = p95[kind] / p95["floor"]
            line += (f"  p95 / floor {ratio:4.2f}  (target <= {TARGET:g}) "
                     f"{'PASS' if ratio <= TARGET else 'FAIL'}")
        out.append(line)
        split = [(a, t - a) for t, a in values if a is not None]
        if split:
            out.append(f"    {'':<36} to the page p50 {statistics.median(a for a, _ in split):6.1f}"
                       f" ms, in the page p50 {statistics.median(p for _, p in split):6.1f} ms"
                       f" ({len(split)} of {len(values)} answers seen arriving)")
    return out


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["serve"]:
        port, kind = int(argv[1]), argv[2]
        if kind == "floor":
            _serve_floor(port)
        else:
            serve_dashboard(port)
        return 0
    p = argparse.ArgumentParser(prog="python -m bench click",
                                description=(__doc__ or "").split("\n")[0])
    p.add_argument("--quick", action="store_true", help="10 clicks each (a smoke test)")
    p.add_argument("--clicks", type=int, default=100)
    p.add_argument("--together", action="store_true",
                   help="keep every page open for the whole run (pages share one GPU process)")
    args = p.parse_args(argv)
    clicks = 10 if args.quick else args.clicks
    samples = measure(clicks, 2 if args.quick else 4, args.together)
    print("\n".join(report(samples, args.together)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
