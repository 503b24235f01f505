"""The derivation's time limit counts processor time: a model ends the same way on an idle
machine and on a busy one, and a stage is stopped by its loops' checks or, on the main
thread, by a timer signal inside one long computation."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from mtt.derivation import deadline
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
