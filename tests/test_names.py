"""Names that round-trip (issue 23 item 3): every expression mtt prints in JSON reads back
with sympy (`sympify`) as the same expression, for every model shipped and tested; the
`names` table gives each written symbol's name in the model."""

from __future__ import annotations

from pathlib import Path

import sympy

from mtt.derivation.pipeline import equations_for, load
from mtt.derivation.theta import theta_matrix
from mtt.derivation.transfer import transfer_function
from mtt.language.diagnostics import MttError
from mtt.present.report import derived_json, expression_names, ss_json

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted(
    p
    for folder in (ROOT / "models", ROOT / "tests" / "data")
    for p in folder.rglob("*.bg")
    if "errors" not in p.parts
)


def _derived(path: Path):
    try:
        equations = equations_for(load(path))
        return equations, theta_matrix(transfer_function(equations))
    except MttError:
        return None


def _reads_back(text: str, expression: sympy.Expr, names: dict[str, str]) -> None:
    read = sympy.sympify(text)  # our own output, not a model's text
    back = {sympy.Symbol(alias): sympy.Symbol(name) for alias, name in names.items()}
    assert read.xreplace(back) == expression, (text, expression)


def test_every_expression_printed_in_json_reads_back():
    derived = 0
    for path in MODELS:
        found = _derived(path)
        if found is None:
            continue
        derived += 1
        equations, theta = found
        record = derived_json(theta, order=0)
        names = record["names"]
        _reads_back(record["num"], theta.num, names)
        _reads_back(record["den"], theta.den, names)
        for texts, row in zip(record["theta"], theta.matrix.tolist(), strict=True):
            for text, entry in zip(texts, row, strict=True):
                _reads_back(text, entry, names)
        symbols = set().union(*(sympy.sympify(record[k]).free_symbols for k in ("num", "den")))
        assert {x.name for x in symbols} - {"s"} == set(names), path
        state = ss_json(equations)
        for name, matrix in equations.matrices().items():
            for texts, row in zip(state[name], matrix.tolist(), strict=True):
                for text, entry in zip(texts, row, strict=True):
                    _reads_back(text, entry, state["names"])
        pairs = zip(state["relations"], equations.relations, strict=True)
        for (written, text), (name, relation) in pairs:
            _reads_back(text, relation, state["names"])
            assert state["names"].get(written, written) == name
    assert derived >= 20  # the models that derive (others are there for their errors)


def test_a_subsystems_names_are_written_with_double_underscores():
    equations, theta = _derived(ROOT / "tests" / "data" / "subsystems" / "drive.bg")
    record = derived_json(theta, order=0)
    assert record["names"] == {"jl": "jl", "motor__jm": "motor.jm"}
    assert "motor__jm*s**2" in record["den"] and "motor." not in record["den"]
    assert record["unknowns"] == ["jl", "motor.jm"]  # the model's names, as before


def test_names_sympy_would_misread_get_an_underscore():
    written = expression_names(["gamma", "E", "lambda", "motor.jm", "motor__jm", "k", "I"])
    assert written == {
        "gamma": "gamma_",
        "E": "E_",
        "lambda": "lambda_",
        "motor.jm": "motor__jm_",  # motor__jm is taken
        "motor__jm": "motor__jm",
        "k": "k",
        "I": "I_",
    }
    for alias in written.values():
        assert sympy.sympify(alias) == sympy.Symbol(alias)
