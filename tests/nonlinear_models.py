"""Nonlinear state equations written by hand (sympy), for the simulator's tests and bench.

Two tanks in cascade (orifice outflows, the upper tank overflowing over a weir) and a
pendulum arm on a DC motor (gravity, Coulomb friction smoothed by tanh or as sign).
"""

from __future__ import annotations

import sympy

from mtt.derivation.nonlinear import NonlinearStateSpace

R = sympy.Rational


def two_tanks() -> NonlinearStateSpace:
    """Volumes q1, q2 (areas 1 and 3/2); pump flow kp u into tank 1; orifice flows c1
    sqrt(h1) into tank 2 and c2 sqrt(h2) out; the upper tank spills 2 (h1 - 3) over its
    weir above the level 3. Output: the lower tank's level h2. Unknowns c1, c2, kp."""
    q1, q2, u, y = sympy.symbols("q1 q2 u y")
    c1, c2, kp = sympy.symbols("c1 c2 kp")
    h1, h2 = q1, q2 / R(3, 2)
    over = 2 * sympy.Max(h1 - 3, 0)
    f = sympy.Matrix(
        [kp * u - c1 * sympy.sqrt(h1) - over, c1 * sympy.sqrt(h1) - c2 * sympy.sqrt(h2)]
    )
    return NonlinearStateSpace("two_tanks", (q1, q2), u, y, (c1, c2, kp), {}, f, sympy.Matrix([h2]))


TWO_TANKS_K = (0.5, 0.4, 1.0)


def pendulum(friction: str = "tanh") -> NonlinearStateSpace:
    """Flux linkage lam (inductance 1/20, resistance 1), angular momentum h (inertia J),
    angle th; torque constant 1/2, gravity 1/2 sin(th), viscous 1/100 and Coulomb fc
    friction (fc tanh(w/(1/50)) or fc sign(w)). Input: the voltage; output: the angle.
    Unknowns J, fc."""
    lam, h, th, u, y = sympy.symbols("lam h th u y")
    J, fc = sympy.symbols("J fc")
    i, w = 20 * lam, h / J
    coulomb = fc * (sympy.tanh(50 * w) if friction == "tanh" else sympy.sign(w))
    f = sympy.Matrix(
        [u - i - R(1, 2) * w, R(1, 2) * i - R(1, 2) * sympy.sin(th) - coulomb - w / 100, w]
    )
    return NonlinearStateSpace(
        f"pendulum_{friction}", (lam, h, th), u, y, (J, fc), {}, f, sympy.Matrix([th])
    )


PENDULUM_K = (0.05, 0.1)
