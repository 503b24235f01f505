"""`mtt.load`: a model file (or its text) in, a `Model` out, whose attributes are the stages
of the derivation chain, each derived once, when first asked for."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from types import MappingProxyType, ModuleType

from mtt.api import systems
from mtt.api.exact import exact
from mtt.api.results import Causality, StateSpace, Theta, TransferFunction
from mtt.derivation import pipeline
from mtt.derivation import theta as derived
from mtt.derivation.budget import chosen_budget
from mtt.derivation.causality import assign
from mtt.derivation.equations import Equations
from mtt.derivation.identifiability import Identifiability, identifiability
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.transfer import transfer_function
from mtt.estimator import codegen
from mtt.language.bondgraph import BondGraph, build
from mtt.language.diagnostics import MttError, Source
from mtt.language.parse import parse
from mtt.resources import resource_dir

TEXT_NAME = "<string>"  # how errors name a model given as text


def example(name: str) -> Path:
    """The path of an example model shipped with mtt (`mtt examples` lists them).

    >>> import mtt
    >>> mtt.example("dc_drive").name
    'dc_drive.bg'
    """
    path = resource_dir("models") / f"{name}.bg"
    if not path.is_file():
        names = ", ".join(sorted(p.stem for p in resource_dir("models").glob("*.bg")))
        raise MttError(f"no example model {name!r} (examples: {names})", kind="io")
    return path


def _source(path_or_text: str | Path) -> Source:
    if isinstance(path_or_text, str) and "\n" in path_or_text:
        return Source(TEXT_NAME, path_or_text.removeprefix("\ufeff"))
    if isinstance(path_or_text, str | Path):
        return pipeline.read_source(path_or_text)
    raise MttError(
        f"expected a file name or model text, not {type(path_or_text).__name__}", kind="bad_value"
    )


def _names(option: str, value: str | Iterable[str] | None) -> tuple[str, ...]:
    if value is None:
        return ()
    names = value.split(",") if isinstance(value, str) else value
    if not isinstance(names, Iterable) or not all(isinstance(name, str) for name in names):
        raise MttError(f"{option} takes parameter names, not {value!r}", kind="bad_value")
    return tuple(name.strip() for name in names if name.strip())


def _component(option: str, value: object) -> str | None:
    if value is None or isinstance(value, str):
        return value
    raise MttError(f"{option} takes a component TYPE:NAME, not {value!r}", kind="bad_value")


def load(
    path_or_text: str | Path,
    *,
    unknowns: str | Iterable[str] | None = None,
    input: str | None = None,
    output: str | None = None,
    set: Mapping[str, object] | None = None,
    keep: str | Iterable[str] | None = None,
    max_terms: int | None = None,
) -> Model:
    """Read and check a model: a file name (str or Path), or the model's text itself (a str
    with a line break). Raise `MttError` for anything wrong in it.

    unknowns: the parameters to identify, instead of those the model declares `unknown`
        (names, or "a,b"); with several, the estimator's k is a vector in that order.
    input, output: the source and the detector (TYPE:NAME), over the model's `input` and
        `output` statements.
    set: values replacing the file's, {name: number or exact expression text}.
    keep: parameters kept symbolic instead of substituted (names, or "a,b").
    max_terms: the most terms a polynomial of the derivation may have (default 20000);
        beyond, deriving raises MttError too_large instead of growing without bound.

    >>> import mtt
    >>> model = mtt.load('''
    ... model rc "a first-order low-pass filter"
    ... param r = 1000
    ... unknown c = 1e-6
    ... Se:v -> 1:loop
    ... 1:loop -> R:r
    ... 1:loop -> 0:out
    ... 0:out -> C:c
    ... 0:out -> De:vc
    ... ''')
    >>> model.transfer_function.expr
    1/(1000*c*s + 1)
    >>> mtt.load(model.source.text, set={"r": 2000}).transfer_function.expr
    1/(2000*c*s + 1)
    """
    if set is not None and not isinstance(set, Mapping):
        raise MttError(f"set takes a dict {{name: value}}, not {set!r}", kind="bad_value")
    overrides = {name: exact(name, value) for name, value in (set or {}).items()}
    chosen = _names("unknowns", unknowns)
    choice = ParameterChoice(
        unknowns=chosen or None,
        keep=frozenset(_names("keep", keep)),
        overrides=MappingProxyType(overrides),
        input=_component("input", input),
        output=_component("output", output),
        budget=chosen_budget(max_terms),
    )
    source = _source(path_or_text)
    graph = build(parse(source), choice.selection)
    parametrise(graph, choice)  # names in set= and keep= are checked now, not at first use
    return Model(graph, choice)


@dataclass(frozen=True, eq=False)
class Model:
    """A checked bond graph model and the choice of its parameters (see `load`).

    Each attribute is a stage of the chain bond graph -> causality -> state space ->
    transfer function -> Theta -> estimator, derived when first used, then kept.

    >>> import mtt
    >>> model = mtt.load(mtt.example("dc_drive"))
    >>> model
    Model('dc_drive', unknowns=('k',), input='Se:v', output='Df:vm')
    >>> model.theta, model.state_space
    (Theta(8x2, monomials (1, k)), StateSpace(states=('p_ia', 'p_jm', 'q_cs', 'p_jl')))
    >>> model.causality.strokes[1]
    '1:a'
    """

    bondgraph: BondGraph
    choice: ParameterChoice

    def __repr__(self) -> str:
        return (
            f"Model({self.name!r}, unknowns={self.unknowns}, input={self.input!r}, "
            f"output={self.output!r})"
        )

    @property
    def name(self) -> str:
        return self.bondgraph.name

    @property
    def description(self) -> str | None:
        return self.bondgraph.description

    @property
    def source(self) -> Source:
        """The model's text and the name errors report it by."""
        return self.bondgraph.source

    @property
    def unknowns(self) -> tuple[str, ...]:
        return self.bondgraph.unknowns

    @property
    def input(self) -> str:
        return self.bondgraph.component(self.bondgraph.input).label

    @property
    def output(self) -> str:
        return self.bondgraph.component(self.bondgraph.output).label

    @property
    def parameters(self) -> dict[str, object]:
        """Every parameter's exact value as the model gives it (None: no value)."""
        return {
            name: self.choice.overrides.get(name, p.value.value if p.value else None)
            for name, p in self.bondgraph.parameters.items()
        }

    def _repr_svg_(self) -> str:
        """The bond graph, drawn (with causal strokes when causality can be assigned)."""
        from mtt.present import drawing

        try:
            causal = self.causality.causal
        except MttError:
            causal = None
        return drawing.render(drawing.figure(self.bondgraph, causal), "svg").decode("utf-8")

    @cached_property
    def causality(self) -> Causality:
        return Causality(assign(self.bondgraph))

    @cached_property
    def _equations(self) -> Equations:
        return pipeline.equations_for(self.bondgraph, self.choice)

    @cached_property
    def state_space(self) -> StateSpace:
        return StateSpace(self._equations)

    @cached_property
    def _theta(self) -> derived.Theta:
        return derived.theta_matrix(transfer_function(self._equations))

    @property
    def transfer_function(self) -> TransferFunction:
        return TransferFunction(self._theta)

    @property
    def theta(self) -> Theta:
        return Theta(self._checked_theta())

    def _checked_theta(self) -> derived.Theta:
        if not self._theta.unknowns:
            raise MttError(
                f"{self.name} declares no unknown parameter: declare one with 'unknown NAME' "
                "or load it with unknowns='NAME'",
                kind="no_unknown",
                file=self.source.name,
            )
        return self._theta

    def identifiability(self) -> Identifiability:
        """Whether input/output data determine the unknowns, decided exactly for generic
        true values (docs/identifiability.md; `mtt identifiability`): `verdict` "global",
        "local" (`solutions` values give each transfer function) or "none" (`combinations`
        of the unknowns are all the data determine).

        >>> import mtt
        >>> mtt.load(mtt.example("rlc3")).identifiability()
        Identifiability('global', unknowns=('r', 'l', 'c'))
        >>> found = mtt.load(mtt.example("dc_motor"), unknowns="jm,jl").identifiability()
        >>> found.verdict, found.combinations
        ('none', (jl + jm,))
        """
        return identifiability(self._checked_theta())

    def to_scipy(
        self, k: object = None, /, *, dt: float | None = None, method: str = "zoh", **known
    ):
        """scipy.signal.TransferFunction at the unknowns' value k (default: the file's): a
        number, or for several a sequence in the order of `unknowns` or a dict by name; any
        free name (an unknown, a kept parameter) may also be given by keyword. With dt, the
        discrete-time system sampled every dt through a hold: method "zoh" (default),
        "foh", "bilinear" or "impulse".

        >>> import mtt
        >>> G = mtt.load(mtt.example("dc_drive")).to_scipy(10)
        >>> G.num.tolist(), G.den.tolist()
        ([10.0, 0.0, 1.0], [1.0, 10.0, 11.1, 11.0, 1.0])
        >>> motor = mtt.load(mtt.example("dc_motor"))  # unknowns ra, jl
        >>> motor.to_scipy([1, 10]).den.tolist() == motor.to_scipy(ra=1, jl=10).den.tolist()
        True
        >>> mtt.load(mtt.example("rlc")).to_scipy(0.1, dt=0.01).dt
        0.01
        """
        return systems.to_scipy(self, k, known, dt, method)

    def to_control(
        self,
        k: object = None,
        /,
        *,
        form: str = "tf",
        dt: float | None = None,
        method: str = "zoh",
        **known,
    ):
        """python-control's system at the unknowns' value k, given as to `to_scipy`: a
        transfer function (form "tf") or the state space of the bond graph's energy
        variables (form "ss"), named as the model, its input and output (and states);
        with dt, sampled as by `to_scipy` (pip install -e '.[control]' in mtt's clone).

        >>> import mtt
        >>> G = mtt.load(mtt.example("dc_drive")).to_control(10)
        >>> G.num[0][0].tolist(), G.den[0][0].tolist()
        ([100.0, 0.0, 10.0], [10.0, 100.0, 111.0, 110.0, 10.0])
        >>> float(G.dcgain()), G.name, G.input_labels, G.output_labels
        (1.0, 'dc_drive', ['Se:v'], ['Df:vm'])
        >>> mtt.load(mtt.example("rlc")).to_control(0.1, form="ss").state_labels
        ['p_l', 'q_c']
        """
        return systems.to_control(self, k, known, form, dt, method)

    def compile(self, path: str | Path) -> Path:
        """Write the standalone estimator module (numpy and scipy only) to `path`, or to
        MODEL.py inside it when it is a directory; return the file written.

        >>> import mtt, tempfile
        >>> with tempfile.TemporaryDirectory() as folder:
        ...     path = mtt.load(mtt.example("rlc")).compile(folder)
        ...     print(path.name, path.read_text().splitlines()[0][3:])
        rlc.py Identify the unknown parameter c of the model rlc from input/output data.
        """
        theta = self._checked_theta()
        try:
            target = codegen.output_path(str(path), theta)
            codegen.write_atomic(target, codegen.render(theta))
        except (OSError, ValueError) as exc:
            name = getattr(exc, "filename", None) or str(path)
            reason = getattr(exc, "strerror", None) or str(exc)
            raise MttError(f"{name}: {reason}", kind="io", file=str(path)) from None
        return target

    @cached_property
    def _estimator(self) -> ModuleType:
        return codegen.load(self._checked_theta())

    def estimator(self) -> ModuleType:
        """The generated estimator module, imported without writing a file: the same
        module `compile` writes (its docstring is its manual).

        >>> import mtt
        >>> module = mtt.load(mtt.example("rlc")).estimator()
        >>> module.UNKNOWN, module.TRUE_VALUE, (module.n, module.m, module.N)
        ('c', 0.1, (2, 1, 1))
        >>> module.transfer_function(0.1)[1].tolist()
        [0.1, 0.4, 2.0]
        """
        return self._estimator

    def simulate(self, t, u, k: object = None, **options):
        """The generated module's `simulate(t, u, k, ...)`; k defaults to the file's value(s).

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))  # G(s) = 2cs / (cs^2 + 4cs + 2), c = 0.1
        >>> t = np.linspace(0.0, 10.0, 1001)
        >>> y = rlc.simulate(t, np.ones_like(t))  # a unit step: y = exp(-2t) sin(4t) / 2
        >>> round(float(y.max()), 3), round(float(y[-1]), 3)
        (0.257, 0.0)
        """
        module = self._estimator
        k = module.TRUE_VALUE if k is None else k
        if k is None:
            raise MttError(
                f"{self.name} gives no value of its unknown: pass k", kind="missing_value"
            )
        return _delegate(module.simulate, t, u, k, **options)

    def estimate(self, t, u, y, **options):
        """The generated module's recursive `estimate(t, u, y, *, k0, ...)` -> Estimate: the
        paper's estimate at every sample, from k0.

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))
        >>> t = np.linspace(0.0, 10.0, 1001)
        >>> u = np.ones_like(t)
        >>> run = rlc.estimate(t, u, rlc.simulate(t, u), k0=0.5)
        >>> run.khat.shape, float(run.khat[0]), round(run.k, 4)  # k: the last of khat
        ((1001,), 0.5, 0.1)
        """
        return _delegate(self._estimator.estimate, t, u, y, **options)

    def fit(self, t, u, y, **options):
        """The generated module's batch `fit(t, u, y, *, method="iv", C="auto", bounds,
        offset, initial_state, hold, ...)` -> Fit: k over whole records (lists of arrays for
        several), unbiased under output noise, with k_se, ci, fit_percent and warnings.

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))
        >>> t = np.linspace(0.0, 10.0, 1001)
        >>> u = np.ones_like(t)
        >>> found = rlc.fit(t, u, rlc.simulate(t, u), offset=False, initial_state=False)
        >>> found.ok, round(found.k, 6), bool(found.k_se < 1e-6), found.ci[1] - found.ci[0] > 0
        (True, 0.1, True, True)
        """
        return _delegate(self._estimator.fit, t, u, y, **options)

    def compare(self, fit, t, u, y):
        """`fit.compare(t, u, y)` -> Comparison: a Fit of this model against a record it was
        not fitted to, with that record's own initial state and output offset estimated by
        least squares (a new record starts wherever the system was): fit_percent,
        residual_rms, offset, initial_state, fitted, residuals.

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))
        >>> t = np.linspace(0.0, 20.0, 2001)
        >>> u = rlc.estimator().input_signal("prbs", t, period=0.5)
        >>> y = rlc.simulate(t, u, hold="zoh")
        >>> found = rlc.fit(t[:1001], u[:1001], y[:1001], hold="zoh", offset=False,
        ...                 initial_state=False)  # the first 10 s, from rest
        >>> later = slice(1000, None)  # the last 10 s, not at rest, 0.3 above
        >>> compared = rlc.compare(found, t[later], u[later], y[later] + 0.3)
        >>> round(compared.fit_percent, 1), round(compared.offset, 3), compared.estimated
        (100.0, 0.3, 'its initial state and output offset estimated by least squares')
        """
        return _delegate(fit.compare, t, u, y)


def _delegate(function, *args, **options):
    """Call the generated module; its ValueErrors (bad arguments, named) become MttError."""
    try:
        return function(*args, **options)
    except ValueError as exc:
        raise MttError(str(exc), kind="bad_argument") from exc
