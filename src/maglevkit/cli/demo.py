"""``maglevkit demo``: the whole chain on the bundled default magnet, with a short report.

Statics grid -> figures (paper Figs. 6-7 analogs, coupling) -> characteristic maps
(paper Fig. 9 analog) -> detailed vs reduced comparison on the standard scenarios.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from ..errors import MaglevkitError
from ._app import app, console, fail, info, interruptible, load_magnet_or_exit, output_dir

DEFAULT_MAGNET = "tr09-standard"


def _rule(title: str) -> None:
    """A heading line (at most 100 columns wide, also in a wide log console)."""
    from rich.rule import Rule

    console.print(Rule(title), width=min(console.width, 100))


def _eddy_text(reduced) -> str:  # type: ignore[no-untyped-def]
    """The reduced model's eddy branch in one phrase: eq. 8's ``R_ec`` (the maps' current
    jump) or the network's ``R_0`` and branch time constants ``L_k/R_k`` (the first
    circuit's, at the maps' reference inductance)."""
    maps = reduced.maps
    if reduced.eddy_modes == 0:
        r_ec = maps.dataset["eddy_resistance_ohm"].values
        return f"eq. 8, R_ec = {np.round(r_ec, 2)} ohm"
    ds = maps.dataset.sel(eddy_modes=reduced.eddy_modes)
    m = reduced.eddy_modes
    r_k = np.asarray(ds["eddy_network_resistance_ohm"].values, dtype=float)[:, :m]
    l_k = np.asarray(ds["eddy_network_inductance_H"].values, dtype=float)[:, :m]
    r_0 = np.asarray(ds["eddy_network_r0_ohm"].values, dtype=float)
    tau_ms = ", ".join(f"{1e3 * t:.3g}" for t in (l_k / r_k)[0])
    return (f"network of {m} RL branch{'es' if m > 1 else ''}, R_0 = {np.round(r_0, 1)} ohm, "
            f"branch time constants {tau_ms} ms ({maps.circuits[0]})")


@app.command(short_help="The whole chain on the bundled standard magnet, with a report.")
def demo(
    out: Annotated[Path, typer.Option(help="Folder for figures and data (created inside an "
                                           "existing directory).")] = Path("out"),
    magnet: Annotated[str, typer.Option(help="Magnet file or bundled name.")] = DEFAULT_MAGNET,
    quick: Annotated[bool, typer.Option(help="Skip the slow open-loop comparison cases "
                                             "(0.5 Hz sine).")] = False,
    eddy_modes: Annotated[int | None, typer.Option(
        "--eddy-modes", metavar="0|1|2|3",
        help="Reduced model: 0 = eq. 8 (one eddy resistor R_ec), 1-3 = the fitted RL eddy "
             "network with that many branches; default: the magnet file's [reduced] "
             "eddy_modes (0 if it has none).")] = None,
) -> None:
    """Run statics, figures, maps and the detailed-vs-reduced comparison; print a report.

    The report goes to stdout, the progress of the maps to stderr.

    \b
    Example:
      maglevkit demo --quick --out demo
    """
    from ..compare import compare_models, error_verdicts, standard_scenarios
    from ..figures import write_figures
    from ..models.statics import solve_statics
    from ..plotting import plot_comparison, plot_force_current, plot_maps
    from ..reduced.current import CurrentModel
    from ..reduction import build_maps
    from .compare import (
        comparison_table,
        eddy_modes_option,
        plot_title,
        reduced_model_name,
        slug,
    )
    from .statics import write_statics_csv

    mag = load_magnet_or_exit(magnet)
    modes = eddy_modes_option(eddy_modes, mag)
    output_dir(out, "--out")
    s0 = getattr(mag, "nominal_gap", None) or 0.010
    i0 = getattr(mag, "nominal_current", None)
    _rule(f"maglevkit demo: {mag.name}")
    written: list[Path] = []
    # Ctrl-C between map points and chunks of time steps, not inside CasADi
    try:
        with interruptible(f"the files written so far are in {str(out)!r}"):
            gaps = np.linspace(0.5 * s0, 2.0 * s0, 9)
            currents = np.linspace(0.0, 2.5 * (i0 or 30.0), 33)
            t0 = time.perf_counter()
            sol = solve_statics(mag, gaps_m=gaps, currents_A=currents, grid=True)
            t_stat = time.perf_counter() - t0
            write_statics_csv(sol, out / "statics.csv")
            written += [out / "statics.csv",
                        plot_force_current(sol, out / "force_current.png", title=mag.name)]
            console.print(f"1. statics: {gaps.size} x {currents.size} grid in {t_stat:.2f} s "
                          f"({len(mag.network.branches)} branches, {mag.network.n_loops} loops)")
            if i0 is not None:
                written += write_figures(mag, out)
                console.print("2. figures: paper Fig. 6/7 analogs and the circuit coupling")
            else:
                i0 = 0.4 * float(currents[-1])
                console.print("2. figures: skipped (the magnet file has no [operating] table)")
            mg = np.linspace(0.5 * s0, 1.6 * s0, 12)
            mc = np.linspace(0.0, float(currents[-1]), 41)
            t0 = time.perf_counter()
            maps = build_maps(mag, gaps_m=mg, currents_A=mc, progress=True)
            t_maps = time.perf_counter() - t0
            written.append(maps.to_netcdf(out / "maps.nc"))
            written += plot_maps(maps, out)
            reduced = CurrentModel(maps, eddy_modes=modes)
            console.print(f"3. maps: {mg.size} gaps x {mc.size} currents per circuit in "
                          f"{t_maps:.1f} s; R_el = {maps.dataset['resistance_ohm'].values.round(3)} ohm, "
                          f"eddy: {_eddy_text(reduced)}")
            cases = standard_scenarios(mag, gap_m=s0, current_A=i0)
            if quick:
                cases = [c for c in cases if "0.5 Hz" not in c.name]
            results = compare_models(mag, reduced, cases, gap_m=s0, current_A=i0)
            for r in results:
                written.append(plot_comparison(r, out / f"compare-{slug(r.scenario.name)}.png",
                                               title=plot_title(mag.name, r)))
    except MaglevkitError as exc:
        raise fail(exc) from None
    except OSError as exc:
        raise fail(f"cannot write the demo's files in {str(out)!r}: "
                   f"{exc.strerror or exc}") from None
    console.print(f"4. detailed vs reduced model ({reduced_model_name(modes)}):")
    console.print(comparison_table(results, f"{mag.name}: detailed vs reduced"))
    main = [r for r in results if not r.scenario.coupling]
    worst = max(main, key=lambda r: r.max_error)
    open_loop = [r.speedup for r in main if r.scenario.kind == "open"]
    _rule("report")
    worst_ac = max(main, key=lambda r: r.max_error_ac)
    nrms_verdict, ac_verdict = error_verdicts(worst.max_error, worst_ac.max_error_ac)
    console.print(f"largest normalised RMS error (coupling case excluded): "
                  f"{100 * worst.max_error:.2f} % ({worst.scenario.name}); {nrms_verdict}")
    console.print(f"largest AC-normalised error (RMS over the signal's variation): "
                  f"{100 * worst_ac.max_error_ac:.2f} % ({worst_ac.scenario.name}); "
                  f"{ac_verdict}")
    for r in results:
        if r.scenario.coupling:
            console.print(f"neglected coupling: stepping only '{r.circuit_names[0]}' moves the "
                          f"other circuits' currents by NRMS {100 * r.current_error[1:].max():.3f} % "
                          "in the reduced model's blind spot")
    console.print(f"speed-up of the reduced model (CPU time, best of {results[0].timing_runs} "
                  f"warm runs, open-loop cases): median {np.median(open_loop):.0f}x, range "
                  f"{min(open_loop):.0f}-{max(open_loop):.0f}x")
    console.print(f"{len(written)} files in {out}/:")
    for p in written:
        console.print(f"  {p}")
    info("next: your own magnet: maglevkit template magnet levitation_magnet > my.toml, edit "
         "it, then maglevkit demo --magnet my.toml; the train: maglevkit vehicle run")
