"""`fit_records`: the generated modules' fit over records held anywhere that answer with sums.

mtt.batch spreads records over worker processes; the fit's steps must then be the module's
own, fed with the sums of the parts' answers. Here the parts are plain `Records` groups in
this process, so the only difference from `fit` on the list is the order of the sums.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest


class Split:
    """Records held in groups (as by several workers): each answer is the sum of the groups'."""

    def __init__(self, module, groups):
        self.groups = [module.Records(group) for group in groups]

    def shapes(self):
        return [shape for group in self.groups for shape in group.shapes()]

    def moments(self, *args):
        return sum(group.moments(*args) for group in self.groups)

    def validate(self, *args):
        return [part for group in self.groups for part in group.validate(*args)]

    def residual_sum(self, *args):
        return sum(group.residual_sum(*args) for group in self.groups)

    def prediction(self, *args):
        return [part for group in self.groups for part in group.prediction(*args)]

    def noise_sums(self, *args):
        return sum(group.noise_sums(*args) for group in self.groups)


def records(module, count: int):
    out = []
    for seed in range(count):
        size = 1500 + 250 * seed
        t = np.linspace(0.0, 0.03 * (size - 1), size)
        u = module.input_signal("prbs", t, period=1.0, seed=seed)
        y = module.with_noise(module.simulate(t, u, 10.0, hold="zoh"), 20.0, seed=seed)
        out.append((t, u, y))
    return out


@pytest.mark.parametrize("method", ["pem", "iv", "ls"])
def test_records_in_groups_fit_as_one_list(dc_drive, method):
    data = records(dc_drive, 5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = dc_drive.fit(*[list(part) for part in zip(*data, strict=True)], method=method,
                             hold="zoh")  # fmt: skip
        split = dc_drive.fit_records(Split(dc_drive, [data[:2], data[2:]]), method=method,
                                     hold="zoh", keep=False)  # fmt: skip
    assert whole.ok and split.ok
    assert split.k == pytest.approx(whole.k, rel=1e-9)
    assert split.k_se == pytest.approx(whole.k_se, rel=1e-9)
    assert split.fit_percent == pytest.approx(whole.fit_percent, rel=1e-9)
    assert split.offsets == pytest.approx(whole.offsets, rel=1e-9)
    assert split.warnings == whole.warnings and split.iterations == whole.iterations
    assert split.fitted == () and split.residuals == ()  # they stayed with the records
    assert len(whole.fitted) == 5 and whole.fitted[4].size == data[4][0].size


def test_shapes_name_records_in_warnings(dc_drive):
    """A record's label (mtt.batch gives its file name) names it in the fit's warnings."""
    data = records(dc_drive, 2)
    data[1] = (data[1][0], np.ones_like(data[1][1]), data[1][2])  # a constant input

    class Named(Split):
        def shapes(self):
            return [replace(shape, label=f"run{i}.csv") for i, shape in enumerate(super().shapes())]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = dc_drive.fit_records(Named(dc_drive, [data]), hold="zoh")
    assert any("the input is constant in run1.csv" in text for text in result.warnings)


def test_median_interval_over_records_is_exact(dc_drive):
    rng = np.random.default_rng(3)
    for count in range(1, 6):
        times = [np.cumsum(rng.integers(1, 4, rng.integers(2, 7)) * 0.1) for _ in range(count)]
        shapes = [dc_drive.Shape.of(t, np.zeros_like(t)) for t in times]
        expected = float(np.median(np.concatenate([np.diff(t) for t in times])))
        assert dc_drive._median_step(shapes) == expected


def test_shape_intervals_match_np_unique(dc_drive):
    """Shape.of counts the intervals' bit patterns where they span few (regular records, by
    counting) and sorts them otherwise: np.unique's values and counts either way."""
    rng = np.random.default_rng(5)
    counted = 0
    for trial in range(400):
        size, dt = int(rng.integers(2, 5000)), 10 ** rng.uniform(-4, 1)
        start = [0.0, rng.uniform(-100, 100)][trial % 2]
        t = [start + dt * np.arange(size), np.linspace(start, start + dt * size, size),
             start + np.cumsum(dt * rng.uniform(0.5, 1.5, size))][trial % 3]  # fmt: skip
        steps = t[1:] - t[:-1]
        bits = steps.view(np.int64)
        counted += bool(bits.max() - bits.min() < steps.size)
        shape = dc_drive.Shape.of(t, np.zeros_like(t))
        values, counts = np.unique(steps, return_counts=True)
        assert np.array_equal(shape.steps.view(np.int64), values.view(np.int64))
        assert np.array_equal(shape.counts, counts) and shape.counts.dtype == counts.dtype
    assert 50 < counted < 350  # (both ways taken)


def test_no_records_is_an_error(dc_drive):
    with pytest.raises(ValueError, match="no records to fit"):
        dc_drive.fit_records(dc_drive.Records([]))
