"""``maglevkit maps build|plot``: characteristic maps of the current-based model."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import MaglevkitError
from ._app import app, console, fail, load_magnet_or_exit, parse_values

maps_app = typer.Typer(help="Characteristic maps F(s, I), L~(s, I), dL/ds(s, I) (paper Sec. IV).",
                       no_args_is_help=True, rich_markup_mode=None)
app.add_typer(maps_app, name="maps")


@maps_app.command("build")
def build(
    magnet: Annotated[str, typer.Argument(help="Magnet TOML file or bundled name.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="netCDF file to write.")]
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
) -> None:
    """Compute the maps of a magnet on a regular grid and store them as netCDF."""
    from concurrent.futures import ProcessPoolExecutor

    from ..reduction import build_maps
    from ..reduction.maps import METHODS

    if method not in METHODS:
        raise typer.BadParameter(f"--method {method!r}: use one of {', '.join(METHODS)}")
    if workers is not None and workers < 1:
        raise typer.BadParameter("--workers must be >= 1")
    g = parse_values(gaps, "--gaps", "m")
    c = parse_values(currents, "--currents", "A")
    mag = load_magnet_or_exit(magnet)
    client = None
    pool = None
    try:
        executor: object
        if scheduler:
            from distributed import Client

            client = Client(scheduler)
            executor = client
        elif workers is None:
            executor = "auto"
        elif workers > 1:
            pool = ProcessPoolExecutor(max_workers=workers)
            executor = pool
        else:
            executor = None
        maps = build_maps(mag, gaps=g, currents=c, executor=executor, progress=True,
                          method=method)
    except MaglevkitError as exc:
        raise fail(exc) from None
    finally:
        if pool is not None:
            pool.shutdown()
        if client is not None:
            client.close()
    path = maps.to_netcdf(output)
    console.print(f"maps of {mag.name!r} ({method}): circuits {', '.join(maps.circuits)}; "
                  f"{g.size} gaps x {c.size} currents")
    if method == "both":
        for name in ("inductance_relative_difference", "dL_ds_relative_difference"):
            worst = float(abs(maps.dataset[name]).max())
            console.print(f"max |{name}| = {100 * worst:.3f} %")
    console.print(f"wrote {path}")


@maps_app.command("plot")
def plot(
    maps_file: Annotated[Path, typer.Argument(help="netCDF maps file.")],
    out: Annotated[Path, typer.Option(help="Folder for the PNG files.")] = Path("out"),
) -> None:
    """Plot the maps (the paper's Fig. 9): one PNG per circuit.

    Maps built with ``--method both`` also get the per-point relative differences of the
    transient and statics methods (``maps_difference_<circuit>.png``).
    """
    from ..plotting import plot_maps
    from ..reduction import load_maps
    from ..reduction.plots import has_method_differences, plot_method_differences

    try:
        maps = load_maps(maps_file)
    except MaglevkitError as exc:
        raise fail(exc) from None
    paths = plot_maps(maps, out)
    if has_method_differences(maps):
        paths += plot_method_differences(maps, out)
    for p in paths:
        console.print(f"wrote {p}")
