"""How a command of the experiment family runs: bad options, data and files end with a
message and exit status 2 (not a traceback), notes and warnings go to stderr, results are
printed as the command line names its options.

Light to import (numpy only when a command runs), so that building the parser costs nothing.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import warnings
from collections.abc import Callable

from mtt.data import DataError, located
from mtt.estimator.advice import for_command_line

EXIT_OK, EXIT_STOPPED, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """Options or data that do not make an experiment; the message says why (and `path`,
    `line` where, for a data file's problem, as a generated module's CSVError does)."""

    def __init__(self, message: str, path: str | None = None, line: int | None = None):
        super().__init__(message)
        self.path, self.line = path, line


def guarded(action: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """Bad options, data and files end with a message and exit status 2, not a traceback
    (with --json also {"ok": false, "errors": [...]} on stdout). The estimator's warnings
    are reported by each command from its results; numpy's floating-point warnings, which
    the estimator's checks turn into messages, are not shown."""

    def run(args) -> int:
        message, where = None, {"file": getattr(args, "file", None), "kind": "usage", "line": None}
        try:
            import numpy as np

            with warnings.catch_warnings(record=True) as caught, np.errstate(all="ignore"):
                warnings.simplefilter("always")
                status = action(args)
            for warning in caught:
                if not _handled(warning.category):
                    say(f"mtt {args.command}: warning: {warning.message}", stderr=True)
            return status
        except (UsageError, ValueError) as exc:  # a DataError's names as options
            message = as_options(exc) if isinstance(exc, DataError) else str(exc)
            place = located(exc)  # a data file's content (or a module's CSVError): where
            if place is not None:
                kind, file, line = place
                where = {"file": file, "kind": kind, "line": line}
        except BrokenPipeError:  # stdout closed by its reader: main's business, not an error
            raise
        except OSError as exc:
            message = f"{exc.filename}: {exc.strerror}" if exc.filename else str(exc)
            if exc.filename:
                where = {"file": exc.filename, "kind": "io", "line": None}
        message = for_command_line(message)
        print(f"mtt {args.command}: error: {message}", file=sys.stderr)
        if getattr(args, "json", False):
            error = {**where, "column": None, "message": message, "notes": []}
            print(json.dumps({"ok": False, "errors": [error]}))
        return EXIT_USAGE

    return run


def as_options(error: DataError) -> str:
    """The message of mtt.data, its parameters named as this command line's options
    (`t_end` is `--t-end`)."""
    message = str(error)
    for name in error.names:
        option = "--" + name.replace("_", "-")
        message = re.sub(rf"(?<![\w-]){re.escape(name)}(?![\w-])", option, message)
    return message


def _handled(category: type) -> bool:
    """Warnings a command reports itself (the estimator's) or that say nothing to a user."""
    return issubclass(category, RuntimeWarning) or category.__name__ == "EstimationWarning"


def say(text: str, *, stderr: bool = False) -> None:
    """Print a result or a note, the estimators' advice named as this command line's options
    (`hold='zoh'` is `--hold zoh` here)."""
    print(for_command_line(text), file=sys.stderr if stderr else sys.stdout)


def warn(command: str, texts) -> None:
    for text in texts:
        say(f"mtt {command}: warning: {text}", stderr=True)
