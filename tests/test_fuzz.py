"""Fuzzing in the test suite (issue 12, item 7), with a fixed budget: random models and
random mutations of the example models end in a result or an `MttError` (never an
internal error, never hanging, never running text from the model); and the transfer
function agrees with a direct numeric solve of the bond graph's equations at random
points. The examples are derandomized (the same every run); tests/fuzz_campaign.py runs
the same generators for as long as you like."""

from __future__ import annotations

import cmath
import tempfile
from pathlib import Path

import numpy as np
import pytest
import sympy
from fuzzing import Files, example, random_model, run, valid_model
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from oracle import equations, parameter_values

from mtt.derivation.pipeline import transfer_for
from mtt.language.diagnostics import MttError


def budget(examples: int) -> settings:
    """A fixed number of derandomized examples: the same ones every run."""
    return settings(
        max_examples=examples,
        derandomize=True,
        database=None,
        deadline=None,  # `run` measures each example's time itself
        suppress_health_check=list(HealthCheck),
    )


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def _check(files, scratch: Path) -> None:
    directory = Path(tempfile.mkdtemp(dir=scratch))
    outcome = run(files, directory)
    assert not outcome.bugs, (files.model, outcome.bugs)
    assert not outcome.executed, files.model
    # a hang raises `Hang` (after 4 x 2 s of processor time, which a busy machine does not
    # stretch); the 2 s budget itself is measured by tests/fuzz_campaign.py, which reports
    # slow models


@budget(60)
@given(st.randoms(use_true_random=False))
def test_random_models_end_in_a_result_or_a_model_error(scratch, rng):
    _check(random_model(rng), scratch)


@budget(60)
@given(st.randoms(use_true_random=False))
def test_mutated_examples_end_in_a_result_or_a_model_error(scratch, rng):
    _check(example(rng), scratch)


@budget(40)
@given(st.randoms(use_true_random=False))
def test_well_formed_models_with_random_expressions(scratch, rng):
    _check(Files(valid_model(rng, expressions=True), {}), scratch)


def _direct_solve(graph, point: dict) -> complex:
    """y/u of the bond graph's equations (tests/oracle.py, written independently of mtt's
    derivation) at one point, solved numerically."""
    rows, unknowns, U, y = equations(graph, parameter_values(graph))
    rows = [sympy.expand(row.xreplace(point)) for row in rows]
    M = np.array([[complex(row.coeff(v)) for v in unknowns] for row in rows])
    b = np.array([-complex(row.coeff(U)) for row in rows])
    return np.linalg.solve(M, b)[unknowns.index(y)]


@budget(40)
@given(st.randoms(use_true_random=False), st.complex_numbers(min_magnitude=0.5, max_magnitude=5))
def test_the_transfer_function_equals_a_direct_numeric_solve(tmp_path_factory, rng, s):
    path = Path(tempfile.mkdtemp(dir=tmp_path_factory.getbasetemp())) / "valid.bg"
    path.write_text(valid_model(rng))
    try:
        tf = transfer_for(path)
    except MttError:
        assume(False)
    from mtt.derivation.pipeline import load

    graph = load(path)
    point = {sympy.Symbol("s"): s, **{sympy.Symbol(k): 1.7 for k in graph.unknowns}}
    G = complex(sympy.N((tf.numerator / tf.denominator).xreplace(point)))
    try:
        direct = _direct_solve(graph, point)
    except np.linalg.LinAlgError:
        assume(False)
    assert cmath.isclose(G, direct, rel_tol=1e-7, abs_tol=1e-9), path.read_text()
