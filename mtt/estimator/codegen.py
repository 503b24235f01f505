"""Stage 7: Theta -> a standalone Python module that identifies the unknown parameter.

The algorithm lives in `templates/estimator_algorithm.py.j2`, the same for every system;
`templates/estimator.py.j2` adds what is particular to one system (Theta as a function of
the known parameters kept symbolic, n, m, N, names and a header docstring). Everything
taken from the model reaches the generated code as a validated identifier, as a string
through `repr`, or as a number printed here from its exact value: so the generated text
is safe to run, and the same Theta always gives the same bytes.
"""

from __future__ import annotations

import importlib.machinery
import linecache
import math
import os
import sys
import types
from functools import cache
from pathlib import Path

import jinja2
import sympy

from mtt.derivation.theta import Theta, refuse_cancelled
from mtt.estimator import advice
from mtt.estimator.literals import (
    doc_text,
    docstring_safe,
    finite_float,
    is_name,
    literal,
    number,
    wrapped,
)
from mtt.language.diagnostics import ModelError, Source, error
from mtt.resources import resource_dir
from mtt.version import __version__

# Keyword names of the generated functions: a kept parameter, passed as a keyword
# argument (`estimate(..., tau=2)`), must not take one of them (tests/test_codegen.py
# holds that this covers every function and method of a module that takes **known).
RESERVED = frozenset(
    {"t", "u", "y", "k", "k0", "beta", "S0", "C", "hold", "method", "rtol", "atol"}
    | {"max_step", "progress", "engine", "bounds", "self", "known", "offset", "initial_state"}
    | {"records", "keep", "fraction", "uncertainty", "noise"}  # fit_records, prior_weight, fit
)
# Run by the interpreter at start-up wherever they are on its path (as are a package's
# __init__ and __main__: every __dunder__ name is refused too).
SPECIAL_MODULES = frozenset({"sitecustomize", "usercustomize"})


def _fail(theta: Theta, kind: str, message: str, name: str | None = None) -> ModelError:
    """An error at the declaration of the parameter `name`, or at the model's name ("" for
    it), or at no place (None: Theta itself)."""
    place = None if name is None else theta.declared.get(name) if name else theta.name_position
    return ModelError(theta.source or Source(theta.source_name, ""), [error(kind, message, place)])


def shadows(name: str) -> bool:
    """Whether an estimator module of this name would shadow a module for code run beside
    it: one of the standard library's, or one installed (numpy, scipy, ...), or a name
    Python gives a meaning wherever it is (__init__, __main__, sitecustomize). The current
    directory is not looked in: an estimator written there before is no module to keep."""
    special = name in SPECIAL_MODULES or (name.startswith("__") and name.endswith("__"))
    if special or name in sys.stdlib_module_names or name in sys.builtin_module_names:
        return True
    here = {"", os.getcwd()}
    return (
        importlib.machinery.PathFinder.find_spec(name, [p for p in sys.path if p not in here])
        is not None
    )


def _check(theta: Theta) -> None:
    """Reject what the generated module could not carry safely or use meaningfully."""
    if not (isinstance(theta.model, str) and is_name(theta.model, dotted=False)):
        raise _fail(
            theta, "bad_name", f"the model name {theta.model!r} is not a Python identifier", ""
        )
    if shadows(theta.model):
        raise _fail(
            theta,
            "reserved_name",
            f"the model name {theta.model!r} is the name of a Python module: the estimator "
            f"module {theta.model}.py would shadow it wherever it is imported; rename the model",
            "",
        )
    for role, names in (("unknown", theta.unknowns), ("parameter", theta.symbols)):
        for name in names:
            if not is_name(name):
                raise _fail(
                    theta,
                    "bad_name",
                    f"the {role} {name!r} is (or has a part that is) a Python keyword, which "
                    "the estimator module cannot name; rename it in the model",
                    name,
                )
    for name in theta.symbols:
        if name in RESERVED:
            raise _fail(
                theta,
                "reserved_name",
                f"the parameter {name!r} cannot be kept symbolic: the estimator's functions "
                "take an argument of that name; substitute its value (drop it from --keep) "
                "or rename it in the model",
                name,
            )
    refuse_cancelled(theta)


def _in_range(theta: Theta, value: sympy.Expr, name: str | None = None) -> sympy.Expr:
    """value (of the parameter `name`, or else a coefficient of Theta), unless the module's
    floating point cannot hold it (it would overflow to inf or vanish): then an error."""
    what = "a coefficient of Theta" if name is None else f"the value of {name}"
    try:
        number = finite_float(value)
    except (OverflowError, ValueError):
        number = math.inf
    if not math.isfinite(number) or (number == 0 and value != 0):
        raise _fail(
            theta,
            "out_of_range",
            f"{what}, about {sympy.sstr(sympy.N(value, 4))}, is beyond the floating-point "
            "range (about 1e-308 to 1e308) that the estimator computes in; give the parameters "
            "values in units nearer 1",
            name,
        )
    return value


def _entry(theta: Theta, expr: sympy.Expr, symbols: list[sympy.Symbol]) -> str:
    """Python text for one entry of Theta, each kept parameter read as p['name']."""
    if not symbols:
        return number(_in_range(theta, expr))
    try:
        poly = sympy.Poly(expr, *symbols)
    except sympy.PolynomialError:
        raise _fail(
            theta,
            "unsupported_theta",
            f"the Theta entry {expr} is not a polynomial in the kept parameters; "
            "substitute their values instead (drop them from --keep)",
        ) from None
    terms = []
    for monomial, coefficient in poly.terms():
        _in_range(theta, coefficient)
        factors = [
            f"p[{symbol.name!r}]" + (f" ** {power}" if power > 1 else "")
            for symbol, power in zip(symbols, monomial, strict=True)
            if power
        ]
        if not factors:
            terms.append(number(coefficient))
        elif abs(coefficient) == 1:
            terms.append(("-" if coefficient < 0 else "") + " * ".join(factors))
        else:
            terms.append(" * ".join([number(coefficient), *factors]))
    if not terms:
        return "0"
    text = terms[0]
    for term in terms[1:]:
        text += f" - {term[1:]}" if term.startswith("-") else f" + {term}"
    return text


@cache
def environment() -> jinja2.Environment:
    environment = jinja2.Environment(
        loader=jinja2.FileSystemLoader(resource_dir("templates")),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        autoescape=False,
    )
    environment.filters["repr"] = repr
    environment.filters["doc"] = docstring_safe
    environment.filters["literal"] = literal
    return environment


def _context(theta: Theta) -> dict:
    _check(theta)
    by_name = {s.name: s for c in (theta, *theta.channels) for s in c.matrix.free_symbols}
    strays = sorted(set(by_name) - set(theta.symbols))
    if strays:
        raise ValueError(f"Theta depends on {strays}, which are not kept parameters")
    symbols = [by_name[name] for name in theta.symbols if name in by_name]
    rows = [
        ([_entry(theta, entry, symbols) for entry in theta.matrix.row(i)], label)
        for i, label in enumerate(theta.row_labels)
    ]
    channels = [[_entry(theta, e, symbols) for e in c.matrix.row(i)] for c in theta.channels
                for i in range(c.matrix.rows)]  # fmt: skip
    defaults = {name: theta.defaults.get(name) for name in theta.symbols}
    several = len(theta.unknowns) > 1
    given = {
        name: finite_float(_in_range(theta, value, name))
        for name, value in theta.true_values.items()
        if value is not None and name in theta.unknowns
    }
    examples = [given.get(name, 1.0) for name in theta.unknowns]
    if several:
        true_value = ", ".join(
            f"{name} = {doc_text(str(theta.true_values[name]))}" for name in given
        )
        true_float = repr(tuple(given.get(name) for name in theta.unknowns))
        example_k, example_k0 = repr(examples), repr([value / 2 for value in examples])
        example_option = ",".join(
            f"{name}={value / 2!r}" for name, value in zip(theta.unknowns, examples, strict=True)
        )
    else:
        value = theta.true_value
        true_value = None if value is None else doc_text(str(value))
        true_float = "None" if value is None else repr(examples[0])
        example_k, example_k0 = repr(examples[0]), repr(examples[0] / 2)
        example_option = example_k0
    return {
        "version": __version__,
        "command_line_advice": advice.COMMAND_LINE,
        "model": theta.model,
        "description": theta.description,
        "source": theta.source_name,
        "input": theta.input,
        "output": theta.output,
        "input_description": theta.input_description,
        "output_description": theta.output_description,
        "several": several,
        "unknown": theta.unknown,
        "unknowns": tuple(theta.unknowns),
        "names": ", ".join(theta.unknowns),
        "degrees": ", ".join(f"{name} {degree}" for name, degree in theta.degrees.items()),
        "columns": ", ".join(theta.column_labels),
        "monomials": repr(tuple(tuple(int(e) for e in monomial) for monomial in theta.monomials)),
        "true_value": true_value or None,
        "true_value_float": true_float,
        "transfer": f"({theta.num})/({theta.den})",
        "numerator": wrapped("B(s)", theta.num),
        "denominator": wrapped("A(s)", theta.den),
        **{"n": theta.n, "m": theta.m, "N": theta.N},
        "assumed": ", ".join(f"{name} = {doc_text(str(v))}" for name, v in theta.assumed.items()),
        "symbols": theta.symbols,
        "parameters_doc": ", ".join(
            f"{name} = {doc_text(str(value))}" if value is not None else f"{name} (no value)"
            for name, value in defaults.items()
        ),
        "defaults": repr(
            {
                name: None if value is None else finite_float(_in_range(theta, value, name))
                for name, value in defaults.items()
            }
        ),  # fmt: skip
        "rows": rows,
        "channels": [channels[i : i + len(rows)] for i in range(0, len(channels), len(rows))],
        "inputs": tuple(c.input for c in theta.channels[: theta.shape[1]]),
        "outputs": tuple(c.output for c in theta.channels[:: theta.shape[1]]),
        "example_k": example_k,
        "example_k0": example_k0,
        "example_k0_option": example_option,
    }


def render(theta: Theta) -> str:
    """The generated module's source text for `theta` (deterministic)."""
    return environment().get_template("estimator.py.j2").render(_context(theta))


def output_path(given: str | None, theta: Theta) -> Path:
    """Where `mtt compile -o GIVEN` writes an estimator (`module_path`)."""
    return module_path(given, theta.model, lambda text: _fail(theta, "reserved_name", text))


def module_path(given: str | None, model: str, refuse) -> Path:
    """Where `mtt compile -o GIVEN` writes the module of `model`: generated/MODEL.py by
    default, MODEL.py inside GIVEN when it is a directory (or ends with a slash), else
    GIVEN itself; `refuse(message)` is the error for a file that would shadow a module."""
    if given is None:
        return Path("generated") / f"{model}.py"
    if not given:
        raise ValueError("-o needs a file or a directory, not an empty name")
    path = Path(given)
    if path.is_dir() or given.endswith(("/", os.sep)):
        return path / f"{model}.py"
    if path.suffix == ".py" and path.stem != model and shadows(path.stem):
        raise refuse(
            f"-o {given}: {path.stem} is the name of a Python module: the module "
            f"{path.name} would shadow it wherever it is imported; choose another file name"
        )
    return path


def load(theta: Theta) -> types.ModuleType:
    """The generated module for `theta`, imported without writing a file: what `mtt
    simulate/estimate` and `Model.estimator()` run (see `load_source`)."""
    return load_source(theta.model, render(theta))


def load_source(model: str, text: str) -> types.ModuleType:
    """A generated module's source text run as the module `_mtt_generated_MODEL`.

    The source is the same text `mtt compile` writes (see the module docstring for why
    running it is safe), registered in sys.modules so that its dataclasses find their
    own module, and in linecache under the name `<_mtt_generated_MODEL>` so that
    tracebacks, warnings and inspect show its lines. Loading the same source again gives
    the module already loaded.
    """
    name = f"_mtt_generated_{model}"
    loaded = sys.modules.get(name)
    if loaded is not None and getattr(loaded, "_mtt_source", None) == text:
        return loaded  # the same module: objects made by it still pickle as its own
    module = types.ModuleType(name)
    module.__file__ = f"<{name}>"  # no file: the text is in linecache
    linecache.cache[module.__file__] = (len(text), None, text.splitlines(True), module.__file__)
    sys.modules[name] = module
    try:
        exec(compile(text, module.__file__, "exec"), module.__dict__)
    except BaseException:
        del sys.modules[name]
        raise
    module._mtt_source = text
    return module
