"""A second, independent derivation of a model's transfer function: the test oracle.

It shares nothing with mtt's derivation but the parsed, validated bond graph (components,
bond directions, parameters). There is no causality and no state space: every bond's
effort e<n> and flow f<n> is an unknown, the constitutive relations of the language
specification's table are restated here as linear equations in the Laplace domain
(zero initial state), and the square system M v = b (with u = 1) is solved at once by
exact Gauss-Jordan elimination over the rational functions of s and the symbolic
parameters: G(s) is the output's entry of the solution. A rank-deficient M means the
model is singular (no unique solution).

    Se   e = u (input) or e = 0          Sf  f = u (input) or f = 0
    MSe  e = its argument, with e(X) the effort of any bond of X (f(X) the flow)
    MSf  f = its argument, likewise
    De   f = 0, y = e                    Df  e = 0, y = f
    R    e = r f       C   f = c s e     I   e = i s f
    TF   (bond 1 into it, bond 2 out)    e1 = n e2, f2 = n f1
    GY   (bond 1 into it, bond 2 out)    e1 = r f2, e2 = r f1
    0    all efforts equal; sum of inward flows = sum of outward flows
    1    all flows equal; sum of inward efforts = sum of outward efforts
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

import sympy
from sympy.polys.matrices import DomainMatrix

from mtt.derivation.pipeline import load
from mtt.language.bondgraph import BondGraph, Selection

S = sympy.Symbol("s")


class Singular(Exception):
    """The oracle's equations have no unique solution."""


def parameter_values(
    graph: BondGraph,
    keep: Iterable[str] = (),
    symbolic: bool = False,
    overrides: Mapping[str, sympy.Expr] | None = None,
) -> dict[sympy.Symbol, sympy.Expr]:
    """Each parameter's value in terms of the symbols kept (the unknown, --keep, valueless)."""
    overrides = dict(overrides or {})
    raw = {
        name: overrides.get(name, p.value.value if p.value is not None else None)
        for name, p in graph.parameters.items()
    }
    kept = {  # symbolic: every parameter given a number (one given by others stays bound)
        name
        for name, value in raw.items()
        if value is None
        or (symbolic and not value.free_symbols)
        or name in set(keep)
        or name in graph.unknowns
    }
    values: dict[sympy.Symbol, sympy.Expr] = {}
    for name in kept:
        values[sympy.Symbol(name)] = sympy.Symbol(name)
    pending = [n for n in raw if n not in kept]
    while pending:  # resolve values that name other parameters (no cycles: validated)
        for name in list(pending):
            value = raw[name]
            if all(sym in values for sym in value.free_symbols):
                values[sympy.Symbol(name)] = value.xreplace(values)
                pending.remove(name)
    return values


def equations(graph: BondGraph, values: Mapping[sympy.Symbol, sympy.Expr]):
    """The rows (dicts variable -> coefficient, and a right-hand side) and the unknowns."""
    bonds = {b.number: b for b in graph.bonds}
    e = {n: sympy.Symbol(f"e{n}") for n in bonds}
    f = {n: sympy.Symbol(f"f{n}") for n in bonds}
    rows: list[sympy.Expr] = []  # each expression equals zero; U stands for the input
    U = sympy.Symbol("U")

    for component in graph.components:
        name, kind = component.name, component.type.name
        touching = [b for b in bonds.values() if name in (b.tail, b.head)]
        p = component.argument.value.xreplace(values) if component.argument is not None else None
        if p is not None and p.has(sympy.zoo, sympy.oo, sympy.nan):
            raise Singular(f"the parameter of {component.label} is infinite")
        if kind in ("Se", "Sf", "MSe", "MSf", "De", "Df", "R", "C", "I"):
            (bond,) = touching
            E, F = e[bond.number], f[bond.number]
            if kind in ("MSe", "MSf"):
                signals = {}
                for use in component.argument.signals:
                    read = next(b.number for b in bonds.values() if use.target in (b.tail, b.head))
                    signals[use.symbol] = (e if use.kind == "e" else f)[read]
                rows.append((E if kind == "MSe" else F) - p.xreplace(signals))
            elif kind == "Se":
                rows.append(E - (U if name == graph.input else 0))
            elif kind == "Sf":
                rows.append(F - (U if name == graph.input else 0))
            elif kind == "De":
                rows.append(F)
            elif kind == "Df":
                rows.append(E)
            elif kind == "R":
                rows.append(E - p * F)
            elif kind == "C":
                rows.append(F - p * S * E)
            else:
                rows.append(E - p * S * F)
        elif kind in ("TF", "GY"):
            (one,) = [b.number for b in touching if b.head == name]
            (two,) = [b.number for b in touching if b.tail == name]
            if kind == "TF":
                rows += [e[one] - p * e[two], f[two] - p * f[one]]
            else:
                rows += [e[one] - p * f[two], e[two] - p * f[one]]
        else:
            common, summed = (e, f) if kind == "0" else (f, e)
            numbers = [b.number for b in touching]
            rows += [common[n] - common[numbers[0]] for n in numbers[1:]]
            rows.append(sum((summed[b.number] if b.head == name else -summed[b.number])
                            for b in touching))  # fmt: skip
    unknowns = [v for n in sorted(bonds) for v in (e[n], f[n])]
    output = graph.component(graph.output)
    (out_bond,) = [b.number for b in bonds.values() if output.name in (b.tail, b.head)]
    y = e[out_bond] if output.type.name == "De" else f[out_bond]
    return rows, unknowns, U, y


def transfer(graph: BondGraph, values: Mapping[sympy.Symbol, sympy.Expr]) -> sympy.Expr:
    """G(s) = y/u by exact Gauss-Jordan elimination; raise `Singular` if M is singular."""
    rows, unknowns, U, y = equations(graph, values)
    if len(rows) != len(unknowns):
        raise AssertionError(f"{len(rows)} equations for {len(unknowns)} unknowns")
    expanded = [sympy.expand(row) for row in rows]
    M = sympy.Matrix([[row.coeff(v) for v in unknowns] + [-row.coeff(U)] for row in expanded])
    augmented = DomainMatrix.from_Matrix(M)
    field = augmented.domain.get_field()
    reduced, pivots = augmented.convert_to(field).to_sparse().rref()
    if pivots != tuple(range(len(unknowns))):
        raise Singular("the equations have no unique solution")
    return sympy.cancel(field.to_sympy(reduced[unknowns.index(y), len(unknowns)].element))


def oracle_tf(
    path: str | Path,
    unknown: str | None = None,
    keep: Iterable[str] = (),
    symbolic: bool = False,
    overrides: Mapping[str, sympy.Expr] | None = None,
    input: str | None = None,
    output: str | None = None,
) -> sympy.Expr:
    """The transfer function of the model file at `path`, derived independently of mtt
    (from `input` to `output`, TYPE:NAME, over the file's: an entry of a transfer matrix,
    the other sources set to zero)."""
    graph = load(path, Selection(None if unknown is None else (unknown,), input, output))
    return transfer(graph, parameter_values(graph, keep, symbolic, overrides))
