"""Sampled records made by scipy alone, independently of the generated modules' algorithm:
the output of scipy.signal.tf2ss(G(s, k)) from an initial state, stepped exactly over each
sampling interval (the input held, or linear between samples) by a block matrix
exponential written here from its definition."""

from __future__ import annotations

import numpy as np
from scipy import linalg, signal


def step(A, B, h, x, u0, u1, hold):
    """x(t + h) of x' = A x + B u, u held at u0 or linear from u0 to u1."""
    order = A.shape[0]
    F = np.zeros((order + 2, order + 2))
    F[:order, :order], F[:order, order] = A, B[:, 0]
    F[order, order + 1] = 1.0  # u(s) = a + b s
    E = linalg.expm(F * h)
    slope = 0.0 if hold == "zoh" else (u1 - u0) / h
    return E[:order, :order] @ x + E[:order, order] * u0 + E[:order, order + 1] * slope


def reference(module, t, u, k, x0, hold: str, **known) -> np.ndarray:
    """The output of scipy's tf2ss(G(s, k)) from x0, step by step (G from the module's
    transfer_function, checked against the paper's elsewhere)."""
    A, B, C, D = signal.tf2ss(*module.transfer_function(k, **known))
    x, y = np.array(x0, dtype=float), np.empty(t.size)
    for i in range(t.size):
        y[i] = C[0] @ x + D[0, 0] * u[i]
        if i + 1 < t.size:
            x = step(A, B, t[i + 1] - t[i], x, u[i], u[i + 1], hold)
    return y


def held(t, u, k, module, x0, **known) -> np.ndarray:
    """The output for an input held between samples on a regular grid: scipy's
    cont2discrete (zoh) and dlsim."""
    system = signal.cont2discrete(signal.tf2ss(*module.transfer_function(k, **known)), t[1] - t[0])
    return signal.dlsim(system, u, t, x0=x0)[1][:, 0]


def prbs(t, period, seed):
    """+-1, switching at random at multiples of `period`."""
    rng = np.random.default_rng(seed)
    count = int(np.floor((t[-1] - t[0]) / period)) + 1
    return rng.choice([-1.0, 1.0], count)[np.floor((t - t[0]) / period + 1e-9).astype(int)]
