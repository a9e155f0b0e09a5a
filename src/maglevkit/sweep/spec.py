"""Sweep files: a base job and the parameters swept as a Cartesian product (TOML, SI units).

Example (``maglevkit/data/sweeps/vehicle-speeds.toml``)::

    [sweep]
    name = "speeds, seeds and a circuit failure"
    job = "vehicle"

    [vehicle]                  # the base job: one maglevkit.vehicle run per case
    file = "tr09"              # vehicle file (path relative to this file) or bundled name
    duration = 0.5             # s
    dt = 1e-3                  # s
    rigid = false              # rigid guideway instead of the elastic spans
    irregularity = "random:0.3e-3"   # vehicle-run syntax; the random part's seed is swept
    payload = 5000.0           # kg per section (a fixed value of a parameter)

    [parameters]               # non-empty lists; every combination is one case
    speed = [69.4, 138.9]      # m/s
    seed = [0, 1]              # seeds of the random irregularity
    failure = ["none", "s2m4/front@0.2"]   # CIRCUIT@T [s], several joined by '+', or none

    [output]                   # optional
    time_series = []           # per-case (time, circuit) series to keep, e.g. ["gap"]

A second job, ``job = "cross-section"``, runs the cross-section vehicle
(:class:`~maglevkit.vehicle.crossrun.CrossSectionModel`) from a ``[cross_section]`` table
(``file``, ``duration``, ``dt``, ``magnets``, ``irregularity``, ``lateral``) and sweeps
its scenario, :data:`CROSS_SECTION_PARAMETERS` (speed, curve, crosswind, seed, failure);
see ``maglevkit/data/sweeps/cross-section-curve.toml``.

The sweepable parameters are :data:`PARAMETERS` (:data:`CROSS_SECTION_PARAMETERS` for
the cross-section job).  Each is given at most once: as a list
in ``[parameters]`` (swept; a coordinate of the result) or as a scalar in the job table
(fixed; an attribute of the result); otherwise its default applies.  Unknown or missing
keys, empty or repeated lists and values of the wrong type or sign raise
:class:`~maglevkit.errors.ParameterFileError` naming the key and what is allowed.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import MaglevkitError, ParameterFileError
from ..magnets.base import Schema, take

__all__ = ["PARAMETERS", "CROSS_SECTION_PARAMETERS", "SweepParameter", "SweepSpec",
           "VehicleJob", "CrossSectionJob", "load_sweep", "parse_sweep", "bundled_sweeps",
           "scenario", "SWEEP_FORMAT"]

SWEEP_FORMAT = "maglevkit-sweep-1"
"""Format tag of the result and case files (part of every case key)."""

MAX_SPEED_M_PER_S = 250.0
"""Largest speed a sweep file accepts [m/s] (900 km/h; the Transrapid's record is 501 km/h):
a larger number is almost surely a speed in km/h."""

TIME_SERIES_VARIABLES = ("gap", "current", "voltage", "force", "guideway_deflection")
"""The vehicle run's (time, circuit) variables a sweep can keep per case."""


@dataclass(frozen=True)
class SweepParameter:
    """One sweepable parameter: name, kind, unit, default and meaning.

    Parameters
    ----------
    name : str
        Key in the sweep file (``[parameters]`` or the job table), e.g. ``"speed"``.
    kind : type
        Python type of a value: ``float``, ``int`` or ``str``.
    unit : str
        SI unit of a value (``"1"``: dimensionless, ``""``: text).
    default : object
        Value when the file gives none (``None`` for ``payload``: the vehicle file's).
    description : str
        Meaning and allowed range (used in error messages).
    """

    name: str
    kind: type
    unit: str
    default: Any
    description: str


PARAMETERS: tuple[SweepParameter, ...] = (
    SweepParameter("speed", float, "m/s", 0.0, "train speed (0 ... 250 m/s)"),
    SweepParameter("seed", int, "1", 0, "seed of the random irregularity (whole number >= 0)"),
    SweepParameter("failure", str, "", "none",
                   "circuits switched off: CIRCUIT@T [s], several joined by '+', or 'none'"),
    SweepParameter("payload", float, "kg", None,
                   "payload per section (default: the vehicle file's)"),
    SweepParameter("resistance_scale", float, "1", 1.0, "factor on every coil's R_el (> 0)"),
    SweepParameter("eddy_resistance_scale", float, "1", 1.0, "factor on every R_ec (> 0)"),
    SweepParameter("controller", str, "", "cascade",
                   "gap controllers: 'cascade' (flux cascade) or 'mpc' (offset-free NMPC)"),
)
"""The sweepable parameters, in the order of the result's dimensions."""

CROSS_SECTION_PARAMETERS: tuple[SweepParameter, ...] = (
    PARAMETERS[0],
    SweepParameter("curve_radius", float, "m", math.inf,
                   "radius R of the full curve (|R| >= 1 m, positive: a left-hand curve; "
                   "inf: straight)"),
    SweepParameter("curve_superelevation", float, "rad", 0.0,
                   "full superelevation of the curve (|c| < 0.3 rad; radians: 12 deg is "
                   "0.2094)"),
    SweepParameter("curve_transition", float, "m", 0.0,
                   "length of the transition into the curve (>= 0; 0: the curve at once)"),
    SweepParameter("curve_start", float, "m", 0.0,
                   "distance travelled where the transition starts (>= 0)"),
    SweepParameter("crosswind_force", float, "N", 0.0,
                   "peak lateral gust force on the car body (0: no gust; negative: from "
                   "the right)"),
    SweepParameter("crosswind_shape", str, "", "1-cosine", "gust shape: 1-cosine or step"),
    SweepParameter("crosswind_rise", float, "s", 0.5, "rise time of the gust (> 0)"),
    SweepParameter("crosswind_hold", float, "s", 1.0, "plateau of the gust (>= 0)"),
    SweepParameter("crosswind_start", float, "s", 0.5, "start time of the gust (>= 0)"),
    PARAMETERS[1],
    PARAMETERS[2],
)
"""The parameters of a cross-section sweep (``job = "cross-section"``), in the order of
the result's dimensions.  ``seed`` seeds the random parts of both irregularities, failures
name the cross-section's circuits (e.g. ``guidance_left/front@0.5``)."""

_BY_NAME = {p.name: p for p in PARAMETERS}
_ALL_BY_NAME = {p.name: p for p in (*PARAMETERS, *CROSS_SECTION_PARAMETERS)}

_SWEEP_SCHEMA = {
    "name": Schema(str, required=False, default=""),
    "job": Schema(str),
}
_VEHICLE_SCHEMA = {
    "file": Schema(str, required=False, default="tr09"),
    "duration": Schema(float, unit="s"),
    "dt": Schema(float, required=False, unit="s", default=1e-3),
    "rigid": Schema(bool, required=False, default=False),
    "irregularity": Schema(str, required=False, default="none"),
}
_OUTPUT_SCHEMA = {
    "time_series": Schema(list, required=False, default=[]),
}
_CROSS_SECTION_SCHEMA = {
    "file": Schema(str, required=False, default="tr09-cross-section"),
    "duration": Schema(float, unit="s"),
    "dt": Schema(float, required=False, unit="s", default=1e-3),
    "magnets": Schema(str, required=False, default="reduced"),
    "irregularity": Schema(str, required=False, default="none"),
    "lateral": Schema(str, required=False, default="none"),
}
CROSS_SECTION_TIME_SERIES = ("gap", "current", "voltage", "force")
"""The cross-section run's per-circuit variables a sweep can keep per case (``gap``: the
levitation and guidance gaps in the bank's circuit order)."""
_TABLES = ("sweep", "vehicle", "cross_section", "parameters", "output")
JOBS = ("vehicle", "cross-section")
_JOB_TABLE = {"vehicle": "vehicle", "cross-section": "cross_section"}


@dataclass(frozen=True)
class VehicleJob:
    """The base job of a vehicle sweep (see the module docstring).

    Attributes
    ----------
    vehicle_file : str
        Bundled vehicle name or an absolute path.
    vehicle_sha256 : str
        Hash of the vehicle file's text and its magnets' equivalent circuits (part of the
        case key: a changed file invalidates stored cases).
    duration_s, dt_s : float
        Run length and step [s].
    rigid : bool
        Rigid guideway.
    irregularity : str
        Irregularity spec without seeds (``maglevkit.vehicle.simulation.parse_irregularity``).
    time_series : tuple of str
        The run's (time, circuit) variables kept per case.
    circuit_names : tuple of str
        The train's bank circuits (to check failures).
    default_payload_kg : float
        The vehicle file's payload per section [kg].
    """

    vehicle_file: str
    vehicle_sha256: str
    duration_s: float
    dt_s: float
    rigid: bool
    irregularity: str
    time_series: tuple[str, ...]
    circuit_names: tuple[str, ...]
    default_payload_kg: float

    kind = "vehicle"
    parameters = PARAMETERS

    @property
    def n_steps(self) -> int:
        return int(round(self.duration_s / self.dt_s))

    def key_data(self) -> dict[str, Any]:
        """What a case's result depends on besides its parameters (for the case key)."""
        return {"job": "vehicle", "vehicle_sha256": self.vehicle_sha256,
                "duration_s": self.duration_s, "dt_s": self.dt_s, "rigid": self.rigid,
                "irregularity": self.irregularity, "time_series": list(self.time_series)}

    def dataset_attrs(self) -> dict[str, Any]:
        """The job's attributes of the sweep's result dataset."""
        return {"job": "vehicle", "vehicle_file": self.vehicle_file,
                "duration_s": self.duration_s, "dt_s": self.dt_s,
                "rigid_guideway": int(self.rigid), "irregularity": self.irregularity}


@dataclass(frozen=True)
class CrossSectionJob:
    """The base job of a cross-section sweep (``job = "cross-section"``).

    Attributes
    ----------
    vehicle_file : str
        Bundled cross-section name or an absolute path.
    vehicle_sha256 : str
        Hash of the parsed cross-section file, its magnets' equivalent circuits and the
        laws (part of the case key).
    duration_s, dt_s : float
        Run length and step [s].
    magnets : str
        ``"reduced"`` or ``"detailed"`` magnet models.
    irregularity : str
        Vertical (stator) irregularity spec without seeds
        (``maglevkit.vehicle.simulation.parse_irregularity``).
    lateral : str
        Lateral (guidance-rail) irregularity spec without seeds
        (``maglevkit.vehicle.crossrun.parse_lateral``).
    time_series : tuple of str
        The run's (time, circuit) variables kept per case.
    circuit_names : tuple of str
        The cross-section's bank circuits (to check failures).
    """

    vehicle_file: str
    vehicle_sha256: str
    duration_s: float
    dt_s: float
    magnets: str
    irregularity: str
    lateral: str
    time_series: tuple[str, ...]
    circuit_names: tuple[str, ...]

    kind = "cross-section"
    parameters = CROSS_SECTION_PARAMETERS

    @property
    def n_steps(self) -> int:
        return int(round(self.duration_s / self.dt_s))

    def key_data(self) -> dict[str, Any]:
        """What a case's result depends on besides its parameters (for the case key)."""
        return {"job": "cross-section", "vehicle_sha256": self.vehicle_sha256,
                "duration_s": self.duration_s, "dt_s": self.dt_s, "magnets": self.magnets,
                "irregularity": self.irregularity, "lateral": self.lateral,
                "time_series": list(self.time_series)}

    def dataset_attrs(self) -> dict[str, Any]:
        """The job's attributes of the sweep's result dataset."""
        return {"job": "cross-section", "vehicle_file": self.vehicle_file,
                "duration_s": self.duration_s, "dt_s": self.dt_s, "magnets": self.magnets,
                "irregularity": self.irregularity, "lateral": self.lateral}


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file.

    Attributes
    ----------
    name : str
        The sweep's name (``[sweep] name``, default the file's stem).
    job : VehicleJob or CrossSectionJob
        The base job every case runs.
    swept : dict
        Swept parameter -> tuple of values (in :data:`PARAMETERS` order).
    fixed : dict
        Every other parameter -> its value.
    source : str
        File path or bundled name (for messages).
    """

    name: str
    job: VehicleJob | CrossSectionJob
    swept: Mapping[str, tuple[Any, ...]]
    fixed: Mapping[str, Any]
    source: str = ""

    @property
    def parameters(self) -> tuple[SweepParameter, ...]:
        """The job's sweepable parameters (:data:`PARAMETERS` or
        :data:`CROSS_SECTION_PARAMETERS`)."""
        return self.job.parameters

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.swept.values())

    @property
    def n_cases(self) -> int:
        return math.prod(self.shape)

    def cases(self) -> Iterator[dict[str, Any]]:
        """Every case's full parameter set (swept and fixed), in C order of :attr:`shape`."""
        names = list(self.swept)
        for combo in itertools.product(*self.swept.values()):
            yield {**self.fixed, **dict(zip(names, combo, strict=True))}

    def case_key(self, params: Mapping[str, Any]) -> str:
        """Hash of the job, the case's parameters and the format (its stored file's name).

        Parameters
        ----------
        params : mapping
            One case's full parameter set, as :meth:`cases` yields it: a value for every
            sweep parameter of the job (:attr:`parameters`, e.g. ``speed`` [m/s], ``seed``,
            ``failure``), JSON-serialisable and finite (an infinite ``curve_radius`` is
            encoded as the text ``"inf"``); other keys are ignored.

        Returns
        -------
        str
            24 hex digits of a SHA-256 over the sweep format, the maglevkit version, the
            job and the case: a new version or job gives new keys.

        Raises
        ------
        KeyError
            A sweep parameter missing from ``params``.
        ValueError
            NaN or infinite values (``json.dumps(allow_nan=False)``).
        TypeError
            Values JSON cannot encode.
        """
        from .._version import __version__

        blob = json.dumps({"format": SWEEP_FORMAT, "maglevkit": __version__,
                           "job": self.job.key_data(),
                           "case": {p.name: _key_value(params[p.name])
                                    for p in self.parameters}},
                          sort_keys=True, allow_nan=False)
        return hashlib.sha256(blob.encode()).hexdigest()[:24]


def _key_value(v: Any) -> Any:
    """A parameter value for the case key: infinities as text (JSON has none)."""
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


def bundled_sweeps() -> tuple[str, ...]:
    """Names of the sweep files shipped with maglevkit (``maglevkit/data/sweeps``)."""
    from ..parameter_files import bundled_files

    return tuple(bundled_files("sweeps"))


def load_sweep(source: str | Path) -> SweepSpec:
    """Load a sweep file by path or bundled name (see :func:`bundled_sweeps`).

    Parameters
    ----------
    source : str or Path
        Path of a TOML sweep file, or the name of a bundled one.  A relative vehicle
        file in it is taken relative to the sweep file's folder.

    Returns
    -------
    SweepSpec

    Raises
    ------
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    """
    from ..parameter_files import read_parameter_file

    params, label = read_parameter_file(source, what="sweep", folder="sweeps")
    path = Path(source)
    base = path.resolve().parent if path.is_file() else None
    return parse_sweep(params, label, base_dir=base)


def _value(name: str, v: Any, where: str) -> Any:
    """One value of a sweepable parameter, checked (``where`` names the key for errors)."""
    p = _ALL_BY_NAME[name]
    unit = f" [{p.unit}]" if p.unit not in ("", "1") else ""
    if name == "curve_radius" and isinstance(v, float) and math.isinf(v):
        return v
    if p.kind is str:
        if not isinstance(v, str) or not v.strip():
            raise ParameterFileError(f"{where} = {v!r}: expected a string: {p.description}")
        if name == "controller" and v.strip() not in ("cascade", "mpc"):
            raise ParameterFileError(f"{where} = {v!r}: expected 'cascade' or 'mpc'")
        text = " ".join(v.split())
        if name == "crosswind_shape":
            scenario({name: text}, where)
        return text
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        what = "a whole number" if p.kind is int else f"a number{unit}"
        raise ParameterFileError(f"{where} = {v!r}: expected {what}: {p.description} "
                                 "(SI units; no unit strings)")
    if p.kind is int:
        if not float(v).is_integer() or v < 0:
            raise ParameterFileError(f"{where} = {v!r}: expected a whole number >= 0")
        return int(v)
    v = float(v)
    if name == "speed" and not 0.0 <= v <= MAX_SPEED_M_PER_S:
        raise ParameterFileError(f"{where} = {v!r} m/s: must be in 0 ... {MAX_SPEED_M_PER_S:g} "
                                 "m/s (speeds are in m/s: 500 km/h is 138.9)")
    if name == "payload" and v < 0:
        raise ParameterFileError(f"{where} = {v!r} kg: must be >= 0")
    if name.endswith("_scale") and v <= 0:
        raise ParameterFileError(f"{where} = {v!r}: must be > 0 (a factor on the nominal value)")
    if name.startswith(("curve_", "crosswind_")):
        scenario({name: v}, where)
    return v


def scenario(params: Mapping[str, Any], where: str = "case") -> tuple[Any, Any]:
    """The curve and the gust of a cross-section case, checked by their own classes.

    Parameters
    ----------
    params : mapping
        ``curve_*`` [m, rad] and ``crosswind_*`` [N, s, shape] values of
        :data:`CROSS_SECTION_PARAMETERS`; missing ones take their defaults.
    where : str, default "case"
        Where the values come from (for error messages).

    Returns
    -------
    (TransitionCurve or None, Crosswind or None)
        None for a straight level track and for a zero gust force.

    Raises
    ------
    ParameterFileError
        A value out of range, naming ``where`` and what is allowed.
    """
    from ..vehicle.crossrun import Crosswind, TransitionCurve

    def get(name: str) -> Any:
        return params.get(name, _ALL_BY_NAME[name].default)

    try:
        curve = TransitionCurve(get("curve_radius"), get("curve_superelevation"),
                                get("curve_transition"), get("curve_start"))
        wind = Crosswind(get("crosswind_force"), rise_s=get("crosswind_rise"),
                         hold_s=get("crosswind_hold"), start_s=get("crosswind_start"),
                         shape=get("crosswind_shape"))
    except MaglevkitError as exc:
        raise ParameterFileError(f"{where}: {exc}") from None
    straight = math.isinf(curve.radius_m) and curve.superelevation_rad == 0.0
    return (None if straight else curve), (None if wind.peak_force_N == 0.0 else wind)


def _check_failure(text: str, where: str, circuits: tuple[str, ...], duration: float,
                   hint: str = "sNmK/front|rear|mid: section N, magnet K") -> None:
    from ..vehicle.simulation import parse_failure

    if text == "none":
        return
    for part in text.split("+"):
        try:
            f = parse_failure(part.strip())
        except MaglevkitError as exc:
            raise ParameterFileError(f"{where}: {exc}; or 'none', several joined by '+'") from None
        if f.circuit not in circuits:
            raise ParameterFileError(
                f"{where}: no circuit {f.circuit!r} in this vehicle; circuits are "
                f"{circuits[0]} ... {circuits[-1]} ({hint})")
        if f.time_s >= duration:
            raise ParameterFileError(f"{where}: failure time {f.time_s:g} s is not within the "
                                     f"run (duration {duration:g} s)")


def _vehicle_identity(vehicle_file: str) -> tuple[float, tuple[str, ...], str]:
    """Payload, bank circuit names and the identity hash of a vehicle file (no maps built)."""
    from ..magnets import load_magnet
    from ..reduction.maps import law_hash, network_hash
    from ..vehicle.train import load_vehicle

    train = load_vehicle(vehicle_file)
    kinds = {"standard": load_magnet(train.standard_magnet), "bow": load_magnet(train.bow_magnet)}
    names = tuple(f"{s.name}/{c}" for s in train.magnet_slots()
                  for c in kinds[s.kind].circuit_names)
    h = hashlib.sha256(repr(dataclasses.replace(train, source="")).encode())
    for kind in ("standard", "bow"):
        h.update(network_hash(kinds[kind].network).encode())
    h.update(law_hash().encode())           # results of another maglevkit's laws differ
    return train.payload_kg, names, h.hexdigest()


def parse_sweep(parameters: Mapping[str, Any], source: str = "parameters", *,
                base_dir: Path | None = None) -> SweepSpec:
    """Validate a parsed sweep TOML dictionary (see the module docstring).

    Loads the vehicle file and its magnets' equivalent circuits (to check failures and
    hash them into the case keys), but builds no maps.

    Parameters
    ----------
    parameters : mapping
        The parsed file: tables ``sweep``, ``vehicle`` and ``parameters`` (required)
        and ``output`` (optional).
    source : str, default "parameters"
        Label for error messages; its stem is the sweep's default name.
    base_dir : Path, optional
        Folder that relative vehicle file paths are relative to (the sweep file's
        folder; None: the current directory).  Keyword only.

    Returns
    -------
    SweepSpec

    Raises
    ------
    ParameterFileError
        Unknown or missing tables or keys; values of the wrong type, sign or range
        (speeds in 0 ... 250 m/s, seeds whole numbers >= 0, payload >= 0 kg, scales
        > 0); empty or repeated lists; a parameter both fixed and swept; a duration that
        is not a whole number of steps or shorter than two; an unknown vehicle file,
        failure circuit or failure time outside the run; a bad irregularity, a seed in
        it, or a swept seed without a random irregularity.
    """
    def bad(msg: str) -> ParameterFileError:
        return ParameterFileError(f"{source}: {msg}")

    if not isinstance(parameters, Mapping):
        raise bad("a sweep file must be a TOML table")
    unknown = sorted(set(parameters) - set(_TABLES))
    if unknown:
        raise bad(f"unknown table(s) {unknown}; a sweep file may have: {', '.join(_TABLES)}")
    if "sweep" not in parameters:
        raise bad("missing the [sweep] table")
    try:
        sw = take(parameters["sweep"], _SWEEP_SCHEMA, "sweep")
        if sw["job"] not in JOBS:
            raise ParameterFileError(f"[sweep] job = {sw['job']!r}: use one of {', '.join(JOBS)}")
    except ParameterFileError as exc:
        raise bad(str(exc)) from None
    table = _JOB_TABLE[sw["job"]]
    for other_job, other in _JOB_TABLE.items():
        if other != table and other in parameters:
            raise bad(f"a [{other}] table belongs to job = {other_job!r}; this sweep's job "
                      f"{sw['job']!r} takes its base job from [{table}]")
    for t in (table, "parameters"):
        if t not in parameters:
            raise bad(f"missing the [{t}] table")
    if sw["job"] == "cross-section":
        return _parse_cross_section(parameters, source, sw, bad, base_dir)
    job, fixed_raw, swept_raw, ts = _job_tables(
        parameters, "vehicle", _VEHICLE_SCHEMA, PARAMETERS, TIME_SERIES_VARIABLES,
        example="speed = [0.0, 138.9] (m/s)", bad=bad)
    _check_time_grid(job, "vehicle", bad)
    # the vehicle (cheap: the file and its magnets' circuits; no maps)
    vfile = _resolve_file(job["file"], base_dir)
    try:
        payload0, circuits, vhash = _vehicle_identity(vfile)
    except MaglevkitError as exc:
        raise bad(f"[vehicle] file = {job['file']!r}: {exc}") from None
    # parameters
    swept, fixed = _parameter_values(
        PARAMETERS, swept_raw, fixed_raw, "vehicle", circuits, job["duration"], bad=bad,
        defaults={"payload": payload0})
    irr = _check_irregularity(job["irregularity"], "seed" in swept, bad)
    spec_job = VehicleJob(vehicle_file=vfile, vehicle_sha256=vhash, duration_s=job["duration"],
                          dt_s=job["dt"], rigid=job["rigid"], irregularity=irr,
                          time_series=tuple(ts), circuit_names=circuits,
                          default_payload_kg=payload0)
    return SweepSpec(name=sw["name"] or Path(source).stem, job=spec_job, swept=swept,
                     fixed=fixed, source=source)


def _job_tables(parameters: Mapping[str, Any], table: str, schema: Mapping[str, Schema],
                params: tuple[SweepParameter, ...], series: tuple[str, ...], *, example: str,
                bad: Any, check_job: Any = None,
                ) -> tuple[dict[str, Any], dict[str, Any], Mapping[str, Any], list[str]]:
    """The job table ``[table]``, the ``[output]`` and ``[parameters]`` tables of a sweep
    file, checked: (job options, fixed parameters as given, swept lists as given, time
    series names).  ``check_job(job)`` checks the job options further (raises
    ParameterFileError); ``example`` is the hint for an empty ``[parameters]``."""
    names = [p.name for p in params]
    try:
        raw_job = parameters[table]
        if not isinstance(raw_job, Mapping):
            raise ParameterFileError(f"[{table}] must be a table")
        fixed_raw = {k: v for k, v in raw_job.items() if k in names}
        unknown_keys = sorted(set(raw_job) - set(schema) - set(names))
        if unknown_keys:
            raise ParameterFileError(
                f"[{table}]: unknown key(s) {unknown_keys}; allowed keys are: "
                f"{', '.join(schema)} and the parameters {', '.join(names)}")
        job = take({k: v for k, v in raw_job.items() if k in schema}, schema, table)
        if check_job is not None:
            check_job(job)
        out = take(parameters.get("output", {}), _OUTPUT_SCHEMA, "output")
        ts = out["time_series"]
        if not all(isinstance(v, str) and v in series for v in ts) or \
                len(set(ts)) != len(ts):
            raise ParameterFileError(f"[output] time_series = {ts!r}: a list of distinct names "
                                     f"from {', '.join(series)} (or [])")
        swept_raw = parameters["parameters"]
        if not isinstance(swept_raw, Mapping):
            raise ParameterFileError("[parameters] must be a table of lists")
        unknown_keys = sorted(set(swept_raw) - set(names))
        if unknown_keys:
            raise ParameterFileError(
                f"[parameters]: unknown key(s) {unknown_keys}; allowed keys are: "
                + ", ".join(f"{p.name} [{p.unit or 'text'}]" for p in params))
        if not swept_raw:
            raise ParameterFileError("[parameters] is empty: give at least one list, e.g. "
                                     + example)
        both = sorted(set(swept_raw) & set(fixed_raw))
        if both:
            raise ParameterFileError(f"{both} given both in [{table}] (fixed) and in "
                                     "[parameters] (swept); give each once")
    except ParameterFileError as exc:
        raise bad(str(exc)) from None
    return job, fixed_raw, swept_raw, ts


def _check_magnets(job: Mapping[str, Any]) -> None:
    """The ``magnets`` option of a cross-section job."""
    if job["magnets"] not in ("reduced", "detailed"):
        raise ParameterFileError(f"[cross_section] magnets = {job['magnets']!r}: use "
                                 "'reduced' or 'detailed'")


def _check_time_grid(job: Mapping[str, Any], table: str, bad: Any) -> None:
    """The job's duration and step: a whole number of steps, at least two."""
    from ..models.inputs import check_span

    try:
        check_span(0.0, job["duration"], job["dt"])
    except MaglevkitError as exc:
        raise bad(f"[{table}] duration/dt: {exc}") from None
    if int(round(job["duration"] / job["dt"])) < 2:
        raise bad(f"[{table}] duration = {job['duration']} s is less than two steps of "
                  f"dt = {job['dt']} s")


def _parameter_values(params: tuple[SweepParameter, ...], swept_raw: Mapping[str, Any],
                      fixed_raw: Mapping[str, Any], table: str, circuits: tuple[str, ...],
                      duration: float, *, bad: Any, defaults: Mapping[str, Any] | None = None,
                      hint: str | None = None,
                      ) -> tuple[dict[str, tuple[Any, ...]], dict[str, Any]]:
    """The swept lists and the fixed values of a sweep, each value checked (failures
    against the job's circuits and duration); ``defaults`` overrides parameter
    defaults (e.g. the vehicle file's payload)."""
    swept: dict[str, tuple[Any, ...]] = {}
    fixed: dict[str, Any] = {}
    try:
        for p in params:
            if p.name in swept_raw:
                vals = swept_raw[p.name]
                if not isinstance(vals, list) or not vals:
                    unit = f" [{p.unit}]" if p.unit not in ("", "1") else ""
                    raise ParameterFileError(f"[parameters] {p.name} = {vals!r}: expected a "
                                             f"non-empty list of values: {p.description}{unit}")
                checked = tuple(_value(p.name, v, f"[parameters] {p.name}[{i}]")
                                for i, v in enumerate(vals))
                if len(set(checked)) != len(checked):
                    raise ParameterFileError(f"[parameters] {p.name} = {vals!r}: repeated values "
                                             "(each value once)")
                swept[p.name] = checked
            elif p.name in fixed_raw:
                fixed[p.name] = _value(p.name, fixed_raw[p.name], f"[{table}] {p.name}")
            else:
                fixed[p.name] = (defaults or {}).get(p.name, p.default)
        for i, v in enumerate(swept.get("failure", (fixed.get("failure"),))):
            where = f"[parameters] failure[{i}]" if "failure" in swept else f"[{table}] failure"
            if hint is None:
                _check_failure(v, where, circuits, duration)
            else:
                _check_failure(v, where, circuits, duration, hint=hint)
    except ParameterFileError as exc:
        raise bad(str(exc)) from None
    return swept, fixed


def _resolve_file(name: str, base_dir: Path | None) -> str:
    """A vehicle file name as given (a bundled name) or as an absolute path (a file)."""
    vpath = Path(name)
    if vpath.suffix == ".toml" or vpath.exists() or (base_dir is not None
                                                     and (base_dir / vpath).exists()):
        if not vpath.is_absolute() and base_dir is not None:
            vpath = base_dir / vpath
        return str(vpath.resolve())
    return name


def _seeded_parts(text: str, key: str, table: str, seeded: tuple[str, ...], bad: Any) -> bool:
    """Check that the seeded parts (``random:``, ...) of a spec carry no seed of their own;
    True if there is one (a swept seed then changes something)."""
    parts = [p.strip() for p in text.split("+") if p.strip()]
    for p in parts:
        if p.startswith(seeded) and len(p.split(":")) > 2:
            kind = p.split(":")[0]
            value = {"random": "RMS", "girders": "H"}.get(kind, "VALUE")
            raise bad(f"[{table}] {key} = {text!r}: give {kind}:{value} without a seed; the "
                      f"seed is the parameter 'seed' (fixed in [{table}] or swept)")
    return any(p.startswith(seeded) for p in parts)


def _check_irregularity(text: str, seed_swept: bool, bad: Any, table: str = "vehicle") -> str:
    """The irregularity spec, checked; its random parts must not carry their own seed."""
    from ..vehicle.simulation import parse_irregularity

    seeded = _seeded_parts(text, "irregularity", table, ("random:",), bad)
    if table == "vehicle" and seed_swept and not seeded:
        raise bad(f"[parameters] seed is swept but [vehicle] irregularity = {text!r} has no "
                  "random part (random:RMS); the seed would change nothing")
    try:
        parse_irregularity(text, span_length_m=1.0)
    except MaglevkitError as exc:
        raise bad(f"[{table}] irregularity: {exc}") from None
    return " ".join(text.split())


def _cross_section_identity(vehicle_file: str) -> tuple[tuple[str, ...], str]:
    """Bank circuit names and the identity hash of a cross-section file (no maps built)."""
    from ..magnets import load_magnet
    from ..reduction.maps import law_hash, network_hash
    from ..vehicle.crossrun import CrossSectionModel
    from ..vehicle.crosssection import load_cross_section

    data = load_cross_section(vehicle_file)
    h = hashlib.sha256(repr(dataclasses.replace(data, source="")).encode())
    names: list[str] = []
    for kind, member in CrossSectionModel.MEMBERS:
        magnet = load_magnet(CrossSectionModel.DEFAULT_MAGNETS[kind])
        names += [f"{member}/{c}" for c in magnet.circuit_names]
        h.update(network_hash(magnet.network).encode())
    h.update(law_hash().encode())
    return tuple(names), h.hexdigest()


def _parse_cross_section(parameters: Mapping[str, Any], source: str, sw: Mapping[str, Any],
                         bad: Any, base_dir: Path | None) -> SweepSpec:
    """The cross-section job of :func:`parse_sweep` (tables present, job checked)."""
    job, fixed_raw, swept_raw, ts = _job_tables(
        parameters, "cross_section", _CROSS_SECTION_SCHEMA, CROSS_SECTION_PARAMETERS,
        CROSS_SECTION_TIME_SERIES, example="speed = [55.6, 125.0] (m/s)", bad=bad,
        check_job=_check_magnets)
    _check_time_grid(job, "cross_section", bad)
    vfile = _resolve_file(job["file"], base_dir)
    try:
        circuits, vhash = _cross_section_identity(vfile)
    except MaglevkitError as exc:
        raise bad(f"[cross_section] file = {job['file']!r}: {exc}") from None
    swept, fixed = _parameter_values(
        CROSS_SECTION_PARAMETERS, swept_raw, fixed_raw, "cross_section", circuits,
        job["duration"], bad=bad,
        hint="MAGNET_SIDE/front|rear, e.g. guidance_left/front")
    irr = _check_irregularity(job["irregularity"], False, bad, table="cross_section")
    lat = " ".join(job["lateral"].split())
    seeded = _seeded_parts(irr, "irregularity", "cross_section", ("random:",), bad)
    seeded = _seeded_parts(lat, "lateral", "cross_section", ("random:", "girders:"),
                           bad) or seeded
    if "seed" in swept and not seeded:
        raise bad(f"[parameters] seed is swept but neither [cross_section] irregularity = "
                  f"{irr!r} nor lateral = {lat!r} has a seeded part (random:RMS, girders:H); "
                  "the seed would change nothing")
    from ..vehicle.crossrun import parse_lateral

    try:
        parse_lateral(lat)
    except MaglevkitError as exc:
        raise bad(f"[cross_section] lateral: {exc}") from None
    spec_job = CrossSectionJob(vehicle_file=vfile, vehicle_sha256=vhash,
                               duration_s=job["duration"], dt_s=job["dt"],
                               magnets=job["magnets"], irregularity=irr, lateral=lat,
                               time_series=tuple(ts), circuit_names=circuits)
    spec = SweepSpec(name=sw["name"] or Path(source).stem, job=spec_job, swept=swept,
                     fixed=fixed, source=source)
    try:     # every combination's curve and gust (e.g. a rise time with a shape)
        for i, case in enumerate(spec.cases()):
            scenario(case, f"case {i}")
    except ParameterFileError as exc:
        raise bad(str(exc)) from None
    return spec
