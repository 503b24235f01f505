"""The derivation's time limit counts processor time: a model ends the same way on an idle
machine and on a busy one, and a stage is stopped by its loops' checks or, on the main
thread, by a timer signal inside one long computation."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from mtt.derivation import deadline, nonlinear
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.pipeline import load
from mtt.derivation.structure import causal_for
from mtt.language.diagnostics import ModelError

MODEL = (Path(__file__).resolve().parent.parent / "models" / "rlc.bg").read_text()


def _spin(seconds: float, check: bool) -> str:
    """Busy for `seconds` of processor time (a bound, should nothing stop it)."""
    start = time.process_time()
    while time.process_time() - start < seconds:
        if check:
            deadline.check()
    return "finished"


def _stage(name: str, body):
    return deadline.timed(name, lambda graph: graph)(lambda graph: body())


def test_waiting_is_not_counted(models):
    graph = models.build(MODEL)
    with deadline.budget(0.05):
        assert _stage("a wait", lambda: time.sleep(0.3) or "slept")(graph) == "slept"


def test_a_stage_past_its_processor_time_stops_at_its_checks(models):
    graph = models.build(MODEL)
    with pytest.raises(ModelError) as caught, deadline.budget(0.2):
        _stage("a loop", lambda: _spin(10.0, check=True))(graph)
    [diagnostic] = caught.value.diagnostics
    assert diagnostic.kind == "too_large"
    assert "a loop" in diagnostic.message and "processor time" in diagnostic.message


@pytest.mark.skipif(
    threading.current_thread() is not threading.main_thread(), reason="signals: main thread"
)
def test_one_long_computation_is_interrupted_on_the_main_thread(models):
    graph = models.build(MODEL)
    with pytest.raises(ModelError) as caught, deadline.budget(0.2):
        _stage("one long step", lambda: _spin(10.0, check=False))(graph)
    assert caught.value.diagnostics[0].kind == "too_large"


def test_a_nonlinear_models_state_equations_are_under_the_limit_too():
    """A model's text can ask for intricate algebra in its nonlinear relations as well."""
    graph = load(Path(__file__).resolve().parent.parent / "models" / "two_tanks.bg")
    with pytest.raises(ModelError) as caught, deadline.budget(0.0):
        nonlinear.derive(causal_for(graph), parametrise(graph, ParameterChoice()))
    [diagnostic] = caught.value.diagnostics
    assert diagnostic.kind == "too_large" and "the state equations" in diagnostic.message
    with deadline.budget(30.0):  # and within it, the same model derives
        assert (
            len(nonlinear.derive(causal_for(graph), parametrise(graph, ParameterChoice())).states)
            == 2
        )
