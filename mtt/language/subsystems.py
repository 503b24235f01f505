"""Reading model files, and the tree of subsystems a model brings in.

A `subsystem NAME = "FILE.bg"` statement reads another model file, relative to the
directory of the file that names it. Those files are as untrusted as the model itself:
only regular `.bg` files of bounded size are read (no devices, pipes or directories, no
absolute paths), a file that includes itself (by any path or link) is
`cyclic_subsystem`, and the nesting depth and the number of instances are bounded, so
that a few small files cannot make the compiler do unbounded work. Each file is read and
parsed once however often it is used; its problems are reported at its own lines,
followed by the chain of subsystem statements that brought it in.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field, replace
from pathlib import Path, PurePosixPath

from mtt.language.diagnostics import (
    Diagnostic,
    Inclusion,
    ModelError,
    Origin,
    Position,
    Source,
    error,
)
from mtt.language.parse import MAX_BONDS, ParsedModel, SubsystemDecl, parse

MAX_FILE_BYTES = 1 << 20  # a model file of a megabyte is already absurd
MAX_DEPTH = 32  # subsystems within subsystems
MAX_INSTANCES = 10_000  # subsystem statements, counted with multiplicity


def read_source(path: str | Path) -> Source:
    """A model file's text (a UTF-8 byte order mark is dropped); unreadable files are model
    errors too (kind `io`)."""
    name = str(path)
    try:
        with open(path, "rb") as file:
            data = file.read(MAX_FILE_BYTES + 1)
        if len(data) > MAX_FILE_BYTES:
            raise ValueError(f"larger than {MAX_FILE_BYTES} bytes (a limit)")
        return Source(name, data.decode("utf-8-sig"))
    except (OSError, ValueError) as exc:  # UnicodeDecodeError is a ValueError
        problem = error("io", f"cannot read the file: {_reason(exc)}")
        raise ModelError(Source(name, ""), [problem]) from None


def _reason(exc: Exception) -> str:
    return exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)


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
    def __init__(self):
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
        except (OSError, ValueError) as exc:
            self.fail("io", f"{label}: cannot read {file}: {_reason(exc)}", where)
            return None
        identity = (info.st_dev, info.st_ino)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_FILE_BYTES:
            what = "is not a regular file" if not stat.S_ISREG(info.st_mode) else "is too large"
            self.fail("io", f"{label}: {file} {what}", where)
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
            return _Parsed(source, None, exc.diagnostics)


@dataclass(frozen=True)
class _Parsed:
    source: Source
    model: ParsedModel | None  # None when it has syntax errors
    problems: tuple[Diagnostic, ...]


def load_tree(parsed: ParsedModel) -> tuple[Instance, list[Diagnostic]]:
    """The model and every subsystem file it brings in, with the problems of reading them."""
    root = Instance("", parsed, Origin(parsed.source))
    loader = _Loader()
    loader.bonds = len(parsed.bonds)
    try:
        info = os.stat(parsed.source.name)
        ancestors = ((info.st_dev, info.st_ino),)
    except (OSError, ValueError):  # a model given as text
        ancestors = ()
    loader.load(root, ancestors)
    return root, loader.problems
