"""The cross-section vehicle's mechanics: car body, levitation chassis, air springs, magnets.

A slice of the vehicle across the track (the paper's cross-section model, Sec. V, Fig.
10(b)), built on :class:`~maglevkit.vehicle.multibody.PlanarMultibody`:

* bodies: the **car body** (its share of one slice, with its payload) and one
  **levitation chassis** spanning both sides (the chassis with its levitation and guidance
  magnets), each with lateral ``y``, vertical ``z`` (down) and roll ``phi`` displacements
  (``phi > 0`` lowers the right side);
* two **air springs**, left and right, between car body and chassis, each a vertical and a
  lateral spring-damper at ``(-+y_a, z_a)`` (the lateral damper, optionally, at its own
  height ``z_d``: ``lateral_damper_z``); each vertical one carries a static preload,
  half the loaded car body's weight ``m_c g / 2`` (the air pressure a levelling valve
  sets), so that on a straight level track the car body sits at its design position
  (``q = 0``) instead of sagging ``m_c g / (2 k_z)`` on the linear stiffness;
* four **force points** on the chassis: the levitation magnets under the stator, left and
  right (force upward, direction ``-z``), and the guidance magnets outboard of the
  guidance rails, left and right (the left one pulls the chassis to the right, ``+y``, the
  right one to the left, ``-y``: they pull against each other);
* a uniform acceleration field ``(a_y, a_z)`` on every mass: gravity on a straight level
  track, gravity and the centrifugal acceleration resolved in the superelevated track
  plane in a curve (:func:`track_field_m_per_s2`).

Coordinates: ``y`` lateral, positive to the right looking forward, from the guideway's
centreline; ``z`` vertical, positive downward, from the underside of the stator (the
levitation magnets' reaction surface).  The file's positions are those of the reference
configuration; displacements ``q`` are measured from it (see the multibody module for the
small-angle linearisation).

The vehicle file (TOML, SI units, every value tagged in ``[provenance]``; bundled
``tr09-cross-section``)::

    [cross_section] name, empty_train_mass, sections, slices_per_section, slice_length
    [car_body]      mass, payload, roll_inertia, centre_z
    [chassis]       mass, roll_inertia, centre_z
    [air_spring]    y, z, vertical_stiffness, vertical_damping, lateral_stiffness,
                    lateral_damping, lateral_damper_z (optional; default z)
                                                          (one spring; mirrored left/right)
    [levitation]    y, z                                  (force point, mirrored)
    [guidance]      y, z                                  (force point, mirrored)
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ParameterFileError, ProvenanceWarning
from ..magnets.base import Schema, take
from ..parameter_files import bundled_files, parse_provenance, read_parameter_file
from ..plant import STANDARD_GRAVITY
from ..validation import Plausible, check_plausible, real_number
from .multibody import ForcePoint, PlanarMultibody, RigidBody, SpringDamper

__all__ = ["CrossSectionData", "CrossSectionMechanics", "CROSS_SECTION_SCHEMA",
           "CROSS_SECTION_TAGS", "CROSS_SECTION_PLAUSIBLE", "bundled_cross_sections", "load_cross_section",
           "parse_cross_section", "track_field_m_per_s2", "track_field_path"]

#: Provenance tags of a cross-section file: published, widely quoted, derived, estimate.
CROSS_SECTION_TAGS = ("[P]", "[R]", "[D]", "[E]")

CROSS_SECTION_SCHEMA: dict[str, dict[str, Schema]] = {
    "cross_section": {
        "name": Schema(str),
        "empty_train_mass": Schema(float, unit="kg"),
        "sections": Schema(int, unit="-"),
        "slices_per_section": Schema(int, unit="-"),
        "slice_length": Schema(float, unit="m"),
    },
    "car_body": {
        "mass": Schema(float, unit="kg"),
        "payload": Schema(float, unit="kg", check="nonnegative"),
        "roll_inertia": Schema(float, unit="kg m^2"),
        "centre_z": Schema(float, unit="m", check="any"),
    },
    "chassis": {
        "mass": Schema(float, unit="kg"),
        "roll_inertia": Schema(float, unit="kg m^2"),
        "centre_z": Schema(float, unit="m", check="any"),
    },
    "air_spring": {
        "y": Schema(float, unit="m"),
        "z": Schema(float, unit="m", check="any"),
        "vertical_stiffness": Schema(float, unit="N/m"),
        "vertical_damping": Schema(float, unit="N s/m", check="nonnegative"),
        "lateral_stiffness": Schema(float, unit="N/m"),
        "lateral_damping": Schema(float, unit="N s/m", check="nonnegative"),
        "lateral_damper_z": Schema(float, required=False, unit="m", check="any"),
    },
    "levitation": {
        "y": Schema(float, unit="m"),
        "z": Schema(float, unit="m", check="any"),
    },
    "guidance": {
        "y": Schema(float, unit="m"),
        "z": Schema(float, unit="m", check="any"),
    },
}

#: The plausible magnitudes of every dimensional key of a cross-section file
#: (:func:`~maglevkit.validation.check_plausible`, the one check of every file kind: a
#: value outside warns, most likely a unit slip such as mm typed for m or t for kg; it is
#: used as given).  One slice of a maglev vehicle is 1-10 m long and weighs 0.1-100 t;
#: heights ``z`` are signed (magnitudes checked).  Every bundled value lies inside and
#: the same value times 1000 or 1/1000 outside (docs/decisions.md).  Impossible values
#: (negative masses, stiffnesses, lateral positions) are refused by the schema.
CROSS_SECTION_PLAUSIBLE: dict[str, Plausible] = {
    "cross_section.empty_train_mass": Plausible(1e3, 1e7, "kg"),
    "cross_section.slice_length": Plausible(0.5, 30.0, "m"),
    "car_body.mass": Plausible(50.0, 1e5, "kg"),
    "car_body.payload": Plausible(1.0, 1e5, "kg"),
    "car_body.roll_inertia": Plausible(100.0, 1e6, "kg m^2"),
    "car_body.centre_z": Plausible(0.01, 5.0, "m"),
    "chassis.mass": Plausible(10.0, 1e5, "kg"),
    "chassis.roll_inertia": Plausible(10.0, 1e6, "kg m^2"),
    "chassis.centre_z": Plausible(1e-3, 3.0, "m"),
    "air_spring.y": Plausible(0.1, 3.0, "m"),
    "air_spring.z": Plausible(0.01, 3.0, "m"),
    "air_spring.vertical_stiffness": Plausible(1e3, 1e7, "N/m"),
    "air_spring.vertical_damping": Plausible(100.0, 1e6, "N s/m"),
    "air_spring.lateral_stiffness": Plausible(1e3, 1e7, "N/m"),
    "air_spring.lateral_damping": Plausible(100.0, 1e6, "N s/m"),
    "air_spring.lateral_damper_z": Plausible(0.01, 3.0, "m"),
    "levitation.y": Plausible(0.1, 3.0, "m"),
    "levitation.z": Plausible(1e-3, 1.0, "m"),
    "guidance.y": Plausible(0.1, 3.0, "m"),
    "guidance.z": Plausible(1e-3, 1.0, "m"),
}


@dataclass(frozen=True)
class CrossSectionData:
    """A parsed cross-section file (SI units; see the module docstring).

    Attributes
    ----------
    name : str
        Label.
    empty_train_mass_kg : float
        Empty mass of the whole train [kg] (the masses' public anchor).
    n_sections, slices_per_section : int
        Sections of the train and slices (magnet positions per side) of one section.
    slice_length_m : float
        Length of the slice along the track [m].
    car_body_mass_kg, payload_kg, car_body_roll_inertia_kg_m2, car_body_centre_z_m : float
        The car body's share of the slice [kg], its payload [kg] (a point mass at the
        centre of mass), roll inertia [kg m^2] and centre height ``z`` [m] (down).
    chassis_mass_kg, chassis_roll_inertia_kg_m2, chassis_centre_z_m : float
        The levitation chassis with its magnets [kg], roll inertia [kg m^2], ``z`` [m].
    spring_y_m, spring_z_m : float
        Air springs at ``y = -+spring_y_m``, ``z = spring_z_m`` [m].
    spring_vertical_stiffness_N_per_m, spring_vertical_damping_N_s_per_m : float
        One air spring, vertical [N/m], [N s/m].
    spring_lateral_stiffness_N_per_m, spring_lateral_damping_N_s_per_m : float
        One air spring, lateral [N/m], [N s/m].
    levitation_y_m, levitation_z_m, guidance_y_m, guidance_z_m : float
        Force points of the magnets at ``y = -+..._y_m`` and ``z`` [m].
    provenance : dict
        ``"table.key" -> tag``.
    source : str
        File path or bundled name.
    lateral_damper_z_m : float or None
        Height ``z`` of the lateral dampers [m] (None: at the air springs' ``z``; see
        :attr:`damper_z_m`).
    """

    name: str
    empty_train_mass_kg: float
    n_sections: int
    slices_per_section: int
    slice_length_m: float
    car_body_mass_kg: float
    payload_kg: float
    car_body_roll_inertia_kg_m2: float
    car_body_centre_z_m: float
    chassis_mass_kg: float
    chassis_roll_inertia_kg_m2: float
    chassis_centre_z_m: float
    spring_y_m: float
    spring_z_m: float
    spring_vertical_stiffness_N_per_m: float
    spring_vertical_damping_N_s_per_m: float
    spring_lateral_stiffness_N_per_m: float
    spring_lateral_damping_N_s_per_m: float
    levitation_y_m: float
    levitation_z_m: float
    guidance_y_m: float
    guidance_z_m: float
    provenance: Mapping[str, str] = field(default_factory=dict)
    source: str = ""
    lateral_damper_z_m: float | None = None

    @property
    def damper_z_m(self) -> float:
        """Height ``z`` of the lateral dampers [m]: ``lateral_damper_z_m``, else the air
        springs' ``spring_z_m``."""
        return self.spring_z_m if self.lateral_damper_z_m is None else self.lateral_damper_z_m

    @property
    def loaded_car_body_mass_kg(self) -> float:
        """Car body plus payload [kg]."""
        return self.car_body_mass_kg + self.payload_kg

    @property
    def total_mass_kg(self) -> float:
        """Everything the magnets carry: loaded car body and chassis [kg]."""
        return self.loaded_car_body_mass_kg + self.chassis_mass_kg

    @property
    def slice_share_kg(self) -> float:
        """The slice's share of the empty train, ``m_train / (sections slices)`` [kg]."""
        return self.empty_train_mass_kg / (self.n_sections * self.slices_per_section)


def parse_cross_section(parameters: Mapping[str, Any],
                        source: str = "parameters") -> CrossSectionData:
    """Validate a parsed cross-section TOML dictionary (see the module docstring).

    Parameters
    ----------
    parameters : mapping
        The parsed TOML file.
    source : str, default "parameters"
        Label for messages (file path or bundled name).

    Returns
    -------
    CrossSectionData

    Raises
    ------
    ParameterFileError
        Unknown or missing tables and keys, values of the wrong type or sign, the force
        points or air
        springs not outboard of nothing (``y > 0``), or the guidance points not outboard
        of the levitation points.

    Warns
    -----
    PlausibilityWarning
        A value outside its plausible range (:data:`CROSS_SECTION_PLAUSIBLE`), naming the
        key, the value, the range and the likely unit slip.
    ProvenanceWarning
        Values without a ``[provenance]`` entry, or tags not starting with one of
        ``[P]``, ``[R]``, ``[D]``, ``[E]``.
    """
    if not isinstance(parameters, Mapping):
        raise ParameterFileError(f"{source}: a cross-section file must be a TOML table")
    allowed = set(CROSS_SECTION_SCHEMA) | {"provenance"}
    unknown = sorted(set(parameters) - allowed)
    if unknown:
        raise ParameterFileError(f"{source}: unknown table(s) {unknown}; a cross-section file "
                                 f"may have: {', '.join(sorted(allowed))}")
    t: dict[str, dict[str, Any]] = {}
    for table, schema in CROSS_SECTION_SCHEMA.items():
        if table not in parameters:
            raise ParameterFileError(f"{source}: missing the [{table}] table (keys: "
                                     f"{', '.join(schema)})")
        try:
            t[table] = take(parameters[table], schema, table)
        except ParameterFileError as exc:
            raise ParameterFileError(f"{source}: {exc}") from None
    check_plausible(t, CROSS_SECTION_PLAUSIBLE, source, stacklevel=3)
    if not t["guidance"]["y"] > t["levitation"]["y"]:
        raise ParameterFileError(f"{source}: [guidance] y = {t['guidance']['y']!r} m must be "
                                 f"outboard of [levitation] y = {t['levitation']['y']!r} m "
                                 "(the guidance magnets face the outer side of the rails)")
    prov = parse_provenance(parameters, CROSS_SECTION_SCHEMA, source)
    needed = [f"{tb}.{k}" for tb in CROSS_SECTION_SCHEMA for k in parameters[tb]]
    missing = [k for k in needed if k not in prov]
    if missing:
        warnings.warn(f"{source}: [provenance] has no entry for {', '.join(missing)}; every "
                      f"value should carry a tag ({', '.join(CROSS_SECTION_TAGS)})",
                      ProvenanceWarning, stacklevel=3)
    bad = [k for k, tag in prov.items() if not tag.startswith(CROSS_SECTION_TAGS)]
    if bad:
        warnings.warn(f"{source}: [provenance] tag(s) of {', '.join(bad)} do not start with "
                      f"{', '.join(CROSS_SECTION_TAGS)}", ProvenanceWarning, stacklevel=3)
    c, cb, ch, sp = t["cross_section"], t["car_body"], t["chassis"], t["air_spring"]
    return CrossSectionData(
        name=c["name"], empty_train_mass_kg=c["empty_train_mass"], n_sections=c["sections"],
        slices_per_section=c["slices_per_section"], slice_length_m=c["slice_length"],
        car_body_mass_kg=cb["mass"], payload_kg=cb["payload"],
        car_body_roll_inertia_kg_m2=cb["roll_inertia"], car_body_centre_z_m=cb["centre_z"],
        chassis_mass_kg=ch["mass"], chassis_roll_inertia_kg_m2=ch["roll_inertia"],
        chassis_centre_z_m=ch["centre_z"], spring_y_m=sp["y"], spring_z_m=sp["z"],
        spring_vertical_stiffness_N_per_m=sp["vertical_stiffness"],
        spring_vertical_damping_N_s_per_m=sp["vertical_damping"],
        spring_lateral_stiffness_N_per_m=sp["lateral_stiffness"],
        spring_lateral_damping_N_s_per_m=sp["lateral_damping"],
        levitation_y_m=t["levitation"]["y"], levitation_z_m=t["levitation"]["z"],
        guidance_y_m=t["guidance"]["y"], guidance_z_m=t["guidance"]["z"],
        provenance=prov, source=source, lateral_damper_z_m=sp["lateral_damper_z"])


def bundled_cross_sections() -> list[str]:
    """Names of the cross-section vehicle files shipped with maglevkit."""
    return bundled_files("vehicle", table="cross_section")


def load_cross_section(source: str | Path = "tr09-cross-section") -> CrossSectionData:
    """Load a cross-section vehicle file by path or bundled name.

    Parameters
    ----------
    source : str or Path, default "tr09-cross-section"
        Path of a TOML file, or the name of a bundled file (:func:`bundled_cross_sections`).

    Returns
    -------
    CrossSectionData

    Raises
    ------
    InputError
        ``source`` is neither a name nor a path.
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    """
    params, label = read_parameter_file(source, what="cross-section", folder="vehicle",
                                        table="cross_section")
    return parse_cross_section(params, label)


def track_field_m_per_s2(speed_m_per_s: float, curve_radius_m: float = math.inf,
                         superelevation_rad: float = 0.0, *,
                         gravity_m_per_s2: float = STANDARD_GRAVITY) -> np.ndarray:
    """The uniform acceleration field ``(a_y, a_z)`` on the masses in the track plane.

    In a curve of radius ``R`` with the track plane banked by the superelevation angle
    ``c`` into the curve, a body moving with the track at speed ``v`` feels gravity and the
    centrifugal acceleration ``v^2/R`` (horizontal, outward); resolved in the banked track
    plane (``y`` along it, outward positive; ``z`` normal to it, down):

        a_y = v^2/R cos(c) - g sin(c),     a_z = v^2/R sin(c) + g cos(c).

    Quasi-steady: constant ``v``, ``R`` and ``c``; the Coriolis terms of the track frame's
    yaw rate ``v/R`` acting on the small relative velocities and the roll acceleration of
    the track plane (zero in the constant curve; in a transition of the order of the
    superelevation rate squared) are left out.  The net force the magnets must supply is
    ``-m a`` on the total mass carried.  ``a_y = 0`` at the balancing speed
    ``v_b = sqrt(g R tan(c))``.

    Parameters
    ----------
    speed_m_per_s : float
        Vehicle speed [m/s], finite.
    curve_radius_m : float, default inf
        Curve radius [m]; positive for a curve to the left (outward = ``+y``, right),
        negative for one to the right, ``inf`` for a straight track; ``|R| >= 1`` m.
    superelevation_rad : float, default 0
        Bank angle ``c`` of the track plane [rad], positive raising the right side (into a
        left-hand curve); ``|c| < 0.3`` rad (17 deg; real maglev tracks bank up to 12 deg).
    gravity_m_per_s2 : float, default STANDARD_GRAVITY
        Gravitational acceleration g [m/s^2], > 0 (keyword only).

    Returns
    -------
    ndarray (2,)
        ``(a_y, a_z)`` [m/s^2].

    Raises
    ------
    InputError
        A non-number or a value outside the stated range.
    """
    v = real_number(speed_m_per_s, "speed_m_per_s", "m/s")
    r = float(curve_radius_m) if isinstance(curve_radius_m, (int, float)) and math.isinf(
        curve_radius_m) else real_number(curve_radius_m, "curve_radius_m", "m")
    c = real_number(superelevation_rad, "superelevation_rad", "rad")
    g = real_number(gravity_m_per_s2, "gravity_m_per_s2", "m/s^2", positive=True)
    if not abs(r) >= 1.0:
        raise InputError(f"curve_radius_m = {curve_radius_m!r} m: |R| must be >= 1 m "
                         "(inf for a straight track)")
    if not abs(c) < 0.3:
        raise InputError(f"superelevation_rad = {superelevation_rad!r} rad: must be in "
                         "(-0.3, 0.3) rad")
    return track_field_path(v, 0.0 if math.isinf(r) else 1.0 / r, c, gravity_m_per_s2=g)


def track_field_path(speed_m_per_s: float, curvature_per_m: Any, superelevation_rad: Any, *,
                     gravity_m_per_s2: float = STANDARD_GRAVITY) -> np.ndarray:
    """The field of :func:`track_field_m_per_s2` along a path (arrays; inputs not checked).

    ``a_y = v^2 kappa cos(c) - g sin(c)``, ``a_z = v^2 kappa sin(c) + g cos(c)`` with the
    curvature ``kappa = 1/R`` (0 on a straight track; a transition curve ramps it).

    Parameters
    ----------
    speed_m_per_s : float
        Speed v [m/s].
    curvature_per_m : array_like
        Curvature ``1/R`` [1/m] (positive: a left-hand curve).
    superelevation_rad : array_like
        Superelevation ``c`` [rad].
    gravity_m_per_s2 : float, default STANDARD_GRAVITY
        g [m/s^2] (keyword only).

    Returns
    -------
    ndarray (..., 2)
        ``(a_y, a_z)`` [m/s^2] over the broadcast shape of the inputs.
    """
    kappa = np.asarray(curvature_per_m, dtype=float)
    c = np.asarray(superelevation_rad, dtype=float)
    cen = speed_m_per_s * speed_m_per_s * kappa
    g = gravity_m_per_s2
    return np.stack(np.broadcast_arrays(cen * np.cos(c) - g * np.sin(c),
                                        cen * np.sin(c) + g * np.cos(c)), axis=-1)


class CrossSectionMechanics:
    """The cross-section vehicle as a :class:`PlanarMultibody` (see the module docstring).

    Parameters
    ----------
    data : CrossSectionData
        The vehicle (from :func:`load_cross_section`).

    Raises
    ------
    InputError
        ``data`` is not a :class:`CrossSectionData`.

    Attributes
    ----------
    system : PlanarMultibody
        Bodies ``car_body``, ``chassis``; elements ``air_spring_{left,right}.{z,y}`` (and
        ``lateral_damper_{left,right}.y`` when the file puts the lateral dampers at their
        own height); force points ``levitation_{left,right}``, ``guidance_{left,right}``.
    point_names : tuple of str
        The force points in the order of ``F``.
    air_spring_preload_N : float
        Static force of each vertical air spring, ``m_c g / 2`` [N] (``m_c`` the loaded
        car body, ``g`` standard gravity): the car body's design position is the
        equilibrium on a straight level track.
    """

    point_names = ("levitation_left", "levitation_right", "guidance_left", "guidance_right")

    def __init__(self, data: CrossSectionData) -> None:
        if not isinstance(data, CrossSectionData):
            raise InputError(f"data must be CrossSectionData (from load_cross_section), got "
                             f"{type(data).__name__}")
        self.data = d = data
        bodies = [RigidBody("car_body", d.loaded_car_body_mass_kg, d.car_body_roll_inertia_kg_m2,
                            (0.0, d.car_body_centre_z_m)),
                  RigidBody("chassis", d.chassis_mass_kg, d.chassis_roll_inertia_kg_m2,
                            (0.0, d.chassis_centre_z_m))]
        elements = []
        #: static force of each vertical air spring [N]: half the loaded car body's weight
        self.air_spring_preload_N = 0.5 * d.loaded_car_body_mass_kg * STANDARD_GRAVITY
        for side, sign in (("left", -1.0), ("right", 1.0)):
            pt = (sign * d.spring_y_m, d.spring_z_m)
            # car body (a) above the chassis (b): e = +z, compression pushes a up, b down
            elements.append(SpringDamper(f"air_spring_{side}.z", "car_body", pt, "chassis", pt,
                                         "z", d.spring_vertical_stiffness_N_per_m,
                                         d.spring_vertical_damping_N_s_per_m,
                                         self.air_spring_preload_N))
            if d.damper_z_m == d.spring_z_m:
                elements.append(SpringDamper(f"air_spring_{side}.y", "car_body", pt, "chassis",
                                             pt, "y", d.spring_lateral_stiffness_N_per_m,
                                             d.spring_lateral_damping_N_s_per_m))
            else:       # the lateral damper at its own height (docs/cross_section.md)
                elements.append(SpringDamper(f"air_spring_{side}.y", "car_body", pt, "chassis",
                                             pt, "y", d.spring_lateral_stiffness_N_per_m, 0.0))
                pd = (sign * d.spring_y_m, d.damper_z_m)
                elements.append(SpringDamper(f"lateral_damper_{side}.y", "car_body", pd,
                                             "chassis", pd, "y", 0.0,
                                             d.spring_lateral_damping_N_s_per_m))
        points = [ForcePoint("levitation_left", "chassis", (-d.levitation_y_m, d.levitation_z_m),
                             "-z"),
                  ForcePoint("levitation_right", "chassis", (d.levitation_y_m, d.levitation_z_m),
                             "-z"),
                  ForcePoint("guidance_left", "chassis", (-d.guidance_y_m, d.guidance_z_m), "+y"),
                  ForcePoint("guidance_right", "chassis", (d.guidance_y_m, d.guidance_z_m), "-y")]
        self.system = PlanarMultibody(bodies, elements, points)

    def with_magnet_springs(self, levitation_stiffness_N_per_m: float,
                            guidance_stiffness_N_per_m: float, *,
                            levitation_damping_N_s_per_m: float = 0.0,
                            guidance_damping_N_s_per_m: float = 0.0) -> PlanarMultibody:
        """The vehicle with each magnet replaced by a linear spring-damper to the track.

        The simplest stand-in for a magnet with its gap controller (the linear magnet
        models the paper's detailed ones replace): a spring-damper between the force point
        and the ground along the force's direction.  For eigenfrequencies and checks of
        the suspension; the magnets proper enter through the force points.

        Parameters
        ----------
        levitation_stiffness_N_per_m, guidance_stiffness_N_per_m : float
            Stiffness of each levitation and guidance magnet [N/m], >= 0.
        levitation_damping_N_s_per_m, guidance_damping_N_s_per_m : float, default 0
            Their damping [N s/m], >= 0 (keyword only).

        Returns
        -------
        PlanarMultibody
            The same bodies, air springs and force points, plus the elements
            ``magnet_<point>`` (body ``chassis`` to the ground).

        Raises
        ------
        InputError
            A value that is not a finite number >= 0.
        """
        s = self.system
        kl = real_number(levitation_stiffness_N_per_m, "levitation_stiffness_N_per_m", "N/m",
                         nonnegative=True)
        kg = real_number(guidance_stiffness_N_per_m, "guidance_stiffness_N_per_m", "N/m",
                         nonnegative=True)
        cl = real_number(levitation_damping_N_s_per_m, "levitation_damping_N_s_per_m",
                         "N s/m", nonnegative=True)
        cg = real_number(guidance_damping_N_s_per_m, "guidance_damping_N_s_per_m", "N s/m",
                         nonnegative=True)
        extra = []
        for p in s.force_points:
            lev = p.name.startswith("levitation")
            extra.append(SpringDamper(f"magnet_{p.name}", p.body, p.point_m, None, p.point_m,
                                      p.direction[1], kl if lev else kg, cl if lev else cg))
        return PlanarMultibody(s.bodies, [*s.elements, *extra], s.force_points)

    def static_trim(self, field_m_per_s2: Any, *, guidance_bias_N: float = 0.0
                    ) -> tuple[np.ndarray, np.ndarray]:
        """Quasi-static equilibrium with the chassis held at its nominal gaps.

        The gap controllers hold the chassis at ``y = z = phi = 0``; the car body settles
        on the air springs.  Unknowns: ``q`` and the four magnet forces; equations: the
        static balance ``K q = B F + G a + Q_pre`` (air-spring preloads), the three chassis
        coordinates zero, and the guidance magnets' sum ``F_gl + F_gr = 2 F_bias``
        (differential operation about a bias force).

        Parameters
        ----------
        field_m_per_s2 : array_like (2,)
            Acceleration field ``(a_y, a_z)`` [m/s^2] (:func:`track_field_m_per_s2`).
        guidance_bias_N : float, default 0
            Bias force of each guidance magnet [N] (keyword only).

        Returns
        -------
        (q, forces_N) : ndarray (6,), ndarray (4,)
            Displacements [m, rad] and forces at the points of :attr:`point_names` [N]
            (negative guidance forces mean the bias is too small to be differential).

        Raises
        ------
        InputError
            A field that is not two finite numbers, or a non-finite bias.
        """
        a = np.asarray(field_m_per_s2, dtype=float)
        if a.shape != (2,) or not np.isfinite(a).all():
            raise InputError(f"field_m_per_s2 = {field_m_per_s2!r}: expected (a_y, a_z) "
                             "[m/s^2], two finite numbers")
        bias = real_number(guidance_bias_N, "guidance_bias_N", "N")
        s = self.system
        n, npt = s.n_dof, s.B.shape[1]
        lhs = np.zeros((n + 4, n + npt))
        rhs = np.zeros(n + 4)
        lhs[:n, :n] = s.K
        lhs[:n, n:] = -s.B
        rhs[:n] = s.G @ a + s.Q_preload
        for i, d in enumerate(("y", "z", "phi")):
            lhs[n + i, s.dof_names.index(f"chassis.{d}")] = 1.0
        lhs[n + 3, n + 2:n + 4] = 1.0
        rhs[n + 3] = 2.0 * bias
        sol = np.linalg.solve(lhs, rhs)
        return sol[:n], sol[n:]

    def linearised_stiffness(self, field_m_per_s2: Any, *, guidance_bias_N: float = 0.0
                             ) -> np.ndarray:
        """``K + K_pre`` about the static trim of :meth:`static_trim`.

        The preload ("pendulum") stiffness of the air springs' and magnets' static forces
        (:meth:`PlanarMultibody.preload_stiffness`) is evaluated with the trim's element
        forces ``k Delta`` and magnet forces; it assumes level bodies (the car body's trim
        roll in a curve, tens of mrad, changes it by that fraction).

        Parameters
        ----------
        field_m_per_s2 : array_like (2,)
            Acceleration field ``(a_y, a_z)`` [m/s^2].
        guidance_bias_N : float, default 0
            Bias force of each guidance magnet [N] (keyword only).

        Returns
        -------
        ndarray (6, 6)
            Stiffness about the trim [N/m, N, N m/rad].
        """
        q, forces = self.static_trim(field_m_per_s2, guidance_bias_N=guidance_bias_N)
        s = self.system
        element_forces = s.stiffness_N_per_m * s.element_deflections(q) + s.preload_N
        return s.K + s.preload_stiffness(element_forces, forces)
