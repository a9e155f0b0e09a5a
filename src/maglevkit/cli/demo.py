"""``maglevkit demo``: the main job on the bundled default magnet, with a short report."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from ._app import app, console, load_magnet_or_exit

DEFAULT_MAGNET = "u-magnet"


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for figures and data.")] = Path("out"),
    magnet: Annotated[str, typer.Option(help="Magnet file or bundled name.")] = DEFAULT_MAGNET,
) -> None:
    """Run the main chain on the default magnet: statics grid, CSV, figures; print a report."""
    from ..models.statics import solve_statics
    from ..plotting import plot_force_current
    from .statics import write_statics_csv

    out.mkdir(parents=True, exist_ok=True)
    mag = load_magnet_or_exit(magnet, eddy_currents=False)
    console.rule(f"maglevkit demo: {mag.name}")
    gaps = np.linspace(0.004, 0.020, 9)
    currents = np.linspace(0.0, 80.0, 33)
    t0 = time.perf_counter()
    sol = solve_statics(mag, gaps=gaps, currents=currents, grid=True)
    dt = time.perf_counter() - t0
    csv_path = out / "statics.csv"
    write_statics_csv(sol, csv_path)
    png = plot_force_current(sol, out / "force_current.png", title=mag.name)
    lin = solve_statics(mag.with_options(saturation=False, eddy_currents=False), gaps=gaps,
                        currents=currents, grid=True)
    i10 = int(np.argmin(np.abs(gaps - 0.010)))
    ratio = sol.force_N[i10, -1] / lin.force_N[i10, -1]
    console.print(f"statics: {gaps.size} x {currents.size} grid solved in {dt * 1e3:.0f} ms")
    console.print(f"force at 10 mm, {currents[-1]:g} A: {sol.force_N[i10, -1]:.0f} N "
                  f"(saturation reduces it to {ratio:.0%} of the unsaturated model)")
    console.print(f"wrote {csv_path}")
    console.print(f"wrote {png}")
