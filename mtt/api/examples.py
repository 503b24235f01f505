"""The example models shipped with mtt: `mtt.examples()` lists them, `mtt.copy_examples(DIR)`
copies them (with their subsystem files) to start from; `mtt examples` prints the same."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mtt import files
from mtt.language.diagnostics import MttError
from mtt.resources import resource_dir


@dataclass(frozen=True)
class Example:
    name: str
    description: str | None  # the model line's description
    path: Path


def examples() -> list[Example]:
    """The shipped example models, by name.

    >>> import mtt
    >>> [e.name for e in mtt.examples()][:2]
    ['absorber', 'absorber_stages']
    """
    from mtt.derivation.pipeline import read_source
    from mtt.language.parse import parse

    found = []
    for path in sorted(resource_dir("models").glob("*.bg")):
        header = parse(read_source(path)).header
        found.append(Example(path.stem, header.description if header else None, path))
    return found


def copy_examples(
    directory: str | os.PathLike, *, force: bool = False, parents: bool | None = None
) -> list[Path]:
    """Copy every example model, and the subsystem files they use (models/parts/), into
    `directory`; the files written. A file there that holds the example already is left as
    it is; one that differs is kept (an MttError, nothing written) unless `force`; anything
    but a regular file is refused. Every file is checked before any is written. The
    directory is made where mtt.files allows (inside the working directory, or `parents`)."""
    source = resource_dir("models")
    copies = [_copy(path, Path(directory) / path.relative_to(source), force)
              for path in sorted(source.rglob("*.bg"))]  # fmt: skip
    parents = parents or Path(directory).is_dir()  # its subdirectories are the copy's own
    written = []
    for destination, data in (copy for copy in copies if copy is not None):
        _said_as_io(destination, files.write_atomic, destination, data, parents=parents)
        written.append(destination)
    return written


def _copy(example: Path, destination: Path, force: bool) -> tuple[Path, bytes] | None:
    """What copying one shipped model writes; None when `destination` already holds it."""

    def read(path: Path, limit: int, recorded: bool) -> bytes:
        return files.read_bytes(path, "a model file", limit, recorded=recorded)

    data = _said_as_io(destination, read, example, files.MAX_MODEL_BYTES, True)
    if not os.path.lexists(destination):
        return destination, data
    if _said_as_io(destination, read, destination, len(data), False) == data:
        return None
    if not force:
        message = f"{destination} exists and differs from the example: not replaced "
        raise MttError(message + "(--force, force=True in Python, replaces it)", kind="io",
                       file=str(destination))  # fmt: skip
    return destination, data


def _said_as_io(destination: Path, action, *arguments, **options):
    """`action(...)`, its OSError said as the user's error about `destination`."""
    try:
        return action(*arguments, **options)
    except OSError as exc:
        where = exc.filename or str(destination)
        raise MttError(f"{where}: {exc.strerror}: not replaced", kind="io", file=where) from None
