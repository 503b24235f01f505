"""How the derived representations read: as text for people, JSON for tools, LaTeX for papers."""

from __future__ import annotations

import sympy

from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.equations import Equations
from mtt.derivation.theta import Theta
from mtt.derivation.transfer import LAPLACE
from mtt.language.bondgraph import BondGraph


def in_powers_of_s(expression: sympy.Expr) -> str:
    """A polynomial in s written highest power first, each coefficient factored."""
    poly = sympy.Poly(expression, LAPLACE)
    terms = []
    for (power,), coefficient in poly.terms():
        c = _factored(coefficient)  # each coefficient factored
        monomial = {0: "", 1: "s"}.get(power, f"s**{power}")
        if not monomial:
            terms.append(str(c))
        elif c == 1:
            terms.append(monomial)
        elif c == -1:
            terms.append(f"-{monomial}")
        else:
            terms.append(f"{_grouped(c)}*{monomial}")
    return " + ".join(terms).replace("+ -", "- ") or "0"


def _factored(polynomial: sympy.Expr) -> sympy.Expr:
    """The polynomial factored, when that is cheap: one of many terms or of huge numbers
    (sympy's multivariate factoring looks for primes of their size) only has its common
    factors taken out."""
    numbers = polynomial.atoms(sympy.Rational)
    digits = max((len(str(abs(r.p))) + len(str(r.q)) for r in numbers), default=0)
    if digits > 40 or len(sympy.Add.make_args(sympy.expand(polynomial))) > 24:
        return sympy.factor_terms(polynomial)
    return sympy.factor(polynomial)


def _heading(theta: Theta) -> str:
    symbols = ", ".join(theta.symbols) or "none"
    unknowns = f"unknown{'s' * (len(theta.unknowns) > 1)} {', '.join(theta.unknowns) or 'none'}"
    return (
        f"model {theta.model}: from {theta.input} to {theta.output}; {unknowns}; symbolic {symbols}"
    )


def _assumed(theta: Theta) -> str:
    if not theta.assumed:
        return ""
    values = ", ".join(f"{name} = {value}" for name, value in theta.assumed.items())
    return f"values substituted: {values}"


def tf_text(theta: Theta) -> str:
    lines = [_heading(theta)]
    if theta.assumed:
        lines.append(_assumed(theta))
    lines += [
        "",
        f"  numerator   (m = {theta.m}):  {in_powers_of_s(theta.num)}",
        f"  denominator (n = {theta.n}):  {in_powers_of_s(theta.den)}",
        "",
        f"  G(s) = {_grouped(_factored(theta.num))} / ({_factored(theta.den)})",
    ]
    return "\n".join(lines)


def _grouped(expression: sympy.Expr) -> str:
    """The expression as text, in parentheses when it is a sum."""
    return f"({expression})" if isinstance(expression, sympy.Add) else str(expression)


def latex(expression: sympy.Basic) -> str:
    """sympy's LaTeX with a thin space between factors and each multi-letter name set as one
    symbol (\\mathit{mass}): math mode drops spaces, and 5 mass s^2 read as 5masss^2."""
    names = {
        symbol: rf"\mathit{{{symbol.name}}}"
        for symbol in expression.free_symbols
        if len(symbol.name) > 1 and sympy.latex(symbol) == symbol.name
    }
    return sympy.latex(expression, mul_symbol=r"\,", symbol_names=names)


def tf_latex(theta: Theta) -> str:
    num, den = (sympy.collect(sympy.expand(p), LAPLACE) for p in (theta.num, theta.den))
    return f"G(s) = \\frac{{{latex(num)}}}{{{latex(den)}}}"


def theta_text(theta: Theta) -> str:
    labels = theta.column_labels
    cells = [[str(entry) for entry in theta.matrix.row(i)] for i in range(theta.matrix.rows)]
    rows = [["", *labels]] + [
        [label, *row] for label, row in zip(theta.row_labels, cells, strict=True)
    ]
    widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
    table = ["  " + "  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    lines = [_heading(theta)]
    if theta.assumed:
        lines.append(_assumed(theta))
    lines += [
        f"Theta: n = {theta.n}, m = {theta.m}, {_degrees(theta)}; rows "
        f"{theta.row_labels[0]}..{theta.row_labels[theta.n]}, "
        f"{'..'.join(dict.fromkeys((theta.row_labels[theta.n + 1], theta.row_labels[-1])))}; "
        f"columns {', '.join(labels)}",
        "",
        *table,
    ]
    return "\n".join(lines)


def _degrees(theta: Theta) -> str:
    if len(theta.unknowns) <= 1:
        return f"N = {theta.N}"
    each = ", ".join(f"{name} {degree}" for name, degree in theta.degrees.items())
    return f"total degree {theta.N} (in {each})"


def theta_latex(theta: Theta) -> str:
    return f"\\Theta = {latex(theta.matrix)}"


def derived_json(theta: Theta, order: int) -> dict:
    """The `tf --json` / `theta --json` record (its shape is a public contract)."""
    return {
        "ok": True,
        "model": theta.model,
        "input": theta.input,
        "output": theta.output,
        "unknown": theta.unknown,
        "unknowns": list(theta.unknowns),
        "monomials": [list(monomial) for monomial in theta.monomials],
        "degrees": theta.degrees,
        "symbols": list(theta.symbols),
        "num": str(theta.num),
        "den": str(theta.den),
        "n": theta.n,
        "m": theta.m,
        "N": theta.N,
        "theta": [[str(e) for e in theta.matrix.row(i)] for i in range(theta.matrix.rows)],
        "order": order,
    }


def ss_text(equations: Equations) -> str:
    graph = equations.causal.bondgraph
    lines = [
        f"model {graph.name}: causal equations (bond variables e<n>, f<n>; "
        "u input, y output; d<x> is dx/dt)"
    ]
    lines += [f"  {name} = {expression}" for name, expression in equations.relations]
    lines += [
        "",
        "descriptor form E x' = A x + B u, y = C x + D u",
        f"  x = [{', '.join(equations.states)}]",
    ]
    for name, matrix in equations.matrices().items():
        lines += ["", f"{name} ="]
        lines += ["  " + line for line in sympy.pretty(matrix, use_unicode=False).splitlines()]
    return "\n".join(lines)


def show_json(graph: BondGraph) -> dict:
    """The `show --json` record: parameters, components, numbered bonds and subsystems
    (depth first: `motor.brush` follows `motor`)."""
    label = lambda name: graph.component(name).label  # noqa: E731
    return {
        "ok": True,
        "file": graph.source.name,
        "model": graph.name,
        "description": graph.description,
        "parameters": {
            p.name: {
                "value": None if p.value is None else str(p.value.value),
                "unknown": p.name in graph.unknowns,
                "description": p.description,
            }
            for p in graph.parameters.values()
        },
        "components": [
            {
                "name": c.name,
                "type": c.type.name,
                "argument": None if c.argument is None else str(c.argument.value),
            }
            for c in graph.components
        ],  # fmt: skip
        "bonds": [
            {"number": b.number, "tail": label(b.tail), "head": label(b.head)} for b in graph.bonds
        ],  # fmt: skip
        "input": label(graph.input),
        "output": label(graph.output),
        "unknowns": list(graph.unknowns),
        "subsystems": [
            {
                "name": sub.name,
                "file": sub.file,
                "parameters": {name: str(value.value) for name, value in sub.bindings},
                "description": sub.description,
            }
            for sub in graph.subsystems
        ],
    }


def causality_json(causal: CausalBondGraph) -> dict:
    """The `causality --json` record: the component at the stroke end of every bond."""
    graph = causal.bondgraph
    label = lambda name: graph.component(name).label  # noqa: E731
    return {
        "ok": True,
        "model": graph.name,
        "bonds": [
            {
                "number": b.number,
                "tail": label(b.tail),
                "head": label(b.head),
                "stroke": label(causal.stroke_at(b.number)),
            }
            for b in graph.bonds
        ],  # fmt: skip
        "dependent": [label(name) for name in causal.dependent],
        "loops": [label(name) for name in causal.loops],
    }


def ss_json(equations: Equations) -> dict:
    """The `ss --json` record: every entry an exact expression, as text."""
    graph = equations.causal.bondgraph
    params = equations.parametrisation
    matrices = {
        name: [[str(entry) for entry in matrix.row(i)] for i in range(matrix.rows)]
        for name, matrix in equations.matrices().items()
    }
    return {
        "ok": True,
        "model": graph.name,
        "input": graph.component(graph.input).label,
        "output": graph.component(graph.output).label,
        "unknowns": list(params.unknowns),
        "symbols": list(params.symbols),
        "relations": [[name, str(expression)] for name, expression in equations.relations],
        "states": list(equations.states),
        **matrices,
    }


def ss_latex(equations: Equations) -> str:
    return "\n".join(f"{name} = {latex(matrix)}" for name, matrix in equations.matrices().items())
