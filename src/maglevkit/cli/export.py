"""``maglevkit export fmu``: the reduced magnet model as an FMI 2.0 co-simulation FMU."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from ..errors import MaglevkitError
from ._app import ForceOption, app, console, fail, info, load_magnet_or_exit, output_file
from .compare import eddy_modes_option

export_app = typer.Typer(help="Export the reduced magnet model for other simulation tools.",
                         no_args_is_help=True, rich_markup_mode=None)
app.add_typer(export_app, name="export",
              short_help="Export the reduced model for other tools (FMI 2.0 FMU).")


@export_app.command("fmu", short_help="FMI 2.0 co-simulation FMU of the reduced model (C, no "
                                      "Python needed).")
def fmu(
    magnet: Annotated[str, typer.Argument(metavar="MAGNET", help="Magnet TOML file or bundled name (the maps "
                                               "must belong to it).")],
    maps_file: Annotated[Path, typer.Argument(metavar="MAPS_FILE", help="netCDF maps of this magnet "
                                                   "(maglevkit maps build).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="FMU file to write (.fmu; its "
                                                                "folder must exist).")]
    = Path("magnet.fmu"),
    model_identifier: Annotated[str | None, typer.Option(
        help="FMI model identifier (C identifier); default from the magnet's name.")] = None,
    eddy_resistance: Annotated[str, typer.Option(
        help="R_ec start values from the maps: fit (step-response fit, default) or jump.")]
    = "fit",
    interpolation: Annotated[str, typer.Option(
        help="Map interpolation: bicubic (default, as the Python model), monotone or "
             "bilinear.")] = "bicubic",
    max_substep: Annotated[float, typer.Option(
        help="Longest RK4 sub-step [s] (start value of the FMU parameter).")] = 1e-3,
    gap: Annotated[float | None, typer.Option(
        help="Start value of the gap inputs [m] (default: the magnet's nominal gap if it "
             "has one and the maps cover it, else the middle of the maps).")] = None,
    current: Annotated[float | None, typer.Option(
        help="Start value of the initial currents I0 [A] (default: nominal, as --gap).")]
    = None,
    motion_eddy: Annotated[bool, typer.Option(
        "--motion-eddy", help="Carry the shielded-gap ladder (a second state per circuit, "
                              "for gap motion; docs/bank.md) instead of eq. 8.")] = False,
    eddy_branches: Annotated[int, typer.Option(
        "--eddy-branches", metavar="1|2",
        help="With --motion-eddy: shielded sections of the ladder, 1 (default: one eddy "
             "state per circuit) or 2 (the three-state ladder: I_e1, I_e2 per circuit; "
             "docs/fmu.md).")] = 1,
    eddy_modes: Annotated[int | None, typer.Option(
        "--eddy-modes", metavar="0|1|2|3",
        help="0 = eq. 8 (one eddy resistor R_ec), 1-3 = the fitted RL eddy network with "
             "that many branch currents per circuit; default: the magnet file's [reduced] "
             "eddy_modes (0 if it has none; 0 with --motion-eddy).")] = None,
    force: ForceOption = False,
) -> None:
    """Write an FMI 2.0 co-simulation FMU of the reduced model (paper eq. 8) of every
    circuit: inputs voltages, gaps and gap rates; outputs coil currents and forces;
    R_el and R_ec as parameters; the maps embedded as C arrays; compiled by the system C
    compiler.  --eddy-modes m (default: the magnet file's [reduced] eddy_modes, 2 for the
    bundled TR09 magnets) exports the fitted RL eddy network with m branches instead of
    one R_ec; --motion-eddy the shielded-gap ladder (our extension of eq. 8 for gap
    motion; its maps need the motion_eddy_* variables), with --eddy-branches 2 the
    three-state ladder (motion_eddy3_* variables).  See docs/fmu.md.

    \b
    Example:
      maglevkit export fmu tr09-standard maps.nc -o tr09.fmu
    """
    if not (math.isfinite(max_substep) and max_substep > 0):   # was named max_substep_s
        raise fail(f"--max-substep {max_substep:g}: must be a finite number of seconds > 0")
    if eddy_branches not in (1, 2):
        raise fail(f"--eddy-branches {eddy_branches}: allowed are 1 (the two-state ladder) "
                   "or 2 (the three-state ladder)")
    if motion_eddy and eddy_modes:
        raise fail(f"--eddy-modes {eddy_modes} with --motion-eddy: these are two reduced "
                   "models (the eddy network, the shielded-gap ladder); choose one")
    if eddy_branches == 2 and not motion_eddy:
        raise fail("--eddy-branches 2 needs --motion-eddy (it chooses the shielded-gap "
                   "ladder's sections; without --motion-eddy the FMU carries eq. 8)")
    output_file(output, "--output", force=force, inputs=(magnet, maps_file))
    if output.suffix.lower() != ".fmu":
        raise fail(f"--output {str(output)!r}: an FMU file must end in .fmu")
    from ..export import export_fmu
    from ..reduction import load_maps

    mag = load_magnet_or_exit(magnet)
    modes = 0 if motion_eddy and eddy_modes is None else eddy_modes_option(eddy_modes, mag)
    try:
        maps = load_maps(maps_file, magnet=mag)
        lo_s, hi_s = float(maps.gaps_m[0]), float(maps.gaps_m[-1])
        lo_i, hi_i = float(maps.currents_A[0]), float(maps.currents_A[-1])
        for opt, value, lo, hi, unit in (("--gap", gap, lo_s, hi_s, "m"),
                                          ("--current", current, lo_i, hi_i, "A")):
            if value is not None and not lo <= value <= hi:
                raise fail(f"{opt} {value:g} {unit} is outside the maps' range {lo:g}..{hi:g} "
                           f"{unit}")
        if gap is None:
            nominal = getattr(mag, "nominal_gap", None)
            gap = nominal if nominal is not None and lo_s <= nominal <= hi_s else None
        if current is None:
            nominal = getattr(mag, "nominal_current", None)
            current = nominal if nominal is not None and lo_i <= nominal <= hi_i else None
        result = export_fmu(maps, output, model_identifier=model_identifier,
                            eddy_resistance=eddy_resistance, interpolation=interpolation,
                            max_substep_s=max_substep, start_gaps_m=gap,
                            initial_currents_A=current, motion_eddy=motion_eddy,
                            eddy_branches=eddy_branches, eddy_modes=modes)
    except MaglevkitError as exc:
        raise fail(exc) from None
    console.print(f"FMU (FMI 2.0 co-simulation) {result.model_identifier!r} of {mag.name!r}: "
                  f"circuits {', '.join(result.circuit_names)}; inputs "
                  f"{', '.join(result.input_names)}; outputs {', '.join(result.output_names)}; "
                  f"parameters {', '.join(result.parameter_names)}; "
                  f"{result.size_bytes / 1024:.0f} KiB, binary for {result.platform}")
    info(f"wrote {result.path}")
    info(f"next: simulate it in an FMI 2.0 tool, e.g. fmpy.simulate_fmu({str(result.path)!r}, "
         "stop_time=0.2) in Python (docs/fmu.md)")
