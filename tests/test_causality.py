"""Sequential causality assignment: strokes, dependent storage, algebraic loops, conflicts."""

from __future__ import annotations

import itertools
import json
import random
import re
from pathlib import Path

import pytest
import sympy
from oracle import oracle_tf

from mtt.derivation.causality import CausalBondGraph, assign, describe
from mtt.derivation.nonlinear import nonlinear_parts, nonlinear_state_space
from mtt.derivation.pipeline import causal_for, load, transfer_for
from mtt.derivation.structure import structure_problems
from mtt.language.diagnostics import ModelError, Source

ROOT = Path(__file__).resolve().parent.parent
SYSTEMS = Path(__file__).resolve().parent / "data" / "systems"
ALL_MODELS = sorted(SYSTEMS.glob("*.bg")) + sorted((ROOT / "models").glob("*.bg"))


def causal(path: Path) -> CausalBondGraph:
    return assign(load(path))


def conflict(models, text: str) -> ModelError:
    with pytest.raises(ModelError) as caught:
        assign(models.build(text))
    return caught.value


def check_rules(c: CausalBondGraph) -> None:
    """Every bond has a causality and every component's causal constraint holds."""
    graph = c.bondgraph
    assert set(c.effort_from) == {b.number for b in graph.bonds}
    for component in graph.components:
        name, kind = component.name, component.type.name
        imposes = [c.imposes_effort(name, p.bond) for p in graph.ports(name)]
        if kind in ("Se", "Df"):
            assert imposes == [True]
        elif kind in ("Sf", "De"):
            assert imposes == [False]
        elif kind == "C":
            assert imposes == [name not in c.dependent]
        elif kind == "I":
            assert imposes == [name in c.dependent]
        elif kind == "TF":
            assert imposes[0] != imposes[1]
        elif kind == "GY":
            assert imposes[0] == imposes[1]
        elif kind == "0":  # exactly one bond brings the effort in
            assert imposes.count(False) == 1
        elif kind == "1":  # exactly one bond brings the flow in
            assert imposes.count(True) == 1


@pytest.mark.parametrize("path", ALL_MODELS, ids=lambda p: p.stem)
def test_every_model_gets_a_complete_consistent_causality(path):
    check_rules(causal(path))


def test_rlc_strokes():
    c = causal(ROOT / "models" / "rlc.bg")
    # I:l (integral) imposes the loop's flow; so every other bond brings its effort into
    # the loop: Se and Df by their fixed causality, C (integral) and R (resistance form)
    assert [c.stroke_at(b) for b in range(1, 6)] == ["loop", "loop", "l", "loop", "loop"]
    assert dict(c.effort_from) == {1: "v", 2: "r", 3: "loop", 4: "c", 5: "i"}
    assert c.dependent == () and c.loops == ()


def test_rlc_describe_lists_strokes():
    text = describe(causal(ROOT / "models" / "rlc.bg"))
    assert text.splitlines() == [
        "causality of rlc (| marks the end of a bond that receives the effort)",
        "    1  Se:v ->| 1:loop",
        "    2  1:loop |-> R:r",
        "    3  1:loop ->| I:l",
        "    4  1:loop |-> C:c",
        "    5  1:loop |-> Df:i",
        "dependent storage (derivative causality): none",
        "algebraic loops (resistors with an arbitrary causality): none",
    ]


def test_paper_models_are_all_integral_without_loops():
    for name in ("dc_drive", "absorber"):
        c = causal(ROOT / "models" / f"{name}.bg")
        assert c.dependent == () and c.loops == ()


@pytest.mark.parametrize(
    "name, dependent",
    [
        ("parallel_caps", ("c2",)),  # the second capacitor meets a fixed effort
        ("source_on_capacitor", ("c",)),  # Se fixes the capacitor's effort
        ("current_into_inductor", ("l",)),  # Sf fixes the inductor's flow
        ("gear", ("j2",)),  # the gear fixes the second inertia's speed
    ],
)
def test_derivative_causality(name, dependent):
    c = causal(SYSTEMS / f"{name}.bg")
    assert c.dependent == dependent
    assert all(not c.integral(x) for x in dependent)
    labels = ", ".join(c.bondgraph.component(x).label for x in dependent)
    assert f"dependent storage (derivative causality): {labels}" in describe(c)


def test_algebraic_loop():
    c = causal(SYSTEMS / "resistor_network.bg")
    assert c.loops == ("r1",)
    assert c.dependent == ()
    assert "algebraic loops (resistors with an arbitrary causality): R:r1" in describe(c)


def test_arbitrary_resistor_gets_resistance_causality():
    # the free choice is the preferred one: R:r1 takes the flow and imposes the effort
    c = causal(SYSTEMS / "resistor_network.bg")
    assert c.imposes_effort("r1", 2)


def test_storage_order_decides_which_is_dependent(models):
    text = "model p\nparam a = 1\nparam b = 2\nSf:i -> 0:n\n0:n -> C:{}\n0:n -> C:{}\n0:n -> De:v\n"
    assert assign(models.build(text.format("a", "b"))).dependent == ("b",)
    assert assign(models.build(text.format("b", "a"))).dependent == ("a",)


def test_two_effort_sources_on_a_zero_junction(models):
    problem = conflict(
        models,
        "model two\ninput Se:a\nSe:a -> 0:n\nSe:b -> 0:n\n0:n -> R:r\nparam r = 1\n0:n -> De:v\n",
    )
    (error,) = problem.errors
    assert error.kind == "causal_conflict"
    assert "Se:a" in error.message and "Se:b" in error.message
    assert error.position.line in (3, 4)  # one of the two sources


def test_two_flow_sources_on_a_one_junction(models):
    problem = conflict(
        models,
        "model two\ninput Sf:a\nSf:a -> 1:n\nSf:b -> 1:n\n1:n -> R:r\nparam r = 1\n1:n -> Df:i\n",
    )
    (error,) = problem.errors
    assert error.kind == "causal_conflict"
    assert "Sf:a" in error.message and "Sf:b" in error.message


def test_effort_source_and_flow_detector_on_a_zero_junction(models):
    # Df imposes e = 0 where Se imposes e = u
    problem = conflict(models, "model d\nSe:v -> 0:n\n0:n -> Df:i\n0:n -> R:r(1)\n")
    (error,) = problem.errors
    assert error.kind == "causal_conflict"
    assert "Se:v" in error.message and "Df:i" in error.message
    assert error.position.line in (2, 3)


def test_flow_source_and_effort_detector_on_a_one_junction(models):
    problem = conflict(models, "model d\nSf:i -> 1:n\n1:n -> De:v\n1:n -> R:r(1)\n")
    assert problem.kinds() == ["causal_conflict"]
    assert "Sf:i" in problem.errors[0].message and "De:v" in problem.errors[0].message


def test_conflict_through_a_transformer(models):
    # Sf:a fixes the flow on the TF's first port, so the TF fixes its second port's flow,
    # the flow of 1:j, which Sf:b also fixes
    problem = conflict(
        models,
        "model t\ninput Sf:a\nSf:a -> TF:t(2) -> 1:j\nSf:b -> 1:j\n1:j -> R:r(1)\n1:j -> Df:i\n",
    )
    assert problem.kinds() == ["causal_conflict"]
    assert "Sf:a" in problem.errors[0].message and "Sf:b" in problem.errors[0].message


def test_conflict_is_rendered_with_its_line(models):
    problem = conflict(models, "model d\nSe:v -> 0:n\n0:n -> Df:i\n0:n -> R:r(1)\n")
    text = Source("test.bg", "").render(problem.errors[0])
    assert text.startswith("test.bg:") and "error[causal_conflict]" in text


def test_unused_sources_keep_their_fixed_causality():
    c = causal(SYSTEMS / "several_ports.bg")
    check_rules(c)
    assert c.imposes_effort("bias", 2)  # Se:bias (set to zero) still imposes effort
    assert not c.imposes_effort("leak", 6)  # Sf:leak still imposes flow


# --- a junction with a single bond fixes a variable, like a source ----------------------

SHORTED = """model shorted
param r = 2
param r2 = 3
Se:v -> 1:a
1:a -> R:r
1:a -> 0:n
0:n -> R:r2
0:n -> 1:short
1:a -> Df:i
"""


def test_single_bond_junction_is_fixed_first(models):
    # 1:short has one bond: its effort is zero, so it fixes the effort of 0:n, which 0:n
    # imposes on R:r2 and on 1:a; with Se and Df, 1:a then has its effort from three bonds
    # and takes its flow from R:r: both resistors are forced into conductance causality,
    # nothing is arbitrary (before, both were reported as algebraic loops)
    c = assign(models.build(SHORTED))
    check_rules(c)
    assert c.loops == ()
    assert c.imposes_effort("short", 5)
    assert not c.imposes_effort("r2", 4) and not c.imposes_effort("r", 2)


def test_single_bond_junctions_do_not_cause_false_conflicts(tmp_path):
    # Found by comparing with the oracle on random graphs: 1:j3 and 0:j4 have a single
    # bond each. The model has a unique solution (G = 0), with C:e2 and C:e4 dependent;
    # that G = 0 is structural: no path leads from the input to the output.
    path = tmp_path / "dangling.bg"
    path.write_text(
        """model dangling
param p1 = 2
param p2 = 3
unknown k = 1
1:j0 -> GY:g1(k) -> 1:j1
0:j2 -> 1:j0
1:j0 -> 1:j3
0:j4 -> 1:j1
Se:u -> 1:j1
0:j2 -> Df:y
1:j1 -> C:e1(k*p1)
1:j0 -> C:e2(p2)
1:j1 -> R:e3(k*p1)
0:j2 -> C:e4(k)
"""
    )
    c = causal(path)
    check_rules(c)
    assert c.dependent == ("e2", "e4")
    assert oracle_tf(path) == 0
    with pytest.raises(ModelError) as caught:
        transfer_for(path)
    assert caught.value.kinds() == ["unreachable_output"]


def test_shorted_network_transfer_function(tmp_path):
    # v = r i + 0: G = 1/r = 1/2
    path = tmp_path / "shorted.bg"
    path.write_text(SHORTED)
    tf = transfer_for(path)
    assert (tf.numerator, tf.denominator) == (1, 2)
    assert oracle_tf(path) == sympy.Rational(1, 2)


def _random_model(rng: random.Random) -> str:
    """A small random bond graph: junctions joined by bonds and two-ports, one-ports on them."""
    junctions = [f"{rng.choice('01')}:j{i}" for i in range(rng.randint(2, 4))]
    lines = ["model random", "param p = 1"]
    lines += [f"{a} -> {b}" for a, b in itertools.pairwise(junctions)]
    for i in range(rng.randint(0, 2)):
        a, b = rng.sample(junctions, 2)
        lines.append(f"{a} -> {rng.choice(['TF', 'GY'])}:t{i}(p) -> {b}")
    lines.append(f"{rng.choice(['Se', 'Sf'])}:u -> {rng.choice(junctions)}")
    lines.append(f"{rng.choice(junctions)} -> {rng.choice(['De', 'Df'])}:y")
    for i in range(rng.randint(1, 4)):
        lines.append(f"{rng.choice(junctions)} -> {rng.choice('RCI')}:e{i}(p)")
    return "\n".join(lines) + "\n"


def _some_causality_exists(graph) -> bool:
    """Brute force: is there any assignment of strokes that every component accepts?"""
    bonds = [b.number for b in graph.bonds]
    for pattern in itertools.product((True, False), repeat=len(bonds)):
        tail_imposes = dict(zip(bonds, pattern, strict=True))
        ok = True
        for component in graph.components:
            name, kind = component.name, component.type.name
            values = [
                tail_imposes[p.bond] == (graph.bond(p.bond).tail == name) for p in graph.ports(name)
            ]
            ok = (
                (kind not in ("Se", "Df") or values == [True])
                and (kind not in ("Sf", "De") or values == [False])
                and (kind != "TF" or values[0] != values[1])
                and (kind != "GY" or values[0] == values[1])
                and (kind != "0" or values.count(False) == 1)
                and (kind != "1" or values.count(True) == 1)
            )
            if not ok:
                break
        if ok:
            return True
    return False


def test_assignment_is_found_whenever_one_exists(models):
    """Backtracking: the procedure never reports a conflict that some assignment avoids."""
    rng = random.Random(1992)
    found = refused = 0
    for _ in range(200):
        text = _random_model(rng)
        try:
            graph = models.build(text)
        except ModelError:
            continue
        if len(graph.bonds) > 9:
            continue
        exists = _some_causality_exists(graph)
        try:
            result = assign(graph)
        except ModelError as problem:
            assert not exists, text
            assert problem.kinds() == ["causal_conflict"]
            refused += 1
            continue
        assert exists, text
        check_rules_structurally(result)
        found += 1
    assert found > 50 and refused > 10  # the sample exercises both outcomes


def check_rules_structurally(c: CausalBondGraph) -> None:
    """`check_rules` without the storage preferences: a complete, consistent causality."""
    for component in c.bondgraph.components:
        if component.type.name not in ("C", "I"):
            continue
        assert c.imposes_effort(component.name, c.bondgraph.ports(component.name)[0].bond) == (
            (component.type.name == "C") != (component.name in c.dependent)
        )
    check_rules(c)


# --- structural problems: found from causality alone, before any algebra ---------------

STRUCTURE = Path(__file__).resolve().parent / "data" / "structure"


@pytest.mark.parametrize("path", sorted(STRUCTURE.glob("*.bg")), ids=lambda p: p.stem)
def test_structural_problems_are_placed(path):
    (expected,) = [
        (kind, int(line), int(column))
        for kind, line, column in re.findall(r"^# expect: (\w+) (\d+):(\d+)$",
                                             path.read_text(), re.MULTILINE)
    ]  # fmt: skip
    with pytest.raises(ModelError) as caught:
        causal_for(load(path), identify=True)
    (problem,) = caught.value.errors
    assert (problem.kind, problem.position.line, problem.position.column) == expected


def test_the_structural_checks_pass_every_valid_model():
    paths = [*ROOT.glob("models/*.bg"), *SYSTEMS.glob("*.bg"),
             *(ROOT / "tests" / "data" / "subsystems").glob("*.bg")]  # fmt: skip
    for path in paths:
        graph = load(path)
        assert structure_problems(assign(graph)) == [], path
        if graph.unknowns and nonlinear_parts(graph):  # each unknown is in the equations
            system = nonlinear_state_space(path)
            free = {str(x) for x in system.f.free_symbols | system.g.free_symbols}
            assert set(graph.unknowns) <= free, path
        elif graph.unknowns:  # and each unknown is really in the transfer function
            tf = transfer_for(path)
            free = {str(x) for x in (tf.numerator / tf.denominator).free_symbols}
            assert set(graph.unknowns) <= free, path


def test_a_path_through_a_signal_reaches_the_output(tmp_path):
    # the only link from the source to the detector is a modulated source's signal
    path = tmp_path / "m.bg"
    path.write_text("model m\nunknown g = 2\nSe:v -> 0:a -> R:r(1)\nMSf:m(g*e(a)) -> 0:b\n"
                    "0:b -> R:load(1)\n0:b -> De:y\n")  # fmt: skip
    assert structure_problems(assign(load(path))) == []
    tf = transfer_for(path)
    assert sympy.expand(tf.numerator - sympy.Symbol("g")) == 0 and tf.denominator == 1


def test_the_deriving_commands_report_what_they_cannot_do(capsys):
    from mtt.cli.main import main

    # the transfer function to an unreachable output is zero: an error for every command
    assert main(["tf", str(STRUCTURE / "island.bg")]) == 2
    assert "error[unreachable_output]" in capsys.readouterr().err
    # an unknown that drops out: the transfer function exists, Theta cannot identify it
    assert main(["tf", str(STRUCTURE / "dropped.bg")]) == 0
    assert "  G(s) = 1 / (c*s + 1)" in capsys.readouterr().out
    assert main(["theta", str(STRUCTURE / "dropped.bg")]) == 2
    assert "dropped.bg:6:9: error[no_dependence]: the unknown k" in capsys.readouterr().err
    assert main(["check", "--json", str(STRUCTURE / "dropped.bg")]) == 2
    (record,) = json.loads(capsys.readouterr().out)["files"]
    assert [(e["kind"], e["line"]) for e in record["errors"]] == [("no_dependence", 6)]
    assert (record["input"], record["output"]) == ("Se:v", "De:y")


def test_an_unknown_that_cancels_exactly_is_refused_by_theta(tmp_path, capsys):
    from mtt.cli.main import main

    # k reaches the output structurally, but R:a(k + 2) in series with R:b(-k) sum to 2
    path = tmp_path / "cancel.bg"
    path.write_text("model cancel\nunknown k = 1\nSe:v -> 1:j\n1:j -> R:a(k + 2)\n"
                    "1:j -> R:b(-k)\n1:j -> C:c(1)\n1:j -> Df:i\n")  # fmt: skip
    assert main(["tf", str(path)]) == 0
    assert "  G(s) = s / (2*s + 1)" in capsys.readouterr().out
    assert main(["theta", "--json", str(path)]) == 2
    record = json.loads(capsys.readouterr().out)
    assert [(e["kind"], e["line"], e["column"]) for e in record["errors"]] == [
        ("no_dependence", 2, 9)
    ]
    assert "cancels out of the exact transfer function" in record["errors"][0]["message"]
