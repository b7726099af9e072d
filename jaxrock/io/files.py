"""The files a user names: where an output goes, whether two names are one file, writing without
ever leaving a half-written file, and one run at a time per output."""

from __future__ import annotations

import os
import socket
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Callable

from .._validate import JaxrockInputError


def output_stem(out: str | os.PathLike, default_name: str) -> Path:
    """`out` as an output stem: a trailing separator or an existing folder means "inside it",
    as `<out>/<default_name>`."""
    text = os.fspath(out)
    if text.endswith((os.sep, "/")) or Path(text).is_dir():
        return Path(text) / default_name
    return Path(text)


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name one file: by identity (hard and symbolic links) when both exist."""
    a, b = Path(a), Path(b)
    if a.exists() and b.exists():
        return os.path.samefile(a, b)
    return a.resolve() == b.resolve()


def write_atomically(path: str | os.PathLike, write: Callable[[Path], None]) -> Path:
    """`write(tmp)` to a temporary of this process beside `path`, then rename it to `path`: a
    reader never sees half a file, and concurrent writers never share a temporary."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f"tmp_{os.getpid()}_", suffix=f"_{path.name}")
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes it 0600: the file gets the mode open() would give it
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


FORCE = False  # `--force`: an output may replace a file jaxrock did not write (set by the command line)
MARK = b"jaxrock"  # every netCDF and figure jaxrock writes holds the word in its first bytes (attributes, metadata)


def refuse_foreign(path: str | os.PathLike, head: bytes | None = None) -> None:
    """Refuse, in one line, to replace `path` when it is a symbolic link, not a regular file, or a
    file jaxrock did not write (unless `FORCE`). A file jaxrock wrote is recognised by its content:
    it starts with `head` (the first bytes the new file will have: a CSV's header, a report's
    title), or its first 64 KiB hold `MARK`."""
    from .._validate import JaxrockInputError, check_file_kind

    p = Path(path)
    check_file_kind("", p)
    if not p.exists() or FORCE:
        return
    with open(p, "rb") as fh:
        first = fh.read(65536)
    if (head and first.startswith(head)) or MARK in first:
        return
    raise JaxrockInputError(f"{p}: exists and was not written by jaxrock; pass --force to overwrite it, or choose another path")


MARKED = (".nc", ".png", ".pdf", ".svg", ".ps", ".eps")  # the formats whose first bytes name jaxrock (`MARK`)


def check_output(name: str, path: str | os.PathLike) -> None:
    """Before a run: `path` can be written (`jaxrock._validate.check_writable`) and, in a format
    that names jaxrock in its first bytes, does not replace a file jaxrock did not write (CSV and
    Markdown outputs are checked as they are written, against the header they will have)."""
    from .._validate import JaxrockInputError, check_writable

    check_writable(name, path)  # the file's kind, too
    if Path(path).suffix.lower() in MARKED:
        try:
            refuse_foreign(path)
        except JaxrockInputError as e:
            raise JaxrockInputError(f"{name} {e}") from None


def write_output(path: str | os.PathLike, write: Callable[[Path], None], head: bytes | None = None) -> Path:
    """An output the user asked for: `refuse_foreign`, then `write_atomically`."""
    refuse_foreign(path, head)
    return write_atomically(path, write)


def text_head(text: str) -> bytes:
    """What identifies a text output of jaxrock's: the first 64 bytes of its first line."""
    return text.split("\n", 1)[0].encode("utf-8")[:64]


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


@contextmanager
def exclusive(path: str | os.PathLike, what: str):
    """Hold `<path>.lock` while a run writes `path` (an output stem, a checkpoint, a results
    file): a second run on it is refused in one line. A lock left by a process that no longer
    exists on this host is taken over."""
    lock = Path(f"{os.path.realpath(path)}.lock")  # by the resolved path: two names of one output share one lock
    lock.parent.mkdir(parents=True, exist_ok=True)
    me = f"{socket.gethostname()} {os.getpid()}"
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                host, pid = lock.read_text().split()
                stale = host == socket.gethostname() and not _alive(int(pid))
            except (OSError, ValueError):
                host, pid, stale = "?", "?", False
            if stale:
                lock.unlink(missing_ok=True)
                continue
            raise JaxrockInputError(f"{what} {path}: another run (process {pid} on {host}) is writing it; wait for it to end, "
                                    f"or choose another path (remove {lock} if that run is gone)") from None
        with os.fdopen(fd, "w") as fh:
            fh.write(me)
        break
    else:
        raise JaxrockInputError(f"{what} {path}: its lock {lock} keeps changing hands; another run is starting on it")
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)
