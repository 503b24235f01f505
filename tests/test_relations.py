"""Language version 3 (issue 19 items 1 and 2): constitutive relations in a component's own
variables, their exact inverses, the causality a one-way relation fixes, nonlinear
modulated sources and two-ports; every new error at its exact place."""

from __future__ import annotations

import pytest
import sympy

from mtt.derivation.causality import assign
from mtt.derivation.pipeline import equations_for, load
from mtt.language.bondgraph import build
from mtt.language.diagnostics import ModelError, Source
from mtt.language.parse import parse
from mtt.language.relations import Constitutive, inverse

S = sympy.Symbol


def _graph(text: str):
    return build(parse(Source("m.bg", text)))


def _errors(text: str) -> list[tuple[str, int, int]]:
    with pytest.raises(ModelError) as caught:
        graph = _graph(text)
        assign(graph)
    return [(d.kind, d.position.line, d.position.column) for d in caught.value.errors]


def _relation(text: str, type_: str = "R"):
    """The constitutive relation of the component `X` in `TYPE:X(text)`."""
    component = _graph(f"model m\nparam a = 2\nparam b = 3\nSf:u -> 0:j\n0:j -> {type_}:x({text})\n"
                       "0:j -> De:y\n").component("x")  # fmt: skip
    return component.relation


def _value(relation) -> sympy.Expr:
    """A relation's right-hand side with own variables as the symbols e, f, q, p."""
    value = relation.expression.value
    return value.xreplace({s: S(s.name[0]) for s in value.free_symbols if "(" in s.name})


@pytest.mark.parametrize(
    ("written", "gives", "inverse_"),
    [
        ("f = a*sqrt(e)", "e", "f**2/a**2"),
        ("e = a*f + b*f + 1", "f", "(e - 1)/(a + b)"),
        ("f = exp(e/a) - 1", "e", "a*log(f + 1)"),
        ("f = b*tanh(e)", "e", "atanh(f/b)"),
        ("e = sin(f)/a", "f", "asin(a*e)"),
        ("f = sat(e/a)", "e", "a*f/sqrt(1 - f**2)"),
        ("e = f^3", "f", "e**(1/3)"),
        ("e = -1/f", "f", "-1/e"),
    ],
)
def test_an_inverse_is_derived_exactly(written, gives, inverse_):
    relation = _relation(written)
    derived = relation.giving(gives)
    assert derived.derived and derived.variable == gives
    want = sympy.sympify(inverse_, locals={"e": S("e"), "f": S("f"), "a": S("a"), "b": S("b")})
    assert sympy.simplify(_value(derived) - want) == 0


@pytest.mark.parametrize(
    "written",
    ["e = a*tanh(f/b) + b*f", "f = abs(e)", "f = sign(e)*a", "f = max(e, 0)", "e = a^f",
     "f = e + e^2"],
)  # fmt: skip
def test_these_have_no_exact_inverse(written):
    relation = _relation(written)
    other = "e" if written.startswith("f") else "f"
    assert relation.giving(other) is None and len(relation.serves()) == 1


def test_the_domain_of_an_inverse_is_said():
    derived = _relation("f = a*sqrt(e)").giving("e")
    assert derived.domain == ("f/a >= 0",)
    assert [str(c) for c in derived.conditions] == ["f(x)/a"]
    assert inverse(_relation("f = a*sqrt(e)").given[0], "e") == derived


def test_a_relation_linear_through_the_origin_is_the_linear_component():
    for text, type_, value in [
        ("f = e/a", "R", "a"),
        ("e = a*f", "R", "a"),
        ("e = q/a", "C", "a"),
        ("q = a*b*e", "C", "a*b"),
        ("f = p/a", "I", "a"),
    ]:
        component = _graph(
            f"model m\nparam a = 2\nparam b = 3\nSf:u -> 0:j\n0:j -> {type_}:x({text})\n"
            "0:j -> De:y\n"
        ).component("x")
        assert isinstance(component.relation, Constitutive) and not component.nonlinear_relation
        assert sympy.simplify(component.argument.value - sympy.sympify(value)) == 0


def test_a_linear_relation_keeps_the_transfer_function():
    old = "model m\nparam r = 2\nunknown c = 1\nSe:v -> 1:a -> R:r\n1:a -> C:c\n1:a -> Df:i\n"
    new = old.replace("R:r", "R:r(f = e/r)").replace("C:c", "C:c(e = q/c)")
    assert equations_for(_graph(old)).matrices() == equations_for(_graph(new)).matrices()


def test_a_one_way_relation_fixes_the_causality_it_serves():
    # on a 1-junction with a flow source the friction receives f: it serves that way
    text = "model m\nunknown fc = 1\nSf:u -> 1:j\n1:j -> R:fr(e = fc*tanh(f) + f)\n1:j -> Df:y\n"
    causal = assign(_graph(text))
    assert causal.imposes_effort("fr", 2)
    # an orifice's sqrt inverts: either causality
    text = "model m\nunknown a = 1\nSf:u -> 1:j\n1:j -> R:o(f = a*sqrt(e))\n1:j -> Df:y\n"
    assert assign(_graph(text)).imposes_effort("o", 2)


def test_a_missing_inverse_is_its_own_error_at_the_relation():
    text = "model m\nparam fc = 1\nSf:u -> 1:j\n1:j -> R:fr(f = fc*tanh(e) + e)\n1:j -> Df:y\n"
    assert _errors(text) == [("no_inverse", 4, 13)]
    # with the inverse given after a comma, the same model is valid
    fixed = text.replace("(f = fc*tanh(e) + e)", "(f = fc*tanh(e) + e, e = f/2)")
    assert assign(_graph(fixed)).imposes_effort("fr", 2)
    # a storage element that only the flow source and the sensor surround must be in
    # integral causality, which needs e from q: q = e + e^3 has no exact inverse
    storage = "model m\nSf:s -> 0:n\n0:n -> C:c(q = e + e^3)\n0:n -> De:y\n"
    assert _errors(storage) == [("no_inverse", 3, 12)]


@pytest.mark.parametrize(
    ("line", "kind", "column"),
    [
        ("0:j -> C:t(e = f/a)", "bad_relation", 16),  # a variable the type does not relate
        ("0:j -> I:m(e = p)", "bad_relation", 12),  # a variable it does not give
        ("0:j -> R:o(f = a*sqrt(e) + f)", "bad_relation", 28),  # on both sides
        ("0:j -> R:z(f = e(j))", "bad_relation", 16),  # another component's signal
        ("0:j -> R:w(f = e, f = 2*e)", "bad_relation", 19),  # the same variable twice
        ("0:j -> TF:x(e = 2) -> 1:k", "bad_relation", 13),  # a type with no relation
        ("0:j -> R:fn(f = foo(e))", "syntax", 17),  # a function outside the list
        ("0:j -> R:mx(f = max(e))", "syntax", 17),  # max takes two or more
        ("0:j -> R:neg(f = sqrt(-2)*e)", "bad_value", 18),  # sqrt of a negative constant
        ("0:j -> R:un(f = b*e)", "undeclared_parameter", 17),
        ("0:j -> R:r(f = e(j)*2)", "bad_relation", 16),
    ],
)
def test_bad_nonlinear_text_is_a_located_error(line, kind, column):
    text = f"model m\nparam a = 2\nSf:u -> 0:j\n{line}\n0:j -> De:y\n"
    if "1:k" in line:
        text += "1:k -> De:z\noutput De:y\n"
    with pytest.raises(ModelError) as caught:
        build(parse(Source("m.bg", text)))
    found = [(d.kind, d.position.line, d.position.column) for d in caught.value.errors]
    assert found[0] == (kind, 4, column), found


def test_a_negative_value_under_a_root_is_located_once_values_are_in():
    text = "model m\nparam a = -2\nSf:u -> 0:j\n0:j -> R:o(f = sqrt(a)*sqrt(e) + e)\n0:j -> De:y\n"
    with pytest.raises(ModelError) as caught:
        build(parse(Source("m.bg", text)))
    (problem,) = caught.value.errors
    assert (problem.kind, problem.position.line, problem.position.column) == ("bad_value", 4, 16)


def test_nonlinear_modulations_and_integrals_are_accepted():
    text = """model m
param m = 2
Se:v -> 1:joint
1:joint -> I:arm(f = p/m)
1:joint -> MSe:gravity(m*sin(q(joint)) + max(f(joint), 0)^2)
0:n -> TF:lever(2*cos(q(joint))) -> 1:b
MSf:drive(e(arm)*f(arm)) -> 0:n
1:b -> R:r(f = e)
1:joint -> Df:y
0:n -> C:c(e = q)
"""
    graph = _graph(text)
    assign(graph)
    assert graph.component("gravity").argument.signals[0].kind == "q"
    # q(X) and p(X) read what f(X) and e(X) read: not a 0-junction's flow
    with pytest.raises(ModelError) as caught:
        _graph(text.replace("sin(q(joint))", "sin(q(n))"))
    (problem,) = caught.value.errors
    assert (problem.kind, problem.position.line) == ("bad_signal", 5)


def test_version_2_models_read_as_before():
    for name in ("rlc", "dc_drive", "absorber"):
        graph = load(f"models/{name}.bg")
        assert all(c.relation is None for c in graph.components)
