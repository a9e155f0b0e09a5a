"""``maglevkit compare``: detailed vs reduced model on the standard scenarios (or one file)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..errors import MaglevkitError
from ._app import app, console, fail, load_magnet_or_exit


def comparison_table(results, title: str) -> Table:  # type: ignore[no-untyped-def]
    """A rich table of errors and speed-ups."""
    from ..compare import AC_MIN_RELATIVE_VARIATION, format_ac_error

    table = Table(title=title)
    for col in ("scenario", "circuit", "current NRMS [%]", "force NRMS [%]",
                "current AC [%]", "force AC [%]", "detailed [ms]", "reduced [ms]", "speed-up"):
        table.add_column(col, justify="left" if col in ("scenario", "circuit") else "right")
    for r in results:
        for j, c in enumerate(r.circuit_names):
            table.add_row(r.scenario.name if j == 0 else "", c,
                          f"{100 * r.current_error[j]:.3f}", f"{100 * r.force_error[j]:.3f}",
                          format_ac_error(r.current_error_ac[j], suffix="", short=True),
                          format_ac_error(r.force_error_ac[j], suffix="", short=True),
                          f"{r.detailed_wall_s * 1e3:.0f}" if j == 0 else "",
                          f"{r.reduced_wall_s * 1e3:.1f}" if j == 0 else "",
                          f"{r.speedup:.0f}" if j == 0 else "")
    table.caption = ("NRMS: RMS(reduced - detailed) / RMS(detailed), the acceptance metric "
                     "(<= 2 %); AC: over the RMS of the detailed signal minus its mean; "
                     "n/a: no variation, the detailed signal varies by less than "
                     f"{100 * AC_MIN_RELATIVE_VARIATION:g} % of its level (RMS about its mean)")
    return table


def plot_title(name: str, result) -> str:  # type: ignore[no-untyped-def]
    """Figure title with the AC-normalised errors (the plot's own note has the NRMS)."""
    from ..compare import format_ac_error

    ac = ", ".join(f"{c}: I {format_ac_error(ci)}, F {format_ac_error(fi)}" for c, ci, fi in
                   zip(result.circuit_names, result.current_error_ac, result.force_error_ac,
                       strict=True))
    return f"{name} -- AC-normalised RMS error {ac}"


def slug(text: str) -> str:
    return re.sub(r"[^0-9a-z]+", "-", text.lower()).strip("-")


@app.command()
def compare(
    magnet: Annotated[str, typer.Argument(help="Magnet TOML file or bundled name.")],
    maps_file: Annotated[Path, typer.Argument(help="netCDF maps of this magnet "
                                                   "(maglevkit maps build).")],
    scenario: Annotated[str | None, typer.Option(help="Scenario TOML file or bundled name; "
                                                      "default: the standard set.")] = None,
    gap: Annotated[float | None, typer.Option(help="Operating gap [m] (default: nominal).")]
    = None,
    current: Annotated[float | None, typer.Option(help="Operating current [A] "
                                                       "(default: nominal).")] = None,
    out: Annotated[Path | None, typer.Option(help="Folder for response plots (PNG).")] = None,
) -> None:
    """Run the detailed flux-based and the reduced current-based model side by side."""
    from ..compare import ComparisonScenario, compare_models, standard_scenarios
    from ..models.current import CurrentModel
    from ..models.scenario import load_scenario
    from ..plotting import plot_comparison
    from ..reduction import load_maps

    mag = load_magnet_or_exit(magnet)
    try:
        maps = load_maps(maps_file, magnet=mag)
        s0 = gap if gap is not None else getattr(mag, "nominal_gap", None)
        i0 = current if current is not None else getattr(mag, "nominal_current", None)
        if s0 is None or i0 is None:
            raise typer.BadParameter("give --gap and --current (the magnet file has no "
                                     "[operating] table)")
        if scenario is None:
            cases = standard_scenarios(mag, gap_m=s0, current_A=i0)
        else:
            sc = load_scenario(scenario)
            cases = [ComparisonScenario(
                Path(scenario).stem, "scenario file", sc.duration_s, sc.dt_s,
                gaps=sc.inputs_for(mag.network.gap_names, "gaps"),
                voltages=sc.inputs_for(mag.network.circuit_names, "voltages"),
                initial_current_A=sc.initial_current_A)]
        results = compare_models(mag, CurrentModel(maps), cases, gap_m=s0, current_A=i0)
    except MaglevkitError as exc:
        raise fail(exc) from None
    console.print(comparison_table(results, f"{mag.name}: detailed vs reduced"))
    if out is not None:
        for r in results:
            p = plot_comparison(r, out / f"compare-{slug(r.scenario.name)}.png",
                                title=plot_title(mag.name, r))
            console.print(f"wrote {p}")
