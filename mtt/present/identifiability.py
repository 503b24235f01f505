"""`mtt identifiability`'s verdict as people read it and as tools read it (JSON)."""

from __future__ import annotations

from mtt.derivation.identifiability import (
    Identifiability,
    Signals,
    expression_text,
    point_text,
)
from mtt.derivation.theta import Theta
from mtt.derivation.transfer_matrix import TransferMatrix

VERDICTS = {
    "global": "globally identifiable",
    "local": "locally identifiable",
    "none": "not identifiable",
}


def _number(value) -> str:
    """An exact value in the language's syntax; an approximate one to 15 digits."""
    if value.is_Rational:
        return expression_text(value)
    real, imaginary = (float(part) for part in value.as_real_imag())
    return f"{real:.15g}" if imaginary == 0 else f"{real:.15g}{imaginary:+.15g}i"


def identifiability_text(theta: Theta, result: Identifiability) -> str:
    return "\n".join(_lines(theta.model, theta.input, theta.output, theta.true_values, result))


def _lines(model, source, target, true_values, result, what="transfer function") -> list[str]:
    names = ", ".join(result.unknowns)
    several = len(result.unknowns) > 1
    values = f"({names})" if several else names
    lines = [
        f"model {model}: from {source} to {target}; unknown{'s' * several} {names}",
        VERDICTS[result.verdict],
    ]
    if result.verdict == "global":
        lines[-1] += f": the {what} determines {names}"
        return lines
    if result.verdict == "local":
        lines[-1] += (
            f": for generic true values {values}, {result.solutions} values give the same {what}:"
        )
        lines += [f"  {point_text(m)}" for m in result.maps]
        others = result.solutions - len(result.maps)
        if others:
            lines.append(f"  and {others} more, algebraic (not rational) in the true values")
        if result.points:
            model = all(true_values.get(n) == v for n, v in result.point.items())
            lines.append(
                f"for {'the model' + chr(39) + 's' if model else 'random'} values {values} = "
                f"{point_text(result.point, _number)} they are ({result.real} real, "
                f"{result.positive} positive):"
            )
            lines += [f"  {point_text(p, _number)}" for p in result.points]
    else:
        lines[-1] += (
            f": for generic true values, a {len(result.unknowns) - result.rank}-parameter "
            f"family of values of {values} gives the same {what}"
        )
    combinations = ", ".join(expression_text(c) for c in result.combinations)
    lines.append(f"the data determine: {combinations or 'nothing'}")
    lines.append(
        f"identified on {'their' if several else 'its'} own: "
        f"{', '.join(result.identified) or 'none'}"
    )
    return lines


def _part(part: Signals) -> str:
    return f"from {', '.join(part.inputs)} to {', '.join(part.outputs)}"


def _briefly(result: Identifiability) -> str:
    """A part's verdict in a line: what it determines."""
    verdict = VERDICTS[result.verdict]
    if result.verdict == "local":
        return f"{verdict} ({result.solutions} solutions)"
    if result.verdict == "global":
        return verdict
    determined = ", ".join(expression_text(c) for c in result.combinations) or "nothing"
    return f"{verdict}: determines {determined}"


def matrix_text(matrix: TransferMatrix, result: Identifiability) -> str:
    """`mtt identifiability` with several inputs or outputs: the verdict from the whole
    transfer matrix, the signals it needs, and what each smaller set of them determines."""
    graph = matrix.equations.causal.bondgraph
    true_values = matrix.equations.parametrisation.true_values
    lines = _lines(
        graph.name, ", ".join(matrix.inputs), ", ".join(matrix.outputs), true_values, result,
        "transfer matrix",
    )  # fmt: skip
    least, parts = result.needed, result.parts
    if least:
        lines.append(
            f"signals needed: {'; or '.join(_part(part) for part in least)} (as much as "
            "from every signal)"
        )
    elif parts:
        every = f"from {', '.join(matrix.inputs)} to {', '.join(matrix.outputs)}"
        lines.append(f"signals needed: all of them, {every}: fewer determine less")
    if parts:
        width = max(len(_part(part)) for part in parts) + 1
        lines.append("what fewer signals determine:")
        lines += [f"  {_part(part) + ':':{width}} {_briefly(part.result)}" for part in parts]
    return "\n".join(lines)


def identifiability_json(theta: Theta, result: Identifiability) -> dict:
    """The `identifiability --json` record (its shape is a public contract)."""
    return {
        "ok": True,
        "model": theta.model,
        "input": theta.input,
        "output": theta.output,
        **_record(result),
    }


def matrix_json(matrix: TransferMatrix, result: Identifiability) -> dict:
    """The `identifiability --json` record with several inputs or outputs: the whole
    matrix's verdict, then `needed` (the smallest sets of signals that determine as much)
    and `parts` (what each smaller set determines)."""
    signals = lambda part: {"inputs": list(part.inputs), "outputs": list(part.outputs)}  # noqa: E731
    return {
        "ok": True,
        "model": matrix.equations.causal.bondgraph.name,
        "inputs": list(matrix.inputs),
        "outputs": list(matrix.outputs),
        **_record(result),
        "needed": [signals(part) for part in result.needed],
        "parts": [{**signals(part), **_record(part.result)} for part in result.parts],
    }


def _record(result: Identifiability) -> dict:
    return {
        "unknowns": list(result.unknowns),
        "verdict": result.verdict,
        "rank": result.rank,
        "solutions": result.solutions,
        "identified": list(result.identified),
        "combinations": [expression_text(c) for c in result.combinations],
        "maps": [{n: expression_text(v) for n, v in m.items()} for m in result.maps],
        "point": {n: _number(v) for n, v in result.point.items()} if result.point else None,
        "points": [{n: _number(v) for n, v in p.items()} for p in result.points],
        "real": result.real if result.points else None,
        "positive": result.positive if result.points else None,
    }
