"""The output-error reference: the fit a competent user would write with numpy and scipy.

Issue 18 names it as the reference for every speed and accuracy claim about `fit`: the
least-squares minimiser over k of the output error y - G(k) u with the record's offset and
initial state, where

- G(s, k) comes from the generated module's `transfer_function(k, **known)`;
- G is split into partial fractions, d + sum r_i / (s - p_i) (scipy.signal.residue), and
  each pole is discretised exactly for the stated hold by one matrix exponential
  (scipy.linalg.expm of the pole augmented with the input's interpolation: hold="zoh" holds
  each sample, hold="linear" interpolates linearly, a first-order hold of a piecewise-linear
  input); this stays exact when p h is tiny, where (e^(p h) - 1) / p loses digits;
- each pole's state is one first-order complex recursion run by scipy.signal.lfilter (a
  conjugate pair of poles is one recursion, its real part doubled); repeated poles are
  refused with a message (their partial fractions are not first-order);
- the offset and the initial state enter the output linearly (a constant and the modes
  e^(p_i (t - t_0))), so they are eliminated exactly at each k by linear least squares
  (variable projection: the residual is y - G(k) u projected off their columns);
- scipy.optimize.least_squares minimises the projected residual over k (several unknowns,
  bounds, its trust-region reflective method, finite-difference Jacobian).

Sampling must be regular (the recursions are lfilter's). `check` asserts that `simulate`
here agrees with the module's own `simulate` to 1e-10 of the output's peak; the benches
call it before they time anything.

    .venv/bin/python bench/output_error_peer.py     # the check on every generated module
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import linalg, optimize, signal

HOLDS = ("zoh", "linear")
REPEATED = 1e-6  # poles closer than this, relative to their size, count as repeated
REAL = 1e-9  # a pole whose imaginary part is below this, relative, is real


class PeerError(ValueError):
    """The peer cannot fit this model or record (the message says why)."""


@dataclass(frozen=True)
class Modes:
    """G(s) = direct + sum weight_i Re(residue_i / (s - pole_i)), one entry per real pole
    and per conjugate pair (weight 2, the pole with positive imaginary part)."""

    poles: np.ndarray  # complex
    residues: np.ndarray  # complex
    weights: np.ndarray  # 1 (real pole) or 2 (conjugate pair)
    direct: float

    @classmethod
    def of(cls, num, den) -> Modes:
        num, den = np.trim_zeros(np.asarray(num, float), "f"), np.asarray(den, float)
        if num.size == 0:
            num = np.zeros(1)
        if num.size > den.size:
            raise PeerError("G(s) is improper (more zeros than poles)")
        direct = 0.0
        if num.size == den.size:  # G = num[0] / den[0] + proper remainder
            direct = num[0] / den[0]
            num = (num - direct * den)[1:]
        if den.size == 1:
            return cls(np.zeros(0, complex), np.zeros(0, complex), np.zeros(0), float(direct))
        poles = np.roots(den)
        size = np.maximum(np.abs(poles), 1e-300)
        gaps = np.abs(poles[:, None] - poles[None, :])
        np.fill_diagonal(gaps, np.inf)
        if np.any(gaps < REPEATED * np.maximum(size[:, None], size[None, :])):
            raise PeerError(
                f"G(s) has repeated poles ({np.array2string(poles, precision=6)}): the peer "
                "runs one first-order recursion per distinct pole"
            )
        # residue of num/den at a simple pole p: num(p) / den'(p)
        residues = np.polyval(num, poles) / np.polyval(np.polyder(den), poles)
        real = np.abs(poles.imag) <= REAL * size
        upper = poles.imag > REAL * size
        keep = real | upper
        poles = np.where(real, poles.real, poles)[keep]
        residues = np.where(real, residues.real, residues)[keep]
        return cls(poles.astype(complex), residues.astype(complex),
                   np.where(real[keep], 1.0, 2.0), float(direct))  # fmt: skip


def discretise(pole: complex, step: float, hold: str) -> tuple[complex, complex, complex]:
    """(a, g0, g1) of x_(j+1) = a x_j + g0 u_j + g1 u_(j+1), exact for x' = p x + u with u
    held (zoh: g1 = 0) or linear between samples, from one 3x3 matrix exponential."""
    F = np.zeros((3, 3), complex)
    F[0, 0], F[0, 1], F[1, 2] = pole, 1.0, 1.0  # x' = p x + v, v' = w, w' = 0
    E = linalg.expm(F * step)
    a, first, second = E[0, 0], E[0, 1], E[0, 2]  # second = int e^(p(h-s)) s ds
    if hold == "zoh":
        return a, first, 0.0
    g1 = second / step  # u(s) = u_j + (u_(j+1) - u_j) s / h
    return a, first - g1, g1


def _regular(t: np.ndarray) -> float:
    steps = np.diff(t)
    step = (t[-1] - t[0]) / (t.size - 1)
    if steps.size and np.max(np.abs(steps - step)) > 1e-9 * max(abs(t[0]), abs(t[-1]), step):
        raise PeerError("the peer needs regular sampling (lfilter's recursions)")
    return step


def mode_states(modes: Modes, t: np.ndarray, u: np.ndarray, hold: str) -> np.ndarray:
    """(modes, samples) complex states of x_i' = p_i x_i + u from rest at t[0]."""
    if hold not in HOLDS:
        raise PeerError(f"hold must be one of {HOLDS}, not {hold!r}")
    step = _regular(t)
    states = np.empty((modes.poles.size, t.size), complex)
    for i, pole in enumerate(modes.poles):
        a, g0, g1 = discretise(pole, step, hold)
        # x_j = a x_(j-1) + g1 u_j + g0 u_(j-1); zi makes x_0 = 0 (rest at the first sample)
        states[i] = signal.lfilter([g1, g0], [1.0, -a], u, zi=[-g1 * u[0]])[0]
    return states


def simulate(module, t, u, k, *, hold: str = "linear", **known) -> np.ndarray:
    """The output from rest, as the module's `simulate` computes it, by partial fractions."""
    t, u = np.asarray(t, float), np.asarray(u, float)
    modes = Modes.of(*module.transfer_function(k, **known))
    forced = (modes.weights * modes.residues) @ mode_states(modes, t, u, hold)
    return forced.real + modes.direct * u


def nuisance_columns(modes: Modes, t: np.ndarray, offset: bool, initial_state: bool):
    """The output's columns linear in the offset and the initial state: 1 and the modes'
    free responses e^(p_i (t - t_0)) (a conjugate pair: its real and imaginary parts)."""
    columns = [np.ones_like(t)] if offset else []
    if initial_state:
        for pole, weight in zip(modes.poles, modes.weights, strict=True):
            free = np.exp(pole * (t - t[0]))
            columns += [free.real] if weight == 1 else [free.real, free.imag]
    return np.column_stack(columns) if columns else np.zeros((t.size, 0))


@dataclass(frozen=True)
class Result:
    """k: the output-error estimate; offset: the fitted output at rest (0 when not fitted);
    cost: half the sum of squared residuals there; evaluations: simulations run."""

    k: float | np.ndarray
    offset: float
    cost: float
    evaluations: int
    status: int
    message: str


def fit(module, t, u, y, *, k0, bounds=None, hold: str = "linear", offset: bool = True,
        initial_state: bool = True, x_scale=None, **known) -> Result:  # fmt: skip
    """Output-error least squares of record (t, u, y) over k from k0, the offset and the
    initial state projected out (variable projection); bounds: (lo, hi) per unknown."""
    t, u, y = (np.asarray(a, float) for a in (t, u, y))
    scalar = np.ndim(k0) == 0
    k0 = np.atleast_1d(np.asarray(k0, float))
    lo, hi = (np.full(k0.size, -np.inf), np.full(k0.size, np.inf)) if bounds is None else (
        np.array([b[0] for b in np.reshape(bounds, (-1, 2))], float),
        np.array([b[1] for b in np.reshape(bounds, (-1, 2))], float))  # fmt: skip

    def point(p):
        return float(p[0]) if scalar else p

    def projected(p):
        modes = Modes.of(*module.transfer_function(point(p), **known))
        states = mode_states(modes, t, u, hold)
        error = y - ((modes.weights * modes.residues) @ states).real - modes.direct * u
        Phi = nuisance_columns(modes, t, offset, initial_state)
        if Phi.shape[1] == 0:
            return error, np.zeros(0)
        Q, R = np.linalg.qr(Phi)
        theta = Q.T @ error
        return error - Q @ theta, linalg.solve_triangular(R, theta)

    scale = np.abs(k0) if x_scale is None else x_scale
    solution = optimize.least_squares(lambda p: projected(p)[0], k0, bounds=(lo, hi),
                                      x_scale=np.where(scale > 0, scale, 1.0))  # fmt: skip
    residual, theta = projected(solution.x)
    return Result(point(solution.x), float(theta[0]) if offset else 0.0,
                  0.5 * float(residual @ residual), int(solution.nfev), int(solution.status),
                  solution.message)  # fmt: skip


def check(module, t, u, k, *, hold: str, tolerance: float = 1e-10, **known) -> float:
    """The largest difference between this peer's and the module's simulation, relative to
    the output's peak; a PeerError above `tolerance` (the benches check before they time)."""
    mine = simulate(module, t, u, k, hold=hold, **known)
    theirs = module.simulate(t, u, k, hold=hold, **known)
    error = float(np.max(np.abs(mine - theirs)) / max(np.max(np.abs(theirs)), 1e-300))
    if not error <= tolerance:
        raise PeerError(
            f"{module.__name__}: the peer's simulation differs from the module's by "
            f"{error:.2e} of its peak (hold={hold!r}), above {tolerance:g}"
        )
    return error


def main() -> None:
    from _generated import ROOT, generated

    t = 0.01 * np.arange(2001)
    rng = np.random.default_rng(0)
    u = np.repeat(rng.choice([-1.0, 1.0], 101), 20)[: t.size]  # a PRBS held 0.2
    ramp = np.interp(t, t[::20], rng.standard_normal(t[::20].size))  # piecewise linear
    for path in sorted((ROOT / "generated").glob("*.py")):
        module = generated(path.stem)
        if not hasattr(module, "transfer_function"):
            continue
        k = module.TRUE_VALUE
        errors = [check(module, t, u, k, hold="zoh"), check(module, t, ramp, k, hold="linear")]
        print(f"{path.stem}: peer vs simulate, zoh {errors[0]:.1e}, linear {errors[1]:.1e}")
    assert math.isfinite(sum(errors))


if __name__ == "__main__":
    main()
