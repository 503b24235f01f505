"""`mtt draw`, `mtt bode` and `mtt examples`: a model as pictures, and the shipped models.

The argparse wiring is light; each command imports what it draws with when it runs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mtt.cli.options import (
    add_parameter_options,
    add_selection_options,
    choice_from_args,
    given,
    selection_from_args,
)
from mtt.cli.value_options import Flatten
from mtt.language.diagnostics import ModelError, MttError

EXIT_OK = 0
FORMATS = ("svg", "png", "pdf")


def _figure_path(text: str) -> str:
    """-o FILE.svg|png|pdf, checked before any work is done."""
    suffix = Path(text).suffix.lstrip(".").lower()
    if not text or suffix not in FORMATS:
        raise argparse.ArgumentTypeError(f"{text!r}: the file must end in .svg, .png or .pdf")
    return text


def _values(text: str) -> list[float]:
    """--k 1,5,10 (also --k 1 5 10: the option extends the list)"""
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas or spaces, not {text!r}"
        ) from None
    if not values or not all(abs(v) < float("inf") for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, not {text!r}")
    return values


def _print_json(record: dict) -> None:
    print(json.dumps(record, allow_nan=False))


def _dpi(text: str) -> float:
    """--dpi, as the other commands that draw take it."""
    try:
        dpi = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, not {text!r}") from None
    if not 10 <= dpi <= 2400:  # also refuses nan
        raise argparse.ArgumentTypeError(f"--dpi must be from 10 to 2400, not {text}")
    return dpi


def _save(figure, path: str, dpi: float) -> None:
    """Write a picture; a path that cannot be written is the user's error, said as such."""
    from mtt.present import drawing

    try:
        drawing.save(figure, path, dpi)
    except OSError as exc:
        raise MttError(f"{exc.filename or path}: {exc.strerror}", kind="io") from None


def cmd_draw(args) -> int:
    from mtt.derivation.causality import assign
    from mtt.derivation.pipeline import load
    from mtt.present import drawing

    graph = load(args.file, selection_from_args(args), part=True)
    causal, problem = None, None
    try:  # a part's strokes depend on where it is used: it is drawn without
        causal = None if graph.open_ports else assign(graph)
    except ModelError as exc:  # still worth a picture: without strokes, and say why
        problem = exc
        print(exc.render(), file=sys.stderr)
        print(f"mtt draw: warning: drawn without causal strokes ({exc.kind})", file=sys.stderr)
    args.out = args.out or f"{Path(args.file).stem}.svg"  # in the working directory
    _save(drawing.figure(graph, causal), args.out, args.dpi)
    if args.json:
        _print_json(
            {"ok": True, "file": args.file, "out": args.out, "model": graph.name,
             "causality": causal is not None,
             "warnings": [d.to_json() for d in problem.errors] if problem else []}
        )  # fmt: skip
    else:
        ports = ", ".join(graph.open_ports)
        what = f"part {graph.name} (ports {ports})" if ports else graph.name
        print(f"wrote {args.out}: bond graph of {what}")
    return EXIT_OK


def cmd_bode(args) -> int:
    from mtt.api.model import Model
    from mtt.derivation.pipeline import load
    from mtt.present import bode

    choice = choice_from_args(args)
    model = Model(load(args.file, choice.selection), choice)
    if not (args.out or args.json):
        args.out = f"{Path(args.file).stem}_bode.svg"  # in the working directory
    unknowns = model.unknowns
    if len(unknowns) > 1 and args.k:
        raise MttError(
            f"--k gives values of one unknown; {model.name} has {len(unknowns)} "
            f"({', '.join(unknowns)}): choose which with --unknown NAME (the others keep the "
            "file's values), or leave --k out for the file's values of all",
            kind="usage",
        )
    if not unknowns and args.k:
        raise MttError(f"{model.name} has no unknown: --k does not apply", kind="no_unknown")
    points = [{unknowns[0]: k} for k in args.k] if args.k else [{}]
    missing = [name for name in unknowns if model.parameters[name] is None]
    if not args.k and missing:
        raise MttError(
            f"{model.name} gives no value of {', '.join(missing)}: pass --k"
            + ("" if len(unknowns) == 1 else " with --unknown NAME, or --set NAME=VALUE"),
            kind="missing_value",
        )
    found = bode.model_bode(model, points)
    if args.out:
        _save(found.figure(), args.out, args.dpi)
    at = "; ".join(found.labels)
    if args.json:
        _print_json({"ok": True, "file": args.file, "out": args.out, **found.record()})
    elif found.several:
        rows, columns = model.transfer_matrix.shape
        print(f"wrote {args.out}: {rows}x{columns} Bode diagrams of {model.name} at {at}")
    elif args.out:
        print(f"wrote {args.out}: Bode diagram of {model.name} at {at}")
    return EXIT_OK


def cmd_examples(args) -> int:
    from mtt.api.examples import copy_examples, examples
    from mtt.resources import resource_dir

    listed = examples()
    copied = []
    if args.copy is not None:
        copied = copy_examples(args.copy, force=args.force, parents=args.parents)
    if args.json:
        _print_json({"ok": True, "copied": [str(path) for path in copied], "examples": [
            {"name": e.name, "description": e.description, "file": str(e.path)} for e in listed
        ]})  # fmt: skip
        return EXIT_OK
    if args.copy is not None:
        print(f"copied {len(copied)} example model(s) to {args.copy}")
        return EXIT_OK
    width = max(len(example.name) for example in listed)
    for example in listed:
        print(f"{example.name:{width}}  {example.description or ''}".rstrip())
    print(f"\n(in {resource_dir('models')}; mtt examples --copy DIR copies them)")
    return EXIT_OK


def register(commands) -> None:
    """Add draw, bode and examples to the `mtt` subcommands."""
    draw = commands.add_parser(
        "draw",
        help="draw the bond graph (SVG, PNG or PDF)",
        description="Draw the model's bond graph: component labels, bonds numbered as in "
        "`mtt show` with a half-arrow at the head (the direction of positive power), and the "
        "causal stroke at the end of each bond that receives the effort.",
    )
    draw.add_argument("file", metavar="FILE")
    draw.add_argument("-o", "--out", type=_figure_path, metavar="FILE.svg|png|pdf",
                      help="the picture to write (default MODEL.svg, MODEL the file's name "
                      "without .bg, in the working directory)")  # fmt: skip
    draw.add_argument("--dpi", type=_dpi, default=150.0,
                      help="resolution of a .png (default 150)")  # fmt: skip
    add_selection_options(draw)
    draw.add_argument("--json", action="store_true", help="print one JSON object")
    draw.set_defaults(run=cmd_draw)

    bode = commands.add_parser(
        "bode",
        help="Bode diagram for several values of the unknown",
        description="Magnitude and phase of the transfer function against frequency, one "
        "curve per value of the unknown.",
    )
    bode.add_argument("file", metavar="FILE")
    bode.add_argument("--k", type=_values, nargs="+", action=Flatten, metavar="V",
                      help="values of the unknown, a curve each: --k 1,5,10 or --k 1 5 10 "
                      "(default: the model file's values of every unknown, one curve)")  # fmt: skip
    bode.add_argument("-o", "--out", type=_figure_path, metavar="FILE.svg|png|pdf",
                      help="the figure to write (default MODEL_bode.svg in the working "
                      "directory, unless --json alone)")  # fmt: skip
    bode.add_argument("--dpi", type=_dpi, default=150.0,
                      help="resolution of a .png (default 150)")  # fmt: skip
    add_parameter_options(bode)
    bode.add_argument("--json", action="store_true",
                      help="print the frequencies, magnitudes and phases as JSON")  # fmt: skip
    bode.set_defaults(run=cmd_bode)

    examples = commands.add_parser(
        "examples",
        help="list the example models, or copy them to a directory",
        description="List the example models shipped with mtt (the paper's DC drive and "
        "absorber among them), or copy them all to a directory to start from.",
    )
    examples.add_argument(
        "--copy", type=given, metavar="DIR", help="copy every example model into DIR"
    )
    examples.add_argument("--force", action="store_true", help="replace files that differ")
    examples.add_argument("--json", action="store_true", help="print one JSON object")
    examples.set_defaults(run=cmd_examples)
