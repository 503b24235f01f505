"""Reading model files, and the tree of subsystems a model brings in.

A `subsystem NAME = "FILE.bg"` statement reads another model file, relative to the
directory of the file that names it. Those files are as untrusted as the model itself:
only regular `.bg` files of bounded size are read (no devices, pipes or directories, no
absolute paths: see mtt.files), and only inside the model's own directory tree, the
shipped parts (mtt's models/ directory) or a directory the user includes (`--include
DIR`, `include=`), wherever a link leads; a file that does not begin as a model
(`model NAME`) is one error naming it, never quoting it (a link to a file of secrets must
not echo them). A file that includes itself (by any path or link) is `cyclic_subsystem`,
and the nesting depth and the number of instances are bounded, so that a few small files
cannot make the compiler do unbounded work. Each file is read and parsed once however
often it is used; its problems are reported at its own lines, followed by the chain of
subsystem statements that brought it in.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field, replace
from pathlib import Path, PurePosixPath

from mtt import files
from mtt.language.diagnostics import (
    Diagnostic,
    Inclusion,
    ModelError,
    Origin,
    Position,
    Source,
    error,
)
from mtt.language.parse import MAX_BONDS, ParsedModel, SubsystemDecl, begins_as_model, parse
from mtt.resources import resource_dir

MAX_FILE_BYTES = files.MAX_MODEL_BYTES
MAX_DEPTH = 32  # subsystems within subsystems
MAX_INSTANCES = 10_000  # subsystem statements, counted with multiplicity


def read_source(path: str | Path) -> Source:
    """A model file's text (a UTF-8 byte order mark is dropped); unreadable files are model
    errors too (kind `io`)."""
    name = str(path)
    try:
        data = files.read_bytes(path, "a model file", MAX_FILE_BYTES)
        return Source(name, data.decode("utf-8-sig"))
    except (OSError, ValueError) as exc:  # UnicodeDecodeError is a ValueError
        problem = error("io", f"cannot read the file: {_reason(exc)}")
        raise ModelError(Source(name, ""), [problem]) from None


def _reason(exc: Exception) -> str:
    return exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)


def _trees(model: Source, include: tuple[str, ...]) -> tuple[str, ...]:
    """The directories subsystem files may come from (real paths): the model's own (the
    working directory for a model given as text), mtt's shipped models, and `include`."""
    home = os.path.dirname(model.name)
    try:
        shipped = [str(resource_dir("models"))]
    except FileNotFoundError:
        shipped = []
    return tuple(os.path.realpath(d or ".") for d in (home, *shipped, *include))


def _within(real: str, trees: tuple[str, ...]) -> bool:
    return any(real.startswith(tree.rstrip(os.sep) + os.sep) for tree in trees)


def relocate(position: Position | None, origin: Origin) -> Position | None:
    """The same line and column, known to belong to `origin`'s file."""
    return None if position is None else replace(position, origin=origin)


def relocated(diagnostic: Diagnostic, origin: Origin) -> Diagnostic:
    """A diagnostic about a file (as its parser reports it) placed in the model's tree."""
    return replace(diagnostic, position=relocate(diagnostic.position, origin), origin=origin)


@dataclass
class Instance:
    """One use of a model file: the model itself, or a subsystem (of a subsystem...)."""

    name: str  # "" for the model, "motor" or "motor.brush" for a subsystem
    parsed: ParsedModel
    origin: Origin  # its file, and the subsystem statements that brought it in
    declaration: SubsystemDecl | None = None  # the statement in the parent
    children: dict[str, Instance] = field(default_factory=dict)  # the loaded subsystems

    @property
    def prefix(self) -> str:
        return f"{self.name}." if self.name else ""

    def walk(self):
        """This instance and every one below it, depth first in file order."""
        yield self
        for child in self.children.values():
            yield from child.walk()


class _Loader:
    def __init__(self, trees: tuple[str, ...]):
        self.trees = trees
        self.problems: list[Diagnostic] = []
        self.files: dict[tuple[int, int], _Parsed | None] = {}  # by (device, inode)
        self.instances = 0
        self.bonds = 0  # of every instance so far, with multiplicity
        self.full = False  # a limit was met: the other subsystem statements are not read

    def load(self, instance: Instance, ancestors: tuple[tuple[int, int], ...]) -> None:
        seen: set[str] = set()
        for decl in instance.parsed.subsystems:
            if decl.name in seen:  # a duplicate_name, which the checks report
                continue
            seen.add(decl.name)
            where = relocate(decl.position, instance.origin)
            child = self.child(instance, decl, where, ancestors)
            if child is not None:
                instance.children[decl.name] = child

    def fail(self, kind: str, message: str, where: Position) -> None:
        self.problems.append(error(kind, message, where))

    def child(self, parent: Instance, decl, where, ancestors) -> Instance | None:
        label = f"subsystem {decl.name} = {decl.file!r}"
        path = PurePosixPath(decl.file)
        if path.is_absolute() or decl.file.startswith("~") or path.suffix != ".bg":
            self.fail(
                "io",
                f"{label}: the file must be a relative path to a .bg file, read from the "
                "directory of the file that names it",
                where,
            )
            return None
        file = os.path.normpath(os.path.join(os.path.dirname(parent.origin.source.name), path))
        try:
            info = os.stat(file)
            real = os.path.realpath(file)
        except (OSError, ValueError) as exc:
            self.fail("io", f"{label}: cannot read {file}: {_reason(exc)}", where)
            return None
        identity = (info.st_dev, info.st_ino)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_FILE_BYTES:
            what = "is not a regular file" if not stat.S_ISREG(info.st_mode) else "is too large"
            self.fail("io", f"{label}: {file} {what}", where)
            return None
        if not _within(real, self.trees):
            leads = "" if real == os.path.abspath(file) else f" (it leads to {real})"
            self.fail(
                "io",
                f"{label}: {file} is outside the model's directory{leads}: subsystem files "
                "are read from the model's directory tree and mtt's shipped parts only (pass "
                "--include DIR, or include= in Python, to allow another directory)",
                where,
            )
            return None
        if identity in ancestors:
            self.fail(
                "cyclic_subsystem",
                f"{label}: {file} includes itself (through this statement)",
                where,
            )
            return None
        self.instances += 1
        if self.full:
            return None
        if len(ancestors) > MAX_DEPTH or self.instances > MAX_INSTANCES:
            self.full = True
            self.fail(
                "too_large",
                f"{label}: more than {MAX_DEPTH} levels of subsystems or {MAX_INSTANCES} "
                "subsystem instances",
                where,
            )
            return None
        name = parent.prefix + decl.name
        inclusion = Inclusion(name, parent.origin.source.name, where.line, where.column)
        if identity not in self.files:
            self.files[identity] = self.parse(file, label, where)
        parsed = self.files[identity]
        if parsed is None:  # reported where it was first read
            return None
        origin = Origin(parsed.source, (inclusion, *parent.origin.within))
        if parsed.model is None:
            self.problems += [relocated(d, origin) for d in parsed.problems]
            return None
        self.bonds += len(parsed.model.bonds)
        if self.bonds > MAX_BONDS:
            self.full = True
            message = f"{label}: the model would have more than {MAX_BONDS} bonds (a limit)"
            self.fail("too_large", message, where)
            return None
        instance = Instance(name, parsed.model, origin, decl)
        self.load(instance, (*ancestors, identity))
        return instance

    def parse(self, file: str, label: str, where: Position):
        """The file parsed, or its syntax errors (reported for each use), or None if
        unreadable (reported here)."""
        try:
            source = read_source(file)
        except ModelError as exc:
            self.fail("io", f"{label}: {exc.diagnostics[0].message}", where)
            return None
        try:
            return _Parsed(source, parse(source), ())
        except ModelError as exc:
            if not begins_as_model(source):  # perhaps not a model at all: never quote it
                message = f"{label}: {file} is not a model file (no 'model NAME' line first)"
                self.fail("io", message, where)
                return None
            return _Parsed(source, None, exc.diagnostics)


@dataclass(frozen=True)
class _Parsed:
    source: Source
    model: ParsedModel | None  # None when it has syntax errors
    problems: tuple[Diagnostic, ...]


def load_tree(
    parsed: ParsedModel, include: tuple[str, ...] = ()
) -> tuple[Instance, list[Diagnostic]]:
    """The model and every subsystem file it brings in, with the problems of reading them
    (`include`: directories subsystem files may also come from)."""
    root = Instance("", parsed, Origin(parsed.source))
    loader = _Loader(_trees(parsed.source, include))
    loader.bonds = len(parsed.bonds)
    try:
        info = os.stat(parsed.source.name)
        ancestors = ((info.st_dev, info.st_ino),)
    except (OSError, ValueError):  # a model given as text
        ancestors = ()
    loader.load(root, ancestors)
    return root, loader.problems
