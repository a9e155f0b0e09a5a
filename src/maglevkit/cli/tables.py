"""``maglevkit maps import`` (maps from measured or FEM tables) and ``maglevkit calibrate``
(a magnet's uncertain factors fitted to measured statics)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import MaglevkitError
from ._app import (
    ForceOption,
    FormatOption,
    OutputFormat,
    add_columns,
    app,
    console,
    fail,
    info,
    load_magnet_or_exit,
    new_table,
    output_file,
    parse_values,
    print_records,
    writing,
)
from .maps import maps_app


def _ohms(text: str | None, option: str) -> Any:
    if text is None:
        return None
    eddy = option == "--eddy-resistance"
    allowed = ("one resistance > 0 in ohm, or one per circuit separated by commas"
               + (" (inf: no eddy currents)" if eddy else ""))
    vals: list[float] = []
    for k, item in enumerate(v.strip() for v in text.split(",")):
        if not item:
            continue
        try:
            val = float(item)
        except ValueError:
            raise fail(f"{option} {text!r}: value {k + 1}, {item!r}, is not a number; give "
                       f"{allowed}") from None
        if not (val > 0.0 and (math.isfinite(val) or (eddy and val == math.inf))):
            raise fail(f"{option} {text!r}: value {k + 1}, {item!r}, is not a resistance "
                       f"> 0{' (or inf)' if eddy else ''}; give {allowed}")
        vals.append(val)
    if not vals:
        raise fail(f"{option} {text!r}: no value; give {allowed}")
    return vals[0] if len(vals) == 1 else vals


def _cli_names(exc: Exception) -> str:
    """The library's keyword names in a message, as this command's options."""
    return (str(exc).replace("eddy_resistance_ohm", "--eddy-resistance")
            .replace("resistance_ohm", "--resistance")
            .replace("reciprocity_tolerance", "--reciprocity-tolerance"))


def _read_step(path: Path) -> tuple[Any, Any]:
    """``time_s``, ``current_A`` columns of a measured voltage step (CSV)."""
    import csv

    import numpy as np

    from ..errors import DataError

    if not path.is_file():
        raise DataError(f"--voltage-step {str(path)!r} does not exist")
    with path.open(newline="", encoding="utf-8-sig") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    if not rows or [h.strip() for h in rows[0]] != ["time_s", "current_A"]:
        raise DataError(f"{path}: a voltage step needs the columns time_s, current_A, got "
                        f"{rows[0] if rows else 'an empty file'}")
    data = np.empty((len(rows) - 1, 2))
    for i, r in enumerate(rows[1:]):
        try:
            data[i] = [float(r[0]), float(r[1])]
        except (ValueError, IndexError):
            raise DataError(f"{path}: data row {i + 1} ({r}) is not two numbers") from None
    return data[:, 0], data[:, 1]


@maps_app.command("import", short_help="Maps from a table of psi(s, I) and/or F(s, I) (CSV, "
                                       "netCDF).")
def import_table(
    data: Annotated[Path, typer.Argument(metavar="DATA", help="CSV (gap_m, current_A, force_N and/or "
                                              "flux_linkage_Wb[_<circuit>]; the file of "
                                              "maglevkit statics --csv) or netCDF table.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="netCDF maps file to write.")]
    = Path("maps.nc"),
    resistance: Annotated[str | None, typer.Option(help="R_el [ohm], one value or one per "
                                                        "circuit (comma list); default: the "
                                                        "magnet's.")] = None,
    eddy_resistance: Annotated[str | None, typer.Option(help="R_ec [ohm], one value or one per "
                                                             "circuit; inf: no eddy currents "
                                                             "(default).")] = None,
    voltage_step: Annotated[Path | None, typer.Option(help="Measured voltage step (CSV: "
                                                           "time_s, current_A; step at t = 0) "
                                                           "giving R_ec (one circuit).")] = None,
    step_voltage: Annotated[float | None, typer.Option(help="The step's voltage change [V] "
                                                            "(with --voltage-step).")] = None,
    magnet: Annotated[str | None, typer.Option(help="The magnet the table describes (bundled "
                                                    "name or TOML): circuit and gap names, "
                                                    "R_el.")] = None,
    name: Annotated[str | None, typer.Option(help="Name stored in the maps.")] = None,
    reciprocity_tolerance: Annotated[float, typer.Option(help="Largest relative co-energy "
                                                              "reciprocity residual accepted.")]
    = 0.1,
    force: ForceOption = False,
) -> None:
    """Build characteristic maps from a table: L~ and dL/ds from the flux linkage's spline,
    the force from the table or by co-energy; checks reciprocity, monotonicity and the grid
    (docs/reduction.md, "Maps from tables").  Warnings name the gap, current and row.

    \b
    Example:
      maglevkit maps import measured.csv --magnet tr09-standard -o maps.nc
    """
    from ..reduction.tables_in import eddy_resistance_from_step, maps_from_table, table_report

    output_file(output, "--output", force=force,
                inputs=(data, voltage_step, magnet))
    mag = load_magnet_or_exit(magnet) if magnet is not None else None
    r_el = _ohms(resistance, "--resistance")
    r_ec = _ohms(eddy_resistance, "--eddy-resistance")
    if (voltage_step is None) != (step_voltage is None):
        raise fail("--voltage-step and --step-voltage go together (the measured step and its "
                   "voltage change [V])")
    if voltage_step is not None and r_ec is not None:
        raise fail("give R_ec either as --eddy-resistance or from --voltage-step, not both")
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        try:
            if voltage_step is not None:
                if r_el is None and mag is None:
                    raise fail("--voltage-step needs R_el: give --resistance or --magnet")
                r_step = r_el if r_el is not None else float(
                    mag.network.resistances[0])  # type: ignore[union-attr]
                if isinstance(r_step, list):
                    raise fail("--voltage-step identifies one circuit: give one --resistance")
                t, i = _read_step(voltage_step)
                ident = eddy_resistance_from_step(t, i, voltage_step_V=float(step_voltage or 0.0),
                                                  resistance_ohm=float(r_step))
                r_ec = ident.eddy_resistance_ohm
                info(f"voltage step: tau = {ident.time_constant_s:.6g} s, L~ = "
                     f"{ident.inductance_H:.6g} H, R_ec = {r_ec:.6g} ohm")
            maps = maps_from_table(data, resistance_ohm=r_el,
                                   eddy_resistance_ohm=float("inf") if r_ec is None else r_ec,
                                   magnet=mag, name=name,
                                   reciprocity_tolerance=reciprocity_tolerance)
        except MaglevkitError as exc:
            raise fail(_cli_names(exc)) from None
    with writing(output, "--output"):
        path = maps.to_netcdf(output)
    rep = table_report(maps)
    console.print(f"maps of {maps.dataset.attrs['magnet_name']!r} (imported table): circuits "
                  f"{', '.join(maps.circuits)}; {maps.gaps_m.size} gaps x "
                  f"{maps.currents_A.size} currents; force {rep.force_from}")
    for c, v in rep.reciprocity_max.items():
        if v == v:   # not NaN
            console.print(f"reciprocity residual {c}: max {100 * v:.3g} % at "
                          f"{rep.reciprocity_worst[c]}")
    info(f"wrote {path}")
    info(f"next: maglevkit export fmu {str(path)!r} -o magnet.fmu (an FMU of these maps), "
         f"or mk.CurrentModel(mk.load_maps({str(path)!r})) in Python")


def _comma_labels(text: str, labels: list[str]) -> list[str]:
    """``--holdout-steps``' comma list as step labels: the one way of joining its pieces
    into known labels (labels may contain commas); the CLI's error otherwise (no reading:
    the unknown pieces and the labels; several: the readings, and ``--holdout-step``)."""
    parts = text.split(",")
    known = set(labels)
    readings: list[list[str]] = []

    def walk(k: int, acc: list[str]) -> None:
        if len(readings) > 1:
            return
        if k == len(parts):
            readings.append(acc)
            return
        if not parts[k].strip():
            walk(k + 1, acc)                    # an empty piece (",," or a trailing comma)
        for end in range(k + 1, len(parts) + 1):
            seg = ",".join(parts[k:end]).strip()
            if seg and seg in known:
                walk(end, [*acc, seg])

    walk(0, [])
    with_commas = [lab for lab in labels if "," in lab]
    hint = ("; labels with commas: give each with --holdout-step LABEL (repeatable)"
            if with_commas else "")
    if not readings:
        unknown = [p.strip() for p in parts if p.strip() and p.strip() not in known]
        raise fail(f"--holdout-steps {text!r}: no step with the label(s) {unknown}; the "
                   f"steps: {labels}{hint}")
    if len(readings) > 1:
        raise fail(f"--holdout-steps {text!r} is ambiguous: it reads as {readings[0]} or as "
                   f"{readings[1]} (step labels contain commas: {with_commas}); give each "
                   "label with --holdout-step LABEL (repeatable)")
    return list(dict.fromkeys(readings[0]))


@app.command("calibrate", short_help="Fit a magnet's network factors to measured statics.")
def calibrate_cmd(
    magnet: Annotated[str, typer.Argument(metavar="MAGNET",
                                          help="Magnet TOML file or bundled name.")],
    data: Annotated[Path, typer.Argument(metavar="DATA", help="Measured statics, CSV (gap_m, current_A, "
                                              "force_N and/or flux_linkage_Wb[_<circuit>]).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Calibrated magnet TOML to "
                                                                "write.")]
    = Path("calibrated.toml"),
    params: Annotated[str | None, typer.Option("--params", help="Parameters to fit (comma "
                                                                "list; default: the five "
                                                                "static factors, with --steps "
                                                                "also the eddy conductance "
                                                                "and R_el scales).")] = None,
    holdout_gaps: Annotated[str | None, typer.Option("--holdout-gaps", help="Gaps [m] left out "
                                                                           "of the fit and "
                                                                           "reported (comma "
                                                                           "list).")] = None,
    steps: Annotated[Path | None, typer.Option("--steps", help="Measured voltage steps "
                                                    "fitted too (CSV: time_s, current_A, "
                                                    "gap_m, initial_current_A, voltage_V "
                                                    "[, step, circuit]).")] = None,
    holdout_steps: Annotated[str | None, typer.Option("--holdout-steps", help=(
        "Labels of --steps' steps left out of the fit and reported (comma list; refused "
        "when step labels with commas make it ambiguous: then --holdout-step)."))] = None,
    holdout_step: Annotated[list[str] | None, typer.Option("--holdout-step", metavar="LABEL", help=(
        "One label of a --steps step left out of the fit and reported, taken as it is "
        "(commas included); repeatable."))] = None,
    select: Annotated[bool, typer.Option("--select-params", help=(
        "Choose the static parameters among the subsets of --params (default: the five "
        "static factors) by leave-one-gap-out cross-validation on the fitted gaps (never "
        "the --holdout-gaps), then fit the best set."))] = False,
    fmt: FormatOption = OutputFormat.table,
    force: ForceOption = False,
) -> None:
    """Calibrate the magnet's leakage and fringing factors, gap offset and iron B-H scalings
    to measured force and/or flux linkage (bounded least squares, exact derivatives);
    with --steps also its eddy conductance and R_el scales to measured voltage steps.

    Prints the values with 95 % confidence intervals, the parameters the data cannot
    determine, and the relative error per point (fitted and held out); --format csv or json
    prints the per-point errors.  Writes the magnet file with a [calibration] table
    (values tagged calibrated, with the data file's SHA-256); every command taking MAGNET
    loads that file with the factors applied.

    \b
    Example:
      maglevkit calibrate tr09-standard measured.csv -o tr09-calibrated.toml
      maglevkit calibrate u-magnet statics.csv --steps steps.csv -o calibrated.toml
    """
    from ..calibration import (
        DEFAULT_PARAMETERS,
        DYNAMIC_PARAMETERS,
        PARAMETERS,
        calibrate,
        read_steps,
        select_parameters,
        write_calibrated_toml,
    )

    output_file(output, "--output", force=force, inputs=(magnet, data, steps))
    names = None
    if params is not None:
        names = [p.strip() for p in params.split(",") if p.strip()]
        unknown = [p for p in names if p not in PARAMETERS]
        if unknown or not names:
            raise fail(f"--params {params!r}: unknown {unknown}; choose from "
                       f"{', '.join(PARAMETERS)}")
    gaps = list(parse_values(holdout_gaps, "--holdout-gaps", "m")) if holdout_gaps else []
    for option, given in (("--holdout-steps", holdout_steps), ("--holdout-step", holdout_step)):
        if given and steps is None:
            raise fail(f"{option} {given!r} needs --steps")
    step_data = None
    held_steps: list[str] = []
    if steps is not None:
        try:
            step_data = read_steps(steps)
        except MaglevkitError as exc:
            raise fail(exc) from None
        labels = [st.label for st in step_data.steps]
        for label in holdout_step or []:
            if label not in labels:
                raise fail(f"--holdout-step {label!r}: no step with that label; the steps: "
                           f"{labels}")
        held_steps = [*(_comma_labels(holdout_steps, labels) if holdout_steps else []),
                      *(holdout_step or [])]
    mag = load_magnet_or_exit(magnet)
    if select:
        pool = names if names is not None else list(DEFAULT_PARAMETERS)
        static = [n for n in pool if n not in DYNAMIC_PARAMETERS]
        dynamic = ([n for n in pool if n in DYNAMIC_PARAMETERS] if names is not None
                   else list(DYNAMIC_PARAMETERS) if steps is not None else [])
        if not static:
            raise fail(f"--select-params: no static parameter among {pool}")
        try:
            ranked = select_parameters(mag, data, candidates=static, holdout_gaps_m=gaps)
        except MaglevkitError as exc:
            raise fail(exc) from None
        for sc in ranked[:5]:
            info(f"cross-validation (leave one fitted gap out): worst "
                 f"{100 * sc.worst:.2f} %, rms {100 * sc.rms:.2f} %: {', '.join(sc.parameters)}")
        names = [*ranked[0].parameters, *dynamic]
        info(f"chosen: {', '.join(names)}")
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        try:
            res = calibrate(mag, data, parameters=names, holdout_gaps_m=gaps, steps=step_data,
                            holdout_steps=held_steps)
        except MaglevkitError as exc:
            raise fail(exc) from None
    with writing(output, "--output"):
        write_calibrated_toml(mag, res, output, data_source=str(data),
                              steps_source="" if steps is None else str(steps))
    records = [{"set": which, "gap_m": r["gap_m"], "current_A": r["current_A"],
                "row": r["row"], "circuit": r["circuit"], "quantity": r["quantity"],
                "data": r["data"], "model": r["model"],
                "relative_error_pct": 100.0 * r["relative_error"], "time_s": None}
               for which, rows in (("fit", res.points), ("holdout", res.holdout)) for r in rows]
    n_static = len(records)
    # the steps' samples (relative to each step's current change) in CSV/JSON; the table
    # gets one summary line per step
    records += [{"set": f"{which} {r['step']}", "gap_m": r["gap_m"], "current_A": r["data"],
                 "row": r["row"], "circuit": r["circuit"], "quantity": "current_A",
                 "data": r["data"], "model": r["model"],
                 "relative_error_pct": 100.0 * r["relative_error"], "time_s": r["time_s"]}
                for which, rows in (("step", res.step_points),
                                    ("holdout step", res.step_holdout)) for r in rows]
    table = new_table(title="relative error per point (model - data)/data")
    add_columns(table, ["set", "gap [m]", "I [A]", "row", "quantity", "data", "model",
                        "error [%]"], left=["set", "quantity"])
    for r in records[:n_static]:
        table.add_row(r["set"], f"{r['gap_m']:g}", f"{r['current_A']:g}", str(r["row"]),
                      r["quantity"], f"{r['data']:.6g}", f"{r['model']:.6g}",
                      f"{r['relative_error_pct']:+.2f}")
    meta = {"values": res.values, "confidence_95": res.confidence_95,
            "undetermined": list(res.undetermined), "bounds_active": list(res.bounds_active),
            "singular_values": res.singular_values.tolist(), "data_sha256": res.data_sha256,
            "steps_sha256": res.steps_sha256}
    if fmt == OutputFormat.table:
        for name in res.parameters:
            unit = "" if PARAMETERS[name].unit == "1" else f" {PARAMETERS[name].unit}"
            console.print(f"{name} = {res.values[name]:.6g} +- {res.confidence_95[name]:.3g}"
                          f"{unit} (95 %)"
                          + ("  NOT DETERMINED by the data" if name in res.undetermined else "")
                          + ("  at a bound" if name in res.bounds_active else ""))
        console.print("singular values (scaled Jacobian): "
                      + ", ".join(f"{v:.3g}" for v in res.singular_values))
        console.print(f"fit: rms {100 * res.residual_rms:.2f} %, max "
                      f"{100 * res.max_error('points'):.2f} %"
                      + (f"; held out: max {100 * res.max_error('holdout'):.2f} % (force "
                         f"{100 * res.max_error('holdout', 'force_N'):.2f} %, flux linkage "
                         f"{100 * res.max_error('holdout', 'flux_linkage_Wb'):.2f} %)"
                         if res.holdout else ""))
        for title, rows in (("voltage steps", res.step_points),
                            ("held-out voltage steps", res.step_holdout)):
            worst: dict[str, float] = {}
            for r in rows:
                worst[r["step"]] = max(worst.get(r["step"], 0.0), abs(r["relative_error"]))
            if worst:
                console.print(f"{title}, max error of the step's current change: "
                              + ", ".join(f"{k} {100 * v:.2f} %" for k, v in worst.items()))
    print_records(records, fmt, table, meta)
    info(f"wrote {output}")
    info(f"next: maglevkit statics {output} (the calibrated magnet), or maglevkit maps build "
         f"{output} -o maps.nc")
