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


def weir_tanks() -> NonlinearStateSpace:
    """The tanks of models/two_tanks.bg: areas 50 and 40, the upper one spilling over its
    rim (30 above its orifice) as a weir, 20 max(h1 - 30, 0)^(3/2), into the lower one.
    A power of a branch that has no real value on the other side of its surface."""
    q1, q2, u, y, a1, a2 = sympy.symbols("q1 q2 u y a1 a2")
    h1, h2 = q1 / 50, q2 / 40
    fall = a1 * sympy.sqrt(h1) + 20 * sympy.Max(h1 - 30, 0) ** R(3, 2)
    f = sympy.Matrix([u - fall, fall - a2 * sympy.sqrt(h2)])
    return NonlinearStateSpace("weir_tanks", (q1, q2), u, y, (a1, a2), {}, f, sympy.Matrix([h2]))


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
