"""The arguments of `mtt compile`, `mtt simulate`, `mtt estimate` and `mtt fit`.

Kept apart from their implementation (experiment.py, which needs numpy, sympy and
scipy) so that building the `mtt` parser, for `--help` or for another command, costs
no heavy import: each command imports its implementation when it runs.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from mtt.cli.options import add_parameter_options, given, words
from mtt.cli.value_options import (
    BoundsAction,
    Flatten,
    named_values,
    numbers,
    starts,
    state_values,
)
from mtt.data import DEFAULT_DT, DEFAULT_SEED, DEFAULT_T_END


def _implementation(name: str, module: str = "experiment") -> Callable[[argparse.Namespace], int]:
    """The command `name` of mtt/cli/MODULE.py (experiment.py unless said), imported when
    it runs."""

    def run(args: argparse.Namespace) -> int:
        import importlib

        from mtt.cli.running import guarded

        implementation = importlib.import_module(f"mtt.cli.{module}")
        return guarded(getattr(implementation, name))(args)

    return run


def _data_options(parser: argparse.ArgumentParser, measured: bool) -> None:
    group = parser.add_argument_group("data")
    if measured:
        group.add_argument(
            "--data",
            metavar="FILE.csv",
            action="append",
            help="measured data: a CSV file with columns t,u,y (see --columns); `fit` takes "
            "several, one per experiment, and combines them, or glob patterns such as "
            "'logs/*.csv' (many records: see below)",
        )
        group.add_argument(
            "--columns",
            metavar="NAME",
            type=words,
            nargs="+",
            action=Flatten,
            help="the names of the CSV columns of time, input and output (default t,u,y): "
            "--columns time,v,w or --columns time v w",
        )
    group.add_argument(
        "--signal",
        type=given,
        metavar="KIND|FILE.csv",
        help="the simulated input: step (default, from t = 0), prbs, square, multisine, or a "
        "CSV file with columns t,u",
    )
    group.add_argument("--amplitude", type=float, help="the input's amplitude (default 1)")
    group.add_argument(
        "--period",
        type=float,
        help="prbs: the time between switches (default span/100); square: the period (span/10); "
        "multisine: the fundamental period (the span)",
    )
    group.add_argument("--t-end", type=float, help=f"duration (default {DEFAULT_T_END:g})")
    group.add_argument("--dt", type=float, help=f"sampling interval (default {DEFAULT_DT:g})")
    group.add_argument(
        "--true",
        "--k",
        dest="true",
        type=named_values,
        metavar="V|NAME=V,...",
        help="the unknowns' true values: a number for one unknown, each by name for several "
        "(ra=1,jl=10); default: the file's",
    )
    noise = group.add_mutually_exclusive_group()
    noise.add_argument(
        "--noise-uniform", type=float, metavar="A", help="add noise uniform in [-A, A] to y"
    )
    noise.add_argument(
        "--noise-snr",
        type=float,
        metavar="DB",
        help="add white Gaussian noise to y at this signal-to-noise ratio in dB (the output's "
        "variance over the noise's)",
    )
    group.add_argument(
        "--seed", type=int, help=f"seed of the noise and the PRBS (default {DEFAULT_SEED})"
    )
    group.add_argument(
        "--hold",
        choices=("linear", "zoh"),
        help="how the input varies between samples: linear, or zoh (held, as from a DAC); "
        "default zoh for a simulated step, prbs or square (held by construction), else linear",
    )
    group.add_argument("--data-plot", type=given, metavar="FILE.png", help="plot input and output")
    group.add_argument(
        "--dpi", type=float, default=120.0, help="resolution of the figures (default 120)"
    )


def _filter_options(group, several: bool, default: str | None) -> None:
    """--filter and --filter-T, spelled as in the generated modules' own command line."""
    group.add_argument(
        "--filter",
        nargs="+" if several else None,
        metavar="C(s)",
        help='the filter: "auto" (chosen from A(s, k) and the sampling) or a polynomial in s, '
        f'e.g. "(1+s)^5" (default {default})',
    )
    listed = {"type": numbers, "nargs": "+", "action": Flatten} if several else {"type": float}
    group.add_argument(
        "--filter-T",
        metavar="T",
        help="the filter(s) (1 + sT)^(n+1)" + (", --filter-T 0.5,1,2 or 0.5 1 2" * several),
        **listed,
    )


def _batch_options(parser: argparse.ArgumentParser) -> None:
    """The fit command's options for many records (mtt/cli/batch.py runs them)."""
    group = parser.add_argument_group(
        "many records",
        "--data takes glob patterns ('logs/*.csv'): each record is then fitted on its own "
        "(files named one by one are combined into one fit); the options below choose",
    )
    mode = group.add_mutually_exclusive_group()
    mode.add_argument(
        "--per-record", action="store_true", help="fit each --data record on its own (a table)"
    )
    mode.add_argument(
        "--pooled", action="store_true", help="fit all --data records together (moments add)"
    )
    where = group.add_mutually_exclusive_group()
    where.add_argument(
        "--jobs", type=int, metavar="N", help="worker processes (default 1: this process)"
    )
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a dask.distributed scheduler (tcp://host:8786; pip install -e '.[dask]' "
        "in mtt's clone)",
    )


def register(commands) -> None:
    """Add compile, simulate, estimate and fit to the `mtt` subcommands."""
    compile_ = commands.add_parser(
        "compile",
        help="write the estimator module of a model",
        description="Write a standalone Python module (numpy and scipy only) that identifies "
        "the model's unknown parameters from input/output data.",
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
    compile_.add_argument("--json", action="store_true", help="print what was written as JSON")
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
    simulate.add_argument(
        "--x0",
        type=state_values,
        metavar="V,...|NAME=V,...",
        help="a nonlinear model's initial state (without --at): a value per state in the "
        "order `mtt ss` lists them (--x0 1000,800), or by name (--x0 q_upper=1000; a state "
        "not named starts at 0); default rest, x = 0",
    )
    simulate.add_argument("--csv", type=given, metavar="FILE", help="write the samples (t,u,y)")
    simulate.add_argument(
        "--json", action="store_true", help="print the samples as JSON arrays t, u, y"
    )
    simulate.set_defaults(run=_implementation("cmd_simulate"))

    estimate = commands.add_parser(
        "estimate",
        help="identify the unknown(s) from data (measured or simulated)",
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
        "--k0",
        type=starts,
        nargs="+",
        action=Flatten,
        required=True,
        metavar="V|NAME=V,...",
        help="initial estimate(s): numbers for one unknown (--k0 0,5,20 or --k0 0 5 20); for "
        "several, each start by name, a space between starts (--k0 ra=0.5,jl=5 ra=2,jl=20)",
    )
    group.add_argument("--beta", type=float, default=0.1, help="forgetting factor (default 0.1)")
    weight = group.add_mutually_exclusive_group()
    weight.add_argument("--S0", type=float, default=1e-4, help="initial weight (default 1e-4)")
    weight.add_argument(
        "--S0-relative",
        type=float,
        metavar="F",
        help="S0 relative to the data: F times their cost's curvature at k0 per unit of time "
        "(the prior weighs as much as F time units of data; 1e-4 suits most records)",
    )
    _filter_options(group, several=True, default="(1 + s)^(n+1)")
    group.add_argument(
        "--engine",
        choices=("moments", "ode"),
        default="moments",
        help="moments: exact, at every sample (default); ode: the paper's integration",
    )
    group.add_argument(
        "--bounds",
        action=BoundsAction,
        nargs="+",
        metavar="LO:HI|NAME=LO:HI,...",
        help="look for the global minimum of J within LO:HI (also LO HI); several unknowns: "
        "each by name, the others within a factor 10 of the file's value (default: everywhere; "
        "several unknowns: that box)",
    )
    group.add_argument("--rtol", type=float, default=1e-6, help="the ODE's relative tolerance")
    group.add_argument("--atol", type=float, default=1e-9, help="the ODE's absolute tolerance")
    outputs = estimate.add_argument_group("outputs")
    outputs.add_argument(
        "--plot", type=given, metavar="FILE.png", help="plot the estimates against time"
    )
    outputs.add_argument(
        "--cost-plot", type=given, metavar="FILE.png", help="plot the cost at the end"
    )
    outputs.add_argument(
        "--cost-range", type=float, nargs=2, metavar=("A", "B"), help="k range of --cost-plot"
    )
    outputs.add_argument("--csv", type=given, metavar="FILE", help="write the trajectories as CSV")
    outputs.add_argument("--json", action="store_true", help="print the results as JSON")
    estimate.set_defaults(run=_implementation("cmd_estimate", "estimating"))

    fit = commands.add_parser(
        "fit",
        help="fit the unknown(s) to whole records, with their uncertainty",
        description="Fit the unknown(s) to whole records (measured, several --data combined, or "
        "simulated) with the generated module's `fit`: by default the minimiser of the exact "
        "sampled-data prediction error (from the global minimiser of the paper's "
        "least-squares cost), with a noise model chosen by the BIC, offsets and initial state "
        "estimated; print the estimate, its standard error and 95 % interval, the fit, the "
        "noise model and every warning. A nonlinear model (without --at) is fitted by "
        "prediction error with its simulator (and the same noise model), from the "
        "small-signal model's estimate and a multistart. Exit status 1 when there is no "
        "estimate or a diagnostic contradicts it (the reason is printed).",
    )
    fit.add_argument("file", metavar="FILE")
    add_parameter_options(fit)
    _data_options(fit, measured=True)
    group = fit.add_argument_group("estimator")
    group.add_argument(
        "--method",
        choices=("pem", "iv", "ls"),
        default="pem",
        help="pem: the exact prediction error (default); iv: refined instrumental variables; "
        "ls: the paper's least squares (both exact for a linear interpolation of the output)",
    )
    group.add_argument(
        "--noise",
        choices=("auto", "white", "ar", "arma"),
        default="auto",
        help="the output noise model of --method pem and of a nonlinear model's fit (default "
        "auto: white, AR or ARMA, orders by the BIC)",
    )
    _filter_options(group, several=False, default="auto")
    group.add_argument(
        "--k0",
        type=named_values,
        metavar="V|NAME=V,...",
        help="where the iterations start (default: least squares); several unknowns: by name",
    )
    group.add_argument(
        "--bounds",
        action=BoundsAction,
        nargs="+",
        metavar="LO:HI|NAME=LO:HI,...",
        help="look for k within LO:HI (also LO HI); several unknowns: each by name, the others "
        "within a factor 10 of the file's value (the default box); one unknown: everywhere",
    )
    group.add_argument(
        "--offset",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="estimate a constant offset of the output (an operating point; default on)",
    )
    group.add_argument(
        "--initial-state",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="allow the system not to be at rest at the first sample (default on)",
    )
    group.add_argument(
        "--beta",
        type=float,
        default=0.0,
        help="iv and ls only: weigh each sample by e^(-beta (t_end - t)) (default 0)",
    )
    group.add_argument(
        "--shooting",
        choices=("auto", "single", "multiple"),
        help="a nonlinear model's fit: simulate each record whole (single), in segments joined "
        "by continuity (multiple), or multiply where single shooting fails (auto, the default)",
    )
    group.add_argument(
        "--multistart",
        type=int,
        metavar="N",
        help="a nonlinear model's fit: N quasi-random starts over the bounds besides the "
        "small-signal model's estimate, --k0 and the file's values (default 4)",
    )
    outputs = fit.add_argument_group("outputs")
    outputs.add_argument(
        "--plot",
        type=given,
        metavar="FILE.png",
        help="plot measured and simulated output and the residuals",
    )
    outputs.add_argument(
        "--csv",
        type=given,
        metavar="FILE",
        help="write t, u, y, the fitted output and the residual (per record: the table)",
    )
    outputs.add_argument("--json", action="store_true", help="print the result as JSON")
    fit.add_argument_group("validation").add_argument(
        "--validate",
        action="append",
        type=given,
        metavar="VAL.csv",
        help="a record the fit did not use (CSV, the columns of --data): its fit %% and "
        "residual RMS with its own initial state and output offset estimated, printed and in "
        "--json and --plot beside the estimation figures (repeat for several)",
    )
    _batch_options(fit)
    fit.set_defaults(run=_implementation("cmd_fit", "fitting"))
