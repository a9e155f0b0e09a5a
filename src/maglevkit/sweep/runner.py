"""Running a sweep through a ``concurrent.futures.Executor``; storing, resuming, assembling.

Every case is one task ``run_case(job, params, key)`` submitted to the executor: a local
:class:`~concurrent.futures.ProcessPoolExecutor` by default, the executor of a
``dask.distributed.Client`` (``client.get_executor()``; pass the client or its executor),
or any other Executor.  The results come back to this process, which stores each as a
small netCDF file ``<resume_dir>/<case key>.nc`` as soon as it arrives (written to a
temporary name and renamed, so an interrupted write leaves no partial file).  A rerun
with the same resume folder loads the stored cases instead of running them again; the
result is assembled from the case Datasets in case order, so it is the same however the
cases were distributed or interrupted.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
from collections.abc import Callable
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from .._files import read_netcdf, write_netcdf_atomically
from .._interrupt import sigint_blocked, stop_pool
from ..errors import InputError, ParameterFileError
from .cases import SUMMARY_UNITS, error_case, run_case
from .spec import SWEEP_FORMAT, SweepSpec

__all__ = ["SweepResult", "run_sweep", "assemble", "case_path"]


@dataclass(frozen=True)
class SweepResult:
    """Result of :func:`run_sweep`.

    Attributes
    ----------
    dataset : xarray.Dataset
        One coordinate per swept parameter (``docs/sweep.md``, "Dataset layout").
    n_cases : int
        Cases of the sweep.
    n_run : int
        Cases computed in this call.
    n_reused : int
        Cases loaded from the resume folder.
    n_failed : int
        Cases with ``status = "error"`` (computed or loaded).
    """

    dataset: Any
    n_cases: int
    n_run: int
    n_reused: int
    n_failed: int

    def to_netcdf(self, path: str | Path) -> Path:
        """Write the dataset (the folder must exist: nothing is created silently).

        Parameters
        ----------
        path : str or Path
            Target netCDF file; written atomically (a temporary file, then renamed).

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        InputError
            The parent folder does not exist.
        """
        p = Path(path)
        if not p.parent.is_dir():
            raise InputError(f"cannot write {str(p)!r}: the directory {str(p.parent)!r} does "
                             "not exist")
        _write(self.dataset, p)
        return p


def case_path(resume_dir: str | Path, key: str) -> Path:
    """File of the stored case ``key`` in ``resume_dir``.

    Parameters
    ----------
    resume_dir : str or Path
        Folder of the stored cases (not checked or created here).
    key : str
        The case key (:meth:`~maglevkit.sweep.SweepSpec.case_key`).

    Returns
    -------
    Path
        ``resume_dir / f"{key}.nc"``.
    """
    return Path(resume_dir) / f"{key}.nc"


def _write(ds: Any, path: Path) -> None:
    """Write netCDF atomically (temporary file in the same folder, then rename)."""
    write_netcdf_atomically(ds, path)


def _load_case(path: Path, key: str) -> Any | None:
    """A stored case, or None if missing, unreadable or not this case."""
    if not path.is_file():
        return None
    try:
        ds = read_netcdf(path)
    except ParameterFileError:          # unreadable: computed again
        return None
    if ds.attrs.get("format") != SWEEP_FORMAT or ds.attrs.get("case_key") != key:
        return None
    return ds


def _as_executor(executor: Any, workers: int | None) -> tuple[Executor | None, bool]:
    """(executor, owned): None runs in this process."""
    if executor is None:
        n = (os.cpu_count() or 1) if workers is None else workers
        if n == 1:
            return None, False
        import multiprocessing

        # spawn: fresh interpreters (no fork of a process with threads, e.g. a dask client);
        # the workers ignore SIGINT: Ctrl-C is this process's to handle, and it stops them
        # (a worker interrupted mid-case, or waited for, left the main process hanging)
        return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_ignore_sigint), True
    if hasattr(executor, "get_executor") and not isinstance(executor, Executor):
        return executor.get_executor(), False      # a dask.distributed Client
    if isinstance(executor, Executor):
        return executor, False
    raise InputError("executor must be None (a local process pool), a concurrent.futures."
                     f"Executor or a dask.distributed Client, got {type(executor).__name__}")


def _ignore_sigint() -> None:
    """Initializer of the local pool's workers: SIGINT (Ctrl-C to the process group) is
    ignored there; the main process stops the workers (:func:`~maglevkit._interrupt.stop_pool`)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_sweep(spec: SweepSpec, *, executor: Any = None, workers: int | None = None,
              resume_dir: str | Path | None = None, retry_failed: bool = False,
              progress: bool = True, stream: IO[str] | None = None,
              on_case: Callable[[int, Any], None] | None = None) -> SweepResult:
    """Run every case of ``spec`` and assemble the results.

    Parameters
    ----------
    spec : SweepSpec
        From :func:`~maglevkit.sweep.load_sweep`.
    executor : Executor or dask.distributed.Client, optional
        Where the cases run.  Default: a local process pool of ``workers`` processes
        (``workers = 1``: in this process, no pool).  An executor you pass is not shut down.
    workers : int, optional
        Size of the default pool (default: the number of CPUs).
    resume_dir : path, optional
        Folder of the stored cases (created if missing, inside an existing directory).
        Cases found there are loaded instead of run; each new case is stored as it
        finishes.  None: nothing is stored.
    retry_failed : bool
        Run stored failed cases again (default: they are loaded like the others).
    progress : bool
        Progress on ``stream`` (default stderr): a bar on a terminal, lines in logs.
    stream : text file, optional
        Where the progress goes (default: ``sys.stderr``).
    on_case : callable, optional
        Called as ``on_case(index, dataset)`` in this process after each case arrives
        (and is stored).

    Returns
    -------
    SweepResult

    Raises
    ------
    InputError
        ``spec`` not a :class:`~maglevkit.sweep.SweepSpec`, ``workers`` not a whole
        number >= 1, or a resume folder that is a file or whose parent does not exist.

    Notes
    -----
    A case whose run raises is recorded with ``status = "error"`` and the error text; so
    is a case whose worker was lost (e.g. a crashed process: ``error`` starts with
    ``"worker: "``); such executor failures are *not* stored, a rerun tries them again.
    """
    from .._progress import ProgressReporter

    if not isinstance(spec, SweepSpec):
        raise InputError(f"spec must be a SweepSpec (from load_sweep), got {type(spec).__name__}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise InputError(f"workers = {workers!r} must be a whole number >= 1")
    cases = list(spec.cases())
    keys = [spec.case_key(c) for c in cases]
    results: list[Any] = [None] * len(cases)
    folder: Path | None = None
    if resume_dir is not None:
        folder = Path(resume_dir)
        if folder.exists() and not folder.is_dir():
            raise InputError(f"resume folder {str(folder)!r} is a file, not a folder")
        if not folder.exists():
            if not folder.parent.is_dir():
                raise InputError(f"resume folder {str(folder)!r}: the directory "
                                 f"{str(folder.parent)!r} does not exist")
            folder.mkdir()
        for i, k in enumerate(keys):
            ds = _load_case(case_path(folder, k), k)
            if ds is not None and not (retry_failed and str(ds["status"].values) != "ok"):
                results[i] = ds
    pending = [i for i, r in enumerate(results) if r is None]
    n_reused = len(cases) - len(pending)

    def store(i: int, ds: Any) -> None:
        results[i] = ds
        if folder is not None:
            _write(ds, case_path(folder, keys[i]))
        if on_case is not None:
            on_case(i, ds)

    reporter: Any = ProgressReporter(len(pending), f"sweep {spec.name}", stream=stream) \
        if progress and pending else contextlib.nullcontext()
    pool, owned = _as_executor(executor, workers) if pending else (None, False)
    stop_now = False
    try:
        with reporter:
            if pool is None:
                for i in pending:
                    store(i, run_case(spec.job, cases[i], keys[i]))
                    if progress:
                        reporter.advance()
            else:
                with sigint_blocked():   # the workers start with SIGINT blocked
                    futures: dict[Future[Any], int] = {
                        pool.submit(run_case, spec.job, cases[i], keys[i]): i for i in pending}
                try:
                    for fut in as_completed(futures):
                        i = futures[fut]
                        exc = fut.exception()
                        if exc is None:
                            store(i, fut.result())
                        else:     # the executor lost the task: recorded, not stored
                            msg = " ".join(str(exc).split()) or "(no message)"
                            results[i] = error_case(cases[i], keys[i],
                                                    f"worker: {type(exc).__name__}: {msg}")
                        if progress:
                            reporter.advance()
                except BaseException:
                    stop_now = True      # interrupted (Ctrl-C) or failed: stop at once
                    if not owned:        # (our own pool's futures fail with it: a cancelled
                        for f in futures:  # one made its manager thread raise in 3.11)
                            f.cancel()
                    raise
    finally:
        if owned and pool is not None:
            if stop_now:
                stop_pool(pool)
            else:
                pool.shutdown(wait=True, cancel_futures=True)
    ds = assemble(spec, results)
    n_failed = int((ds["status"].values != "ok").sum())
    return SweepResult(ds, len(cases), len(pending), n_reused, n_failed)


def _union(results: list[Any], dim: str) -> list[str]:
    names: list[str] = []
    seen: set[str] = set()
    for r in results:
        if dim in r.coords:
            for c in r[dim].values:
                if str(c) not in seen:
                    seen.add(str(c))
                    names.append(str(c))
    return names


def assemble(spec: SweepSpec, results: list[Any]) -> Any:
    """One Dataset from the case Datasets (in :meth:`SweepSpec.cases` order).

    Dimensions: the swept parameters (in the order of the job's parameters,
    :attr:`SweepSpec.parameters`), then ``circuit``, ``comfort_point`` (vehicle job) and
    ``time`` for the per-case arrays.  Values a case lacks (a failed case, a run too short
    for comfort figures) are NaN, text ``""``.

    Parameters
    ----------
    spec : SweepSpec
        The sweep the cases belong to (gives the dimensions and fixed parameters).
    results : list of xarray.Dataset
        One Dataset per case (from :func:`~maglevkit.sweep.run_case` or the resume
        folder), in :meth:`SweepSpec.cases` order, ``spec.n_cases`` of them.

    Returns
    -------
    xarray.Dataset
    """
    import xarray as xr

    from .._version import __version__

    dims = list(spec.swept)
    shape = spec.shape
    n = len(results)
    inner = {"circuit": _union(results, "circuit")}
    if spec.job.kind == "vehicle":
        inner["comfort_point"] = _union(results, "comfort_point")
    if spec.job.time_series:
        inner["time"] = [str(t) for t in range(spec.job.n_steps + 1)]   # positions only
    index = {d: {c: j for j, c in enumerate(v)} for d, v in inner.items()}
    # variable -> (inner dims, dtype) from the first case that has it
    layout: dict[str, tuple[tuple[str, ...], str]] = {}
    attrs: dict[str, dict[str, Any]] = {}
    for r in results:
        for name, var in r.data_vars.items():
            if name not in layout:
                layout[str(name)] = (tuple(str(d) for d in var.dims),
                                     "U" if var.dtype.kind in "OUS" else "f")
                attrs[str(name)] = dict(var.attrs)
    data: dict[str, Any] = {}
    for name, (vdims, kind) in layout.items():
        full_shape = (n, *(len(inner[d]) for d in vdims))
        arr = np.full(full_shape, "", dtype=object) if kind == "U" else np.full(full_shape, np.nan)
        for k, r in enumerate(results):
            if name not in r.data_vars:
                continue
            v = r[name]
            if not vdims:
                arr[k] = str(v.values) if kind == "U" else float(v.values)
                continue
            sel = [np.array([index[d][str(c)] for c in r[d].values], dtype=int) if d != "time"
                   else np.arange(r.sizes["time"]) for d in vdims]
            where: Any = (k, *np.ix_(*sel))
            arr[where] = v.values
        if kind == "U":
            arr = arr.astype(str)
        data[name] = arr.reshape(*shape, *full_shape[1:])
    coords: dict[str, Any] = {}
    for p in spec.parameters:
        if p.name in spec.swept:
            vals = spec.swept[p.name]
            cattrs = {"long_name": p.description.split(" (")[0]}
            if p.unit:
                cattrs["units"] = p.unit
            coords[p.name] = (p.name, np.array(vals, dtype=str if p.kind is str else None),
                              cattrs)
    coords["circuit"] = ("circuit", np.array(inner["circuit"], dtype=str))
    if "comfort_point" in inner:
        coords["comfort_point"] = ("comfort_point", np.array(inner["comfort_point"], dtype=str),
                                   {"long_name": "car N at the floor point (fraction of the "
                                                 "section length from its centre, negative "
                                                 "forward)"})
    if spec.job.time_series:
        coords["time"] = ("time", np.arange(spec.job.n_steps + 1) * spec.job.dt_s,
                          {"units": "s"})
    variables: dict[str, Any] = {}
    order = ["status", "error"] + [v for v in layout if v not in ("status", "error")]
    for name in order:
        if name not in data:
            continue
        vattrs = dict(attrs.get(name, {}))
        if name in SUMMARY_UNITS:
            vattrs["units"], vattrs["long_name"] = SUMMARY_UNITS[name]
        elif name == "status":
            vattrs["long_name"] = "ok, or error (the run raised; see error)"
        elif name == "error":
            vattrs["long_name"] = "the error of a failed case (type: message), else empty"
        elif name in ("touchdown_circuit", "touchdown_kind"):
            vattrs["long_name"] = ("circuit of the first touchdown" if name.endswith("circuit")
                                   else "closed (magnet on the stator) or landed (on the skids)")
        variables[name] = ((*dims, *layout[name][0]), data[name], vattrs)
    if not layout:      # no cases at all cannot happen (lists are non-empty); keep it safe
        variables["status"] = (tuple(dims), np.full(shape, "", dtype=str), {})
    job = spec.job
    fixed = {f"fixed_{k}": (v if not (isinstance(v, float) and not math.isfinite(v))
                            else str(v)) for k, v in spec.fixed.items()}
    ds = xr.Dataset(variables, coords=coords, attrs={
        "format": SWEEP_FORMAT, "maglevkit": __version__, "sweep": spec.name,
        "source": spec.source, **job.dataset_attrs(), "swept": ",".join(dims),
        "fixed_parameters": json.dumps(dict(spec.fixed), sort_keys=True), **fixed})
    return ds
