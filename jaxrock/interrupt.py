"""Stopping a long run on a signal without losing its work.

A KeyboardInterrupt raised wherever Python happens to be (inside a JAX dispatch, a file write,
between a result and its checkpoint) loses work and can crash the process (XLA's threads are torn
down under it). Inside `deferred_signals()` the first SIGINT or SIGTERM only records that a stop
was asked for; the long loops (`overturning_spectrum`, `refine_boundaries`, the record spectra,
`run_scenes`) call `stop_point()` where their finished work is on disk, and that raises
`Interrupted` there. A second signal ends the process at once (exit 128 + signal number); what
was finished is on disk already, and half-written files are only ever temporaries.

Python runs signal handlers between bytecodes: a signal that arrives while XLA compiles or runs
a batch is seen when that batch returns, so a stop takes at most the time of one batch.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

_pending: int | None = None


class Interrupted(KeyboardInterrupt):
    """A signal asked the run to stop; raised at a point where finished work is kept."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def stop_point() -> None:
    """Raise `Interrupted` if a signal asked the run to stop (inside `deferred_signals`)."""
    if _pending is not None:
        raise Interrupted(_pending)


def _handler(signum, frame):
    global _pending
    if _pending is not None:
        sys.stderr.write(f"\n{signal.Signals(signum).name} again: stopping now (finished batches are kept)\n")
        sys.stderr.flush()
        os._exit(128 + signum)
    _pending = signum
    sys.stderr.write(f"\n{signal.Signals(signum).name}: stopping after the batch in progress (finished work is kept); "
                     "send it again to stop at once\n")
    sys.stderr.flush()


@contextlib.contextmanager
def deferred_signals():
    """SIGINT and SIGTERM stop the run at its next `stop_point()` (see the module docstring).
    Outside the main thread (where Python cannot set handlers) it does nothing."""
    global _pending
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.signal(s, _handler) for s in (signal.SIGINT, signal.SIGTERM)}
    _pending = None
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        _pending = None


__all__ = ["Interrupted", "deferred_signals", "stop_point"]
