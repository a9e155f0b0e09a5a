"""``maglevkit design``: optimise a magnet's geometry and coil (IPOPT, exact gradients)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Annotated

import typer

from ..errors import MaglevkitError, MaglevkitWarning
from ._app import (
    ForceOption,
    FormatOption,
    OutputFormat,
    add_columns,
    app,
    console,
    fail,
    info,
    new_table,
    output_file,
    plot_file,
    print_records,
    writing,
)


@app.command(short_help="Optimise a magnet's geometry and coil for mass or power (IPOPT).")
def design(
    spec: Annotated[str, typer.Argument(
        metavar="SPEC", help="Design spec TOML file or bundled name (maglevkit list designs).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Magnet parameter file of the "
                                                                "optimum to write (TOML).")]
    = Path("design.toml"),
    objective: Annotated[str | None, typer.Option(
        help="Override the spec's objective: mass (iron + conductor) or power (R I^2 at the "
             "nominal point).")] = None,
    pareto: Annotated[Path | None, typer.Option(
        help="Also sweep the mass-power Pareto front (epsilon constraint) and plot it to this "
             "figure file; the format follows the suffix (.png, .pdf, .svg, .jpg, ...).")]
    = None,
    pareto_points: Annotated[int, typer.Option(help="Designs on the Pareto front (>= 2).")]
    = 7,
    fmt: FormatOption = OutputFormat.table,
    force: ForceOption = False,
) -> None:
    """Optimise the geometry and coil of the spec's magnet under its constraints and write
    the optimum as a magnet parameter file (tagged "optimised" in its provenance).

    Prints every constraint at the optimum (value, bound, slack, active or not) on stdout;
    the objective, IPOPT's status and iterations on stderr.  docs/design.md describes the
    spec, the variables and the constraints.

    \b
    Example:
      maglevkit design u-magnet-design -o design.toml --pareto front.png
      maglevkit design tr09-design -o tr09-optimised.toml
    """
    from ..design import (
        OBJECTIVES,
        design_magnet,
        pareto_front,
        plot_pareto,
        read_design_spec,
        write_design_toml,
    )

    output_file(output, "--output", formats=("toml",), force=force, inputs=(spec,))
    plot_file(pareto, "--pareto", force=force, inputs=(spec,))
    if objective is not None and objective not in OBJECTIVES:
        raise fail(f"--objective {objective!r}: use one of {', '.join(OBJECTIVES)}")
    if pareto is not None and pareto_points < 2:
        raise fail(f"--pareto-points {pareto_points}: at least 2")
    try:
        problem = read_design_spec(spec)
        with warnings.catch_warnings():     # non-convergence: the error below says it
            warnings.filterwarnings("ignore", message="design_magnet: IPOPT",
                                    category=MaglevkitWarning)
            result = design_magnet(problem, objective=objective)
    except MaglevkitError as exc:
        raise fail(exc) from None
    records = []
    for c in result.constraints.values():
        if c.detail == "variable bound" and not c.active:
            continue
        records.append({"constraint": c.name, "value": c.value, "sense": c.sense,
                        "bound": c.bound, "unit": c.unit, "slack": c.slack,
                        "active": "yes" if c.active else "no",
                        "d_objective_d_bound": c.sensitivity,
                        "detail": c.detail})
    table = new_table("constraints at the optimum (variable bounds: the active ones)")
    add_columns(table, ["constraint", "value", "sense", "bound", "unit", "slack", "active",
                        "d objective/d bound", "detail"],
                left=("constraint", "sense", "unit", "active", "detail"))
    for r in records:
        table.add_row(*(f"{v:.6g}" if isinstance(v, float) else str(v) for v in r.values()))
    meta = {"objective": result.objective, "objective_value": result.objective_value,
            "values": result.values, "mass_kg": result.mass_kg, "power_W": result.power_W,
            "nominal_current_A": result.nominal_current_A, "status": result.status,
            "iterations": result.iterations, "active": list(result.active)}
    print_records(records, fmt, table, meta)
    if fmt is OutputFormat.table:
        for name, v in result.values.items():
            console.print(f"{name} = {v:.6g}")
    unit = "kg" if result.objective == "mass" else "W"
    info(f"{result.objective} = {result.objective_value:.6g} {unit} (mass {result.mass_kg:.4g} "
         f"kg, power {result.power_W:.4g} W at I_n = {result.nominal_current_A:.4g} A); "
         f"IPOPT {result.status} after {result.iterations} iterations")
    if not result.success:
        raise fail(f"IPOPT did not converge ({result.status}); no file written: check that "
                   "the requirements can be met within the variable bounds")
    with writing(output, "--output"):
        path = write_design_toml(result, output)
    info(f"wrote {path}")
    if pareto is not None:
        try:
            front = pareto_front(problem, points=pareto_points)
        except MaglevkitError as exc:
            raise fail(exc) from None
        bad = [r for r in front if not r.success]
        if bad:
            info(f"{len(bad)} of {len(front)} front designs did not converge (left out)")
        with writing(pareto, "--pareto"):
            plot_pareto(front, pareto)
        spread = [r.power_W for r in front if r.success and math.isfinite(r.power_W)]
        info(f"wrote {pareto} ({len(spread)} designs, power {min(spread):.4g} ... "
             f"{max(spread):.4g} W)")
    info(f"next: maglevkit statics {path}")
