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
    workers: Annotated[int, typer.Option(help="Local worker processes (1: in this process).")]
    = 1,
    scheduler: Annotated[str | None, typer.Option(help="Address of a dask.distributed "
                                                        "scheduler (tcp://host:port).")] = None,
) -> None:
    """Compute the maps of a magnet on a regular grid and store them as netCDF."""
    from concurrent.futures import ProcessPoolExecutor

    from ..reduction import build_maps

    g = parse_values(gaps, "--gaps", "m")
    c = parse_values(currents, "--currents", "A")
    mag = load_magnet_or_exit(magnet)
    if workers < 1:
        raise typer.BadParameter("--workers must be >= 1")
    client = None
    try:
        if scheduler:
            from distributed import Client

            client = Client(scheduler)
            executor: object = client
        elif workers > 1:
            executor = ProcessPoolExecutor(max_workers=workers)
        else:
            executor = None
        maps = build_maps(mag, gaps=g, currents=c, executor=executor, progress=True)
    except MaglevkitError as exc:
        raise fail(exc) from None
    finally:
        if client is not None:
            client.close()
    path = maps.to_netcdf(output)
    console.print(f"maps of {mag.name!r}: circuits {', '.join(maps.circuits)}; "
                  f"{g.size} gaps x {c.size} currents")
    console.print(f"wrote {path}")


@maps_app.command("plot")
def plot(
    maps_file: Annotated[Path, typer.Argument(help="netCDF maps file.")],
    out: Annotated[Path, typer.Option(help="Folder for the PNG files.")] = Path("out"),
) -> None:
    """Plot the maps (the paper's Fig. 9): one PNG per circuit."""
    from ..plotting import plot_maps
    from ..reduction import load_maps

    try:
        maps = load_maps(maps_file)
    except MaglevkitError as exc:
        raise fail(exc) from None
    for p in plot_maps(maps, out):
        console.print(f"wrote {p}")
