"""The CLI's argument parser: argparse's own errors start as the CLI's do.

argparse printed ``python -m app: error: ...`` (its ``prog``) for a bad flag while every other
refusal says ``fieldrig: error: ...``, so a pipeline had two prefixes to grep. ``prog`` stays
the command as typed, for the usage line; only the error line's prefix is the CLI's. Every
help page (each subcommand's too) ends with the exit codes, as README.md says.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

ERROR_PREFIX = "fieldrig: error:"
EXIT_SCENARIO_FAILED = 1
EXIT_BAD_INPUT = 2  # argparse's own usage error code too
EXIT_USAGE = EXIT_BAD_INPUT
EXIT_MACHINE_FAILED = 3  # an OSError (a file system, the screenshots' browser): not the input
# The epilog of every help page (docs/scenarios.md "Exit codes" says the same): keep it in
# step with the codes above.
EXIT_CODES_HELP = (
    f"exit codes: 0 ok (serving: stopped by Ctrl-C, SIGTERM or --run-for); "
    f"{EXIT_SCENARIO_FAILED} a scenario step failed (scenario run); "
    f"{EXIT_BAD_INPUT} bad input: a bad flag, a wrong rig, scenario or exercise file, an output "
    "path that cannot take the output, a host or port that cannot be served; "
    f"{EXIT_MACHINE_FAILED} the machine failed the run (a file that cannot be written, the "
    "screenshots' browser); 130 / 143 a scenario run interrupted by SIGINT / SIGTERM; every "
    "error one 'fieldrig: error:' line, no traceback")


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are ``fieldrig: error: ...`` (after the usage line);
    its subparsers are of this class too, so every help page, a subcommand's included, ends
    with the exit codes unless given another epilog."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("epilog", EXIT_CODES_HELP)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        self.exit(EXIT_USAGE, f"{ERROR_PREFIX} {message}\n")

    def parse_args(self, args: Sequence[str] | None = None,  # type: ignore[override]
                   namespace: argparse.Namespace | None = None) -> argparse.Namespace:
        """As argparse's, but an unknown argument is refused by the subcommand it was given
        to: argparse hands a subparser's leftovers to the top parser, whose usage
        (``scenario [-h] {list,run} ...``) names none of the subcommand's flags."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            self._chosen(parsed).error(f"unrecognized arguments: {' '.join(extras)}")
        return parsed

    def _chosen(self, parsed: argparse.Namespace) -> argparse.ArgumentParser:
        """The innermost (sub)parser the parsed arguments went through."""
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                sub = action.choices.get(getattr(parsed, action.dest or "", None))
                if sub is not None:
                    return sub._chosen(parsed) if isinstance(sub, Parser) else sub
        return self
