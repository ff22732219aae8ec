"""The CLI's argument parser: argparse's own errors start as the CLI's do.

argparse printed ``python -m app: error: ...`` (its ``prog``) for a bad flag while every other
refusal says ``fieldrig: error: ...``, so a pipeline had two prefixes to grep. ``prog`` stays
the command as typed, for the usage line; only the error line's prefix is the CLI's.
"""

from __future__ import annotations

import argparse
import sys
from typing import NoReturn

ERROR_PREFIX = "fieldrig: error:"
EXIT_USAGE = 2  # argparse's own, the CLI's EXIT_BAD_INPUT


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are ``fieldrig: error: ...`` (after the usage line);
    its subparsers are of this class too."""

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        self.exit(EXIT_USAGE, f"{ERROR_PREFIX} {message}\n")
