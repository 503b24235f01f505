"""The output-error reference of the benches (bench/output_error_peer.py), loaded by path:
its simulation agrees with the modules' exact `simulate` to 1e-10, and its fit returns the
true k of noise-free records with an offset and an initial state (made by scipy's lsim)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

ROOT = Path(__file__).resolve().parent.parent


def _peer():
    spec = importlib.util.spec_from_file_location(
        "output_error_peer", ROOT / "bench" / "output_error_peer.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses need their module registered
    spec.loader.exec_module(module)
    return module


peer = _peer()


def _prbs(t: np.ndarray, period: float, seed: int) -> np.ndarray:
    switches = np.random.default_rng(seed).choice([-1.0, 1.0], int(t[-1] / period) + 2)
    return switches[np.floor(t / period + 1e-9).astype(int)]


def _ramps(t: np.ndarray, every: int, seed: int) -> np.ndarray:
    """A piecewise-linear input, its corners every `every` samples."""
    corners = np.random.default_rng(seed).standard_normal(t[::every].size)
    return np.interp(t, t[::every], corners)


@pytest.mark.parametrize("name", ["dc_drive", "absorber", "dc_motor", "rlc3"])
def test_simulation_agrees_with_the_modules(request, name):
    module = request.getfixturevalue(name)
    t = 0.01 * np.arange(1501)
    k = module.TRUE_VALUE
    assert peer.check(module, t, _prbs(t, 0.2, 1), k, hold="zoh") < 1e-10
    assert peer.check(module, t, _ramps(t, 20, 2), k, hold="linear") < 1e-10
    # and against scipy's own simulation of the held input (independent of both)
    num, den = module.transfer_function(k)
    u = _prbs(t, 0.2, 3)
    lsim = signal.lsim((num, den), u, t, interp=False)[1]
    mine = peer.simulate(module, t, u, k, hold="zoh")
    assert np.max(np.abs(mine - lsim)) < 1e-10 * np.max(np.abs(lsim))


class _Fixed:
    """A stand-in module with a fixed G(s) (the peer needs only `transfer_function`)."""

    __name__ = "fixed"

    def __init__(self, num, den):
        self.num, self.den = num, den

    def transfer_function(self, k):
        return np.array(self.num, float) * k, np.array(self.den, float)

    def simulate(self, t, u, k, *, hold):
        interp = hold == "linear"
        return signal.lsim((np.array(self.num) * k, self.den), u, t, interp=interp)[1]


def test_direct_feedthrough_and_complex_poles():
    """G(s) = (s^2 + 0.5) / (s^2 + 0.4 s + 4): a direct term and a conjugate pair."""
    fixed = _Fixed([1.0, 0.0, 0.5], [1.0, 0.4, 4.0])
    t = 0.005 * np.arange(2001)
    modes = peer.Modes.of(*fixed.transfer_function(1.0))
    assert modes.direct == 1.0 and modes.poles.size == 1 and modes.weights[0] == 2
    for hold, u in (("zoh", _prbs(t, 0.3, 4)), ("linear", _ramps(t, 7, 5))):
        assert peer.check(fixed, t, u, 1.0, hold=hold) < 1e-10


def test_repeated_poles_and_irregular_sampling_are_refused():
    double = _Fixed([1.0], [1.0, 2.0, 1.0])
    t = 0.01 * np.arange(100)
    with pytest.raises(peer.PeerError, match="repeated poles"):
        peer.simulate(double, t, np.ones_like(t), 1.0, hold="zoh")
    simple = _Fixed([1.0], [1.0, 1.0])
    with pytest.raises(peer.PeerError, match="regular sampling"):
        peer.simulate(simple, t**2, np.ones_like(t), 1.0, hold="zoh")
    with pytest.raises(peer.PeerError, match="hold"):
        peer.simulate(simple, t, np.ones_like(t), 1.0, hold="foh")


@pytest.mark.parametrize("hold", ["zoh", "linear"])
def test_fit_is_exact_with_offset_and_initial_state(dc_drive, hold):
    """The issue's short record: 3 s of the DC drive at dt 0.01, not at rest, offset 0.3;
    the record made by scipy's lsim from a random initial state, not by the peer."""
    t = 0.01 * np.arange(301)
    u = _prbs(t, 0.2, 6) if hold == "zoh" else _ramps(t, 20, 6)
    system = signal.StateSpace(*signal.tf2ss(*dc_drive.transfer_function(10.0)))
    x0 = np.random.default_rng(7).standard_normal(4)
    y = signal.lsim(system, u, t, X0=x0, interp=hold == "linear")[1] + 0.3
    result = peer.fit(dc_drive, t, u, y, k0=5.0, hold=hold, bounds=[(0.1, 100.0)])
    assert abs(result.k / 10.0 - 1) < 1e-6
    assert abs(result.offset - 0.3) < 1e-6
    # at rest without offset, the nuisances cannot absorb the start: the wrong model's fit
    # leaves a residual far above the exact one
    plain = peer.fit(dc_drive, t, u, y, k0=5.0, hold=hold, offset=False, initial_state=False)
    assert plain.cost > 1e6 * max(result.cost, 1e-30)


def test_fit_several_unknowns_within_bounds(dc_motor):
    t = 0.01 * np.arange(3001)
    u = _prbs(t, 0.5, 8)
    y = signal.lsim(dc_motor.transfer_function((1.0, 10.0)), u, t, interp=False)[1]
    result = peer.fit(dc_motor, t, u, y, k0=(2.0, 5.0), bounds=[(0.1, 10.0), (1.0, 100.0)],
                      hold="zoh")  # fmt: skip
    np.testing.assert_allclose(result.k, [1.0, 10.0], rtol=1e-6)
    pinned = peer.fit(dc_motor, t, u, y, k0=(2.0, 5.0), bounds=[(1.5, 10.0), (1.0, 100.0)],
                      hold="zoh")  # fmt: skip
    assert pinned.k[0] == pytest.approx(1.5)  # held at its bound
