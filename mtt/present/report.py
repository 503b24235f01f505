"""How the derived representations read: as text for people, JSON for tools, LaTeX for papers."""

from __future__ import annotations

import keyword
from collections.abc import Iterable

import sympy

from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.equations import INPUT, OUTPUT, Equations, signal_names
from mtt.derivation.theta import Theta
from mtt.derivation.transfer import LAPLACE
from mtt.language.bondgraph import BondGraph
from mtt.present.polynomials import factored, grouped, in_powers_of_s, text


def _read_as_symbol(name: str) -> bool:
    """Whether sympy's parser reads the name as a symbol: not a keyword, nor a name it
    knows (E is Euler's number, gamma a function, lambda a keyword)."""
    return not (keyword.iskeyword(name) or name in ("True", "False", "None") or name in _SYMPY)


_SYMPY = frozenset(sympy.__all__)


def expression_names(names: Iterable[str]) -> dict[str, str]:
    """How each model name is written in the expressions mtt prints, so that sympy reads
    them back as the same expression (`sympify`, `parse_expr`): a subsystem's dots as
    double underscores (motor.jm as motor__jm), and an underscore more at the end of a name
    sympy would read as something else (gamma_, E_, lambda_) or that is taken."""
    names = list(names)
    taken = set(names)
    written = {}
    for name in names:
        alias = name.replace(".", "__")
        while not _read_as_symbol(alias) or (alias != name and alias in taken):
            alias += "_"
        taken.add(alias)
        written[name] = alias
    return written


class Written:
    """The expressions of one result as text, each symbol by its `expression_names`."""

    def __init__(self, *expressions: sympy.Expr):
        symbols = set().union(*(e.free_symbols for e in expressions)) - {LAPLACE}
        ordered = sorted(symbols, key=lambda x: x.name)
        self.names = expression_names(x.name for x in ordered)  # model name -> as written
        self.renaming = {
            x: sympy.Symbol(self.names[x.name]) for x in ordered if self.names[x.name] != x.name
        }

    def __call__(self, expression: sympy.Expr) -> sympy.Expr:
        return expression.xreplace(self.renaming) if self.renaming else expression

    def text(self, expression: sympy.Expr) -> str:
        return str(self(expression))

    @property
    def table(self) -> dict[str, str]:
        """Each symbol as written -> its name in the model (dotted for a subsystem's)."""
        return {alias: name for name, alias in self.names.items()}

    @property
    def note(self) -> str | None:
        renamed = [f"{a} is {n}" for n, a in self.names.items() if a != n]
        return f"names in the expressions: {', '.join(renamed)}" if renamed else None


def appearing(theta: Theta) -> list[str]:
    """The parameters kept symbolic that the transfer function holds (one that cancels, or
    that no path from input to output reaches, is not listed)."""
    held = {x.name for x in theta.num.free_symbols | theta.den.free_symbols}
    return [name for name in theta.symbols if name in held]


def heading(model: str, source: str, target: str, unknowns, symbols) -> str:
    """`model M: from Se:v to Df:w; unknown k; symbolic none` (sources and targets may
    be several, separated by commas)."""
    names = f"unknown{'s' * (len(unknowns) > 1)} {', '.join(unknowns) or 'none'}"
    kept = ", ".join(symbols) or "none"
    return f"model {model}: from {source} to {target}; {names}; symbolic {kept}"


def _heading(theta: Theta) -> str:
    return heading(theta.model, theta.input, theta.output, theta.unknowns, appearing(theta))


def assumed_text(assumed) -> str:
    """`values substituted: a = 1, b = 2` (empty when there are none)."""
    if not assumed:
        return ""
    values = ", ".join(f"{name} = {value}" for name, value in assumed.items())
    return f"values substituted: {values}"


def _assumed(theta: Theta) -> str:
    return assumed_text(theta.assumed)


def _preamble(theta: Theta, written: Written) -> list[str]:
    """The heading, the values substituted and the names written otherwise, if any."""
    lines = [_heading(theta)]
    if theta.assumed:
        lines.append(_assumed(theta))
    return lines + ([written.note] if written.note else [])


def tf_text(theta: Theta) -> str:
    written = Written(theta.num, theta.den)
    num, den = written(theta.num), written(theta.den)
    lines = _preamble(theta, written) + [
        "",
        f"  numerator   (m = {theta.m}):  {in_powers_of_s(num)}",
        f"  denominator (n = {theta.n}):  {in_powers_of_s(den)}",
        "",
        f"  G(s) = {grouped(factored(num))} / ({text(factored(den))})",
    ]
    return "\n".join(lines)


def latex(expression: sympy.Basic) -> str:
    """sympy's LaTeX with a thin space between factors and each multi-letter name set as one
    symbol (\\mathit{mass}): math mode drops spaces, and 5 mass s^2 read as 5masss^2."""
    names = {
        symbol: rf"\mathit{{{symbol.name}}}"
        for symbol in expression.free_symbols
        if len(symbol.name) > 1 and sympy.latex(symbol) == symbol.name
    }
    return sympy.latex(expression, mul_symbol=r"\,", symbol_names=names)


def tf_latex(theta: Theta) -> str:
    num, den = (sympy.collect(sympy.expand(p), LAPLACE) for p in (theta.num, theta.den))
    return f"G(s) = \\frac{{{latex(num)}}}{{{latex(den)}}}"


def theta_text(theta: Theta) -> str:
    labels = theta.column_labels
    written = Written(theta.num, theta.den)
    cells = [[written.text(e) for e in theta.matrix.row(i)] for i in range(theta.matrix.rows)]
    rows = [["", *labels]] + [
        [label, *row] for label, row in zip(theta.row_labels, cells, strict=True)
    ]
    widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
    table = ["  " + "  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    lines = _preamble(theta, written) + [
        f"Theta: n = {theta.n}, m = {theta.m}, {_degrees(theta)}; rows "
        f"{theta.row_labels[0]}..{theta.row_labels[theta.n]}, "
        f"{'..'.join(dict.fromkeys((theta.row_labels[theta.n + 1], theta.row_labels[-1])))}; "
        f"columns {', '.join(labels)}",
        "",
        *table,
    ]
    return "\n".join(lines)


def _degrees(theta: Theta) -> str:
    if len(theta.unknowns) <= 1:
        return f"N = {theta.N}"
    each = ", ".join(f"{name} {degree}" for name, degree in theta.degrees.items())
    return f"total degree {theta.N} (in {each})"


def theta_latex(theta: Theta) -> str:
    return f"\\Theta = {latex(theta.matrix)}"


def derived_json(theta: Theta, order: int) -> dict:
    """The `tf --json` / `theta --json` record (its shape is a public contract)."""
    written = Written(theta.num, theta.den)
    return {
        "ok": True,
        "model": theta.model,
        "input": theta.input,
        "output": theta.output,
        "unknown": theta.unknown,
        "unknowns": list(theta.unknowns),
        "monomials": [list(monomial) for monomial in theta.monomials],
        "degrees": theta.degrees,
        "symbols": appearing(theta),
        "names": written.table,
        "num": written.text(theta.num),
        "den": written.text(theta.den),
        "n": theta.n,
        "m": theta.m,
        "N": theta.N,
        "theta": [[written.text(e) for e in theta.matrix.row(i)] for i in range(theta.matrix.rows)],
        "order": order,
    }


def _written_equations(equations: Equations) -> Written:
    matrices = equations.matrices().values()
    states = (sympy.Symbol(x) for x in equations.states)
    return Written(*(e for _, e in equations.relations), *matrices, *states)


def _signals(equations: Equations) -> str:
    """`u input, y output`, or with several `inputs u1 = Se:v, u2 = Se:tl; outputs ...`."""
    if not equations.several:
        return "u input, y output"
    graph = equations.causal.bondgraph
    return "; ".join(
        f"{what} " + ", ".join(
            f"{variable} = {graph.component(name).label}"
            for name, variable in signal_names(names, letter).items()
        )
        for what, names, letter in (
            ("inputs", equations.inputs, INPUT), ("outputs", equations.outputs, OUTPUT)
        )
    )  # fmt: skip


def ss_text(equations: Equations) -> str:
    graph = equations.causal.bondgraph
    written = _written_equations(equations)
    lines = [
        f"model {graph.name}: causal equations (bond variables e<n>, f<n>; "
        f"{_signals(equations)}; d<x> is dx/dt)"
    ]
    if written.note:
        lines.append(written.note)
    lines += [
        f"  {written.names.get(name, name)} = {written.text(expression)}"
        for name, expression in equations.relations
    ]
    lines += [
        "",
        "descriptor form E x' = A x + B u, y = C x + D u",
        f"  x = [{', '.join(written.names.get(x, x) for x in equations.states)}]",
    ]
    if equations.several:
        for letter, names in ((INPUT, equations.inputs), (OUTPUT, equations.outputs)):
            lines.append(f"  {letter} = [{', '.join(signal_names(names, letter).values())}]")
    for name, matrix in equations.matrices().items():
        lines += ["", f"{name} ="]
        pretty = sympy.pretty(written(matrix), use_unicode=False)
        lines += ["  " + line for line in pretty.splitlines()]
    return "\n".join(lines)


def show_json(graph: BondGraph) -> dict:
    """The `show --json` record: parameters, components, numbered bonds and subsystems
    (depth first: `motor.brush` follows `motor`)."""
    label = lambda name: graph.component(name).label  # noqa: E731
    return {
        "ok": True,
        "file": graph.source.name,
        "model": graph.name,
        "description": graph.description,
        "parameters": {
            p.name: {
                "value": None if p.value is None else str(p.value.value),
                "unknown": p.name in graph.unknowns,
                "description": p.description,
            }
            for p in graph.parameters.values()
        },
        "components": [
            {
                "name": c.name,
                "type": c.type.name,
                "argument": c.relation.text()
                if c.relation is not None
                else None
                if c.argument is None
                else str(c.argument.value),
            }
            for c in graph.components
        ],  # fmt: skip
        "bonds": [
            {"number": b.number, "tail": label(b.tail), "head": label(b.head)} for b in graph.bonds
        ],  # fmt: skip
        "input": label(graph.input),
        "output": label(graph.output),
        "inputs": [label(name) for name in graph.inputs],
        "outputs": [label(name) for name in graph.outputs],
        "unknowns": list(graph.unknowns),
        "subsystems": [
            {
                "name": sub.name,
                "file": sub.file,
                "parameters": {name: str(value.value) for name, value in sub.bindings},
                "description": sub.description,
            }
            for sub in graph.subsystems
        ],
    }


def causality_json(causal: CausalBondGraph) -> dict:
    """The `causality --json` record: the component at the stroke end of every bond."""
    graph = causal.bondgraph
    label = lambda name: graph.component(name).label  # noqa: E731
    return {
        "ok": True,
        "model": graph.name,
        "bonds": [
            {
                "number": b.number,
                "tail": label(b.tail),
                "head": label(b.head),
                "stroke": label(causal.stroke_at(b.number)),
            }
            for b in graph.bonds
        ],  # fmt: skip
        "dependent": [label(name) for name in causal.dependent],
        "loops": [label(name) for name in causal.loops],
    }


def ss_json(equations: Equations) -> dict:
    """The `ss --json` record: every entry an exact expression, as text."""
    graph = equations.causal.bondgraph
    params = equations.parametrisation
    written = _written_equations(equations)
    matrices = {
        name: [[written.text(entry) for entry in matrix.row(i)] for i in range(matrix.rows)]
        for name, matrix in equations.matrices().items()
    }
    label = lambda name: graph.component(name).label  # noqa: E731
    return {
        "ok": True,
        "model": graph.name,
        "input": label(equations.inputs[0]),
        "output": label(equations.outputs[0]),
        "inputs": [label(name) for name in equations.inputs],
        "outputs": [label(name) for name in equations.outputs],
        "unknowns": list(params.unknowns),
        "symbols": list(params.symbols),
        "names": written.table,
        "relations": [
            [written.names.get(name, name), written.text(expression)]
            for name, expression in equations.relations
        ],
        "states": [written.names.get(x, x) for x in equations.states],
        **matrices,
    }


def ss_latex(equations: Equations) -> str:
    return "\n".join(f"{name} = {latex(matrix)}" for name, matrix in equations.matrices().items())
