"""The vehicle (train) parameter file and the train's layout.

A vehicle file is TOML with SI units and a ``[provenance]`` table, like the magnet and
guideway files (see ``maglevkit/data/vehicle/tr09.toml``, bundled as ``"tr09"``)::

    [vehicle]    name, sections, section_length, magnets_per_side, frames_per_section,
                 nominal_gap, touchdown_gap, landing_gap, standard_magnet, bow_magnet
    [car_body]   mass, pitch_inertia, payload
    [frame]      mass, pitch_inertia, magnet_mass
    [secondary]  stiffness, damping, positions
    [joint]      stiffness, damping
    [control]    bandwidth, damping, flux_bandwidth, voltage_limit, velocity_blend (optional)
    [magnets]    motion_eddy (optional table and key, default false), eddy_branches
                 (optional, default 1; 2: the three-state ladder), eddy_modes (optional:
                 0 eq. 8, 1-3 the maps' fitted eddy network, not with motion_eddy; left
                 out: each magnet's own default from its magnet file)

Unknown or missing keys and bad values raise :class:`~maglevkit.errors.ParameterFileError`
naming the key.  Train coordinate ``xi`` [m]: distance behind the train's nose (positive
rearwards); a point at ``xi`` is at ``x = x_nose(t) - xi`` on the guideway.

The model is planar (heave-pitch): the left and right magnets and air springs of one
position along the train are lumped into one line; a lumped circuit stands for the two
equal circuits of both sides (its force counts twice; :attr:`TrainData.sides`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterFileError
from ..magnets.base import Schema, take
from ..parameter_files import bundled_files, parse_provenance, read_parameter_file
from ..validation import Plausible, check_plausible

__all__ = ["TrainData", "MagnetSlot", "bundled_vehicles", "load_vehicle", "parse_vehicle",
           "VEHICLE_SCHEMA", "VEHICLE_PLAUSIBLE"]

VEHICLE_SCHEMA: dict[str, dict[str, Schema]] = {
    "vehicle": {
        "name": Schema(str),
        "sections": Schema(int, unit="-"),
        "section_length": Schema(float, unit="m"),
        "magnets_per_side": Schema(int, unit="-"),
        "frames_per_section": Schema(int, unit="-"),
        "nominal_gap": Schema(float, unit="m"),
        "touchdown_gap": Schema(float, unit="m", check="nonnegative"),
        "landing_gap": Schema(float, unit="m"),
        "standard_magnet": Schema(str),
        "bow_magnet": Schema(str),
    },
    "car_body": {
        "mass": Schema(float, unit="kg"),
        "pitch_inertia": Schema(float, unit="kg m^2"),
        "payload": Schema(float, unit="kg", check="nonnegative"),
    },
    "frame": {
        "mass": Schema(float, unit="kg"),
        "pitch_inertia": Schema(float, unit="kg m^2"),
        "magnet_mass": Schema(float, unit="kg", check="nonnegative"),
    },
    "secondary": {
        "stiffness": Schema(float, unit="N/m"),
        "damping": Schema(float, unit="N s/m", check="nonnegative"),
        "positions": Schema(list, unit="m"),
    },
    "joint": {
        "stiffness": Schema(float, unit="N/m", check="nonnegative"),
        "damping": Schema(float, unit="N s/m", check="nonnegative"),
    },
    "control": {
        "bandwidth": Schema(float, unit="Hz"),
        "damping": Schema(float, unit="-"),
        "flux_bandwidth": Schema(float, unit="Hz"),
        "voltage_limit": Schema(float, unit="V"),
        "velocity_blend": Schema(float, unit="-", check="nonnegative", required=False,
                                 default=0.0),
    },
    # optional table (a file without it: every key's default)
    "magnets": {
        "motion_eddy": Schema(bool, required=False, default=False),
        "eddy_branches": Schema(int, required=False, default=1, unit="-"),
        # unset (None): every magnet's own default (its file's reduced model)
        "eddy_modes": Schema(int, required=False, default=None, unit="-"),
    },
}

#: Tables a vehicle file may leave out (all their keys have defaults).
OPTIONAL_TABLES = frozenset({"magnets"})


#: The plausible magnitudes of every dimensional key of a vehicle file
#: (:func:`~maglevkit.validation.check_plausible`): the bundled ``tr09`` lies inside, the
#: same file with one value times 1000 or 1/1000 outside (docs/decisions.md).
VEHICLE_PLAUSIBLE: dict[str, Plausible] = {
    "vehicle.section_length": Plausible(2.0, 200.0, "m"),
    "vehicle.nominal_gap": Plausible(1e-3, 0.1, "m"),
    "vehicle.touchdown_gap": Plausible(1e-4, 0.05, "m"),
    "vehicle.landing_gap": Plausible(1e-3, 0.2, "m"),
    "car_body.mass": Plausible(1e3, 1e6, "kg"),
    "car_body.pitch_inertia": Plausible(1e4, 1e9, "kg m^2"),
    "car_body.payload": Plausible(50.0, 1e5, "kg"),
    "frame.mass": Plausible(50.0, 2e4, "kg"),
    "frame.pitch_inertia": Plausible(50.0, 1e6, "kg m^2"),
    "frame.magnet_mass": Plausible(20.0, 1e4, "kg"),
    "secondary.stiffness": Plausible(1e3, 1e7, "N/m"),
    "secondary.damping": Plausible(100.0, 1e6, "N s/m"),
    "secondary.positions": Plausible(0.05, 50.0, "m"),
    "joint.stiffness": Plausible(1e4, 1e8, "N/m"),
    "joint.damping": Plausible(500.0, 5e6, "N s/m"),
    "control.bandwidth": Plausible(0.1, 200.0, "Hz"),
    "control.flux_bandwidth": Plausible(1.0, 5000.0, "Hz"),
    "control.voltage_limit": Plausible(10.0, 2e4, "V"),
}


@dataclass(frozen=True)
class MagnetSlot:
    """One lumped magnet position of the train.

    Attributes
    ----------
    name : str
        ``"s{section}m{index}"`` (both 1-based), e.g. ``"s1m1"`` for the nose magnet.
    kind : str
        ``"standard"`` or ``"bow"``.
    section, frame : int
        0-based section and global frame index.
    centre_m : float
        Train coordinate ``xi`` of the magnet's centre [m].
    """

    name: str
    kind: str
    section: int
    frame: int
    centre_m: float


@dataclass(frozen=True)
class TrainData:
    """A parsed vehicle file (SI units).

    Attributes
    ----------
    name : str
        Vehicle name.
    n_sections, n_frames_per_section, magnets_per_side : int
        Sections (car bodies), levitation frames per section and magnet positions per
        side of a section (a multiple of the frames per section).
    section_length_m, nominal_gap_m, touchdown_gap_m : float
        Section length [m], nominal gap [m] and the gap at or below which a magnet counts
        as closed onto the stator [m] (``touchdown_gap_m < nominal_gap_m``).
    landing_gap_m : float
        Gap at or above which the frame's skids sit on the slide rail [m]
        (``> nominal_gap_m``); a vehicle run stops at either limit.
    standard_magnet, bow_magnet : str
        Magnet files (bundled names or paths).
    car_body_mass_kg, car_body_pitch_inertia_kg_m2, payload_kg : float
        Per section; the payload is spread uniformly over the section length.
    frame_mass_kg, frame_pitch_inertia_kg_m2, magnet_mass_kg : float
        Frame without magnets; one magnet of one side.
    spring_stiffness_N_per_m, spring_damping_N_s_per_m : float
        One lumped air-spring position (both sides).
    spring_positions_m : tuple of float
        Air springs relative to the frame centre (train coordinate) [m].
    joint_stiffness_N_per_m, joint_damping_N_s_per_m : float
        Vertical stiffness [N/m] and damping [N s/m] of the joint between two sections.
    control_bandwidth_Hz, control_damping, flux_bandwidth_Hz, voltage_limit_V : float
        Gap-controller design of every circuit: gap-loop natural frequency [Hz], damping
        ratio [-] (in (0, 5)), flux-loop bandwidth [Hz] and voltage limit [V] (see
        :func:`~maglevkit.control.design_gap_controller`).
    control_velocity_blend : float
        Share ``beta`` in [0, 1] [-] of the magnet's absolute velocity in the gap
        controllers' damping input (:func:`~maglevkit.control.damping_input`; key
        ``velocity_blend`` of ``[control]``, default 0: the gap rate only).
    motion_eddy : bool
        Fly the reduced magnets with the shielded-gap ladder (key ``motion_eddy`` of the
        optional ``[magnets]`` table, default False: eq. 8;
        :class:`~maglevkit.vehicle.VehicleModel` option ``motion_eddy``).
    eddy_branches : int
        Shielded sections of that ladder (key ``eddy_branches`` of ``[magnets]``, default
        1: the two-state ladder; 2: the three-state ladder, only with ``motion_eddy``).
    eddy_modes : int or None
        Branches of the maps' fitted eddy network every reduced magnet flies with (key
        ``eddy_modes`` of ``[magnets]``: 0 eq. 8, 1-3 the network, not with
        ``motion_eddy``; :class:`~maglevkit.vehicle.VehicleModel` option ``eddy_modes``).
        None (the key left out): each magnet's own default, from its magnet file
        (docs/vehicle.md, "Which reduced model the magnets fly").
    provenance : dict
        ``"table.key" -> tag/source``.
    source : str
        File path or bundled name.
    sides : int
        Magnets per lumped position (2: left and right).
    """

    name: str
    n_sections: int
    section_length_m: float
    magnets_per_side: int
    n_frames_per_section: int
    nominal_gap_m: float
    touchdown_gap_m: float
    landing_gap_m: float
    standard_magnet: str
    bow_magnet: str
    car_body_mass_kg: float
    car_body_pitch_inertia_kg_m2: float
    payload_kg: float
    frame_mass_kg: float
    frame_pitch_inertia_kg_m2: float
    magnet_mass_kg: float
    spring_stiffness_N_per_m: float
    spring_damping_N_s_per_m: float
    spring_positions_m: tuple[float, ...]
    joint_stiffness_N_per_m: float
    joint_damping_N_s_per_m: float
    control_bandwidth_Hz: float
    control_damping: float
    flux_bandwidth_Hz: float
    voltage_limit_V: float
    provenance: Mapping[str, str] = field(default_factory=dict)
    source: str = ""
    sides: int = 2
    control_velocity_blend: float = 0.0
    motion_eddy: bool = False
    eddy_branches: int = 1
    eddy_modes: int | None = None

    # ------------------------------------------------------------------ derived layout
    @property
    def length_m(self) -> float:
        """Train length [m]."""
        return self.n_sections * self.section_length_m

    @property
    def magnet_length_m(self) -> float:
        """Length of one magnet position [m]."""
        return self.section_length_m / self.magnets_per_side

    @property
    def frame_length_m(self) -> float:
        return self.section_length_m / self.n_frames_per_section

    @property
    def n_frames(self) -> int:
        return self.n_sections * self.n_frames_per_section

    @property
    def section_centres_m(self) -> np.ndarray:
        """Train coordinate of every car body's centre of mass [m]."""
        return (np.arange(self.n_sections) + 0.5) * self.section_length_m

    @property
    def frame_centres_m(self) -> np.ndarray:
        """Train coordinate of every frame's centre [m]."""
        return (np.arange(self.n_frames) + 0.5) * self.frame_length_m

    @property
    def frame_section(self) -> np.ndarray:
        """Section index of every frame."""
        return np.arange(self.n_frames) // self.n_frames_per_section

    @property
    def loaded_car_body_mass_kg(self) -> float:
        return self.car_body_mass_kg + self.payload_kg

    @property
    def loaded_car_body_inertia_kg_m2(self) -> float:
        """Car body plus uniformly spread payload, ``J + m_p L^2 / 12`` [kg m^2]."""
        return self.car_body_pitch_inertia_kg_m2 + self.payload_kg * self.section_length_m ** 2 / 12

    @property
    def frame_total_mass_kg(self) -> float:
        """One frame with its magnets (both sides) [kg]."""
        per = self.magnets_per_side // self.n_frames_per_section
        return self.frame_mass_kg + self.sides * per * self.magnet_mass_kg

    @property
    def frame_total_inertia_kg_m2(self) -> float:
        """Frame plus its magnets as point masses at the magnet centres [kg m^2]."""
        per = self.magnets_per_side // self.n_frames_per_section
        lm = self.magnet_length_m
        offsets = (np.arange(per) + 0.5) * lm - 0.5 * per * lm
        return self.frame_pitch_inertia_kg_m2 + self.sides * self.magnet_mass_kg * float(
            (offsets ** 2).sum())

    @property
    def total_mass_kg(self) -> float:
        """The loaded train [kg]."""
        return self.n_sections * (self.loaded_car_body_mass_kg
                                  + self.n_frames_per_section * self.frame_total_mass_kg)

    def magnet_slots(self) -> tuple[MagnetSlot, ...]:
        """Every lumped magnet position, nose first; the first and the last are bow magnets."""
        per = self.magnets_per_side // self.n_frames_per_section
        out = []
        n = self.n_sections * self.magnets_per_side
        for k in range(n):
            sec, idx = divmod(k, self.magnets_per_side)
            kind = "bow" if k in (0, n - 1) else "standard"
            out.append(MagnetSlot(f"s{sec + 1}m{idx + 1}", kind, sec, k // per,
                                  (k + 0.5) * self.magnet_length_m))
        return tuple(out)


def _check(cond: bool, msg: str, source: str) -> None:
    if not cond:
        raise ParameterFileError(f"{source}: {msg}")


def parse_vehicle(parameters: Mapping[str, Any], source: str = "parameters") -> TrainData:
    """Validate a parsed vehicle TOML dictionary (see the module docstring).

    Raises
    ------
    ParameterFileError
        Unknown or missing tables and keys, bad values, a standard magnet that is not a
        levitation magnet.

    Warns
    -----
    PlausibilityWarning
        A dimensional value outside its plausible range (:data:`VEHICLE_PLAUSIBLE`; most
        likely a unit slip such as tonnes typed into a kilogram key), naming the key.
    """
    if not isinstance(parameters, Mapping):
        raise ParameterFileError(f"{source}: a vehicle file must be a TOML table")
    allowed = set(VEHICLE_SCHEMA) | {"provenance"}
    unknown = sorted(set(parameters) - allowed)
    if unknown:
        raise ParameterFileError(f"{source}: unknown table(s) {unknown}; a vehicle file may have: "
                                 f"{', '.join(sorted(allowed))}")
    t: dict[str, dict[str, Any]] = {}
    for table, schema in VEHICLE_SCHEMA.items():
        if table not in parameters and table in OPTIONAL_TABLES:
            t[table] = take({}, schema, table)
            continue
        if table not in parameters:
            raise ParameterFileError(f"{source}: missing the [{table}] table (keys: "
                                     f"{', '.join(schema)})")
        try:
            t[table] = take(parameters[table], schema, table)
        except ParameterFileError as exc:
            raise ParameterFileError(f"{source}: {exc}") from None
    # before the cross-checks, which can refuse a slipped value without naming its unit
    check_plausible(t, VEHICLE_PLAUSIBLE, source, stacklevel=3)
    v = t["vehicle"]
    _check(v["sections"] >= 1, f"[vehicle] sections = {v['sections']} must be >= 1", source)
    _check(v["frames_per_section"] >= 1 and v["magnets_per_side"] % v["frames_per_section"] == 0,
           f"[vehicle] magnets_per_side = {v['magnets_per_side']} must be a multiple of "
           f"frames_per_section = {v['frames_per_section']} (each frame carries whole magnets)",
           source)
    _check(v["touchdown_gap"] < v["nominal_gap"],
           f"[vehicle] touchdown_gap = {v['touchdown_gap']} m must be below nominal_gap = "
           f"{v['nominal_gap']} m", source)
    pos = t["secondary"]["positions"]
    _check(len(pos) >= 1 and all(isinstance(p, (int, float)) and not isinstance(p, bool)
                                 and np.isfinite(p) for p in pos),
           f"[secondary] positions = {pos!r}: expected a non-empty list of numbers [m]", source)
    half = 0.5 * v["section_length"] / v["frames_per_section"]
    _check(all(abs(p) <= half for p in pos),
           f"[secondary] positions = {pos!r}: air springs must lie on their frame "
           f"(|position| <= {half:.4g} m)", source)
    _check(v["landing_gap"] > v["nominal_gap"],
           f"[vehicle] landing_gap = {v['landing_gap']} m must be above nominal_gap = "
           f"{v['nominal_gap']} m", source)
    c = t["control"]
    _check(0 < c["damping"] < 5, f"[control] damping = {c['damping']} must be in (0, 5)", source)
    _check(0 <= c["velocity_blend"] <= 1, f"[control] velocity_blend = {c['velocity_blend']} "
           "must be in [0, 1] (0: damping from the gap rate, 1: from the absolute velocity)",
           source)
    mg = t["magnets"]
    _check(mg["eddy_branches"] in (1, 2), f"[magnets] eddy_branches = {mg['eddy_branches']}: "
           "use 1 (the two-state shielded-gap ladder) or 2 (the three-state ladder)", source)
    _check(mg["eddy_branches"] == 1 or mg["motion_eddy"],
           f"[magnets] eddy_branches = {mg['eddy_branches']} needs motion_eddy = true (the "
           "shielded-gap ladder's sections)", source)
    _check(mg["eddy_modes"] in (None, 0, 1, 2, 3), f"[magnets] eddy_modes = "
           f"{mg['eddy_modes']}: use 0 (eq. 8) or 1, 2, 3 (branches of the maps' fitted eddy "
           "network), or leave it out (each magnet's own default)", source)
    _check(not mg["eddy_modes"] or not mg["motion_eddy"],
           f"[magnets] eddy_modes = {mg['eddy_modes']} with motion_eddy = true: two eddy "
           "extensions of eq. 8; use one of them", source)
    prov = parse_provenance(parameters, VEHICLE_SCHEMA, source)
    cb, fr, se, jo = t["car_body"], t["frame"], t["secondary"], t["joint"]
    return TrainData(
        name=v["name"], n_sections=v["sections"], section_length_m=v["section_length"],
        magnets_per_side=v["magnets_per_side"], n_frames_per_section=v["frames_per_section"],
        nominal_gap_m=v["nominal_gap"], touchdown_gap_m=v["touchdown_gap"],
        landing_gap_m=v["landing_gap"],
        standard_magnet=v["standard_magnet"], bow_magnet=v["bow_magnet"],
        car_body_mass_kg=cb["mass"], car_body_pitch_inertia_kg_m2=cb["pitch_inertia"],
        payload_kg=cb["payload"], frame_mass_kg=fr["mass"],
        frame_pitch_inertia_kg_m2=fr["pitch_inertia"], magnet_mass_kg=fr["magnet_mass"],
        spring_stiffness_N_per_m=se["stiffness"], spring_damping_N_s_per_m=se["damping"],
        spring_positions_m=tuple(float(p) for p in pos),
        joint_stiffness_N_per_m=jo["stiffness"], joint_damping_N_s_per_m=jo["damping"],
        control_bandwidth_Hz=c["bandwidth"], control_damping=c["damping"],
        flux_bandwidth_Hz=c["flux_bandwidth"], voltage_limit_V=c["voltage_limit"],
        control_velocity_blend=c["velocity_blend"],
        motion_eddy=bool(mg["motion_eddy"]), eddy_branches=int(mg["eddy_branches"]),
        eddy_modes=None if mg["eddy_modes"] is None else int(mg["eddy_modes"]),
        provenance=prov, source=source)


def bundled_vehicles() -> list[str]:
    """Names of the vehicle files shipped with maglevkit."""
    return bundled_files("vehicle", table="vehicle")


def load_vehicle(source: str | Path = "tr09") -> TrainData:
    """Load a vehicle file by path or bundled name (default: the bundled ``tr09``).

    Parameters
    ----------
    source : str or Path, default "tr09"
        Path of a TOML file, or the name of a bundled file (:func:`bundled_vehicles`).

    Returns
    -------
    TrainData

    Raises
    ------
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    """
    try:
        params, label = read_parameter_file(source, what="vehicle", folder="vehicle",
                                            table="vehicle")
    except ParameterFileError as exc:
        path = Path(str(source))
        if path.suffix == ".toml" or path.exists():
            raise
        # a name: say that the cross-section vehicles are bundled too (another loader)
        xsec = bundled_files("vehicle", table="cross_section")
        raise ParameterFileError(f"{exc}; bundled cross-section vehicles (--vehicle NAME, "
                                 f"load_cross_section): {', '.join(xsec)}") from None
    return parse_vehicle(params, label)
