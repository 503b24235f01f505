"""`mtt` run in the test's own process: faster than a child, and its output read by capsys."""

from __future__ import annotations

from mtt.cli.main import main


def run_mtt(capsys, *args: str) -> tuple[int, str, str]:
    """`mtt ARGS`: exit status (argparse's exit included), stdout, stderr."""
    try:
        status = main(list(args))
    except SystemExit as exit:
        status = exit.code
    out, err = capsys.readouterr()
    return status, out, err
