"""``maglevkit simulate``: transient of the flux-based model driven by a scenario file."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import MaglevkitError
from ._app import (
    ForceOption,
    FormatOption,
    OutputFormat,
    add_columns,
    app,
    console,
    fail,
    info,
    interruptible,
    load_magnet_or_exit,
    new_table,
    output_file,
    plot_file,
    print_records,
    writing,
)


def write_simulation_csv(res, path: Path) -> None:  # type: ignore[no-untyped-def]
    """CSV with one row per time sample and unit-suffixed columns (the folder must exist)."""
    import numpy as np

    cols = res.columns()
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(cols))
        data = np.column_stack(list(cols.values()))
        for row in data:
            w.writerow([f"{v:.10g}" for v in row])


def simulation_summary(res) -> list[dict[str, Any]]:  # type: ignore[no-untyped-def]
    """The summary of a run: one record per quantity with its start, end and maximum.

    Quantities: every circuit's current [A], the total force [N]; then the energy
    balance [J] (``end`` = the value over the run) and its relative residual.
    """
    eb = res.energy_balance()
    rows: list[dict[str, Any]] = []
    for j, nm in enumerate(res.circuit_names):
        i = res.currents_A[:, j]
        rows.append({"quantity": f"current[{nm}]", "unit": "A", "start": float(i[0]),
                     "end": float(i[-1]), "max": float(i.max())})
    f = res.force_N
    rows.append({"quantity": "force", "unit": "N", "start": float(f[0]), "end": float(f[-1]),
                 "max": float(f.max())})
    for name, value in (("energy_in", eb.electrical_J), ("energy_ohmic", eb.ohmic_J),
                        ("energy_eddy", eb.eddy_J), ("energy_stored_change", eb.magnetic_change_J),
                        ("energy_mechanical", eb.mechanical_J)):
        rows.append({"quantity": name, "unit": "J", "start": None, "end": float(value),
                     "max": None})
    rows.append({"quantity": "energy_relative_residual", "unit": "1", "start": None,
                 "end": float(eb.relative_residual), "max": None})
    return rows


@app.command(short_help="Transient of the detailed flux-based model under a scenario.")
def simulate(
    magnet: Annotated[str, typer.Argument(metavar="MAGNET", help="Magnet TOML file or bundled name "
                                               "(e.g. u-magnet).")],
    scenario: Annotated[str, typer.Option(help="Scenario TOML file or bundled name (e.g. step).")]
    = "step",
    csv_path: Annotated[Path | None, typer.Option("--csv", help="Write the time series (CSV; "
                                                            "its folder must exist).")]
    = None,
    plot: Annotated[Path | None, typer.Option(help="Write a figure of the response (PNG, PDF, "
                                                   "SVG, ... by the file suffix).")]
    = None,
    fmt: FormatOption = OutputFormat.table,
    force: ForceOption = False,
) -> None:
    """Simulate the flux-based dynamic model (paper eqs. 4-7) under a scenario's signals.

    Prints a summary (currents, force, energy balance); --format csv or json prints it as
    records (quantity, unit, start, end, max).

    \b
    Example:
      maglevkit simulate u-magnet --scenario step --csv run.csv
    """
    from ..models.flux import FluxModel
    from ..models.flux import simulate_flux as run_simulation
    from ..models.scenario import load_scenario

    output_file(csv_path, "--csv", force=force, inputs=(magnet, scenario))
    plot_file(plot, force=force, inputs=(magnet, scenario))
    try:
        sc = load_scenario(scenario)
    except MaglevkitError as exc:
        raise fail(exc) from None
    mag = load_magnet_or_exit(magnet, **sc.model_options)
    try:
        fm = FluxModel(mag, **sc.solver_options)
        volts = sc.inputs_for(fm.circuit_names, "voltages")
        gaps = sc.inputs_for(fm.gap_names, "gaps")
        with interruptible():   # Ctrl-C between chunks of steps, not inside CasADi
            res = run_simulation(fm, (0.0, sc.duration_s), dt_s=sc.dt_s, gaps_m=gaps,
                                 voltages_V=volts, initial_currents_A=sc.initial_current_A)
    except MaglevkitError as exc:
        raise fail(exc) from None
    rows = simulation_summary(res)
    headline = (f"{mag.name}: simulated {sc.duration_s:g} s in {res.time_s.size - 1} steps "
                f"({fm.method}, rtol {fm.rtol:g})")
    if fmt == OutputFormat.table:
        console.print(headline)
        table = new_table()
        add_columns(table, ["quantity", "unit", "start", "end", "max"], left=("quantity", "unit"))
        for r in rows:
            table.add_row(r["quantity"], r["unit"],
                          *("" if r[k] is None else f"{r[k]:.6g}" for k in ("start", "end", "max")))
        console.print(table)
    else:
        print_records(rows, fmt, meta={"magnet": mag.name, "scenario": str(scenario),
                                       "duration_s": sc.duration_s, "steps": res.time_s.size - 1,
                                       "method": fm.method, "rtol": fm.rtol})
    if csv_path is not None:
        with writing(csv_path, "--csv"):
            write_simulation_csv(res, csv_path)
        info(f"wrote {csv_path}")
    if plot is not None:
        from ..plotting import plot_simulation

        with writing(plot, "--plot"):
            plot_simulation(res, plot, title=f"{mag.name}: {Path(str(scenario)).stem}")
        info(f"wrote {plot}")
    info(f"next: maglevkit maps build {magnet} -o maps.nc, then maglevkit compare {magnet} "
         "maps.nc (the reduced model against this one)")
