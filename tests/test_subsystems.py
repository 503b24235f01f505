"""Subsystems: files used as parts of a model, their ports, names, errors and safety.

The models under tests/data/subsystems are assembled and checked against hand-derived
transfer functions and against the oracle (which sees only the assembled bond graph);
errors are checked at their exact file, line and column, with the notes that say which
subsystem statements brought the file in.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
import sympy
from oracle import oracle_tf

from mtt.cli.main import main
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import load, transfer_for
from mtt.language import subsystems
from mtt.language.bondgraph import Selection
from mtt.language.diagnostics import ModelError

ROOT = Path(__file__).resolve().parent.parent
HERE = Path(__file__).resolve().parent / "data" / "subsystems"
MODELS = sorted(HERE.glob("*.bg"))

s, k, jl, jm, r = sympy.symbols("s k jl jm r")


def write(base: Path, files: dict[str, str]) -> Path:
    """Write model files under `base`; the first one is the model."""
    for name, text in files.items():
        (base / name).parent.mkdir(parents=True, exist_ok=True)
        (base / name).write_text(text, encoding="utf-8")
    return base / next(iter(files))


def failure(path: Path, **selection) -> ModelError:
    with pytest.raises(ModelError) as caught:
        load(path, Selection(**selection))
    return caught.value


def places(problem: ModelError, base: Path) -> list[tuple]:
    """(file relative to base, line, column, kind, notes) of every error."""
    found = []
    for d in problem.errors:
        file = os.path.relpath(d.file, base)
        notes = tuple(n.replace(str(base) + os.sep, "") for n in d.notes)
        line, column = (d.position.line, d.position.column) if d.position else (None, None)
        found.append((file, line, column, d.kind, notes))
    return found


def equal(a, b) -> bool:
    return sympy.expand(a - b) == 0


# --- assembled models ----------------------------------------------------------------------


def test_a_ladder_of_one_section_file_used_three_times():
    # Three RC sections (r = 1, c = 1/2) with the last capacitance k: from the load back,
    # v3 = y, i3 = k s y, v2 = v3 + i3, i2 = i3 + v2 s/2, v1 = v2 + i2, i1 = i2 + v1 s/2,
    # v = v1 + i1, so y/v = 4 / (k s^3 + (8 k + 1) s^2 + (12 k + 6) s + 4).
    tf = transfer_for(HERE / "ladder.bg")
    assert equal(tf.numerator, 4)
    assert equal(tf.denominator, k * s**3 + (8 * k + 1) * s**2 + (12 * k + 6) * s + 4)
    graph = load(HERE / "ladder.bg")
    assert [b.number for b in graph.bonds] == list(range(1, 14))
    assert graph.unknowns == ("k",)
    assert graph.parameters["s3.c"].value.value == k  # set by the parent: not an unknown
    assert graph.component("s2.c").argument.value == sympy.Symbol("s2.c")


def test_a_subsystem_with_its_own_source_and_unknown():
    # Armature v = (ra + la s) i + km w, shaft km i = (jm + jl) s w: with ra = r = 2,
    # la = 1/10, km = 1: w/v = 10 / ((jl + jm) s^2 + 20 (jl + jm) s + 10).
    graph = load(HERE / "drive.bg")
    assert (graph.input, graph.output) == ("motor.v", "w")  # `input Se:motor.v`
    assert graph.unknowns == ("jl", "motor.jm")  # the motor's unknown is the model's
    J = jl + sympy.Symbol("motor.jm")
    tf = transfer_for(HERE / "drive.bg")
    assert equal(tf.numerator, 10) and equal(tf.denominator, J * s**2 + 20 * J * s + 10)


def test_dotted_names_on_the_command_line():
    # the load torque into the load: w/torque = (ra + la s) / ((ra + la s) J s + km^2)
    choice = ParameterChoice(
        unknowns=("jl",),
        input="Se:torque",
        keep=frozenset({"motor.ra"}),
        overrides={"motor.km": sympy.Integer(2)},
    )
    tf = transfer_for(HERE / "drive.bg", choice)
    ra = sympy.Symbol("motor.ra")
    assert equal(tf.numerator, 10 * ra + s)
    assert equal(tf.denominator, (jl + 1) * s**2 + 10 * ra * (jl + 1) * s + 40)
    assert tf.equations.parametrisation.assumed["motor.km"] == 2


def test_two_levels_of_subsystems():
    # plant -> geared (gear n = 1/2, sets the motor's km = 2 and jm = 1/10) -> motor, a load
    # jl with friction 1/10: w/v = n km / ((ra + la s)(jm s + n^2 (jl s + 1/10)) + km^2),
    # ra = 1, la = 1/10: 400 / (2 (5 jl + 2) s^2 + (100 jl + 41) s + 1610).
    graph = load(HERE / "plant.bg")
    assert graph.unknowns == ("jl",) and graph.input == "drive.motor.v"
    assert [sub.name for sub in graph.subsystems] == ["drive", "drive.motor"]
    tf = transfer_for(HERE / "plant.bg")
    assert equal(tf.numerator, 400)
    assert equal(tf.denominator, 2 * (5 * jl + 2) * s**2 + (100 * jl + 41) * s + 1610)


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
@pytest.mark.parametrize("symbolic", [False, True], ids=["values", "symbolic"])
def test_the_oracle_agrees_on_assembled_models(path, symbolic):
    tf = transfer_for(path, ParameterChoice(symbolic=symbolic))
    assert sympy.cancel(tf.numerator / tf.denominator - oracle_tf(path, symbolic=symbolic)) == 0


def test_a_bond_may_join_two_subsystems_ports_and_ports_may_chain(tmp_path):
    # a pass-through subsystem (its two ports bonded to each other) between two resistors
    model = write(tmp_path, {
        "top.bg": "model top\nsubsystem w = \"wire.bg\"\nsubsystem x = \"wire.bg\"\n"
                  "Se:v -> 1:j -> R:a(2)\n1:j -> w.in\nw.out -> x.in\nx.out -> Df:i\n",
        "wire.bg": "model wire\nSS:in -> SS:out\n",
    })  # fmt: skip
    graph = load(model)
    assert [(graph.component(b.tail).label, graph.component(b.head).label)
            for b in graph.bonds] == [("Se:v", "1:j"), ("1:j", "R:a"), ("1:j", "Df:i")]  # fmt: skip
    assert equal(transfer_for(model).numerator, 1)  # i = v / 2
    assert equal(transfer_for(model).denominator, 2)


def test_a_signal_reads_a_subsystems_junction_by_its_dotted_name(tmp_path):
    # tank: u = (s + 1) x; the parent's modulated flow g x fills a unit capacitor: y = g x / s
    model = write(tmp_path, {
        "top.bg": 'model top\nunknown g = 2\nsubsystem tank = "tank.bg"\nSf:u -> tank.in\n'
                  "MSf:m(g*e(tank.x)) -> 0:b\n0:b -> C:cb(1)\n0:b -> De:y\n",
        "tank.bg": "model tank\nSS:in -> 0:x\n0:x -> C:h(1)\n0:x -> R:out(1)\n",
    })  # fmt: skip
    tf = transfer_for(model)
    assert equal(tf.numerator * (s**2 + s) - tf.denominator * sympy.Symbol("g"), 0)


def test_show_draws_the_subsystem_tree(capsys):
    assert main(["show", str(HERE / "plant.bg")]) == 0
    out = capsys.readouterr().out.splitlines()
    at = out.index("subsystems (2)")
    assert [line.split() for line in out[at + 1 : at + 3]] == [
        ["drive", str(HERE / "parts" / "geared.bg"), "(n", "=", "1/2)"],
        ["motor", str(HERE / "parts" / "motor.bg"), "(km", "=", "2,", "jm", "=", "1/10)"],
    ]
    assert out[at + 2].startswith("    motor")  # indented under drive
    assert main(["show", "--json", str(HERE / "plant.bg")]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["subsystems"] == [
        {"name": "drive", "file": str(HERE / "parts" / "geared.bg"),
         "parameters": {"n": "1/2"}, "description": None},
        {"name": "drive.motor", "file": str(HERE / "parts" / "motor.bg"),
         "parameters": {"km": "2", "jm": "1/10"}, "description": None},
    ]  # fmt: skip


def test_check_json_counts_the_assembled_model(capsys):
    assert main(["check", "--json", str(HERE / "ladder.bg")]) == 0
    (record,) = json.loads(capsys.readouterr().out)["files"]
    assert (record["components"], record["bonds"]) == (14, 13)
    assert record["parameters"]["s3.c"] == "k" and record["unknown"] == ["k"]


def test_the_specification_examples(tmp_path):
    # `1:a -> motor.shaft` (the parent's bond into the port: the motor's own bond points
    # out of SS:shaft) and `input Se:motor.v`, a source of the subsystem, with a dotted name
    model = write(tmp_path, {
        "top.bg": 'model top\nsubsystem motor = "motor.bg" (r = 2)\nSe:u -> 1:a -> motor.shaft\n'
                  "1:a -> Df:i\ninput Se:motor.v\n",
        "motor.bg": "model motor\nparam r = 1\nSe:v -> 1:m\nSS:shaft -> 1:m\n1:m -> R:r\n",
    })  # fmt: skip
    graph = load(model)
    assert (graph.input, graph.output) == ("motor.v", "i")
    # one current i in both loops; with u = 0 the shaft's effort is 0, so v = r i
    tf = transfer_for(model)
    assert (tf.numerator, tf.denominator) == (1, 2)
    # with v = 0 instead, u reaches the resistor through the shaft: u = r i
    tf = transfer_for(model, ParameterChoice(input="Se:u"))
    assert (tf.numerator, tf.denominator) == (1, 2)


# --- errors, at their file, line and column ----------------------------------------------


def test_errors_two_levels_down_are_placed_in_their_file_with_notes(capsys):
    top = HERE / "errors" / "top.bg"
    problem = failure(top)
    base = HERE / "errors"
    notes = ("in subsystem mid.b1 (middle.bg:2)", "in subsystem mid (top.bg:4)")
    # bottom.bg is used twice: each of its errors is reported once
    assert places(problem, base) == [
        ("bottom.bg", 5, 12, "undeclared_parameter", notes),
        ("bottom.bg", 6, 12, "bad_signal", notes),
    ]
    assert main(["check", str(top)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[:5] == [
        f"{base / 'bottom.bg'}:5:12: error[undeclared_parameter]: parameter 'q' is not declared",
        " 5 | 1:s -> R:r(q)",
        "   |            ^",
        f"note: in subsystem mid.b1 ({base / 'middle.bg'}:2)",
        f"note: in subsystem mid ({top}:4)",
    ]
    assert main(["check", "--json", str(top)]) == 2
    (first, _) = json.loads(capsys.readouterr().out)["files"][0]["errors"]
    assert first["file"] == str(base / "bottom.bg") and first["line"] == 5
    assert first["notes"] == [f"in subsystem mid.b1 ({base / 'middle.bg'}:2)",
                              f"in subsystem mid ({top}:4)"]  # fmt: skip


STAGE = "model stage\nparam c = 1\nSS:in -> 0:n\n0:n -> C:c\n0:n -> SS:out\n"


@pytest.mark.parametrize(
    ("files", "expected"),
    [
        # an SS in the model itself
        ({"top.bg": "model top\nSe:v -> SS:p\n0:j -> De:y\n"},
         [("top.bg", 2, 9, "bad_port", ())]),
        # a port the subsystem does not have
        ({"top.bg": 'model top\nsubsystem a = "stage.bg"\nSe:v -> a.in\na.outlet -> De:y\n',
          "stage.bg": STAGE},
         [("top.bg", 2, 11, "unconnected_component", ()), ("top.bg", 4, 1, "bad_port", ())]),
        # a bond against the direction of the subsystem's own bond at its SS
        ({"top.bg": 'model top\nsubsystem a = "stage.bg"\nSe:v -> a.in\nDe:y -> a.out\n',
          "stage.bg": STAGE},
         [("top.bg", 4, 6, "port_direction", ())]),
        # a port bonded twice, and an unknown subsystem
        ({"top.bg": 'model top\nsubsystem a = "stage.bg"\nSe:v -> a.in\na.out -> De:y\n'
                    "Sf:u -> a.in\nb.in -> 0:z\ninput Se:v\n", "stage.bg": STAGE},
         [("top.bg", 3, 9, "bad_arity", ()), ("top.bg", 6, 1, "undeclared_component", ())]),
        # a binding of a parameter the subsystem does not declare, and a binding twice
        ({"top.bg": 'model top\nsubsystem a = "stage.bg" (d = 1, c = 2, c = 3)\n'
                    "Se:v -> a.in\na.out -> De:y\n", "stage.bg": STAGE},
         [("top.bg", 2, 27, "undeclared_parameter", ()),
          ("top.bg", 2, 41, "duplicate_argument", ())]),
        # a subsystem's name taken twice (with a component too)
        ({"top.bg": 'model top\nsubsystem a = "stage.bg"\nsubsystem a = "stage.bg"\n'
                    "Se:v -> a.in\na.out -> De:a\n", "stage.bg": STAGE},
         [("top.bg", 3, 11, "duplicate_name", ()), ("top.bg", 5, 10, "duplicate_name", ())]),
        # a missing file, at the subsystem statement
        ({"top.bg": 'model top\nsubsystem a = "nowhere.bg"\nSe:v -> a.in\na.out -> De:y\n'},
         [("top.bg", 2, 11, "io", ())]),
        # a file including itself, directly
        ({"top.bg": 'model top\nsubsystem a = "loop.bg"\nSe:v -> a.p\n',
          "loop.bg": 'model loop\nsubsystem again = "loop.bg"\nSS:p -> 0:j\n0:j -> again.p\n'},
         [("loop.bg", 2, 11, "cyclic_subsystem", ("in subsystem a (top.bg:2)",))]),
        # ... and through another file, back to the model itself
        ({"top.bg": 'model top\nsubsystem a = "parts/a.bg"\nSe:v -> a.p\n',
          "parts/a.bg": 'model a\nsubsystem b = "b.bg"\nSS:p -> b.p\n',
          "parts/b.bg": 'model b\nsubsystem top = "../top.bg"\nSS:p -> top.p\n'},
         [("parts/b.bg", 2, 11, "cyclic_subsystem",
           ("in subsystem a.b (parts/a.bg:2)", "in subsystem a (top.bg:2)"))]),
        # a syntax error in a subsystem's file, and a dotted component in a bond
        ({"top.bg": 'model top\nsubsystem a = "bad.bg"\nSe:v -> a.p\n',
          "bad.bg": "model bad\nparam = 2\n"},
         [("bad.bg", 2, 7, "syntax", ("in subsystem a (top.bg:2)",))]),
        # a subsystem's component in a bond, or a port of a subsystem's subsystem
        ({"top.bg": "model top\nSe:v -> R:a.x\nSe:w -> a.b.p\n"},
         [("top.bg", 2, 9, "syntax", ()), ("top.bg", 3, 9, "syntax", ())]),
        # a signal of a subsystem's component that does not exist, or cannot be read
        ({"top.bg": 'model top\nsubsystem a = "stage.bg"\nSe:v -> a.in\na.out -> De:y\n'
                    "MSf:m(e(a.x) + f(a.n)) -> 0:j\n0:j -> C:q(1)\n", "stage.bg": STAGE},
         [("top.bg", 5, 7, "undeclared_component", ()), ("top.bg", 5, 16, "bad_signal", ())]),
        # the model's input named with a dotted name that does not exist
        ({"top.bg": 'model top\nsubsystem a = "stage.bg"\nSe:v -> a.in\na.out -> De:y\n'
                    "input Se:a.v\n", "stage.bg": STAGE},
         [("top.bg", 5, 7, "undeclared_component", ())]),
    ],
    ids=["ss-at-top", "no-such-port", "port-direction", "port-twice", "bindings",
         "duplicate", "missing", "self-include", "cycle", "syntax", "dotted", "signals",
         "input"],
)  # fmt: skip
def test_subsystem_errors_are_placed(tmp_path, files, expected):
    assert places(failure(write(tmp_path, files)), tmp_path) == expected


def test_an_error_in_the_assembled_model_is_placed_in_the_subsystem(tmp_path):
    # causal conflict: two effort sources on one 0-junction, one of them in the subsystem
    model = write(tmp_path, {
        "top.bg": 'model top\nsubsystem a = "src.bg"\na.p -> 0:j\nSe:w -> 0:j\n0:j -> Df:i\n'
                  "input Se:w\n",
        "src.bg": "model src\nSe:v -> SS:p\n",
    })  # fmt: skip
    with pytest.raises(ModelError) as caught:
        transfer_for(model)
    assert places(caught.value, tmp_path) == [("top.bg", 4, 1, "causal_conflict", ())]
    assert caught.value.errors[0].message.startswith("Se:a.v and Se:w both impose the effort")
    # an unknown entering irrationally, inside the subsystem
    model = write(tmp_path, {
        "top.bg": 'model top\nsubsystem a = "r.bg"\nSe:v -> 1:j -> a.p\n1:j -> Df:i\n',
        "r.bg": "model r\nunknown k = 1\nSS:p -> R:x(sqrt(k))\n",
    })  # fmt: skip
    with pytest.raises(ModelError) as caught:
        transfer_for(model)
    assert places(caught.value, tmp_path) == [
        ("r.bg", 3, 13, "non_rational_unknown", ("in subsystem a (top.bg:2)",))
    ]


# --- what a subsystem file may not make the compiler do -----------------------------------


@pytest.mark.parametrize(
    ("path", "says"),
    [
        ("/etc/passwd.bg", "must be a relative path to a .bg file"),
        ("~/x.bg", "must be a relative path to a .bg file"),
        ("secret.txt", "must be a relative path to a .bg file"),
        ("folder.bg", "is not a regular file"),
        ("huge.bg", "is too large"),
        ("bad\x00name.bg", "cannot read"),
    ],
)
def test_only_regular_relative_bg_files_of_bounded_size_are_read(tmp_path, path, says):
    (tmp_path / "folder.bg").mkdir()
    (tmp_path / "secret.txt").write_text("model secret\nSe:v -> SS:p\n")
    with open(tmp_path / "huge.bg", "wb") as huge:
        huge.truncate(subsystems.MAX_FILE_BYTES + 1)
    text = f'model top\nsubsystem a = "{path}"\nSe:v -> a.p\n'
    problem = failure(write(tmp_path, {"top.bg": text}))
    assert places(problem, tmp_path) == [("top.bg", 2, 11, "io", ())]
    assert says in problem.errors[0].message


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_named_pipe_is_not_read(tmp_path):
    os.mkfifo(tmp_path / "pipe.bg")  # reading it would block forever
    model = write(tmp_path, {"top.bg": 'model top\nsubsystem a = "pipe.bg"\nSe:v -> a.p\n'})
    assert "is not a regular file" in failure(model).errors[0].message


def test_a_link_back_to_an_including_file_is_a_cycle(tmp_path):
    write(tmp_path, {"parts/a.bg": 'model a\nsubsystem b = "b.bg"\nSS:p -> b.p\n'})
    (tmp_path / "parts" / "b.bg").symlink_to(tmp_path / "parts" / "a.bg")
    model = write(tmp_path, {"top.bg": 'model top\nsubsystem a = "parts/a.bg"\nSe:v -> a.p\n'})
    assert [p[3] for p in places(failure(model), tmp_path)] == ["cyclic_subsystem"]


def test_nesting_and_instances_are_bounded(tmp_path, monkeypatch):
    # each file uses the next one twice: 2^12 instances from 13 small files
    files = {"f0.bg": 'model f0\nsubsystem a = "f1.bg"\nSe:v -> a.p\n'}
    for i in range(1, 12):
        files[f"f{i}.bg"] = (f'model f{i}\nsubsystem a = "f{i + 1}.bg"\nsubsystem b = '
                             f'"f{i + 1}.bg"\nSS:p -> 0:j\n0:j -> a.p\n0:j -> b.p\n')  # fmt: skip
    files["f12.bg"] = "model f12\nSS:p -> C:c(1)\n"
    model = write(tmp_path, files)
    monkeypatch.setattr(subsystems, "MAX_INSTANCES", 100)
    found = places(failure(model), tmp_path)
    assert {p[3] for p in found} == {"too_large"}
    file, line, column, _, notes = found[0]  # at the subsystem statement that goes too far
    assert (line, column) in ((2, 11), (3, 11)) and file.startswith("f") and notes
    monkeypatch.setattr(subsystems, "MAX_INSTANCES", 10_000)
    monkeypatch.setattr(subsystems, "MAX_DEPTH", 5)
    kinds = {p[3] for p in places(failure(model), tmp_path)}
    assert kinds == {"too_large"}
