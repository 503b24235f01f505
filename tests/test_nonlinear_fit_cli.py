"""`mtt fit` and `Model.fit` on a nonlinear model (issue 20 item 1): models/two_tanks.bg
fitted by prediction error with its simulator, from the small-signal model's estimate, on
records made independently by solve_ivp (tests/nonlinear_records.py), a held-out record
validated; the linear fit's own options refused with a message."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from inprocess import run_mtt
from nonlinear_records import held, noisy, pump, weir_rhs

import mtt

ROOT = Path(__file__).resolve().parent.parent
MODEL = str(ROOT / "models" / "two_tanks.bg")
TRUE = (2.0, 2.5)  # the model file's values


def _record(seed: int, high: float = 16.0):
    """A pump between 4 and `high` cm^3/s switching every 100 s at most, sampled every 5 s
    from the steady state at 4; at 16 the upper tank overflows (its level passes 30)."""
    t = np.arange(400) * 5.0
    u = pump(t, 4.0, high, 20, seed)
    states = held(weir_rhs(TRUE), t, u, [50 * (4 / 2.0) ** 2, 40 * (4 / 2.5) ** 2])
    return t, u, states[:, 1] / 40, states


def _write(path: Path, t, u, y) -> str:
    path.write_text(
        "t,u,y\n"
        + "".join(
            f"{float(a)!r},{float(b)!r},{float(c)!r}\n" for a, b, c in zip(t, u, y, strict=True)
        )
    )
    return str(path)


def test_mtt_fit_of_a_nonlinear_model_reports_and_validates_as_the_linear_one(tmp_path, capsys):
    t, u, clean, states = _record(1)
    assert states[:, 0].max() / 50 > 30  # the record reaches the overflow
    y = noisy(clean, 20, seed=1)
    new_t, new_u, new_clean, _ = _record(2)
    new_y = noisy(new_clean, 20, seed=2)
    data, held_out = (
        _write(tmp_path / "a.csv", t, u, y),
        _write(tmp_path / "b.csv", new_t, new_u, new_y),
    )
    status, out, err = run_mtt(capsys, "fit", MODEL, "--data", data, "--validate", held_out,
                               "--hold", "zoh", "--multistart", "0", "--json")  # fmt: skip
    assert status == 0, err
    found = json.loads(out)
    k, k_se = np.array(found["k"]), np.array(found["k_se"])
    assert found["ok"] and found["method"] == "pem" and found["unknowns"] == ["a1", "a2"]
    assert np.all(np.abs(k - TRUE) < 3 * k_se) and np.all(k_se < 0.02 * k)
    assert found["identifiable"] and found["shooting"] == "single"
    x0, offset = found["initial_states"][0], found["offsets"][0]
    assert x0[0] == pytest.approx(states[0, 0], rel=0.02)  # the lower level trades off with
    assert x0[1] / 40 + offset == pytest.approx(clean[0], abs=3 * np.std(y - clean))  # the offset
    origins = [start["origin"] for start in found["starts"]]
    assert origins[-1] == "the model file's values" and len(origins) <= 2
    truth = 100 * (1 - np.linalg.norm(new_y - new_clean) / np.linalg.norm(new_y - new_y.mean()))
    assert abs(found["validation"][0]["fit_percent"] - truth) < 1.0


@pytest.mark.parametrize(
    ("model", "options", "message"),
    [
        (MODEL, ["--method", "ls"], "method is an option of a linear model's fit"),
        (MODEL, ["--beta", "0.1"], "beta is an option of a linear model's fit"),
        (str(ROOT / "models" / "rlc.bg"), ["--shooting", "single"],
         "--shooting is an option of a nonlinear model's fit"),
    ],
)  # fmt: skip
def test_options_of_the_other_kind_of_fit_are_refused(tmp_path, capsys, model, options, message):
    t = np.arange(50) * 5.0
    data = _write(tmp_path / "a.csv", t, np.full(t.size, 4.0), np.full(t.size, 2.56))
    status, _, err = run_mtt(capsys, "fit", model, "--data", data, *options)
    assert status == 2 and message in err


def test_model_fit_of_a_nonlinear_model_starts_from_the_small_signal_estimate():
    t, u, clean, _ = _record(3, high=10.0)  # below the rim: the small-signal model fits
    model = mtt.load(MODEL)
    found = model.fit(t, u, noisy(clean, 20, seed=3), hold="zoh", multistart=0)
    assert found.ok and found.method == "pem", found.message
    origin, start, reached = found.starts[0]
    assert origin.startswith("the small-signal model at u = ")
    np.testing.assert_allclose(reached, found.k)
    assert np.all(np.abs(found.k - TRUE) < 3 * found.k_se)
    text = found.summary()
    assert "prediction error with the nonlinear model" in text
    assert "record 1: initial state q_upper = " in text and f"a1 = {found.k[0]:.6g} ± " in text
    with pytest.raises(mtt.MttError, match="C is an option of a linear model's fit"):
        model.fit(t, u, clean, C="(1+s)^3")


def test_many_records_of_a_nonlinear_model_go_through_mtt_batch(tmp_path):
    import mtt.batch

    model, paths, records = mtt.load(MODEL), [], []
    for seed in (4, 5, 6):
        t, u, clean, _ = _record(seed)
        records.append((t, u, noisy(clean, 20, seed=seed)))
        paths.append(_write(tmp_path / f"r{seed}.csv", *records[-1]))
    record = model.read_csv(paths[0])  # by the simulator (not the small-signal estimator)
    np.testing.assert_array_equal(record.y, records[0][2])
    batch = mtt.batch.fit_many(model, str(tmp_path / "r*.csv"), jobs=1, hold="zoh", multistart=0)
    assert batch.ok and len(batch) == 3
    for outcome in batch:
        k, k_se = outcome.result.k, outcome.result.k_se
        assert np.all(np.abs(k - TRUE) < 3 * k_se), outcome.name
    assert "prediction error with the nonlinear model" in batch.table()
    pooled = mtt.batch.fit_many(model, paths[:2], jobs=1, pooled=True, hold="zoh", multistart=0,
                                validate=paths[2])  # fmt: skip
    joint = model.simulator().fit(*map(list, zip(*records[:2], strict=True)), hold="zoh",
                                  multistart=0)  # fmt: skip
    np.testing.assert_array_equal(pooled.pooled.k, joint.k)  # the records fitted jointly
    assert pooled.pooled.ok and len(pooled.pooled.states) == 2
    assert pooled.validation[0].comparison.fit_percent > 85
    with pytest.raises(mtt.MttError, match="unexpected parameter 'bogus'"):
        mtt.batch.fit_many(model, paths, jobs=1, bogus=1.0)


def test_the_small_signal_estimator_is_derived_once_per_model_and_operating_point(monkeypatch):
    """A second start on the same model and input level reuses the estimator (the steady
    state, the linearisation, Theta, the generated module); another level derives its own."""
    from mtt.api.nonlinear_fits import linearised_start

    t, u, clean, _ = _record(3, high=10.0)
    y = noisy(clean, 20, seed=3)
    model = mtt.load(MODEL)
    derived = []
    linearise = type(model).linearise

    def counted(self, *args, **at):
        derived.append(at)
        return linearise(self, *args, **at)

    monkeypatch.setattr(type(model), "linearise", counted)
    first = linearised_start(model, t, u, y, hold="zoh")
    again = linearised_start(model, t, u, y, hold="zoh")
    assert len(derived) == 1 and again.note == first.note
    np.testing.assert_array_equal(again.k, first.k)
    linearised_start(model, t, u + 1.0, y, hold="zoh")
    assert len(derived) == 2 and derived[1]["u"] == pytest.approx(derived[0]["u"] + 1.0)


def test_mtt_fit_exits_1_where_the_nonlinear_verdict_refuses(tmp_path, capsys):
    """A constant pump at its steady state: the record carries next to nothing about the
    orifices once the initial state and offset are fitted (over 99.99 % of it theirs). The
    verdict refuses as the linear fit's does: ok False, the reason first, exit status 1."""
    t = np.arange(60) * 5.0
    y = 2.56 + 0.01 * np.random.default_rng(0).standard_normal(t.size)
    data = _write(tmp_path / "flat.csv", t, np.full(t.size, 4.0), y)
    status, out, err = run_mtt(capsys, "fit", MODEL, "--data", data, "--hold", "zoh",
                               "--multistart", "0", "--json")  # fmt: skip
    found = json.loads(out)
    assert status == 1 and not found["ok"]
    assert "poorly determined" in found["warnings"][0]
    assert any(text.startswith("the initial states and offsets take 99.99")
               for text in found["warnings"])  # fmt: skip
