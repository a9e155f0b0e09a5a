"""``maglevkit export fmu``: the reduced magnet model as an FMI 2.0 co-simulation FMU."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

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
                                               "must belong to it); alone: the maps file, "
                                               "for maps imported from a table.")],
    maps_file: Annotated[Path | None, typer.Argument(
        metavar="MAPS_FILE", help="netCDF maps of this magnet (maglevkit maps build), or "
                                    "maps imported from a table describing it (maglevkit "
                                    "maps import).")] = None,
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
    three-state ladder (motion_eddy3_* variables).  Maps imported from a table (maglevkit
    maps import) take MAPS_FILE alone, or MAGNET MAPS_FILE with the magnet the table
    describes (its circuits and gaps must be the maps'; it gives the start values); they
    carry eq. 8 only.  See docs/fmu.md.

    \b
    Example:
      maglevkit export fmu tr09-standard maps.nc -o tr09.fmu
      maglevkit export fmu imported.nc -o mine.fmu
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
    output_file(output, "--output", force=force,
                inputs=(magnet,) if maps_file is None else (magnet, maps_file))
    if output.suffix.lower() != ".fmu":
        raise fail(f"--output {str(output)!r}: an FMU file must end in .fmu")
    from ..export import export_fmu

    try:
        mag, maps = _magnet_and_maps(magnet, maps_file)
        if mag is None or _imported_from(maps) is not None:
            modes = _imported_eddy_modes(eddy_modes, motion_eddy, maps)
        else:
            modes = (0 if motion_eddy and eddy_modes is None
                     else eddy_modes_option(eddy_modes, mag))
        lo_s, hi_s = float(maps.gaps_m[0]), float(maps.gaps_m[-1])
        lo_i, hi_i = float(maps.currents_A[0]), float(maps.currents_A[-1])
        for opt, value, lo, hi, unit in (("--gap", gap, lo_s, hi_s, "m"),
                                          ("--current", current, lo_i, hi_i, "A")):
            if value is not None and not lo <= value <= hi:
                raise fail(f"{opt} {value:g} {unit} is outside the maps' range {lo:g}..{hi:g} "
                           f"{unit}")
        if gap is None:
            nominal = getattr(mag, "nominal_gap", None) if mag is not None else None
            gap = nominal if nominal is not None and lo_s <= nominal <= hi_s else None
        if current is None:
            nominal = getattr(mag, "nominal_current", None) if mag is not None else None
            current = nominal if nominal is not None and lo_i <= nominal <= hi_i else None
        result = export_fmu(maps, output, model_identifier=model_identifier,
                            eddy_resistance=eddy_resistance, interpolation=interpolation,
                            max_substep_s=max_substep, start_gaps_m=gap,
                            initial_currents_A=current, motion_eddy=motion_eddy,
                            eddy_branches=eddy_branches, eddy_modes=modes)
    except MaglevkitError as exc:
        raise fail(exc) from None
    of = mag.name if mag is not None else maps.dataset.attrs.get("magnet_name", "the table")
    console.print(f"FMU (FMI 2.0 co-simulation) {result.model_identifier!r} of {of!r}: "
                  f"circuits {', '.join(result.circuit_names)}; inputs "
                  f"{', '.join(result.input_names)}; outputs {', '.join(result.output_names)}; "
                  f"parameters {', '.join(result.parameter_names)}; "
                  f"{result.size_bytes / 1024:.0f} KiB, binary for {result.platform}")
    info(f"wrote {result.path}")
    info(f"next: simulate it in an FMI 2.0 tool, e.g. fmpy.simulate_fmu({str(result.path)!r}, "
         "stop_time=0.2) in Python (docs/fmu.md)")


def _imported_from(maps: Any) -> str | None:
    """The table's source of maps imported from a table (``maglevkit maps import``), else
    None (maps built from a magnet)."""
    source = maps.dataset.attrs.get("table_source")
    return None if source is None else str(source)


def _magnet_and_maps(magnet: str, maps_file: Path | None) -> tuple[Any, Any]:
    """(magnet or None, maps) of the command's one or two arguments.

    Two arguments: built maps must belong to the magnet (the hash of its equivalent
    circuit); imported maps have no such hash (they carry the table's), so the magnet
    must describe them: the same circuits and only gap inputs the magnet has (the magnet
    gives the start values: its nominal point).  One
    argument: the maps file, which must be imported (built maps need their magnet: its
    nominal point and its file's ``[reduced] eddy_modes``)."""
    from ..reduction import load_maps

    if maps_file is None:
        path = Path(magnet)
        if not path.is_file():
            raise fail(f"one argument, {magnet!r}: it must be a maps file imported from a "
                       "table (maglevkit maps import); for a magnet's built maps give "
                       "MAGNET MAPS_FILE")
        maps = load_maps(path)
        if _imported_from(maps) is None:
            raise fail(f"{magnet}: these maps were built from magnet "
                       f"{maps.dataset.attrs.get('magnet_name')!r}; give it too: maglevkit "
                       f"export fmu MAGNET {magnet} (one argument is for maps imported from "
                       "a table)")
        return None, maps
    mag = load_magnet_or_exit(magnet)
    maps = load_maps(maps_file)
    source = _imported_from(maps)
    if source is None:
        maps.check_magnet(mag)
        return mag, maps
    net = mag.network
    if sorted(maps.circuits) != sorted(net.circuit_names):
        raise fail(f"{maps_file}: maps imported from {source!r} have the circuits "
                   f"{', '.join(maps.circuits)}, magnet {mag.name!r} has "
                   f"{', '.join(net.circuit_names)}; import the table with --magnet "
                   f"{magnet}, or give the maps file alone")
    gaps = sorted({g for group in maps.pole_groups.values() for g in group})
    foreign = [g for g in gaps if g not in net.gap_names]
    if foreign:
        raise fail(f"{maps_file}: maps imported from {source!r} drive the gaps "
                   f"{', '.join(foreign)}, which magnet {mag.name!r} does not have (its gaps: "
                   f"{', '.join(net.gap_names)}); import the table with --magnet {magnet}, "
                   "or give the maps file alone")
    return mag, maps


def _imported_eddy_modes(eddy_modes: int | None, motion_eddy: bool, maps: Any) -> int:
    """``--eddy-modes`` for maps without a magnet's network (imported from a table): eq. 8
    only; the eddy network and the shielded-gap ladder are fitted to a detailed model's
    frequency response, which a table does not have."""
    if motion_eddy:
        raise fail("--motion-eddy: maps imported from a table carry no shielded-gap ladder "
                   "(it is fitted to a magnet's detailed model, which a table does not have); "
                   "leave it out (eq. 8 with the table's R_ec)")
    if eddy_modes:
        raise fail(f"--eddy-modes {eddy_modes}: maps imported from a table carry no eddy "
                   "network (it is fitted to a magnet's detailed model, which a table does "
                   "not have); allowed is 0 (eq. 8 with the table's R_ec)")
    return eddy_modes_option(eddy_modes, maps)
