"""``maglevkit maps build|plot``: characteristic maps of the current-based model."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from .._interrupt import stop_pool
from ..errors import InputError, MaglevkitError
from ._app import (
    ForceOption,
    app,
    console,
    fail,
    info,
    interruptible,
    load_magnet_or_exit,
    output_dir,
    output_file,
    parse_values,
    writing,
)

maps_app = typer.Typer(help="Characteristic maps F(s, I), L~(s, I), dL/ds(s, I) (paper Sec. IV).",
                       no_args_is_help=True, rich_markup_mode=None)
app.add_typer(maps_app, name="maps",
              short_help="Characteristic maps of the reduced model: build (netCDF) and plot.")

SCHEDULER_TIMEOUT_S = 10.0
"""Default ``--scheduler-timeout`` [s] (dask's own default is 30 s)."""


def connect_scheduler(address: str, timeout_s: float) -> Any:
    """A ``dask.distributed.Client`` for ``address``, or an :class:`InputError` that says why not.

    A ``tcp://host:port`` address is first probed with a plain TCP connection (at most
    ``timeout_s``), before dask is even imported, so a refused connection fails at once
    instead of after dask's retries (30 s by default).
    """
    import importlib.util
    from urllib.parse import urlsplit

    if importlib.util.find_spec("distributed") is None:
        raise InputError("--scheduler needs dask.distributed: pip install "
                         "'maglevkit[distributed]'")
    if not (math.isfinite(timeout_s) and timeout_s > 0.0):
        raise InputError(f"--scheduler-timeout = {timeout_s!r} s must be a number > 0")
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if parts.scheme not in ("tcp", "tls", "inproc", "ucx", "ws", "wss") or \
            (parts.scheme == "tcp" and (not host or port is None)):
        raise InputError(f"--scheduler {address!r}: expected an address like tcp://host:8786")
    if parts.scheme == "tcp" and host and port is not None:
        import socket

        try:
            socket.create_connection((host, port), timeout=timeout_s).close()
        except OSError as exc:
            why = "timed out" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc))
            raise InputError(f"cannot reach the dask scheduler at {address}: {why} (waited at "
                             f"most {timeout_s:g} s, --scheduler-timeout); start one with "
                             "`dask scheduler` or check the address") from None
    from distributed import Client

    try:
        return Client(address, timeout=timeout_s)
    except Exception as exc:   # noqa: BLE001 - any failure of the remote end is reported
        detail = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise InputError(f"could not connect to the dask scheduler at {address} within "
                         f"{timeout_s:g} s (--scheduler-timeout): {detail} (is it a dask "
                         "scheduler?)") from None


@maps_app.command("build", short_help="Compute the maps on a regular grid (netCDF).")
def build(
    magnet: Annotated[str, typer.Argument(metavar="MAGNET", help="Magnet TOML file or bundled name.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="netCDF file to write (its "
                                                                "folder must exist).")]
    = Path("maps.nc"),
    gaps: Annotated[str, typer.Option(help="Gap grid [m], start:stop:count (equidistant).")]
    = "0.004:0.020:17",
    currents: Annotated[str, typer.Option(help="Current grid [A], start:stop:count.")]
    = "0:80:33",
    method: Annotated[str, typer.Option(help="How L~ and dL/ds are computed: statics (exact "
                                             "sensitivities, fast), transient (the paper's "
                                             "time integrations) or both (statics plus "
                                             "transient and their relative differences).")]
    = "statics",
    workers: Annotated[int | None, typer.Option(help="Local worker processes (1: in this "
                                                     "process; default: automatic, a pool "
                                                     "for transient maps).")] = None,
    scheduler: Annotated[str | None, typer.Option(help="Address of a dask.distributed "
                                                        "scheduler (tcp://host:port).")] = None,
    scheduler_timeout: Annotated[float, typer.Option(help="Seconds to wait for the scheduler "
                                                          "before giving up.")]
    = SCHEDULER_TIMEOUT_S,
    force: ForceOption = False,
) -> None:
    """Compute the maps of a magnet on a regular grid and store them as netCDF.

    Progress goes to stderr: a progress bar on a terminal, otherwise a plain line with
    the ETA every 10 % (at least every 10 s).

    \b
    Example:
      maglevkit maps build tr09-standard -o maps.nc
    """
    from concurrent.futures import ProcessPoolExecutor

    if workers is not None and workers < 1:
        raise typer.BadParameter("--workers must be >= 1")
    g = parse_values(gaps, "--gaps", "m")
    c = parse_values(currents, "--currents", "A")
    output_file(output, "--output", force=force, inputs=(magnet,))
    client = None
    if scheduler:   # before the heavy imports: an unreachable scheduler fails at once
        try:
            client = connect_scheduler(scheduler, scheduler_timeout)
        except MaglevkitError as exc:
            raise fail(exc) from None

    from ..reduction import build_maps
    from ..reduction.maps import METHODS

    if method not in METHODS:
        if client is not None:
            client.close()
        raise typer.BadParameter(f"--method {method!r}: use one of {', '.join(METHODS)}")
    pool = None
    built = False
    try:
        mag = load_magnet_or_exit(magnet)
        executor: object
        if client is not None:
            executor = client
        elif workers is None:
            executor = "auto"
        elif workers > 1:
            pool = ProcessPoolExecutor(max_workers=workers)
            executor = pool
        else:
            executor = None
        # a Ctrl-C, or whatever failure CasADi made of it (a second Ctrl-C): interrupted
        with interruptible(f"no maps written to {str(output)!r}"):
            maps = build_maps(mag, gaps_m=g, currents_A=c, executor=executor, progress=True,
                              method=method)
        built = True
    except MaglevkitError as exc:
        raise fail(exc) from None
    finally:
        if pool is not None:
            if built:
                pool.shutdown()
            else:   # interrupted or failed: stop the workers, do not run the rest
                stop_pool(pool)
        if client is not None:
            client.close()
    with writing(output, "--output"):
        path = maps.to_netcdf(output)
    console.print(f"maps of {mag.name!r} ({method}): circuits {', '.join(maps.circuits)}; "
                  f"{g.size} gaps x {c.size} currents")
    if method == "both":
        for name in ("inductance_relative_difference", "dL_ds_relative_difference"):
            worst = float(abs(maps.dataset[name]).max())
            console.print(f"max |{name}| = {100 * worst:.3f} %")
    info(f"wrote {path}")
    info(f"next: maglevkit compare {magnet} {path} (detailed vs reduced), or maglevkit maps "
         f"plot {path}")


@maps_app.command("plot", short_help="Plot the maps (the paper's Fig. 9 analog, PNG).")
def plot(
    maps_file: Annotated[Path, typer.Argument(metavar="MAPS_FILE", help="netCDF maps file.")],
    out: Annotated[Path, typer.Option(help="Folder for the PNG files (created inside an "
                                           "existing directory).")] = Path("out"),
) -> None:
    """Plot the maps (the paper's Fig. 9): one PNG per circuit.

    Maps built with --method both also get the per-point relative differences of the
    transient and statics methods (maps_difference_<circuit>.png).

    \b
    Example:
      maglevkit maps plot maps.nc --out maps-figures
    """
    from ..reduction import load_maps
    from ..reduction.plots import has_method_differences

    try:
        maps = load_maps(maps_file)
    except MaglevkitError as exc:
        raise fail(exc) from None
    output_dir(out, "--out")
    from ..plotting import plot_maps
    from ..reduction.plots import plot_method_differences

    try:
        with writing(out, "plots in"):
            paths = plot_maps(maps, out)
            if has_method_differences(maps):
                paths += plot_method_differences(maps, out)
    except MaglevkitError as exc:
        raise fail(exc) from None
    for p in paths:
        info(f"wrote {p}")
