"""Records of nonlinear models made independently of mtt: scipy's solve_ivp (DOP853, tight
tolerances) on hand-written right-hand sides, the input held between samples (zoh), one
integration per piece of constant input, and seeded output noise. For the tests and the
bench of the nonlinear fit."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def held(rhs, t: np.ndarray, u: np.ndarray, x0) -> np.ndarray:
    """States at the sample times t (N, n) of x' = rhs(x, u) with u held from each sample to
    the next, from x0."""
    x = np.array(x0, dtype=float)
    states = np.empty((t.size, x.size))
    states[0] = x
    changes = np.flatnonzero(np.diff(u[:-1]) != 0) + 1
    bounds = [0, *changes.tolist(), t.size - 1]
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        value = float(u[a])
        run = solve_ivp(lambda _, z, v=value: rhs(z, v), (t[a], t[b]), x, method="DOP853",
                        t_eval=t[a : b + 1], rtol=1e-12, atol=1e-12)  # fmt: skip
        assert run.success, run.message
        states[a : b + 1] = run.y.T
        x = run.y[:, -1]
    return states


def pump(t: np.ndarray, low: float, high: float, period: int, seed: int) -> np.ndarray:
    """A random binary pump signal between low and high, switching every `period` samples
    at most."""
    bits = np.random.default_rng(seed).integers(0, 2, t.size // period + 1)
    return low + (high - low) * np.repeat(bits, period)[: t.size].astype(float)


def noisy(y: np.ndarray, snr_db: float, seed: int) -> np.ndarray:
    """y plus white Gaussian noise at a signal-to-noise ratio in dB (var y over the noise's)."""
    scale = float(np.std(y)) * 10 ** (-snr_db / 20)
    return y + scale * np.random.default_rng(seed).standard_normal(y.size)


def tanks_rhs(k):
    """The two tanks of nonlinear_models.two_tanks at the unknowns k = (c1, c2, kp)."""
    c1, c2, kp = k

    def rhs(x, u):
        h1, h2 = max(x[0], 0.0), max(x[1] / 1.5, 0.0)
        out = c1 * math.sqrt(h1)
        return [kp * u - out - 2 * max(h1 - 3, 0.0), out - c2 * math.sqrt(h2)]

    return rhs


def tanks_output(states: np.ndarray) -> np.ndarray:
    return states[:, 1] / 1.5


def weir_rhs(k):
    """models/two_tanks.bg at its unknowns k = (a1, a2): areas 50 and 40, the upper tank
    spilling over its rim 30 above its orifice as a weir, 20 max(h1 - 30, 0)^(3/2)."""
    a1, a2 = k

    def rhs(x, u):
        h1, h2 = max(x[0] / 50, 0.0), max(x[1] / 40, 0.0)
        fall = a1 * math.sqrt(h1) + 20 * max(h1 - 30, 0.0) ** 1.5
        return [u - fall, fall - a2 * math.sqrt(h2)]

    return rhs
