"""``maglevkit statics``: force-current-gap characteristics of a magnet."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..errors import MaglevkitError
from ._app import app, console, fail, load_magnet_or_exit, parse_values


def write_statics_csv(sol, path: Path) -> None:  # type: ignore[no-untyped-def]
    """CSV of a grid solution: one row per (gap, current), per-circuit columns suffixed.

    With several circuits (all at the same current) the per-circuit columns are
    ``flux_linkage_Wb_NAME``, ``differential_inductance_H_NAME`` (``d psi_NAME / dI`` with
    every circuit's current moving together) and ``dpsi_dgap_Wb_per_m_NAME`` (all gaps
    moving together).
    """
    names = sol.circuit_names
    multi = len(names) > 1

    def cols(base: str) -> list[str]:
        return [f"{base}_{n}" for n in names] if multi else [base]

    header = ["gap_m", "current_A", "force_N", *cols("flux_linkage_Wb"),
              *cols("differential_inductance_H"), *cols("dpsi_dgap_Wb_per_m")]
    ldiff = sol.common_differential_inductance_H
    dpsi = sol.common_dpsi_dgap_Wb_per_m
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        ns, ni = sol.force_N.shape
        for i in range(ns):
            for j in range(ni):
                row = [sol.gaps_m[i, j, 0], sol.currents_A[i, j, 0], sol.force_N[i, j],
                       *sol.flux_linkage_Wb[i, j], *ldiff[i, j], *dpsi[i, j]]
                # "+ 0.0" turns a negative zero (e.g. the force at I = 0) into "0"
                w.writerow([f"{float(v) + 0.0:.9g}" for v in row])


@app.command()
def statics(
    magnet: Annotated[str, typer.Argument(help="Magnet TOML file or bundled name (e.g. u-magnet).")],
    gaps: Annotated[str, typer.Option(help="Gaps [m]: start:stop:count or a comma list.")]
    = "0.004:0.020:9",
    currents: Annotated[str, typer.Option(help="Currents [A] (every circuit): start:stop:count "
                                               "or a comma list.")] = "0:80:17",
    csv_path: Annotated[Path | None, typer.Option("--csv", help="Write the grid to this CSV.")]
    = None,
    plot: Annotated[Path | None, typer.Option(help="Write force-over-current curves (PNG).")]
    = None,
    saturation: Annotated[bool, typer.Option(help="Saturable iron (off: constant mu_r(0)).")]
    = True,
    fringing: Annotated[bool, typer.Option(help="Fringing permeances at the pole edges.")] = True,
    leakage: Annotated[bool, typer.Option(help="Leakage permeances.")] = True,
) -> None:
    """Solve the magnet's statics on a gap x current grid (same current in every circuit)."""
    from ..models.statics import solve_statics
    from ..plotting import plot_force_current

    g = parse_values(gaps, "--gaps", "m")
    c = parse_values(currents, "--currents", "A")
    mag = load_magnet_or_exit(magnet, saturation=saturation, fringing=fringing, leakage=leakage,
                              eddy_currents=False)
    try:
        sol = solve_statics(mag, gaps=g, currents=c, grid=True)
    except MaglevkitError as exc:
        raise fail(exc) from None
    table = Table(title=f"{mag.name}: total force [N]")
    table.add_column("gap [mm]")
    shown = sorted({0, len(c) // 2, len(c) - 1})
    for j in shown:
        table.add_column(f"I = {c[j]:g} A", justify="right")
    for i, s in enumerate(g):
        table.add_row(f"{s * 1e3:.2f}", *(f"{sol.force_N[i, j]:.1f}" for j in shown))
    console.print(table)
    if csv_path is not None:
        write_statics_csv(sol, csv_path)
        console.print(f"wrote {csv_path}")
    if plot is not None:
        plot_force_current(sol, plot, title=mag.name)
        console.print(f"wrote {plot}")
