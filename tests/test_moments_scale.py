"""The moments (the initialiser's data) are exact in any unit of time and for any filter speed
against the sampling: checked against a reference computed independently (scipy's lsim on a
fine grid, exact for the holds, and Simpson's rule), scaled by the time unit.

They were formed by a matrix exponential in the filter's companion coordinates, whose states
s^i w / C differ by T^i: at times in microseconds (a scale of 1e6) a Gram matrix's diagonal
came out negative, and a filter fast against the sampling lost every digit."""

from __future__ import annotations

import numpy as np
from scipy import integrate, signal


def reference(c, t, W, holds, orders, panels: int) -> np.ndarray:
    """int D D^T over the record, D = s^i w / C(s) for each signal w of W and i in its
    orders, from each interval cut into `panels` (even) Simpson panels."""
    starts = [np.linspace(a, b, panels, endpoint=False) for a, b in zip(t[:-1], t[1:], strict=True)]
    fine = np.concatenate(starts)
    fine = np.append(fine, t[-1])
    rows = []
    for w, hold, order in zip(W, holds, orders, strict=True):
        if hold == "linear":
            samples, interp = np.interp(fine, t, w), True
        else:  # held from each sample to the next: exact with lsim's own hold between points
            held = np.clip(np.searchsorted(t, fine, "right") - 1, 0, t.size - 2)
            samples, interp = w[held], False
        for i in range(order + 1):
            _, out, _ = signal.lsim((np.r_[1.0, np.zeros(i)], c), samples, fine, interp=interp)
            rows.append(out)
    D = np.array(rows)
    return integrate.simpson(D[:, None, :] * D[None, :, :], x=fine, axis=-1)


def record(dc_drive, t):
    rng = np.random.default_rng(3)
    u = dc_drive.input_signal("prbs", t, period=0.4)
    return u, dc_drive.simulate(t, u, 10.0, hold="zoh") + 0.05 * rng.standard_normal(t.size)


def test_moments_are_exact_at_any_unit_of_time(dc_drive):
    t = np.linspace(0.0, 6.0, 301)
    u, y = record(dc_drive, t)
    c = dc_drive.filter_polynomial(0.5)
    orders = (dc_drive.n, dc_drive.m)
    reference_at_1 = reference(c, t, [y, u], ("linear", "zoh"), orders, 16)
    power = np.concatenate([np.arange(order + 1) for order in orders])
    for scale in (1.0, 1e3, 1e6, 1e9):
        # s^i w / C scales as scale^-i, and the integral as scale
        expected = reference_at_1 * scale ** (1.0 - power[:, None] - power[None, :])
        got = dc_drive.moments(t * scale, u, y, C=0.5 * scale, hold="zoh", offset=False,
                               initial_state=False).XX  # fmt: skip
        assert (np.diag(got) > 0).all()  # (was negative at 1e9)
        size = np.sqrt(np.outer(np.diag(expected), np.diag(expected)))
        # (2.5e-3 at 1e6; the reference's own error: 1.2e-9)
        assert np.max(np.abs(got - expected) / size) < 1e-7, scale


def test_moments_are_exact_for_a_filter_fast_against_the_sampling(dc_drive):
    """T a tenth of the sampling interval: over an interval the filter's states decay by
    e^-10 per pole, and e^(+10) in Van Loan's exponential over the whole interval cost 9 of
    the 16 digits; now the interval is halved until the exponential stays near 1."""
    t = np.linspace(0.0, 0.5, 11)
    u, y = record(dc_drive, t)
    c = dc_drive.filter_polynomial(0.005)
    orders = (dc_drive.n, dc_drive.m)
    expected = reference(c, t, [y, u], ("linear", "zoh"), orders, 1000)
    got = dc_drive.moments(t, u, y, C=0.005, hold="zoh", offset=False, initial_state=False).XX
    size = np.sqrt(np.outer(np.diag(expected), np.diag(expected)))
    assert np.max(np.abs(got - expected) / size) < 1e-6  # (was 7.6e5; the reference's own: 6e-8)


def test_kept_filter_maps_give_the_moments_computed_afresh(dc_drive):
    """The filter's coordinates, step maps and derivatives are kept from record to record
    (`_kept_filter`): the moments of each record, with forgetting (beta scales a kept map)
    and without, in any order, are those computed afresh, bit for bit; what is kept is
    read-only."""
    t = 0.01 * np.arange(2001)  # (2000 steps: the blocked recursion's blocks of 16)
    c = dc_drive.filter_polynomial(0.3)
    rng = np.random.default_rng(5)
    records = [np.array([rng.standard_normal(t.size), np.sign(rng.standard_normal(t.size)),
                         np.ones(t.size)]) for _ in range(2)]  # fmt: skip
    holds, needs = ("linear", "zoh", "zoh"), (dc_drive.n, dc_drive.m, dc_drive.n)

    def moments(i: int, beta: float) -> np.ndarray:
        return dc_drive._filtered_moments(c, t, records[i], holds, needs, beta)

    expected = {}
    for question in [(0, 0.0), (1, 0.0), (0, 0.2), (1, 0.2)]:
        dc_drive._FILTERS.clear()
        expected[question] = moments(*question)
    dc_drive._FILTERS.clear()
    for question in [(0, 0.0), (1, 0.2), (0, 0.2), (1, 0.0), (0, 0.0), (1, 0.2)]:
        assert np.array_equal(moments(*question), expected[question]), question
    kept = [array for found in dc_drive._FILTERS.values() for array in found
            if isinstance(array, np.ndarray)]  # fmt: skip
    assert len(dc_drive._FILTERS) == 4 and kept and not any(array.flags.writeable for array in kept)
