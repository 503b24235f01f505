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
from mtt.present.polynomials import factored, grouped, in_powers_of_s, text


def _written(matrix: TransferMatrix) -> report.Written:
    """The names of the matrix's expressions as sympy reads them back (`report`)."""
    entries = [
        e for row in matrix.entries for entry in row for e in (entry.numerator, entry.denominator)
    ]
    return report.Written(matrix.A, *matrix.B, *entries)


def _heading(matrix: TransferMatrix, written: report.Written) -> list[str]:
    params = matrix.equations.parametrisation
    model = matrix.equations.causal.bondgraph.name
    held = {x.name for x in matrix.A.free_symbols.union(*(b.free_symbols for b in matrix.B))}
    lines = [
        report.heading(
            model, ", ".join(matrix.inputs), ", ".join(matrix.outputs),
            params.unknowns, [name for name in params.symbols if name in held],
        )
    ]  # fmt: skip
    if params.assumed:
        lines.append(report.assumed_text(params.assumed))
    if written.note:
        lines.append(written.note)
    return lines


def _channels(matrix: TransferMatrix):
    """(i, j, 'from Se:v to Df:w') for every entry, by output then input."""
    for i, output in enumerate(matrix.outputs):
        for j, input_ in enumerate(matrix.inputs):
            yield i, j, f"from {input_} to {output}"


def _reduced(matrix: TransferMatrix, i: int, j: int, written: report.Written) -> str | None:
    """What reducing the entry cancels, and the reduced entry; None if nothing in s."""
    common = matrix.cancelled(i, j)
    if common is None:
        return None
    entry = matrix.entries[i][j]
    num, den = (factored(written(p)) for p in (entry.numerator, entry.denominator))
    cancelled = sympy.factor(written(common))
    return f"reduced: the factor {cancelled} cancels: G = {grouped(num)} / ({text(den)})"


def matrix_text(matrix: TransferMatrix) -> str:
    """`mtt tf` with several inputs or outputs."""
    rows, columns = matrix.shape
    written = _written(matrix)
    lines = _heading(matrix, written) + [
        "",
        f"  G(s) = B(s) / A(s): a {rows}x{columns} matrix of polynomials B over the common "
        "characteristic polynomial A",
        f"  A (n = {matrix.n}):  {in_powers_of_s(written(matrix.A))}",
        "",
    ]
    labels = list(_channels(matrix))
    width = max(len(label) for _, _, label in labels) + 1
    reduced = 0
    for i, j, label in labels:
        b = matrix.B[i, j]
        degree = sympy.degree(b, LAPLACE) if b != 0 else 0
        shown = in_powers_of_s(written(b))
        lines.append(f"  {label + ':':{width}}  B (m = {degree}):  {shown}")
        note = _reduced(matrix, i, j, written)
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
    written = _written(matrix)
    entries = []
    for i, j, _ in _channels(matrix):
        entry, common = matrix.entries[i][j], matrix.cancelled(i, j)
        entries.append(
            {
                "input": matrix.inputs[j],
                "output": matrix.outputs[i],
                "B": written.text(matrix.B[i, j]),
                "num": written.text(entry.numerator),
                "den": written.text(entry.denominator),
                "m": entry.degree("num"),
                "n": entry.degree("den"),
                "cancelled": None if common is None else str(sympy.factor(written(common))),
            }
        )
    return {
        **_record(matrix),
        "names": written.table,
        "A": written.text(matrix.A),
        "n": matrix.n,
        "B": [[written.text(b) for b in matrix.B.row(i)] for i in range(matrix.B.rows)],
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
    return {
        **_record(matrix),
        "channels": [report.derived_json(theta, order) for theta in thetas.values()],
    }


def _record(matrix: TransferMatrix) -> dict:
    """What the JSON records of a transfer matrix begin with."""
    params = matrix.equations.parametrisation
    return {
        "ok": True,
        "model": matrix.equations.causal.bondgraph.name,
        "inputs": list(matrix.inputs),
        "outputs": list(matrix.outputs),
        "unknowns": list(params.unknowns),
        "symbols": list(params.symbols),
    }
