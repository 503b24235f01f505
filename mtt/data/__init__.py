"""Data input: the records an identification works on, measured (CSV files) or simulated
(a test signal through the model, with noise), for the command line and the API alike.

Light to import (the defaults below appear in the command line's help); the readers and
the simulation are in mtt.data.records.
"""

DEFAULT_T_END, DEFAULT_DT, DEFAULT_SEED = 10.0, 0.01, 0
SIGNAL_KINDS = ("step", "prbs", "square", "multisine")
HELD_SIGNALS = ("step", "prbs", "square")  # piecewise constant between their samples
MAX_SAMPLES = 10**7


class DataError(ValueError):
    """Data or experiment settings that do not make a record; `names` are the parameters
    its message names, by their Python names (a command line says its options instead)."""

    def __init__(self, message: str, *names: str, path: str | None = None, line: int | None = None):
        super().__init__(message)
        self.names = names
        self.path, self.line = path, line  # a data file's problem: where (as a CSVError)


def default_hold(signal: str | None, measured: bool) -> str:
    """zoh for a test signal that is held by construction (the fit of a simulated PRBS must
    not read its jumps as ramps), linear for measured data and an input read from a file."""
    return "zoh" if not measured and (signal or "step") in HELD_SIGNALS else "linear"


def located(error: Exception) -> tuple[str, str, int | None] | None:
    """(kind, file, line) of a data file's problem, as --json and the API's MttError report
    it: a DataError at a file, or a generated module's CSVError ("bad_data", or its own
    kind: "io" when the file cannot be read at all); None for any other error."""
    path = getattr(error, "path", None)
    if path is None:
        return None
    return getattr(error, "kind", "bad_data"), path, getattr(error, "line", None)
