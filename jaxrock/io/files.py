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
