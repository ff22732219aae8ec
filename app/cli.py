"""Command line: ``python -m app`` serves the dashboard; ``python -m app scenario run FILE``;
``python -m app scenario list`` lists the example scenarios with their rig files.

Stable flags (issue 2): ``--host`` (default 127.0.0.1), ``--port`` (default 8080), ``--rig``.
Classroom (issue 6, docs/classroom.md): ``--rig`` again or ``--rigs N`` serves several rigs, one
port each from ``--port`` up; a non-loopback ``--host`` asks for an instructor token (printed,
or ``--instructor-token``); every served session is recorded unless ``--no-record``.
Bad input (a broken rig or scenario file, a bad flag) prints one line and exits 2, with no
traceback; so does the machine failing a run (a file that cannot be written, the browser of
``--screenshots`` dying), with exit 3 (docs/scenarios.md "Exit codes").
``--run-for SECONDS`` stops serving after that many wall seconds (exit 0).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from app.cli_parser import EXIT_BAD_INPUT, EXIT_MACHINE_FAILED, EXIT_SCENARIO_FAILED, Parser
from app.out_paths import (
    EVENTS_FILE,
    check_out,
    check_record,
    check_recordings_dir,
    check_state_dir,
    event_lines,
    image_name,
    prepare_out,
    write_events,
)
from app.rig_config import DEFAULT_RIG, RigConfigError, build_rig, load_rig_spec
from app.runtime import MAX_SPEED
from app.scenario import (
    EXAMPLES_DIR,
    Scenario,
    ScenarioError,
    check_against,
    load_scenario,
    run_scenario,
)

if TYPE_CHECKING:
    from app.rig import Rig


def _speed(text: str) -> float:
    """``--speed``: the runtime's range, checked before anything serves (``nan`` killed the
    simulation thread with a traceback, a speed <= 0 served a rig that never moved, exit 0)."""
    try:
        speed = float(text)
    except ValueError:
        speed = math.nan
    if not 0 < speed <= MAX_SPEED:  # also refuses nan and inf
        raise argparse.ArgumentTypeError(f"{text!r} is not a speed: give a number in "
                                         f"(0, {MAX_SPEED:g}]")
    return speed


def _run_for(text: str) -> float:
    """``--run-for``: 0 serves and stops at once (the smoke tests' check of the flags); a
    negative or ``nan`` time is a typo, not a run."""
    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not 0 <= seconds < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r} is not a time: give seconds >= 0")
    return seconds


def _serve_parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m app",
               description="FieldRig: serve the dashboard of a virtual rig. Subcommands: "
                           "'scenario run FILE', 'scenario list', 'ethercat export-esi' "
                           "(each with --help).")
    _rig_flags(p)
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=8080, help="dashboard port (default 8080)")
    p.add_argument("--speed", type=_speed, default=1.0,
                   help=f"simulated seconds per wall second, above 0 and up to {MAX_SPEED:g} "
                        "(default 1.0)")
    p.add_argument("--run-for", type=_run_for, default=None, metavar="SECONDS",
                   help="stop after this many wall seconds (for smoke tests)")
    # One or the other: given both, --no-record dropped --record's PATH without a word.
    record = p.add_mutually_exclusive_group()
    record.add_argument("--record", default=None, metavar="PATH",
                        help="record the session to this rerun file (.rrd); default: a file "
                             "in STATE_DIR/recordings (one per rig)")
    record.add_argument("--no-record", action="store_true",
                        help="do not record the session (no Download recording)")
    p.add_argument("--rigs", type=int, default=None, metavar="N",
                   help="serve N copies of the rig (one per trainee), on ports PORT..PORT+N-1")
    p.add_argument("--exercises", default=None, metavar="DIR",
                   help="exercise files (*.toml with an [exercise] table) the instructor may "
                        "play from the Classroom folder (docs/classroom.md)")
    p.add_argument("--scenarios", default=None, metavar="DIR",
                   help="your own scenario files (*.toml): the Scenario tab lists them first, "
                        "then the shipped ones (docs/scenarios.md)")
    p.add_argument("--instructor-token", default=None, metavar="TOKEN",
                   help="the instructor's token (default with a non-loopback --host: a new "
                        "one, printed at start)")
    p.add_argument("--modbus-port", type=int, default=5020,
                   help="TCP port of the drives' Modbus line, bound to --host (default 5020)")
    p.add_argument("--can-interface", choices=("virtual", "udp_multicast", "socketcan"),
                   default="virtual",
                   help="the drives' CAN bus: 'virtual' (in this process), 'udp_multicast' "
                        "(another process on this machine can be the master), 'socketcan'")
    p.add_argument("--can-channel", default=None,
                   help="virtual: a name; udp_multicast: GROUP[:PORT][@ADDRESS|@any] "
                        "(default 239.74.163.2:43113 on loopback; @ADDRESS joins on that "
                        "interface, @any on the default one); socketcan: e.g. can0")
    p.add_argument("--modbus-framer", choices=("socket", "rtu"), default="socket",
                   help="Modbus TCP ('socket') or RTU frames over TCP ('rtu', as the real "
                        "drive speaks RTU)")
    # EtherCAT wire (issue 8, app/ethercat_wire/bridge.py)
    p.add_argument("--ethercat-if", default=None, metavar="IFACE",
                   help="put the rig's EtherCAT line on this network interface (raw frames, "
                        "needs CAP_NET_RAW) for a real master; off by default")
    return p


def _scenario_parser() -> argparse.ArgumentParser:
    p = Parser(prog="python -m app scenario",
               description="Run a scenario headless, as fast as possible, and print its "
                           "events as JSON lines ('run FILE'), or list the example scenarios "
                           "('list').")
    sub = p.add_subparsers(dest="verb", required=True)
    sub.add_parser("list", help="the example scenarios, one per line: file, name and rig file "
                                "(tab-separated)")
    run = sub.add_parser("run", help="run a scenario file")
    run.add_argument("file", help="scenario TOML file")
    run.add_argument("--out", default=None, metavar="DIR",
                     help="directory for events.jsonl (and the screenshots); it gets this "
                          "run's files only: before the run it removes any events.jsonl and "
                          "NN-name.png there (an earlier run's, or yours of those names), "
                          "each said on stderr; other files stay")
    run.add_argument("--quiet", action="store_true",
                     help="do not print events on stdout (with --screenshots: nor viser's "
                          "banner on stderr)")
    run.add_argument("--record", default=None, metavar="PATH",
                     help="also record the run to a rerun file (.rrd)")
    run.add_argument("--screenshots", action="store_true",
                     help="serve the dashboard, play the scenario in headless Chromium and "
                          "write one PNG per checkpoint into --out (docs/scenarios.md)")
    _rig_flags(run, serving=False)
    return p


def _rig_flags(p: argparse.ArgumentParser, serving: bool = True) -> None:
    if serving:
        p.add_argument("--rig", action="append", default=None,
                       help="rig file (TOML); default: the embedded default rig; give it "
                            "several times to serve several rigs")
        p.add_argument("--state-dir", default="var",
                       help="where device flash files live (default ./var)")
    else:
        p.add_argument("--rig", default=None,
                       help="rig file; default: the scenario's own, else the default rig")
        p.add_argument("--state-dir", default=None,
                       help="keep device flash files here; default: in memory, so every run "
                            "starts from the same factory state")


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        if argv[:1] == ["scenario"]:
            return _scenario(_scenario_parser().parse_args(argv[1:]))
        if argv[:1] == ["ethercat"]:  # issue 8: export-esi (app/ethercat_wire/esi.py)
            from app.ethercat_wire.esi import main as ethercat_main

            return ethercat_main(argv[1:])
        return _serve(_serve_parser().parse_args(argv))
    except (RigConfigError, ScenarioError) as exc:
        print(f"fieldrig: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # screenshots.ScreenshotError and devices' FlashError too
        print(f"fieldrig: error: {_os_error_text(exc)}", file=sys.stderr)
        return EXIT_MACHINE_FAILED


def _os_error_text(exc: OSError) -> str:
    """``PATH: Is a directory`` rather than ``[Errno 21] Is a directory: 'PATH'``."""
    if exc.strerror and exc.filename is not None:
        return f"{exc.filename}: {exc.strerror}"
    return str(exc) or type(exc).__name__


def _scenario(args: argparse.Namespace) -> int:
    if args.verb == "list":
        return _scenario_list()
    # A CI job's timeout (SIGTERM) ends a run as Ctrl-C does: the recording is closed, the
    # server and browser of --screenshots stopped, and one line says what is left.
    with _sigterm_as_interrupt():
        try:
            return _scenario_run(args)
        except KeyboardInterrupt as exc:
            return _interrupted(args, exc)


def _interrupted(args: argparse.Namespace, exc: KeyboardInterrupt) -> int:
    """One line; exit 128 + the signal, as a shell reports a process the signal ended. An
    --out without events.jsonl (removed before the run, written last) is a run that did not
    finish: its pictures so far stay (docs/scenarios.md "Output folder")."""
    signum = exc.signum if isinstance(exc, Terminated) else signal.SIGINT
    what = []
    if args.out and not (Path(args.out) / EVENTS_FILE).exists():
        what.append(f"{args.out} is incomplete (no {EVENTS_FILE})")
    if args.record and Path(args.record).exists():
        what.append(f"{args.record} stops at the interruption")
    print("fieldrig: interrupted" + (": " + "; ".join(what) if what else ""), file=sys.stderr)
    return 128 + signum


def _scenario_run(args: argparse.Namespace) -> int:
    scenario = load_scenario(args.file)
    rig_path = args.rig or scenario.rig or str(DEFAULT_RIG)
    if args.state_dir is not None:  # before build_rig reads the flash files there
        check_state_dir(args.state_dir)
    rig = build_rig(load_rig_spec(rig_path), state_dir=args.state_dir)
    # The whole file is checked against the rig before anything starts (a server, a browser,
    # a recording): a wrong file is one error line and exit 2 in every mode.
    check_against(scenario, rig)
    if args.screenshots and not args.out:
        raise ScenarioError("--screenshots needs --out DIR")
    # So are the output paths: a bad one must not cost a run, nor leave a recording that
    # looks complete beside a traceback.
    if args.record:
        check_record(args.record)
    out = check_out(args.out, _run_files(scenario, args.screenshots)) if args.out else None
    if out is not None:
        for removed in prepare_out(out):  # stderr: stdout is the event lines a pipeline reads
            print(f"fieldrig: removed {removed} (--out holds this run's files only)",
                  file=sys.stderr)
    if args.screenshots:
        from app.screenshots import run_with_screenshots

        result = run_with_screenshots(scenario, rig, args.out, record=args.record,
                                      quiet=args.quiet)
    elif args.record:
        from app.recording import RigRecorder, scenario_observer

        recorder = RigRecorder(args.record, start_time=False)
        try:
            result = run_scenario(scenario, rig, on_tick=scenario_observer(recorder))
        finally:
            recorder.close()
    else:
        result = run_scenario(scenario, rig)
    text = event_lines(result.events)
    # The one writer of events.jsonl (--screenshots too), first: a reader of stdout that
    # stops early must not cost the file.
    if out is not None:
        write_events(out, text)
    if not args.quiet:
        _stdout(text)
    for failure in result.failures:
        print(f"fieldrig: scenario step failed: {failure}", file=sys.stderr)
    return EXIT_SCENARIO_FAILED if result.failures else 0


def _stdout(text: str) -> None:
    """Write to stdout. A reader that stopped reading (``| head -1``, ``| true``) is not an
    error: what it did not take goes to devnull (the recipe of the Python docs' "Note on
    SIGPIPE", so the flush at exit does not fail again) and the exit code stays the
    command's own (docs/scenarios.md "Exit codes"). No stdout at all (``>&-``: Python then
    has sys.stdout None) is the same: nothing is written."""
    if sys.stdout is None:
        return
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


def _run_files(scenario: Scenario, screenshots: bool) -> list[str]:
    """The names the run writes into --out: its events, and a picture per checkpoint."""
    checkpoints = [s for s in scenario.steps if s.kind == "checkpoint"] if screenshots else []
    return [EVENTS_FILE, *(image_name(i, s.text) for i, s in enumerate(checkpoints, 1))]


def _scenario_list() -> int:
    """Each example of static/scenarios, sorted by file: ``FILE<TAB>NAME<TAB>RIG``, the paths
    as a command typed here takes them (``scenario run FILE --rig RIG``). A file that does not
    load is one error line on stderr, and the exit code 2."""
    from app.player import shown_path

    broken = False
    for path in sorted(EXAMPLES_DIR.glob("*.toml")):
        try:
            scenario = load_scenario(path)
        except ScenarioError as exc:
            print(f"fieldrig: error: {exc}", file=sys.stderr)
            broken = True
            continue
        rig = Path(scenario.rig) if scenario.rig else DEFAULT_RIG
        name = " ".join(scenario.name.split())  # one line, one column, whatever the file says
        _stdout(f"{shown_path(path)}\t{name}\t{shown_path(rig)}\n")
    return EXIT_BAD_INPUT if broken else 0


def _serve(args: argparse.Namespace) -> int:
    from app.classroom.roles import Access
    from app.ui.panels.classroom_rig import serve_rig

    rig_files = list(args.rig or [str(DEFAULT_RIG)])
    if args.rigs is not None:
        if args.rigs < 1 or len(rig_files) != 1:
            raise RigConfigError("--rigs", "", "give N >= 1 and one --rig (or none)")
        rig_files = rig_files * args.rigs
    count = len(rig_files)
    for flag, port in (("--port", args.port), ("--modbus-port", args.modbus_port)):
        if not 0 < port < 65536 - (count - 1):
            raise RigConfigError(flag, "", f"{port} is not a TCP port (for {count} rig(s))")
    if count > 1 and args.can_interface != "virtual":
        raise RigConfigError("--can-interface", "", "several rigs in one process need the "
                             "'virtual' CAN interface (one bus per rig)")
    _check_can_channel(args)
    if args.instructor_token is not None and not args.instructor_token.strip():
        raise RigConfigError("--instructor-token", "", "an empty token")
    access_token = Access.for_host(args.host, args.instructor_token).token
    if args.record:  # before any rig starts serving
        for i in range(count):
            check_record(_record_path(args, Path(args.state_dir), "", "", i, count) or "")
    state_dirs = [Path(args.state_dir) / (f"rig{i + 1}" if count > 1 else "")
                  for i in range(count)]
    for state_dir in state_dirs:  # before build_rig reads the flash files there
        check_state_dir(state_dir, writable=False)
        if not args.record and not args.no_record:  # the session's file goes in there
            check_recordings_dir(state_dir / "recordings")
    rigs = [build_rig(load_rig_spec(rig_file), state_dir=state_dir)
            for rig_file, state_dir in zip(rig_files, state_dirs, strict=True)]
    exercises = _exercise_files(args.exercises, rigs[0])  # --rigs N: N copies of one file
    if args.scenarios is not None:  # checked now: a broken own file is exit 2, not a gap
        from app.ui.panels.scenario_player import own_scenarios

        own_scenarios(args.scenarios)
    _check_listen(args, rigs)
    served, extras = [], []
    stamp = time.strftime("%Y%m%d-%H%M%S")
    try:
        for i, (rig, state_dir) in enumerate(zip(rigs, state_dirs, strict=True)):
            record = _record_path(args, state_dir, rig.name, stamp, i, count)
            one = serve_rig(rig, Access(access_token), host=args.host, port=args.port + i,
                            speed=args.speed, record=record, exercise_files=exercises,
                            scenarios=Path(args.scenarios) if args.scenarios else None)
            served.append(one)
            if one.port != args.port + i:  # taken between the check and now: viser moved on
                raise RigConfigError("--port", "", f"{args.port + i} was taken while starting")
            one.runtime.power_on()  # a served rig starts powered
            extras.append(_start_modbus(one.runtime, args, args.modbus_port + i))
            extras.append(_start_canopen(one.runtime, args,
                                         _can_channel(args, i) if count > 1 else None))
            if args.ethercat_if:  # EtherCAT wire (issue 8, app/ethercat_wire/bridge.py)
                from app.ethercat_wire.bridge import start_wire

                extras.append(start_wire(one.runtime, args.ethercat_if, rigs=count))
            print(f"FieldRig: rig {i + 1} '{rig.name}' at {one.shown_url}"
                  + (f" (listening on {args.host})" if one.shown_url != one.url else "")
                  + (f" (recording {record})" if record else ""), flush=True)
        if access_token is not None:
            print(f"FieldRig: instructor token {access_token}: open a rig's URL with "
                  f"?token={access_token} (e.g. {served[0].instructor_url}); any other "
                  "browser is a trainee", flush=True)
        print("FieldRig: serving (Ctrl-C to stop)", flush=True)
        stop = threading.Event()
        with contextlib.suppress(KeyboardInterrupt), _sigterm_as_interrupt():
            stop.wait(args.run_for)
    finally:
        for extra in extras:
            if extra is not None:
                extra.stop_in_thread() if hasattr(extra, "stop_in_thread") else extra.stop()
        for one in served:
            one.stop()
    return 0


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised as Ctrl-C's KeyboardInterrupt is (``scenario run`` tells them apart
    for its exit code)."""

    signum = signal.SIGTERM


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM stops serving, or a scenario run, as Ctrl-C does. A service manager (systemd,
    docker, a CI job's timeout) stops a process with SIGTERM, whose default action ends it at
    once: the recordings were left without the footer a closed Rerun file gets, the servers
    were not shut down, and a run said nothing. Only the main thread may set a handler; the
    previous one is put back."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(_signum: int, _frame: object) -> None:
        raise Terminated

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _record_path(args: argparse.Namespace, state_dir: Path, name: str, stamp: str, i: int,
                 count: int) -> str | None:
    """``--record`` (numbered per rig when several), else a file per session in the state dir
    (every served session is recorded: the Download recording button sends it)."""
    if args.no_record:
        return None
    if args.record:
        path = Path(args.record)
        return str(path if count == 1 else path.with_stem(f"{path.stem}-{i + 1}"))
    safe = "".join(c if c.isalnum() or c in "-_" else "-" for c in name) or "rig"
    return str(state_dir / "recordings" / f"{safe}-{stamp}.rrd")


def _exercise_files(directory: str | None, rig: Rig) -> list[Path]:
    """The exercise files of ``--exercises DIR``, each checked now against the rig served, as
    ``scenario run`` checks a scenario: its commands, and its hidden fault among the rig's
    (a broken one: exit 2; before, an unknown fault surfaced only at *Play file and start*)."""
    if directory is None:
        return []
    from app.classroom.exercise_file import check_exercise, load_exercise
    from app.classroom.faults import catalog

    folder = Path(directory)
    if not folder.is_dir():  # the words of --scenarios (own_scenarios): not "no *.toml in"
        raise RigConfigError("--exercises", "", f"{folder}: no such folder" if not
                             folder.exists() else f"{folder}: not a folder (give the folder "
                                                  "that holds the *.toml files)")
    files = sorted(folder.glob("*.toml"))
    if not files:
        raise RigConfigError("--exercises", "", f"no *.toml in {directory}")
    faults = catalog(rig.describe(), rig.snapshot())
    for path in files:
        scenario, spec = load_exercise(path)
        check_exercise(scenario, spec, rig, faults)
    return files


def _can_channel(args: argparse.Namespace, i: int) -> str:
    return f"{args.can_channel or 'fieldrig'}-rig{i + 1}"


def _start_modbus(runtime: Any, args: argparse.Namespace, port: int) -> Any:
    """The drives' Modbus line (pymodbus), when the rig has drives; None otherwise."""
    from app.modbus.server import DriveModbusServer

    drives = _modbus_drives(runtime.rig)
    if not drives:
        return None
    server = DriveModbusServer(drives, runtime.submit, host=args.host, port=port,
                               framer=args.modbus_framer, call=runtime.call)
    server.start_in_thread()
    runtime.modbus = server.served()
    print(f"FieldRig: Modbus ({args.modbus_framer}) on {args.host}:{server.port}",
          flush=True)
    return server


def _check_listen(args: argparse.Namespace, rigs: list[Rig]) -> None:
    """Every port the rigs will listen on, on ``--host``, before the first serves (viser hangs
    on a host it cannot bind, and moves on from a port in use: app/listen_check.py)."""
    from app.listen_check import ListenError, check_listen

    web = [("--port", args.port + i) for i in range(len(rigs))]
    modbus = [("--modbus-port", args.modbus_port + i) for i, rig in enumerate(rigs)
              if _modbus_drives(rig)]
    both = sorted({p for _, p in web} & {p for _, p in modbus})
    if both:
        raise RigConfigError("--modbus-port", "", f"{both[0]} is also a dashboard port "
                             f"(--port {args.port}, one port per rig from there)")
    try:
        check_listen(args.host, web + modbus)
    except ListenError as exc:
        raise RigConfigError(exc.flag, "", exc.reason) from None


def _check_can_channel(args: argparse.Namespace) -> None:
    """A channel that cannot be one is refused before any rig serves (it was a traceback from
    bind() once the dashboard and the Modbus line were up)."""
    from app.canopen_bus import CanBusError, check_channel

    try:
        check_channel(args.can_interface, args.can_channel)
    except CanBusError as exc:
        raise RigConfigError("--can-channel", "", str(exc)) from None


def _modbus_drives(rig: Rig) -> list[Any]:
    from devices.servo.drive import ServoDrive

    return [d for d in rig.devices.values() if isinstance(d, ServoDrive)]


def _start_canopen(runtime: Any, args: argparse.Namespace, channel: str | None) -> Any:
    """The drives' CAN bus (python-can), when the rig has CANopen nodes; None otherwise."""
    from app.canopen_bus import CanBusError, CanOpenBus
    from devices.canopen.node import CanOpenNode

    nodes = [d for d in runtime.rig.devices.values() if isinstance(d, CanOpenNode)]
    if not nodes:
        return None
    bus = CanOpenBus(nodes, runtime.submit, args.can_interface, channel or args.can_channel)
    bus.attach(runtime)
    try:
        bus.start()
    except CanBusError as exc:
        raise RigConfigError("--can-interface", "", str(exc)) from None
    return bus
