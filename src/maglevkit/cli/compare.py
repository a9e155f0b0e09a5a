"""``maglevkit compare``: detailed vs reduced model on the standard scenarios (or one file)."""

from __future__ import annotations

import re
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..errors import MaglevkitError
from ._app import (
    FormatOption,
    OutputFormat,
    add_columns,
    app,
    fail,
    info,
    interruptible,
    load_magnet_or_exit,
    new_table,
    output_dir,
    print_records,
    writing,
)

COLUMNS = ("scenario", "circuit", "current NRMS [%]", "force NRMS [%]", "current AC [%]",
           "force AC [%]", "detailed CPU [ms]", "reduced CPU [ms]", "speed-up")
"""Table headers; :func:`comparison_records` has the same columns with unit-suffixed keys."""


def comparison_records(results) -> list[dict[str, object]]:  # type: ignore[no-untyped-def]
    """One record per scenario and circuit (errors in percent, CPU times in ms: the best of
    the timed warm runs, :func:`maglevkit.compare.compare_models`)."""
    rows: list[dict[str, object]] = []
    for r in results:
        for j, c in enumerate(r.circuit_names):
            rows.append({"scenario": r.scenario.name, "circuit": c,
                         "current_nrms_percent": 100 * float(r.current_error[j]),
                         "force_nrms_percent": 100 * float(r.force_error[j]),
                         # None (JSON null, empty CSV cell): no variation to normalise by
                         "current_ac_percent": _percent_or_none(r.current_error_ac[j]),
                         "force_ac_percent": _percent_or_none(r.force_error_ac[j]),
                         "detailed_cpu_ms": 1e3 * float(r.detailed_cpu_s),
                         "reduced_cpu_ms": 1e3 * float(r.reduced_cpu_s),
                         "speedup": float(r.speedup)})
    return rows


def _percent_or_none(value: float) -> float | None:
    v = float(value)
    return None if v != v else 100 * v


def comparison_table(results, title: str) -> Table:  # type: ignore[no-untyped-def]
    """A rich table of errors and speed-ups (cells fold, nothing is cut)."""
    from ..compare import AC_MIN_RELATIVE_VARIATION, format_ac_error

    table = new_table(title)
    add_columns(table, COLUMNS, left=("scenario", "circuit"))
    for r in results:
        for j, c in enumerate(r.circuit_names):
            table.add_row(r.scenario.name if j == 0 else "", c,
                          f"{100 * r.current_error[j]:.3f}", f"{100 * r.force_error[j]:.3f}",
                          format_ac_error(r.current_error_ac[j], suffix="", short=True),
                          format_ac_error(r.force_error_ac[j], suffix="", short=True),
                          f"{r.detailed_cpu_s * 1e3:.0f}" if j == 0 else "",
                          f"{r.reduced_cpu_s * 1e3:.2f}" if j == 0 else "",
                          f"{r.speedup:.0f}" if j == 0 else "")
    table.caption = ("NRMS: RMS(reduced - detailed) / RMS(detailed), the acceptance metric "
                     "(<= 2 %); AC: over the RMS of the detailed signal minus its mean; "
                     "n/a: no variation, the detailed signal varies by less than "
                     f"{100 * AC_MIN_RELATIVE_VARIATION:g} % of its level (RMS about its mean); "
                     + timing_note(results))
    return table


def timing_note(results) -> str:  # type: ignore[no-untyped-def]
    """How the times were taken, for the tables and reports that print them."""
    runs = max((getattr(r, "timing_runs", 1) for r in results), default=1)
    return (f"times: CPU time (process_time) of one run, best of {runs} timed runs after an "
            "untimed warm-up run of each model (warm: compiled, caches filled); speed-up = "
            "detailed / reduced")


def eddy_modes_option(value: int | None, source: object) -> int:
    """The ``--eddy-modes`` option checked, or else ``source``'s default (a magnet or maps:
    :func:`maglevkit.reduction.default_eddy_modes`)."""
    from ..magnets.base import REDUCED_EDDY_MODES
    from ..reduction import default_eddy_modes

    if value is None:
        return default_eddy_modes(source)
    if value not in REDUCED_EDDY_MODES:
        raise fail(f"--eddy-modes {value}: allowed are "
                   f"{', '.join(map(str, REDUCED_EDDY_MODES))} (0: eq. 8 with one R_ec; 1-3: "
                   "the eddy network's RL branches)")
    return int(value)


def reduced_model_name(eddy_modes: int) -> str:
    """What the reduced model with ``eddy_modes`` is, for titles and reports."""
    if eddy_modes == 0:
        return "eq. 8, one eddy resistor R_ec"
    return f"eddy network, {eddy_modes} RL branch{'es' if eddy_modes > 1 else ''}"


def plot_title(name: str, result) -> str:  # type: ignore[no-untyped-def]
    """Figure title with the AC-normalised errors (the plot's own note has the NRMS)."""
    from ..compare import format_ac_error

    ac = ", ".join(f"{c}: I {format_ac_error(ci)}, F {format_ac_error(fi)}" for c, ci, fi in
                   zip(result.circuit_names, result.current_error_ac, result.force_error_ac,
                       strict=True))
    return f"{name} -- AC-normalised RMS error {ac}"


def slug(text: str) -> str:
    return re.sub(r"[^0-9a-z]+", "-", text.lower()).strip("-")


@app.command(short_help="Detailed vs reduced model: errors and speed-up per scenario.")
def compare(
    magnet: Annotated[str, typer.Argument(metavar="MAGNET", help="Magnet TOML file or bundled name.")],
    maps_file: Annotated[Path, typer.Argument(metavar="MAPS_FILE", help="netCDF maps of this magnet "
                                                   "(maglevkit maps build).")],
    scenario: Annotated[str | None, typer.Option(help="Scenario TOML file or bundled name; "
                                                      "default: the standard set (not with "
                                                      "--gap/--current: the file sets its "
                                                      "own).")] = None,
    gap: Annotated[float | None, typer.Option(help="Operating gap [m] (default: nominal).")]
    = None,
    current: Annotated[float | None, typer.Option(help="Operating current [A] "
                                                       "(default: nominal).")] = None,
    out: Annotated[Path | None, typer.Option(help="Folder for response plots (PNG; created "
                                                  "inside an existing directory).")] = None,
    repeat: Annotated[int, typer.Option(min=1, help="Timed runs per model and scenario after "
                                                    "a warm-up run; the best CPU time counts.")]
    = 3,
    extrapolate: Annotated[bool, typer.Option(
        help="Let the reduced model extrapolate beyond its maps' grid (warned) instead of "
             "stopping with an error.")] = False,
    eddy_modes: Annotated[int | None, typer.Option(
        "--eddy-modes", metavar="0|1|2|3",
        help="Reduced model: 0 = eq. 8 (one eddy resistor R_ec), 1-3 = the fitted RL eddy "
             "network with that many branches; default: the magnet file's [reduced] "
             "eddy_modes (0 if it has none).")] = None,
    fmt: FormatOption = OutputFormat.table,
) -> None:
    """Run the detailed flux-based and the reduced current-based model side by side.

    Prints NRMS and AC-normalised errors, CPU times (best of --repeat warm runs) and the
    speed-up per scenario and
    circuit; --format csv or json prints the same columns with unit-suffixed keys.

    \b
    Example:
      maglevkit compare tr09-standard maps.nc --out compare-figures
    """
    from ..compare import ComparisonScenario, compare_models, standard_scenarios
    from ..models.scenario import load_scenario
    from ..reduced.current import CurrentModel
    from ..reduction import load_maps

    if scenario is not None and (gap is not None or current is not None):
        given = " and ".join(f"{o} {v:g}" for o, v in (("--gap", gap), ("--current", current))
                             if v is not None)
        raise fail(f"{given} with --scenario {scenario!r}: a scenario file sets its own gaps "
                   "and initial current ([gaps], [scenario] initial_current); --gap and "
                   "--current set the operating point of the standard scenarios only: "
                   "leave them out or edit the scenario file")
    mag = load_magnet_or_exit(magnet)
    modes = eddy_modes_option(eddy_modes, mag)
    s0 = gap if gap is not None else getattr(mag, "nominal_gap", None)
    i0 = current if current is not None else getattr(mag, "nominal_current", None)
    if scenario is None and (s0 is None or i0 is None):
        raise fail(f"magnet {mag.name!r}: give --gap and --current (the magnet file has no "
                   "[operating] table)")
    if out is not None:
        output_dir(out, "--out")
    try:
        maps = load_maps(maps_file, magnet=mag)
        if scenario is None:
            assert s0 is not None and i0 is not None   # checked above
            cases = standard_scenarios(mag, gap_m=s0, current_A=i0)
            meta = {"magnet": mag.name, "gap_m": s0, "current_A": i0}
        else:
            sc = load_scenario(scenario)
            cases = [ComparisonScenario(
                Path(scenario).stem, "scenario file", sc.duration_s, sc.dt_s,
                gaps_m=sc.inputs_for(mag.network.gap_names, "gaps"),
                voltages_V=sc.inputs_for(mag.network.circuit_names, "voltages"),
                initial_current_A=sc.initial_current_A)]
            # the file's own operating point; the header names the file, not a gap it
            # did not run at (issue 27: "gap_m": 10.0 was printed for --gap 10)
            meta = {"magnet": mag.name, "scenario": str(scenario)}
        reduced = CurrentModel(maps, extrapolate=extrapolate, eddy_modes=modes)
        meta["reduced_eddy_modes"] = modes
        results = []
        start = time.monotonic()
        with interruptible():   # Ctrl-C between chunks of steps, not inside CasADi
            for k, case in enumerate(cases, 1):
                # progress on stderr: the standard set takes ~30 s
                info(f"compare: scenario {k}/{len(cases)} {case.name} ...")
                results += compare_models(mag, reduced, [case],
                                          gap_m=s0 if s0 is not None else 0.0,
                                          current_A=i0 if i0 is not None else 0.0,
                                          repeat=repeat)
        info(f"compare: {len(cases)} scenario(s) done in {time.monotonic() - start:.1f} s")
    except MaglevkitError as exc:
        raise fail(exc) from None
    print_records(comparison_records(results) if fmt != OutputFormat.table else [], fmt,
                  comparison_table(results, f"{mag.name}: detailed vs reduced "
                                            f"({reduced_model_name(modes)})"), meta=meta)
    if out is not None:
        from ..plotting import plot_comparison

        for r in results:
            target = out / f"compare-{slug(r.scenario.name)}.png"
            with writing(target):
                p = plot_comparison(r, target, title=plot_title(mag.name, r))
            info(f"wrote {p}")
    info(f"next: maglevkit export fmu {magnet} {maps_file} -o magnet.fmu (the reduced model "
         "for other tools)" + ("" if out is not None else ", or add --out DIR for figures"))
