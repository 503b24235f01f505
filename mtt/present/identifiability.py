"""`mtt identifiability`'s verdict as people read it and as tools read it (JSON)."""

from __future__ import annotations

from mtt.derivation.identifiability import Identifiability, expression_text, point_text
from mtt.derivation.theta import Theta

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
    names = ", ".join(result.unknowns)
    several = len(result.unknowns) > 1
    values = f"({names})" if several else names
    lines = [
        f"model {theta.model}: from {theta.input} to {theta.output}; "
        f"unknown{'s' * several} {names}",
        VERDICTS[result.verdict],
    ]
    if result.verdict == "global":
        lines[-1] += f": the transfer function determines {names}"
        return "\n".join(lines)
    if result.verdict == "local":
        lines[-1] += (
            f": for generic true values {values}, {result.solutions} values give the same "
            "transfer function:"
        )
        lines += [f"  {point_text(m)}" for m in result.maps]
        others = result.solutions - len(result.maps)
        if others:
            lines.append(f"  and {others} more, algebraic (not rational) in the true values")
        if result.points:
            model = all(theta.true_values.get(n) == v for n, v in result.point.items())
            lines.append(
                f"for {'the model' + chr(39) + 's' if model else 'random'} values {values} = "
                f"{point_text(result.point, _number)} they are ({result.real} real, "
                f"{result.positive} positive):"
            )
            lines += [f"  {point_text(p, _number)}" for p in result.points]
    else:
        lines[-1] += (
            f": for generic true values, a {len(result.unknowns) - result.rank}-parameter "
            f"family of values of {values} gives the same transfer function"
        )
    combinations = ", ".join(expression_text(c) for c in result.combinations)
    lines.append(f"the data determine: {combinations or 'nothing'}")
    lines.append(
        f"identified on {'their' if several else 'its'} own: "
        f"{', '.join(result.identified) or 'none'}"
    )
    return "\n".join(lines)


def identifiability_json(theta: Theta, result: Identifiability) -> dict:
    """The `identifiability --json` record (its shape is a public contract)."""
    return {
        "ok": True,
        "model": theta.model,
        "input": theta.input,
        "output": theta.output,
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
