"""Ctrl-C in long computations: deferred to safe points, pools stopped at once.

A SIGINT that lands inside a CasADi evaluation (IDAS, a rootfinder) is turned by CasADi
into a failure of that evaluation (a ``RuntimeError`` with pages of solver inputs, then a
wrong diagnosis such as "check the magnet's dimensions") or leaves a pending
``KeyboardInterrupt`` that surfaces as a ``SystemError``.  Within :func:`deferred_sigint`
the first SIGINT is only noted and raised as :class:`KeyboardInterrupt` at the next
:func:`check_interrupt` (between two tasks: a map point, a case); a second SIGINT
raises at once.  :func:`stop_pool` ends a local process pool without waiting for its
running tasks.  :func:`sigint_received` tells whether a SIGINT reached this process
under :func:`deferred_sigint` or :func:`recorded_sigint` (the CLI's entry point), so that
a failure it caused (CasADi's) is reported as the interruption it was.  Needs only the
standard library (below every other layer).
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Iterator
from concurrent.futures import Executor
from typing import Any

__all__ = ["InterruptState", "deferred_sigint", "check_interrupt", "sigint_blocked",
           "stop_pool", "recorded_sigint", "sigint_received"]


class InterruptState:
    """Whether a SIGINT arrived within :func:`deferred_sigint` (attribute ``requested``)."""

    def __init__(self) -> None:
        self.requested = False


_ACTIVE: list[InterruptState] = []
_RECEIVED = InterruptState()     # any SIGINT under deferred_sigint or recorded_sigint


def sigint_received() -> bool:
    """Whether a SIGINT arrived under :func:`deferred_sigint` or :func:`recorded_sigint`.

    Returns
    -------
    bool
        True once a SIGINT was noted (it stays set: the process is ending).
    """
    return _RECEIVED.requested


@contextlib.contextmanager
def recorded_sigint() -> Iterator[None]:
    """Python's own Ctrl-C (``KeyboardInterrupt`` at once), noted for
    :func:`sigint_received` (main thread only; elsewhere nothing changes).

    A SIGINT inside a CasADi evaluation becomes that evaluation's failure (a
    ``SolverError`` with a wrong diagnosis, or a ``SystemError``); the CLI asks
    :func:`sigint_received` to report it as the interruption instead.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        _RECEIVED.requested = True
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        if signal.getsignal(signal.SIGINT) is handler:   # not replaced meanwhile (SIG_IGN)
            signal.signal(signal.SIGINT, old)


@contextlib.contextmanager
def deferred_sigint() -> Iterator[InterruptState]:
    """Defer the first SIGINT to the next :func:`check_interrupt` (main thread only).

    Yields an :class:`InterruptState`; its ``requested`` stays set after the block so that
    the caller can tell an interruption from another failure it caused.
    """
    state = InterruptState()
    if threading.current_thread() is not threading.main_thread():
        yield state
        return

    def handler(signum: int, frame: Any) -> None:
        _RECEIVED.requested = True
        if state.requested:
            raise KeyboardInterrupt
        state.requested = True

    old = signal.signal(signal.SIGINT, handler)
    _ACTIVE.append(state)
    try:
        yield state
    finally:
        _ACTIVE.remove(state)
        # restored only if still ours: the CLI's report of the interruption ignores
        # further SIGINTs (SIG_IGN) and a restored handler turned a second Ctrl-C during
        # the exit into a death by SIGINT (rc -2 instead of 130)
        if signal.getsignal(signal.SIGINT) is handler:
            signal.signal(signal.SIGINT, old)


def check_interrupt() -> None:
    """Raise :class:`KeyboardInterrupt` if a deferred SIGINT is pending (a safe point)."""
    if _ACTIVE and _ACTIVE[-1].requested:
        raise KeyboardInterrupt


@contextlib.contextmanager
def sigint_blocked() -> Iterator[None]:
    """Block SIGINT in this thread while starting pool workers (POSIX, main thread).

    Worker processes started meanwhile inherit the blocked mask, so a Ctrl-C to the
    process group cannot interrupt them while they import (a traceback per worker
    before their initializer could ignore SIGINT); the main process stops them
    (:func:`stop_pool`).  A SIGINT to this process meanwhile stays pending and is
    delivered when the block ends: nothing is lost.
    """
    if not hasattr(signal, "pthread_sigmask") \
            or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def stop_pool(pool: Executor, timeout_s: float = 5.0) -> None:
    """Stop a local ``ProcessPoolExecutor`` at once: terminate its workers.

    ``shutdown(wait=True)`` after an interrupt waited for the running tasks (minutes), and
    a second Ctrl-C then left orphaned workers.  The workers get SIGTERM, SIGKILL after
    ``timeout_s``; the main process waits on their sentinels (the pool's manager thread
    may reap them first, so ``join`` could not tell).  The futures are not cancelled
    first: the manager thread fails the waiting ones itself (setting a cancelled one
    raised ``InvalidStateError`` in Python 3.11).  A second SIGINT meanwhile is ignored.
    """
    from multiprocessing.connection import wait

    procs = list((getattr(pool, "_processes", None) or {}).values())
    old = None
    if threading.current_thread() is threading.main_thread():
        old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        for proc in procs:
            with contextlib.suppress(Exception):
                proc.terminate()
        sentinels = {proc.sentinel: proc for proc in procs}
        deadline = time.monotonic() + timeout_s
        while sentinels and time.monotonic() < deadline:
            for ready in wait(list(sentinels), timeout=max(deadline - time.monotonic(), 0.0)):
                sentinels.pop(ready, None)  # type: ignore[call-overload]
        for proc in sentinels.values():
            with contextlib.suppress(Exception):
                proc.kill()
    finally:
        if old is not None:
            signal.signal(signal.SIGINT, old)
    # let the pool's manager thread finish (it sees the dead workers at once): else its
    # closing raced the interpreter's exit hook, "OSError: Bad file descriptor" on stderr.
    # Taken before ``shutdown``, which sets the attribute to None (so a join after it
    # never happened and the race stayed, seen once in CI).
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False)
    if manager is not None:
        manager.join(timeout=timeout_s)
