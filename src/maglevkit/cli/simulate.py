"""``maglevkit simulate``: transient of the flux-based model driven by a scenario file."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape

from ..errors import MaglevkitError
from ._app import app, console, fail, load_magnet_or_exit


def write_simulation_csv(res, path: Path) -> None:  # type: ignore[no-untyped-def]
    """CSV with one row per time sample and unit-suffixed columns."""
    cols = res.columns()
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(cols))
        data = np.column_stack(list(cols.values()))
        for row in data:
            w.writerow([f"{v:.10g}" for v in row])


@app.command()
def simulate(
    magnet: Annotated[str, typer.Argument(help="Magnet TOML file or bundled name "
                                               "(e.g. u-magnet).")],
    scenario: Annotated[str, typer.Option(help="Scenario TOML file or bundled name (e.g. step).")]
    = "step",
    csv_path: Annotated[Path | None, typer.Option("--csv", help="Write the time series (CSV).")]
    = None,
    plot: Annotated[Path | None, typer.Option(help="Write a figure of the response (PNG).")]
    = None,
) -> None:
    """Simulate the flux-based dynamic model (paper eqs. 4-7) under a scenario's signals."""
    from ..models.flux import FluxModel
    from ..models.flux import simulate as run_simulation
    from ..models.scenario import load_scenario
    from ..plotting import plot_simulation

    try:
        sc = load_scenario(scenario)
    except MaglevkitError as exc:
        raise fail(exc) from None
    mag = load_magnet_or_exit(magnet, **sc.model_options)
    try:
        fm = FluxModel(mag, **sc.solver_options)
        volts = sc.inputs_for(fm.circuit_names, "voltages")
        gaps = sc.inputs_for(fm.gap_names, "gaps")
        res = run_simulation(fm, (0.0, sc.duration_s), dt=sc.dt_s, gaps=gaps, voltages=volts,
                             initial_currents=sc.initial_current_A)
    except MaglevkitError as exc:
        raise fail(exc) from None
    eb = res.energy_balance()
    console.print(f"{mag.name}: simulated {sc.duration_s:g} s in {res.time_s.size - 1} steps "
                  f"({fm.method}, rtol {fm.rtol:g})")
    for j, nm in enumerate(res.circuit_names):
        line = (f"  current [{nm}]: {res.currents_A[0, j]:.4g} A -> {res.currents_A[-1, j]:.4g} A "
                f"(max {res.currents_A[:, j].max():.4g} A)")
        console.print(escape(line))
    console.print(f"  total force: {res.force_N[0]:.5g} N -> {res.force_N[-1]:.5g} N")
    console.print(f"  energy: in {eb.electrical_J:.5g} J = ohmic {eb.ohmic_J:.5g} + eddy "
                  f"{eb.eddy_J:.5g} + stored {eb.magnetic_change_J:.5g} + mechanical "
                  f"{eb.mechanical_J:.5g} (relative residual {eb.relative_residual:.1e})")
    if csv_path is not None:
        write_simulation_csv(res, csv_path)
        console.print(f"wrote {csv_path}")
    if plot is not None:
        plot_simulation(res, plot, title=f"{mag.name}: {Path(str(scenario)).stem}")
        console.print(f"wrote {plot}")
