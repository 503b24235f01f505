"""The values a result of the derivation is evaluated at: the unknowns' (positionally, as
the estimator gives them, or by name) and the kept parameters' (by name). A name not given
takes the model file's value; a positional value and the same name by keyword is an error,
never a silent choice (a kept parameter may be called `k`, the unknown something else)."""

from __future__ import annotations

from collections.abc import Mapping

import sympy

from mtt.api.exact import exact
from mtt.language.diagnostics import MttError


def by_name(model: str, unknowns: tuple[str, ...], value: object) -> dict[str, object]:
    """The unknowns' value as values by name: one unknown's value (also a vector of length
    1, as a fit's k), a sequence in the order of the unknowns, or a dict by name."""
    if isinstance(value, Mapping):
        return dict(value)
    if len(unknowns) == 1:  # a number, or a vector of length 1 (a fit's k) as one
        vector = not isinstance(value, str) and hasattr(value, "__len__") and len(value) == 1
        if vector:
            value = next(iter(value.ravel() if hasattr(value, "ravel") else value))
        return {unknowns[0]: value}
    if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != len(unknowns):
        raise MttError(
            f"{model} has {len(unknowns)} unknowns ({', '.join(unknowns)}): give k as a "
            f"sequence of {len(unknowns)} values in that order, a dict by name, or each by "
            f"keyword, not {value!r}",
            kind="bad_argument",
        )
    return dict(zip(unknowns, value, strict=True))


def substitution(
    params, model: str, value: object = None, given: Mapping[str, object] | None = None
) -> dict[sympy.Symbol, sympy.Expr]:
    """Symbol -> exact value for every free name of `params` (a Theta or a Parametrisation:
    its unknowns, kept symbols, defaults, true values and substituted parameters)."""
    named = dict(given or {})
    if value is not None:
        if not params.unknowns:
            raise MttError(f"{model} has no unknown: give values by name", kind="bad_argument")
        positional = by_name(model, params.unknowns, value)
        both = sorted(named.keys() & positional.keys())
        if both:
            raise MttError(f"{both[0]} is given twice: in k and by name", kind="bad_argument")
        named.update(positional)
    free = params.unknowns + params.symbols
    for name in named:
        if name in params.assumed:
            raise MttError(
                f"{name} is known and substituted (= {params.assumed[name]}): load the model "
                f"with keep=[{name!r}] to vary it, or set={{{name!r}: ...}}",
                kind="substituted_parameter",
            )
        if name not in free:
            raise MttError(
                f"{name!r} is not a parameter of {model} (free: {', '.join(free) or 'none'})",
                kind="undeclared_parameter",
            )
    defaults = {**params.defaults, **params.true_values}
    values = {}
    for name in free:
        found = exact(name, named[name]) if name in named else defaults[name]
        if found is None:
            raise MttError(
                f"{model} gives no value for {name}: pass {name}=VALUE", kind="missing_value"
            )
        values[sympy.Symbol(name)] = found
    return values
