"""What a Model does with records (`Model` inherits it): simulate the model, read measured
records, and run the generated module's recursive `estimate` and batch `fit` on them, the
nonlinear model's fit by its simulator (mtt/api/nonlinear_fits.py)."""

from __future__ import annotations

import math
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from mtt.api import nonlinear_fits
from mtt.api.fits import Fit, delegate
from mtt.data import located, records, signals
from mtt.data.records import Record
from mtt.language.diagnostics import MttError

if TYPE_CHECKING:
    from mtt.language.bondgraph import BondGraph


class Experiments:
    """The methods of `Model` that take records: t, u, y in, a simulation, an estimate or a
    fit out (through the generated module, its errors as MttError)."""

    bondgraph: BondGraph
    name: str
    _simulates: bool  # a nonlinear model without an operating point: its simulator
    _simulator: ModuleType
    _estimator: ModuleType

    def simulate(self, t, u, k: object = None, **options):
        """The generated module's `simulate(t, u, k, ...)`; k defaults to the file's value(s)
        (for a nonlinear model without an operating point, the simulator's: x0=, hold=...).

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))  # G(s) = 2cs / (cs^2 + 4cs + 2), c = 0.1
        >>> t = np.linspace(0.0, 10.0, 1001)
        >>> y = rlc.simulate(t, np.ones_like(t))  # a unit step: y = exp(-2t) sin(4t) / 2
        >>> round(float(y.max()), 3), round(float(y[-1]), 3)
        (0.257, 0.0)
        """
        module = self._simulator if self._simulates else self._estimator
        k = module.TRUE_VALUE if k is None else k
        if k is None:
            raise MttError(
                f"{self.name} gives no value of its unknown: pass k", kind="missing_value"
            )
        return delegate(module.simulate, t, u, k, **options)

    def read_csv(self, path: str | Path, *, columns=None) -> Record:
        """A measured record (mtt.data): the columns `columns` (time, input, output, "T,U,Y"
        or three names; default t,u,y) of a CSV file, comma-, semicolon- or tab-separated,
        its times increasing strictly; `record.t`, `.u`, `.y` go to `fit` and `estimate`
        (a nonlinear model's read by its simulator). With several inputs or outputs: the
        time and every signal (default their labels, t,Se:v,...,Df:w), `u` and `y` with a
        column per signal, as `fit` takes them."""
        module = self._simulator if self._simulates else self._estimator
        try:
            if self.bondgraph.several:
                names = signals.signal_columns(module, columns)
                return signals.read_signals(module, str(path), names)
            return records.read(module, str(path), records.columns(columns))
        except (OSError, ValueError) as exc:  # of what kind, where: as `mtt fit --json` says
            place = located(exc)  # the file's content: bad_data at its line
            kind = place[0] if place else "io" if isinstance(exc, OSError) else "bad_argument"
            line = place[2] if place else None
            raise MttError(str(exc), kind=kind, file=str(path), line=line) from None

    def estimate(
        self, t, u, y, *, k0, beta: float = 0.1, S0: float = 1e-4, C=None, hold: str = "linear",
        engine: str = "moments", bounds=None, method: str = "RK23", rtol: float = 1e-6,
        atol: float = 1e-9, max_step: float = math.inf, progress=None, **known: float,
    ):  # fmt: skip
        """The generated module's recursive `estimate` -> Estimate: the paper's estimate at
        every sample, from k0 (the module's docstring says what each keyword does; `known`:
        values of the parameters kept symbolic).

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))
        >>> t = np.linspace(0.0, 10.0, 1001)
        >>> u = np.ones_like(t)
        >>> run = rlc.estimate(t, u, rlc.simulate(t, u), k0=0.5)
        >>> run.khat.shape, float(run.khat[0]), round(run.k, 4)  # k: the last of khat
        ((1001,), 0.5, 0.1)
        """
        options = dict(k0=k0, beta=beta, S0=S0, C=C, hold=hold, engine=engine, bounds=bounds,
                       method=method, rtol=rtol, atol=atol, max_step=max_step,
                       progress=progress)  # fmt: skip
        return delegate(self._estimator.estimate, t, u, y, **options, **known)

    def fit(
        self, t, u, y, *, method: str = "pem", noise: str = "auto", C="auto", k0=None,
        bounds=None, offset: bool = True, initial_state: bool = True, hold: str = "linear",
        beta: float = 0.0, uncertainty: bool = True, **known: float,
    ) -> Fit:  # fmt: skip
        """The generated module's batch `fit` -> Fit: k over whole records (lists of arrays for
        several), the minimiser of the exact prediction error with a noise model, with k_se,
        ci, fit_percent, noise, warnings and ok; it prints as `mtt fit` does (`summary()`). With
        several inputs or outputs, u and y have a column per signal: `fit_signals`.

        >>> import mtt, numpy as np
        >>> rlc = mtt.load(mtt.example("rlc"))
        >>> t = np.linspace(0.0, 10.0, 1001)
        >>> u = np.ones_like(t)
        >>> found = rlc.fit(t, u, rlc.simulate(t, u), offset=False, initial_state=False)
        >>> found.ok, round(found.k, 6), bool(found.k_se < 1e-6), found.ci[1] - found.ci[0] > 0
        (True, 0.1, True, True)
        >>> print(found.summary().splitlines()[0])
        rlc: 1001 samples
        """
        options = dict(noise=noise, C=C, k0=k0, bounds=bounds, offset=offset,
                       initial_state=initial_state, hold=hold)  # fmt: skip
        if self.bondgraph.several:  # u, y: a column (or a dict entry) per input, per output
            return delegate(self._estimator.fit_signals, t, u, y, **options, **known)
        options.update(method=method, beta=beta, uncertainty=uncertainty)
        if self._simulates:  # a nonlinear model: prediction error (docs/nonlinear_fit.md)
            return nonlinear_fits.fit(self, t, u, y, **options, **known)
        result = delegate(self._estimator.fit, t, u, y, **options, **known)
        records = [t] if np.ndim(t[0]) == 0 else t  # one record, or a list of them
        return Fit(result, self._estimator, tuple(f"{np.size(r)} samples" for r in records))

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
        return delegate(fit.compare, t, u, y)
