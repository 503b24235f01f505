"""The generated module's `fit` options as the command line gives them (`mtt fit`, one
process or many)."""

from __future__ import annotations

from mtt.cli import unknowns
from mtt.cli.experiment import hold_of
from mtt.cli.running import UsageError


def options(module, args) -> dict:
    """The module's `fit` options from the command line (k0 and bounds by unknown)."""
    given = [flag for flag in ("shooting", "multistart") if getattr(args, flag) is not None]
    if given:
        raise UsageError(f"--{given[0]} is an option of a nonlinear model's fit")
    return dict(
        method=args.method, noise=args.noise, C=_filter(args),
        k0=None if args.k0 is None else unknowns.point(module, args.k0, "--k0"),
        bounds=unknowns.bounds(module, args.bounds), offset=args.offset,
        initial_state=args.initial_state, hold=hold_of(args), beta=args.beta,
    )  # fmt: skip


SIGNAL_SETTINGS = ("noise", "C", "k0", "bounds", "offset", "initial_state", "hold")


def signal_options(module, args) -> dict:
    """The options of `fit_signals` (several inputs or outputs) from the command line; the
    linear fit's --method iv|ls and --beta are refused there, not ignored."""
    if args.method != "pem":
        raise UsageError(
            f"--method {args.method} is not supported with several inputs or outputs: they "
            "are fitted by the exact prediction error (--method pem, the default), whose starts "
            "are the paper's least-squares cost of every signal (docs/estimator.md)"
        )
    if args.beta != 0.0:
        raise UsageError("--beta weighs the samples of --method iv and ls, which are not "
                         "supported with several inputs or outputs (--method pem is)")  # fmt: skip
    chosen = options(module, args)
    return {key: value for key, value in chosen.items() if key in SIGNAL_SETTINGS}


def _filter(args):
    """C for the module's `fit`: --filter-T T, --filter TEXT ("auto" by default)."""
    if args.filter is not None and args.filter_T is not None:
        raise UsageError("--filter and --filter-T do not go together")
    if args.filter_T is not None:
        return args.filter_T
    return "auto" if args.filter is None else args.filter.strip()


def nonlinear_options(module, args) -> dict:
    """The options of a nonlinear model's fit (mtt.api.nonlinear_fits.fit): those of the
    linear fit that apply (--noise among them), --shooting and --multistart; --method,
    --filter and --beta (linear options) are refused there unless at their defaults."""
    found = dict(
        k0=None if args.k0 is None else unknowns.point(module, args.k0, "--k0"),
        bounds=unknowns.bounds(module, args.bounds), offset=args.offset,
        initial_state=args.initial_state, hold=hold_of(args),
        method=args.method, noise=args.noise, C=_filter(args), beta=args.beta,
    )  # fmt: skip
    for flag in ("shooting", "multistart"):
        if getattr(args, flag) is not None:
            found[flag] = getattr(args, flag)
    return found
