"""``maglevkit statics``: force-current-gap characteristics of a magnet."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Annotated

import typer

from ..errors import MaglevkitError
from ._app import (
    ForceOption,
    FormatOption,
    OutputFormat,
    add_columns,
    app,
    fail,
    info,
    load_magnet_or_exit,
    new_table,
    output_file,
    parse_values,
    plot_file,
    print_records,
    writing,
)


def statics_records(sol) -> list[dict[str, float]]:  # type: ignore[no-untyped-def]
    """One record per (gap, current) of a grid solution, per-circuit keys suffixed.

    With several circuits (all at the same current) the per-circuit keys are
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
    records = []
    ns, ni = sol.force_N.shape
    for i in range(ns):
        for j in range(ni):
            row = [sol.gaps_m[i, j, 0], sol.currents_A[i, j, 0], sol.force_N[i, j],
                   *sol.flux_linkage_Wb[i, j], *ldiff[i, j], *dpsi[i, j]]
            # "+ 0.0" turns a negative zero (e.g. the force at I = 0) into "0"
            records.append({k: float(v) + 0.0 for k, v in zip(header, row, strict=True)})
    return records


def write_statics_csv(sol, path: Path) -> None:  # type: ignore[no-untyped-def]
    """CSV of a grid solution (:func:`statics_records`, 9 significant digits).

    The folder must exist (the command line checks it before solving).
    """
    records = statics_records(sol)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(records[0]))
        for r in records:
            w.writerow([f"{v:.9g}" for v in r.values()])


@app.command(short_help="Force, flux linkage and inductance on a gap x current grid.")
def statics(
    magnet: Annotated[str, typer.Argument(
        metavar="MAGNET", help="Magnet TOML file or bundled name (e.g. u-magnet).")],
    gaps: Annotated[str, typer.Option(help="Gaps [m]: start:stop:count or a comma list.")]
    = "0.004:0.020:9",
    currents: Annotated[str, typer.Option(help="Currents [A] (every circuit): start:stop:count "
                                               "or a comma list.")] = "0:80:17",
    csv_path: Annotated[Path | None, typer.Option("--csv", help="Write the grid to this CSV "
                                                            "file (its folder must exist).")]
    = None,
    plot: Annotated[Path | None, typer.Option(help="Write force-over-current curves (PNG, "
                                                   "PDF, SVG, ... by the file suffix).")]
    = None,
    saturation: Annotated[bool, typer.Option(help="Saturable iron (off: constant mu_r(0)).")]
    = True,
    fringing: Annotated[bool, typer.Option(help="Fringing permeances at the pole edges.")] = True,
    leakage: Annotated[bool, typer.Option(help="Leakage permeances.")] = True,
    fmt: FormatOption = OutputFormat.table,
    force: ForceOption = False,
) -> None:
    """Solve the magnet's statics on a gap x current grid (same current in every circuit).

    Prints the total force at (up to) three currents as a table; --format csv or json
    prints the whole grid instead (the columns of --csv).

    \b
    Example:
      maglevkit statics u-magnet --gaps 0.006:0.014:5 --currents 0:40:9 --csv s.csv
    """
    from ..models.statics import solve_statics

    g = parse_values(gaps, "--gaps", "m")
    c = parse_values(currents, "--currents", "A")
    output_file(csv_path, "--csv", force=force, inputs=(magnet,))
    plot_file(plot, force=force, inputs=(magnet,))
    mag = load_magnet_or_exit(magnet, saturation=saturation, fringing=fringing, leakage=leakage,
                              eddy_currents=False)
    try:
        sol = solve_statics(mag, gaps_m=g, currents_A=c, grid=True)
    except MaglevkitError as exc:
        raise fail(exc) from None
    table = new_table(f"{mag.name}: total force [N]")
    shown = sorted({0, len(c) // 2, len(c) - 1})
    add_columns(table, ["gap [mm]", *(f"I = {c[j]:g} A" for j in shown)])
    for i, s in enumerate(g):
        table.add_row(f"{s * 1e3:.2f}", *(f"{sol.force_N[i, j]:.1f}" for j in shown))
    print_records(statics_records(sol) if fmt != OutputFormat.table else [], fmt, table,
                  meta={"magnet": mag.name, "circuits": list(sol.circuit_names)})
    if csv_path is not None:
        with writing(csv_path, "--csv"):
            write_statics_csv(sol, csv_path)
        info(f"wrote {csv_path}")
    if plot is not None:
        from ..plotting import plot_force_current

        with writing(plot, "--plot"):
            plot_force_current(sol, plot, title=mag.name)
        info(f"wrote {plot}")
    info(f"next: maglevkit maps build {magnet} -o maps.nc (the reduced model's maps), or "
         f"maglevkit simulate {magnet} (a transient)")
