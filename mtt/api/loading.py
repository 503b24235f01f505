"""`mtt.load` and `mtt.example`: a model file (or its text) in, a checked `Model` out."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from types import MappingProxyType

from mtt import files
from mtt.api.exact import exact, exact_point
from mtt.api.model import Model
from mtt.derivation import pipeline
from mtt.derivation.budget import chosen_budget
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.language.bondgraph import build
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


def _component(option: str, value: object) -> str | tuple[str, ...] | None:
    """TYPE:NAME, or several (a list, or "Se:v,Se:tl")."""
    if value is None or isinstance(value, str):
        return value
    chosen = tuple(value) if isinstance(value, Iterable) else None
    if chosen and all(isinstance(name, str) for name in chosen):
        return chosen
    raise MttError(
        f"{option} takes a component TYPE:NAME, not {value!r} (several: a list of them)",
        kind="bad_value",
    )


def load(
    path_or_text: str | Path,
    *,
    unknowns: str | Iterable[str] | None = None,
    input: str | Iterable[str] | None = None,
    output: str | Iterable[str] | None = None,
    set: Mapping[str, object] | None = None,
    keep: str | Iterable[str] | None = None,
    max_terms: int | None = None,
    at: Mapping[str, object] | None = None,
    branch: int | None = None,
    include: str | Path | Iterable[str | Path] | None = None,
) -> Model:
    """Read and check a model: a file name (str or Path), or the model's text itself (a str
    with a line break). Raise `MttError` for anything wrong in it.

    unknowns: the parameters to identify, instead of those the model declares `unknown`
        (names, or "a,b"); with several, the estimator's k is a vector in that order.
    input, output: the source and the detector (TYPE:NAME), over the model's `input` and
        `output` statements; several (a list, or "Se:v,Se:tl") for a transfer matrix.
    set: values replacing the file's, {name: number or exact expression text}.
    keep: parameters kept symbolic instead of substituted (names, or "a,b").
    max_terms: the most terms a polynomial of the derivation may have (default 30000);
        beyond, deriving raises MttError too_large instead of growing without bound.
    at, branch: a nonlinear model's operating point ({"u": 3.2}, or states by name) and
        which steady state when there are several: its stages are then those of its
        small-signal model there (see `Model.linearise`).
    include: directories subsystem files may also come from (docs/security.md).

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
        at=exact_point(at),
        branch=branch,
        include=files.directories("include", include),
    )
    source = _source(path_or_text)
    graph = build(parse(source), choice.selection)
    parametrise(graph, choice)  # names in set= and keep= are checked now, not at first use
    return Model(graph, choice)
