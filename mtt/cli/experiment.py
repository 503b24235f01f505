"""`mtt compile` and `mtt simulate`, and the experiment of `simulate`, `estimate` and `fit`.

`compile` writes the estimator module. The others build the same module in memory
(codegen.load) and call its functions, so the algorithm exists once, in the template; the
records come from mtt.data, their options from the command line (read here).
"""

from __future__ import annotations

import json
import sys
from types import ModuleType

from mtt import files
from mtt.cli import unknowns
from mtt.cli.options import choice_from_args
from mtt.cli.running import EXIT_OK, UsageError
from mtt.data import default_hold, records
from mtt.data.records import Record
from mtt.derivation import pipeline
from mtt.derivation.nonlinear import nonlinear_parts
from mtt.estimator import codegen, nonlinear_codegen
from mtt.present import tables


def hold_of(args) -> str:
    """--hold, or its default (mtt.data.default_hold)."""
    if args.hold is not None:
        return args.hold
    return default_hold(args.signal, measured=bool(getattr(args, "data", None)))


def refuse_simulation(args) -> None:
    """With --data there is nothing to simulate: a simulation option is an error, not ignored."""
    simulation = {"--signal": args.signal, "--t-end": args.t_end, "--dt": args.dt}
    simulation |= {"--true": args.true}
    simulation |= {"--noise-uniform": args.noise_uniform, "--noise-snr": args.noise_snr}
    simulation |= {"--seed": args.seed, "--amplitude": args.amplitude, "--period": args.period}
    given = [flag for flag, value in simulation.items() if value is not None]
    if given:
        raise UsageError(f"--data and {given[0]} do not go together ({given[0]} simulates)")


def experiment_data(module: ModuleType, args, several: bool = False) -> list[Record]:
    """Measured data (each --data), or a simulation of the model with the chosen input and
    noise: one record unless `several` (fit) allows more."""
    if getattr(args, "data", None):
        refuse_simulation(args)
        if len(args.data) > 1 and not several:
            raise UsageError(
                f"{args.command} takes one --data ({len(args.data)} given); `mtt fit` combines "
                "several experiments"
            )
        names = records.columns(args.columns)
        return [records.read(module, path, names) for path in args.data]
    if getattr(args, "columns", None) and not getattr(args, "validate", None):
        raise UsageError("--columns names the columns of --data files (and of --validate files)")
    t, u, source = records.input_signal(
        module, args.signal, t_end=args.t_end, dt=args.dt, period=args.period,
        amplitude=args.amplitude, seed=args.seed,
    )  # fmt: skip
    k = unknowns.true_point(module, args.true)
    if isinstance(k, list):
        example = ",".join(f"{name}=..." for name in k) if len(module.UNKNOWNS) > 1 else "V"
        raise UsageError(
            f"the model gives no value of {', '.join(k)} to simulate with: pass --true {example}"
        )
    return [
        records.simulate(
            module,
            t,
            u,
            k,
            source=source,
            x0=records.initial_state(module, getattr(args, "x0", None), u[0], k),
            hold=hold_of(args),
            seed=args.seed,
            noise_uniform=args.noise_uniform,
            noise_snr=args.noise_snr,
        )  # fmt: skip
    ]


# the commands --------------------------------------------------------------------------


def module_for(args, several: bool = False) -> ModuleType:
    """The estimator module; with several inputs or outputs only where `several` allows."""
    module = codegen.load(pipeline.theta_for(args.file, choice_from_args(args)))
    return module if several and hasattr(module, "theta_channels") else checked_module(module)


def checked_module(module: ModuleType) -> ModuleType:
    """The module, if it has one input and one output and the model gives every kept
    parameter a value."""
    if hasattr(module, "theta_channels"):
        raise UsageError(several_records(module))
    missing = [name for name, value in module.DEFAULTS.items() if value is None]
    if missing:
        name = missing[0]
        raise UsageError(f"the model gives no value for {name}: pass --set {name}=VALUE")
    return module


def several_records(module: ModuleType) -> str:
    """Why a command that reads records refuses a model of several inputs or outputs."""
    return (
        f"from {', '.join(module.INPUTS)} to {', '.join(module.OUTPUTS)}: the commands that "
        "read records (estimate, validate, simulate, batch) take one input and one output "
        "(--input TYPE:NAME --output TYPE:NAME); `mtt fit --data` fits every signal, as do "
        "the API's Model.fit and the compiled module's fit_signals (docs/estimator.md)"
    )


def _nonlinear(args):
    """(graph, choice) of a nonlinear model given no operating point (whose module is
    its simulator, not an estimator), else None."""
    choice = choice_from_args(args)
    if choice.at is None:
        graph = pipeline.load(args.file, choice.selection)
        if nonlinear_parts(graph):
            return graph, choice
    return None


def cmd_compile(args) -> int:
    nonlinear = _nonlinear(args)
    if nonlinear:  # no operating point: the nonlinear model's simulator
        return _compile_simulator(args, *nonlinear)
    theta = pipeline.theta_for(args.file, choice_from_args(args))
    source = codegen.render(theta)
    path = codegen.output_path(args.path, theta)
    files.write_atomic(path, source)
    kept = f", {', '.join(theta.symbols)} kept symbolic" if theta.symbols else ""
    if args.json:
        print(json.dumps({"ok": True, "path": str(path), "model": theta.model,
                          "unknown": theta.unknown, "unknowns": list(theta.unknowns),
                          "n": theta.n, "m": theta.m, "N": theta.N,
                          "kept": list(theta.symbols)}))  # fmt: skip
        return EXIT_OK
    print(
        f"wrote {path}: estimator of {', '.join(theta.unknowns)} for {theta.model} "
        f"(n = {theta.n}, m = {theta.m}, N = {theta.N}{kept})"
    )
    return EXIT_OK


def _compile_simulator(args, graph, choice) -> int:
    """`mtt compile` of a nonlinear model: the simulator of its state equations, with
    sensitivities (mtt.estimator.nonlinear_codegen; with --at, the small-signal model's
    estimator instead)."""
    system, values = pipeline.state_equations_for(graph, choice)
    source = nonlinear_codegen.render(system, values=values, description=graph.description)
    path = nonlinear_codegen.output_path(args.path, system)
    files.write_atomic(path, source)
    unknowns = [symbol.name for symbol in system.unknowns]
    states = [symbol.name for symbol in system.states]
    if args.json:
        written = {"ok": True, "path": str(path), "model": system.name, "kind": "simulator"}
        print(json.dumps(written | {"unknowns": unknowns, "states": states}))
        return EXIT_OK
    print(
        f"wrote {path}: simulator of {system.name} ({len(states)} states: "
        f"{', '.join(states)}), with sensitivities to {', '.join(unknowns) or 'no unknown'} "
        "and the initial state (--at u=VALUE: the small-signal estimator instead)"
    )
    return EXIT_OK


def cmd_simulate(args) -> int:
    from mtt.present import plots  # matplotlib: a quarter second, paid by plotting only

    nonlinear = _nonlinear(args)
    if nonlinear:  # the nonlinear model itself (from rest), by its generated simulator
        graph, choice = nonlinear
        system, values = pipeline.state_equations_for(graph, choice)
        description = graph.description
        module = checked_module(
            nonlinear_codegen.load(system, values=values, description=description)
        )
    else:
        module = module_for(args)
    (data,) = experiment_data(module, args)
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean,
            title=f"{module.MODEL}: {data.note}", input_label=plots.signal_label(module, "input"),
            output_label=plots.signal_label(module, "output"), dpi=args.dpi,
        )  # fmt: skip
    if args.csv:
        files.write_atomic(
            args.csv, tables.csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True))
        )
    if args.json:
        arrays = {name: getattr(data, name).tolist() for name in ("t", "u", "y")}
        print(json.dumps({"ok": True, "model": module.MODEL, "note": data.note, "csv": args.csv,
                          **arrays}))  # fmt: skip
    elif args.csv:
        print(f"wrote {args.csv}: {data.note}")
    elif not args.data_plot:
        sys.stdout.write(tables.csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True)))
    return EXIT_OK
