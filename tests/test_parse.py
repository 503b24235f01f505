"""Stage 1, text -> ParsedModel: every construct of the grammar, with the values it must give."""

from __future__ import annotations

import time

import pytest
import sympy
from sympy import Rational, Symbol

from mtt.language.diagnostics import ModelError, Position, Source
from mtt.language.parse import MAX_DIGITS, parse, parse_expression

a, b, c, x, k = sympy.symbols("a b c x k")


def value_of(expression: str) -> sympy.Expr:
    """The exact value the parser gives `param p = EXPRESSION`."""
    parsed = parse(Source("test.bg", f"model m\nparam p = {expression}\n"))
    (parameter,) = parsed.parameters
    return parameter.value.value


def syntax_errors(text: str) -> list[tuple[int, int, str]]:
    """(line, column, message) of every error parsing `text` raises; all must be `syntax`."""
    with pytest.raises(ModelError) as caught:
        parse(Source("test.bg", text))
    assert {d.kind for d in caught.value.errors} == {"syntax"}
    return [(d.position.line, d.position.column, d.message) for d in caught.value.errors]


# expressions --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("-x^2", -(x**2)),
        ("-2^2", -4),
        ("(-2)^2", 4),
        ("2^3^2", 512),
        ("(2^3)^2", 64),
        ("2^-3", Rational(1, 8)),
        ("2^-3^2", Rational(1, 512)),
        ("2*-3", -6),
        ("--3", 3),
        ("2^3*2", 16),
        ("1+2*3", 7),
        ("(1+2)*3", 9),
        ("10-4-3", 3),
        ("a-b-c", a - b - c),
        ("8/4/2", 1),
        ("a/b/c", a / (b * c)),
        ("a/b*c", a * c / b),
        ("-a*b", -a * b),
    ],
)
def test_precedence_and_associativity(text, expected):
    assert value_of(text) == expected


def test_subtraction_and_division_group_to_the_left():
    # a-b-c is (a-b)-c, not a-(b-c); a/b/c is (a/b)/c, not a/(b/c)
    assert value_of("a-b-c") != a - (b - c)
    assert value_of("a/b/c") != a / (b / c)
    assert value_of("2^3^2") != (2**3) ** 2


@pytest.mark.parametrize(
    ("caret", "star"),
    [
        ("2^10", "2**10"),
        ("x^3", "x**3"),
        ("2^3^2", "2**3**2"),
        ("-x^2", "-x**2"),
        ("a^-b", "a**-b"),
    ],
)
def test_double_star_is_the_power_operator(caret, star):
    assert value_of(caret) == value_of(star)
    assert value_of("2**3^2") == 512


@pytest.mark.parametrize(
    ("literal", "exact"),
    [
        ("2", Rational(2)),
        ("0.1", Rational(1, 10)),
        (".5", Rational(1, 2)),
        ("5.", Rational(5)),
        ("1e-3", Rational(1, 1000)),
        ("1.5E+2", Rational(150)),
        ("1E3", Rational(1000)),
        ("2.50e-1", Rational(1, 4)),
        ("0.333", Rational(333, 1000)),
        ("007", Rational(7)),
    ],
)
def test_decimal_literals_are_exact_rationals(literal, exact):
    value = value_of(literal)
    assert isinstance(value, sympy.Rational)
    assert value == exact
    assert not value.atoms(sympy.Float)


def test_exact_arithmetic_never_rounds():
    assert value_of("0.1 + 0.2") == Rational(3, 10)
    assert value_of("0.1*3") == Rational(3, 10)
    assert value_of("1/3") == Rational(1, 3)
    assert value_of("1/3 + 1/6") == Rational(1, 2)
    assert value_of("2 * 0.1 * x") == Rational(1, 5) * x


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("sqrt(4)", 2),
        ("sqrt(2)", sympy.sqrt(2)),
        ("sqrt(x)", sympy.sqrt(x)),
        ("exp(0)", 1),
        ("exp(x)", sympy.exp(x)),
        ("log(1)", 0),
        ("log(exp(3))", 3),
        ("log(x)", sympy.log(x)),
        ("sin(pi)", 0),
        ("sin(pi/2)", 1),
        ("cos(pi)", -1),
        ("cos(0)", 1),
        ("pi", sympy.pi),
        ("2*pi*x", 2 * sympy.pi * x),
        ("sqrt(2)^2", 2),
        ("-sqrt(4)^2", -4),
    ],
)
def test_functions_and_pi(text, expected):
    assert value_of(text) == expected


def test_pi_is_a_constant_not_a_parameter_name():
    parsed = parse(Source("test.bg", "model m\nparam p = 2*pi*f\n"))
    assert [use.name for use in parsed.parameters[0].value.names] == ["f"]


def test_names_in_an_expression_are_recorded_with_their_places():
    parsed = parse(Source("test.bg", "model m\nparam p = b*c + sqrt(b)\n"))
    uses = [(u.name, u.position) for u in parsed.parameters[0].value.names]
    assert uses == [("b", Position(2, 11)), ("c", Position(2, 13)), ("b", Position(2, 22))]


def test_lone_expression_for_filters():
    s = Symbol("s")
    assert parse_expression("s^2 + 2*s + 1") == s**2 + 2 * s + 1
    assert parse_expression("(s + 0.5)^2") == (s + Rational(1, 2)) ** 2
    with pytest.raises(ModelError) as caught:
        parse_expression("s + w")
    assert [(d.kind, d.position) for d in caught.value.errors] == [
        ("undeclared_parameter", Position(1, 5))
    ]


# statements and layout ----------------------------------------------------------

RLC = """\
model rlc "series RLC circuit"
param r = 2 "resistance [ohm]"
param l = 0.5 "inductance [H]"
unknown c = 0.1 "capacitance [F]"
Se:v -> 1:loop
1:loop -> R:r
1:loop -> I:l
1:loop -> C:c
1:loop -> Df:i
"""


def test_statements_give_header_parameters_and_bonds():
    parsed = parse(Source("rlc.bg", RLC))
    assert (parsed.header.name, parsed.header.description) == ("rlc", "series RLC circuit")
    assert [(p.name, p.value.value, p.unknown) for p in parsed.parameters] == [
        ("r", 2, False),
        ("l", Rational(1, 2), False),
        ("c", Rational(1, 10), True),
    ]
    assert [p.description for p in parsed.parameters] == [
        "resistance [ohm]",
        "inductance [H]",
        "capacitance [F]",
    ]
    assert [(bd.tail.label, bd.head.label) for bd in parsed.bonds] == [
        ("Se:v", "1:loop"),
        ("1:loop", "R:r"),
        ("1:loop", "I:l"),
        ("1:loop", "C:c"),
        ("1:loop", "Df:i"),
    ]
    assert parsed.declarations == ()
    assert parsed.ports == ()


def test_comments_blank_lines_and_hash_inside_a_description():
    text = (
        "# a comment before everything\n"
        "\n"
        'model m "first # not a comment"  # a comment\n'
        "   \t  \n"
        "   # an indented comment\n"
        'param f = 50 "mains # Europe" # trailing comment with "quotes"\n'
        'R:r "a # in a component description"\n'
        "Se:v -> 1:j  # comment after a bond\n"
        "\n\n"
    )
    parsed = parse(Source("test.bg", text))
    assert parsed.header.description == "first # not a comment"
    assert parsed.parameters[0].description == "mains # Europe"
    assert parsed.parameters[0].value.value == 50
    assert parsed.declarations[0].description == "a # in a component description"
    assert parsed.header.position == Position(3, 7)
    assert [(bd.tail.label, bd.head.label) for bd in parsed.bonds] == [("Se:v", "1:j")]


def test_crlf_line_endings_parse_like_lf():
    crlf = parse(Source("test.bg", RLC.replace("\n", "\r\n")))
    lf = parse(Source("test.bg", RLC))
    assert crlf.header == lf.header
    assert crlf.parameters == lf.parameters
    assert crlf.bonds == lf.bonds
    assert crlf.parameters[2].description == "capacitance [F]"


def test_crlf_errors_are_placed_and_shown_without_carriage_returns():
    with pytest.raises(ModelError) as caught:
        parse(Source("test.bg", "model m\r\nparam a = )\r\nSe:v -> 1:j\r\n"))
    (problem,) = caught.value.errors
    assert (problem.kind, problem.position) == ("syntax", Position(2, 11))
    assert caught.value.render().splitlines()[1] == " 2 | param a = )"


def test_spaces_are_optional_around_arrows_equals_and_before_arguments():
    text = "model m\nparam a=2\nparam b =3\nSe:v->1:j ->R:a (a*b)\n1:j->  Df:d\n"
    parsed = parse(Source("test.bg", text))
    assert [(p.name, p.value.value) for p in parsed.parameters] == [("a", 2), ("b", 3)]
    assert [(bd.tail.label, bd.head.label) for bd in parsed.bonds] == [
        ("Se:v", "1:j"),
        ("1:j", "R:a"),
        ("1:j", "Df:d"),
    ]
    assert parsed.bonds[1].head.argument.value == a * b


def test_statements_may_come_in_any_order_after_the_model_line(models):
    text = (
        "model m\n"
        "input Se:v\n"  # names a source mentioned further down
        "1:j -> R:r(g)\n"  # uses g before its declaration
        "Se:v -> 1:j\n"
        "1:j -> Df:i\n"
        "param g = 2*h\n"  # uses h before its declaration
        "param h = 3\n"
    )
    graph = models.build(text)
    assert graph.input == "v"
    assert graph.component("r").argument.value == Symbol("g")
    assert graph.parameters["g"].value.value == 2 * Symbol("h")


def test_a_chain_is_one_bond_per_arrow_numbered_in_file_order(models):
    text = (
        "model m\nparam k = 1\nparam n = 2\nSe:v -> 1:a -> TF:n -> 0:b\n0:b -> C:k\n0:b -> De:y\n"
    )
    parsed = models.parse(text)
    assert [(bd.tail.label, bd.head.label) for bd in parsed.bonds] == [
        ("Se:v", "1:a"),
        ("1:a", "TF:n"),
        ("TF:n", "0:b"),
        ("0:b", "C:k"),
        ("0:b", "De:y"),
    ]
    # each bond is placed at its arrow
    assert [bd.position for bd in parsed.bonds] == [
        Position(4, 6),
        Position(4, 13),
        Position(4, 21),
        Position(5, 5),
        Position(6, 5),
    ]
    graph = models.build(text)
    assert [(bd.number, bd.tail, bd.head) for bd in graph.bonds] == [
        (1, "v", "a"),
        (2, "a", "n"),
        (3, "n", "b"),
        (4, "b", "k"),
        (5, "b", "y"),
    ]
    # a two-port's ports: the inward bond first
    assert [(p.bond, p.inward) for p in graph.ports("n")] == [(2, True), (3, False)]
    assert [(p.bond, p.inward) for p in graph.ports("b")] == [(3, True), (4, False), (5, False)]


def test_inline_declarations_with_arguments_in_a_chain(models):
    text = (
        "model m\nunknown k = 10\nparam ks = 4\n"
        "Se:v -> 1:l -> I:jl(k) \n"
        "1:l -> C:cs(1/ks)\n"
        "1:l -> R:rl(2*k + 0.5)\n"
        "1:l -> Df:w\n"
    )
    graph = models.build(text)
    assert graph.component("jl").argument.value == k
    assert graph.component("cs").argument.value == 1 / Symbol("ks")
    assert graph.component("rl").argument.value == 2 * k + Rational(1, 2)
    assert graph.component("jl").argument.position == Position(4, 21)
    assert graph.unknowns == ("k",)


def test_an_omitted_argument_means_the_parameter_of_the_same_name(models):
    graph = models.build("model m\nparam ra = 1\nSe:v -> 1:a -> R:ra\n1:a -> Df:i\n")
    argument = graph.component("ra").argument
    assert argument.value == Symbol("ra")
    assert [(u.name, u.position) for u in argument.names] == [("ra", Position(3, 16))]
    # junctions, sources and detectors get no implied argument
    assert graph.component("a").argument is None
    assert graph.component("v").argument is None
    assert graph.component("i").argument is None


def test_an_argument_may_be_given_at_any_one_mention(models):
    text = 'model m\nR:r "declared here"\nSe:v -> 1:a -> R:r(5)\n1:a -> Df:i\n'
    graph = models.build(text)
    assert graph.component("r").argument.value == 5
    assert graph.component("r").description == "declared here"
    assert graph.component("r").position == Position(2, 1)  # the first mention


def test_parameter_values_may_reference_other_parameters(models):
    text = (
        "model m\nparam ks = 4\nparam cs = 1/ks\nparam r = 2*cs + ks\n"
        "Se:v -> 1:a -> C:cs\n1:a -> R:r\n1:a -> Df:i\n"
    )
    graph = models.build(text)
    ks = Symbol("ks")
    assert graph.parameters["cs"].value.value == 1 / ks
    # values are kept as written, in terms of the other parameters
    assert graph.parameters["r"].value.value == 2 * Symbol("cs") + ks
    assert [u.name for u in graph.parameters["r"].value.names] == ["cs", "ks"]


def test_a_parameter_without_a_value_stays_symbolic(models):
    text = (
        'model m\nparam g "no value"\nunknown k\nparam r = g*k\nSe:v -> 1:a -> R:r\n1:a -> Df:i\n'
    )
    graph = models.build(text)
    assert graph.parameters["g"].value is None
    assert graph.parameters["g"].description == "no value"
    assert graph.parameters["k"].value is None
    assert graph.parameters["k"].declared_unknown
    assert graph.parameters["r"].value.value == Symbol("g") * k
    assert list(graph.parameters) == ["g", "k", "r"]  # file order


def test_descriptions_everywhere_they_are_allowed(models):
    text = (
        'model m "the model"\n'
        'param r = 1 "a known one"\n'
        'unknown c = 2 "the unknown"\n'
        'R:r "a resistor"\n'
        'Se:v "the drive"\n'
        "Se:v -> 1:a -> R:r\n1:a -> C:c\n1:a -> Df:i\n"
    )
    graph = models.build(text)
    assert graph.description == "the model"
    assert graph.parameters["r"].description == "a known one"
    assert graph.parameters["c"].description == "the unknown"
    assert graph.component("r").description == "a resistor"
    assert graph.component("v").description == "the drive"
    assert graph.component("c").description is None


def test_statement_words_are_not_reserved_as_parameter_names(models):
    text = "model m\nparam model = 2\nparam input = model + 1\nSe:v -> R:r(input)\n"
    parsed = models.parse(text)
    assert [(p.name, p.value.value) for p in parsed.parameters] == [
        ("model", 2),
        ("input", Symbol("model") + 1),
    ]


def test_input_and_output_statements(models):
    text = (
        "model m\nparam r = 1\n"
        "Se:v -> 1:a -> R:r\nSf:w -> 1:a\n1:a -> Df:i\n1:a -> De:e\n"
        "input Sf:w\noutput De:e\n"
    )
    parsed = models.parse(text)
    assert [(p.role, p.type, p.name, p.position) for p in parsed.ports] == [
        ("input", "Sf", "w", Position(7, 7)),
        ("output", "De", "e", Position(8, 8)),
    ]
    graph = models.build(text)
    assert (graph.input, graph.output) == ("w", "e")


# syntax errors ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("line", "column"),
    [
        ("param p = 1 +", 14),  # missing operand
        ("param p = (1", 13),  # unclosed parenthesis
        ("param p = 2 3", 13),  # two operands
        ("param p = 2(3)", 12),  # no implicit multiplication
        ("param 9p = 1", 7),  # a name cannot start with a digit
        ('param p = 1 "one" "two"', 19),  # one description
        ('param p = "text"', 11),  # a string is not a value
        ("param p = 1,5", 12),  # no comma decimals
        ("Se:v -> 1 : j", 9),  # no spaces inside TYPE:NAME
        ("Se:v <- 1:j", 6),  # no left arrow
        ("Se:v -> 1:j ->", 15),  # a dangling arrow
        ('Se:v -> 1:j "bonds have no description"', 13),
        ("input Se:v Sf:w", 12),
        ("param p = tangent(1)", 11),  # unknown function
        ("param p = 1/0", 13),  # division by zero
        ("param p = log(0)", 11),  # undefined value
        ("param p = 0^-1", 12),
    ],
)
def test_syntax_errors_are_placed(line, column):
    (problem,) = syntax_errors(f"model m\n{line}\n")
    assert problem[:2] == (2, column)


def test_every_syntax_error_is_reported_not_only_the_first():
    text = "model m\nparam a = 1 +\nparam b = 2\nparam c = )\nSe:v -> -> R:x\nparam d = 3\n"
    assert [where[:2] for where in syntax_errors(text)] == [(2, 14), (4, 11), (5, 9)]


def test_missing_model_line_is_a_syntax_error_at_the_first_statement():
    (problem,) = syntax_errors("# only a comment\n\nparam r = 2\nSe:v -> R:r\n")
    assert problem[:2] == (3, 7)
    assert "model" in problem[2]


def test_repeated_or_late_model_line_is_a_syntax_error():
    (problem,) = syntax_errors("model m\nparam r = 2\nmodel n\n")
    assert problem[:2] == (3, 7)
    assert "second" in problem[2]
    (problem,) = syntax_errors("param r = 2\nmodel m\n")
    assert problem[:2] == (2, 7)
    assert "first" in problem[2]


def test_syntax_error_messages_name_what_was_expected():
    ((_, _, message),) = syntax_errors("model m\nparam p = 2 3\n")
    assert message.startswith("unexpected '3'; expected ")
    assert "'^'" in message and "end of line" in message
    assert "(?:" not in message  # no raw regular expressions
    ((_, _, message),) = syntax_errors("model m\nbogus\n")
    assert "a statement is model, param, unknown, input, output" in message


# untrusted input ----------------------------------------------------------------


@pytest.mark.parametrize(
    "template",
    [
        "model m\nparam p = {code}\nSe:v -> 1:j -> R:r(p)\n1:j -> Df:i\n",
        "model m\nSe:v -> 1:j -> R:r({code})\n1:j -> Df:i\n",
        "model m\nR:r({code})\nSe:v -> 1:j -> R:r\n1:j -> Df:i\n",
    ],
)
@pytest.mark.parametrize(
    "code",
    [
        "__import__('os').system('touch {marker}')",
        '__import__("os").system("touch {marker}")',
        'eval(\'__import__("os").system("touch {marker}")\')',
        "exec(open)",
        "eval(1)",
        "__import__(os)",
        "().__class__",
        "lambda: 1",
        "x if 1 else 2",
        "[1]",
        "x.y",
    ],
)
def test_program_text_in_an_expression_is_rejected_and_never_run(tmp_path, models, template, code):
    marker = tmp_path / "pwned_x"
    text = template.format(code=code.replace("{marker}", str(marker)))
    problem = models.failure(text)
    assert problem.kinds() and set(problem.kinds()) == {"syntax"}
    assert all(d.position is not None and d.position.line == 2 for d in problem.errors)
    assert not marker.exists()


def test_names_that_look_like_python_are_plain_parameter_names(models):
    # `__import__` without a call is just an (undeclared) parameter name
    problem = models.failure("model m\nSe:v -> 1:j -> R:r(__import__)\n1:j -> Df:i\n")
    assert problem.kinds() == ["undeclared_parameter"]


@pytest.mark.parametrize(
    ("expression", "column"),
    [
        ("1e999999999", 11),
        ("1e-999999999", 11),
        ("1e" + "9" * 5000, 11),
        ("9" * (MAX_DIGITS + 1), 11),
        ("0." + "0" * MAX_DIGITS + "1", 11),
        ("10^10^10", 13),
        ("2^2^2^2^2^2", 14),  # 2^65536, the second operator
        ("(10^3000)*(10^3000)", 12),  # the product, placed at its first operand
        ("10^3000 * 10^3000 / 3", 11),
        ("x^100000", 12),
        ("x^(10^3000)", 12),
        ("pi^100000", 13),
        ("(10^2000)^(10^2000)", 20),
        ("(10^3999 + 1)^(1/2)", 24),  # a root of a huge number: sympy would search factors
        ("sqrt(10^200 + 1)", 11),
        ("log(10^500)", 11),
    ],
)
def test_huge_numbers_are_rejected_quickly(expression, column):
    start = time.process_time()
    (problem,) = syntax_errors(f"model m\nparam p = {expression}\n")
    assert time.process_time() - start < 1.0
    assert problem[:2] == (2, column)
    assert "range" in problem[2] or "digits" in problem[2]


def test_large_but_allowed_numbers_are_exact_and_printable():
    assert value_of("10^3999") == 10**3999
    assert value_of("9.999e3999") == 9999 * 10**3996
    assert value_of("2.5e-3998") == Rational(25, 10**3999)
    assert len(str(value_of("9" * MAX_DIGITS))) == MAX_DIGITS
    assert value_of("1e0000000000000000003") == 1000  # leading zeros in the exponent


@pytest.mark.parametrize("text", ["1e4000", "1e-4000", "10^4000", "-(10^4000)"])
def test_a_number_of_more_than_four_thousand_digits_is_refused(text):
    # 1e4000 has 4001 digits (it was accepted, though documented as too many)
    with pytest.raises(ModelError, match="number out of range"):
        value_of(text)


# signals (modulated sources) -------------------------------------------------------


def test_signal_terms_are_symbols_of_their_own_with_places(models):
    parsed = models.parse("model m\nparam l\nunknown k\nMSf:gas_in(l/k * e(x2) - 2*f(pipe))\n")
    argument = parsed.declarations[0].use.argument
    l_, k_ = sympy.symbols("l k")
    assert argument.value == l_ / k_ * Symbol("e(x2)") - 2 * Symbol("f(pipe)")
    assert [(u.kind, u.target, u.position) for u in argument.signals] == [
        ("e", "x2", Position(4, 18)),
        ("f", "pipe", Position(4, 28)),
    ]
    assert [u.name for u in argument.names] == ["l", "k"]  # the signals' components are not
    assert argument.signal_problem is None


def test_a_signal_may_name_a_subsystems_component_with_a_dotted_name(models):
    argument = models.parse("model m\nMSe:x(2*e(motor.shaft))\n").declarations[0].use.argument
    assert [(u.text, u.position) for u in argument.signals] == [("e(motor.shaft)", Position(2, 9))]
    assert argument.value == 2 * Symbol("e(motor.shaft)")


@pytest.mark.parametrize(
    ("text", "message", "column"),
    [
        ("e(x) + 1", "a constant term", 8),
        ("2 - f(x)*k", "a constant term", 1),
        ("e(x)*f(y)", "a product of signals", 6),
        ("k*sqrt(e(x))", "a signal inside a function", 8),
        ("e(x)^2", "a signal in a power", 1),
        ("2^e(x)", "a signal in a power", 3),
        ("k/(1 + e(x))", "a signal in a denominator", 8),
        ("e(2*x)", "its argument is a component's name", 3),
    ],
)
def test_where_an_argument_stops_being_linear_in_its_signals(models, text, message, column):
    problem = models.parse(f"model m\nMSf:z({text})\n").declarations[0].use.argument.signal_problem
    assert message in problem.message and problem.position == Position(2, 6 + column)


def test_linear_combinations_of_signals_with_parameter_coefficients(models):
    for text in ("e(x)", "-f(y)", "(k + 1)*e(x)/k - f(y)*2^k", "e(x) + 0", "e(x)*(2 - 2)"):
        argument = models.parse(f"model m\nMSf:z({text})\n").declarations[0].use.argument
        assert argument.signal_problem is None, text


def test_e_and_f_are_still_parameter_names(models):
    graph = models.build(
        "model m\nparam e = 2\nparam f = 3\nSe:v -> 1:j\n1:j -> R:r(e*f)\n1:j -> Df:i\n"
    )
    assert graph.component("r").argument.value == Symbol("e") * Symbol("f")


def test_only_signals_take_dotted_names(models):
    assert syntax_errors("model m\nparam p = sqrt(a.b)\n") == [
        (2, 16, "a.b: a dotted name only names a signal, in e(...) or f(...)")
    ]
