"""Stage 2, ParsedModel -> BondGraph: validation errors (kind and place), warnings, rendering."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import sympy
from sympy import Rational, Symbol

from mtt.derivation.pipeline import load, read_source
from mtt.language.bondgraph import Selection, build
from mtt.language.diagnostics import ModelError, Position, Severity, Source
from mtt.language.parse import parse

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
MODELS = sorted((ROOT / "models").glob("*.bg"))
ERROR_FILES = sorted((DATA / "errors").glob("*.bg"))
VALID_FILES = sorted((DATA / "valid").glob("*.bg"))
EXPECT = re.compile(r"^# expect(-warning)?: (\w+)(?: (\d+):(\d+))?$", re.MULTILINE)

# every kind `mtt check` can report (the other three come from deriving a transfer function)
CHECKED_KINDS = {
    "syntax",
    "empty_model",
    "unknown_component_type",
    "undeclared_parameter",
    "undeclared_component",
    "duplicate_name",
    "duplicate_argument",
    "bad_argument",
    "bad_arity",
    "bad_two_port",
    "self_bond",
    "unconnected_component",
    "no_input",
    "no_output",
    "cyclic_definition",
}


def expectations(path: Path, warnings: bool = False) -> list[tuple[str, int | None, int | None]]:
    """The `# expect: KIND [LINE:COL]` (or `# expect-warning:`) comments of a data file."""
    found = []
    for match in EXPECT.finditer(path.read_text(encoding="utf-8")):
        if bool(match[1]) == warnings:
            line, column = (int(match[3]), int(match[4])) if match[3] else (None, None)
            found.append((match[2], line, column))
    return found


def places(diagnostics) -> list[tuple[str, int | None, int | None]]:
    return [
        (d.kind, d.position.line if d.position else None, d.position.column if d.position else None)
        for d in diagnostics
    ]


def failure(path: Path) -> ModelError:
    with pytest.raises(ModelError) as caught:
        load(path)
    return caught.value


# errors, one data file per kind ----------------------------------------------------


@pytest.mark.parametrize("path", ERROR_FILES, ids=lambda p: p.stem)
def test_error_file_reports_exactly_the_expected_errors(path):
    expected = expectations(path)
    assert expected, f"{path.name} has no '# expect:' line"
    problem = failure(path)
    assert sorted(places(problem.errors), key=str) == sorted(expected, key=str)
    # reported in file order, the errors without a place first
    order = [d.position or Position(0, 0) for d in problem.errors]
    assert order == sorted(order)
    assert problem.warnings == ()


def test_every_checked_error_kind_has_a_data_file():
    covered = {kind for path in ERROR_FILES for kind, _, _ in expectations(path)}
    assert covered >= CHECKED_KINDS
    # each kind has a file of its own, where it is the only kind reported
    alone = {
        kinds.pop()
        for path in ERROR_FILES
        if len(kinds := {kind for kind, _, _ in expectations(path)}) == 1
    }
    assert alone >= CHECKED_KINDS


@pytest.mark.parametrize(
    ("name", "kind", "where"),
    [
        ("no_input_none", "no_input", None),
        ("no_input_several", "no_input", None),
        ("no_input_not_source", "no_input", Position(6, 7)),
        ("no_output_none", "no_output", None),
        ("no_output_several", "no_output", None),
        ("no_output_not_detector", "no_output", Position(6, 8)),
        ("syntax_missing_model", "syntax", Position(4, 7)),
        ("syntax_repeated_model", "syntax", Position(4, 7)),
        ("syntax_late_model", "syntax", Position(3, 7)),
        ("empty_model", "empty_model", None),
        ("empty_model_no_bond", "empty_model", None),
    ],
)
def test_each_way_of_getting_an_error_kind(name, kind, where):
    (error,) = failure(DATA / "errors" / f"{name}.bg").errors
    assert (error.kind, error.position, error.severity) == (kind, where, Severity.ERROR)


def test_error_messages_say_what_is_wrong():
    messages = {d.kind: d.message for d in failure(DATA / "errors" / "several_kinds.bg").errors}
    assert messages["duplicate_name"] == "parameter 'r' is already declared on line 12"
    assert messages["undeclared_parameter"] == "parameter 'q' is not declared"
    assert messages["unknown_component_type"].startswith("unknown component type 'Q'")
    assert messages["self_bond"] == "a bond from 1:j to itself"
    assert messages["unconnected_component"] == "C:lost is not connected to any bond"
    assert "0 inward and 1 outward" in messages["bad_two_port"]
    assert messages["no_output"] == "the model has no detector (an output is needed)"
    assert "z" in messages["cyclic_definition"]
    several = failure(DATA / "errors" / "no_input_several.bg").errors[0].message
    assert "Se:v" in several and "Sf:f" in several and "input TYPE:NAME" in several


def test_one_pass_reports_errors_of_many_kinds():
    problem = failure(DATA / "errors" / "several_kinds.bg")
    assert len(set(problem.kinds())) == 9
    assert len(problem.errors) == 9


def test_syntax_errors_on_several_lines_are_all_reported():
    assert places(failure(DATA / "errors" / "syntax.bg").errors) == [
        ("syntax", 5, 15),
        ("syntax", 7, 6),
    ]


def test_s_in_a_parameter_value_explains_itself(models):
    problem = models.failure("model m\nparam r = 2*s\nSe:v -> 1:j -> R:r\n1:j -> Df:i\n")
    (error,) = problem.errors
    assert error.kind == "undeclared_parameter"
    assert "Laplace" in error.message


def test_a_name_used_with_two_types_is_reported_once_and_does_not_cascade(models):
    text = "model m\nunknown x = 1\nSe:v -> 1:j -> C:x\n1:j -> Df:i\nC:x\nI:x\n1:j -> I:x\n"
    problem = models.failure(text)
    # one report per clashing mention; the bond to I:x does not give C:x a second bond
    assert places(problem.errors) == [("duplicate_name", 6, 1), ("duplicate_name", 7, 8)]


def test_an_empty_text_is_an_empty_model(models):
    for text in ("", "\n\n", "# just a comment\n", "  \t \n"):
        problem = models.failure(text)
        assert places(problem.errors) == [("empty_model", None, None)]


# --unknown and the unknown parameter ----------------------------------------------


def test_unknown_option_chooses_among_several_unknowns():
    parsed = parse(read_source(DATA / "valid" / "several_unknowns.bg"))
    assert build(parsed).unknowns == ("a", "b", "c")  # every unknown, in file order
    assert build(parsed, Selection(("c", "a"))).unknowns == ("c", "a")
    assert build(parsed, Selection(("b",))).unknowns == ("b",)
    assert build(parsed, Selection(("r0",))).unknowns == ("r0",)  # any parameter may be chosen


def test_unknown_option_naming_no_parameter_is_an_error(models):
    text = "model m\nunknown c = 1\nSe:v -> 1:j -> C:c\n1:j -> Df:i\n"
    assert models.build(text).unknowns == ("c",)
    problem = models.failure(text, unknown="zz")
    assert places(problem.errors) == [("undeclared_parameter", None, None)]
    assert "zz" in problem.errors[0].message


def test_a_model_without_unknown_is_valid(models):
    graph = models.build("model m\nparam r = 1\nSe:v -> 1:j -> R:r\n1:j -> Df:i\n")
    assert graph.unknowns == ()


# warnings ----------------------------------------------------------------------------


def test_one_ports_against_the_usual_direction_give_bond_direction_warnings():
    path = DATA / "valid" / "active_elements.bg"
    graph = load(path)
    assert places(graph.warnings) == expectations(path, warnings=True)
    assert places(graph.warnings) == [("bond_direction", 5, 1), ("bond_direction", 6, 8)]
    assert all(w.severity is Severity.WARNING for w in graph.warnings)
    rendered = graph.source.render(graph.warnings[0])
    assert rendered.splitlines()[0] == (
        f"{path}:5:1: warning[bond_direction]: "
        "the bond of R:r points out of it, which makes it an active element"
    )


def test_warnings_travel_with_errors(models):
    text = "model m\nparam r = 2\nR:r -> 1:j\n1:j -> Df:i\n"  # no source, R:r reversed
    problem = models.failure(text)
    assert places(problem.errors) == [("no_input", None, None)]
    assert places(problem.warnings) == [("bond_direction", 3, 1)]
    assert "warning[bond_direction]" in problem.render()


def test_conventional_directions_give_no_warning():
    for path in MODELS:
        assert load(path).warnings == ()
    assert load(DATA / "valid" / "everything.bg").warnings == ()


# the rendered format -------------------------------------------------------------


def test_rendered_error_has_location_kind_source_line_and_caret(models):
    text = "model m\nparam r = 2\nSe:v -> 1:j -> Q:x\n1:j -> Df:i\n"
    problem = models.failure(text)
    lines = problem.render().splitlines()
    assert lines[0] == (
        "test.bg:3:16: error[unknown_component_type]: "
        "unknown component type 'Q' (known: Se Sf MSe MSf De Df R C I TF GY 0 1 SS)"
    )
    assert lines[1] == " 3 | Se:v -> 1:j -> Q:x"
    assert lines[2] == "   |                ^"
    assert lines[2].index("^") == lines[1].index("Q:x")
    # below the model, a 1-based column 16 is the 16th character of the line
    assert text.splitlines()[2][16 - 1 :].startswith("Q:x")


def test_caret_lines_up_with_tabs_and_two_digit_line_numbers(models):
    text = "model m\n" + "\n" * 9 + "\tparam p = 1 +\n"
    lines = failure_render(text)
    assert lines[0].startswith("test.bg:11:15: error[syntax]: ")
    assert lines[1] == " 11 |  param p = 1 +"
    assert lines[2] == "    |               ^"
    assert lines[2].index("^") == len(lines[1])


def test_errors_without_a_place_are_one_line(models):
    problem = models.failure("model m\nparam r = 2\nSe:v -> 1:j -> R:r\n")
    assert problem.render() == (
        "test.bg: error[no_output]: the model has no detector (an output is needed)"
    )


def test_rendered_source_line_is_the_parsers_line_despite_unusual_line_breaks():
    # a form feed and a Unicode line separator are not line breaks for the parser
    text = 'model m "a\u2028b"\f\nparam p = )\n'
    lines = failure_render(text)
    assert lines[0].startswith("test.bg:2:11: error[syntax]")
    assert lines[1] == " 2 | param p = )"


def failure_render(text: str) -> list[str]:
    with pytest.raises(ModelError) as caught:
        build(parse(Source("test.bg", text)))
    return caught.value.render().splitlines()


# reading files ---------------------------------------------------------------------


def test_unreadable_files_are_io_errors(tmp_path):
    with pytest.raises(ModelError) as caught:
        read_source(tmp_path / "missing.bg")
    assert places(caught.value.errors) == [("io", None, None)]
    (tmp_path / "latin1.bg").write_bytes('model m "caf\xe9"\n'.encode("latin-1"))
    with pytest.raises(ModelError) as caught:
        read_source(tmp_path / "latin1.bg")
    assert places(caught.value.errors) == [("io", None, None)]
    with pytest.raises(ModelError) as caught:
        read_source(tmp_path)  # a directory
    assert places(caught.value.errors) == [("io", None, None)]


def test_a_crlf_file_reads_like_an_lf_file(tmp_path):
    text = (ROOT / "models" / "rlc.bg").read_text(encoding="utf-8")
    (tmp_path / "rlc.bg").write_bytes(text.replace("\n", "\r\n").encode("utf-8"))
    crlf, lf = load(tmp_path / "rlc.bg"), load(ROOT / "models" / "rlc.bg")
    assert [(b.number, b.tail, b.head, b.position) for b in crlf.bonds] == [
        (b.number, b.tail, b.head, b.position) for b in lf.bonds
    ]
    assert {n: p.value.value for n, p in crlf.parameters.items()} == {
        n: p.value.value for n, p in lf.parameters.items()
    }
    assert crlf.parameters["c"].description == "capacitance [F]"


# the example of the language specification, and the shipped models -----------------


def spec_examples() -> list[tuple[str, str]]:
    """Every ```bg block of docs/language.md (and the example of the shared spec, if present)."""
    blocks = []
    guide = ROOT / "docs" / "language.md"
    for number, block in enumerate(
        re.findall(r"^```bg\n(.*?)^```", guide.read_text(encoding="utf-8"), re.S | re.M)
    ):
        blocks.append((f"language.md#{number}", block))
    spec = Path("/work/shared/docs/bg-language.md")
    if spec.exists():
        text = spec.read_text(encoding="utf-8")
        example = text.split("## Example", 1)[1]
        blocks.append(("bg-language.md", re.search(r"```\n(.*?)```", example, re.S)[1]))
    return blocks


@pytest.mark.parametrize(("where", "text"), spec_examples(), ids=lambda v: v[:20])
def test_the_example_of_the_language_spec_is_accepted(where, text):
    graph = build(parse(Source(where, text)))
    assert graph.name == "rlc"
    assert graph.description == "series RLC circuit"
    assert {n: p.value.value for n, p in graph.parameters.items()} == {
        "r": 2,
        "l": Rational(1, 2),
        "c": Rational(1, 10),
    }
    assert (graph.input, graph.output, graph.unknowns) == ("v", "i", ("c",))
    assert sorted(c.label for c in graph.components) == [
        "1:loop",
        "C:c",
        "Df:i",
        "I:l",
        "R:r",
        "Se:v",
    ]
    assert [(b.tail, b.head) for b in graph.bonds] == [
        ("v", "loop"),
        ("loop", "r"),
        ("loop", "l"),
        ("loop", "c"),
        ("loop", "i"),
    ]
    assert graph.component("c").argument.value == Symbol("c")
    assert graph.warnings == ()


def test_the_guide_has_the_example_and_it_is_the_shipped_rlc_model():
    (guide_example,) = [text for where, text in spec_examples() if where.startswith("language")]
    shipped = (ROOT / "models" / "rlc.bg").read_text(encoding="utf-8")
    statements = [line for line in shipped.splitlines() if line and not line.startswith("#")]
    assert [line for line in guide_example.splitlines() if line and line[0] != "#"] == statements


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
def test_shipped_models_are_valid(path):
    graph = load(path)
    assert graph.warnings == ()
    assert graph.unknowns


def test_shipped_models_have_the_documented_ports():
    ports = {p.stem: (load(p).input, load(p).output, load(p).unknowns) for p in MODELS}
    assert ports["rlc"] == ("v", "i", ("c",))
    assert ports["dc_drive"] == ("v", "vm", ("k",))
    assert ports["absorber"] == ("feed", "x_l", ("k",))


def test_everything_file_builds_with_every_construct():
    graph = load(DATA / "valid" / "everything.bg")
    ra, inductance, ks, m = sympy.symbols("ra l ks m")
    values = {n: (p.value.value if p.value else None) for n, p in graph.parameters.items()}
    assert values == {
        "ra": Rational(3, 20),
        "l": Rational(1, 2),
        "ks": 8,
        "rc": ra / 2 + 5,
        "n": None,
        "g": 2 * sympy.pi,
        "m": 10,
    }
    assert graph.parameters["ra"].description == "exact: 3/20"
    assert graph.component("ra").description == "armature resistance # with a hash"
    arguments = {c.name: c.argument.value for c in graph.components if c.argument is not None}
    assert arguments == {
        "n": Symbol("n"),
        "g": Symbol("g"),
        "ra": ra,
        "la": 2 * inductance,
        "cb": 1 / ks,
        "rc": Symbol("rc"),
        "m": m,
    }
    assert (graph.input, graph.output, graph.unknowns) == ("v", "x", ("m",))
    assert [(b.number, b.tail, b.head) for b in graph.bonds][:5] == [
        (1, "v", "a"),
        (2, "a", "n"),
        (3, "n", "b"),
        (4, "b", "g"),
        (5, "g", "c"),
    ]
    assert len(graph.bonds) == 13
    assert graph.graph.number_of_nodes() == 14
    assert [(p.bond, p.inward) for p in graph.ports("g")] == [(4, True), (5, False)]


def test_every_kind_the_compiler_reports_is_documented():
    """docs/language.md has a row for each kind the language, derivation and estimator
    stages can report, and for no other (found in their source, so a new kind cannot go
    undocumented, nor a retired one stay)."""
    reported = {"no_input", "no_output"}  # chosen by role, not written out at the call
    call = re.compile(
        r'(?:error|warning|report|_fail|fail|Problem|Unsupported)\(\s*(?:theta,\s*)?"([a-z_]+)"'
    )
    for stage in ("language", "derivation", "estimator"):
        for path in (ROOT / "mtt" / stage).glob("*.py"):
            reported |= set(call.findall(path.read_text(encoding="utf-8")))
    documented = set(re.findall(r"^\| `([a-z_]+)` \|", (ROOT / "docs" / "language.md").read_text(),
                                re.MULTILINE))  # fmt: skip
    assert len(reported) >= 32
    assert reported <= documented, reported - documented
    # and no row for a kind nothing reports any more (several_unknowns was retired)
    assert documented <= reported, documented - reported
