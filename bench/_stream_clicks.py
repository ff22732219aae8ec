"""Benchmark 3's clicking case: what one page's clicks cost the pages that watch, and itself.

A GUI message a page sends may have replaced a change its throttled sender dropped
(docs/dashboard.md "Fast clicks"); the widgets that show device values answer it by sending
the model's value again. This measures what that costs: the default rig idle in OP behind the
dashboard as shipped, one Python client clicking a control (``Reset fault`` by default: a
Synced box, seed 000 §6.17, harmless on a healthy coupler) at a set rate while 1 or 10 others
watch, each counted over an idle span and then a clicking span of the same length. "per
click" is the clicking span's messages less the idle span's, over the clicks sent.

``trees``: run the server from other checkouts of the project (``git worktree add``) in the
same run, alternating with this one, so the machine's load hits every tree alike. A tree
needs only ``python -m bench.streaming serve PORT idle plain`` (every tree since session 4).
"""

from __future__ import annotations

import asyncio
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bench._browser import ROOT, ServerProcess
from bench._viser_page import decode, encode, page

WATCHERS = (1, 10)
RATE = 5.0  # clicks per second: a person clicking briskly
LABEL = "Reset fault"


@dataclass
class Span:
    """Counts of what one page received between two instants (CLOCK_MONOTONIC)."""

    start: float
    end: float
    messages: int = 0
    bytes: int = 0
    by_type: dict[str, int] = field(default_factory=dict)

    def per_s(self) -> tuple[float, float]:
        seconds = self.end - self.start
        return self.bytes / seconds / 1000, self.messages / seconds


def _uuid_of(backlog: list[dict[str, Any]], label: str) -> str:
    for message in backlog:
        if message["type"].startswith("Gui") and message.get("props", {}).get("label") == label:
            return str(message["uuid"])
    raise LookupError(f"no widget labelled {label!r} in the dashboard")


async def _page(port: int, spans: list[Span], clicks: tuple[float, float] | None,
                label: str, rate: float, sent: list[int]) -> None:
    """One page: counts into ``spans``; with ``clicks`` (from, to), clicks ``label`` then."""
    import zstandard
    from viser._messages import GuiUpdateMessage

    unzip = zstandard.ZstdDecompressor()
    async with page(port) as (ws, first):
        backlog = decode(first, unzip)

        async def click() -> None:
            assert clicks is not None
            uuid, value = _uuid_of(backlog, label), False
            await asyncio.sleep(max(0.0, clicks[0] - time.monotonic()))
            while time.monotonic() < clicks[1]:
                value = not value  # as a page sends a checkbox's change
                await ws.send(encode(GuiUpdateMessage(uuid, {"value": value})))
                sent[0] += 1
                await asyncio.sleep(1 / rate)

        clicking = asyncio.ensure_future(click()) if clicks else None
        end = max(s.end for s in spans)
        while (now := time.monotonic()) < end:
            try:
                raw = await asyncio.wait_for(ws.recv(), timeout=end - now)
            except TimeoutError:
                break
            received = time.monotonic()
            span = next((s for s in spans if s.start <= received < s.end), None)
            if span is None or not isinstance(raw, bytes):
                continue
            messages = decode(raw, unzip)
            span.bytes += len(raw)
            span.messages += len(messages)
            for m in messages:
                kind = m["type"] + (":" + ",".join(m["updates"]) if "updates" in m else "")
                span.by_type[kind] = span.by_type.get(kind, 0) + 1
        if clicking is not None:
            await clicking


@dataclass
class Result:
    tree: str
    watchers: int
    clicks: int
    seconds: float
    watcher: list[tuple[Span, Span]]  # (idle, clicking) per watching page
    clicker: tuple[Span, Span]


def measure(port: int, tree: str, watchers: int, seconds: float, settle: float,
            label: str = LABEL, rate: float = RATE) -> Result:
    """Connect 1 + ``watchers`` pages, let their backlog pass (``settle`` s), count an idle
    span of ``seconds``, then a span of as long with the clicks."""
    begin = time.monotonic() + settle + 0.1 * watchers  # every page connected by then
    plan = [(begin, begin + seconds), (begin + seconds, begin + 2 * seconds)]
    pages = [[Span(a, b) for a, b in plan] for _ in range(1 + watchers)]
    sent = [0]

    async def main() -> None:
        await asyncio.gather(*(
            _page(port, spans, plan[1] if k == 0 else None, label, rate, sent)
            for k, spans in enumerate(pages)))
    asyncio.run(main())
    clicker, *rest = pages
    return Result(tree, watchers, sent[0], seconds,
                  [(s[0], s[1]) for s in rest], (clicker[0], clicker[1]))


def _mean(spans: list[Span]) -> tuple[float, float]:
    rates = [s.per_s() for s in spans]
    return statistics.fmean(r[0] for r in rates), statistics.fmean(r[1] for r in rates)


def lines(result: Result) -> list[str]:
    out = []
    for who, idle, busy in (("watching page", [w[0] for w in result.watcher],
                             [w[1] for w in result.watcher]),
                            ("clicking page", [result.clicker[0]], [result.clicker[1]])):
        (kb0, m0), (kb1, m1) = _mean(idle), _mean(busy)
        extra = (m1 - m0) * result.seconds / max(1, result.clicks)
        out.append(f"    {result.tree:<8} {result.watchers:>2} watching, {who}: idle "
                   f"{kb0:6.1f} kB/s {m0:6.1f} msg/s, clicking {kb1:6.1f} kB/s {m1:6.1f} msg/s"
                   f"  ({extra:+5.1f} messages per click)")
    return out


def widget_updates(result: Result) -> str:
    """GUI value updates (a widget's value set) per click, to a watching and the clicking page:
    what the widgets showing device values send for a click, LEDs and tables aside."""
    def per_click(spans: tuple[Span, Span]) -> float:
        idle, busy = (s.by_type.get("GuiUpdateMessage:value", 0) for s in spans)
        return (busy - idle) / max(1, result.clicks)
    return (f"    {result.tree:<8} {result.watchers:>2} watching, widget values per click: to a "
            f"watching page {per_click(result.watcher[0]):4.1f}, to the clicking page "
            f"{per_click(result.clicker):4.1f} ({result.clicks} clicks)")


def report(quick: bool, trees: list[Path], rate: float = RATE,
           label: str = LABEL) -> list[str]:
    seconds, settle = (3.0, 2.0) if quick else (10.0, 3.0)
    named = [("this", ROOT)] + [(t.name, t) for t in trees]
    out = [f"  clicking: one page clicks {label!r} at {rate:g}/s (a checkbox's change message "
           f"each), idle {seconds:g} s then clicking {seconds:g} s; rates per page"
           + (f"; trees: {', '.join(f'{n} = {p}' for n, p in named)}" if trees else "")]
    for watchers in WATCHERS:
        results = []
        for name, root in named:  # alternating, one server per tree and count
            server = ServerProcess("bench.streaming", "idle", "plain", what=f"{name} server",
                                   cwd=root)
            try:
                results.append(measure(server.port, name, watchers, seconds, settle, label,
                                       rate))
            finally:
                server.close()
        for result in results:
            out += lines(result)
        out += [widget_updates(r) for r in results]
    return out
