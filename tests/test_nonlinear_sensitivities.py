"""Sensitivities from a state on the edge of a function's domain (issue 19 item 5): two
tanks at rest, where the orifice's sqrt has an infinite derivative. dx/dk is finite and
returned; a column of dx/dx0 whose coordinate is on the edge is NaN (not defined: a level
below zero has no value). The reference: central finite differences over solve_ivp on the
hand-written right-hand side (tests/nonlinear_records.py), independent of the simulator,
the pump kept below the upper tank's rim (no overflow kink for the differences to cross)."""

from __future__ import annotations

import numpy as np
import pytest
from nonlinear_records import held, pump, weir_rhs

import mtt

K = np.array([2.0, 2.5])
TIGHT = dict(hold="zoh", rtol=1e-11, atol=1e-13)


@pytest.fixture(scope="module")
def tanks():
    return mtt.load(mtt.example("two_tanks")).simulator()


def _differences(t, u, x0, step: float = 1e-4) -> np.ndarray:
    """dy/d(a1, a2, x0) (N, 4) by central differences of the independent simulation (the
    columns of a coordinate at 0 left NaN: it has no value below)."""
    x0 = np.asarray(x0, dtype=float)
    point = np.r_[K, x0]
    columns = []
    for i in range(point.size):
        if i >= K.size and x0[i - K.size] == 0:
            columns.append(np.full(t.size, np.nan))
            continue
        h = step * max(1.0, abs(point[i]))
        ends = []
        for sign in (1, -1):
            moved = point.copy()
            moved[i] += sign * h
            ends.append(held(weir_rhs(moved[:2]), t, u, moved[2:])[:, 1] / 40)
        columns.append((ends[0] - ends[1]) / (2 * h))
    return np.array(columns).T


def _agree(found: np.ndarray, reference: np.ndarray, tolerance: float = 1e-6) -> None:
    """Equal to `tolerance` of each column's largest value, NaN where the reference is."""
    np.testing.assert_array_equal(np.isnan(found), np.isnan(reference))
    scale = np.nanmax(np.abs(reference), axis=0, initial=0.0)
    error = np.nanmax(np.abs(found - reference), axis=0, initial=0.0)
    assert np.all(error <= tolerance * scale), error / scale


def test_from_rest_the_unknowns_columns_are_returned_and_the_initial_states_are_nan(tanks):
    """The issue's case: both tanks empty, a constant pump, four samples over 2 s."""
    t = np.linspace(0.0, 2.0, 5)
    u = np.full(t.size, 10.0)
    s = tanks.sensitivities(t, u, K, x0=[0.0, 0.0], **TIGHT)
    _agree(np.c_[s.dy_dk, s.dy_dx0][1:], _differences(t, u, [0.0, 0.0])[1:])
    assert np.all(s.dy_dk[1:] != 0) and np.all(s.dy_dk[0] == 0)
    # at the first sample x = x0 whatever x0: dx/dx0 = I there, NaN after
    np.testing.assert_array_equal(s.dx_dx0[0], np.eye(2))
    np.testing.assert_array_equal(s.dy_dx0[0], [0.0, 1 / 40])
    assert np.isnan(s.dx_dx0[1:]).all() and np.isfinite(s.dx_dk).all()


def test_from_rest_over_a_long_pump_record(tanks):
    t = np.arange(241) * 2.5
    u = pump(t, 2.0, 10.0, 24, seed=4)
    s = tanks.sensitivities(t, u, K, x0=[0.0, 0.0], **TIGHT)
    _agree(np.c_[s.dy_dk, s.dy_dx0][1:], _differences(t, u, [0.0, 0.0])[1:])
    np.testing.assert_allclose(s.y, tanks.simulate(t, u, K, x0=[0.0, 0.0], **TIGHT), rtol=1e-9)


@pytest.mark.parametrize("x0", [[500.0, 0.0], [0.0, 400.0]])
def test_one_tank_empty_only_its_own_column_is_nan(tanks, x0):
    t = np.arange(121) * 2.5
    u = pump(t, 2.0, 10.0, 24, seed=5)
    s = tanks.sensitivities(t, u, K, x0=x0, **TIGHT)
    _agree(np.c_[s.dy_dk, s.dy_dx0][1:], _differences(t, u, x0)[1:])


def test_tanks_at_rest_until_the_pump_starts(tanks):
    """No inflow for 20 samples: the state stays at rest whatever k (dx/dk = 0 there), then
    fills."""
    t = np.arange(121) * 2.5
    u = np.r_[np.zeros(20), np.full(101, 8.0)]
    s = tanks.sensitivities(t, u, K, x0=[0.0, 0.0], **TIGHT)
    assert np.all(s.x[:21] == 0) and np.all(s.dx_dk[:21] == 0)
    _agree(s.dy_dk, _differences(t, u, [0.0, 0.0])[:, :2])
    assert np.isnan(s.dx_dx0[1:]).all()


def test_rows_of_parameter_sets_from_rest_equal_one_set_at_a_time(tanks):
    t = np.arange(41) * 2.5
    u = pump(t, 2.0, 10.0, 8, seed=6)
    k = np.array([K, [1.8, 2.7], [2.2, 2.3]])
    both = tanks.sensitivities(t, u, k, x0=[[0.0, 0.0], [300.0, 0.0], [0.0, 0.0]], **TIGHT)
    for b, x0 in enumerate(([0.0, 0.0], [300.0, 0.0], [0.0, 0.0])):
        one = tanks.sensitivities(t, u, k[b], x0=x0, **TIGHT)
        np.testing.assert_array_equal(both.dy_dk[b], one.dy_dk)
        np.testing.assert_array_equal(both.dy_dx0[b], one.dy_dx0)
