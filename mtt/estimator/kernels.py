"""Nonlinear state equations -> the straight-line Python kernels of a generated simulator.

A kernel is a function of plain positional arguments (the states x0.., the input u, the
unknowns k0.., the kept parameters c0.., the branch modes m0..) whose body is the
expressions' common subexpressions, computed once (sympy.cse), then a tuple of results.
The same text runs on floats (bound to `math`) and on numpy arrays of any shape (bound to
numpy): one integrator steps a single record with Python floats, another a batch of
parameter sets with arrays.

Nonsmooth functions (abs, sign, min, max) are *frozen*: each occurrence becomes a
polynomial in a mode m = +-1 that selects its branch (abs(a) -> m a, max(a, b) ->
(1 + m)/2 a + (1 - m)/2 b), and its switching function s (a, or a - b) says where the branch
changes. Within a mode the right-hand side is smooth, so the integrators step it at full
order and locate the crossings of s (events) between steps; the Jacobians are those of
the branch in force. Only names made here reach the text: a model's names never do.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy
from sympy.printing.pycode import PythonCodePrinter

# The functions a kernel may call: the model language's smooth functions, the inverses the
# derivation writes, and pow_ for a power that is neither an integer nor +-1/2. Each is
# bound to math's function (floats) or numpy's (arrays) by the generated module.
FUNCTIONS = ("sqrt", "exp", "log", "sin", "cos", "tan", "tanh", "atan", "asin", "acos", "atanh")
# side(s): the branch of a kink in force at a state (its mode: 1 where s >= 0, else -1);
# tie(s): a jump's mode at a state (1, -1, or 0 on its surface: the integrators decide)
SIDE, TIE = sympy.Function("side"), sympy.Function("tie")
CONSTANTS = {sympy.pi: "pi", sympy.E: "e"}


class KernelError(ValueError):
    """The equations hold something a kernel cannot compute (an unknown function, a
    symbol that is no state, input, unknown or kept parameter)."""


@dataclass(frozen=True)
class Switch:
    """One nonsmooth site: its kind ("abs", "sign", "max", "min") and its switching
    function in frozen form (it may read the modes of the sites inside it)."""

    kind: str
    function: sympy.Expr

    @property
    def continuous(self) -> bool:
        """Whether the right-hand side is continuous where the branch changes (a kink,
        not a jump): then crossing it leaves the sensitivities continuous too."""
        return self.kind != "sign"


@dataclass(frozen=True)
class Frozen:
    """Expressions with their nonsmooth sites replaced by mode polynomials. A min or max
    chooses its branch by selectors, symbols worth 1 or 0 (`selectors`: each one's value
    in terms of its mode), kept as symbols so that a power of a branch pulls them out
    (max(z, 0)^(3/2) -> q z^(3/2)): its derivative then never divides 0 by 0."""

    expressions: tuple[sympy.Expr, ...]
    switches: tuple[Switch, ...]
    modes: tuple[sympy.Symbol, ...]
    selectors: tuple[tuple[sympy.Symbol, sympy.Expr], ...] = ()


def freeze(expressions: list[sympy.Expr]) -> Frozen:
    """Replace every abs, sign, min and max (innermost first) by its mode polynomial."""
    sites: dict[tuple[str, tuple[sympy.Expr, ...]], sympy.Symbol] = {}
    switches: list[Switch] = []
    modes: list[sympy.Symbol] = []
    selectors: list[tuple[sympy.Symbol, sympy.Expr]] = []
    chosen: dict[sympy.Symbol, tuple[sympy.Symbol, sympy.Symbol]] = {}

    def select(m: sympy.Symbol) -> tuple[sympy.Symbol, sympy.Symbol]:
        """The selectors (1 + m)/2 and (1 - m)/2 of mode m, as symbols."""
        if m not in chosen:
            up, down = sympy.Symbol(f"{m.name}p"), sympy.Symbol(f"{m.name}n")
            chosen[m] = (up, down)
            selectors.extend([(up, (1 + m) / 2), (down, (1 - m) / 2)])
        return chosen[m]

    def mode(kind: str, function: sympy.Expr, key: tuple) -> sympy.Symbol:
        if key not in sites:
            symbol = sympy.Symbol(f"m{len(modes)}")
            sites[key] = symbol
            modes.append(symbol)
            switches.append(Switch(kind, function))
        return sites[key]

    def walk(expr: sympy.Expr) -> sympy.Expr:
        if not expr.args:
            return expr
        args = [walk(arg) for arg in expr.args]
        if isinstance(expr, sympy.Abs):
            return mode("abs", args[0], ("abs", tuple(args))) * args[0]
        if isinstance(expr, sympy.sign):
            return mode("sign", args[0], ("sign", tuple(args)))
        if isinstance(expr, sympy.Max | sympy.Min):
            kind = "max" if isinstance(expr, sympy.Max) else "min"
            ordered = sorted(args, key=sympy.default_sort_key)  # a deterministic fold
            value = ordered[0]
            for arg in ordered[1:]:
                up, down = select(mode(kind, value - arg, (kind, (value, arg))))
                if kind == "min":
                    up, down = down, up
                value = up * value + down * arg  # exact in floating point: 1 and 0
            return value
        if isinstance(expr, sympy.Piecewise | sympy.Heaviside):
            raise KernelError(f"{type(expr).__name__} is not supported in a simulator: {expr}")
        if isinstance(expr, sympy.Pow) and args[1].is_positive and args[0].is_Mul:
            picked = [f for f in args[0].args if f in chosen_symbols()]
            if picked:  # (q z)^e = q z^e for a selector q (1 or 0) and e > 0
                rest = sympy.Mul(*(f for f in args[0].args if f not in picked))
                return sympy.Mul(*picked) * rest ** args[1]
        return expr.func(*args)

    def chosen_symbols() -> set[sympy.Symbol]:
        return {symbol for symbol, _ in selectors}

    frozen = tuple(walk(sympy.sympify(e)) for e in expressions)
    return Frozen(frozen, tuple(switches), tuple(modes), tuple(selectors))


def shielded(expr: sympy.Expr, selectors: tuple[tuple[sympy.Symbol, sympy.Expr], ...]):
    """expr with every branch that a selector switches off kept inside its domain
    (`selectors`: definitions among which the selector pairs mNp, mNn): in a
    product q * (...) the powers and logarithms of z become those of q z + (1 - q) (z
    where the branch is on, 1 where it is off; 1 - q is q's complement selector, so both
    are exact), and asin, acos, atanh of z those of q z. Otherwise an inactive branch,
    say (h - hmax)^(3/2) below the rim, would be evaluated outside its domain before the
    zero multiplies it."""
    named = {symbol.name: symbol for symbol, _ in selectors}
    complement = {
        named[up]: named[up[:-1] + "n"]
        for up in named
        if up.endswith("p") and up[:-1] + "n" in named
    }
    complement |= {down: up for up, down in complement.items()}

    def shield(e: sympy.Expr, q: sympy.Symbol) -> sympy.Expr:
        if not e.args:
            return e
        args = [shield(a, q) for a in e.args]
        if isinstance(e, sympy.Pow) and not (args[1].is_Integer and args[1] >= 0):
            return sympy.Pow(q * args[0] + complement[q], args[1], evaluate=False)
        if isinstance(e, sympy.log):
            return sympy.log(q * args[0] + complement[q], evaluate=False)
        if isinstance(e, sympy.asin | sympy.acos | sympy.atanh):
            return e.func(q * args[0], evaluate=False)
        return e.func(*args)

    def walk(e: sympy.Expr) -> sympy.Expr:
        if not e.args:
            return e
        if e.is_Mul:
            picked = [f for f in e.args if f in complement]
            if picked:
                rest = [shield(walk(f), picked[0]) for f in e.args if f not in picked]
                return sympy.Mul(*picked, *rest, evaluate=False)
        return e.func(*(walk(a) for a in e.args))

    return walk(sympy.sympify(expr)) if complement else expr


class _Printer(PythonCodePrinter):
    """Python text with bare function names (bound by the generated module) and names from
    `names`; every other symbol is an error."""

    def __init__(self, names: dict[sympy.Symbol, str]):
        super().__init__({"fully_qualified_modules": False, "standard": "python3"})
        self.names = names

    def _print_Symbol(self, expr):
        if expr not in self.names:
            raise KernelError(f"the symbol {expr} is no state, input, unknown or parameter")
        return self.names[expr]

    def _print_Pow(self, expr, rational=False):
        if not expr.free_symbols:
            return self._constant(expr)
        base, power = expr.args
        if power.is_Integer or power in (sympy.S.Half, -sympy.S.Half):
            return super()._print_Pow(expr, rational)
        return f"pow_({self._print(base)}, {self._print(power)})"  # math.pow: no complex

    def _constant(self, expr) -> str:
        """A number such as sqrt(6), computed here to full precision."""
        value = sympy.N(expr, 30)
        if not (value.is_real and value.is_finite):
            raise KernelError(f"the constant {expr} is not a finite real number")
        return f"({float(value)!r})"

    def _print_Function(self, expr):
        if not expr.free_symbols:
            return self._constant(expr)
        name = type(expr).__name__
        if name not in FUNCTIONS and expr.func not in (SIDE, TIE):
            raise KernelError(f"the function {name} cannot be simulated")
        return f"{name}({', '.join(self._print(a) for a in expr.args)})"

    def _print_NumberSymbol(self, expr):
        return CONSTANTS[expr]

    def _print_Exp1(self, expr):
        return "e"

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Rational(self, expr):
        return repr(float(expr))

    def _print_ImaginaryUnit(self, expr):
        raise KernelError("the equations are complex (an imaginary unit): not simulated")

    def _print_Infinity(self, expr):
        raise KernelError("the equations hold an infinite constant")

    _print_NegativeInfinity = _print_ComplexInfinity = _print_NaN = _print_Infinity


@dataclass(frozen=True)
class Kernel:
    """A kernel's text: `def name(arguments): body; return (results)`."""

    name: str
    arguments: tuple[str, ...]
    body: tuple[str, ...]  # lines "w3 = ..."
    results: tuple[str, ...]

    def source(self, indent: str = "    ") -> str:
        lines = [f"def {self.name}({', '.join(self.arguments)}):"]
        lines += [indent + line for line in self.body]
        results = "".join(f"{result}, " for result in self.results).rstrip()
        lines.append(indent + f"return ({results})")
        return "\n".join(lines)


def _check_functions(expressions: list[sympy.Expr]) -> None:
    """A KernelError for a function the generated module cannot evaluate."""
    for expr in expressions:
        for call in sympy.sympify(expr).atoms(sympy.Function):
            if type(call).__name__ not in FUNCTIONS and call.func not in (SIDE, TIE):
                raise KernelError(f"the function {type(call).__name__} cannot be simulated")


def _used(prelude: tuple[tuple[sympy.Symbol, sympy.Expr], ...], needed: set) -> list:
    """The prelude's definitions that `needed` uses, and those they use, last first."""
    wanted = []
    for symbol, value in reversed(prelude):
        if symbol in needed:
            wanted.append((symbol, value))
            needed |= value.free_symbols
    return wanted


def kernel(
    name: str,
    arguments: list[sympy.Symbol],
    expressions: list[sympy.Expr],
    names: dict[sympy.Symbol, str],
    prelude: tuple[tuple[sympy.Symbol, sympy.Expr], ...] = (),
) -> Kernel:
    """The kernel computing `expressions` from `arguments` (all named in `names`), after
    the `prelude`'s definitions (symbol = expression of the arguments) that it uses."""
    _check_functions(expressions)
    expressions = [shielded(e, prelude) for e in expressions]
    temporaries = sympy.numbered_symbols("w")
    replacements, reduced = sympy.cse(list(expressions), symbols=temporaries, optimizations=None)
    names = dict(names)
    body = []
    printer = _Printer(names)
    needed = set().union(*(sympy.sympify(e).free_symbols for e in expressions))
    wanted = _used(prelude, needed)
    for symbol, value in reversed(wanted):
        names[symbol] = symbol.name
        body.append(f"{symbol.name} = {printer.doprint(value)}")
    for symbol, value in replacements:
        text = printer.doprint(value)
        names[symbol] = symbol.name
        body.append(f"{symbol.name} = {text}")
    results = tuple(printer.doprint(e) for e in reduced)
    return Kernel(name, tuple(names[a] for a in arguments), tuple(body), results)


def field_kernel(
    name: str,
    outer: list[sympy.Symbol],
    inner: list[sympy.Symbol],
    expressions: list[sympy.Expr],
    names: dict[sympy.Symbol, str],
    prelude: tuple[tuple[sympy.Symbol, sympy.Expr], ...] = (),
) -> Kernel:
    """A kernel of the `outer` arguments that returns (field,): field, a function of the
    `inner` ones, computes `expressions`. Every subexpression free of the inner arguments
    (a product of parameters, a branch's selector times a constant) is computed once, in
    the outer function: an integrator that calls the field many times with the outer
    arguments fixed (the parameters, the branches) then does only the rest each time."""
    _check_functions(expressions)
    expressions = [shielded(e, prelude) for e in expressions]
    varying = set(inner)
    fixed = sympy.numbered_symbols("z")
    table: dict[sympy.Expr, sympy.Symbol] = {}

    def constant(e: sympy.Expr) -> sympy.Expr:
        if e.is_Atom:
            return e
        if e not in table:
            table[e] = next(fixed)
        return table[e]

    def hoist(e: sympy.Expr) -> sympy.Expr:
        if e.is_Atom:
            return e
        if not e.free_symbols & varying:
            return constant(e)
        if e.is_Add or e.is_Mul:
            free = [a for a in e.args if not a.free_symbols & varying]
            bound = [hoist(a) for a in e.args if a.free_symbols & varying]
            return e.func(*bound, *([constant(e.func(*free))] if free else []))
        return e.func(*(hoist(a) for a in e.args))

    replacements, reduced = sympy.cse(
        list(expressions), symbols=sympy.numbered_symbols("w"), optimizations=None
    )
    inside = []  # the field's own common subexpressions, their fixed parts hoisted
    for symbol, value in replacements:
        if value.free_symbols & varying:
            inside.append((symbol, hoist(value)))
            varying.add(symbol)
        else:
            table[value] = symbol  # computed once, outside
    reduced = [hoist(e) for e in reduced]
    names = dict(names) | {symbol: symbol.name for symbol, _ in replacements}
    names |= {symbol: symbol.name for symbol in table.values()}
    printer = _Printer(names)
    needed = set().union(*(sympy.sympify(e).free_symbols for e in [*table, *reduced]))
    needed |= set().union(*(value.free_symbols for _, value in inside))
    wanted = _used(prelude, needed)
    body = [f"{symbol.name} = {printer.doprint(value)}" for symbol, value in reversed(wanted)]
    for symbol, _ in wanted:
        names[symbol] = symbol.name
    body += [f"{symbol.name} = {printer.doprint(value)}" for value, symbol in table.items()]
    field = Kernel(
        "field",
        tuple(names[a] for a in inner),
        tuple(f"{symbol.name} = {printer.doprint(value)}" for symbol, value in inside),
        tuple(printer.doprint(e) for e in reduced),
    )
    body += field.source().splitlines()
    return Kernel(name, tuple(names[a] for a in outer), tuple(body), ("field",))
