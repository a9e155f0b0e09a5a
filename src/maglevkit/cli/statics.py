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


def statics_records(sol, pole_groups=None) -> list[dict[str, float]]:  # type: ignore[no-untyped-def]
    """One record per (gap, current) of a grid solution, per-circuit keys suffixed.

    One circuit: ``gap_m, current_A, force_N, flux_linkage_Wb, differential_inductance_H,
    dpsi_dgap_Wb_per_m``.  With several circuits (all at the same current, all gaps equal)
    the total ``force_N``, then per circuit ``NAME``:

    * ``force_N_NAME``: the force of the circuit's poles (its pole group, as in the maps);
    * ``flux_linkage_Wb_NAME``;
    * ``mutual_inductance_H_NAME``: ``sum_{k != NAME} dpsi_NAME/dI_k``, the part of the
      symmetric-path slope ``dpsi_NAME/dI`` that the other circuits' currents make;
    * ``mutual_dpsi_dgap_Wb_per_m_NAME``: ``dpsi_NAME/ds`` of the other circuits' poles
      moving together;
    * ``differential_inductance_H_NAME`` (``d psi_NAME / dI`` with every circuit's current
      moving together) and ``dpsi_dgap_Wb_per_m_NAME`` (all gaps moving together).

    The force and the two mutual terms are what ``maglevkit maps import`` needs besides
    the flux linkage to reproduce the built maps (docs/reduction.md, "Maps from tables").

    Parameters
    ----------
    sol : StaticSolution
        A grid solution (``grid=True``).
    pole_groups : mapping, optional
        Circuit -> its gap inputs.  Default: the maps' rule
        (:func:`~maglevkit.models.statics.pole_groups_from_sensitivities`) at the grid point
        nearest to :func:`~maglevkit.reduction.maps.pole_group_point`.
    """
    import numpy as np

    names = sol.circuit_names
    multi = len(names) > 1

    def cols(base: str) -> list[str]:
        return [f"{base}_{n}" for n in names] if multi else [base]

    ldiff = sol.common_differential_inductance_H
    dpsi = sol.common_dpsi_dgap_Wb_per_m
    if multi:
        groups = pole_groups or _grid_pole_groups(sol)
        gi = {g: k for k, g in enumerate(sol.gap_names)}
        own = np.zeros((len(names), len(gi)), dtype=bool)
        for j, c in enumerate(names):
            own[j, [gi[g] for g in groups[c]]] = True
        force_j = np.einsum("...k,jk->...j", sol.pole_force_N, own)
        mutual_l = ldiff - np.diagonal(sol.differential_inductance_H, axis1=-2, axis2=-1)
        mutual_s = np.sum(np.where(own, 0.0, sol.dpsi_dgap_Wb_per_m), axis=-1)
        per_circuit = np.concatenate((force_j, sol.flux_linkage_Wb, mutual_l, mutual_s),
                                     axis=-1)
        extra = [*cols("force_N"), *cols("flux_linkage_Wb"), *cols("mutual_inductance_H"),
                 *cols("mutual_dpsi_dgap_Wb_per_m")]
    else:
        per_circuit = sol.flux_linkage_Wb
        extra = cols("flux_linkage_Wb")
    header = ["gap_m", "current_A", "force_N", *extra, *cols("differential_inductance_H"),
              *cols("dpsi_dgap_Wb_per_m")]
    records = []
    ns, ni = sol.force_N.shape
    for i in range(ns):
        for j in range(ni):
            row = [sol.gaps_m[i, j, 0], sol.currents_A[i, j, 0], sol.force_N[i, j],
                   *per_circuit[i, j], *ldiff[i, j], *dpsi[i, j]]
            # "+ 0.0" turns a negative zero (e.g. the force at I = 0) into "0"
            records.append({k: float(v) + 0.0 for k, v in zip(header, row, strict=True)})
    return records


def _grid_pole_groups(sol) -> dict[str, tuple[str, ...]]:  # type: ignore[no-untyped-def]
    """The maps' pole groups from a grid solution's own sensitivities, at the grid point
    nearest to the maps' reference point (:func:`~maglevkit.reduction.maps.pole_group_point`)."""
    import numpy as np

    from ..models.statics import pole_groups_from_sensitivities
    from ..reduction.maps import pole_group_point

    gaps, currents = sol.gaps_m[:, 0, 0], sol.currents_A[0, :, 0]
    ref_gap, ref_current = pole_group_point(gaps, currents)
    k = int(np.argmin(np.abs(gaps - ref_gap)))
    m = int(np.argmin(np.abs(currents - ref_current)))
    if currents[m] == 0.0:          # no flux to tell the poles apart: the largest current
        m = int(np.argmax(np.abs(currents)))
        if currents[m] == 0.0:      # all at 0 A: every force and dpsi/ds is 0, no groups needed
            return {c: () for c in sol.circuit_names}
    return pole_groups_from_sensitivities(sol.dpsi_dgap_Wb_per_m[k, m], sol.circuit_names,
                                          sol.gap_names)


def write_statics_csv(sol, path: Path, pole_groups=None) -> None:  # type: ignore[no-untyped-def]
    """CSV of a grid solution (:func:`statics_records`, 9 significant digits).

    The folder must exist (the command line checks it before solving).
    """
    records = statics_records(sol, pole_groups)
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
