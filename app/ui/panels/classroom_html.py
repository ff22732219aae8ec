"""The classroom panel's HTML blocks: what a trainee and the instructor read.

Each block carries an id (``fr-exercise-*``) and ``data-phase`` for browser tests.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any, Literal, Protocol

from app.ui.style import esc

TRAINEE_ID = "fr-exercise-trainee"
INSTRUCTOR_ID = "fr-exercise-instructor"
HISTORY_ID = "fr-exercise-history"
MAX_ACTIONS_SHOWN = 12


class Names(Protocol):
    def get(self, client_id: int | None) -> str | None: ...


Audience = Literal["trainee", "instructor", "open"]
LATCHED = ("If the rig still shows an alarm, reset it (Reset fault, resync, alarm reset), then "
           "press <i>Done</i>.")


def trainee_html(report: Mapping[str, Any] | None, elapsed_s: float,
                 mine: bool = True, *, audience: Audience = "trainee", name: str = "") -> str:
    """The Exercise box. A trainee's: no hidden fault, no answer, no score: what the trainee
    is asked and whether the answer is in; ``mine``: this page named it (the first answer
    counts, another's was refused); ``name``: what the instructor's page calls this trainee
    ("" not yet named). The instructor's (a rig with a token): what the trainees are doing and
    where the result is, the Instructor folder under it. ``open``: a rig where every page is
    the instructor and answers too."""
    phase = report["phase"] if report else "none"
    if audience == "instructor":
        body = _instructor_words(phase, elapsed_s)
    elif report is None:
        starts = ("Start one in the Instructor folder below" if audience == "open" else
                  "When the instructor starts one")
        body = (f'<span class="fr-muted">No exercise is running. {starts}, the rig gets a '
                "hidden fault: find its cause from the LEDs, the codes and the log, name it "
                "below, then reset what stays latched and press Done.</span>")
    elif phase == "running":
        body = (f"<b>Exercise running</b> ({elapsed_s:.0f} s): the rig has a fault. Find its "
                "cause, pick it and press <i>Name the cause</i>.")
    elif phase == "answered" and mine:
        body = f"<b>Answer recorded.</b> {LATCHED}"
    elif phase == "answered":
        other = "Another page" if audience == "open" else "Another trainee"
        body = f"<b>{other} named a cause</b> (the first answer counts). {LATCHED}"
    elif audience == "open":
        body = "<b>Exercise finished.</b> The result and the score are in the Instructor folder."
    else:
        body = "<b>Exercise finished.</b> The instructor has your result."
    if name:
        body += f'<br><span class="fr-muted">The instructor\'s page calls you {esc(name)}.</span>'
    return f'<div id="{TRAINEE_ID}" data-phase="{phase}" style="font-size:0.85em">{body}</div>'


def _instructor_words(phase: str, elapsed_s: float) -> str:
    if phase == "none":
        return ('<span class="fr-muted">No exercise is running. Start one in the Instructor '
                "folder below: the trainees' pages ask them to find the hidden fault's cause, "
                "name it and press Done. Their answer, their commands and the score show "
                "there.</span>")
    if phase == "running":
        return (f"<b>Exercise running</b> ({elapsed_s:.0f} s): the trainees are looking for the "
                "cause (the answer is theirs: <i>Name the cause</i> is refused on this page). "
                "<i>End and score</i> in the Instructor folder ends it.")
    if phase == "answered":
        return ("<b>A trainee named a cause</b>: which, and whether it is right, is in the "
                "Instructor folder. They reset what stays latched and press <i>Done</i>; "
                "<i>End and score</i> ends it now.")
    return "<b>Exercise finished.</b> The result and the score are in the Instructor folder."


def _score_lines(score: Mapping[str, Any]) -> list[str]:
    parts = "".join(f"<li>{esc(p['rule'])}: {p['points']:+d} &middot; {esc(p['why'])}</li>"
                    for p in score["parts"])
    return [f"<b>Score {score['total']} / {score['maximum']}</b>",
            f'<ul style="margin:2px 0 2px 1.2em;padding:0">{parts}</ul>']


def instructor_html(report: Mapping[str, Any] | None, elapsed_s: float,
                    refusals: Iterable[str] = (), names: Names | None = None) -> str:
    """The instructor's board; ``names``: what it calls the connections (app/classroom/
    names.py), "trainee 1", ..., never viser's connection numbers."""
    def who(client_id: int | None) -> str:
        found = names.get(client_id) if names is not None else None
        return found or ("the server" if client_id is None else "a page")

    phase = report["phase"] if report else "none"
    lines: list[str] = []
    if report is None:
        lines.append('<span class="fr-muted">No exercise. Pick a hidden fault and press '
                     "Start: the trainees see its effects, never the fault itself.</span>")
    else:
        lines.append(f"<b>Hidden fault</b>: {esc(report['fault'])}")
        lines.append(f"<b>Cause</b>: {esc(report['cause'])}")
        lines.append(f"<b>Phase</b>: {esc(phase)} &middot; {elapsed_s:.0f} s")
        if report["answer"] is not None:
            verdict = "right" if report["right"] else "wrong"
            lines.append(f"<b>Answer</b> ({verdict}, at {report['answered_s']:.0f} s, by "
                         f"{esc(who(report['answered_by']))}): {esc(report['answer'])}")
        if report["fixed"] is not None:
            lines.append(f"<b>Fault gone</b>: {'yes' if report['fixed'] else 'no'}")
        actions = report["actions"]
        if actions:
            shown = actions[-MAX_ACTIONS_SHOWN:]
            items = "".join(
                f"<li>{a['t']:.0f} s {esc(who(a['client']))} {esc(a['text'])}"
                + (' <span style="color:#a11616">refused</span>' if a["refused"] else "")
                + "</li>" for a in shown)
            more = len(actions) - len(shown)
            lines.append(f"<b>Actions</b> ({len(actions)}"
                         + (f", last {len(shown)}" if more else "") + ")"
                         f'<ol style="margin:2px 0 2px 1.4em;padding:0">{items}</ol>')
        if report["score"] is not None:
            lines.extend(_score_lines(report["score"]))
    refused = list(refusals)
    if refused:
        items = "".join(f"<li>{esc(r)}</li>" for r in refused[-5:])
        lines.append(f'<b>Refused commands</b><ul style="margin:2px 0 0 1.2em;padding:0">'
                     f"{items}</ul>")
    return (f'<div id="{INSTRUCTOR_ID}" data-phase="{phase}" style="font-size:0.82em">'
            f'{"<br>".join(lines)}</div>')


def _verdict(report: Mapping[str, Any]) -> str:
    return "right" if report["right"] else "wrong" if report["answer"] is not None \
        else "none named"


def history_html(results: Iterable[Mapping[str, Any]]) -> str:
    rows = "".join(
        f"<tr><td>{esc(r['fault'])}</td><td>{_verdict(r)}</td>"
        f"<td>{'yes' if r['fixed'] else 'no'}</td>"
        f"<td style=\"white-space:nowrap\">{r['finished_s']:.0f} s</td>"
        f"<td><b>{r['score']['total']}</b></td></tr>" for r in results)
    if not rows:
        return (f'<div id="{HISTORY_ID}" class="fr-muted" style="font-size:0.82em">'
                "No scores yet.</div>")
    return (f'<table id="{HISTORY_ID}" style="font-size:0.78em;width:100%"><thead><tr>'
            "<th>Fault</th><th>Cause</th><th>Fixed</th><th>Time</th><th>Score</th></tr></thead>"
            f"<tbody>{rows}</tbody></table>")
