"""``maglevkit sweep SWEEP.toml -o sweep.nc``: scenario sweeps (docs/sweep.md)."""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import MaglevkitError
from ._app import (
    INTERRUPTED_EXIT_CODE,
    ForceOption,
    app,
    console,
    fail,
    info,
    interrupted,
    output_file,
    writing,
)

__all__ = ["INTERRUPTED_EXIT_CODE", "sweep"]


def _resume_folder(path: Path) -> Path:
    if path.exists() and not path.is_dir():
        raise fail(f"--resume-dir {str(path)!r} is a file, not a folder")
    if not path.exists() and not path.parent.is_dir():
        raise fail(f"--resume-dir {str(path)!r}: the directory {str(path.parent)!r} does not "
                   "exist; create it first (only the last folder is created)")
    return path


@app.command("sweep", short_help="Scenario sweeps of vehicle runs into one netCDF dataset.")
def sweep(
    sweep_file: Annotated[str, typer.Argument(metavar="SWEEP_FILE", help="Sweep TOML file or bundled name.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="netCDF file to write (its "
                                                                "folder must exist).")],
    workers: Annotated[int | None, typer.Option(help="Local worker processes (default: the "
                                                     "number of CPUs; 1: in this process).")]
    = None,
    scheduler: Annotated[str | None, typer.Option(
        help="A dask.distributed scheduler address (tcp://host:port), or local-cluster for a "
             "dask LocalCluster of --workers processes on this machine.")] = None,
    scheduler_timeout: Annotated[float, typer.Option(help="Seconds to wait for the scheduler "
                                                          "before giving up.")] = 10.0,
    resume_dir: Annotated[Path | None, typer.Option(
        help="Folder of the stored cases (default: OUTPUT with .cases instead of its suffix); "
             "a rerun skips the cases stored there.")] = None,
    retry_failed: Annotated[bool, typer.Option(help="Run stored failed cases again.")] = False,
    progress: Annotated[bool, typer.Option(help="Progress on stderr.")] = True,
    force: ForceOption = False,
) -> None:
    """Run every combination of a sweep file's parameters and write one netCDF dataset
    (a coordinate per swept parameter; summary per case, errors of failed cases).

    Cases are stored one file each in the resume folder as they finish; interrupt (Ctrl-C)
    and run the same command again to continue.  Results on stdout, progress on stderr.

    \b
    Example:
      maglevkit sweep vehicle-speeds -o sweep.nc --workers 2
    """
    from ..sweep import load_sweep, run_sweep

    output_file(output, "-o", formats=("nc",), force=force, inputs=(sweep_file,))
    folder = _resume_folder(resume_dir if resume_dir is not None
                            else output.with_suffix(".cases"))
    if workers is not None and workers < 1:
        raise fail(f"--workers {workers}: must be >= 1")
    try:
        spec = load_sweep(sweep_file)
    except MaglevkitError as exc:
        raise fail(exc) from None
    client: Any = None
    cluster: Any = None
    executor: Any = None
    try:
        if scheduler == "local-cluster":
            import importlib.util

            if importlib.util.find_spec("distributed") is None:
                raise fail("--scheduler local-cluster needs dask.distributed: pip install "
                           "'maglevkit[distributed]'")
            from distributed import Client, LocalCluster

            cluster = LocalCluster(n_workers=workers or (os.cpu_count() or 1), threads_per_worker=1,
                                   processes=True, dashboard_address=None)
            client = Client(cluster)
            executor = client
        elif scheduler:
            from .maps import connect_scheduler

            client = connect_scheduler(scheduler, scheduler_timeout)
            executor = client
        info(f"sweep {spec.name!r}: {spec.n_cases} cases ("
             + " x ".join(f"{len(v)} {k}" for k, v in spec.swept.items())
             + f"); stored cases in {folder}")
        try:
            res = run_sweep(spec, executor=executor, workers=workers, resume_dir=folder,
                            retry_failed=retry_failed, progress=progress)
        except KeyboardInterrupt:
            from ..sweep import case_path

            # a second Ctrl-C while counting is ignored: the exit is on its way
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            stored = sum(case_path(folder, spec.case_key(c)).is_file() for c in spec.cases())
            raise interrupted(f"{stored} of {spec.n_cases} cases stored in {folder}; run the "
                              "same command again to resume") from None
    except MaglevkitError as exc:
        raise fail(exc) from None
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            import logging

            # the nanny's "still alive after 4 s, killing" while the workers exit is noise
            logging.getLogger("distributed.nanny").setLevel(logging.ERROR)
            cluster.close()
    with writing(output, "-o"):
        res.to_netcdf(output)
    _report(res)
    info(f"wrote {output}")
    info(f"next: xarray.open_dataset({str(output)!r}) (one coordinate per swept parameter; "
         "docs/sweep.md)")


def _report(res: Any) -> None:
    import numpy as np

    ds = res.dataset
    ok = ds["status"].values == "ok"
    console.print(f"{res.n_cases} cases: {res.n_run} run, {res.n_reused} reused from the "
                  f"resume folder; {int(ok.sum())} ok, {res.n_failed} failed")
    if ok.any() and "min_gap" in ds:
        g = ds["min_gap"].values[ok]
        c = ds["max_current"].values[ok]
        td = np.isfinite(ds["touchdown_time"].values[ok]).sum()
        console.print(f"min gap {np.nanmin(g) * 1e3:.3f} mm, max current {np.nanmax(c):.2f} A "
                      f"over the ok cases; {td} with touchdown")
    if res.n_failed:
        dims = list(ds["status"].dims)
        for idx in zip(*np.nonzero(~ok), strict=True):
            label = ", ".join(f"{d}={ds[d].values[i]}" for d, i in zip(dims, idx, strict=True))
            console.print(f"failed: {label}: {ds['error'].values[idx]}")
