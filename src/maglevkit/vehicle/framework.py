"""The vehicle framework's time loop: one runner for every vehicle model.

A vehicle model (the heave-pitch train :class:`~maglevkit.vehicle.VehicleModel`, the
cross-section slice :class:`~maglevkit.vehicle.crossrun.CrossSectionModel`) is an assembly
of parts read from its file: mechanics, guideway and irregularities, the magnets through
the bank, controllers.  What it adds is its step, in one of two forms, and what an event
means for it; this module runs either form:

- :func:`run_blocks`: a compiled CasADi block function ``(S, P, C) -> (S_next, R)`` that
  chains ``block_steps`` steps (``P`` and ``R`` one row per step of C-ordered arrays),
  called with two ping-pong state buffers bound once; the records go straight into one
  preallocated array.  After every block a cheap vectorised ``look`` says whether any row
  needs the per-step ``check`` (touchdown, a limit crossed within a step, a circuit the
  kernel flagged, leaving the guideway window), which either stops the run at a step with
  its event or raises.
- :func:`run_steps`: a Python step ``step(k)`` (the NumPy reference loops, detailed
  magnets, controllers through the :class:`~maglevkit.control.interface.Controller`
  interface) that records step ``k`` and returns ``None`` or a stop.

Both give a :class:`LoopOutcome`: the last recorded step, the event, wall and CPU time,
and whether Ctrl-C stopped the loop (then the steps done are kept: the model builds its
partial run and raises :class:`~maglevkit.vehicle.simulation.VehicleRunInterrupted` with
it; a Ctrl-C before the second step re-raises).  Progress goes to stderr through
:class:`LoopProgress` (a bar on a terminal, plain lines with the ETA in logs).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["LoopOutcome", "LoopProgress", "PartEvaluator", "run_blocks", "run_steps"]


class LoopProgress:
    """Progress of a vehicle run on stderr (:class:`maglevkit._progress.ProgressReporter`:
    a rich bar on a terminal, plain lines with the ETA in logs), fed every ~0.5 % of the
    steps so that the time loop stays free of it.

    Parameters
    ----------
    total : int
        Steps of the run [1].
    enabled : bool
        False: every method does nothing.
    label : str, default "vehicle run (steps)"
        What the bar counts.
    """

    def __init__(self, total: int, *, enabled: bool, label: str = "vehicle run (steps)"
                 ) -> None:
        self.enabled = enabled and total > 0
        self.total = total
        self._next = 0
        self._done = 0
        self._rep: Any = None
        if self.enabled:
            from .._progress import ProgressReporter

            self._rep = ProgressReporter(total, label)
            self._rep.__enter__()

    def update(self, k: int) -> None:
        """Report ``k`` [1] steps done (shown when another ~0.5 % is done)."""
        if self.enabled and k >= self._next:
            k = min(k, self.total)
            self._rep.advance(k - self._done)
            self._done = k
            self._next = k + max(1, self.total // 200)

    def close(self, finished: bool = True) -> None:
        """Close the bar (``finished``: the closing ``done`` line in plain mode)."""
        if self.enabled:
            self.enabled = False
            if finished:
                self._rep.advance(self.total - self._done)
                self._rep.__exit__(None, None, None)
            else:
                self._rep.__exit__(KeyboardInterrupt, None, None)


@dataclass(frozen=True)
class LoopOutcome:
    """How a time loop ended.

    Attributes
    ----------
    last_step : int
        Index of the last recorded step (``n_steps`` for a whole run).
    event : object
        What the model's step or check returned with its stop (e.g. its touchdown
        tuple), None for a whole or interrupted run.
    wall_s, cpu_s : float
        Wall-clock and process CPU time of the loop [s].
    interrupted : bool
        Ctrl-C stopped the loop; the records up to ``last_step`` are whole.
    call_s : float
        Wall time inside the compiled block calls [s] (0 for :func:`run_steps`).
    """

    last_step: int
    event: Any
    wall_s: float
    cpu_s: float
    interrupted: bool
    call_s: float = 0.0


def run_steps(step: Callable[[int], tuple[int, Any] | None], *, n_steps: int,
              progress: bool = False, label: str = "vehicle run (steps)") -> LoopOutcome:
    """Run a Python step function for ``k = 0 ... n_steps``.

    Parameters
    ----------
    step : callable
        ``step(k)`` records the state at step ``k`` and (for ``k < n_steps``) advances
        it; returns None to go on, or ``(last_step, event)`` to stop there.  The loop
        also stops after ``k = n_steps``.
    n_steps : int
        Steps of the run [1] (records ``0 ... n_steps``).
    progress : bool, default False
        Progress on stderr (:class:`LoopProgress`).
    label : str, default "vehicle run (steps)"
        The progress bar's label.

    Returns
    -------
    LoopOutcome
        On Ctrl-C during step ``k``: ``last_step = k - 1``, ``interrupted`` True.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C before the second step (nothing worth keeping).
    """
    bar = LoopProgress(n_steps, enabled=progress, label=label)
    clock = time.perf_counter
    t0, c0 = clock(), time.process_time()
    last, event, interrupted = n_steps, None, False
    k = 0
    try:
        for k in range(n_steps + 1):
            stop = step(k)
            if stop is not None:
                last, event = stop
                break
            bar.update(k + 1)
    except KeyboardInterrupt:
        interrupted, last = True, k - 1
        if last < 1:
            bar.close(finished=False)
            raise
    wall, cpu = clock() - t0, time.process_time() - c0
    bar.close(finished=not interrupted)
    return LoopOutcome(last, event, wall, cpu, interrupted)


def run_blocks(function: Any, *, state: np.ndarray, inputs: np.ndarray,
               constants: np.ndarray, n_steps: int, n_record: int, block_steps: int,
               look: Callable[[int, np.ndarray], bool],
               check: Callable[[int, np.ndarray, bool], tuple[int, Any] | None],
               progress: bool = False, label: str = "vehicle run (steps)",
               before_block: Callable[[int, np.ndarray, np.ndarray], None] | None = None
               ) -> tuple[LoopOutcome, np.ndarray]:
    """Run a compiled block step function over ``k = 0 ... n_steps``.

    Parameters
    ----------
    function : casadi.Function
        ``(S, P, C) -> (S_next, R)`` chaining ``block_steps`` steps (compiled).
    state : ndarray (n_state,)
        The state at step 0 (copied).
    inputs : ndarray (n_rows, n_inputs)
        Per-step inputs, C-ordered, ``n_rows`` a multiple of ``block_steps`` and
        ``> n_steps`` (rows after ``n_steps`` pad the last block; their records are
        never looked at).
    constants : ndarray (n_constants,)
        Per-run constants ``C``.
    n_steps : int
        Steps of the run [1].
    n_record : int
        Length of a step's record ``R`` [1].
    block_steps : int
        Steps per call [1].
    look : callable
        ``look(k0, rows)``: True if any of the block's valid records ``rows`` (steps
        ``k0 ...``, at most up to ``n_steps``) needs the per-step ``check``; blocks that
        reach ``n_steps`` are always checked.
    check : callable
        ``check(k, row, final)`` for every step of a looked-at block, in order
        (``final``: ``k == n_steps``, no step follows): None to go on,
        ``(last_step, event)`` to stop; it may raise (the model's own error).
    progress : bool, default False
        Progress on stderr (:class:`LoopProgress`), updated per block.
    label : str, default "vehicle run (steps)"
        The progress bar's label.
    before_block : callable, optional
        ``before_block(k0, state, records)`` before each block (steps ``k0 ...``), with
        the state at step ``k0`` and the records so far; it may write the block's rows
        of ``inputs`` (e.g. a sampled controller's held voltages).

    Returns
    -------
    (LoopOutcome, ndarray (n_rows, n_record))
        The outcome and the records (rows up to ``last_step`` are the run's).  On Ctrl-C
        the block under way is dropped unless it was computed and checked (the interrupt
        came in the progress update after it): ``last_step`` is the last step of the
        blocks done.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C during the first block.
    """
    nb = int(block_steps)
    n_rows = inputs.shape[0]
    s_buf = [np.array(state, dtype=float), np.zeros_like(state, dtype=float)]
    consts = np.ascontiguousarray(constants, dtype=float)
    records = np.empty((n_rows, n_record))
    bufs: list[Any] = []
    evals: list[Any] = []
    for j in (0, 1):
        buf, ev = function.buffer()
        buf.set_arg(0, memoryview(s_buf[j]))        # type: ignore[arg-type]
        buf.set_res(0, memoryview(s_buf[1 - j]))    # type: ignore[arg-type]
        buf.set_arg(2, memoryview(consts))          # type: ignore[arg-type]
        bufs.append(buf)
        evals.append(ev)
    bar = LoopProgress(n_steps, enabled=progress, label=label)
    clock = time.perf_counter
    t0, c0 = clock(), time.process_time()
    t_call = 0.0
    last, event, interrupted, done = n_steps, None, False, False
    kept = -1                        # the last step of the blocks computed and checked
    try:
        for blk in range(n_rows // nb):
            k0 = blk * nb
            j = blk & 1
            if before_block is not None:
                before_block(k0, s_buf[j], records)
            bufs[j].set_arg(1, memoryview(inputs[k0:k0 + nb]))   # type: ignore[arg-type]
            rows = records[k0:k0 + nb]
            bufs[j].set_res(1, memoryview(rows))                  # type: ignore[arg-type]
            tc = clock()
            evals[j]()
            t_call += clock() - tc
            k1 = min(k0 + nb, n_steps + 1)
            if k1 <= n_steps and not look(k0, rows[:k1 - k0]):
                kept = k1 - 1
                bar.update(k1)
                continue
            for k in range(k0, k1):
                stop = check(k, records[k], k == n_steps)
                if stop is not None:
                    last, event = stop
                    done = True
                    break
                if k == n_steps:
                    done = True
                    break
            if done:
                break
            kept = k1 - 1
            bar.update(k1)
    except KeyboardInterrupt:
        interrupted, last = True, kept
        if last < 1:
            bar.close(finished=False)
            raise
    wall, cpu = clock() - t0, time.process_time() - c0
    bar.close(finished=not interrupted)
    return LoopOutcome(last, event, wall, cpu, interrupted, t_call), records


class PartEvaluator:
    """A part of a vehicle step (a CasADi function) evaluated in place, for Python steps.

    The function is bound once to NumPy buffers (:class:`~maglevkit.models.compiled.
    BoundCall`) and runs on CasADi's virtual machine, so that a reference loop evaluates
    the compiled step's own laws without the conversion cost of a plain call (measured
    ~200 us per call for such a part on the shared machine, a few us bound).

    Parameters
    ----------
    function : casadi.Function
        The part; its inputs dense vectors or scalars (units those of the part).
    """

    def __init__(self, function: Any) -> None:
        from ..models.compiled import BoundCall

        self.function = function
        self._call = BoundCall(function)
        # outputs with structural zeros (e.g. a rigid guideway's deflection): scattered
        # into dense vectors
        self._rows: list[np.ndarray | None] = []
        for i in range(function.n_out()):
            sp = function.sparsity_out(i)
            self._rows.append(None if sp.nnz() == sp.numel() else
                              np.asarray(sp.find(), dtype=int))

    def __call__(self, *inputs: Any) -> tuple[np.ndarray, ...]:
        """Evaluate the part on ``inputs`` (in the function's input order, units its own).

        Parameters
        ----------
        *inputs : float or array_like
            One value per input of the function, broadcast into its buffer.

        Returns
        -------
        tuple of ndarray
            Every output as a new dense 1-D array.
        """
        call = self._call
        for buf, value in zip(call.args, inputs, strict=True):
            buf[...] = value
        call.eval()
        out = []
        for res, rows, i in zip(call.res, self._rows, range(len(self._rows)), strict=True):
            if rows is None:
                out.append(res.copy())
            else:
                full = np.zeros(self.function.sparsity_out(i).numel())
                full[rows] = res
                out.append(full)
        return tuple(out)
