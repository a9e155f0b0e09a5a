"""Runs of the cross-section vehicle: magnets through the bank, gap controllers, scenarios.

The mechanics (:mod:`maglevkit.vehicle.crosssection`) get their four force points from a
:class:`~maglevkit.reduced.bank.MagnetBank` of four magnets: the levitation magnets left
and right (``tr09-standard``: vertical gap to the stator underside) and the guidance
magnets left and right (``tr-guidance``: lateral gap to the side rail).  Reduced models
(eq. 8 on characteristic maps built once and cached, :mod:`maglevkit.vehicle.mapcache`)
by default; ``magnets="detailed"`` puts the flux-based models into the same bank.

Control: one :class:`~maglevkit.control.cascade.CascadeController` per magnet through the
shared :class:`~maglevkit.control.interface.Controller` interface, every sample
(``dt_s``):

* levitation, per side: its own gap and gap rate;
* guidance, per side, **differential operation**: both magnets run about a bias current
  ``I_b`` (their bias forces cancel) and see the *differential* gap
  ``s_0 + (s_own - s_other)/2`` (the chassis' lateral position), so one pulls harder
  exactly when the other lets go, and their integral actions act on the lateral position
  only (two integrators on gaps whose sum a rail offset may change would wind up against
  each other).

Plant per step (``t_k -> t_k + dt``), in this order: gaps and rates from the mechanics and
the guideway (irregularities, rail offsets) at ``t_k``; controller voltages, the
2-quadrant chopper ``U >= -R_ec I_L`` (the coil current cannot reverse), failed circuits
at 0 V; the bank's step with the gaps moving linearly; the mechanics' exact zero-order
hold step with the mean of the start and end forces, the track's acceleration field and
the crosswind at mid-step.  Two implementations: the NumPy loop with the controller
objects (the reference) and the same step compiled (:meth:`CrossSectionModel.
compiled_step`, the default for reduced magnets; equal to the reference to ~1e-13 while
the chopper does not clamp).

Gaps (``z`` down, ``y`` right; ``Delta s = gap_matrix q`` of the force points)::

    levitation   s = s_0 + Delta s - r_z(x)          (r_z: stator lower, positive down)
    guidance     s_left  = s_0 + Delta s_left  + r_y(x)
                 s_right = s_0 + Delta s_right - r_y(x)   (r_y: rails shifted to the right)
"""

from __future__ import annotations

import math
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, MaglevkitWarning
from ..plant import STANDARD_GRAVITY, chopper_floor
from ..validation import Plausible, check_plausible, real_number
from .crosssection import CrossSectionData, CrossSectionMechanics, track_field_path
from .framework import PartEvaluator, run_blocks, run_steps
from .simulation import (
    Failure,
    VehicleRunInterrupted,
    check_eddy_branches,
    check_motion_eddy_options,
    check_run_speed,
    failure_times,
    interrupted_report_lines,
    limit_crossing,
    touchdown_report_line,
    vehicle_bank,
    vehicle_eddy_modes,
    write_run_netcdf,
)

__all__ = ["CrossSectionModel", "CrossSectionRun", "TransitionCurve", "Crosswind",
           "LATERAL_ALIGNMENT_PSD", "SCENARIO_PLAUSIBLE", "parse_curve", "parse_crosswind", "parse_lateral"]

#: One-sided PSD of the lateral alignment (German high-speed track, "low irregularity":
#: ``A_a = 2.119e-7 m rad``, the corner frequencies of the vertical spectrum; Zhai,
#: Vehicle-Track Coupled Dynamics, 2020) in the parameters of
#: :class:`~maglevkit.vehicle.irregularities.GermanTrackPSD`.
LATERAL_ALIGNMENT_PSD = {"A_v_m_rad": 2.119e-7, "omega_c_rad_per_m": 0.8246,
                         "omega_r_rad_per_m": 0.0206}

SIDES = ("left", "right")

#: Plausible magnitudes of the scenario values (:func:`~maglevkit.validation.
#: check_plausible`: outside, most likely a unit slip, e.g. a radius in km or a gust in kN;
#: the value is used as given, with a :class:`~maglevkit.errors.PlausibilityWarning`).
#: Rail irregularities above 10 mm exceed the nominal gap.
SCENARIO_PLAUSIBLE: dict[str, Plausible] = {
    "curve.radius_m": Plausible(100.0, 1e5, "m"),
    "crosswind.peak_force_N": Plausible(100.0, 1e6, "N"),
    "lateral.rms_m": Plausible(1e-5, 0.01, "m"),
    "lateral.height_m": Plausible(1e-5, 0.01, "m"),
}

#: Largest superelevation (cant) of a curve [rad] a run accepts (17.19 deg).
SUPERELEVATION_LIMIT_RAD = 0.3


@dataclass(frozen=True)
class TransitionCurve:
    """A curve entered through a transition of length ``transition_m``.

    From ``start_m`` the curvature ``1/R`` and the superelevation ``c`` ramp linearly with
    the distance (a clothoid with a linear cant ramp) to their full values at
    ``start_m + transition_m``, constant after.  The track's acceleration field follows
    :func:`~maglevkit.vehicle.crosssection.track_field_path` at every point
    (quasi-steady: the roll rate ``v dc/dx`` of the track plane in the transition and its
    jumps at the ramp's ends are left out).

    Parameters
    ----------
    radius_m : float
        Radius R of the full curve [m], ``|R| >= 1`` (positive: a left-hand curve, outward
        ``+y``), or ``inf`` (straight).
    superelevation_rad : float
        Full superelevation c [rad], ``|c| < 0.3``.
    transition_m : float
        Length of the transition [m], >= 0 (0: the curve starts at once).
    start_m : float, default 0
        Distance travelled at the transition's start [m], >= 0.
    """

    radius_m: float
    superelevation_rad: float
    transition_m: float
    start_m: float = 0.0

    def __post_init__(self) -> None:
        r = self.radius_m
        if not (isinstance(r, (int, float)) and not isinstance(r, bool)
                and (math.isinf(r) or (math.isfinite(r) and abs(r) >= 1.0))):
            raise InputError(f"curve radius_m = {r!r} m: expected |R| >= 1 m or inf")
        c = real_number(self.superelevation_rad, "curve superelevation_rad", "rad")
        if not abs(c) < SUPERELEVATION_LIMIT_RAD:
            # a value that would be a valid angle in degrees: probably typed as such
            raise InputError(_superelevation_range(c)
                             + ("; sweep files and the Python API take it in rad (12 deg = "
                                "0.2094 rad), --curve in deg: degrees typed as radians?"
                                if abs(c) < math.degrees(SUPERELEVATION_LIMIT_RAD) else ""))
        real_number(self.transition_m, "curve transition_m", "m", nonnegative=True)
        real_number(self.start_m, "curve start_m", "m", nonnegative=True)
        check_plausible({"curve": {"radius_m": r}}, SCENARIO_PLAUSIBLE, stacklevel=4)

    def ramp(self, distance_m: Any) -> np.ndarray:
        """Share (0 to 1) of the full curve at the distances travelled [m] (-).

        Parameters
        ----------
        distance_m : array_like
            Distance travelled [m].

        Returns
        -------
        ndarray
            0 before the transition, 1 after it, linear in between.
        """
        x = np.asarray(distance_m, dtype=float) - self.start_m
        if self.transition_m == 0:
            return (x >= 0).astype(float)
        return np.clip(x / self.transition_m, 0.0, 1.0)

    def field(self, speed_m_per_s: float, distance_m: Any) -> np.ndarray:
        """Acceleration field ``(a_y, a_z)`` [m/s^2] at the distances [m], shape (..., 2).

        Parameters
        ----------
        speed_m_per_s : float
            Speed [m/s].
        distance_m : array_like
            Distance travelled [m].

        Returns
        -------
        ndarray (..., 2)
        """
        share = self.ramp(distance_m)
        kappa = 0.0 if math.isinf(self.radius_m) else 1.0 / self.radius_m
        return track_field_path(speed_m_per_s, share * kappa, share * self.superelevation_rad)


@dataclass(frozen=True)
class Crosswind:
    """A crosswind gust on the car body: a lateral force and its roll moment.

    Shape ``"1-cosine"`` (the discrete gust of the airworthiness codes, e.g. EASA CS-25.341:
    ``U(t) = U_max/2 (1 - cos(pi t / H))`` up to the peak at ``t = H``), here rising over
    ``rise_s``, held for ``hold_s`` and falling back symmetrically, applied to the force::

        F(t) = F_max g(t),   g = (1 - cos(pi tau / T_r))/2 on the ramps,  1 on the plateau

    ``"step"``: ``F_max`` from ``start_s`` on (a constant lateral force).  The force acts
    along ``+y`` (to the right) at the height ``z_cp`` of the centre of pressure, so its
    roll moment about the car body's centre of mass is ``F (z_c - z_cp)``.

    Parameters
    ----------
    peak_force_N : float
        F_max [N], finite (negative: wind from the right).
    rise_s : float, default 0.5
        Rise time T_r [s], > 0 (``"1-cosine"``).
    hold_s : float, default 1.0
        Plateau [s], >= 0 (``"1-cosine"``).
    start_s : float, default 0.5
        Start time [s], >= 0.
    shape : {"1-cosine", "step"}
        Time shape.
    pressure_height_m : float, default 0.3
        Height of the centre of pressure above the car body's centre of mass [m] [E].
    """

    peak_force_N: float
    rise_s: float = 0.5
    hold_s: float = 1.0
    start_s: float = 0.5
    shape: str = "1-cosine"
    pressure_height_m: float = 0.3

    def __post_init__(self) -> None:
        real_number(self.peak_force_N, "crosswind peak_force_N", "N")
        real_number(self.rise_s, "crosswind rise_s", "s", positive=True)
        real_number(self.hold_s, "crosswind hold_s", "s", nonnegative=True)
        real_number(self.start_s, "crosswind start_s", "s", nonnegative=True)
        real_number(self.pressure_height_m, "crosswind pressure_height_m", "m")
        if self.shape not in ("1-cosine", "step"):
            raise InputError(f"crosswind shape = {self.shape!r}; allowed: '1-cosine', 'step'")
        check_plausible({"crosswind": {"peak_force_N": self.peak_force_N}},
                        SCENARIO_PLAUSIBLE, stacklevel=4)

    def force_N(self, time_s: Any) -> np.ndarray:
        """Lateral force ``F(t)`` [N] at the times [s].

        Parameters
        ----------
        time_s : array_like
            Times [s].

        Returns
        -------
        ndarray
            Force along ``+y`` [N].
        """
        t = np.asarray(time_s, dtype=float) - self.start_s
        if self.shape == "step":
            return np.where(t >= 0, self.peak_force_N, 0.0)
        tr, th = self.rise_s, self.hold_s
        up = 0.5 * (1 - np.cos(np.pi * np.clip(t, 0, tr) / tr))
        down = 0.5 * (1 - np.cos(np.pi * np.clip(2 * tr + th - t, 0, tr) / tr))
        return self.peak_force_N * np.minimum(up, down)


def _numbers(text: str, what: str, example: str) -> list[float]:
    try:
        vals = [float(v) for v in str(text).split(":")]
    except ValueError:
        raise InputError(f"{what} = {text!r}: expected numbers separated by ':', e.g. "
                         f"{example}") from None
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"{what} = {text!r}: values must be finite numbers, e.g. {example}")
    return vals


def parse_curve(text: str) -> TransitionCurve:
    """``"RADIUS_M:SUPERELEVATION_DEG:TRANSITION_M[:START_M]"`` -> :class:`TransitionCurve`.

    Parameters
    ----------
    text : str
        E.g. ``"4000:12:300"`` (R = 4000 m, 12 deg, 300 m transition from the start).

    Returns
    -------
    TransitionCurve

    Raises
    ------
    InputError
        Not three or four numbers, or values out of range (named).
    """
    vals = _numbers(text, "--curve", "4000:12:300")
    if len(vals) not in (3, 4):
        raise InputError(f"--curve = {text!r}: expected RADIUS_M:SUPERELEVATION_DEG:"
                         "TRANSITION_M[:START_M], e.g. 4000:12:300")
    c = math.radians(vals[1])
    if math.isfinite(c) and not abs(c) < SUPERELEVATION_LIMIT_RAD:    # without the files' hint
        raise InputError(f"--curve = {text!r}: {_superelevation_range(c)}")
    try:
        return TransitionCurve(vals[0], c, vals[2], vals[3] if len(vals) == 4 else 0.0)
    except InputError as exc:
        raise InputError(f"--curve = {text!r}: {exc}") from None


def _superelevation_range(c: float) -> str:
    """The out-of-range message of a superelevation ``c`` [rad], in both units."""
    lim, lim_deg = SUPERELEVATION_LIMIT_RAD, math.degrees(SUPERELEVATION_LIMIT_RAD)
    return (f"curve superelevation {math.degrees(c):.6g} deg (superelevation_rad = "
            f"{c:.6g} rad): must be in ({-lim_deg:.2f}, {lim_deg:.2f}) deg, i.e. "
            f"({-lim:g}, {lim:g}) rad")


def parse_crosswind(text: str) -> Crosswind:
    """``"PEAK_N[:RISE_S[:HOLD_S[:START_S[:SHAPE]]]]"`` -> :class:`Crosswind`.

    Parameters
    ----------
    text : str
        E.g. ``"8000:0.5:1:0.5"`` or ``"5000:0.5:0:0.2:step"`` (shape ``1-cosine`` or
        ``step``; a step has no rise or hold: those slots only place ``START_S``).

    Returns
    -------
    Crosswind

    Raises
    ------
    InputError
        Bad numbers, a bad shape or values out of range (named).

    Warns
    -----
    MaglevkitWarning
        A step with RISE_S/HOLD_S but no START_S (they would be ignored), or with a
        non-zero HOLD_S (a step does not end).
    """
    parts = str(text).split(":")
    shape = "1-cosine"
    if parts and parts[-1] in ("1-cosine", "step"):
        shape = parts.pop()
    if not 1 <= len(parts) <= 4:
        raise InputError(f"--crosswind = {text!r}: expected PEAK_N[:RISE_S[:HOLD_S[:START_S"
                         "]]][:SHAPE], SHAPE 1-cosine or step, e.g. 8000:0.5:1:0.5")
    vals = _numbers(":".join(parts), "--crosswind", "8000:0.5:1:0.5")
    names = ("peak_force_N", "rise_s", "hold_s", "start_s")
    # a step has neither rise nor hold: those slots only place START_S (was silent)
    if shape == "step" and len(vals) in (2, 3):
        warnings.warn(f"--crosswind = {text!r}: the step shape has no rise or hold, so "
                      f"{' and '.join(n.upper() for n in names[1:len(vals)])} "
                      f"{':'.join(f'{v:g}' for v in vals[1:])} s are ignored; give "
                      f"PEAK_N:step, or PEAK_N:0.5:0:START_S:step to set its start",
                      MaglevkitWarning, stacklevel=2)
    elif shape == "step" and len(vals) == 4 and vals[2] != 0.0:
        warnings.warn(f"--crosswind = {text!r}: HOLD_S = {vals[2]:g} s is ignored: a step "
                      "holds its force from START_S to the end of the run (use the 1-cosine "
                      "shape for a gust that ends; for a step put 0 there)",
                      MaglevkitWarning, stacklevel=2)
    try:
        return Crosswind(**dict(zip(names, vals, strict=False)), shape=shape)
    except InputError as exc:
        raise InputError(f"--crosswind = {text!r}: {exc}") from None


def parse_lateral(text: str, *, girder_length_m: float = 24.768) -> Any:
    """A lateral guidance-rail irregularity from a short spec (parts joined by ``+``):

    * ``random:RMS[:SEED]`` - random alignment of the German track spectrum's shape
      (:data:`LATERAL_ALIGNMENT_PSD`) over wavelengths 1-100 m, scaled to ``RMS`` [m];
    * ``girders:H[:SEED]`` - each girder's rails offset by a seeded uniform value in
      ``[-H/2, H/2]`` [m] (steps at the girder joints, ``girder_length_m`` apart);
    * ``none``.

    Parameters
    ----------
    text : str
        E.g. ``"random:0.3e-3:1+girders:0.5e-3"``.
    girder_length_m : float, default 24.768
        Girder (span) length [m] (keyword only).

    Returns
    -------
    Profile or None

    Raises
    ------
    InputError
        Unknown parts or bad numbers (naming ``--lateral`` and the allowed forms).
    """
    from .irregularities import GermanTrackPSD, JointSteps, RandomProfile

    prof: Any = None
    parts = [p.strip() for p in str(text).split("+") if p.strip()]
    if not parts:
        raise InputError("--lateral: empty spec; use e.g. random:0.3e-3+girders:0.5e-3 or none")
    for p in parts:
        if p == "none":
            continue
        kind, _, rest = p.partition(":")
        try:
            nums = [float(x) for x in rest.split(":")] if rest else []
        except ValueError:
            nums = []
        ok = (len(nums) in (1, 2) and all(math.isfinite(x) for x in nums) and nums[0] > 0
              and (len(nums) == 1 or (nums[1] >= 0 and nums[1] == int(nums[1]))))
        if not ok or kind not in ("random", "girders"):
            raise InputError(f"--lateral part {p!r}: use random:RMS[:SEED], girders:H[:SEED] "
                             "(metres, RMS and H > 0, SEED a whole number) or none, joined "
                             "by '+'")
        seed = int(nums[1]) if len(nums) == 2 else 0
        check_plausible({"lateral": {"rms_m" if kind == "random" else "height_m": nums[0]}},
                        SCENARIO_PLAUSIBLE, "--lateral")
        if kind == "random":
            lo, hi = 2 * np.pi / 100.0, 2 * np.pi / 1.0
            base = GermanTrackPSD(**LATERAL_ALIGNMENT_PSD)
            psd = GermanTrackPSD(A_v_m_rad=base.A_v_m_rad * nums[0] ** 2
                                 / base.variance_m2(lo, hi),
                                 omega_c_rad_per_m=base.omega_c_rad_per_m,
                                 omega_r_rad_per_m=base.omega_r_rad_per_m)
            new: Any = RandomProfile(psd, lo, hi, seed=seed)
        else:
            new = JointSteps(nums[0], pitch_m=girder_length_m, pattern="random", seed=seed)
        prof = new if prof is None else prof + new
    return prof


@dataclass(frozen=True)
class CrossSectionRun:
    """Result of a cross-section run.

    Attributes
    ----------
    dataset : xarray.Dataset
        Time series, units in the attributes (see :meth:`CrossSectionModel.run`).
    min_gap_m : dict
        Minimum gap per magnet [m].
    touchdown : tuple or None
        ``(circuit, time_s, gap_m, kind)`` of the first gap at or below the touchdown gap
        (``"closed"``) or at or above the landing gap (``"open"``), or None.
    comfort : dict
        ``"lateral"``: ISO 2631-1 ``Wd`` RMS and Sperling ``Wz``; ``"vertical"``: ``Wk``
        RMS and ``Wz`` of the car body's accelerations (mean removed).
    wall_time_s : float
        Time spent in the time loop [s].
    real_time_factor : float
        Simulated time / wall time of the loop.
    """

    dataset: Any
    min_gap_m: dict[str, float]
    touchdown: tuple[str, float, float, str] | None
    comfort: dict[str, dict[str, float]] = field(default_factory=dict)
    wall_time_s: float = math.nan
    real_time_factor: float = math.nan

    def to_netcdf(self, path: str | Path) -> Path:
        """Write the dataset to netCDF and return the path
        (:func:`~maglevkit.vehicle.simulation.write_run_netcdf`: atomically; a missing
        folder is an :class:`~maglevkit.errors.InputError`).

        Parameters
        ----------
        path : str or Path
            Target file.
        """
        return write_run_netcdf(self.dataset, path)

    def report(self) -> str:
        """A short plain-text report."""
        ds = self.dataset
        lines = [f"{ds.attrs['vehicle']}: {float(ds.attrs['speed_m_per_s']) * 3.6:.0f} km/h, "
                 f"{float(ds.time[-1]):.3g} s simulated ({self.real_time_factor:.1f}x real "
                 "time)"]
        for k, v in self.min_gap_m.items():
            lines.append(f"  minimum {k} gap {v * 1e3:.3f} mm")
        lines.append(touchdown_report_line(ds, self.touchdown))
        lines.extend(interrupted_report_lines(ds))
        for name, ci in self.comfort.items():
            lines.append(f"  comfort {name}: ISO 2631 a_w = {ci['weighted_rms_m_per_s2']:.4f} "
                         f"m/s^2, Sperling Wz = {ci['sperling_wz']:.2f}")
        return "\n".join(lines)


class CrossSectionModel:
    """The cross-section vehicle with its magnets and gap controllers (module docstring).

    Parameters
    ----------
    data : CrossSectionData, optional
        The vehicle (default: the bundled ``tr09-cross-section``).
    levitation_magnet, guidance_magnet : str, default "tr09-standard", "tr-guidance"
        Magnet files (bundled names or paths); each must be as long as the slice.
    magnets : {"reduced", "detailed"}
        Reduced current-based models on cached maps, or the detailed flux-based models.
    maps_cache : path, optional
        Directory of the cached maps (:mod:`maglevkit.vehicle.mapcache`).
    compiled : {"auto", "always", "never"}
        Passed to the bank.
    nominal_gap_m : float, default 0.010
        Nominal gap of levitation and guidance magnets [m] [P 10 mm].
    guidance_bias_current_A : float, default 20.0
        Bias current of both guidance magnets [A] [E] (their bias forces cancel).
    bandwidth_Hz, damping : float, default 5.0, 0.7
        Gap loops' natural frequency [Hz] and damping ratio [-] [E] (as the heave-pitch
        train's file).
    flux_bandwidth_Hz : float, default 30.0
        Flux loops' bandwidth [Hz] [E].
    voltage_limit_V : float, default 440.0
        Chopper supply ``|U| <= U_max`` [V] [P].
    touchdown_gap_m, landing_gap_m : float, default 0.002, 0.020
        A gap at or below ``touchdown_gap_m`` (magnet on its rail) or at or above
        ``landing_gap_m`` stops the run [m] [E].
    motion_eddy : bool or "levitation", default False
        Fly the reduced magnets with the shielded-gap ladder (:class:`MagnetBank` option
        ``motion_eddy``; docs/reduction.md, "Gap motion"): the shielding eddy current
        ``I_e`` of every circuit in both loops, recorded as ``levitation_eddy_current``
        and ``guidance_eddy_current`` (0 in eq. 8 circuits); the chopper floor ``U >=
        -R_a (I_L + I_e)``.  ``"levitation"``: the levitation magnets only, the guidance
        magnets eq. 8 (the bundled guidance magnet's ladder fits its detailed model
        poorly and destabilises its loops; docs/vehicle.md).  Reduced magnets whose maps
        carry the ladder only.
    eddy_branches : {1, 2}, default 1
        Shielded sections of that ladder: 1 the two-state ladder, 2 the three-state ladder
        (``I_e1``, ``I_e2`` per circuit; the eddy-current records then have an
        ``eddy_state`` dimension; docs/equations.md section 8, "Three states"), only with
        ``motion_eddy``.
    eddy_modes : {0, 1, 2, 3} or mapping of str to int, optional
        Fly the reduced magnets with the maps' fitted eddy network of that many branches
        (:class:`MagnetBank` option ``eddy_modes``; docs/bank.md, "Eddy-network members"):
        the branch currents ``I_k`` in both loops, recorded as ``levitation_eddy_current``
        and ``guidance_eddy_current`` (an ``eddy_state`` dimension for more than one
        branch; 0 in a kind's circuits on eq. 8); the chopper floor ``U >= -R_0 (I_L +
        sum_k I_k)``.  An int: every magnet; a mapping ``{"levitation": m, "guidance":
        m}``: per kind (a kind left out takes its default).  None (default): each magnet
        file's own default (``[reduced] eddy_modes``;
        :attr:`~maglevkit.magnets.Magnet.default_eddy_modes`), 0 with ``motion_eddy`` or
        detailed magnets (docs/cross_section.md, "Which reduced model the magnets fly").
        Not 1-3 with ``motion_eddy``; reduced magnets whose maps carry the network only.

    Raises
    ------
    InputError
        Bad options (named), magnets of the wrong kind or length.
    """

    DEFAULT_MAGNETS = {"levitation": "tr09-standard", "guidance": "tr-guidance"}
    """Default magnet files of the two kinds (bundled names)."""
    MEMBERS = tuple((k, f"{k}_{s}") for k in ("levitation", "guidance") for s in SIDES)
    """``(kind, bank member name)`` of the four magnets, in the bank's order."""

    def __init__(self, data: CrossSectionData | None = None, *,
                 levitation_magnet: str = "tr09-standard", guidance_magnet: str = "tr-guidance",
                 magnets: str = "reduced", maps_cache: Any = None, compiled: str = "auto",
                 nominal_gap_m: float = 0.010, guidance_bias_current_A: float = 20.0,
                 bandwidth_Hz: float = 5.0, damping: float = 0.7,
                 flux_bandwidth_Hz: float = 30.0, voltage_limit_V: float = 440.0,
                 touchdown_gap_m: float = 0.002, landing_gap_m: float = 0.020,
                 motion_eddy: bool | str = False, eddy_branches: int = 1,
                 eddy_modes: int | Mapping[str, int] | None = None) -> None:
        from ..control import design_gap_controller
        from ..magnets import load_magnet
        from ..models.flux import FluxModel
        from ..reduced.bank import MagnetBank
        from .crosssection import load_cross_section
        from .mapcache import vehicle_maps

        self.data = d = load_cross_section() if data is None else data
        self.mechanics = CrossSectionMechanics(d)
        if magnets not in ("reduced", "detailed"):
            raise InputError(f"magnets (--magnets) = {magnets!r}; use 'reduced' or 'detailed'")
        self.s0 = real_number(nominal_gap_m, "nominal_gap_m", "m", positive=True)
        self.bias_A = real_number(guidance_bias_current_A, "guidance_bias_current_A", "A",
                                  positive=True)
        self.touchdown_gap_m = real_number(touchdown_gap_m, "touchdown_gap_m", "m",
                                           positive=True)
        self.landing_gap_m = real_number(landing_gap_m, "landing_gap_m", "m", positive=True)
        if not self.touchdown_gap_m < self.s0 < self.landing_gap_m:
            raise InputError(f"touchdown_gap_m = {touchdown_gap_m!r} m, nominal_gap_m = "
                             f"{nominal_gap_m!r} m, landing_gap_m = {landing_gap_m!r} m: "
                             "must increase in that order")
        kinds = {"levitation": load_magnet(levitation_magnet),
                 "guidance": load_magnet(guidance_magnet)}
        want = {"levitation": "levitation_magnet", "guidance": "guidance_magnet"}
        for kind, mag in kinds.items():
            if mag.kind != want[kind]:
                raise InputError(f"{kind}_magnet = {mag.name!r} is a {mag.kind!r} magnet; "
                                 f"expected a {want[kind]!r}")
        par = kinds["levitation"].parameters["magnet"]
        length = {"levitation": float(par["poles"]) * float(par["pole_pitch"]),
                  "guidance": float(kinds["guidance"].parameters["magnet"]["section_length"])
                  * len(kinds["guidance"].circuit_names)}
        for kind, ln in length.items():
            if abs(ln - d.slice_length_m) > 1e-3:
                raise InputError(f"{kind} magnet {kinds[kind].name!r} is {ln:.4f} m long, "
                                 f"but the slice is {d.slice_length_m:.4f} m")
        self.magnets = kinds
        self.maps = {k: vehicle_maps(m, cache_dir=maps_cache) for k, m in kinds.items()}
        self.member_names = tuple(name for _, name in self.MEMBERS)
        members = [(n, FluxModel(kinds[n.split("_")[0]]) if magnets == "detailed"
                    else self.maps[n.split("_")[0]]) for n in self.member_names]
        if isinstance(motion_eddy, np.bool_):
            motion_eddy = bool(motion_eddy)
        if not (isinstance(motion_eddy, bool) or motion_eddy == "levitation"):
            raise InputError(f"motion_eddy = {motion_eddy!r}; use True (every magnet), "
                             "'levitation' (the levitation magnets only) or False")
        self.eddy_branches = check_eddy_branches(eddy_branches,
                                                 motion_eddy=motion_eddy is not False)
        """Shielded sections of the ladder: 1 (two-state) or 2 (three-state)."""
        if motion_eddy is not False:
            check_motion_eddy_options(magnets=magnets, eddy_resistance_scale=1.0)
        self.eddy_modes_of = vehicle_eddy_modes(eddy_modes, kinds,
                                                motion_eddy=motion_eddy is not False,
                                                magnet_kind=magnets)
        """Branches of the eddy network each magnet kind (``"levitation"``,
        ``"guidance"``) flies with (0: eq. 8): the option, else each magnet file's own
        default (:func:`~maglevkit.vehicle.simulation.vehicle_eddy_modes`)."""
        self.eddy_modes = max(self.eddy_modes_of.values())
        """The most eddy-network branches of a magnet kind (0: none flies the network)."""
        self.bank = vehicle_bank(
            MagnetBank, members, motion_eddy=motion_eddy is not False,
            eddy_branches=self.eddy_branches, eddy_modes=self.eddy_modes_of,
            files={"levitation": levitation_magnet, "guidance": guidance_magnet},
            kind_of={n: n.split("_")[0] for n in self.member_names},
            ladder_kinds=("levitation",) if motion_eddy == "levitation" else None,
            option=f"motion_eddy = {motion_eddy!r}", gap_inputs="circuit", compiled=compiled)
        self.magnet_kind = magnets
        self.motion_eddy = motion_eddy
        """The ``motion_eddy`` option (True, ``"levitation"`` or False)."""
        # circuits of each member, in the bank's order
        sl = self.bank.circuit_slices
        self.circuit_slices = [sl[n] for n in self.member_names]
        # trim on a straight level track: guidance magnets at the bias current, the
        # levitation magnets carry the rest (both circuits of a magnet at one current)
        self.guidance_bias_force_N = self._force("guidance", self.s0, self.bias_A)
        self.trim_field = track_field_path(0.0, 0.0, 0.0)
        q, forces = self.mechanics.static_trim(self.trim_field,
                                               guidance_bias_N=self.guidance_bias_force_N)
        self.trim_q, self.trim_force_N = q, forces
        self.trim_current_A = np.array([self._current("levitation", forces[0]),
                                        self._current("levitation", forces[1]),
                                        self.bias_A, self.bias_A])
        g = STANDARD_GRAVITY
        lev = design_gap_controller(kinds["levitation"], mass_kg=forces[0] / g, gap_m=self.s0,
                                    current_A=float(self.trim_current_A[0]),
                                    bandwidth_hz=bandwidth_Hz, damping=damping,
                                    flux_bandwidth_hz=flux_bandwidth_Hz,
                                    voltage_limit_V=voltage_limit_V)
        # differential pair: each guidance magnet moves half the slice laterally
        gui = design_gap_controller(kinds["guidance"], mass_kg=0.5 * d.total_mass_kg,
                                    gap_m=self.s0, current_A=self.bias_A,
                                    bandwidth_hz=bandwidth_Hz, damping=damping,
                                    flux_bandwidth_hz=flux_bandwidth_Hz,
                                    voltage_limit_V=voltage_limit_V)
        self.designs = {"levitation": lev, "guidance": gui}
        self.voltage_limit_V = float(voltage_limit_V)
        self.flux_bandwidth_Hz = float(flux_bandwidth_Hz)
        self._compiled_cache: dict[float, dict[str, Any]] = {}

    # ------------------------------------------------------------------ statics helpers
    def _spline(self, kind: str, var: str, circuit: str) -> Any:
        from scipy.interpolate import RectBivariateSpline

        m = self.maps[kind]
        return RectBivariateSpline(m.gaps_m, m.currents_A, m.variable(var, circuit))

    def _force(self, kind: str, gap: float, current: float) -> float:
        """Force of a magnet of ``kind`` [N] with every circuit at ``current`` (maps)."""
        return sum(float(self._spline(kind, "force_N", c)(gap, current)[0, 0])
                   for c in self.magnets[kind].circuit_names)

    def _current(self, kind: str, force: float) -> float:
        from scipy.optimize import brentq

        c = self.maps[kind].currents_A
        fmax = self._force(kind, self.s0, float(c[-1]))
        if not 0 < force < fmax:
            raise InputError(f"the {kind} magnet would have to carry {force:.5g} N at the "
                             f"nominal gap; its maps reach {fmax:.5g} N")
        return float(brentq(lambda i: self._force(kind, self.s0, i) - force, c[0], c[-1],
                            xtol=1e-10))

    def _flux(self, kind: str, current: float) -> np.ndarray:
        return np.array([float(self._spline(kind, "flux_linkage_Wb", c)(self.s0, current)[0, 0])
                         for c in self.magnets[kind].circuit_names])

    def controllers(self) -> list[Any]:
        """Fresh controllers of the four magnets (levitation left, right, guidance left,
        right), each a :class:`~maglevkit.control.cascade.CascadeController` whose flux
        estimate starts at its magnet's trim flux (from the maps).

        Returns
        -------
        list of CascadeController
        """
        from ..control import CascadeController

        out = []
        for j, name in enumerate(self.member_names):
            kind = name.split("_")[0]
            out.append(CascadeController(self.designs[kind], initial_flux_Wb=self._flux(
                kind, float(self.trim_current_A[j]))))
        return out

    def discretize(self, dt_s: float, *, damping: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Exact zero-order-hold step ``x+ = Ad x + Bd Q`` of the mechanics
        (:meth:`PlanarMultibody.discretize`).

        Parameters
        ----------
        dt_s : float
            Step [s], > 0.
        damping : bool, default True
            Include the air springs' dampers.

        Returns
        -------
        (Ad, Bd) : ndarray (12, 12), ndarray (12, 6)
        """
        return self.mechanics.system.discretize(dt_s, damping=damping)

    def _step_parts(self, dt: float) -> dict[str, Any]:
        """The step's parts (:func:`~maglevkit.vehicle.stepkernel.build_vehicle_parts`) for
        the slice: every circuit a force point of the rigid guideway (force matrix
        ``gap_matrix^T`` per circuit, so that ``s = s_0 + gap_matrix q - r`` and the
        mechanics' load is ``Q_g + B F``), the cascade gains per circuit, the guidance
        pairs' integrators fed the differential gap error."""
        from .stepkernel import build_vehicle_parts

        bank = self.bank
        s = self.mechanics.system
        nq, nc = s.n_dof, bank.n_circuits
        circ = np.repeat(np.arange(4), 2)
        gm = s.gap_matrix[circ]                            # (nc, nq): every circuit's gap
        ad, bd = self.discretize(dt)
        designs = [self.designs[n.split("_")[0]] for n in self.member_names]
        gains = {k: np.array([getattr(designs[c], k) for c in circ])
                 for k in ("kp_per_m", "kd_s_per_m", "ki_per_m_s", "kflux_per_s")}
        psi0 = np.concatenate([np.asarray(d.flux_bias_Wb) for d in designs])
        res = np.concatenate([np.asarray(d.resistances_ohm) for d in designs])
        integ = np.eye(nc)
        for a, b in ((4, 6), (5, 7)):                     # guidance pairs left/right
            integ[a, a] = integ[b, b] = 0.5
            integ[a, b] = integ[b, a] = -0.5
        return build_vehicle_parts(
            dt=dt, nominal_gap_m=self.s0, span_length_m=1.0, origin_m=0.0,
            wavenumbers=np.zeros(0), guideway_ad=np.zeros((0, 0)),
            guideway_bd=np.zeros((0, 0)), n_spans=0, mech_ad=ad, mech_bd=bd,
            gravity_force=np.zeros(nq), force_matrix=gm.T, gains=gains, flux_bias_Wb=psi0,
            resistance_ohm=res, eddy_resistance_ohm=bank.eddy_resistance_ohm,
            voltage_limit_V=self.voltage_limit_V, integral_projection=integ,
            midspan_shape=np.zeros(0))

    # ------------------------------------------------------------------ the run
    def run(self, *, speed_m_per_s: float, duration_s: float, dt_s: float = 1e-3,
            curve: TransitionCurve | None = None, crosswind: Crosswind | None = None,
            vertical: Any = None, lateral: Any = None,
            failures: Sequence[Failure] = (), loop: str = "auto",
            progress: bool = False) -> CrossSectionRun:
        """Simulate the slice at constant speed from the straight-level trim.

        Parameters
        ----------
        speed_m_per_s : float
            Speed v [m/s], >= 0.
        duration_s : float
            Simulated time [s], > 0.
        dt_s : float, default 1e-3
            Time step and controller sample time [s], > 0.
        curve : TransitionCurve, optional
            Curve entry (default: straight level track).
        crosswind : Crosswind, optional
            Gust on the car body.
        vertical, lateral : Profile, optional
            Stator (vertical, positive down) and guidance-rail (lateral, positive to the
            right) irregularities [m] over the distance travelled (e.g. ``JointSteps``
            with the girder length for rail offsets at girder joints).
        failures : sequence of Failure
            Circuits (``"levitation_left/front"``, ... :attr:`MagnetBank.circuit_names`)
            switched to 0 V from their time on.
        loop : {"auto", "compiled", "python"}
            ``"python"``: the NumPy loop with the controllers through the
            :class:`~maglevkit.control.interface.Controller` interface (the reference);
            ``"compiled"``: the same step as one compiled CasADi function per block of
            steps (:meth:`compiled_step`; reduced magnets only); ``"auto"`` (default):
            compiled for reduced magnets, else the NumPy loop.
        progress : bool, default False
            Progress on stderr (the vehicle framework's runner: a bar on a terminal,
            plain lines with the ETA in logs), and a one-line note before the compiled
            step is built for a new ``dt_s`` (compiled once per ``dt_s`` and cached on
            disk; the first time takes minutes on a loaded machine).

        Returns
        -------
        CrossSectionRun
            Dataset variables over ``time``: ``levitation_gap``, ``levitation_force``,
            ``levitation_current`` (``levitation_circuit``), ``guidance_gap``,
            ``guidance_force``, ``guidance_current`` (``guidance_circuit``),
            ``voltage`` (``circuit``), ``car_body_lateral_acceleration``,
            ``car_body_vertical_acceleration``, ``car_body_roll_acceleration``,
            displacements ``car_body_y``, ... ``chassis_phi``, ``field_a_y``, ``field_a_z``,
            ``crosswind_force``; SI units in the attributes.  Dataset attributes: the
            vehicle, speed, step, gaps, magnets and bias current, and the scenario
            (``failures``, ``touchdown``, ``curve``, ``crosswind``,
            ``vertical_irregularity``, ``lateral_irregularity``; "" when none).

        Raises
        ------
        InputError
            Bad options (named), unknown failure circuits, non-finite irregularities.
        OutOfRangeError
            A circuit leaving its maps (from the bank).
        VehicleRunInterrupted
            Ctrl-C during the time loop, carrying the run up to the last whole step (or
            block of the compiled loop); a plain ``KeyboardInterrupt`` before the second.

        Warns
        -----
        MaglevkitWarning
            A curve that starts beyond the distance covered, a crosswind that starts after
            the run (the run never reaches them); a step ``dt_s`` too coarse for the flux
            loop (above ``0.06 / flux_bandwidth_Hz``, 2 ms at 30 Hz).
        PlausibilityWarning
            A speed above 160 m/s (most likely km/h typed into ``speed_m_per_s``).
        """
        v = real_number(speed_m_per_s, "speed_m_per_s", "m/s", nonnegative=True)
        check_run_speed(v, "CrossSectionModel.run")
        dur = real_number(duration_s, "duration_s", "s", positive=True)
        dt = real_number(dt_s, "dt_s", "s", positive=True)
        # the controllers sample every step and hold their voltage over it: that hold lags
        # the flux loop by pi f dt at its bandwidth f; 2 ms at 30 Hz is 11 deg of its phase
        # margin, beyond it the loop degrades fast (dt = 50 ms touched down at 0.3 s)
        f_flux = self.flux_bandwidth_Hz
        if dt > 0.06 / f_flux * (1 + 1e-9):
            warnings.warn(f"dt_s = {dt:g} s is coarse for the {f_flux:g} Hz flux loop: the "
                          f"controllers hold their voltage over a step, a lag of pi f dt = "
                          f"{math.degrees(math.pi * f_flux * dt):.0f} deg at {f_flux:g} Hz "
                          f"(11 deg at {0.06 / f_flux * 1e3:.3g} ms); the gaps may oscillate "
                          f"or touch down: use dt_s <= {0.06 / f_flux:.3g} s",
                          MaglevkitWarning, stacklevel=2)
        n = int(round(dur / dt))
        if n < 1:
            raise InputError(f"duration_s = {duration_s!r} s is shorter than one step "
                             f"dt_s = {dt_s!r} s")
        if curve is not None and not isinstance(curve, TransitionCurve):
            raise InputError(f"curve must be a TransitionCurve, got {type(curve).__name__}")
        if crosswind is not None and not isinstance(crosswind, Crosswind):
            raise InputError(f"crosswind must be a Crosswind, got {type(crosswind).__name__}")
        # a scenario that the run never reaches is almost always a slip (km for m, ms for s)
        if curve is not None and float(curve.ramp(v * dur)) == 0.0:
            warnings.warn(f"the curve starts at {curve.start_m:g} m, but the run covers "
                          f"{v * dur:g} m ({v:g} m/s for {dur:g} s): it never enters it",
                          MaglevkitWarning, stacklevel=2)
        if crosswind is not None and crosswind.start_s >= dur:
            warnings.warn(f"the crosswind starts at {crosswind.start_s:g} s, after the run's "
                          f"{dur:g} s: it never blows", MaglevkitWarning, stacklevel=2)
        bank = self.bank
        names = bank.circuit_names
        fail_t = failure_times(failures, names, end_s=n * dt, stacklevel=3)
        s = self.mechanics.system
        t = np.arange(n + 1) * dt
        xs, xmid = v * t, v * (t + 0.5 * dt)
        field_mid = (curve.field(v, xmid) if curve is not None
                     else np.broadcast_to(self.trim_field, (n + 1, 2)))
        # irregularities at every step start: (elevation, slope) along the path
        rz = np.zeros(n + 1)
        rz_x = np.zeros(n + 1)
        ry = np.zeros(n + 1)
        ry_x = np.zeros(n + 1)
        for what, prof, val, slope in (("vertical", vertical, rz, rz_x),
                                       ("lateral", lateral, ry, ry_x)):
            if prof is None:
                continue
            if not (callable(prof) and callable(getattr(prof, "slope", None))):
                raise InputError(f"{what} = {prof!r}: expected an irregularity Profile "
                                 "(vehicle.irregularities; from a text spec: "
                                 f"{'parse_irregularity' if what == 'vertical' else 'parse_lateral'}"
                                 ") or None")
            val[:] = prof(xs)
            slope[:] = prof.slope(xs)
            if not (np.isfinite(val).all() and np.isfinite(slope).all()):
                raise InputError(f"the {what} irregularity gives non-finite values")
        # crosswind: generalised force of a lateral force at the centre of pressure
        q_ext = np.zeros((n + 1, s.n_dof))
        wind = np.zeros(n + 1)
        if crosswind is not None:
            d = self.data
            z_cp = d.car_body_centre_z_m - crosswind.pressure_height_m
            col = s.point_jacobian("car_body", (0.0, z_cp))[0]
            wind = crosswind.force_N(t + 0.5 * dt)
            q_ext = wind[:, None] * col[None, :]
        if loop not in ("auto", "compiled", "python"):
            raise InputError(f"loop = {loop!r}; allowed: 'auto', 'compiled', 'python'")
        if loop == "compiled" and self.magnet_kind != "reduced":
            raise InputError("loop = 'compiled' needs reduced magnets (magnets='reduced')")
        use_compiled = loop == "compiled" or (loop == "auto" and self.magnet_kind == "reduced")
        sign_y = np.array([0.0, 0.0, 1.0, -1.0])        # rail shift r_y opens left, closes right
        sign_z = np.array([-1.0, -1.0, 0.0, 0.0])       # stator lower closes levitation gaps
        # per magnet: r enters the gap as -r (as the heave-pitch step's irregularity)
        r_mag = -(np.outer(rz, sign_z) + np.outer(ry, sign_y))
        rx_mag = -(np.outer(rz_x, sign_z) + np.outer(ry_x, sign_y))
        if use_compiled:
            if progress:
                self._note_compiling(dt)
            out = self._compiled_loop(dt, v, t, r_mag, rx_mag, field_mid, q_ext, fail_t, n,
                                      progress)
        else:
            out = self._python_loop(dt, v, t, r_mag, rx_mag, field_mid, q_ext, fail_t, n,
                                    progress)
        rec_gap, rec_force, rec_cur, rec_u, rec_x, rec_acc, touchdown, last, outcome, rec_ie = out
        res = self._result(v, dt, t, rec_gap, rec_force, rec_cur, rec_u, rec_x, rec_acc,
                           touchdown, last, outcome.wall_s, field_mid, wind, rec_ie)
        # the scenario in the file (as the heave-pitch run's attributes): a run can be read
        # back and repeated from its netCDF alone
        res.dataset.attrs.update({
            "failures": ", ".join(f"{f.circuit}@{f.time_s:g}" for f in failures),
            "touchdown": "" if touchdown is None else
                         f"{touchdown[3]}: {touchdown[0]}@{touchdown[1]:.6g} s "
                         f"({touchdown[2]:.6g} m)",
            "curve": "" if curve is None else repr(curve),
            "crosswind": "" if crosswind is None else repr(crosswind),
            "vertical_irregularity": "" if vertical is None else repr(vertical),
            "lateral_irregularity": "" if lateral is None else repr(lateral),
            "interrupted": "" if not outcome.interrupted else
                           f"Ctrl-C: the run stopped at t = {float(t[last]):.6g} s "
                           f"of {float(t[-1]):.6g} s"})
        if outcome.interrupted:
            raise VehicleRunInterrupted(res)
        return res

    def _python_loop(self, dt: float, v: float, t: np.ndarray, r_mag: np.ndarray,
                     rx_mag: np.ndarray, field_mid: np.ndarray, q_ext: np.ndarray,
                     fail_t: np.ndarray, n: int, progress: bool = False) -> tuple[Any, ...]:
        from ..control import Measurement
        from .stepkernel import terminal_current

        s = self.mechanics.system
        bank = self.bank
        nq = s.n_dof
        x = np.concatenate([self.trim_q, np.zeros(nq)])
        # gaps and the mechanics' step: the step's parts (as the compiled step's)
        parts = self._step_parts(dt)
        f_in = PartEvaluator(parts["guideway_in"])
        f_mech = PartEvaluator(parts["mechanics_loaded"])
        no_guideway = np.zeros(0)
        state = bank.initial_state(gaps_m=self.s0, currents_A=np.repeat(self.trim_current_A, 2))
        stepper = bank.stepper(state, dt)
        ctl = self.controllers()
        # chopper bound per circuit: -R_ec I_L (none for detailed members, NaN R_ec)
        r_ec = np.where(np.isnan(bank.eddy_resistance_ohm), 0.0, bank.eddy_resistance_ohm)
        chop = ~np.isnan(bank.eddy_resistance_ohm)
        nc = bank.n_circuits
        rec_gap = np.empty((n + 1, 4))
        rec_force = np.empty((n + 1, nc))
        rec_cur = np.empty((n + 1, nc))
        rec_u = np.zeros((n + 1, nc))
        rec_x = np.empty((n + 1, 2 * nq))
        rec_acc = np.empty((n + 1, nq))
        # the ladder's shielding eddy currents I_e at every step start (motion_eddy),
        # (n_t, n_c) or, three-state, (n_t, n_c, 2) as the bank's state
        ne = bank.n_eddy_states
        rec_ie = (np.zeros((n + 1, nc) + ((ne,) if ne > 1 else ())) if ne else None)
        gap_circ = np.repeat(np.arange(4), 2)
        x_circ = np.zeros(nc)
        force = stepper.member_force_N.copy()
        force_c = stepper.circuit_force_N.copy()

        def step(k: int) -> tuple[int, Any] | None:
            """Record the state at step ``k`` and advance it (None), or stop there."""
            nonlocal x, force, force_c
            q, qd = x[:nq], x[nq:]
            gaps_c, rates_c = f_in(x, no_guideway, x_circ, r_mag[k][gap_circ],
                                   rx_mag[k][gap_circ], v)[:2]
            gaps, rates = gaps_c[::2], rates_c[::2]          # one per magnet
            rec_gap[k] = gaps
            rec_x[k] = x
            rec_force[k] = stepper.circuit_force_N
            rec_cur[k] = stepper.currents_A
            if rec_ie is not None:
                rec_ie[k] = stepper.eddy_currents_A
            rec_acc[k] = s.accelerations(q, qd, force, field_mid[k], q_ext[k])
            # a gap at a limit now, or crossing it within the coming step on the linear
            # path the bank moves it along (the maps start at the touchdown gap)
            event = self._limit_event(gaps, rates if k < n else None, float(t[k]), dt)
            if event is not None:
                return k, event
            if k == n:
                return None
            # controllers: levitation on their own gaps, guidance on the differential gap
            diff = 0.5 * (gaps[2] - gaps[3])
            diff_rate = 0.5 * (rates[2] - rates[3])
            meas_g = (gaps[0], gaps[1], self.s0 + diff, self.s0 - diff)
            meas_r = (rates[0], rates[1], diff_rate, -diff_rate)
            cur = stepper.currents_A.copy()     # a view would change with the step
            u = np.empty(nc)
            for j, c in enumerate(ctl):
                meas = Measurement(float(t[k]), float(meas_g[j]), float(meas_r[j]),
                                   cur[2 * j:2 * j + 2], self.s0)
                if k == 0:
                    c.reset(meas, sample_time_s=dt)
                u[2 * j:2 * j + 2] = c.update(meas)
            # 2-quadrant chopper: coil current (U + R_ec I_L)/(R_el + R_ec) >= 0 (the
            # ladder's: R_a and I_L + I_e); then the failed circuits at 0 V (the compiled
            # step's order)
            il = terminal_current(stepper.inductor_currents_A,
                                  None if rec_ie is None else stepper.eddy_currents_A, nc)
            u[chop] = chopper_floor(u[chop], il[chop], r_ec[chop])
            u[fail_t <= t[k]] = 0.0
            rec_u[k] = u
            f_start = force_c
            stepper.advance(voltages_V=u, gaps_m=gaps_c, gap_rates_m_per_s=rates_c)
            force = stepper.member_force_N.copy()
            force_c = stepper.circuit_force_N.copy()
            (x,) = f_mech(x, 0.5 * (f_start + force_c),
                          s.G @ field_mid[k] + s.Q_preload + q_ext[k])
            return None

        outcome = run_steps(step, n_steps=n, progress=progress,
                            label="cross-section run (steps)")
        return (rec_gap, rec_force, rec_cur, rec_u, rec_x, rec_acc, outcome.event,
                outcome.last_step, outcome, rec_ie)

    # ------------------------------------------------------------------ compiled step
    def compiled_step(self, dt_s: float = 1e-3, *, block_steps: int = 50,
                      lanes: bool = True) -> dict[str, Any]:
        """The run's step as one CasADi function, chained ``block_steps`` times.

        The same step as the NumPy loop of :meth:`run` (``loop="python"``), in the same
        order: gaps ``s = s_0 + gap_matrix q - r``, rates; the controllers' voltages, the
        chopper and the failures; the bank's step (:meth:`MagnetBank.step_function`); the
        flux estimates and integrators; the mechanics' exact ZOH step with
        ``Q = B S F_bar + Q_pre + Q_t`` (``S`` sums a magnet's circuits, ``Q_t = G a +
        Q_wind`` at mid-step, a per-step input).  Gaps, controllers, their update and the
        mechanics' step are the vehicle step's parts (:func:`~maglevkit.vehicle.
        stepkernel.build_vehicle_parts`, as the heave-pitch step's), not copies: per circuit, the
        guidance integrators fed the differential gap error ``(s_own - s_other)/2``
        through the integral matrix.  Per circuit, with every gap sum of a guidance pair
        ``2 s_0`` (a rigid chassis and one rail profile for both rails), the guidance
        controllers' own gaps equal the NumPy loop's differential gaps.

        Parameters
        ----------
        dt_s : float, default 1e-3
            Step [s], > 0.
        block_steps : int, default 50
            Steps per call (keyword only).
        lanes : bool, default True
            Call the bank's SIMD-lane library (:meth:`MagnetBank.compiled_step_library`)
            where it exists; False: the bank's CasADi step function (keyword only).

        Returns
        -------
        dict
            ``"block"``: ``(S, P, C) -> (S_next, R)`` (``P``, ``R`` one column per step);
            ``"state"``, ``"inputs"``, ``"record"``: slices of ``S``, ``P``, ``R``.
        """
        import casadi as ca

        from .stepkernel import bank_step_outputs, pack_slices, terminal_current

        bank = self.bank
        if self.magnet_kind != "reduced":
            raise InputError("the compiled cross-section step needs reduced magnets")
        s = self.mechanics.system
        nq, nc = s.n_dof, bank.n_circuits
        dt = real_number(dt_s, "dt_s", "s", positive=True)
        lib = bank.compiled_step_library(dt) if lanes else None
        bank_step = lib[0] if lib is not None else bank.step_function(dt)
        parts = self._step_parts(dt)
        f_in, f_ctl, f_upd, f_mech = (parts[k] for k in (
            "guideway_in", "controllers", "controller_update", "mechanics_loaded"))
        # the ladder's I_e last in state and record (motion_eddy; three-state: 2 n_c,
        # every circuit's I_e1, then I_e2); else the layout before
        ne = bank.n_eddy_states
        eddy = [("I_e", nc * ne)] if ne else []
        st = pack_slices([("x", 2 * nq), ("I_L", nc), ("psi_hat", nc), ("integral", nc),
                          ("current", nc), ("force", nc), *eddy])
        pi = pack_slices([("r", nc), ("r_x", nc), ("Q_t", nq), ("t", 1)])
        rc = pack_slices([("gap", nc), ("gap_rate", nc), ("current", nc), ("force", nc),
                          ("I_L", nc), ("x", 2 * nq), ("voltage", nc), ("n_bad", 1),
                          ("flags", nc), ("I_L_min", nc), ("I_L_max", nc), *eddy])
        n_st = max(v.stop for v in st.values())
        S, P, C = (ca.MX.sym("S", n_st), ca.MX.sym("P", pi["t"].stop),
                   ca.MX.sym("C", 1 + nc))
        x, il, psi, itg, cur, frc = (S[st[k]] for k in ("x", "I_L", "psi_hat", "integral",
                                                         "current", "force"))
        ie = S[st["I_e"]] if eddy else None
        v, fail_t = C[0], C[1:]
        # gaps and rates of every circuit (the rigid guideway's part: no deflection)
        gaps, rates = f_in(x, ca.DM.zeros(0), ca.DM.zeros(nc), P[pi["r"]], P[pi["r_x"]],
                           v)[:2]
        # the chopper's current: I_L, or I_L + I_e with the ladder (its floor -R_a (I_L + I_e))
        u = f_ctl.call({"gap": gaps, "gap_rate": rates, "I_L": terminal_current(il, ie, nc),
                        "current": cur, "psi_hat": psi, "integral": itg, "t": P[pi["t"]],
                        "fail_t": fail_t})["U"]
        il_n, cur_n, frc_n, n_bad, flags, il_lo, il_hi, ie_n = bank_step_outputs(
            bank_step, il=il, ie=ie, gaps=gaps, voltages=u, rates=rates, dt=dt)
        upd = f_upd.call({"psi_hat": psi, "integral": itg, "U": u, "current": cur,
                          "current_next": cur_n, "gap": gaps})
        # the mechanics' ZOH step with the load Q_g = Q_pre + Q_t (field and wind, per step)
        x_n = f_mech(x, 0.5 * (frc + frc_n), ca.DM(s.Q_preload) + P[pi["Q_t"]])
        s_next = ca.vertcat(x_n, il_n, upd["psi_hat_next"], upd["integral_next"], cur_n, frc_n,
                            *([] if ie_n is None else [ie_n]))
        # the bank kernel's reason codes and the sub-step extremes of I_L per circuit:
        # a flagged step's message without stepping again (MagnetBank.raise_step_flags)
        rec = ca.vertcat(gaps, rates, cur, frc, il, x, u, n_bad, flags, il_lo, il_hi,
                         *([] if ie is None else [ie]))
        step = ca.Function("maglevkit_cross_section_step", [S, P, C], [s_next, rec])
        nb = int(block_steps)
        sb, pb = ca.MX.sym("S", S.shape[0]), ca.MX.sym("P", P.shape[0], nb)
        sv: Any = sb
        recs = []
        for j in range(nb):
            sv, r_j = step(sv, pb[:, j], C)
            recs.append(r_j)
        block = ca.Function(f"maglevkit_cross_section_step{nb}", [sb, pb, C],
                            [sv, ca.horzcat(*recs)], ["S", "P", "C"], ["S_next", "R"])
        return {"block": block, "state": st, "inputs": pi, "record": rc, "block_steps": nb,
                "lanes": lib}

    def _limit_event(self, gaps: np.ndarray, rates: np.ndarray | None, t_k: float,
                     dt: float) -> tuple[str, float, float, str] | None:
        """The touchdown at ``t_k`` (a gap at a limit) or within the coming step (the
        crossing on the linear path, :func:`~maglevkit.vehicle.simulation.limit_crossing`:
        its time and the gap there, not the end value extrapolated past the limit);
        ``rates`` None: the last record, no step follows."""
        lo_lim, hi_lim = self.touchdown_gap_m, self.landing_gap_m
        lo, hi = gaps.min(), gaps.max()
        if lo <= lo_lim or hi >= hi_lim:
            closed = bool(lo <= lo_lim)
            j = int(np.argmin(gaps)) if closed else int(np.argmax(gaps))
            return (self.member_names[j], t_k, float(gaps[j]), "closed" if closed else "open")
        if rates is None:
            return None
        hit = limit_crossing(gaps, rates, dt_s=dt, start_s=t_k, touchdown_gap_m=lo_lim,
                             landing_gap_m=hi_lim)
        if hit is None:
            return None
        j, when, gap, closed = hit
        return (self.member_names[j], when, gap, "closed" if closed else "open")

    def _note_compiling(self, dt: float) -> None:
        """One line on stderr before the compiled step for ``dt`` is first built here."""
        if dt in self._compiled_cache:
            return
        sys.stderr.write(f"compiling the cross-section step for dt = {dt:g} s (once per dt, "
                         "cached on disk: minutes the first time, seconds after) ...\n")
        sys.stderr.flush()

    def _compiled_block(self, dt: float) -> dict[str, Any]:
        from ..models.compiled import compile_function, compile_linked

        cache: dict[float, dict[str, Any]] = self._compiled_cache
        hit = cache.get(dt)
        if hit is None:
            hit = self.compiled_step(dt)
            f = None
            if hit["lanes"] is not None:
                f = compile_linked(hit["block"], hit["lanes"][1])
            if f is None:
                if hit["lanes"] is not None:      # rebuild on the bank's CasADi step
                    hit = self.compiled_step(dt, lanes=False)
                f, _ = compile_function(hit["block"], mode=self.bank.compiled_mode)
            hit["compiled"] = f
            cache[dt] = hit
        return hit

    def _compiled_loop(self, dt: float, v: float, t: np.ndarray, r_mag: np.ndarray,
                       rx_mag: np.ndarray, field_mid: np.ndarray, q_ext: np.ndarray,
                       fail_t: np.ndarray, n: int, progress: bool = False) -> tuple[Any, ...]:
        from ..errors import SolverError
        from .stepkernel import eddy_block_as_state

        s = self.mechanics.system
        bank = self.bank
        nq = s.n_dof
        hit = self._compiled_block(dt)
        fun, st, pi, rc, nb = (hit["compiled"], hit["state"], hit["inputs"], hit["record"],
                               hit["block_steps"])
        circ = np.repeat(np.arange(4), 2)
        n_rows = -(-(n + 1) // nb) * nb
        p_all = np.zeros((n_rows, pi["t"].stop))
        p_all[:n + 1, pi["r"]] = r_mag[:, circ]
        p_all[:n + 1, pi["r_x"]] = rx_mag[:, circ]
        p_all[:n + 1, pi["Q_t"]] = field_mid @ s.G.T + q_ext
        p_all[:n + 1, pi["t"].start] = t
        p_all[n + 1:, pi["t"].start] = t[-1] + dt * np.arange(1, n_rows - n)
        state0 = bank.initial_state(gaps_m=self.s0, currents_A=np.repeat(self.trim_current_A, 2))
        out0 = bank.outputs(state0)
        consts = np.concatenate([[v], fail_t])
        s_init = np.zeros(max(v_.stop for v_ in st.values()))
        s_init[st["x"]] = np.concatenate([self.trim_q, np.zeros(nq)])
        s_init[st["I_L"]] = state0.inductor_currents_A
        flux = [self._flux(n_.split("_")[0], float(self.trim_current_A[j]))
                for j, n_ in enumerate(self.member_names)]
        s_init[st["psi_hat"]] = np.concatenate(flux)
        s_init[st["current"]] = out0.currents_A
        s_init[st["force"]] = out0.circuit_force_N
        if state0.eddy_currents_A is not None:     # (n_c, 2): column-major
            s_init[st["I_e"]] = np.ravel(state0.eddy_currents_A, order="F")
        g_sl, r_sl, b_sl = rc["gap"], rc["gap_rate"], rc["n_bad"].start
        lo_lim, hi_lim = self.touchdown_gap_m, self.landing_gap_m

        def look(k0: int, rows: np.ndarray) -> bool:
            """A gap at a limit now or at the step's end on its linear path, or a flag."""
            gaps, rates = rows[:, g_sl], rows[:, r_sl]
            ends = gaps + rates * dt
            return bool(((gaps.min(axis=1) <= lo_lim) | (gaps.max(axis=1) >= hi_lim)
                         | (ends.min(axis=1) <= lo_lim) | (ends.max(axis=1) >= hi_lim)
                         | (rows[:, b_sl] != 0)).any())

        def check(k: int, row: np.ndarray, final: bool) -> tuple[int, Any] | None:
            g = row[g_sl][::2]                                     # one gap per magnet
            event = self._limit_event(g, None if final else row[r_sl][::2], float(t[k]), dt)
            if event is not None:
                return k, event
            if not final and row[b_sl] != 0:
                # the step's own reason codes (the bank kernel's StepFlag bits) and sub-step
                # extremes, turned into the bank's message (member, circuit, gap, current
                # and range), as the heave-pitch vehicle's compiled loop: no second step
                bank.raise_step_flags(row[rc["flags"]], gaps_m=row[g_sl],
                                      gap_rates_m_per_s=row[r_sl],
                                      inductor_currents_A=row[rc["I_L"]],
                                      voltages_V=row[rc["voltage"]],
                                      current_min_A=row[rc["I_L_min"]],
                                      current_max_A=row[rc["I_L_max"]],
                                      start_s=float(t[k]), end_s=float(t[k]) + dt)
                raise SolverError(f"cross-section run at t = {t[k]:.4f} s: the compiled "
                                  "step flagged the magnets, but its reason codes name no "
                                  "reason; rerun with loop='python'")
            return None

        outcome, rec = run_blocks(fun, state=s_init, inputs=p_all, constants=consts,
                                  n_steps=n, n_record=max(v_.stop for v_ in rc.values()),
                                  block_steps=nb,
                                  look=look, check=check, progress=progress,
                                  label="cross-section run (steps)")
        last, touchdown = outcome.last_step, outcome.event
        m = last + 1
        rx = rec[:m, rc["x"]]
        frc = rec[:m, rc["force"]]
        member = frc.reshape(m, 4, 2).sum(axis=2)
        acc = s.accelerations(rx[:, :nq], rx[:, nq:], member, field_mid[:m], q_ext[:m])
        u = rec[:m, rc["voltage"]].copy()
        u[-1] = 0.0                  # the last record's step is not taken (as the NumPy loop)
        return (rec[:m, g_sl][:, ::2], frc, rec[:m, rc["current"]], u, rx, acc, touchdown,
                last, outcome, None if "I_e" not in rc else
                eddy_block_as_state(rec[:m, rc["I_e"]], bank.n_circuits))

    def _result(self, v: float, dt: float, t: np.ndarray, rec_gap: np.ndarray,
                rec_force: np.ndarray, rec_cur: np.ndarray, rec_u: np.ndarray,
                rec_x: np.ndarray, rec_acc: np.ndarray, touchdown: Any, last: int,
                wall: float, field_mid: np.ndarray, wind: np.ndarray,
                rec_ie: np.ndarray | None = None) -> CrossSectionRun:
        import xarray as xr

        from .comfort import comfort_indices, lateral_comfort_indices
        from .stepkernel import eddy_modes_label, eddy_record

        s = self.mechanics.system
        names = self.bank.circuit_names
        gap_circ = np.repeat(np.arange(4), 2)
        m = last + 1
        tt = t[:m]
        lev_c = [f"{sd}/{c}" for sd in SIDES for c in self.magnets["levitation"].circuit_names]
        gui_c = [f"{sd}/{c}" for sd in SIDES for c in self.magnets["guidance"].circuit_names]
        cg = rec_gap[:m][:, gap_circ]
        ds = xr.Dataset(coords={"time": ("time", tt, {"units": "s"}),
                                "levitation_circuit": lev_c, "guidance_circuit": gui_c,
                                "circuit": list(names)})

        def put(name: str, dims: tuple[str, ...], val: np.ndarray, units: str,
                desc: str) -> None:
            ds[name] = (dims, val, {"units": units, "description": desc})

        put("levitation_gap", ("time", "levitation_circuit"), cg[:, :4], "m",
            "vertical gap of each levitation circuit to the stator underside")
        put("guidance_gap", ("time", "guidance_circuit"), cg[:, 4:], "m",
            "lateral gap of each guidance circuit to its side rail")
        put("levitation_force", ("time", "levitation_circuit"), rec_force[:m, :4], "N",
            "attraction force of each levitation circuit (upward on the chassis)")
        put("guidance_force", ("time", "guidance_circuit"), rec_force[:m, 4:], "N",
            "attraction force of each guidance circuit (towards its rail)")
        put("levitation_current", ("time", "levitation_circuit"), rec_cur[:m, :4], "A",
            "coil current")
        put("guidance_current", ("time", "guidance_circuit"), rec_cur[:m, 4:], "A",
            "coil current")
        if rec_ie is not None:
            dims, coords, long_name = eddy_record(rec_ie, modes=self.eddy_modes_of)
            ds = ds.assign_coords(coords)
            for j, kind in ((slice(0, 4), "levitation"), (slice(4, None), "guidance")):
                put(f"{kind}_eddy_current", ("time", f"{kind}_circuit", *dims),
                    rec_ie[:m, j], "A", long_name)
        put("voltage", ("time", "circuit"), rec_u[:m], "V", "circuit voltage held over the step")
        for i, dof in enumerate(s.dof_names):
            body, kind = dof.split(".")
            put(f"{body}_{kind}", ("time",), rec_x[:m, i], "rad" if kind == "phi" else "m",
                f"{body} {kind} displacement from the design position (z down, y right)")
        put("car_body_lateral_acceleration", ("time",), rec_acc[:m, 0], "m/s^2",
            "car body centre, in the track plane (y, right)")
        put("car_body_vertical_acceleration", ("time",), rec_acc[:m, 1], "m/s^2",
            "car body centre, normal to the track plane (z, down)")
        put("car_body_roll_acceleration", ("time",), rec_acc[:m, 2], "rad/s^2", "car body")
        put("field_a_y", ("time",), field_mid[:m, 0], "m/s^2",
            "track field along y (centrifugal and gravity in the banked plane), mid-step")
        put("field_a_z", ("time",), field_mid[:m, 1], "m/s^2", "track field along z, mid-step")
        put("crosswind_force", ("time",), wind[:m], "N", "lateral gust force on the car body")
        ds.attrs.update({"vehicle": self.data.name, "speed_m_per_s": v, "dt_s": dt,
                         "nominal_gap_m": self.s0, "touchdown_gap_m": self.touchdown_gap_m,
                         "landing_gap_m": self.landing_gap_m,
                         "magnets": self.magnet_kind + (
                             f", shielded-gap ladder (motion_eddy = {self.motion_eddy!r}"
                             + (", three-state)" if self.eddy_branches == 2 else ")")
                             if self.bank.motion_eddy else
                             f", eddy network ({eddy_modes_label(self.eddy_modes_of)})"
                             if self.eddy_modes else ""),
                         "guidance_bias_current_A": self.bias_A})
        min_gap = {"levitation": float(cg[:, :4].min()), "guidance": float(cg[:, 4:].min())}
        if touchdown is not None and touchdown[3] == "closed":   # a crossing within a step
            kind = touchdown[0].split("_")[0]                    # is below the records
            min_gap[kind] = min(min_gap[kind], touchdown[2])
        comfort: dict[str, dict[str, float]] = {}
        if m >= 64:
            lat = rec_acc[:m, :1] - rec_acc[:m, :1].mean()
            ver = rec_acc[:m, 1:2] - rec_acc[:m, 1:2].mean()
            wd, wz_y = lateral_comfort_indices(lat, 1.0 / dt)
            wk, wz_z = comfort_indices(ver, 1.0 / dt)
            comfort = {"lateral": {"weighted_rms_m_per_s2": float(wd[0]),
                                   "sperling_wz": float(wz_y[0])},
                       "vertical": {"weighted_rms_m_per_s2": float(wk[0]),
                                    "sperling_wz": float(wz_z[0])}}
        return CrossSectionRun(ds, min_gap, touchdown, comfort, wall,
                               float(tt[-1]) / wall if wall > 0 else math.inf)
