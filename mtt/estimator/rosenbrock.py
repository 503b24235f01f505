"""A Rosenbrock step (RODAS4) written out as straight-line Python for one model.

One step of a linearly implicit method needs the Jacobian, one LU factorisation of
W = I/(h gamma) - f_x and a solve per stage: for the few states of a bond graph model,
the factorisation is printed element by element, skipping the entries that are zero in
every state (the sparsity of f_x is known symbolically), so that the same text steps one
parameter set in Python floats or many at once in numpy arrays, with no call into LAPACK
per step. The generated module's integrators step every sample interval with it (and
sub-steps under error control), where the input changes at each sample.

The method: RODAS4 of Hairer and Wanner (Solving ODEs II, 2nd ed., section VI.4; their
code rodas.f), in the form of Sandu et al. (Atmos. Environ. 31, 1997): six stages,
order 4, an embedded order-3 solution, L-stable and stiffly accurate.
"""

from __future__ import annotations

from dataclasses import dataclass

from mtt.estimator.kernels import Kernel


@dataclass(frozen=True)
class Tableau:
    """W K_i = f(t + alpha_i h, y + sum_j a_ij K_j) + sum_j (c_ij / h) K_j + gamma_i h f_t,
    W = I / (h gamma) - f_x; y_new = y + sum_i m_i K_i; error sum_i e_i K_i."""

    gamma: float
    alpha: tuple[float, ...]
    gammas: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]  # row i: a_i0 .. a_i(i-1)
    c: tuple[tuple[float, ...], ...]
    m: tuple[float, ...]
    e: tuple[float, ...]
    order: int


_A5 = (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950)
RODAS4 = Tableau(
    gamma=0.25,
    alpha=(0.0, 0.386, 0.210, 0.630, 1.0, 1.0),
    gammas=(0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0),
    a=(
        (),
        (1.544,),
        (0.9466785280815826, 0.2557011698983284),
        (3.314825187068521, 2.896124015972201, 0.9986419139977817),
        _A5,
        (*_A5, 1.0),
    ),
    c=(
        (),
        (-5.6688,),
        (-2.430093356833875, -0.2063599157091915),
        (-0.1073529058151375, -9.594562251023355, -20.47028614809616),
        (7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160),
        (
            8.083246795921522,
            -7.981132988064893,
            -31.52159432874371,
            16.31930543123136,
            -6.058818238834054,
        ),
    ),
    m=(*_A5, 1.0, 1.0),
    e=(0.0, 0.0, 0.0, 0.0, 0.0, 1.0),
    order=4,
)


def _combination(terms: list[tuple[float, str]], start: str | None = None) -> str:
    """start + c1*v1 + c2*v2 ... as text, zero coefficients left out."""
    text = start or ""
    for coefficient, name in terms:
        if coefficient == 0:
            continue
        product = name if abs(coefficient) == 1 else f"{abs(coefficient)!r}*{name}"
        if not text:
            text = product if coefficient > 0 else f"-{product}"
        else:
            text += f" {'+' if coefficient > 0 else '-'} {product}"
    return text or "0.0"


def _unpack(names: list[str], value: str) -> list[str]:
    """The line `a, b, ... = value` (a trailing comma: one name unpacks too), none for no
    names (a model without unknowns has no sensitivities to them)."""
    return [f"{''.join(f'{name}, ' for name in names)}= {value}"] if names else []


@dataclass(frozen=True)
class _Factored:
    """W = I/(h gamma) - f_x factorised in place as L U (unit lower L, multipliers in the
    w's below the diagonal, 1/U's diagonal in p0..), without pivoting: W is dominated by
    its diagonal for the steps the error control allows. `lines` compute it (after f_x's
    entries j0_0.. and f_u's fu0.. from the kernel `jacobian`); `solve` prints a solve."""

    n: int
    lines: tuple[str, ...]
    lower: frozenset[tuple[int, int]]
    upper: frozenset[tuple[int, int]]

    @classmethod
    def of(cls, n: int, zeros: set[tuple[int, int]], state: list[str], gamma: float):
        entries = [(i, j) for i in range(n) for j in range(n)]
        lines = [
            f"_d = jacobian({', '.join(state)})",
            *_unpack([f"j{i}_{j}" for i, j in entries], f"_d[:{n * n}]"),
            *_unpack([f"fu{i}" for i in range(n)], f"_d[{n * n}:{n * n + n}]"),
            f"_g = 1.0 / ({gamma!r}*h)",
            "_hinv = 1.0 / h",
            "_hdu = h*du",
        ]
        nonzero = {(i, j) for i, j in entries if (i, j) not in zeros or i == j}
        for i, j in sorted(nonzero):
            lines.append(f"w{i}_{j} = _g - j{i}_{j}" if i == j else f"w{i}_{j} = -j{i}_{j}")
        for k in range(n):
            lines.append(f"p{k} = 1.0 / w{k}_{k}")
            for i in range(k + 1, n):
                if (i, k) not in nonzero:
                    continue
                lines.append(f"w{i}_{k} = w{i}_{k}*p{k}")
                for j in range(k + 1, n):
                    if (k, j) in nonzero:
                        old = f"w{i}_{j} - " if (i, j) in nonzero else "-"
                        lines.append(f"w{i}_{j} = {old}w{i}_{k}*w{k}_{j}")
                        nonzero.add((i, j))
        lower = frozenset((i, j) for i, j in nonzero if i > j)
        upper = frozenset((i, j) for i, j in nonzero if i < j)
        return cls(n, tuple(lines), lower, upper)

    def solve(self, target: str, r: list[str]) -> list[str]:
        """Lines solving W target = r (r's names overwritten), into target0, target1.."""
        lines = []
        for i in range(self.n):  # forward: L z = r
            terms = [(-1.0, f"w{i}_{k}*{r[k]}") for k in range(i) if (i, k) in self.lower]
            if terms:
                lines.append(f"{r[i]} = {_combination(terms, r[i])}")
        for i in reversed(range(self.n)):  # backward: U K = z
            terms = [
                (-1.0, f"w{i}_{j}*{target}{j}")
                for j in range(i + 1, self.n)
                if (i, j) in self.upper
            ]
            lines.append(f"{target}{i} = ({_combination(terms, r[i])})*p{i}")
        return lines


def step_kernel(n: int, zeros: set[tuple[int, int]], rest: list[str],
                tableau: Tableau = RODAS4) -> Kernel:  # fmt: skip
    """`rosenbrock(x0.., u, rest.., du, h) -> (x_new0.., error0..)`: one step from the state
    x at an input u changing at the rate du, the other arguments of the model's kernels
    (`rest`: unknowns, kept parameters, modes) passed through. `zeros`: the entries of f_x
    that are zero at every state (kept out of the factorisation)."""
    x = [f"x{i}" for i in range(n)]
    factored = _Factored.of(n, zeros, [*x, "u", *rest], tableau.gamma)
    body = list(factored.lines)

    def solve(stage: int) -> None:
        body.extend(factored.solve(f"K{stage}_", [f"r{stage}_{i}" for i in range(n)]))

    stages = len(tableau.alpha)
    for s in range(stages):
        if s == 0:
            y = x
        else:
            y = [f"y{i}" for i in range(n)]
            for i in range(n):
                terms = [(a, f"K{j}_{i}") for j, a in enumerate(tableau.a[s])]
                body.append(f"y{i} = {_combination(terms, x[i])}")
        time = "u" if tableau.alpha[s] == 0 else f"u + {tableau.alpha[s]!r}*_hdu"
        body += _unpack([f"f{i}" for i in range(n)], f"rhs({', '.join([*y, time, *rest])})")
        for i in range(n):
            terms = []
            if tableau.c[s]:
                inner = _combination([(c, f"K{j}_{i}") for j, c in enumerate(tableau.c[s])])
                terms.append((1.0, f"_hinv*({inner})"))
            if tableau.gammas[s]:
                terms.append((tableau.gammas[s], f"_hdu*fu{i}"))
            body.append(f"r{s}_{i} = {_combination(terms, f'f{i}')}")
        solve(s)
    results = [
        _combination([(m, f"K{s}_{i}") for s, m in enumerate(tableau.m)], x[i]) for i in range(n)
    ]
    results += [_combination([(e, f"K{s}_{i}") for s, e in enumerate(tableau.e)]) for i in range(n)]
    arguments = (*x, "u", *rest, "du", "h")
    return Kernel("rosenbrock", arguments, tuple(body), tuple(results))


def sensitivity_kernel(n: int, p: int, zeros: set[tuple[int, int]], rest: list[str],
                       tableau: Tableau = RODAS4) -> Kernel:  # fmt: skip
    """`rosenbrock_sensitivity(x0.., s0_0.., u, rest.., du, h) -> (x_new.., s_new..,
    errors..)`: one step of the states and their sensitivities S (n x (p + n), to the
    unknowns then the initial state; s{i}_{a} row by row), the method applied to the
    augmented system with its exact Jacobian [[f_x, 0], [M, I (x) f_x]]: M v = (d f_x / dx
    v) S + [d f_k / dx v, 0] comes from `second`, and the block triangle needs W's LU
    only, W K_S = r_S + M K_x for each column. `zeros`: the entries of f_x zero at every
    state (so are their derivatives)."""
    columns = p + n
    x = [f"x{i}" for i in range(n)]
    S = [[f"s{i}_{a}" for a in range(columns)] for i in range(n)]
    state = [*x, "u", *rest]
    entries = [(i, j) for i in range(n) for j in range(n)]
    factored = _Factored.of(n, zeros, state, tableau.gamma)
    body = list(factored.lines)
    solve = factored.solve

    def coupled(prefix: str, d: str) -> None:
        """prefix{i}_{a} = (d f_x S0)_{ia} + [a < p] (d f_k)_{ia} from a `second` result d."""
        body.extend(_unpack([f"{d}j{i}_{j}" for i, j in entries], f"{d}[:{n * n}]"))
        body.extend(_unpack([f"{d}k{i}_{a}" for i in range(n) for a in range(p)], f"{d}[{n * n}:]"))
        for i in range(n):
            for a in range(columns):
                terms = [(1.0, f"{d}j{i}_{j}*{S[j][a]}") for j in range(n) if (i, j) not in zeros]
                start = f"{d}k{i}_{a}" if a < p else None
                body.append(f"{prefix}{i}_{a} = {_combination(terms, start)}")

    body.append(f"_t = second({', '.join(state)}, {', '.join(['0.0'] * n)}, du)")
    coupled("st", "_t")
    stages = len(tableau.alpha)
    for s in range(stages):
        if s == 0:
            y, ys = x, S
        else:
            y = [f"y{i}" for i in range(n)]
            ys = [[f"ys{i}_{a}" for a in range(columns)] for i in range(n)]
            for i in range(n):
                terms = [(a, f"K{j}_{i}") for j, a in enumerate(tableau.a[s])]
                body.append(f"y{i} = {_combination(terms, x[i])}")
                for a in range(columns):
                    terms = [(c, f"L{j}_{i}_{a}") for j, c in enumerate(tableau.a[s])]
                    body.append(f"{ys[i][a]} = {_combination(terms, S[i][a])}")
        time = "u" if tableau.alpha[s] == 0 else f"u + {tableau.alpha[s]!r}*_hdu"
        stage = [*y, time, *rest]
        body += _unpack([f"f{i}" for i in range(n)], f"rhs({', '.join(stage)})")
        body.append(f"_e = jacobian({', '.join(stage)})")
        body += _unpack([f"e{i}_{j}" for i, j in entries], f"_e[:{n * n}]")
        sensitivity = [f"ek{i}_{a}" for i in range(n) for a in range(p)]
        body += _unpack(sensitivity, f"_e[{n * n + n}:{n * n + n + n * p}]")
        for i in range(n):
            terms = []
            if tableau.c[s]:
                inner = _combination([(c, f"K{j}_{i}") for j, c in enumerate(tableau.c[s])])
                terms.append((1.0, f"_hinv*({inner})"))
            if tableau.gammas[s]:
                terms.append((tableau.gammas[s], f"_hdu*fu{i}"))
            body.append(f"r{i} = {_combination(terms, f'f{i}')}")
        body += solve(f"K{s}_", [f"r{i}" for i in range(n)])
        body.append(
            f"_m = second({', '.join(state)}, {', '.join(f'K{s}_{i}' for i in range(n))}, 0.0)"
        )
        coupled("mk", "_m")
        for a in range(columns):
            for i in range(n):
                terms = [(1.0, f"e{i}_{j}*{ys[j][a]}") for j in range(n) if (i, j) not in zeros]
                if a < p:
                    terms.append((1.0, f"ek{i}_{a}"))
                if tableau.c[s]:
                    inner = _combination([(c, f"L{j}_{i}_{a}") for j, c in enumerate(tableau.c[s])])
                    terms.append((1.0, f"_hinv*({inner})"))
                if tableau.gammas[s]:
                    terms.append((tableau.gammas[s], f"h*st{i}_{a}"))
                terms.append((1.0, f"mk{i}_{a}"))
                body.append(f"q{i} = {_combination(terms)}")
            body += solve(f"L{s}_", [f"q{i}" for i in range(n)])
            body += [f"L{s}_{i}_{a} = L{s}_{i}" for i in range(n)]
    results = [
        _combination([(m, f"K{s}_{i}") for s, m in enumerate(tableau.m)], x[i]) for i in range(n)
    ]
    results += [
        _combination([(m, f"L{s}_{i}_{a}") for s, m in enumerate(tableau.m)], S[i][a])
        for i in range(n)
        for a in range(columns)
    ]
    results += [_combination([(e, f"K{s}_{i}") for s, e in enumerate(tableau.e)]) for i in range(n)]
    results += [
        _combination([(e, f"L{s}_{i}_{a}") for s, e in enumerate(tableau.e)])
        for i in range(n)
        for a in range(columns)
    ]
    arguments = (*x, *(name for row in S for name in row), "u", *rest, "du", "h")
    return Kernel("rosenbrock_sensitivity", arguments, tuple(body), tuple(results))
