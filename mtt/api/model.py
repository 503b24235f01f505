"""A checked model (`Model`), whose attributes are the stages of the derivation chain, each
derived once, when first asked for (`mtt.load` makes one: mtt/api/loading.py)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from types import ModuleType

from mtt import files
from mtt.api import systems
from mtt.api.exact import exact, exact_point
from mtt.api.experiments import Experiments
from mtt.api.matrix import TransferMatrix
from mtt.api.results import Causality, StateSpace, SteadyStates, Theta, TransferFunction
from mtt.api.values import by_name
from mtt.derivation import pipeline
from mtt.derivation import theta as derived
from mtt.derivation.causality import assign
from mtt.derivation.equations import Equations
from mtt.derivation.equilibria import equilibria
from mtt.derivation.identifiability import Identifiability, identifiability, matrix_identifiability
from mtt.derivation.nonlinear import nonlinear_parts
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.transfer import transfer_function
from mtt.derivation.transfer_matrix import estimator_theta, transfer_matrix
from mtt.estimator import codegen, nonlinear_codegen
from mtt.language.bondgraph import BondGraph
from mtt.language.diagnostics import MttError, Source


@dataclass(frozen=True, eq=False)
class Model(Experiments):
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
    def inputs(self) -> tuple[str, ...]:
        """The sources driven, TYPE:NAME (several: a transfer matrix)."""
        return tuple(self.bondgraph.component(n).label for n in self.bondgraph.inputs)

    @property
    def outputs(self) -> tuple[str, ...]:
        return tuple(self.bondgraph.component(n).label for n in self.bondgraph.outputs)

    @property
    def input(self) -> str:
        """TYPE:NAME (several separated by commas)."""
        return ",".join(self.inputs)

    @property
    def output(self) -> str:
        return ",".join(self.outputs)

    @property
    def parameters(self) -> dict[str, object]:
        """Every parameter's exact value as the model gives it (None: no value)."""
        return {
            name: self.choice.overrides.get(name, p.value.value if p.value else None)
            for name, p in self.bondgraph.parameters.items()
        }

    def summary(self) -> str:
        """What `mtt show` prints: the parameters, components, numbered bonds, input and
        output.

        >>> import mtt
        >>> print(mtt.load(mtt.example("rlc")).summary().splitlines()[0])
        model rlc: series RLC circuit
        """
        from mtt.present.summary import describe

        return describe(self.bondgraph)

    def bode(self, *points: object):
        """The Bode diagram `mtt bode` draws, a curve per point (the unknowns' value, given
        as to `to_scipy`; none: the file's values), of every entry of G(s) with several
        inputs or outputs: `.figure()` (matplotlib), `.record()` (its --json), `.data`
        (frequency, magnitude_db, phase_deg).

        >>> import mtt
        >>> found = mtt.load(mtt.example("dc_drive")).bode(1, 10)
        >>> found.labels, found.data.magnitude_db.shape
        (('k = 1', 'k = 10'), (2, 400))
        """
        from mtt.present.bode import model_bode

        named = [by_name(self.name, self.unknowns, point) for point in points]
        return model_bode(self, named or [{}])

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
    def _system(self):
        return pipeline.state_equations_for(self.bondgraph, self.choice)

    @property
    def nonlinear(self) -> bool:
        """Whether a relation, a modulated source or a two-port makes the model nonlinear."""
        return bool(nonlinear_parts(self.bondgraph))

    @cached_property
    def state_space(self) -> StateSpace:
        """The state equations: x' = f(x, u), y = g(x, u) for a nonlinear model (about
        an operating point, when it has one: the small-signal model), E x' = A x + B u,
        y = C x + D u for a linear one."""
        if self.nonlinear and self.choice.at is None:
            return StateSpace(None, self._system[0])
        return StateSpace(self._equations)

    def equilibrium(self, u: object) -> SteadyStates:
        """The steady states at the constant input u: every branch, exact in the unknowns
        and kept parameters where sympy solves the equations, else numeric (docs/api.md)."""
        system, values = self._system
        return SteadyStates(system, equilibria(system, exact("u", u), values))

    def linearise(self, branch: int | None = None, **at: object) -> Model:
        """The model about an operating point (u=..., states by name, or x=[...]): its
        stages (state_space, transfer_function, theta, compile, fit) are those of the
        small-signal model there (docs/api.md)."""
        choice = replace(self.choice, at=exact_point(at), branch=branch)
        return Model(self.bondgraph, choice)

    @cached_property
    def transfer_matrix(self) -> TransferMatrix:
        """G(s) = B(s) / A(s) from every input to every output (also of one input and one
        output: a 1x1 matrix over the characteristic polynomial)."""
        return TransferMatrix(transfer_matrix(self._equations))

    @cached_property
    def _theta(self) -> derived.Theta:
        return derived.theta_matrix(transfer_function(self._equations))

    @property
    def transfer_function(self) -> TransferFunction:
        return TransferFunction(self._theta)

    @property
    def theta(self) -> Theta:
        return Theta(self._checked_theta(self._theta))

    def _checked_theta(self, theta: derived.Theta | None = None) -> derived.Theta:
        theta = theta or (
            estimator_theta(self._equations) if self.bondgraph.several else self._theta
        )
        if not theta.unknowns:
            raise MttError(
                f"{self.name} declares no unknown parameter: declare one with 'unknown NAME' "
                "or load it with unknowns='NAME'",
                kind="no_unknown",
                file=self.source.name,
            )
        return theta

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
        if self.bondgraph.several:  # from every entry, and what fewer signals determine
            return matrix_identifiability(self.transfer_matrix.matrix)
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

    def compile(self, path: str | Path, *, parents: bool = False) -> Path:
        """Write the standalone estimator module (numpy and scipy only) to `path`, or to
        MODEL.py inside it when it is a directory; return the file written (never over the
        model's files; new directories outside the working directory only with `parents`).
        For a nonlinear model without an operating point, the module is its simulator.

        >>> import mtt, tempfile
        >>> with tempfile.TemporaryDirectory() as folder:
        ...     path = mtt.load(mtt.example("rlc")).compile(folder)
        ...     print(path.name, path.read_text().splitlines()[0][3:])
        rlc.py Identify the unknown parameter c of the model rlc from input/output data.
        """
        try:
            if self._simulates:  # a nonlinear model, no operating point: its simulator
                system, values = self._system
                target = nonlinear_codegen.output_path(str(path), system)
                text = nonlinear_codegen.render(system, values=values, description=self.description)
            else:
                theta = self._checked_theta()
                target = codegen.output_path(str(path), theta)
                text = codegen.render(theta)
            files.write_atomic(target, text, inputs=self.bondgraph.files, parents=parents)
        except (OSError, ValueError) as exc:  # (a FileClash is an MttError already)
            name = getattr(exc, "filename", None) or str(path)
            reason = getattr(exc, "strerror", None) or str(exc)
            raise MttError(f"{name}: {reason}", kind="io", file=str(path)) from None
        return target

    @property
    def _simulates(self) -> bool:
        """Whether the model's module is the nonlinear simulator (not an estimator)."""
        return self.nonlinear and self.choice.at is None

    @cached_property
    def _simulator(self) -> ModuleType:
        system, values = self._system
        return nonlinear_codegen.load(system, values=values, description=self.description)

    def simulator(self) -> ModuleType:
        """The generated simulator of the state equations (docs/simulator.md): one record
        or many parameter sets at once, with sensitivities to the unknowns and the
        initial state; imported without writing a file, the module `compile` writes for a
        nonlinear model.

        >>> import mtt, numpy as np
        >>> tanks = mtt.load(mtt.example("two_tanks")).simulator()
        >>> t = np.linspace(0.0, 600.0, 601)
        >>> run = tanks.sensitivities(t, np.full(t.size, 10.0), x0=[1000.0, 1000.0])
        >>> run.y.shape, run.dy_dk.shape, round(float(run.y[-1]), 2)
        ((601,), (601, 2), 15.57)
        """
        return self._simulator

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
