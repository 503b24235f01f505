"""The arguments of `mtt compile`, `mtt simulate` and `mtt estimate`.

Kept apart from their implementation (experiment.py, which needs numpy, sympy and
scipy) so that building the `mtt` parser, for `--help` or for another command, costs
no heavy import: each command imports its implementation when it runs.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from mtt.cli.options import add_parameter_options

DEFAULT_T_END, DEFAULT_DT, DEFAULT_SEED = 10.0, 0.01, 0


def _implementation(name: str) -> Callable[[argparse.Namespace], int]:
    """The command `name` of experiment.py, imported when it runs."""

    def run(args: argparse.Namespace) -> int:
        from mtt.cli import experiment

        return experiment.guarded(getattr(experiment, name))(args)

    return run


def _data_options(parser: argparse.ArgumentParser, measured: bool) -> None:
    group = parser.add_argument_group("data")
    if measured:
        group.add_argument(
            "--data", metavar="FILE.csv", help="measured data: a CSV file with columns t,u,y"
        )
    group.add_argument(
        "--signal",
        metavar="step|FILE.csv",
        help="the simulated input signal: a unit step at t = 0 (default), or a CSV file with "
        "columns t,u",
    )
    group.add_argument("--t-end", type=float, help=f"duration (default {DEFAULT_T_END:g})")
    group.add_argument("--dt", type=float, help=f"sampling interval (default {DEFAULT_DT:g})")
    group.add_argument("--k", type=float, help="true value of the unknown (default: the file's)")
    group.add_argument(
        "--noise-uniform", type=float, metavar="A", help="add noise uniform in [-A, A] to y"
    )
    group.add_argument("--seed", type=int, help=f"noise seed (default {DEFAULT_SEED})")
    group.add_argument(
        "--hold",
        choices=("linear", "zoh"),
        default="linear",
        help="how the input varies between samples (default linear)",
    )
    group.add_argument("--data-plot", metavar="FILE.png", help="plot input and output")


def register(commands) -> None:
    """Add compile, simulate and estimate to the `mtt` subcommands."""
    compile_ = commands.add_parser(
        "compile",
        help="write the estimator module of a model",
        description="Write a standalone Python module (numpy and scipy only) that identifies "
        "the model's unknown parameter from input/output data.",
    )
    compile_.add_argument("file", metavar="FILE")
    compile_.add_argument(
        "-o",
        "--out",
        metavar="PATH",
        dest="path",
        help="the file to write, or a directory to write MODEL.py into (default "
        "generated/MODEL.py); a link is written through, a device or fifo refused",
    )
    add_parameter_options(compile_)
    compile_.set_defaults(run=_implementation("cmd_compile"))

    simulate = commands.add_parser(
        "simulate",
        help="simulate an experiment's data",
        description="Simulate the model's output for an input, with optional noise; print the "
        "samples as CSV (t,u,y) unless --csv or --data-plot is given.",
    )
    simulate.add_argument("file", metavar="FILE")
    add_parameter_options(simulate)
    _data_options(simulate, measured=False)
    simulate.add_argument("--csv", metavar="FILE", help="write the samples (t,u,y)")
    simulate.set_defaults(run=_implementation("cmd_simulate"))

    estimate = commands.add_parser(
        "estimate",
        help="identify the unknown from data (measured or simulated)",
        description="Run the generated estimator once per starting value and filter; print "
        "the final estimates, the local minima of the cost and its global minimum (a warning "
        "says when the estimate is not there). Exit status 1 if a run stopped early (the "
        "estimate left the region where the cost is convex).",
    )
    estimate.add_argument("file", metavar="FILE")
    add_parameter_options(estimate)
    _data_options(estimate, measured=True)
    group = estimate.add_argument_group("estimator")
    group.add_argument(
        "--k0", type=float, nargs="+", required=True, metavar="V", help="initial estimate(s)"
    )
    group.add_argument("--beta", type=float, default=0.1, help="forgetting factor (default 0.1)")
    group.add_argument("--S0", type=float, default=1e-4, help="initial weight (default 1e-4)")
    group.add_argument(
        "--filter",
        nargs="+",
        metavar="C(s)",
        help='filter polynomial(s) in s, e.g. "(1+s)^5" (default (1 + s)^(n+1))',
    )
    group.add_argument(
        "--filter-T", type=float, nargs="+", metavar="T", help="filter(s) (1 + sT)^(n+1)"
    )
    group.add_argument(
        "--engine",
        choices=("moments", "ode"),
        default="moments",
        help="moments: exact, at every sample (default); ode: the paper's integration",
    )
    group.add_argument(
        "--bounds",
        type=float,
        nargs=2,
        metavar=("LO", "HI"),
        help="look for the global minimum of J within [LO, HI] (default: everywhere)",
    )
    group.add_argument("--rtol", type=float, default=1e-6, help="the ODE's relative tolerance")
    group.add_argument("--atol", type=float, default=1e-9, help="the ODE's absolute tolerance")
    outputs = estimate.add_argument_group("outputs")
    outputs.add_argument("--plot", metavar="FILE.png", help="plot the estimates against time")
    outputs.add_argument("--cost-plot", metavar="FILE.png", help="plot the cost at the end")
    outputs.add_argument(
        "--cost-range", type=float, nargs=2, metavar=("A", "B"), help="k range of --cost-plot"
    )
    outputs.add_argument("--csv", metavar="FILE", help="write the trajectories as CSV")
    outputs.add_argument("--json", action="store_true", help="print the results as JSON")
    estimate.set_defaults(run=_implementation("cmd_estimate"))
