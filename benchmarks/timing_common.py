"""Timing helpers shared by the benchmarks and measurement scripts of this folder
(``bench_vehicle``, ``bench_bank_motion_eddy``, ``measure_network_cost``,
``measure_mpc_substeps``): CPU time per call, a compiled CasADi function bound to its
buffers, a sibling script loaded as a module.

Times are process CPU time (``time.process_time``): the machine is shared, and wall time
counts the other processes.  The scripts put this folder on ``sys.path`` to import it
(as they do ``fem_common``).
"""

from __future__ import annotations

import importlib.util
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent


def sibling_module(name: str) -> Any:
    """The script ``name``.py of this folder, loaded as a module (its own copy: module-level
    state of the script is not shared with another load)."""
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def cpu_per_call(fn: Callable[[], Any], calls: int, *, repeats: int = 1,
                 warm: bool = False) -> float:
    """CPU time per call [s] of ``fn``: ``calls`` calls per batch, the best of ``repeats``
    batches (one call first when ``warm``, untimed)."""
    if warm:
        fn()
    best = math.inf
    for _ in range(repeats):
        t0 = time.process_time()
        for _ in range(calls):
            fn()
        best = min(best, (time.process_time() - t0) / calls)
    return best


def bind_buffer(f: Any, args: Sequence[Any]) -> tuple[Callable[[], None], list[np.ndarray],
                                                        tuple[Any, ...]]:
    """A CasADi function's ``buffer()`` bound to ``args`` (flattened to contiguous float
    arrays) and to zeroed output arrays: the evaluation without Python-side conversions.

    Returns
    -------
    ev : callable
        One evaluation, writing into ``outputs``.
    outputs : list of ndarray
        The function's outputs (nonzeros), one array each.
    keep : tuple
        The buffer and the input arrays: hold them as long as ``ev`` is called (the buffer
        refers to their memory).
    """
    buf, ev = f.buffer()
    ins = [np.ascontiguousarray(np.asarray(a, dtype=float).ravel()) for a in args]
    outs = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
    for i, a in enumerate(ins):
        buf.set_arg(i, memoryview(a))
    for i, o in enumerate(outs):
        buf.set_res(i, memoryview(o))
    return ev, outs, (buf, ins)
