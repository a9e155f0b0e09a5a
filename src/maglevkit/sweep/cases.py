"""One case of a sweep: a vehicle run reduced to its summary (and optional time series).

:func:`run_case` runs in the executor's worker processes; it never raises for a failing
case: the error is returned in the case's Dataset (``status = "error"``, ``error`` the
exception's type and message).  Each worker process keeps the last few assembled
:class:`~maglevkit.vehicle.VehicleModel` objects (maps, bank, controllers), keyed by what
they depend on (vehicle, guideway, payload, resistance scales), so cases that differ only
in speed, seed or failure reuse them (a run does not change its model), and a model whose
assembly failed with a :class:`~maglevkit.errors.MaglevkitError` (e.g. a payload the
magnets cannot carry) fails the other cases of the same key without a second attempt.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import OrderedDict
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import MaglevkitError
from .spec import CROSS_SECTION_PARAMETERS, PARAMETERS, SWEEP_FORMAT, CrossSectionJob, VehicleJob

__all__ = ["run_case", "error_case", "TIMING_VARIABLES", "SUMMARY_UNITS"]

TIMING_VARIABLES = ("setup_time", "wall_time", "real_time_factor")
"""Per-case variables that measure the machine, not the physics (they differ between
runs; everything else of a case is deterministic)."""

SUMMARY_UNITS = {
    "min_gap": ("m", "smallest gap of any circuit over the run"),
    "max_gap": ("m", "largest gap of any circuit over the run"),
    "max_current": ("A", "largest coil current of any circuit"),
    "max_abs_voltage": ("V", "largest |voltage| of any circuit"),
    "touchdown_time": ("s", "time of the first touchdown (NaN: none); the run stopped there"),
    "simulated_time": ("s", "simulated time (shorter than the duration after a touchdown)"),
    "gap_min": ("m", "smallest gap of the circuit"),
    "gap_max": ("m", "largest gap of the circuit"),
    "current_peak": ("A", "largest coil current of the circuit"),
    "wk_rms": ("m/s^2", "ISO 2631-1 Wk-weighted RMS floor acceleration (NaN: run too short, "
                        "< 64 samples)"),
    "sperling_wz": ("1", "Sperling ride index Wz (NaN: run too short)"),
    "setup_time": ("s", "wall time to assemble the vehicle model (0: reused in this worker)"),
    "wall_time": ("s", "wall time of the run's time loop"),
    "real_time_factor": ("1", "simulated time / wall time of the time loop"),
    # the cross-section job's
    "min_levitation_gap": ("m", "smallest levitation gap (vertical, to the stator) over the run"),
    "min_guidance_gap": ("m", "smallest guidance gap (lateral, to the side rail) over the run"),
    "peak_lateral_acceleration": ("m/s^2", "largest |lateral acceleration| of the car body"),
    "lateral_wd_rms": ("m/s^2", "ISO 2631-1 Wd-weighted RMS lateral car-body acceleration "
                                "(NaN: run too short, < 64 samples)"),
    "lateral_sperling_wz": ("1", "Sperling ride index Wz, lateral (NaN: run too short)"),
    "vertical_wk_rms": ("m/s^2", "ISO 2631-1 Wk-weighted RMS vertical car-body acceleration "
                                 "(NaN: run too short)"),
    "vertical_sperling_wz": ("1", "Sperling ride index Wz, vertical (NaN: run too short)"),
    "net_guidance_force_end": ("N", "net guidance force, right minus left magnet, at the end "
                                    "of the run (in a steady curve m v^2/R cos c - m g sin c)"),
}
"""Unit and meaning of every summary variable of a case."""

_MODELS: OrderedDict[tuple[Any, ...], Any] = OrderedDict()
_MODELS_KEPT = 4


def _model(job: VehicleJob, params: Mapping[str, Any]) -> tuple[Any, float]:
    """The vehicle model of a case (from this process's cache) and its setup time [s]."""
    from ..vehicle.simulation import VehicleModel
    from ..vehicle.train import load_vehicle

    key = (job.vehicle_file, job.vehicle_sha256, job.rigid, params["payload"],
           params["resistance_scale"], params["eddy_resistance_scale"], params["controller"])
    if key in _MODELS:
        _MODELS.move_to_end(key)
        known = _MODELS[key]
        if isinstance(known, MaglevkitError):    # the same assembly fails the same way
            raise known
        return known, 0.0
    t0 = time.perf_counter()
    try:
        train = dataclasses.replace(load_vehicle(job.vehicle_file), payload_kg=params["payload"])
        model = VehicleModel(train, rigid=job.rigid,
                             resistance_scale=params["resistance_scale"],
                             eddy_resistance_scale=params["eddy_resistance_scale"],
                             controller=params["controller"])
    except MaglevkitError as exc:
        _remember(key, exc)
        raise
    _remember(key, model)
    return model, time.perf_counter() - t0


def _remember(key: tuple[Any, ...], value: Any) -> None:
    _MODELS[key] = value
    while len(_MODELS) > _MODELS_KEPT:
        _MODELS.popitem(last=False)


def _irregularity(job: VehicleJob, seed: int, span_length_m: float) -> Any:
    from ..vehicle.simulation import parse_irregularity

    parts = [p.strip() for p in job.irregularity.split("+") if p.strip()]
    parts = [f"{p}:{seed}" if p.startswith("random:") else p for p in parts]
    return parse_irregularity("+".join(parts), span_length_m=span_length_m)


def _failures(text: str) -> list[Any]:
    from ..vehicle.simulation import parse_failure

    return [] if text == "none" else [parse_failure(p.strip()) for p in text.split("+")]


def _base(params: Mapping[str, Any], key: str, status: str, error: str) -> Any:
    import xarray as xr

    names = CROSS_SECTION_PARAMETERS if "curve_radius" in params else PARAMETERS
    return xr.Dataset(
        {"status": ((), status), "error": ((), error)},
        attrs={"format": SWEEP_FORMAT, "case_key": key,
               **{f"param_{p.name}": params[p.name] for p in names}})


def error_case(params: Mapping[str, Any], key: str, error: str) -> Any:
    """The Dataset of a failed case (status ``"error"`` and the error text).

    Parameters
    ----------
    params : mapping
        The case's full parameter set (stored as ``param_*`` attributes).
    key : str
        The case key.
    error : str
        The error text, ``"TypeName: message"``.

    Returns
    -------
    xarray.Dataset
    """
    return _base(params, key, "error", error)


def run_case(job: VehicleJob | CrossSectionJob, params: Mapping[str, Any], key: str) -> Any:
    """Run one case; return its Dataset (summary, optional time series, status, error).

    Never raises for an error of the case itself (any ``Exception``): it is returned as
    ``status = "error"`` with ``"TypeName: message"``.

    Parameters
    ----------
    job : VehicleJob or CrossSectionJob
        The sweep's base job (vehicle file, duration [s], step [s], guideway,
        irregularity, time series to keep).
    params : mapping
        The case's full parameter set (every name of the job's parameters: for a
        vehicle job :data:`~maglevkit.sweep.PARAMETERS`: ``speed`` [m/s], ``seed``,
        ``failure``, ``payload`` [kg], ``resistance_scale``, ``eddy_resistance_scale``, ``controller``;
        for a cross-section job :data:`~maglevkit.sweep.CROSS_SECTION_PARAMETERS`:
        ``speed`` [m/s], ``curve_radius`` [m], ``curve_superelevation`` [rad], ...).
    key : str
        The case key, stored in the Dataset's attributes.

    Returns
    -------
    xarray.Dataset
        Status, error text, summary scalars (:data:`SUMMARY_UNITS`), per-circuit and
        per-comfort-point values, and the requested time series.
    """
    try:
        if isinstance(job, CrossSectionJob):
            return _run_cross_section(job, params, key)
        return _run(job, params, key)
    except Exception as exc:   # noqa: BLE001 - a failing case is a result, not a crash
        msg = " ".join(str(exc).split()) or "(no message)"
        return error_case(params, key, f"{type(exc).__name__}: {msg}")


def _run(job: VehicleJob, params: Mapping[str, Any], key: str) -> Any:
    model, setup = _model(job, params)
    prof = _irregularity(job, int(params["seed"]), model.guideway.span.length_m)
    res = model.run(speed_m_per_s=float(params["speed"]), duration_s=job.duration_s,
                    dt_s=job.dt_s, irregularity=prof, failures=_failures(params["failure"]))
    ds = res.dataset
    gap = ds["gap"].values
    cur = ds["current"].values
    volt = ds["voltage"].values
    out = _base(params, key, "ok", "")
    scalars = {
        "min_gap": float(gap.min()), "max_gap": float(gap.max()),
        "max_current": float(cur.max()),
        "max_abs_voltage": float(np.nanmax(np.abs(volt))) if np.isfinite(volt).any() else math.nan,
        "touchdown_time": math.nan if res.touchdown is None else float(res.touchdown[1]),
        "simulated_time": float(ds["time"].values[-1]),
        "setup_time": setup, "wall_time": float(res.wall_time_s),
        "real_time_factor": float(res.real_time_factor),
    }
    circuits = [str(c) for c in ds["circuit"].values]
    out = _case_results(out, scalars, res.touchdown, circuits, gap, cur)
    points = list(res.comfort)
    out = out.assign_coords(comfort_point=("comfort_point", points))
    out["wk_rms"] = ("comfort_point", [res.comfort[p]["wk_rms_m_per_s2"] for p in points])
    out["sperling_wz"] = ("comfort_point", [res.comfort[p]["sperling_wz"] for p in points])
    return _time_series(out, job, len(circuits), {
        name: (ds[name].values, {"units": ds[name].attrs.get("units", ""),
                                 "long_name": ds[name].attrs.get("long_name", name)})
        for name in job.time_series})


def _case_results(out: Any, scalars: Mapping[str, Any], touchdown: Any,
                  circuits: list[str], gap: np.ndarray, cur: np.ndarray) -> Any:
    """A case's dataset with its scalars, its touchdown (circuit, kind) and the per-circuit
    extremes of the gaps [m] and currents [A] (time x circuit arrays) added."""
    for name, value in scalars.items():
        out[name] = ((), value)
    out["touchdown_circuit"] = ((), "" if touchdown is None else touchdown[0])
    out["touchdown_kind"] = ((), "" if touchdown is None else touchdown[3])
    out = out.assign_coords(circuit=("circuit", circuits))
    out["gap_min"] = ("circuit", gap.min(axis=0))
    out["gap_max"] = ("circuit", gap.max(axis=0))
    out["current_peak"] = ("circuit", cur.max(axis=0))
    return out


def _time_series(out: Any, job: Any, n_circuits: int,
                 series: Mapping[str, tuple[np.ndarray, dict[str, str]]]) -> Any:
    """A case's dataset with its kept time series (name: (time x circuit values, attrs))
    added on the job's full time grid, NaN after an early end (touchdown)."""
    if not series:
        return out
    n = job.n_steps + 1
    out = out.assign_coords(time=("time", np.arange(n) * job.dt_s))
    for name, (vals, attrs) in series.items():
        full = np.full((n, n_circuits), np.nan)
        full[:vals.shape[0]] = vals
        out[name] = (("time", "circuit"), full, attrs)
    return out


def _cross_section_model(job: CrossSectionJob) -> tuple[Any, float]:
    """The cross-section model of a job (from this process's cache) and its setup time [s]."""
    from ..vehicle.crossrun import CrossSectionModel
    from ..vehicle.crosssection import load_cross_section

    key = ("cross-section", job.vehicle_file, job.vehicle_sha256, job.magnets)
    if key in _MODELS:
        _MODELS.move_to_end(key)
        known = _MODELS[key]
        if isinstance(known, MaglevkitError):
            raise known
        return known, 0.0
    t0 = time.perf_counter()
    try:
        model = CrossSectionModel(load_cross_section(job.vehicle_file), magnets=job.magnets)
    except MaglevkitError as exc:
        _remember(key, exc)
        raise
    _remember(key, model)
    return model, time.perf_counter() - t0


def _seeded(text: str, seed: int, kinds: tuple[str, ...]) -> str:
    parts = [p.strip() for p in text.split("+") if p.strip()]
    return "+".join(f"{p}:{seed}" if p.startswith(kinds) else p for p in parts)


def _run_cross_section(job: CrossSectionJob, params: Mapping[str, Any], key: str) -> Any:
    from ..vehicle.crossrun import parse_lateral
    from ..vehicle.data import load_guideway
    from ..vehicle.simulation import parse_irregularity
    from .spec import scenario

    model, setup = _cross_section_model(job)
    seed = int(params["seed"])
    girder = load_guideway().span.length_m
    vertical = parse_irregularity(_seeded(job.irregularity, seed, ("random:",)),
                                  span_length_m=girder)
    lateral = parse_lateral(_seeded(job.lateral, seed, ("random:", "girders:")),
                            girder_length_m=girder)
    curve, wind = scenario(params)
    res = model.run(speed_m_per_s=float(params["speed"]), duration_s=job.duration_s,
                    dt_s=job.dt_s, curve=curve, crosswind=wind, vertical=vertical,
                    lateral=lateral, failures=_failures(params["failure"]))
    ds = res.dataset
    series = {
        "gap": np.concatenate([ds["levitation_gap"].values, ds["guidance_gap"].values], axis=1),
        "current": np.concatenate([ds["levitation_current"].values,
                                   ds["guidance_current"].values], axis=1),
        "force": np.concatenate([ds["levitation_force"].values,
                                 ds["guidance_force"].values], axis=1),
        "voltage": ds["voltage"].values,
    }
    units = {"gap": "m", "current": "A", "force": "N", "voltage": "V"}
    gap, cur, volt = series["gap"], series["current"], series["voltage"]
    gf = ds["guidance_force"].values
    half = gf.shape[1] // 2            # left circuits first, then right
    comfort = res.comfort
    nan = math.nan
    out = _base(params, key, "ok", "")
    scalars = {
        "min_gap": float(gap.min()), "max_gap": float(gap.max()),
        "min_levitation_gap": res.min_gap_m["levitation"],
        "min_guidance_gap": res.min_gap_m["guidance"],
        "max_current": float(cur.max()),
        "max_abs_voltage": float(np.nanmax(np.abs(volt))) if np.isfinite(volt).any() else nan,
        "touchdown_time": nan if res.touchdown is None else float(res.touchdown[1]),
        "simulated_time": float(ds["time"].values[-1]),
        "peak_lateral_acceleration": float(np.abs(
            ds["car_body_lateral_acceleration"].values).max()),
        "lateral_wd_rms": comfort.get("lateral", {}).get("weighted_rms_m_per_s2", nan),
        "lateral_sperling_wz": comfort.get("lateral", {}).get("sperling_wz", nan),
        "vertical_wk_rms": comfort.get("vertical", {}).get("weighted_rms_m_per_s2", nan),
        "vertical_sperling_wz": comfort.get("vertical", {}).get("sperling_wz", nan),
        "net_guidance_force_end": float(gf[-1, half:].sum() - gf[-1, :half].sum()),
        "setup_time": setup, "wall_time": float(res.wall_time_s),
        "real_time_factor": float(res.real_time_factor),
    }
    circuits = [str(c) for c in ds["circuit"].values]
    out = _case_results(out, scalars, res.touchdown, circuits, gap, cur)
    return _time_series(out, job, len(circuits), {
        name: (series[name], {"units": units[name], "long_name": name})
        for name in job.time_series})
