"""Nonlinear state equations, steady states and small-signal models as text, LaTeX and
JSON (`mtt ss` of a nonlinear model, `mtt equilibrium`, `mtt linearise`, and the API)."""

from __future__ import annotations

import math

import sympy

from mtt.derivation.equilibria import Equilibria
from mtt.derivation.nonlinear import NonlinearStateSpace, kept
from mtt.derivation.operating import SmallSignal


def _parameters(ss: NonlinearStateSpace) -> list[str]:
    lines = []
    if ss.unknowns:
        lines.append(f"unknowns: {', '.join(map(str, ss.unknowns))}")
    if ss.known:
        known = ", ".join(f"{name} = {value}" for name, value in ss.known.items())
        lines.append(f"known (substituted): {known}")
    return lines


def equations_text(ss: NonlinearStateSpace) -> str:
    lines = [
        f"model {ss.name}: nonlinear state equations x' = f(x, u), y = g(x, u) "
        f"(u the input, y the output)",
        f"  x = [{', '.join(map(str, ss.states))}]",
    ]
    lines += [f"  d{x}/dt = {value}" for x, value in zip(ss.states, ss.f, strict=True)]
    lines += [f"  {ss.output} = {ss.g[0]}"]
    if ss.domain:
        where = ", ".join(f"{c} >= 0" for c in ss.domain)
        lines.append(f"  where {where} (the domain of the inverses mtt derived)")
    return "\n".join([*lines, "", *_parameters(ss)])


def equations_latex(ss: NonlinearStateSpace) -> str:
    rows = [
        f"\\dot{{{sympy.latex(x)}}} = {sympy.latex(value)}"
        for x, value in zip(ss.states, ss.f, strict=True)
    ]
    rows.append(f"{sympy.latex(ss.output)} = {sympy.latex(ss.g[0])}")
    return "\\begin{aligned}\n" + " \\\\\n".join(f"  {r}" for r in rows) + "\n\\end{aligned}"


def equations_json(ss: NonlinearStateSpace) -> dict:
    """The `ss --json` record of a nonlinear model: every expression as exact text, and the
    parameters kept symbolic (`symbols`)."""
    return {
        "ok": True,
        "model": ss.name,
        "nonlinear": True,
        "states": [str(x) for x in ss.states],
        "f": [str(value) for value in ss.f],
        "g": str(ss.g[0]),
        "domain": [str(c) for c in ss.domain],
        "unknowns": [str(k) for k in ss.unknowns],
        "symbols": [symbol.name for symbol in kept(ss)],
        "known": {str(name): str(value) for name, value in ss.known.items()},
    }


def _number(value: float) -> str:
    return "nan" if math.isnan(value) else f"{value:.10g}"


def equilibria_text(ss: NonlinearStateSpace, found: Equilibria) -> str:
    how = "exact" if found.method == "exact" else "numeric, at the file's values"
    count = len(found.branches)
    lines = [
        f"model {ss.name}: steady states at u = {found.u} ({how}): "
        f"{count} branch{'es' * (count != 1)}"
    ]
    for number, branch in enumerate(found.branches, 1):
        lines.append(f"  branch {number}")
        for x, value in branch.x.items():
            numeric = branch.numeric[x]
            exact = "" if not branch.exact or value.is_Float else f"{value}  "
            lines.append(f"    {x} = {exact}(= {_number(numeric)})")
        for x in branch.free:
            lines.append(f"    {x}: any value (a continuum of steady states)")
        y = "" if not branch.exact else f"{branch.y}  "
        lines.append(f"    {ss.output} = {y}(= {_number(branch.y_numeric)})")
    if not found.branches:
        lines.append("  none found")
    if found.method == "numeric":
        lines.append(
            "sympy could not solve the equations exactly: the branches are those a root "
            "finder reached from many starting points"
        )
    return "\n".join(lines)


def equilibria_json(ss: NonlinearStateSpace, found: Equilibria) -> dict:
    return {
        "ok": True,
        "model": ss.name,
        "u": str(found.u),
        "method": found.method,
        "states": [str(x) for x in ss.states],
        "branches": [
            {
                "x": {str(x): str(v) for x, v in branch.x.items()},
                "x_numeric": {str(x): v for x, v in branch.numeric.items()},
                "free": [str(x) for x in branch.free],
                "y": str(branch.y),
                "y_numeric": None if math.isnan(branch.y_numeric) else branch.y_numeric,
            }
            for branch in found.branches
        ],
    }


def small_signal_text(ss: NonlinearStateSpace, small: SmallSignal, tf: str) -> str:
    point = ", ".join(f"{x} = {v}" for x, v in small.x0.items())
    lines = [
        f"model {ss.name}: small-signal model about u = {small.u0}, {point} (y = {small.y0} there)",
        "x' = A x + B u, y = C x + D u in the deviations from that point",
        f"  x = [{', '.join(map(str, ss.states))}]",
    ]
    for name in "ABCD":
        matrix = getattr(small, name)
        lines += ["", f"{name} ="]
        lines += ["  " + line for line in sympy.pretty(matrix, use_unicode=False).splitlines()]
    return "\n".join([*lines, "", tf])


def small_signal_json(ss: NonlinearStateSpace, small: SmallSignal, tf: dict) -> dict:
    def rows(matrix: sympy.Matrix) -> list[list[str]]:
        return [[str(entry) for entry in matrix.row(i)] for i in range(matrix.rows)]

    return {
        "ok": True,
        "model": ss.name,
        "u0": str(small.u0),
        "x0": {str(x): str(v) for x, v in small.x0.items()},
        "y0": str(small.y0),
        "states": [str(x) for x in ss.states],
        **{name: rows(getattr(small, name)) for name in "ABCD"},
        "transfer_function": tf,
        "warnings": [note.to_json() for note in small.notes],
    }
