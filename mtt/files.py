"""The user's files: what mtt reads is bounded, what it writes never replaces what it read.

Every reader and writer of mtt goes through here (model and subsystem files, CSV data and
signals, estimator modules, pictures, tables), so that one set of rules holds:

* reading: only regular files are opened (a FIFO, a device, a directory, anything under
  /proc, /sys or /dev is refused before it is opened, so that nothing blocks or streams
  for ever), of bounded size (`MAX_MODEL_BYTES` for a model, `MAX_DATA_BYTES` for data);
* writing: the target (followed through symbolic links, compared by device and inode, so
  hard links count too) must not be a file the same command read, or any file a caller
  names as an input: a clash is `MttError` (kind `io`) and nothing is written. Writes are
  atomic (a temporary file in the same directory, then a rename), keep the permissions of
  the file they replace, and refuse anything but a regular file. A missing directory is
  created only inside the working directory unless `parents` allows it anywhere.

A `session` (one per command of the `mtt` program) remembers the files read, so that a
writer can check its target against them; the outputs it is told of are checked as each
input is read, so that a command whose output is one of its inputs fails before it writes
anything.
"""

from __future__ import annotations

import contextlib
import errno
import fnmatch
import glob as globlib
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

from mtt.language.diagnostics import MttError

MAX_MODEL_BYTES = 1 << 20  # a model file of a megabyte is already absurd
MAX_DATA_BYTES = 1 << 30  # a CSV record: ten million samples of three numbers fit
MAX_MODULE_BYTES = 1 << 24  # a generated estimator module (some 200 kB)
SYSTEM_TREES = ("/proc", "/sys", "/dev")  # files there are not data: they stream or block


class FileClash(MttError):
    """A write whose target is one of the command's inputs (kind `io`)."""

    def __init__(self, message: str, file: str):
        super().__init__(message, kind="io", file=file)


@dataclass
class Session:
    """What one command read (by identity, with how it was named) and what it will write."""

    read: dict[tuple[int, int], tuple[str, str]] = field(default_factory=dict)  # name, what
    outputs: dict[str, str] = field(default_factory=dict)  # real path -> as given
    parents: bool = False  # create missing directories anywhere


_SESSION: ContextVar[Session | None] = ContextVar("mtt_files_session", default=None)


@contextlib.contextmanager
def session(outputs: Iterable[str] = (), parents: bool = False) -> Iterator[Session]:
    """Remember every file read until the block ends; `outputs` are the files the block
    will write (an input among them is refused when it is read)."""
    current = Session(parents=parents)
    for output in outputs:
        current.outputs[os.path.realpath(output)] = output
    token = _SESSION.set(current)
    try:
        yield current
    finally:
        _SESSION.reset(token)


def _identity(info: os.stat_result) -> tuple[int, int]:
    return info.st_dev, info.st_ino


def _in_system_tree(real: str) -> bool:
    return any(real == root or real.startswith(root + "/") for root in SYSTEM_TREES)


def _refusal(path: str, what: str, info: os.stat_result | None, real: str) -> str | None:
    """Why `path` is not read, or None."""
    if _in_system_tree(real):
        return f"{path} is a system file ({real}), not {what}"
    if info is None:
        return None
    if stat.S_ISDIR(info.st_mode):
        return f"{path} is a directory, not {what}"
    if not stat.S_ISREG(info.st_mode):
        return f"{path} is not a regular file (a pipe or a device), not {what}"
    return None


def check_input(
    path: str | os.PathLike, what: str, limit: int = MAX_DATA_BYTES, recorded: bool = True
) -> str:
    """Before another reader (numpy, pandas, a generated module) opens `path`: refuse what
    is not a regular file of at most `limit` bytes, and note it as read (unless not
    `recorded`: read only to compare with what will be written there); return the path as
    a string. Raises OSError (with the file's name) or `FileClash`."""
    name = os.fspath(path)
    info = os.stat(name)
    _checked(name, what, info, limit, recorded)
    return name


def _checked(name: str, what: str, info: os.stat_result, limit: int, recorded: bool) -> None:
    real = os.path.realpath(name)
    problem = _refusal(name, what, info, real)
    if problem is None and info.st_size > limit:
        problem = f"{name} is larger than {limit} bytes (a limit), too large for {what}"
    if problem is not None:
        raise OSError(errno.EINVAL, problem.removeprefix(f"{name} "), name)
    if recorded:
        _note(name, real, info, what)


def _note(name: str, real: str, info: os.stat_result, what: str) -> None:
    current = _SESSION.get()
    if current is None:
        return
    output = current.outputs.get(real)
    if output is None:
        with contextlib.suppress(OSError):
            output = next(
                (given for out, given in current.outputs.items()
                 if os.path.exists(out) and _identity(os.stat(out)) == _identity(info)),
                None,
            )  # fmt: skip
    if output is not None:
        raise FileClash(_clash_message(output, name, what), output)
    current.read.setdefault(_identity(info), (name, what))


def _clash_message(output: str, read: str, what: str) -> str:
    same = "" if output == read else f" is the file {read}, which"
    return (
        f"{output}{same} is read by this command as {what}: writing it would replace "
        "it; nothing was written (choose another output file)"
    )


def directories(option: str, value: object) -> tuple[str, ...]:
    """Directories given in Python (`include=`): one, or an iterable of them."""
    if value is None:
        return ()
    several = value if isinstance(value, Iterable) and not isinstance(value, str) else [value]
    if not all(isinstance(d, str | os.PathLike) and os.fspath(d) for d in several):
        raise MttError(f"{option} takes directories, not {value!r}", kind="bad_value")
    return tuple(os.fspath(d) for d in several)


def source_text(path: str | os.PathLike, what: str, limit: int) -> str:
    """A text file (UTF-8) read as `read_bytes` does; its problems are `MttError` (io)."""
    try:
        return read_bytes(path, what, limit).decode("utf-8")
    except (OSError, UnicodeDecodeError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        raise MttError(f"{os.fspath(path)}: {reason}", kind="io", file=os.fspath(path)) from None


def open_input(path: str | os.PathLike, what: str, limit: int, recorded: bool = True) -> BinaryIO:
    """`path` opened for reading in binary, when it is a regular file of at most `limit`
    bytes (checked on the open file too, so that a file swapped for a FIFO in between
    cannot block). Raises OSError (with the file's name) or `FileClash`."""
    name = os.fspath(path)
    check_input(name, what, limit, recorded=False)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    handle = os.open(name, flags)
    try:
        _checked(name, what, os.fstat(handle), limit, recorded)
        os.set_blocking(handle, True)
        return os.fdopen(handle, "rb")
    except BaseException:
        os.close(handle)
        raise


def read_bytes(path: str | os.PathLike, what: str, limit: int, recorded: bool = True) -> bytes:
    """The content of a regular file of at most `limit` bytes (see `open_input`)."""
    with open_input(path, what, limit, recorded) as file:
        data = file.read(limit + 1)
    if len(data) > limit:  # it grew while being read
        name = os.fspath(path)
        raise OSError(errno.EFBIG, f"larger than {limit} bytes (a limit)", name)
    return data


# writing ---------------------------------------------------------------------------------


def _inside(real: str, directory: str) -> bool:
    return real == directory or real.startswith(directory.rstrip(os.sep) + os.sep)


def _make_parent(target: Path, given: str, parents: bool) -> None:
    """Create the missing directories of `target`: anywhere with `parents`, else only
    inside the working directory (a mistyped absolute path creates nothing)."""
    parent = target.parent
    if parent.is_dir():
        return
    if not parents and not _inside(str(parent), os.path.realpath(os.getcwd())):
        missing = parent
        while not missing.parent.exists() and missing.parent != missing:
            missing = missing.parent
        raise OSError(
            errno.ENOENT,
            f"the directory {missing} does not exist, and mtt creates directories only "
            "inside the working directory (create it first, or pass --parents; parents=True "
            "in Python)",
            given,
        )
    parent.mkdir(parents=True, exist_ok=True)


def check_output(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """The real path `path` would write, after checking that it is none of the files this
    session read nor of `inputs`. Raises `FileClash`."""
    given = os.fspath(path)
    if not given:
        raise ValueError("an empty file name")
    target = Path(os.path.realpath(given))
    try:
        identity = _identity(os.stat(target))
    except OSError:
        return target  # nothing there yet: nothing to replace
    current = _SESSION.get()
    read = dict(current.read) if current else {}
    for other in inputs:
        with contextlib.suppress(OSError):
            read.setdefault(_identity(os.stat(other)), (os.fspath(other), "an input"))
    if identity in read:
        raise FileClash(_clash_message(given, *read[identity]), given)
    return target


def write_atomic(
    path: str | os.PathLike,
    data: str | bytes,
    *,
    inputs: Iterable[str | os.PathLike] = (),
    parents: bool | None = None,
) -> None:
    """Write a file so that readers see the old content or the new, never a part.

    The target must not be an input (the session's files read, or `inputs`): `FileClash`.
    A symbolic link is written through (its target is replaced, the link stays); anything
    that is not a regular file (a device such as /dev/null, a FIFO, a directory) is refused,
    never replaced. Missing directories: see `_make_parent` (`parents` None: the session's
    choice).
    """
    given = os.fspath(path)
    target = check_output(given, inputs)
    if parents is None:
        current = _SESSION.get()
        parents = bool(current and current.parents)
    mode = None
    try:
        status = os.stat(target)
    except FileNotFoundError:
        _make_parent(target, given, parents)
    else:
        if not stat.S_ISREG(status.st_mode):
            what = "a directory" if stat.S_ISDIR(status.st_mode) else "not a regular file"
            raise OSError(errno.EEXIST, f"{what}: not replaced", given)
        mode = stat.S_IMODE(status.st_mode)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    try:
        handle, temporary = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.")
    except OSError as exc:  # name the file asked for, not the temporary one
        raise OSError(exc.errno, exc.strerror, given) from None
    try:
        with os.fdopen(handle, "wb") as file:
            file.write(payload)
        if mode is None:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        os.chmod(temporary, mode)
        os.replace(temporary, target)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


# patterns ---------------------------------------------------------------------------------

MAX_GLOB_ENTRIES = 100_000  # directory entries one pattern may look at


class _TooWide(Exception):
    pass


def glob(pattern: str, limit: int = MAX_GLOB_ENTRIES) -> list[str]:
    """The sorted files a glob pattern matches (`*`, `?`, `[...]` within a name; `**` any
    directories below, symbolic links to directories not followed; names starting with a
    dot only when the pattern's part does), looking at no more than `limit` directory
    entries: `/**/*.csv` is an error, not a scan of the whole file system. Raises
    `MttError` (kind `too_large`) beyond the limit."""
    parts = Path(pattern).parts
    start = parts[0] if parts and Path(parts[0]).is_absolute() else ""
    found = [start]
    seen = [0]

    def entries(directory: str) -> list[os.DirEntry]:
        try:
            with os.scandir(directory or ".") as listing:
                result = []
                for entry in listing:
                    seen[0] += 1
                    if seen[0] > limit:
                        raise _TooWide
                    result.append(entry)
                return result
        except OSError:  # not a directory, or not readable: no match below it
            return []

    def below(directory: str) -> Iterator[str]:
        yield directory
        for entry in entries(directory):
            if entry.is_dir(follow_symlinks=False) and not entry.name.startswith("."):
                yield from below(os.path.join(directory, entry.name))

    try:
        for part in parts[1 if start else 0 :]:
            if part == "**":
                found = [d for directory in found for d in below(directory)]
            elif globlib.has_magic(part):
                found = [
                    os.path.join(directory, entry.name)
                    for directory in found
                    for entry in entries(directory)
                    if fnmatch.fnmatchcase(entry.name, part)
                    and (part.startswith(".") or not entry.name.startswith("."))
                ]
            else:
                found = [os.path.join(directory, part) for directory in found]
    except _TooWide:
        raise MttError(
            f"the pattern {pattern!r} looks at more than {limit} files and directories (a "
            "limit): name the directory the records are in",
            kind="too_large",
            file=pattern,
        ) from None
    return sorted({path for path in found if os.path.isfile(path)})
