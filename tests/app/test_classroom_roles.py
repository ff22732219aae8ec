"""Roles and access (issue 6 "Classroom"): a trainee connection never injects a fault, resets
the rig or controls a scenario, whatever it sends; the refusal is logged and notified."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from typing import Any

import pytest
from viser_page import wait as _wait

from app.classroom.roles import (
    INSTRUCTOR_ONLY,
    INSTRUCTOR_OPERATIONS,
    Access,
    Operation,
    Role,
    allowed,
    instructor_only,
    is_loopback,
    operation_allowed,
)
from app.rig_config import DEFAULT_RIG, build_rig, load_rig_spec
from app.runtime import Runtime
from app.ui.commands import ERROR_S, NOTE_S, REFUSALS_DEVICE, CommandSender, Gate, Sent, notify
from devices.events import LogLine


class FakeClient:
    """What CommandSender uses of a viser ClientHandle: its id and its notifications."""

    def __init__(self, client_id: int) -> None:
        self.client_id = client_id
        self.notes: list[tuple[str, str, Any]] = []

    def add_notification(self, title: str, body: str, **kw: Any) -> None:
        self.notes.append((title, body, kw.get("color")))


@pytest.mark.parametrize("rule", INSTRUCTOR_ONLY, ids=lambda r: f"{r.kind}.{r.action}")
def test_every_instructor_only_row_is_refused_to_a_trainee(rule: Any) -> None:
    kind = "fastcat" if rule.kind == "*" else rule.kind
    args = dict(rule.when)
    assert instructor_only(kind, rule.action, args) is not None
    assert not allowed(Role.TRAINEE, kind, rule.action, args)
    assert allowed(Role.INSTRUCTOR, kind, rule.action, args)


@pytest.mark.parametrize(("kind", "action", "args"), [
    ("fastcat", "link", {"connected": True}),  # plugging the cable back is a repair
    ("fastcat", "power", {"on": True}),
    ("fastcat", "encoder_fault", {"encoder": 1, "fault": "lost", "active": False}),
    ("fastcat", "set_reset_fault", {"on": True}),
    ("fastcat", "write_object", {"index": 0x5200, "sub": 1, "value": 1}),
    ("servo", "alarm_reset", {}),
    ("servo", "jam_load", {"active": False}),
    ("master", "resync", {}),
    ("master", "plug_cable", {"cable": 1}),
    ("master", "power_slave", {"position": 1, "on": True}),
    ("master", "clear_dc_fault", {}),
    ("canopen", "frame", {"cob_id": 0, "data": "81 01"}),
])
def test_operation_and_repairs_are_the_trainees(kind: str, action: str,
                                               args: dict[str, Any]) -> None:
    assert allowed(Role.TRAINEE, kind, action, args)


def test_every_rule_names_a_real_action() -> None:
    """The table is read from the models' ACTIONS: a renamed action must not slip out."""
    from devices.coe.actions import ACTIONS as COE
    from devices.cpx.actions import ACTIONS as CPX
    from devices.fastcat.coupler import FastCat
    from devices.master import EtherCatMaster
    from devices.servo.actions import ACTIONS as SERVO
    from devices.trscat.commands import ACTIONS as TRS

    tables = {"fastcat": FastCat.ACTIONS, "servo": SERVO, "servo_ecat": COE, "trscat": TRS,
              "cpx_e_ec": CPX, "master": EtherCatMaster.ACTIONS}
    everything = set().union(*tables.values())
    for rule in INSTRUCTOR_ONLY:
        names = everything if rule.kind == "*" else tables[rule.kind]
        assert rule.action in names, rule
        if rule.kind != "*":
            params = {p.name for p in tables[rule.kind][rule.action].params}
            assert set(rule.when) <= params, rule


@pytest.mark.parametrize("operation", list(Operation))
def test_operations(operation: Operation) -> None:
    assert operation_allowed(Role.INSTRUCTOR, operation)
    assert operation_allowed(Role.TRAINEE, operation) == (operation not in INSTRUCTOR_OPERATIONS)


@pytest.mark.parametrize(("host", "loopback"), [
    ("127.0.0.1", True), ("localhost", True), ("::1", True), ("0.0.0.0", False),
    ("192.168.1.20", False), ("rig.example", False)])
def test_access_for_host(host: str, loopback: bool) -> None:
    assert is_loopback(host) == loopback
    access = Access.for_host(host)
    assert access.open == loopback
    assert access.role(7) is (Role.INSTRUCTOR if loopback else Role.TRAINEE)
    assert Access.for_host(host, "given").token == "given"


def test_token_makes_a_connection_instructor_until_it_closes() -> None:
    access = Access("s3cret")
    assert access.role(1) is Role.TRAINEE
    assert not access.present(1, "guess")
    assert access.role(1) is Role.TRAINEE
    assert access.present(1, " s3cret ")
    assert access.role(1) is Role.INSTRUCTOR
    assert access.role(2) is Role.TRAINEE
    assert access.role(None) is Role.INSTRUCTOR  # the server itself
    access.forget(1)
    assert access.role(1) is Role.TRAINEE


@pytest.fixture
def runtime() -> Iterator[Runtime]:
    rt = Runtime(build_rig(load_rig_spec(DEFAULT_RIG), state_dir=None))
    rt.set_paused(True)
    rt.start()
    yield rt
    rt.stop()


def test_trainee_injection_is_refused_logged_and_notified(
        runtime: Runtime, caplog: pytest.LogCaptureFixture) -> None:
    gate = Gate(Access("tok"))
    seen: list[Sent] = []
    gate.observe(seen.append)
    sender = CommandSender(runtime, gate)
    trainee, instructor = FakeClient(1), FakeClient(2)
    assert gate.access.present(2, "tok")
    with caplog.at_level(logging.WARNING, logger="app.ui.commands"):
        sender.send(trainee, "fastcat", "inject_fault", {"fault": "coupler:0x04"})
        sender.send(trainee, "fastcat/3", "encoder_fault",
                    {"encoder": 1, "fault": "lost", "active": True})
        sender.send(trainee, "drive", "inject_alarm", {"code": "16"})
    assert [s.refused != "" for s in seen] == [True, True, True]
    assert all(note[2] == "red" for note in trainee.notes) and len(trainee.notes) == 3
    assert sum("refused from trainee connection 1" in r.message for r in caplog.records) == 3
    lines = _wait(lambda: [e for e in runtime.events_since(0)[1]
                           if isinstance(e, LogLine) and e.device == REFUSALS_DEVICE])
    assert "inject_fault" in lines[0].text
    runtime.advance(0).result(timeout=5)
    assert runtime.rig.snapshot()["devices"]["fastcat"]["injected"] == []
    # The same command from the instructor goes through.
    sender.send(instructor, "fastcat", "inject_fault", {"fault": "coupler:0x04"})
    _wait(lambda: runtime.submit(runtime.rig.snapshot).result(timeout=5)
          ["devices"]["fastcat"]["injected"])
    assert seen[-1].role is Role.INSTRUCTOR and not seen[-1].refused


def test_trainee_operates_the_rig(runtime: Runtime) -> None:
    gate = Gate(Access("tok"))
    sender = CommandSender(runtime, gate)
    trainee = FakeClient(5)
    results: list[Any] = []
    sender.send(trainee, "fastcat", "set_rotary", {"value": 3}, done=results.append)
    sender.submit(trainee, "read", lambda: runtime.rig.device("fastcat").rotary_switch,
                  done=results.append)
    _wait(lambda: len(results) == 2)
    assert results[1] == 3 and trainee.notes == []


@pytest.mark.parametrize("operation", sorted(INSTRUCTOR_OPERATIONS, key=lambda o: o.value))
def test_trainee_operations_refused(runtime: Runtime, operation: Operation) -> None:
    sender = CommandSender(runtime, Gate(Access("tok")))
    trainee, ran = FakeClient(3), []
    assert not sender.allow(trainee, operation)
    sender.submit(trainee, "x", lambda: ran.append(1), operation=operation)
    assert len(trainee.notes) == 2 and ran == []
    assert sender.allow(None, operation)  # the server itself


def test_open_rig_everyone_instructor(runtime: Runtime) -> None:
    sender = CommandSender(runtime)  # no gate installed: an open one
    client = FakeClient(9)
    assert sender.role(client) is Role.INSTRUCTOR
    assert sender.allow(client, Operation.SCENARIO)


def test_docs_list_every_instructor_only_action() -> None:
    """docs/classroom.md's table names every row of INSTRUCTOR_ONLY under its device kind."""
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[2] / "docs" / "classroom.md").read_text()
    rows = {line.split("|")[1].strip().strip("`"): line.split("|")[2]
            for line in doc.splitlines() if line.startswith("| `") or line.startswith("| any")}
    for rule in INSTRUCTOR_ONLY:
        kind = "any" if rule.kind == "*" else rule.kind
        cell = rows[kind]
        written = f"`{rule.action}`" + "".join(f" {k}={str(v).lower()}"
                                             for k, v in rule.when.items())
        assert written in cell, (kind, written)


def test_every_notification_closes_by_itself() -> None:
    """Refusals stayed until clicked and piled up over the LEDs a trainee reads; they now
    close after ERROR_S (longer than a confirmation)."""
    shown: list[tuple[str, Any]] = []

    class Page:
        client_id = 7

        def add_notification(self, title: str, body: str, color: str = "",
                             auto_close_seconds: Any = None) -> None:
            shown.append((color, auto_close_seconds))

    notify(Page(), "fastcat: power refused", "instructor only", error=True)  # type: ignore[arg-type]
    notify(Page(), "Instructor", "You are the instructor")  # type: ignore[arg-type]
    assert shown == [("red", ERROR_S), ("blue", NOTE_S)]
    assert NOTE_S < ERROR_S < 60
