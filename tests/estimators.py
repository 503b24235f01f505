"""The committed estimator modules as a user imports them, their paper data, and the cost
J(k, t) computed from its definition, independently of the modules' algorithm.

The modules under test are the committed ones in generated/ (test_codegen checks that they
are what mtt generates today).
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.polynomial import Polynomial
from scipy import integrate, signal

ROOT = Path(__file__).resolve().parent.parent


def load(name: str):
    """generated/NAME.py, imported (and registered, so that its objects pickle)."""
    spec = importlib.util.spec_from_file_location(
        f"generated_{name}", ROOT / "generated" / f"{name}.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def dc_drive():
    return load("dc_drive")


@pytest.fixture(scope="module")
def absorber():
    return load("absorber")


@pytest.fixture(scope="module")
def dc_motor():
    """The DC motor with two unknowns, the armature resistance ra and the load inertia jl."""
    return load("dc_motor")


@pytest.fixture(scope="module")
def rlc3():
    """The series RLC circuit with three unknowns r, l and c."""
    return load("rlc3")


def step(t_end: float, dt: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, t_end, round(t_end / dt) + 1)
    return t, np.ones_like(t)


@pytest.fixture(scope="module")
def noisy_absorber(absorber):
    """The paper's absorber data: k = 0.72, unit step, 4 s, noise uniform in +-0.02."""
    t, u = step(4.0)
    y = absorber.simulate(t, u, 0.72) + np.random.default_rng(0).uniform(-0.02, 0.02, t.size)
    return t, u, y


def exact_cost(
    module, t, u, y, *, k0, beta, S0, C, upto: int, refine: int = 10, hold: str = "linear"
) -> Polynomial:
    """J(k, t[upto]) as a polynomial in k, from the definition (method.md section 3).

    The filtered data come from scipy's exact first-order-hold simulation of s^i/C(s) on a
    grid `refine` times finer than the samples (the interpolated data are piecewise linear,
    so this is exact; a held input is held on the fine grid, whose last point in each
    interval is one fine step from the next sample), and the weighted integral from
    Simpson's rule on that grid.
    """
    fine = np.linspace(t[0], t[upto], upto * refine + 1)
    c = module.filter_polynomial(C)
    rows = []
    held = u[np.minimum(np.searchsorted(t, fine, "right") - 1, upto)]
    for signal_samples, degree in ((y, module.n), (u, module.m)):
        data = np.interp(fine, t, signal_samples)
        if hold == "zoh" and signal_samples is u:
            data = held
        for i in range(degree + 1):
            numerator = np.r_[1.0, np.zeros(i)]  # s^i
            rows.append(signal.lsim((numerator, c), data, fine)[1])
    phi = module.theta().T @ np.array(rows)  # g(k, tau) = sum_j phi_j(tau) k^j
    weight = np.exp(-beta * (fine[-1] - fine))
    square = [
        sum(phi[a] * phi[power - a] for a in range(len(phi)) if 0 <= power - a < len(phi))
        for power in range(2 * len(phi) - 1)
    ]
    integral = [integrate.simpson(weight * q, x=fine) for q in square]
    prior = 0.5 * math.exp(-beta * (fine[-1] - fine[0])) * S0 * Polynomial([-k0, 1.0]) ** 2
    return prior + 0.5 * Polynomial(integral)
