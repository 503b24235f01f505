"""How a transfer matrix (several inputs and outputs) reads: as text, JSON and LaTeX.

Each channel's Theta is that of its reduced entry, as for one input and one output
(`report`): the matrix adds the common characteristic polynomial and says which entries
reduce.
"""

from __future__ import annotations

import sympy

from mtt.derivation.theta import Theta
from mtt.derivation.transfer import LAPLACE
from mtt.derivation.transfer_matrix import TransferMatrix
from mtt.present import report


def _heading(matrix: TransferMatrix) -> list[str]:
    params = matrix.equations.parametrisation
    model = matrix.equations.causal.bondgraph.name
    lines = [
        report.heading(
            model, ", ".join(matrix.inputs), ", ".join(matrix.outputs),
            params.unknowns, params.symbols,
        )
    ]  # fmt: skip
    if params.assumed:
        lines.append(report.assumed_text(params.assumed))
    return lines


def _channels(matrix: TransferMatrix):
    """(i, j, 'from Se:v to Df:w') for every entry, by output then input."""
    for i, output in enumerate(matrix.outputs):
        for j, input_ in enumerate(matrix.inputs):
            yield i, j, f"from {input_} to {output}"


def _reduced(matrix: TransferMatrix, i: int, j: int) -> str | None:
    """What reducing the entry cancels, and the reduced entry; None if nothing in s."""
    common = matrix.cancelled(i, j)
    if common is None:
        return None
    entry = matrix.entries[i][j]
    num, den = (report.factored(p) for p in (entry.numerator, entry.denominator))
    return (
        f"reduced: the factor {sympy.factor(common)} cancels: G = {report.grouped(num)} / ({den})"
    )


def matrix_text(matrix: TransferMatrix) -> str:
    """`mtt tf` with several inputs or outputs."""
    rows, columns = matrix.shape
    lines = _heading(matrix) + [
        "",
        f"  G(s) = B(s) / A(s): a {rows}x{columns} matrix of polynomials B over the common "
        "characteristic polynomial A",
        f"  A (n = {matrix.n}):  {report.in_powers_of_s(matrix.A)}",
        "",
    ]
    labels = list(_channels(matrix))
    width = max(len(label) for _, _, label in labels) + 1
    reduced = 0
    for i, j, label in labels:
        b = matrix.B[i, j]
        degree = sympy.degree(b, LAPLACE) if b != 0 else 0
        lines.append(f"  {label + ':':{width}}  B (m = {degree}):  {report.in_powers_of_s(b)}")
        note = _reduced(matrix, i, j)
        if note:
            reduced += 1
            lines.append(f"      {note}")
    lines.append("")
    lines.append(
        f"  {reduced} of the {rows * columns} entries reduce"
        if reduced
        else "  every entry B/A is reduced: no factor in s cancels"
    )
    return "\n".join(lines)


def matrix_latex(matrix: TransferMatrix) -> str:
    A = sympy.collect(sympy.expand(matrix.A), LAPLACE)
    B = matrix.B.applyfunc(lambda b: sympy.collect(sympy.expand(b), LAPLACE))
    return f"G(s) = \\frac{{1}}{{{report.latex(A)}}} {report.latex(B)}"


def matrix_json(matrix: TransferMatrix, order: int) -> dict:
    """The `tf --json` record with several inputs or outputs."""
    params = matrix.equations.parametrisation
    entries = []
    for i, j, _ in _channels(matrix):
        entry, common = matrix.entries[i][j], matrix.cancelled(i, j)
        entries.append(
            {
                "input": matrix.inputs[j],
                "output": matrix.outputs[i],
                "B": str(matrix.B[i, j]),
                "num": str(entry.numerator),
                "den": str(entry.denominator),
                "m": entry.degree("num"),
                "n": entry.degree("den"),
                "cancelled": None if common is None else str(sympy.factor(common)),
            }
        )
    return {
        "ok": True,
        "model": matrix.equations.causal.bondgraph.name,
        "inputs": list(matrix.inputs),
        "outputs": list(matrix.outputs),
        "unknowns": list(params.unknowns),
        "symbols": list(params.symbols),
        "A": str(matrix.A),
        "n": matrix.n,
        "B": [[str(b) for b in matrix.B.row(i)] for i in range(matrix.B.rows)],
        "entries": entries,
        "order": order,
    }


def thetas_text(matrix: TransferMatrix, thetas: dict[tuple[int, int], Theta]) -> str:
    """`mtt theta` with several inputs or outputs: each channel's Theta (a zero entry has
    none)."""
    blocks = []
    for i, j, label in _channels(matrix):
        theta = thetas.get((i, j))
        blocks.append(report.theta_text(theta) if theta else f"{label}: G = 0, so no Theta")
    return "\n\n".join(blocks)


def thetas_latex(thetas: dict[tuple[int, int], Theta]) -> str:
    """Each channel's Theta, subscripted with its input and output."""
    return "\n".join(
        f"\\Theta_{{\\mathrm{{{_tex(theta.input)}}} \\to \\mathrm{{{_tex(theta.output)}}}}} = "
        f"{report.latex(theta.matrix)}"
        for theta in thetas.values()
    )


def _tex(label: str) -> str:
    """A component's label in \\mathrm: `Se{:}v`, an underscore escaped."""
    return label.replace(":", "{:}").replace("_", "\\_")


def thetas_json(matrix: TransferMatrix, thetas: dict[tuple[int, int], Theta], order: int) -> dict:
    """The `theta --json` record with several inputs or outputs: a record per channel as
    `theta --json` gives for one (without a zero entry's)."""
    params = matrix.equations.parametrisation
    return {
        "ok": True,
        "model": matrix.equations.causal.bondgraph.name,
        "inputs": list(matrix.inputs),
        "outputs": list(matrix.outputs),
        "unknowns": list(params.unknowns),
        "symbols": list(params.symbols),
        "channels": [report.derived_json(theta, order) for theta in thetas.values()],
    }
