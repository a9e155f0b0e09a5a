"""``maglevkit vehicle run``: the 3-section train on the elastic guideway."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import MaglevkitError, MaglevkitWarning
from ._app import (
    INTERRUPTED_EXIT_CODE,
    ForceOption,
    app,
    fail,
    info,
    interrupted,
    output_dir,
    output_file,
    writing,
)

__all__ = ["INTERRUPTED_EXIT_CODE", "run", "vehicle_app"]

vehicle_app = typer.Typer(help="Vehicle runs: heave-pitch train on an elastic guideway.",
                          no_args_is_help=True, rich_markup_mode=None)
app.add_typer(vehicle_app, name="vehicle",
              short_help="Vehicle runs: heave-pitch train on an elastic guideway.")


@vehicle_app.command("run", short_help="Run the train at constant speed; report gaps, currents, comfort.")
def run(
    vehicle: Annotated[str, typer.Argument(
        metavar="VEHICLE", help="Vehicle TOML file or bundled name.")] = "tr09",
    speed_kmh: Annotated[float | None, typer.Option(
        "--speed-kmh", help="Speed [km/h] (0 ... 2000; default 0, standing; sweep files "
                            "give speed in m/s).")]
    = None,
    speed: Annotated[float | None, typer.Option(
        "--speed", help="Deprecated: the speed in km/h; use --speed-kmh.")] = None,
    duration: Annotated[float, typer.Option(help="Simulated time [s].")] = 1.0,
    dt: Annotated[float, typer.Option(help="Time step [s].")] = 1e-3,
    irregularity: Annotated[str, typer.Option(
        help="Guideway irregularity: sag:A, joints:H, random:RMS[:SEED] (metres), joined by '+', "
             "or none.")] = "none",
    failure: Annotated[list[str] | None, typer.Option(
        metavar="CIRCUIT@T",
        help="CIRCUIT@T: switch a circuit off at T seconds (e.g. s2m4/front@0.5); repeatable.")]
    = None,
    rigid: Annotated[bool, typer.Option(help="Rigid guideway instead of the elastic spans.")] = False,
    guideway: Annotated[str | None, typer.Option(
        metavar="NAME|FILE",
        help="Guideway file (spans, girder data) or bundled name; default the bundled "
             "'guideway' (see: maglevkit list guideways).")] = None,
    magnets: Annotated[str, typer.Option(
        help="reduced (one force per circuit) or detailed (flux models, per pole; slow).")]
    = "reduced",
    maps_cache: Annotated[Path | None, typer.Option(help="Directory of the cached maps.")] = None,
    motion_eddy: Annotated[bool | None, typer.Option(
        "--motion-eddy/--no-motion-eddy",
        help="Reduced magnets with the shielded-gap ladder (eddy currents under gap motion; "
             "a second state per circuit); default: the vehicle file's [magnets] "
             "motion_eddy (off unless set).")] = None,
    eddy_branches: Annotated[int | None, typer.Option(
        "--eddy-branches", metavar="1|2",
        help="Shielded sections of that ladder: 1 (two-state) or 2 (three-state: two eddy "
             "states per circuit); needs --motion-eddy; default: the vehicle file's "
             "[magnets] eddy_branches (1 unless set; 1 for a cross-section).")] = None,
    eddy_modes: Annotated[int | None, typer.Option(
        "--eddy-modes", metavar="0|1|2|3",
        help="Reduced magnets with the maps' fitted eddy network of that many branches (one "
             "state per branch and circuit; 0: eq. 8; not with --motion-eddy), every magnet; "
             "default: the vehicle file's [magnets] eddy_modes, else each magnet file's "
             "[reduced] eddy_modes (the bundled TR09 magnets: 2).")] = None,
    controller: Annotated[str, typer.Option(
        metavar="cascade|mpc",
        help="Gap controllers: cascade (flux cascade, compiled step) or mpc (offset-free "
             "NMPC, real-time iteration, one per circuit, 2 ms sample; NumPy loop, slower).")]
    = "cascade",
    output: Annotated[Path | None, typer.Option("-o", "--output", help="Write the run (netCDF).")]
    = None,
    plot: Annotated[Path | None, typer.Option(help="Write figures (PNG) into this directory.")]
    = None,
    progress: Annotated[bool, typer.Option(
        help="Progress on stderr (a bar on a terminal, plain lines with the ETA in logs).")]
    = True,
    force: ForceOption = False,
    vehicle_option: Annotated[str | None, typer.Option(
        "--vehicle", metavar="NAME|FILE",
        help="Vehicle file or bundled name (as VEHICLE); a cross-section file (e.g. "
             "tr09-cross-section) runs the cross-section model.")] = None,
    curve: Annotated[str | None, typer.Option(
        metavar="RADIUS_M:SUPERELEVATION_DEG:TRANSITION_M",
        help="Cross-section only: enter a curve through a transition of that length "
             "(optional 4th value: its start [m]).")] = None,
    crosswind: Annotated[str | None, typer.Option(
        metavar="PEAK_N[:RISE_S[:HOLD_S[:START_S]]][:SHAPE]",
        help="Cross-section only: lateral gust force on the car body, SHAPE 1-cosine "
             "(default) or step.")] = None,
    lateral: Annotated[str | None, typer.Option(
        metavar="SPEC",
        help="Cross-section only: guidance-rail irregularity random:RMS[:SEED] (alignment "
             "spectrum), girders:H[:SEED] (rail offsets at girder joints), joined by '+'; "
             "--irregularity is then the stator's (vertical).")] = None,
) -> None:
    """Run the train at constant speed; report minimum gaps, peak currents, comfort and the
    real-time factor (results on stdout, diagnostics on stderr).  Ctrl-C stops the run:
    "interrupted" on stderr, exit code 130, and with -o the run up to there is written
    (both vehicles).  A cross-section
    vehicle (--vehicle tr09-cross-section) runs one slice across the track with levitation
    and guidance magnets, curves and crosswind.

    \b
    Example:
      maglevkit vehicle run tr09 --speed-kmh 400 --duration 1.5 -o run.nc
      maglevkit vehicle run --vehicle tr09-cross-section --speed-kmh 400 --duration 6 --curve 4000:12:300
      maglevkit vehicle run tr09 --speed-kmh 400 --duration 0.5 --controller mpc
    """
    if _cross_section_requested(vehicle, vehicle_option, curve, crosswind, lateral):
        if guideway is not None or rigid:
            raise fail("--guideway/--rigid: the cross-section model runs on a rigid "
                       "guideway; leave them out")
        if controller != "cascade":   # was ignored: the run went with cascade controllers
            raise fail(f"--controller {controller}: the cross-section model has cascade "
                       "gap controllers only (the NMPC flies the heave-pitch train); leave "
                       "--controller out")
        if speed is not None:       # was ignored: the run went at 0 km/h
            raise fail(f"--speed {speed:g}: use --speed-kmh for a cross-section run (--speed "
                       "is its deprecated old name)")
        try:
            _run_cross_section(vehicle_option or vehicle, speed_kmh, duration, dt, failure,
                               magnets, maps_cache, output, plot, force, curve, crosswind,
                               irregularity, lateral, progress, bool(motion_eddy),
                               1 if eddy_branches is None else eddy_branches, eddy_modes)
        except KeyboardInterrupt:
            raise interrupted() from None
        return
    if vehicle_option is not None:
        vehicle = vehicle_option
    try:
        _run(vehicle, speed_kmh, speed, duration, dt, irregularity, failure, rigid, magnets,
             maps_cache, output, plot, progress, force, guideway, controller, motion_eddy,
             eddy_branches, eddy_modes)
    except KeyboardInterrupt:
        raise interrupted() from None


def _run(vehicle: str, speed_kmh: float | None, speed: float | None, duration: float,
         dt: float, irregularity: str, failure: list[str] | None, rigid: bool, magnets: str,
         maps_cache: Path | None, output: Path | None, plot: Path | None, progress: bool,
         force: bool, guideway: str | None = None, controller: str = "cascade",
         motion_eddy: bool | None = None, eddy_branches: int | None = None,
         eddy_modes: int | None = None) -> None:
    from ..vehicle.data import load_guideway
    from ..vehicle.simulation import (
        VehicleModel,
        VehicleRunInterrupted,
        parse_failure,
        parse_irregularity,
    )
    from ..vehicle.train import load_vehicle

    output = output_file(output, "-o", formats=("nc",), force=force,   # netCDF, as sweep -o
                         inputs=(vehicle, guideway))
    if plot is not None:   # checked now, created only when the figures are written
        plot = output_dir(plot, "--plot", create=False)
    try:
        # the unit in the option's name: sweep files' speed is in m/s (issue 27)
        opt = "--speed-kmh"
        if speed is not None:
            if speed_kmh is not None:
                raise typer.BadParameter("give --speed-kmh only (--speed is its deprecated "
                                         "old name)")
            warnings.warn("--speed is deprecated and will be removed: use --speed-kmh (the "
                          "same value, km/h; sweep files give speed in m/s)",
                          FutureWarning, stacklevel=1)   # shown to users
            opt, speed_kmh = "--speed", speed
        speed_kmh = _check_run_options(speed_kmh, duration, dt, speed_option=opt)
        if controller not in ("cascade", "mpc"):
            raise typer.BadParameter(f"--controller {controller!r}: use cascade or mpc")
        train = load_vehicle(vehicle)
        fails = [parse_failure(f) for f in (failure or [])]
        prof = parse_irregularity(irregularity, span_length_m=train.section_length_m)
        info(f"setting up {train.name} (maps, controllers) ...")
        track = load_guideway(guideway) if guideway is not None else None
        model = VehicleModel(train, guideway=track, rigid=rigid, magnets=magnets,
                             maps_cache=maps_cache, controller=controller,
                             motion_eddy=motion_eddy, eddy_branches=eddy_branches,
                             eddy_modes=eddy_modes)
        if prof is not None and not rigid:
            with warnings.catch_warnings():   # its warnings were shown by the first parse
                warnings.simplefilter("ignore", MaglevkitWarning)
                prof = parse_irregularity(irregularity,
                                          span_length_m=model.guideway.span.length_m)
        res = model.run(speed_m_per_s=speed_kmh / 3.6, duration_s=duration, dt_s=dt,
                        irregularity=prof, failures=fails, progress=progress)
    except VehicleRunInterrupted as exc:
        raise _interrupted_run(exc, output) from None
    except typer.BadParameter as exc:
        raise fail(str(exc)) from None
    except MaglevkitError as exc:
        raise fail(exc) from None
    from ..vehicle.plots import plot_vehicle_run

    _report_and_write(res, output, plot, plot_vehicle_run)


def _interrupted_run(exc: Any, output: Path | None) -> BaseException:
    """A run stopped by Ctrl-C (``exc``, a ``VehicleRunInterrupted``; either vehicle):
    print its report, write it up to there (-o) and return the exit to raise."""
    # the shared report (one "interrupted" line; a second Ctrl-C is ignored from here)
    stop = interrupted(str(exc.run.dataset.attrs["interrupted"]))
    typer.echo(exc.run.report())
    if output is not None:
        with writing(output, "-o"):
            exc.run.to_netcdf(output)
        info(f"wrote the run up to there to {output}")
    return stop


def _check_run_options(speed_kmh: float | None, duration: float, dt: float, *,
                       speed_option: str = "--speed-kmh") -> float:
    """The speed [km/h] of a run (None: 0), checked with its duration and step [s]; the
    messages name the options (``speed_option``: the one the speed came from)."""
    speed_kmh = 0.0 if speed_kmh is None else speed_kmh
    if not (speed_kmh >= 0 and speed_kmh < 2000):
        raise typer.BadParameter(f"{speed_option} {speed_kmh} km/h must be in 0 ... 2000")
    # the options' names, not the API's (duration_s, dt_s)
    for opt, value in (("--duration", duration), ("--dt", dt)):
        if not (math.isfinite(value) and value > 0):
            raise typer.BadParameter(f"{opt} {value:g}: must be a finite number of "
                                     "seconds > 0")
    if duration < 2 * dt:
        raise typer.BadParameter(f"--duration {duration:g} s is less than two steps of "
                                 f"--dt {dt:g} s")
    return speed_kmh


def _report_and_write(res: Any, output: Path | None, plot: Path | None,
                      plotter: Callable[[Any, Path], list[Path]]) -> None:
    """Print a finished run's report; write it (-o, netCDF) and its figures (--plot)."""
    typer.echo(res.report())
    if output is not None:
        with writing(output, "-o"):
            res.to_netcdf(output)
        info(f"wrote {output}")
    if plot is not None:
        output_dir(plot, "--plot")
        with writing(plot, "--plot"):
            written = plotter(res.dataset, plot)
        for p in written:
            info(f"wrote {p}")
    if output is not None:
        info(f"next: xarray.open_dataset({str(output)!r}) in Python (the run's time series)")
    elif plot is None:
        info("next: add --plot DIR (figures) or -o run.nc (the time series); several runs: "
             "maglevkit list sweeps")


# ---------------------------------------------------------------- cross-section (issue 24)
def _cross_section_requested(vehicle: str, vehicle_option: str | None, curve: str | None,
                             crosswind: str | None, lateral: str | None = None) -> bool:
    """True when the vehicle named is a cross-section file; --curve/--crosswind need one."""
    from ..vehicle.crosssection import bundled_cross_sections

    name = vehicle_option or vehicle
    is_xsec = name in bundled_cross_sections()
    if not is_xsec and Path(name).is_file():
        try:
            import tomllib
        except ImportError:  # pragma: no cover - Python 3.10
            import tomli as tomllib  # type: ignore[no-redef]
        try:
            is_xsec = "cross_section" in tomllib.loads(Path(name).read_text())
        except (OSError, ValueError, UnicodeDecodeError):
            is_xsec = False
    if not is_xsec:
        for opt, val in (("--curve", curve), ("--crosswind", crosswind),
                         ("--lateral", lateral)):
            if val is not None:
                raise fail(f"{opt} {val!r}: needs a cross-section vehicle (--vehicle "
                           f"tr09-cross-section); {name!r} is a heave-pitch train")
    return is_xsec


def _run_cross_section(name: str, speed_kmh: float | None, duration: float, dt: float,
                       failure: list[str] | None, magnets: str, maps_cache: Path | None,
                       output: Path | None, plot: Path | None, force: bool,
                       curve: str | None, crosswind: str | None, irregularity: str = "none",
                       lateral: str | None = None, progress: bool = True,
                       motion_eddy: bool = False, eddy_branches: int = 1,
                       eddy_modes: int | None = None) -> None:
    from ..vehicle.crossrun import (
        CrossSectionModel,
        parse_crosswind,
        parse_curve,
        parse_lateral,
    )
    from ..vehicle.crosssection import load_cross_section
    from ..vehicle.data import load_guideway
    from ..vehicle.simulation import VehicleRunInterrupted, parse_failure, parse_irregularity

    output = output_file(output, "-o", formats=("nc",), force=force, inputs=(name,))
    if plot is not None:   # checked now, created only when the figures are written
        plot = output_dir(plot, "--plot", create=False)
    try:
        speed_kmh = _check_run_options(speed_kmh, duration, dt)
        data = load_cross_section(name)
        fails = [parse_failure(f) for f in (failure or [])]
        crv = parse_curve(curve) if curve is not None else None
        gust = parse_crosswind(crosswind) if crosswind is not None else None
        girder = load_guideway().span.length_m
        vert = parse_irregularity(irregularity, span_length_m=girder)
        lat = parse_lateral(lateral, girder_length_m=girder) if lateral is not None else None
        info(f"setting up {data.name} (maps, controllers) ...")
        model = CrossSectionModel(data, magnets=magnets, maps_cache=maps_cache,
                                  motion_eddy=motion_eddy, eddy_branches=eddy_branches,
                                  eddy_modes=eddy_modes)
        res = model.run(speed_m_per_s=speed_kmh / 3.6, duration_s=duration, dt_s=dt,
                        curve=crv, crosswind=gust, failures=fails, vertical=vert,
                        lateral=lat, progress=progress)
    except VehicleRunInterrupted as exc:   # as the train's: reported, written up to there
        raise _interrupted_run(exc, output) from None
    except typer.BadParameter as exc:
        raise fail(str(exc)) from None
    except MaglevkitError as exc:
        raise fail(exc) from None
    from ..vehicle.crossplots import plot_cross_section_run

    _report_and_write(res, output, plot, plot_cross_section_run)
