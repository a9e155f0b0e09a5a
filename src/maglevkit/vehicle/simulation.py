"""Vehicle runs: the train's mechanics, its magnets (one bank), gap controllers and the guideway.

Per time step ``t_k -> t_k + dt`` (fixed step, sample-and-hold controllers)::

    x_p      = x_nose(t_k) - xi_p                       force points on the guideway
    s_p      = s_0 + u_p - w(x_p) - r(x_p)              gap (u_p = B_p^T q: frame point)
    s_p'     = u_p' - (w_t + v w_x)(x_p) - v r_x(x_p)   gap rate (moving-load term v w_x)
    U        = controllers(s, s', u', I, psi_hat)       one vectorised flux cascade per circuit
                                                        (damping from s' and u', velocity_blend)
    I, F     = bank.step(U, s, s')                      all circuits, one call
    q, q'    <- exact ZOH step of M q'' + C q' + K q = Q_g - B F_bar
    guideway <- exact ZOH step with F_bar at the mid-step positions
    F_bar    = (F(t_k) + F(t_k+1)) / 2 x sides          (both sides' magnets per lumped line)

``r`` is the irregularity plus the girders' precamber (``Guideway.built_in_profile``),
evaluated once along the points' paths.  The bank's freewheeling diodes keep the coil
currents >= 0 within a step (``freewheel``).
Coarse distribution (default): one gap and one force per circuit at the circuit's centre,
reduced models (maps).  Fine distribution (``magnets="detailed"``): the detailed flux-based
models with one gap and one force per pole.  Failures switch a circuit's voltage to 0 from
a given time on.  A run stops at the first touchdown, a gap at or below the touchdown gap
(magnet closing onto the stator) or at or above the landing gap (frame down on its skids):
there is no contact model.  Equations: ``docs/vehicle.md``.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import (
    InputError,
    MaglevkitError,
    MaglevkitWarning,
    OutOfRangeError,
    ParameterFileError,
    SolverError,
)
from ..plant import STANDARD_GRAVITY
from ..validation import Plausible, check_plausible, external_stacklevel
from .framework import PartEvaluator, run_blocks, run_steps
from .guideway import Guideway
from .mechanics import VehicleMechanics
from .train import TrainData

__all__ = ["Failure", "VehicleRun", "VehicleModel", "VehicleRunInterrupted", "run_vehicle",
           "parse_failure", "parse_irregularity", "RUN_PLAUSIBLE", "check_run_speed",
           "limit_crossing", "touchdown_report_line", "interrupted_report_lines",
           "failure_times",
           "write_run_netcdf"]

#: Plausible magnitudes of the run options (:func:`~maglevkit.validation.check_plausible`:
#: outside, most likely a unit slip; the value is used as given, with a
#: :class:`~maglevkit.errors.PlausibilityWarning`).  Speed: the Transrapid's design speed
#: is 500 km/h (139 m/s); above 160 m/s (576 km/h) a speed in km/h typed into the m/s
#: option is far more likely than a real run.  Irregularity amplitudes (sag, joint steps,
#: random RMS) above 10 mm exceed the nominal gap; below 1 um they are a slip too.
RUN_PLAUSIBLE: dict[str, Plausible] = {
    "run.speed_m_per_s": Plausible(0.01, 160.0, "m/s"),
    "irregularity.sag": Plausible(1e-6, 0.01, "m"),
    "irregularity.joints": Plausible(1e-6, 0.01, "m"),
    "irregularity.random": Plausible(1e-6, 0.01, "m"),
}


def check_run_speed(speed_m_per_s: float, where: str) -> None:
    """Warn about an implausible vehicle speed (:data:`RUN_PLAUSIBLE`, e.g. km/h as m/s).

    Parameters
    ----------
    speed_m_per_s : float
        The run's speed [m/s].
    where : str
        The caller, for the message (e.g. ``"VehicleModel.run"``).

    Warns
    -----
    PlausibilityWarning
        Above 160 m/s (576 km/h) or below 0.01 m/s (zero is plausible).
    """
    check_plausible({"run": {"speed_m_per_s": speed_m_per_s}},
                    {"run.speed_m_per_s": RUN_PLAUSIBLE["run.speed_m_per_s"]}, where,
                    stacklevel=4)

#: cost weights of the vehicle circuits' NMPC (MPCWeights fields; docs/decisions.md, "Any
#: controller in the vehicle loop"): the gap rate is the guideway's more than the magnet's
#: and is left almost free, gap 1 mm against 200 V
_VEHICLE_MPC_WEIGHTS = {"gap_m": 1e-3, "gap_rate_m_per_s": 1.0, "voltage_V": 200.0}
#: disturbance model of the vehicle circuits' NMPC (MagnetHeaveModel.disturbances): no
#: force disturbance, whose estimates drift apart on a frame (docs/vehicle.md); the load
#: goes to the reference integral
_VEHICLE_MPC_DISTURBANCES = ("voltage",)
#: where the vehicle circuits' NMPC linearises its prediction (RealTimeMPC's
#: ``linearization``): interval 0 at the current estimate, the rest at the target; the
#: same must-show results as the full RTI to < 1 % at half its update time
#: (docs/decisions.md, "The NMPC flying the train at speed")
_VEHICLE_MPC_LINEARIZATION = "target"


def limit_crossing(gaps_m: Any, rates_m_per_s: Any, *, dt_s: float, start_s: float,
                   touchdown_gap_m: float, landing_gap_m: float
                   ) -> tuple[int, float, float, bool] | None:
    """The first gap to cross a limit within one step, on the linear path over the step.

    The bank moves every gap linearly over a step, ``s(t) = s + s' (t - t_0)``; a gap whose
    end value ``s + s' dt`` is at or below the touchdown gap (at or above the landing gap)
    crosses it at ``t_0 + (limit - s) / s'``.  The crossing is reported at that time with
    the gap there (the limit itself): not the end value extrapolated past the limit, which
    lay below every recorded gap (the run's report then showed a touchdown gap below its
    minimum gap).  The one law of both vehicle runs' within-step touchdowns.

    Parameters
    ----------
    gaps_m : array_like
        Gaps at the start of the step [m].
    rates_m_per_s : array_like
        Their rates over the step [m/s].
    dt_s : float
        Step length [s].
    start_s : float
        Time at the start of the step [s].
    touchdown_gap_m, landing_gap_m : float
        The limits [m].

    Returns
    -------
    (int, float, float, bool) or None
        Index of the gap crossing first, the crossing time [s], the gap there [m] and
        whether it closed (True: touchdown gap; False: landing gap); None if no gap ends
        the step beyond a limit.
    """
    g = np.asarray(gaps_m, dtype=float)
    r = np.asarray(rates_m_per_s, dtype=float)
    end = g + r * dt_s
    closed, opened = end <= touchdown_gap_m, end >= landing_gap_m
    if not (closed.any() or opened.any()):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        frac_c = np.where(closed, (touchdown_gap_m - g) / np.where(r != 0, r, np.inf), np.inf)
        frac_o = np.where(opened, (landing_gap_m - g) / np.where(r != 0, r, np.inf), np.inf)
    frac_c = np.clip(np.nan_to_num(frac_c, nan=0.0, posinf=np.inf), 0.0, np.inf)
    frac_o = np.clip(np.nan_to_num(frac_o, nan=0.0, posinf=np.inf), 0.0, np.inf)
    frac_c = np.where(closed, np.minimum(frac_c, dt_s), np.inf)
    frac_o = np.where(opened, np.minimum(frac_o, dt_s), np.inf)
    jc, jo = int(np.argmin(frac_c)), int(np.argmin(frac_o))
    is_closed = bool(frac_c[jc] <= frac_o[jo])
    j = jc if is_closed else jo
    tau = float(frac_c[j] if is_closed else frac_o[j])
    # the gap there: the limit itself (exactly, not g + r tau rounded past it), or the
    # gap measured at the start where it is already beyond the limit
    gap = float(g[j]) if tau == 0.0 else (touchdown_gap_m if is_closed else landing_gap_m)
    return j, start_s + tau, gap, is_closed


@dataclass(frozen=True)
class Failure:
    """Circuit ``circuit`` (a bank circuit name, e.g. ``"s2m4/front"``) switched off
    (voltage 0) from ``time_s`` [s] on.

    Parameters
    ----------
    circuit : str
        Name of the circuit, ``"<magnet>/<circuit>"`` as in the vehicle bank's
        ``circuit_names``; :meth:`VehicleModel.run` refuses unknown names
        (:class:`InputError`).
    time_s : float
        Run time [s] from which the circuit's voltage is 0, a finite number >= 0 (0: from
        the first step); otherwise InputError (a NaN time would never fail the circuit).
        Of several failures of one circuit the earliest counts.
    """

    circuit: str
    time_s: float

    def __post_init__(self) -> None:
        from ..validation import real_number

        if not isinstance(self.circuit, str) or not self.circuit:
            raise InputError(f"failure circuit = {self.circuit!r}: expected a circuit name "
                             "such as 's2m4/front'")
        object.__setattr__(self, "time_s", real_number(self.time_s, f"failure {self.circuit!r} "
                                                       "time_s", "s", nonnegative=True))


def parse_failure(text: str) -> Failure:
    """``"CIRCUIT@T"`` -> :class:`Failure` (``T`` in seconds)."""
    name, sep, t = str(text).rpartition("@")
    try:
        if not sep or not name:
            raise ValueError
        ts = float(t)
        if not math.isfinite(ts) or ts < 0:
            raise ValueError
    except ValueError:
        raise InputError(f"failure {text!r}: expected CIRCUIT@T, e.g. s2m4/front@0.5 (T >= 0 s)"
                         ) from None
    return Failure(name, ts)


def write_run_netcdf(dataset: Any, path: str | Path) -> Path:
    """Write a run's Dataset to netCDF atomically (an interrupted write leaves no damaged
    file); the folder must exist: nothing is created silently.

    Parameters
    ----------
    dataset : xarray.Dataset
        The run's time series.
    path : str or path-like
        The netCDF file to write (no unit); an existing file is replaced.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    InputError
        The parent directory of ``path`` does not exist.
    """
    from .._files import write_netcdf_atomically

    p = Path(path)
    if not p.parent.is_dir():
        raise InputError(f"cannot write {str(p)!r}: the directory {str(p.parent)!r} does "
                         "not exist")
    return write_netcdf_atomically(dataset, p)


def touchdown_report_line(dataset: Any, touchdown: tuple[str, float, float, str] | None, *,
                          what: dict[str, str] | None = None) -> str:
    """The touchdown line of a run's plain-text report: the gap limits kept, or where and
    when the first limit was crossed.

    Parameters
    ----------
    dataset : xarray.Dataset
        The run's Dataset, with the attributes ``touchdown_gap_m`` and ``landing_gap_m``
        [m].
    touchdown : tuple or None
        ``(circuit, time_s, gap_m, kind)`` of the first crossing (time [s], gap [m],
        ``kind`` "closed" at the touchdown gap, "landed" or "open" at the landing gap), or
        None.
    what : dict, optional
        Words for each ``kind`` (keyword only; default: the kind itself).

    Returns
    -------
    str
        One line, indented by two spaces.
    """
    if touchdown is None:
        return (f"  no touchdown (gaps stayed within "
                f"{float(dataset.attrs['touchdown_gap_m']) * 1e3:g} ... "
                f"{float(dataset.attrs['landing_gap_m']) * 1e3:g} mm)")
    c, t, g, kind = touchdown
    return (f"  TOUCHDOWN ({(what or {}).get(kind, kind)}): circuit {c} at t = {t:.4f} s (gap "
            f"{g * 1e3:.3f} mm); the run stopped there")


def interrupted_report_lines(dataset: Any) -> list[str]:
    """The line of a run's plain-text report that says the run was interrupted (Ctrl-C),
    where it stopped; none for a whole run (both vehicles' reports).

    Parameters
    ----------
    dataset : xarray.Dataset
        The run's Dataset; its ``interrupted`` attribute (empty or absent for a whole run)
        says where the run stopped.

    Returns
    -------
    list of str
        One line indented by two spaces, or no line.
    """
    why = dataset.attrs.get("interrupted")
    return [f"  INTERRUPTED ({why})"] if why else []


def failure_times(failures: Sequence[Failure], circuit_names: Sequence[str], *,
                  end_s: float, stacklevel: int = 2) -> np.ndarray:
    """Each circuit's failure time of a run (both vehicles): the earliest of its failures.

    Parameters
    ----------
    failures : sequence of Failure
        The run's circuit failures (circuit name, time [s]).
    circuit_names : sequence of str
        The vehicle bank's circuit names, in its order.
    end_s : float
        The run's end [s]: a failure after it is noted with a ``MaglevkitWarning`` (the
        circuit does not fail in the run).
    stacklevel : int, default 2
        The warning's stack level (keyword only).

    Returns
    -------
    numpy.ndarray
        Failure time per circuit [s], ``inf`` for a circuit that does not fail.

    Raises
    ------
    InputError
        A failure that is not a :class:`Failure`, or names no circuit of the bank.
    """
    import warnings

    names = list(circuit_names)
    fail_t = np.full(len(names), np.inf)
    for f in failures:
        if not isinstance(f, Failure):
            raise InputError(f"failures must be Failure objects, got {f!r}")
        if f.circuit not in names:
            listed = (", ".join(names) if len(names) <= 8 else
                      f"e.g. {', '.join(names[:3])} ... {names[-1]} (magnet/circuit)")
            raise InputError(f"failure: no circuit {f.circuit!r}; circuits are {listed}")
        k = names.index(f.circuit)
        fail_t[k] = min(fail_t[k], f.time_s)
        if f.time_s > end_s:   # was ignored without a note
            warnings.warn(f"failure {f.circuit}@{f.time_s:g}: {f.time_s:g} s is after the "
                          f"end of the run ({end_s:g} s, --duration); the circuit does not "
                          "fail in this run", MaglevkitWarning, stacklevel=stacklevel)
    return fail_t


@dataclass(frozen=True)
class VehicleRun:
    """Result of a vehicle run.

    Attributes
    ----------
    dataset : xarray.Dataset
        Time series (see :meth:`VehicleModel.run`), units in the variables' attributes.
    min_gap_m : dict
        Minimum gap per magnet [m] (over its circuits' gaps).
    peak_current_A : dict
        Peak coil current per circuit [A].
    touchdown : tuple or None
        ``(circuit, time_s, gap_m, kind)`` of the first gap at or below the touchdown gap
        (``kind = "closed"``: the magnet closes onto the stator) or at or above the landing
        gap (``"landed"``: the frame is down on its skids), or None.
    comfort : dict
        ``"<section>.<point>" -> {"wk_rms_m_per_s2": ..., "sperling_wz": ...}``.
    wall_time_s : float
        Time spent in the time loop [s].
    real_time_factor : float
        Simulated time / wall time.
    timing_s : dict
        Wall time per part of the loop [s]: magnets, mechanics, guideway, controllers,
        other (the NumPy loop), or ``compiled step`` and ``other`` (the compiled loop,
        whose parts are one call; :mod:`benchmarks.bench_vehicle` times them apart).
    cpu_time_s : float
        Process CPU time spent in the time loop [s] (less sensitive to a busy machine
        than the wall time).
    loop : str
        ``"compiled"`` or ``"python"``: which implementation of the step ran.
    controller_update_time_s : ndarray
        Wall time of every update of the controllers other than the vectorised cascade
        [s] (one entry per circuit and sample; for ``controller="mpc"`` one entry per
        sample, all circuits' NMPC updates in one call; empty for the cascade).
    controller_update_cpu_time_s : ndarray
        The same updates' CPU (thread) time [s], less sensitive to a busy machine.
    """

    dataset: Any
    min_gap_m: dict[str, float]
    peak_current_A: dict[str, float]
    touchdown: tuple[str, float, float, str] | None
    comfort: dict[str, dict[str, float]]
    wall_time_s: float
    real_time_factor: float
    timing_s: dict[str, float] = field(default_factory=dict)
    cpu_time_s: float = math.nan
    loop: str = "python"
    controller_update_time_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    controller_update_cpu_time_s: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def to_netcdf(self, path: str | Path) -> Path:
        """Write the run's Dataset to netCDF and return the path (:func:`write_run_netcdf`:
        atomically; a missing folder is an :class:`~maglevkit.errors.InputError`).

        Parameters
        ----------
        path : str or path-like
            The netCDF file to write; an existing file is replaced.
        """
        return write_run_netcdf(self.dataset, path)

    def report(self) -> str:
        """A short plain-text report."""
        ds = self.dataset
        lines = [f"{ds.attrs['vehicle']}: {float(ds.attrs['speed_m_per_s']) * 3.6:.0f} km/h, "
                 f"{float(ds.time[-1]):.3g} s simulated ({self.real_time_factor:.2f}x real time"
                 + (f", {float(ds.time[-1]) / self.cpu_time_s:.2f}x by CPU time"
                    if self.cpu_time_s > 0 else "") + f"; {self.loop} step)"]
        mg = min(self.min_gap_m.items(), key=lambda kv: kv[1])
        mc = max(self.peak_current_A.items(), key=lambda kv: kv[1])
        lines.append(f"  minimum gap {mg[1] * 1e3:.3f} mm (magnet {mg[0]}); peak current "
                     f"{mc[1]:.2f} A (circuit {mc[0]})")
        lines.append(touchdown_report_line(
            ds, self.touchdown, what={"closed": "gap closed: magnet on the stator",
                                      "landed": "frame down on its skids"}))
        ut = self.controller_update_time_s
        if ut.size:
            p50, p99 = np.percentile(ut, [50, 99]) * 1e6
            c50, c99 = np.percentile(self.controller_update_cpu_time_s, [50, 99]) * 1e6
            lines.append(f"  controller: {ds.attrs.get('controller', '')}; {ut.size} updates, "
                         f"median {p50:.0f} us, p99 {p99:.0f} us, max {ut.max() * 1e6:.0f} us "
                         f"(wall time; CPU time median {c50:.0f} us, p99 {c99:.0f} us)")
        lines.extend(interrupted_report_lines(ds))
        for k, v in self.comfort.items():
            lines.append(f"  comfort {k}: ISO 2631 Wk a_w = {v['wk_rms_m_per_s2']:.4f} m/s^2, "
                         f"Sperling Wz = {v['sperling_wz']:.2f}")
        return "\n".join(lines)


class VehicleModel:
    """The assembled train: mechanics, magnet bank, controllers, guideway.

    Parameters
    ----------
    train : TrainData
    guideway : Guideway or GuidewayData, optional
        A :class:`Guideway` is used as it is.  A parsed guideway file
        (:func:`~maglevkit.vehicle.load_guideway`) gives its spans with a moving system
        boundary of the window the train needs, as the default does with the bundled
        file; ``rigid=True`` makes either rigid.
    rigid : bool
        Use a rigid guideway (ignored when ``guideway`` is given).
    magnets : {"reduced", "detailed"}
        Reduced current-based models with one force per circuit (coarse), or detailed
        flux-based models with one gap and force per pole (fine).
    maps_cache : path, optional
        Directory of the cached characteristic maps (:mod:`maglevkit.vehicle.mapcache`).
    compiled : {"auto", "always", "never"}
        Passed to the bank.
    resistance_scale, eddy_resistance_scale : float
        Factors on every circuit's ohmic resistance ``R_el`` and eddy-current resistances
        (eq. 8's ``R_ec``, the eddy network's ``R_0`` and ``R_k``) of the reduced models
        (e.g. 1.3 for a hot coil); default 1.  They change the
        plant and what the controllers' flux estimate and chopper limit use (both read the
        bank's resistances); the gains stay designed on the nominal magnet.  Reduced models
        only (``magnets="reduced"``).
    freewheel : bool
        The choppers' freewheeling diodes in the plant (default True): a reduced circuit's
        coil current cannot go below zero within a step (:class:`MagnetBank` option
        ``freewheel``); False: eq. 8 with the held voltages, the chopper limit
        ``U >= -R_ec I_L`` of the controllers holding at the sample instants only.
    controller : {"cascade", "mpc"} or mapping of str to Controller, default "cascade"
        The gap controllers.  ``"cascade"``: the flux cascade on every circuit (vectorised,
        in the compiled step).  ``"mpc"``: the offset-free NMPC in its real-time form
        (:class:`~maglevkit.control.realtime.RealTimeMPC`) on every circuit, designed from
        the plant's own maps, the circuit's share of its frame's mass and its trim load
        (:meth:`design_circuit_mpc`; reduced magnets only); it gets its frame's rigid-body
        fit of the gaps and the voltages the chopper applied (docs/vehicle.md).  A mapping from circuit names
        (``"s2m4/front"``) to :class:`~maglevkit.control.interface.Controller` objects:
        those circuits get these controllers (one object per circuit, called with that
        circuit's :class:`~maglevkit.control.interface.Measurement`: its gap [m], gap rate
        [m/s], its current as a 1-element array [A], the nominal gap as reference; each
        returns one voltage [V]), the others keep the cascade.  Controllers other than the
        cascade run in the NumPy loop (``loop="python"``).
    controller_sample_time_s : float, optional
        Sample (hold) time [s] of the controllers given by ``controller`` (not the
        cascade, which runs every step), a whole number of run steps.  Default: 2e-3 s
        for ``"mpc"`` (docs/decisions.md, "Any controller in the vehicle loop"), the run's
        step for a mapping.
    mpc_options : mapping, optional
        Keyword arguments for :meth:`design_circuit_mpc` (``horizon``, ``qp_solver``,
        ``weights``, ``linearization`` (default ``"target"``), ...) with
        ``controller="mpc"``; and ``reference_integral_time_s``
        [s] (default 0.5; None: off): the NMPC's gap reference of circuit ``j`` is
        ``s0 - e_j / T``, ``e_j`` the integral of the frame-projected gap error (the
        cascade's integral), which removes the mean gap error that the random
        irregularity leaves (docs/decisions.md, "Any controller in the vehicle loop").
    motion_eddy : bool, optional
        Fly the reduced magnets with the shielded-gap ladder (:class:`MagnetBank` option
        ``motion_eddy``; docs/reduction.md, "Gap motion"): a second electric state per
        circuit, the shielding eddy current ``I_e``, carried by both loops and recorded
        (the dataset's ``eddy_current``); with ``controller="mpc"`` the NMPCs' prediction
        models carry it too.  None (default): the vehicle file's ``[magnets]
        motion_eddy`` (false unless set).  Needs reduced magnets whose maps carry the
        ladder and ``eddy_resistance_scale = 1``.
    eddy_branches : {1, 2}, optional
        Shielded sections of that ladder (:class:`MagnetBank` option ``eddy_branches``;
        docs/equations.md section 8, "Three states"): 1 the two-state ladder (``I_e``), 2
        the three-state ladder (``I_e1``, ``I_e2`` per circuit, the dataset's
        ``eddy_current`` with an ``eddy_state`` dimension), only with ``motion_eddy``.
        None (default): the vehicle file's ``[magnets] eddy_branches`` (1 unless set).
    eddy_modes : {0, 1, 2, 3} or mapping of str to int, optional
        Fly the reduced magnets with the maps' fitted eddy network of that many branches
        (:class:`MagnetBank` option ``eddy_modes``; docs/bank.md, "Eddy-network members";
        0: eq. 8): ``eddy_modes`` branch currents ``I_k`` per circuit, carried by both
        loops, the NMPCs' prediction models and the record (``eddy_current``, with an
        ``eddy_state`` dimension for more than one branch); the chopper's diodes act on
        ``I_L + sum_k I_k`` (needs a finite fitted ``R_0``).  An int: every magnet; a
        mapping ``{"standard": m, "bow": m}``: per kind (a kind left out takes its
        default).  None (default): the vehicle file's ``[magnets] eddy_modes``, else each
        magnet file's own default (``[reduced] eddy_modes``,
        :attr:`~maglevkit.magnets.Magnet.default_eddy_modes`; the bundled TR09 files: 2),
        0 with ``motion_eddy`` or detailed magnets (:func:`vehicle_eddy_modes`;
        docs/vehicle.md, "Which reduced model the magnets fly").  Not 1-3 with
        ``motion_eddy``; needs reduced magnets whose maps carry the network
        (``build_maps``).
    """

    def __init__(self, train: TrainData, *, guideway: Any = None, rigid: bool = False,
                 magnets: str = "reduced", maps_cache: Any = None, compiled: str = "auto",
                 resistance_scale: float = 1.0, eddy_resistance_scale: float = 1.0,
                 freewheel: bool = True, controller: Any = "cascade",
                 controller_sample_time_s: float | None = None, mpc_options: Any = None,
                 motion_eddy: bool | None = None, eddy_branches: int | None = None,
                 eddy_modes: int | None = None) -> None:
        from ..magnets import load_magnet
        from ..models.flux import FluxModel
        from ..reduced.bank import MagnetBank
        from .data import GuidewayData, load_guideway
        from .mapcache import vehicle_maps

        if not isinstance(train, TrainData):
            raise InputError(f"train must be TrainData (from load_vehicle), got {type(train).__name__}")
        if magnets not in ("reduced", "detailed"):
            raise InputError(f"magnets (--magnets) = {magnets!r}; use 'reduced' or 'detailed'")
        self.train = train
        self.fine = magnets == "detailed"
        motion_eddy = train.motion_eddy if motion_eddy is None else motion_eddy
        if not isinstance(motion_eddy, (bool, np.bool_)):
            raise InputError(f"motion_eddy = {motion_eddy!r} must be True or False (or None: "
                             "the vehicle file's [magnets] motion_eddy)")
        self.motion_eddy = bool(motion_eddy)
        self.eddy_branches = check_eddy_branches(
            train.eddy_branches if eddy_branches is None else eddy_branches,
            motion_eddy=self.motion_eddy,
            where="" if eddy_branches is not None else " (the vehicle file's [magnets])")
        """Shielded sections of the ladder: 1 (two-state) or 2 (three-state)."""
        if self.motion_eddy:
            check_motion_eddy_options(magnets=magnets,
                                      eddy_resistance_scale=eddy_resistance_scale)
        kinds = {"standard": load_magnet(train.standard_magnet), "bow": load_magnet(train.bow_magnet)}
        self.magnets = kinds
        self.eddy_modes_of = vehicle_eddy_modes(
            eddy_modes, kinds, file_value=train.eddy_modes, motion_eddy=self.motion_eddy,
            magnet_kind=magnets, file_where=" (the vehicle file's [magnets])")
        """Branches of the eddy network each magnet kind (``"standard"``, ``"bow"``) flies
        with (0: eq. 8): the option, else the vehicle file's ``[magnets] eddy_modes``, else
        each magnet file's own default (:func:`vehicle_eddy_modes`)."""
        self.eddy_modes = max(self.eddy_modes_of.values())
        """The most eddy-network branches of a magnet kind (0: none flies the network)."""
        for kind, mag in kinds.items():
            if mag.kind != "levitation_magnet":   # was: KeyError 'poles'
                source = train.standard_magnet if kind == "standard" else train.bow_magnet
                raise ParameterFileError(
                    f"{train.source or 'vehicle file'}: [vehicle] {kind}_magnet = {source!r} is "
                    f"a {mag.kind!r} magnet; a vehicle's magnets must be levitation magnets "
                    "(kind = \"levitation_magnet\", e.g. the bundled tr09-standard and tr09-bow)")
            par = mag.parameters["magnet"]
            length = float(par["poles"]) * float(par["pole_pitch"])
            if abs(length - train.magnet_length_m) > 1e-3:
                raise InputError(f"{kind} magnet {mag.name!r} is {length:.4f} m long, but the "
                                 f"vehicle's magnet positions are {train.magnet_length_m:.4f} m "
                                 "(section_length / magnets_per_side)")
        self.maps = {k: vehicle_maps(m, cache_dir=maps_cache) for k, m in kinds.items()}
        scales = (resistance_scale, eddy_resistance_scale)
        for what, sc in zip(("resistance_scale", "eddy_resistance_scale"), scales, strict=True):
            if isinstance(sc, bool) or not isinstance(sc, (int, float)) or \
                    not (math.isfinite(sc) and sc > 0):
                raise InputError(f"{what} = {sc!r} must be a number > 0 (a factor on the "
                                 "nominal resistance)")
        if scales != (1.0, 1.0):
            if self.fine:
                raise InputError("resistance_scale and eddy_resistance_scale apply to the "
                                 "reduced models' maps; use magnets='reduced'")
            self.maps = {k: _scaled_resistances(m, *scales) for k, m in self.maps.items()}
        self.slots = train.magnet_slots()
        members: list[tuple[str, Any]] = []
        for s in self.slots:
            members.append((s.name, FluxModel(kinds[s.kind]) if self.fine else self.maps[s.kind]))
        self.bank = vehicle_bank(MagnetBank, members, motion_eddy=self.motion_eddy,
                                 eddy_branches=self.eddy_branches, eddy_modes=self.eddy_modes_of,
                                 files={"standard": train.standard_magnet,
                                        "bow": train.bow_magnet},
                                 kind_of={s.name: s.kind for s in self.slots},
                                 gap_inputs="pole" if self.fine else "circuit",
                                 compiled=compiled, freewheel=freewheel)
        bank = self.bank
        # pole and circuit positions (train coordinate), frame of every circuit
        pole_xi: list[float] = []
        pole_frame: list[int] = []
        pole_circuit: list[int] = []
        circ_xi: list[float] = []
        circ_frame: list[int] = []
        circ_poles: list[int] = []
        circ_kind: list[str] = []
        for s in self.slots:
            mag = kinds[s.kind]
            pitch = float(mag.parameters["magnet"]["pole_pitch"])
            names = list(mag.gap_names)
            xi = s.centre_m - 0.5 * train.magnet_length_m + (np.arange(len(names)) + 0.5) * pitch
            groups = self.maps[s.kind].pole_groups
            first = len(circ_xi)
            circuit_of: dict[int, int] = {}
            for c in mag.circuit_names:
                idx = [names.index(p) for p in groups[c]]
                for j in idx:
                    circuit_of[j] = len(circ_xi)
                circ_xi.append(float(xi[idx].mean()))
                circ_frame.append(s.frame)
                circ_poles.append(len(idx))
                circ_kind.append(s.kind)
            for j in range(len(names)):            # bank pole order: the magnet's gap names
                pole_xi.append(float(xi[j]))
                pole_frame.append(s.frame)
                pole_circuit.append(circuit_of[j])
            assert len(circ_xi) - first == len(mag.circuit_names)
        self.circuit_xi_m = np.array(circ_xi)
        self.circuit_frame = np.array(circ_frame)
        self.circuit_poles = np.array(circ_poles)
        self.circuit_kind = tuple(circ_kind)
        self.pole_xi_m = np.array(pole_xi)
        self.pole_circuit = np.array(pole_circuit)
        nc = bank.n_circuits
        if len(circ_xi) != nc:  # pragma: no cover - layout and bank disagree
            raise InputError("internal: circuit layout does not match the bank")
        if self.fine:
            # bank pole order = member order, each member's gap_names order
            self.point_xi_m = self.pole_xi_m
            frames = np.array(pole_frame)
            weights = np.ones(self.pole_xi_m.size)
        else:
            self.point_xi_m = self.circuit_xi_m
            frames = self.circuit_frame
            weights = self.circuit_poles.astype(float)
        self.mechanics = VehicleMechanics(train, self.point_xi_m.tolist(), frames.tolist())
        self._weights = weights
        # guideway
        if guideway is None or isinstance(guideway, GuidewayData):
            data = load_guideway() if guideway is None else guideway
            gw0 = data.guideway(n_spans=1, rigid=rigid)
            guideway = data.guideway(n_spans=gw0.spans_needed(train.length_m), rigid=rigid)
        if not isinstance(guideway, Guideway):
            raise InputError(f"guideway must be a Guideway or a guideway file's data "
                             f"(load_guideway), got {type(guideway).__name__}")
        self.guideway = guideway
        # trim: forces per point, per circuit; trim currents
        self.trim_q, point_force = self.mechanics.static_trim(weights)
        per_side = point_force / train.sides
        circ_force: np.ndarray = (np.bincount(self.pole_circuit, weights=per_side, minlength=nc)
                                  if self.fine else per_side)
        self.trim_force_N = circ_force          # per circuit of one side
        self.trim_current_A = self._trim_currents(circ_force)
        self._design_controllers()
        if bank.n_eddy_states:
            # the ladder's chopper floor U >= -R_a (I_L + I_e): the bank's R_a (the eddy
            # network's: U >= -R_0 (I_L + sum_k I_k), the bank's R_0)
            self.eddy_resistance_ohm = np.array(bank.eddy_resistance_ohm, dtype=float)
        self._step_functions: dict[Any, Any] = {}
        self._measure_functions: dict[Any, Any] = {}
        self._part_functions: dict[float, Any] = {}
        self._set_controllers(controller, controller_sample_time_s, mpc_options)

    # ------------------------------------------------------------------ set-up helpers
    def _circuit_map(self, j: int, var: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        member, circuit = self.bank.circuit_names[j].split("/", 1)
        kind = self.slots[self.bank.member_names.index(member)].kind
        maps = self.maps[kind]
        return maps.gaps_m, maps.currents_A, maps.variable(var, circuit)

    def _interp(self, j: int, var: str, gap: float, current: float) -> float:
        from scipy.interpolate import RectBivariateSpline

        g, c, v = self._circuit_map(j, var)
        return float(RectBivariateSpline(g, c, v)(gap, current)[0, 0])

    def _trim_currents(self, force: np.ndarray) -> np.ndarray:
        """Current of every circuit carrying ``force`` [N] at the nominal gap (statics maps)."""
        from scipy.interpolate import RectBivariateSpline
        from scipy.optimize import brentq

        s0 = self.train.nominal_gap_m
        out = np.empty(force.size)
        cache: dict[tuple[str, str], Any] = {}
        for j, f in enumerate(force):
            member, circuit = self.bank.circuit_names[j].split("/", 1)
            kind = self.slots[self.bank.member_names.index(member)].kind
            key = (kind, circuit)
            if key not in cache:
                g, c, v = self._circuit_map(j, "force_N")
                cache[key] = (RectBivariateSpline(g, c, v), c)
            spl, c = cache[key]
            fmax = float(spl(s0, c[-1])[0, 0])
            if not 0 < f < fmax:
                raise InputError(f"circuit {self.bank.circuit_names[j]!r} would have to carry "
                                 f"{f:.5g} N at the nominal gap; its maps reach {fmax:.5g} N")
            out[j] = brentq(lambda i, f=f, spl=spl: float(spl(s0, i)[0, 0]) - f, c[0], c[-1],
                            xtol=1e-10)
        return out

    def _design_controllers(self) -> None:
        from ..control import design_gap_controller

        tr = self.train
        nc = self.bank.n_circuits
        kp, kd, ki, kf = (np.empty(nc) for _ in range(4))
        psi0 = np.empty(nc)
        s0 = tr.nominal_gap_m
        for kind, mag in self.magnets.items():
            sel = np.array([k == kind for k in self.circuit_kind])
            if not sel.any():
                continue
            load = float(self.trim_force_N[sel].sum()) / (sel.sum() / len(mag.circuit_names))
            cur = float(self.trim_current_A[sel].mean())
            ctl = design_gap_controller(mag, mass_kg=load / STANDARD_GRAVITY, gap_m=s0,
                                        current_A=cur, bandwidth_hz=tr.control_bandwidth_Hz,
                                        damping=tr.control_damping,
                                        flux_bandwidth_hz=tr.flux_bandwidth_Hz,
                                        voltage_limit_V=tr.voltage_limit_V)
            kp[sel], kd[sel], ki[sel], kf[sel] = (ctl.kp_per_m, ctl.kd_s_per_m, ctl.ki_per_m_s,
                                                  ctl.kflux_per_s)
        for j in range(nc):
            psi0[j] = self._interp(j, "flux_linkage_Wb", s0, float(self.trim_current_A[j]))
        r_ec = np.empty(nc)
        for j, name in enumerate(self.bank.circuit_names):
            member, circuit = name.split("/", 1)
            kind = self.slots[self.bank.member_names.index(member)].kind
            r_ec[j] = float(self.maps[kind].dataset["eddy_resistance_fit_ohm"].sel(
                circuit=circuit))
        self.eddy_resistance_ohm = r_ec
        # integral action on what a rigid frame can correct: the gap errors of a frame's
        # circuits projected on its heave and pitch (P = A (A^T A)^-1 A^T, rows of A =
        # (1, xi_j - xi_frame)).  On a curved girder the circuits' gaps cannot all be
        # nominal at once; independent integrators would wind up against each other.
        proj = np.zeros((nc, nc))
        centres = self.train.frame_centres_m
        for f in range(self.train.n_frames):
            cols = np.flatnonzero(self.circuit_frame == f)
            a = np.column_stack([np.ones(cols.size), self.circuit_xi_m[cols] - centres[f]])
            proj[np.ix_(cols, cols)] = a @ np.linalg.solve(a.T @ a, a.T)
        self.integral_projection = proj
        self.gains = {"kp_per_m": kp, "kd_s_per_m": kd, "ki_per_m_s": ki, "kflux_per_s": kf}
        self.flux_bias_Wb = psi0

    def _set_controllers(self, controller: Any, sample_time_s: float | None,
                         mpc_options: Any) -> None:
        """``self.controller_kind`` ("cascade", "mpc", "custom") and
        ``self.circuit_controllers`` (circuit index -> Controller, the circuits that do not
        use the vectorised cascade)."""
        from collections.abc import Mapping

        from ..control.interface import Controller
        from ..validation import real_number

        names = self.bank.circuit_names
        self.circuit_controllers: dict[int, Any] = {}
        self.reference_integral_time_s: float | None = None
        if sample_time_s is not None:
            sample_time_s = real_number(sample_time_s, "controller_sample_time_s", "s",
                                        positive=True)
        if isinstance(controller, str):
            if controller not in ("cascade", "mpc"):
                raise InputError(f"controller = {controller!r}; use 'cascade', 'mpc' or a "
                                 "mapping from circuit names to Controller objects")
            if controller == "cascade":
                if mpc_options is not None or sample_time_s is not None:
                    raise InputError("mpc_options and controller_sample_time_s need "
                                     "controller='mpc' or a mapping of controllers")
                self.controller_kind = "cascade"
                self.controller_sample_time_s: float | None = None
                return
            if self.fine:
                raise InputError("controller = 'mpc' needs reduced magnets (magnets='reduced'): "
                                 "the NMPC is designed from the reduced models' maps")
            if mpc_options is not None and not isinstance(mpc_options, Mapping):
                raise InputError(f"mpc_options must be a mapping of keyword arguments, got "
                                 f"{type(mpc_options).__name__}")
            ts = 2e-3 if sample_time_s is None else sample_time_s
            opts = dict(mpc_options or {})
            tau = opts.pop("reference_integral_time_s", 0.5)
            if tau is not None:
                tau = real_number(tau, "mpc_options['reference_integral_time_s']", "s",
                                  positive=True)
            self.reference_integral_time_s = tau
            self.controller_kind = "mpc"
            self.controller_sample_time_s = ts
            designs: dict[Any, Any] = {}
            for j in range(len(names)):
                self.circuit_controllers[j] = self._circuit_mpc(j, ts, opts, designs)
            return
        if mpc_options is not None:
            raise InputError("mpc_options needs controller='mpc'")
        if not isinstance(controller, Mapping) or not controller:
            raise InputError(f"controller = {controller!r}; use 'cascade', 'mpc' or a "
                             "non-empty mapping from circuit names to Controller objects")
        for key, ctl in controller.items():
            if key not in names:
                raise InputError(f"controller: no circuit {key!r}; circuits are e.g. "
                                 f"{', '.join(names[:3])} ... {names[-1]} (magnet/circuit)")
            if not isinstance(ctl, Controller):
                raise InputError(f"controller[{key!r}] is a {type(ctl).__name__}, not a "
                                 "Controller (reset, update, diagnostics, gap_ref_m, "
                                 "voltage_limit_V: maglevkit.control.Controller)")
            self.circuit_controllers[names.index(key)] = ctl
        self.controller_kind = "custom"
        self.controller_sample_time_s = sample_time_s

    def design_circuit_mpc(self, circuit: int, *, sample_time_s: float, horizon: int = 10,
                           **options: Any) -> Any:
        """The offset-free NMPC (real-time form) for one circuit of the vehicle, designed
        from the plant's maps of that circuit, its frame's mass and its trim load.

        The prediction model (:class:`~maglevkit.control.model.MagnetHeaveModel`) is the
        circuit's own reduced model (the bank's maps of its magnet kind, that circuit
        only: eq. 8 has no coupling between circuits) on the circuit's share of its
        levitation frame's mass, loaded with its trim force (as the weight of that mass
        under an equivalent gravity), means over the circuits of the same magnet kind and
        circuit name; with a voltage disturbance (``disturbances`` adds others); its
        reference is the nominal gap and its voltage limit the train's chopper limit
        (docs/vehicle.md, "Any controller in the loop").

        Parameters
        ----------
        circuit : int
            Index of the circuit in the bank (``bank.circuit_names``).
        sample_time_s : float
            Controller sample time [s], > 0.
        horizon : int, default 10
            Shooting intervals of the NMPC.
        **options
            Further keyword arguments of :class:`~maglevkit.control.realtime.RealTimeMPC`
            (``qp_solver``, ``weights``, ``substeps``, ``observer_options``, ...), and
            ``disturbances`` (the prediction model's, default ``("voltage",)``).

        Returns
        -------
        RealTimeMPC
            A new controller (own observer and QP state); circuits of the same kind and
            name share the compiled functions (disk cache).

        Raises
        ------
        InputError
            ``circuit`` not a circuit index, or detailed magnets.
        ParameterError
            Bad NMPC options (from :class:`RealTimeMPC`).
        """
        return self._circuit_mpc(circuit, sample_time_s, {"horizon": horizon, **options}, None)

    def _circuit_mpc(self, circuit: Any, sample_time_s: float, options: dict[str, Any],
                     shared: dict[Any, Any] | None) -> Any:
        """:meth:`design_circuit_mpc`, the prediction models shared through ``shared``."""
        from ..control.model import MagnetHeaveModel
        from ..control.mpc import MPCWeights
        from ..control.realtime import RealTimeMPC

        options = {"horizon": 10, "weights": MPCWeights(**_VEHICLE_MPC_WEIGHTS),
                   "linearization": _VEHICLE_MPC_LINEARIZATION, **options}
        dist = tuple(options.pop("disturbances", _VEHICLE_MPC_DISTURBANCES))
        nc = self.bank.n_circuits
        if isinstance(circuit, bool) or not isinstance(circuit, (int, np.integer)) or \
                not 0 <= int(circuit) < nc:
            raise InputError(f"circuit = {circuit!r} must be a circuit index 0..{nc - 1}")
        if self.fine:
            raise InputError("design_circuit_mpc needs reduced magnets (magnets='reduced')")
        j = int(circuit)
        member, cname = self.bank.circuit_names[j].split("/", 1)
        kind = self.circuit_kind[j]
        key = (kind, cname, dist)
        shared = {} if shared is None else shared
        model = shared.get(key)
        if model is None:
            from ..reduction.maps import CharacteristicMaps

            maps = self.maps[kind]
            one = CharacteristicMaps(maps.dataset.sel(circuit=[cname]))
            same = [i for i, n in enumerate(self.bank.circuit_names)
                    if self.circuit_kind[i] == kind and n.split("/", 1)[1] == cname]
            # dynamic mass: the circuit's share of its levitation frame (frame and magnets,
            # both sides); the car body rides on the ~1 Hz secondary springs and does not
            # follow the gap loop.  The load: the circuit's trim force, as the weight of
            # that mass under an equivalent gravity (docs/vehicle.md)
            per_frame = np.bincount(self.circuit_frame, minlength=self.train.n_frames)
            fr = self.circuit_frame[same]
            dyn = self.mechanics.body_mass_kg[self.train.n_sections + fr] / (
                self.train.sides * per_frame[fr])
            mass = float(dyn.mean())
            plant: Any = one
            modes = self.eddy_modes_of[kind]
            if modes or self.bank.motion_eddy:   # the prediction model with the plant's
                # ladder or its kind's eddy network (I_e in its state after [I_L, s, s'],
                # estimated by its EKF from the current)
                from ..reduced.bank import MagnetBank

                plant = (MagnetBank({"magnet": one}, compiled="never", eddy_modes=modes)
                         if modes else
                         MagnetBank({"magnet": one}, compiled="never", motion_eddy=True,
                                    eddy_branches=self.eddy_branches))
            model = MagnetHeaveModel(plant, mass_kg=mass,
                                     gravity=float(self.trim_force_N[same].mean()) / mass,
                                     disturbances=dist, compiled=self.bank.compiled_mode)
            shared[key] = model
        return RealTimeMPC(model, gap_ref_m=self.train.nominal_gap_m,
                           sample_time_s=sample_time_s,
                           voltage_limit_V=self.train.voltage_limit_V, **options)

    # ------------------------------------------------------------------ the run
    def run(self, *, speed_m_per_s: float, duration_s: float, dt_s: float = 1e-3,
            irregularity: Any = None, failures: Sequence[Failure] = (), progress: bool = False,
            floor_points: Sequence[float] = (-0.4, 0.0, 0.4), loop: str = "auto",
            payload_step_s: float | None = None, payload_fraction: float = 0.1) -> VehicleRun:
        """Simulate the train at constant speed.

        Parameters
        ----------
        speed_m_per_s : float
            Speed [m/s] (>= 0).
        duration_s, dt_s : float
            Run length and fixed step [s].
        irregularity : Profile, optional
            Guideway irregularity ``r(x)`` (positive downward), see
            :mod:`maglevkit.vehicle.irregularities`.
        failures : sequence of Failure
            Circuits switched off (voltage 0) from a time on; every circuit must be one of
            the bank's (else :class:`InputError`).
        progress : bool
            Progress on stderr: a bar on a terminal, plain lines with the ETA in logs.
        floor_points : sequence of float
            Car-body floor points for comfort, as fractions of the section length from its
            centre (negative: forward).
        loop : {"auto", "compiled", "python"}
            How a time step is computed: ``"compiled"``, one compiled CasADi function per
            step for guideway, gaps, controllers, magnets and mechanics
            (:mod:`maglevkit.vehicle.stepkernel`; reduced magnets only); ``"python"``, the
            NumPy loop (the reference; needed for detailed magnets); ``"auto"`` (default):
            compiled for reduced magnets unless the bank was made with
            ``compiled="never"``.  Both give the same run to rounding.  Controllers
            other than the cascade (``controller`` of :class:`VehicleModel`) and a
            payload step run in the NumPy loop.
        payload_step_s : float, optional
            Time [s] of a payload step: from then on every car body weighs
            ``1 + payload_fraction`` times its own weight (an added load; the bodies'
            inertia stays).  None (default): no step.
        payload_fraction : float, default 0.1
            The payload step as a fraction of each car body's weight [-], finite.

        Returns
        -------
        VehicleRun
            Its dataset has dims ``time``, ``circuit``, ``magnet``, ``section``, ``frame``,
            ``span``, ``floor_point``.

        Raises
        ------
        VehicleRunInterrupted
            Ctrl-C (``KeyboardInterrupt``) during the time loop, carrying the run up to the
            last whole step (a plain ``KeyboardInterrupt`` before the first step).
        OutOfRangeError
            A circuit leaves its characteristic maps other than by a touchdown (a gap that
            crosses the touchdown or landing gap within a step is reported as a touchdown
            at the step's end, like one at a step's start), or the train leaves the
            integrated spans.
        """
        import xarray as xr

        from ..control import damping_input
        from ..models.inputs import reject_bools
        from .stepkernel import eddy_modes_label, eddy_record, terminal_current

        for name, v in (("speed_m_per_s", speed_m_per_s), ("duration_s", duration_s),
                        ("dt_s", dt_s)):
            reject_bools(v, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise InputError(f"{name} = {v!r} must be a finite number")
        if speed_m_per_s < 0 or duration_s <= 0 or dt_s <= 0:
            raise InputError("speed_m_per_s must be >= 0 and duration_s, dt_s > 0")
        check_run_speed(speed_m_per_s, "VehicleModel.run")
        if loop not in ("auto", "compiled", "python"):
            raise InputError(f"loop = {loop!r}; use 'auto', 'compiled' or 'python'")
        if loop == "compiled" and self.fine:
            raise InputError("loop = 'compiled' needs reduced magnets (magnets='reduced'); "
                             "detailed magnets run in the Python loop")
        compiled_loop = loop == "compiled" or (loop == "auto" and not self.fine
                                               and self.bank.compiled_mode != "never")
        if payload_step_s is not None:
            from ..validation import real_number

            payload_step_s = real_number(payload_step_s, "payload_step_s", "s",
                                         nonnegative=True)
            payload_fraction = real_number(payload_fraction, "payload_fraction", "1")
        # the NMPC ("mpc") runs between compiled blocks of its sample's steps (with payload
        # steps); other controllers, and the cascade with a payload step, in the NumPy loop
        sampled = self.controller_kind == "mpc"
        if not sampled and (self.circuit_controllers or payload_step_s is not None):
            if loop == "compiled":
                raise InputError("loop = 'compiled' runs the cascade without payload steps; "
                                 f"controller = {self.controller_kind!r} and payload steps run "
                                 "in the NumPy loop (loop='python' or 'auto')")
            compiled_loop = False
        n_steps = int(round(duration_s / dt_s))
        if n_steps < 2:
            raise InputError(f"duration_s = {duration_s} s is less than two steps of {dt_s} s")
        tr, bank, mech, gw = self.train, self.bank, self.mechanics, self.guideway
        names = bank.circuit_names
        nc = bank.n_circuits
        fail_t = failure_times(failures, names, end_s=n_steps * dt_s, stacklevel=3)
        v = float(speed_m_per_s)
        dt = float(dt_s)
        s0 = tr.nominal_gap_m
        sides = tr.sides
        xi = self.point_xi_m
        npt = xi.size
        span_l = gw.span.length_m
        # nose such that the rear starts 0.3 span behind pier 1 of the guideway
        x_nose0 = gw.origin_m + span_l * 1.3 + tr.length_m
        times = np.arange(n_steps + 1) * dt
        # irregularities at every point and step (vectorised once)
        x_ref = x_nose0 + v * times
        xpath = x_ref[:, None] - xi[None, :]
        built_in = gw.built_in_profile          # the girders' precamber: part of r(x)
        if built_in is not None:
            irregularity = built_in if irregularity is None else irregularity + built_in
        if irregularity is not None:
            r_all, rx_all = irregularity.on_paths(xpath, start_m=x_nose0 - xi, step_m=v * dt)
        else:
            r_all = np.zeros_like(xpath)
            rx_all = np.zeros_like(xpath)
        # guideway helpers (exact ZOH, mode shapes at the points)
        span = gw.span
        nm = gw.n_modes
        gstate = gw.initial_state(first_span=int(gw.span_index(xpath[0].min())))

        # initial state: static guideway deflection under the trim loads, frames fitted
        f_pts = self.mechanics_trim_forces()
        if nm:
            qf = gw.modal_forces(gstate, xpath[0], f_pts)
            qs = span.static_modal_displacement(qf)
            gstate = type(gstate)(0.0, gstate.first_span, qs, np.zeros_like(qs))
            d0 = gw.deflection(gstate, xpath[0]).deflection_m
        else:
            d0 = np.zeros(npt)
        target = d0 + r_all[0]                  # point displacement giving the nominal gap
        q = self.trim_q.copy()
        nsec2 = 2 * tr.n_sections
        frames_of_pts = mech.force_bodies - tr.n_sections
        for fi in range(tr.n_frames):
            cols = np.flatnonzero(frames_of_pts == fi)
            a = mech.B[nsec2 + 2 * fi: nsec2 + 2 * fi + 2][:, cols].T
            q[nsec2 + 2 * fi: nsec2 + 2 * fi + 2] = np.linalg.lstsq(a, target[cols],
                                                                   rcond=None)[0]
        q[:nsec2] = np.linalg.solve(mech.K[:nsec2, :nsec2],
                                    mech.Q_gravity[:nsec2] - mech.K[:nsec2, nsec2:] @ q[nsec2:])
        qd = np.zeros_like(q)
        ndof = mech.n_dof
        x_m = np.concatenate([q, qd])
        bt = mech.B.T.copy()
        # bank initial state
        u_p = bt @ q
        gaps_p = s0 + u_p - d0 - r_all[0]
        if not np.all(gaps_p > 0):   # the irregularity closes the gap before the first step
            k = int(np.argmin(np.where(np.isfinite(gaps_p), gaps_p, -np.inf)))
            raise InputError(
                f"irregularity: the guideway profile closes the gap at t = 0 (gap "
                f"{gaps_p[k]:.4g} m at point {k}, irregularity r = {r_all[0][k]:.4g} m there, "
                f"nominal gap {s0:g} m); irregularity amplitudes are in metres "
                "(--irregularity sag:0.5e-3 is 0.5 mm): give a smaller amplitude")
        if self.fine:
            bstate = bank.initial_state(gaps_m=gaps_p, currents_A=self.trim_current_A)
            circ_avg = np.zeros((nc, npt))
            circ_avg[self.pole_circuit, np.arange(npt)] = 1.0
            circ_avg /= circ_avg.sum(axis=1, keepdims=True)
        else:
            bstate = bank.initial_state(gaps_m=gaps_p, currents_A=self.trim_current_A)
            circ_avg = None
        # the initial coil currents and forces in the steady state U = R_el I_L: the bank's
        # outputs (its first call maps the circuit function, later ones take its inlined
        # graph, 0.65 ms for the 50 TR09 circuits; a compiled output function per model
        # gave the same bits after ~1.1 s of code generation, nmpcnet)
        out0 = bank.outputs(bstate)
        force_c = out0.circuit_force_N.copy()
        current = out0.currents_A.copy()
        if self.fine:
            pf0 = out0.pole_force_N
            assert pf0 is not None
            force_pts = pf0.copy()
        else:
            force_pts = force_c.copy()
        # controllers (vectorised over circuits)
        blend = tr.control_velocity_blend
        psi0 = self.flux_bias_Wb
        res = bank.resistance_ohm
        psi_hat = psi0.copy()
        integ = np.zeros(nc)
        # records
        rec = {k: np.empty((n_steps + 1, nc)) for k in ("gap", "current", "voltage", "force",
                                                        "deflection")}
        rec_q = np.empty((n_steps + 1, ndof))
        rec_qd = np.empty((n_steps + 1, ndof))
        rec_mid = np.zeros((n_steps + 1, gw.n_spans))
        rec_span = np.zeros((n_steps + 1, gw.n_spans), dtype=int)
        rec_fp = np.empty((n_steps + 1, npt))
        # the ladder's shielding eddy currents I_e at every step start (motion_eddy),
        # (n_t, n_c) or, three-state, (n_t, n_c, 2) as the bank's state
        ne = bank.n_eddy_states
        rec_ie = (np.zeros((n_steps + 1, nc) + ((ne,) if ne > 1 else ())) if ne else None)
        timing = dict.fromkeys(("magnets", "mechanics", "guideway", "controllers", "other"), 0.0)
        ctl_times: list[float] = []
        ctl_cpu: list[float] = []
        touchdown: tuple[str, float, float, str] | None = None
        last = n_steps
        interrupted = False
        if compiled_loop:
            last, touchdown, wall, cpu, interrupted = self._compiled_loop(
                dt=dt, v=v, times=times, x_ref=x_ref, xpath=xpath, r_all=r_all, rx_all=rx_all,
                x_m=x_m, gstate=gstate, i_l=bstate.inductor_currents_A,
                i_e=bstate.eddy_currents_A, rec_ie=rec_ie, psi_hat=psi_hat,
                integ=integ, current=current, force=force_c, fail_t=fail_t, rec=rec,
                rec_q=rec_q, rec_qd=rec_qd, rec_fp=rec_fp, rec_mid=rec_mid,
                rec_span=rec_span, timing=timing, progress=progress,
                sampled=(gaps_p, self._initial_gap_rates(v, rx_all[0], xpath[0], gstate),
                         ctl_times, ctl_cpu, None if payload_step_s is None else
                         (int(math.ceil(payload_step_s / dt - 1e-9)),
                          self._payload_gravity(payload_fraction))) if sampled else None)
        else:
            # one discarded step first: compiles (or loads) the bank's kernel outside the timing
            if not self.fine:
                bank.step(bstate, dt, res * current, gaps_p, 0.0)
            # the step's parts (stepkernel.build_vehicle_parts), evaluated on CasADi's
            # virtual machine: the laws of the compiled step, not a copy of them
            parts = self._part_evaluators(dt)
            f_in, f_cas, f_lim, f_upd, f_mech, f_out = (parts[k] for k in (
                "guideway_in", "cascade", "voltage_limits", "controller_update",
                "mechanics_loaded", "guideway_out"))
            clock = time.perf_counter
            # guideway modal state in ring order, [q | q'] per row (as Guideway.step), flat
            n_sp = gw.n_spans if nm else 0
            gx = np.concatenate([gstate.modal_displacement_m, gstate.modal_velocity_m_per_s],
                                axis=1).ravel() if nm else np.zeros(0)
            span_ids = np.arange(gw.n_spans)
            k_out = -1
            if nm:
                first_k, keep, k_out = gw.window_schedule(
                    xpath.min(axis=1), xpath.max(axis=1) + 0.5 * v * dt,
                    first_span=gstate.first_span)
            i_l_fine = np.zeros(nc)          # detailed members: the chopper reads I, not I_L
            # controllers other than the vectorised cascade, sampled every `hold` steps
            ext_idx, hold, u_ext, ext_ctl = self._start_controllers(
                dt, gaps_p if circ_avg is None else circ_avg @ gaps_p,
                self._initial_gap_rates(v, rx_all[0], xpath[0], gstate), current)
            k_pay = (n_steps + 1 if payload_step_s is None
                     else int(math.ceil(payload_step_s / dt - 1e-9)))
            q_grav = mech.Q_gravity

            def step(k: int) -> tuple[int, Any] | None:
                """Record the state at step ``k`` and advance it (None), or stop there."""
                nonlocal gx, x_m, bstate, current, force_c, force_pts, psi_hat, integ, q_grav
                t0 = clock()
                t = times[k]
                x_pts = xpath[k]
                if k == k_out:
                    raise OutOfRangeError(
                        f"vehicle run at t = {t:.4f} s: the train left the integrated "
                        f"spans {first_k[k]} ... {first_k[k] + n_sp - 1}")
                if nm and not keep[k].all():    # spans recycled by the moving boundary
                    gx.reshape(n_sp, -1)[keep[k] == 0.0] = 0.0
                gaps_p, rates_p, w, mid, vel_p = f_in(x_m, gx, x_pts, r_all[k], rx_all[k], v)
                t1 = clock()
                gaps_c = gaps_p if circ_avg is None else circ_avg @ gaps_p
                rates_c = rates_p if circ_avg is None else circ_avg @ rates_p
                # record the state at t_k
                rec["gap"][k] = gaps_c
                rec["current"][k] = current
                rec["force"][k] = force_c
                rec["deflection"][k] = w if circ_avg is None else circ_avg @ w
                rec_q[k], rec_qd[k] = x_m[:ndof], x_m[ndof:]
                rec_fp[k] = force_pts
                if rec_ie is not None:
                    rec_ie[k] = bstate.eddy_currents_A
                if nm:
                    rec_span[k] = first_k[k] + span_ids
                    rec_mid[k] = mid[rec_span[k] % n_sp]
                gmin = float(gaps_c.min())
                gmax = float(gaps_c.max())
                if gmin <= tr.touchdown_gap_m or gmax >= tr.landing_gap_m:
                    closed = gmin <= tr.touchdown_gap_m
                    j = int(np.argmin(gaps_c) if closed else np.argmax(gaps_c))
                    rec["voltage"][k] = np.nan
                    return k, (names[j], float(t), float(gaps_c[j]),
                               "closed" if closed else "landed")
                if k == n_steps:
                    rec["voltage"][k] = rec["voltage"][k - 1]
                    return None
                t3 = clock()
                if ext_idx.size and k % hold == 0:
                    self._sample_controllers(ext_ctl, ext_idx, u_ext, t, gaps_c, rates_c,
                                             current, ctl_times,
                                             rec["voltage"][max(k - hold, 0):k], integ,
                                             ctl_cpu)
                # controllers (flux cascade, every circuit at once), the damping input
                # blending the gap rate with the force points' absolute velocity
                vel_c = vel_p if circ_avg is None else circ_avg @ vel_p
                (u,) = f_cas(gaps_c, damping_input(rates_c, vel_c, blend), current, psi_hat,
                             integ)
                if ext_idx.size:        # the other controllers' voltages, held
                    u[ext_idx] = u_ext[ext_idx]
                # |U| <= U_max, the 2-quadrant chopper, failed circuits at 0 V
                # the chopper's current: I_L, or I_L + I_e in ladder circuits (the
                # compiled step's i_chop)
                i_chop = (i_l_fine if self.fine else terminal_current(
                    bstate.inductor_currents_A, bstate.eddy_currents_A, nc))
                (u,) = f_lim(u, i_chop, current, t, fail_t)
                rec["voltage"][k] = u
                t4 = clock()
                try:
                    bstate, out = bank.step(bstate, dt, u, gaps_p, rates_p,
                                            pole_forces=self.fine)
                except MaglevkitError as exc:
                    within = self._touchdown_within_step(gaps_c, rates_c, dt,
                                                         float(times[k + 1]))
                    if within is None:
                        raise type(exc)(f"vehicle run at t = {t:.4f} s: {exc}") from None
                    rec["voltage"][k] = np.nan
                    return k, within
                t5 = clock()
                new_current = out.currents_A
                psi_hat, integ = f_upd(psi_hat, integ, u, current, new_current, gaps_c)
                new_pts = out.pole_force_N if self.fine else out.circuit_force_N
                assert new_pts is not None
                f_bar = (0.5 * sides) * (force_pts + new_pts)
                t6 = clock()
                if k == k_pay:
                    q_grav = self._payload_gravity(payload_fraction)
                (x_m,) = f_mech(x_m, f_bar, q_grav)
                t7 = clock()
                if nm:
                    (gx,) = f_out(gx, x_pts, v, f_bar)
                t8 = clock()
                current = new_current
                force_c = out.circuit_force_N
                force_pts = new_pts
                timing["guideway"] += (t1 - t0) + (t8 - t7)
                timing["other"] += (t3 - t1) + (t6 - t5)
                timing["controllers"] += t4 - t3
                timing["magnets"] += t5 - t4
                timing["mechanics"] += t7 - t6
                return None

            outcome = run_steps(step, n_steps=n_steps, progress=progress)
            last, touchdown, interrupted = outcome.last_step, outcome.event, outcome.interrupted
            wall, cpu = outcome.wall_s, outcome.cpu_s
        n = last + 1
        times = times[:n]
        sl = slice(0, n)
        secs = tr.n_sections
        q_all = rec_q[sl]
        rec["force"] *= sides
        q_g_all = np.repeat(mech.Q_gravity[None, :], n, axis=0)
        if payload_step_s is not None:
            # the mechanics' step k -> k+1 holds the load of step k (ZOH); the record
            # row k is the state at t_k, whose acceleration sees the load from then on
            q_g_all[times >= payload_step_s - 1e-9 * dt] = self._payload_gravity(
                payload_fraction)
        qdd_all = mech.accelerations(q_all, rec_qd[sl], rec_fp[sl] * sides,
                                     gravity_force=q_g_all)
        floor = np.asarray(floor_points, dtype=float)
        acc_floor = (qdd_all[:, 0:2 * secs:2, None]
                     + qdd_all[:, 1:2 * secs:2, None] * floor[None, None, :] * tr.section_length_m)
        fr0 = 2 * secs
        eddy_dims, eddy_coords, eddy_name = ((), {}, "") if rec_ie is None else eddy_record(
            rec_ie, modes=self.eddy_modes_of, scope="one side's circuit")
        member_of = [nm_.split("/", 1)[0] for nm_ in names]
        ds = xr.Dataset(
            {
                "gap": (("time", "circuit"), rec["gap"][sl], {"units": "m",
                        "long_name": "air gap of the circuit (substitute gap)"}),
                "current": (("time", "circuit"), rec["current"][sl], {"units": "A",
                            "long_name": "coil current (one side's circuit)"}),
                "voltage": (("time", "circuit"), rec["voltage"][sl], {"units": "V",
                            "long_name": "circuit voltage held from this sample to the next"}),
                "force": (("time", "circuit"), rec["force"][sl], {"units": "N",
                          "long_name": "magnet force of the lumped circuit (both sides), "
                                       "attraction positive"}),
                **({} if rec_ie is None else {"eddy_current": (
                    ("time", "circuit", *eddy_dims), rec_ie[sl],
                    {"units": "A", "long_name": eddy_name})}),
                "guideway_deflection": (("time", "circuit"), rec["deflection"][sl],
                                        {"units": "m", "long_name": "guideway deflection under "
                                                                    "the circuit (down positive)"}),
                "car_body_heave": (("time", "section"), q_all[:, 0:fr0:2], {"units": "m",
                                   "long_name": "car-body heave (down positive)"}),
                "car_body_pitch": (("time", "section"), q_all[:, 1:fr0:2], {"units": "rad",
                                   "long_name": "car-body pitch (rear down positive)"}),
                "car_body_acceleration": (("time", "section", "floor_point"), acc_floor,
                                          {"units": "m/s^2", "long_name": "car-body vertical "
                                           "floor acceleration (down positive)"}),
                "frame_heave": (("time", "frame"), q_all[:, fr0::2], {"units": "m",
                                "long_name": "levitation-frame heave (down positive)"}),
                "frame_pitch": (("time", "frame"), q_all[:, fr0 + 1::2], {"units": "rad",
                                "long_name": "levitation-frame pitch (rear down positive)"}),
                "midspan_deflection": (("time", "span_slot"), rec_mid[sl], {"units": "m",
                                       "long_name": "midspan deflection of the integrated "
                                                    "spans, rearmost first"}),
                "span_index": (("time", "span_slot"), rec_span[sl], {"units": "1",
                               "long_name": "index of the span in each slot"}),
            },
            coords={"time": ("time", times, {"units": "s"}),
                    "circuit": list(names),
                    **eddy_coords,
                    "magnet_of_circuit": ("circuit", member_of),
                    "circuit_position": ("circuit", self.circuit_xi_m, {"units": "m",
                                         "long_name": "distance behind the nose"}),
                    "section": np.arange(1, secs + 1),
                    "frame": np.arange(1, tr.n_frames + 1),
                    "floor_point": ("floor_point", floor, {"units": "1",
                                    "long_name": "position from the section centre / "
                                                 "section length"})},
            attrs={"vehicle": tr.name, "speed_m_per_s": v, "dt_s": dt,
                   "nose_position_at_t0_m": x_nose0,
                   "nominal_gap_m": s0, "touchdown_gap_m": tr.touchdown_gap_m,
                   "landing_gap_m": tr.landing_gap_m,
                   "magnets": "detailed (fine, per pole)" if self.fine else
                              "reduced (coarse, per circuit)" + (
                                  ", shielded-gap ladder (motion_eddy" + (
                                      ", three-state)" if bank.n_eddy_states == 2 else ")")
                                  if bank.motion_eddy else
                                  f", eddy network ({eddy_modes_label(self.eddy_modes_of)})"
                                  if self.eddy_modes else ""),
                   "controller": self.controller_kind + (
                       "" if self.controller_sample_time_s is None else
                       f" (sample time {self.controller_sample_time_s:g} s)"),
                   "payload_step": "" if payload_step_s is None else
                                   f"+{payload_fraction:g} x car-body weight at "
                                   f"{payload_step_s:g} s",
                   "guideway": repr(gw), "failures": ", ".join(f"{f.circuit}@{f.time_s:g}"
                                                               for f in failures),
                   "touchdown": "" if touchdown is None else
                                f"{touchdown[3]}: {touchdown[0]}@{touchdown[1]:.6g} s "
                                f"({touchdown[2]:.6g} m)",
                   "interrupted": "" if not interrupted else
                                  f"Ctrl-C: the run stopped at t = {float(times[-1]):.6g} s "
                                  f"of {n_steps * dt:.6g} s"},
        )
        gaps = rec["gap"][sl]
        min_gap = {m: float(gaps[:, [j for j, o in enumerate(member_of) if o == m]].min())
                   for m in bank.member_names}
        if touchdown is not None and touchdown[3] == "closed":   # a crossing within a step
            mem = member_of[names.index(touchdown[0])]            # is below the records
            min_gap[mem] = min(min_gap[mem], touchdown[2])
        peak = {c: float(rec["current"][sl, j].max()) for j, c in enumerate(names)}
        comfort = self._comfort(acc_floor, times, dt, floor)
        sim_t = float(times[-1])
        result = VehicleRun(ds, min_gap, peak, touchdown, comfort, wall,
                            sim_t / wall if wall > 0 else math.inf, timing, cpu,
                            "compiled" if compiled_loop else "python",
                            np.asarray(ctl_times, dtype=float), np.asarray(ctl_cpu, dtype=float))
        if interrupted:
            raise VehicleRunInterrupted(result)
        return result

    # ------------------------------------------------------------------ compiled loop
    def step_function(self, dt_s: float = 1e-3) -> Any:
        """The vehicle step for steps of ``dt_s`` [s] as one CasADi function (uncompiled),
        with its layout and parts (:class:`maglevkit.vehicle.stepkernel.VehicleStepFunction`);
        reduced magnets only.

        Parameters
        ----------
        dt_s : float, default 1e-3
            Step length [s], finite and > 0; the guideway and mechanics are discretised
            for it and the bank's RK4 sub-step count follows from it.

        Returns
        -------
        VehicleStepFunction

        Raises
        ------
        InputError
            A bad ``dt_s``, or a model with ``magnets="detailed"``.
        """
        return self._step_function(float(dt_s), self.bank.step_function(float(dt_s)))

    def _part_constants(self, dt: float) -> dict[str, Any]:
        """The run's constants of the step's parts (:func:`build_vehicle_parts`)."""
        gw, mech, span = self.guideway, self.mechanics, self.guideway.span
        nm = gw.n_modes
        ad_g, bd_g = span.discretize(dt) if nm else (np.zeros((0, 0)), np.zeros((0, 0)))
        ad_m, bd_m = mech.discretize(dt)
        return dict(
            dt=dt, nominal_gap_m=self.train.nominal_gap_m, span_length_m=span.length_m,
            origin_m=gw.origin_m, wavenumbers=span.wavenumbers_rad_per_m if nm else np.zeros(0),
            guideway_ad=ad_g, guideway_bd=bd_g, n_spans=gw.n_spans, mech_ad=ad_m,
            mech_bd=bd_m, gravity_force=mech.Q_gravity, force_matrix=mech.B, gains=self.gains,
            flux_bias_Wb=self.flux_bias_Wb, resistance_ohm=self.bank.resistance_ohm,
            eddy_resistance_ohm=self.eddy_resistance_ohm,
            voltage_limit_V=self.train.voltage_limit_V,
            integral_projection=self.integral_projection,
            midspan_shape=span.mode_shapes(0.5 * span.length_m)[0] if nm else np.zeros(0))

    def _step_function(self, dt: float, bank_step: Any, hold: int | None = None) -> Any:
        """The composed step (``hold``: the held-voltage step of a sampled controller,
        ``hold`` steps per block)."""
        from .stepkernel import build_vehicle_step

        if self.fine:
            raise InputError("the compiled vehicle step needs reduced magnets "
                             "(magnets='reduced')")
        kw: dict[str, Any] = {} if hold is None else {
            "controller": "held", "block_steps": hold, "name": "maglevkit_vehicle_held"}
        return build_vehicle_step(bank_step=bank_step, sides=float(self.train.sides),
                                  velocity_blend=self.train.control_velocity_blend,
                                  point_offsets_m=self.point_xi_m,
                                  motion_eddy=self.bank.n_eddy_states > 0,
                                  eddy_states=max(self.bank.n_eddy_states, 1),
                                  **self._part_constants(dt), **kw)

    def _part_evaluators(self, dt: float) -> dict[str, Any]:
        """The step's parts for steps of ``dt`` (:func:`build_vehicle_parts`), bound for
        the reference loop (:class:`~maglevkit.vehicle.framework.PartEvaluator`), built
        once per ``dt``.  The element-wise controller parts run expanded to scalar
        expressions (CasADi's SX machine: ~3 us per call against 2-57 us as matrix
        expressions), the matrix parts as they are (the expansion was 1.7-2.8x slower)."""
        from .stepkernel import build_vehicle_parts

        hit = self._part_functions.get(dt)
        if hit is None:
            parts = build_vehicle_parts(chopper="coil_current" if self.fine else "eq8",
                                        **self._part_constants(dt))
            hit = {k: PartEvaluator(f.expand() if k in ("cascade", "voltage_limits",
                                                         "controller_update") else f)
                   for k, f in parts.items() if k not in ("controllers", "mechanics")}
            self._part_functions[dt] = hit
        return hit

    def _compiled_step(self, dt: float, hold: int | None = None) -> tuple[Any, Any, int]:
        """(compiled block function, layout, steps per block), built and compiled (or
        loaded from the disk cache) once per ``dt``; with ``hold``, the held-voltage step
        (blocks of ``hold`` steps) and the layout's ``measure`` function compiled as
        :attr:`_measure_functions` ``[(dt, hold)]``."""
        from ..control.realtime import vector_flags
        from ..models.compiled import compile_function, compile_linked

        key: Any = dt if hold is None else (dt, hold)
        hit = self._step_functions.get(key)
        if hit is None:
            f = None
            lanes = None if self.fine else self.bank.compiled_step_library(dt)
            if lanes is not None:
                # the bank's SIMD-lane step (its own library) called from the vehicle's
                # generated C, linked against that library; both in the default cache
                # directory (the bank above is built without a cache_dir)
                ext, lib = lanes
                vs = self._step_function(dt, ext, hold)
                # None (e.g. a linker without these options): the CasADi bank step below
                f = compile_linked(vs.block_function, lib, flags=vector_flags())
            if f is None:
                vs = self._step_function(dt, self.bank.step_function(dt), hold)
                f, _ = compile_function(vs.block_function, mode=self.bank.compiled_mode)
            if hold is not None:
                self._measure_functions[key] = compile_function(
                    vs.measure, mode=self.bank.compiled_mode)[0]
            hit = (f, vs.layout, vs.block_steps)
            self._step_functions[key] = hit
        return hit

    def _compiled_loop(self, *, dt: float, v: float, times: np.ndarray, x_ref: np.ndarray,
                       xpath: np.ndarray, r_all: np.ndarray, rx_all: np.ndarray,
                       x_m: np.ndarray, gstate: Any,
                       i_l: np.ndarray, psi_hat: np.ndarray, integ: np.ndarray,
                       i_e: np.ndarray | None, rec_ie: np.ndarray | None,
                       current: np.ndarray, force: np.ndarray, fail_t: np.ndarray,
                       rec: dict[str, np.ndarray], rec_q: np.ndarray, rec_qd: np.ndarray,
                       rec_fp: np.ndarray, rec_mid: np.ndarray, rec_span: np.ndarray,
                       timing: dict[str, float], progress: bool, sampled: Any = None
                       ) -> tuple[int, tuple[str, float, float, str] | None, float, float, bool]:
        """The time loop with one compiled call per block of steps; fills the records like
        the NumPy loop.  Returns ``(last step, touchdown, wall time, CPU time,
        interrupted)``.

        Events are looked for after every block, in the NumPy loop's order per step: the
        loads leaving the integrated spans, touchdown, the end of the run, a circuit the
        kernel flagged (a touchdown within the step, else diagnosed by the bank's own step,
        which raises).  Steps a block computed after the event are discarded, and on
        Ctrl-C the block under way.

        ``sampled`` (the NMPC, ``controller="mpc"``): ``(initial gaps, initial gap rates,
        update wall times, update CPU times, payload step (first step, gravity) or
        None)``; then a block is one controller sample (the held-voltage step), and
        before each block the controllers update from the gaps the step measures
        (:meth:`_sample_controllers`, as the NumPy loop).
        """
        from .stepkernel import eddy_block_as_state

        hold = None
        if sampled is not None:
            gaps0, rates0, ctl_times, ctl_cpu, payload = sampled
            ext_idx, hold, u_ext, ext_ctl = self._start_controllers(dt, gaps0, rates0,
                                                                    current)
        fun, lay, nb = self._compiled_step(dt, hold)
        tr, gw, bank = self.train, self.guideway, self.bank
        names = bank.circuit_names
        n_steps = times.size - 1
        nm = gw.n_modes
        n_sp = lay.n_spans
        st, sp, rl = lay.state, lay.step_inputs, lay.record
        n_rows = -(-(n_steps + 1) // nb) * nb            # whole blocks
        p_all = np.empty((n_rows, lay.n_step_inputs))
        # the points ride at x_ref - xi_p, as xpath = (x_nose0 + v t) - xi; rows after the
        # run repeat its last step (they pad the last block)
        for key, col in (("x_ref", x_ref[:, None]), ("r", r_all), ("r_x", rx_all),
                         ("t", times[:, None])):
            p_all[:n_steps + 1, sp[key]] = col
            p_all[n_steps + 1:, sp[key]] = col[-1]
        p_all[:, sp["keep"]] = 1.0
        # moving system boundary, vectorised: the window's first span at every step (it
        # moves to the rearmost load, never back), the rows it recycles (reset to rest at
        # that step) and the first step whose loads leave the window
        first0 = gstate.first_span
        k_out = -1
        if nm:
            first_k, keep, k_out = gw.window_schedule(
                xpath.min(axis=1), xpath.max(axis=1) + 0.5 * v * dt, first_span=first0)
            p_all[:n_steps + 1, sp["keep"]] = keep
        else:
            first_k = np.full(times.shape, first0)
        before = None
        if hold is not None:
            p_all[:, sp["q_g"]] = self.mechanics.Q_gravity
            if payload is not None:
                p_all[payload[0]:, sp["q_g"]] = payload[1]
            before = self._sampler(dt, hold, times, p_all, consts_v=np.concatenate(
                [[v], fail_t]), lay=lay, k_out=k_out, ctl=(ext_idx, u_ext, ext_ctl),
                ctl_times=ctl_times, ctl_cpu=ctl_cpu)
        # the state at step 0
        s0v = np.zeros(lay.n_state)
        s0v[st["x_mech"]] = x_m
        if nm:
            s0v[st["guideway"]] = np.concatenate([gstate.modal_displacement_m,
                                                  gstate.modal_velocity_m_per_s], axis=1).ravel()
        s0v[st["I_L"]], s0v[st["psi_hat"]], s0v[st["integral"]] = i_l, psi_hat, integ
        s0v[st["current"]], s0v[st["force"]] = current, force
        if i_e is not None:     # (n_c, 2) of the three-state ladder: column-major
            s0v[st["I_e"]] = np.ravel(i_e, order="F")
        consts = np.concatenate([[v], fail_t])
        i_min, i_max, i_bad = rl["gap_min"].start, rl["gap_max"].start, rl["n_bad"].start
        td_gap, land_gap = tr.touchdown_gap_m, tr.landing_gap_m

        def look(k0: int, rows: np.ndarray) -> bool:
            """Any event in the block: a gap at a limit, a flagged circuit, the window."""
            if k0 <= k_out < k0 + nb:
                return True
            if nb <= 4:     # a sampled controller's blocks: three scalars per row
                return any(r[i_min] <= td_gap or r[i_max] >= land_gap or r[i_bad] != 0
                           for r in rows)
            return bool(((rows[:, i_min] <= td_gap) | (rows[:, i_max] >= land_gap)
                         | (rows[:, i_bad] != 0)).any())

        def check(k: int, row: np.ndarray, final: bool) -> tuple[int, Any] | None:
            """The NumPy loop's order per step: the loads leaving the integrated spans,
            touchdown, the end of the run, a circuit the kernel flagged (a touchdown
            within the step, else the bank's message of the step's reason codes, which
            raises)."""
            if k == k_out:
                raise OutOfRangeError(f"vehicle run at t = {times[k]:.4f} s: the train left "
                                      f"the integrated spans {first_k[k]} ... "
                                      f"{first_k[k] + n_sp - 1}")
            if row[i_min] <= td_gap or row[i_max] >= land_gap:
                gaps = row[rl["gap"]]
                if np.isfinite(gaps).all():
                    closed = row[i_min] <= td_gap
                    jj = int(np.argmin(gaps) if closed else np.argmax(gaps))
                    return k, (names[jj], float(times[k]), float(gaps[jj]),
                               "closed" if closed else "landed")
            if final or not row[i_bad]:
                return None
            within = self._touchdown_within_step(row[rl["gap"]], row[rl["gap_rate"]], dt,
                                                 float(times[k + 1]))
            if within is not None:
                return k, within
            # the compiled step's own reason codes (the bank kernel's StepFlag bits) and
            # sub-step extremes, turned into the bank's message (no second step)
            try:
                bank.raise_step_flags(row[rl["flags"]], gaps_m=row[rl["gap"]],
                                      gap_rates_m_per_s=row[rl["gap_rate"]],
                                      inductor_currents_A=row[rl["I_L"]],
                                      voltages_V=row[rl["voltage"]],
                                      current_min_A=row[rl["I_L_min"]],
                                      current_max_A=row[rl["I_L_max"]],
                                      start_s=float(times[k]), end_s=float(times[k + 1]))
            except MaglevkitError as exc:
                raise type(exc)(f"vehicle run at t = {times[k]:.4f} s: {exc}") from None
            return None

        outcome, r_all_rec = run_blocks(fun, state=s0v, inputs=p_all, constants=consts,
                                        n_steps=n_steps, n_record=lay.n_record,
                                        block_steps=nb, look=look, check=check,
                                        progress=progress, before_block=before)
        last, touchdown, interrupted = outcome.last_step, outcome.event, outcome.interrupted
        wall, cpu = outcome.wall_s, outcome.cpu_s
        timing.clear()
        timing["compiled step"] = outcome.call_s
        if hold is not None:
            timing["controllers"] = float(sum(ctl_times))
        timing["other"] = max(wall - outcome.call_s - timing.get("controllers", 0.0), 0.0)
        n = last + 1
        rr = r_all_rec[:n]
        for key in ("gap", "current", "force", "deflection", "voltage"):
            rec[key][:n] = rr[:, rl[key]]
        rec_q[:n], rec_qd[:n], rec_fp[:n] = rr[:, rl["q"]], rr[:, rl["q_dot"]], rr[:, rl["force"]]
        if rec_ie is not None:     # the state's column-major block as the bank's shape
            rec_ie[:n] = eddy_block_as_state(rr[:, rl["I_e"]], bank.n_circuits)
        if nm:
            rec_span[:n] = first_k[:n, None] + np.arange(n_sp)
            rec_mid[:n] = np.take_along_axis(rr[:, rl["midspan_ring"]], rec_span[:n] % n_sp,
                                             axis=1)
        if touchdown is not None:
            rec["voltage"][last] = np.nan
        elif n_steps >= 1 and not interrupted:
            rec["voltage"][n_steps] = rec["voltage"][n_steps - 1]
        return last, touchdown, wall, cpu, interrupted

    def _sampler(self, dt: float, hold: int, times: np.ndarray, p_all: np.ndarray, *,
                 consts_v: np.ndarray, lay: Any, k_out: int, ctl: tuple[Any, Any, Any],
                 ctl_times: list[float], ctl_cpu: list[float]) -> Any:
        """The compiled loop's ``before_block`` for a sampled controller: the gaps the
        step measures at the sample (compiled ``measure`` part), the controllers' update
        (:meth:`_sample_controllers`), their voltages into the block's held-voltage rows.
        Skipped where the NumPy loop stops before sampling (the run's end, touchdown,
        the loads leaving the integrated spans): the block's check reports those."""
        from ..models.compiled import BoundCall

        meas = BoundCall(self._measure_functions[(dt, hold)])
        meas.args[2][:] = consts_v
        ext_idx, u_ext, ext_ctl = ctl
        st, sp, rl = lay.state, lay.step_inputs, lay.record
        n_steps = times.size - 1
        td_gap, land_gap = self.train.touchdown_gap_m, self.train.landing_gap_m

        s_cur, s_int, r_u, p_u = st["current"], st["integral"], rl["voltage"], sp["u_held"]
        m_state, m_inputs = meas.args[0], meas.args[1]
        gaps, rates = meas.res

        def before(k0: int, state: np.ndarray, records: np.ndarray) -> None:
            if k0 >= n_steps or k0 == k_out:
                return
            m_state[:] = state
            m_inputs[:] = p_all[k0]
            meas.eval()
            if gaps.min() <= td_gap or gaps.max() >= land_gap:
                return
            self._sample_controllers(ext_ctl, ext_idx, u_ext, float(times[k0]), gaps, rates,
                                     state[s_cur], ctl_times,
                                     records[max(k0 - hold, 0):k0, r_u], state[s_int], ctl_cpu)
            p_all[k0:k0 + hold, p_u] = u_ext

        return before

    def _start_controllers(self, dt: float, gaps: np.ndarray, rates: np.ndarray,
                           current: np.ndarray) -> tuple[np.ndarray, int, np.ndarray, list[Any]]:
        """Reset the controllers other than the cascade at the run's start: ``(their
        circuit indices, steps per sample, held voltages, controllers)``."""
        from ..control.interface import Measurement

        ctls = self.circuit_controllers
        idx = np.array(sorted(ctls), dtype=int)
        ts = self.controller_sample_time_s
        ts = dt if ts is None else ts
        hold = int(round(ts / dt))
        if hold < 1 or abs(hold * dt - ts) > 1e-9 * ts:
            raise InputError(f"controller_sample_time_s = {ts:g} s must be a whole number of "
                             f"run steps (dt_s = {dt:g} s)")
        s0 = self.train.nominal_gap_m
        if self.controller_kind == "mpc":
            gaps, rates = s0 + self.integral_projection @ (gaps - s0), \
                self.integral_projection @ rates
        first = [Measurement(0.0, float(gaps[j]), float(rates[j]), current[j:j + 1].copy(), s0)
                 for j in idx.tolist()]
        if self.controller_kind == "mpc":
            # every circuit's NMPC in one compiled call per sample (built once per model)
            batch = getattr(self, "mpc_batch", None)
            if batch is None:
                from ..control.realtime import RealTimeMPCBatch

                batch = self.mpc_batch = RealTimeMPCBatch([ctls[j] for j in idx.tolist()])
            batch.reset(first, sample_time_s=ts)
            return idx, hold, np.zeros(self.bank.n_circuits), [batch]
        for j, meas in zip(idx.tolist(), first, strict=True):
            ctls[j].reset(meas, sample_time_s=ts)
        return idx, hold, np.zeros(self.bank.n_circuits), [ctls[j] for j in idx.tolist()]

    def _initial_gap_rates(self, v: float, r_x: np.ndarray, x_pts: np.ndarray,
                           gstate: Any) -> np.ndarray:
        """Circuit gap rates [m/s] at the start (frames at rest): the guideway's and the
        irregularity's motion under the circuits, ``-(w_t + v w_x) - v r_x``."""
        rate = -v * r_x
        if self.guideway.n_modes:
            d = self.guideway.deflection(gstate, x_pts)
            rate = rate - d.rate_m_per_s - v * d.slope
        if self.fine:
            rate = np.bincount(self.pole_circuit, weights=rate) / np.bincount(self.pole_circuit)
        return np.asarray(rate, dtype=float)

    def _sample_controllers(self, ctls: list[Any], idx: np.ndarray, u_out: np.ndarray,
                            t: float, gaps: np.ndarray, rates: np.ndarray, current: np.ndarray,
                            times: list[float], applied: np.ndarray,
                            integral: np.ndarray, times_cpu: list[float]) -> None:
        """One sample of the controllers ``ctls`` (circuits ``idx``): their voltages into
        ``u_out``, each update's wall (CPU) time [s] appended to ``times``
        (``times_cpu``); ``applied``: the
        voltages applied since the last sample (rows), ``integral``: the projected gap
        error integral [m s] (the NMPC's reference correction)."""
        s0 = self.train.nominal_gap_m
        tau = self.reference_integral_time_s
        # (s0 - e / tau, elementwise, is the same as full(s0) - e / tau)
        refs = np.full(gaps.size, s0) if tau is None else s0 - integral / tau
        # the mean of the applied rows: numpy's mean (the rows summed in order, / count)
        ua = np.add.reduce(applied, axis=0) / applied.shape[0] if applied.shape[0] else None
        clock, cpu = time.perf_counter, time.thread_time
        if self.controller_kind == "mpc":       # RealTimeMPCBatch: one call, every circuit
            # what the circuit's frame can do: gaps and rates projected on the frame's
            # heave and pitch (the cascade's integral projection), so that the offset-free
            # estimates of a frame's circuits do not wind up against each other
            gaps = s0 + self.integral_projection @ (gaps - s0)   # (the batch: no rates)
            every = idx.size == gaps.size           # (idx is sorted and unique)
            t0, c0 = clock(), cpu()
            try:
                u_out[idx] = ctls[0].update(
                    gaps if every else gaps[idx], current if every else current[idx],
                    refs if every else refs[idx], None if ua is None else
                    (ua if every else ua[idx]), time_s=float(t))
            except MaglevkitError as exc:
                j = int(idx[int(getattr(exc, "state", {}).get("controller", 0))])
                raise type(exc)(f"vehicle run at t = {t:.4f} s, controller of circuit "
                                f"{self.bank.circuit_names[j]!r}: {exc}") from None
            times.append(clock() - t0)
            times_cpu.append(cpu() - c0)
            return
        from ..control.interface import Measurement

        for c, j in zip(ctls, idx.tolist(), strict=True):
            m = Measurement(float(t), float(gaps[j]), float(rates[j]), current[j:j + 1].copy(),
                            float(refs[j]),
                            applied_voltages_V=None if ua is None else ua[j:j + 1].copy())
            t0, c0 = clock(), cpu()
            try:
                u = np.asarray(c.update(m), dtype=float).ravel()
            except MaglevkitError as exc:
                raise type(exc)(f"vehicle run at t = {t:.4f} s, controller of circuit "
                                f"{self.bank.circuit_names[j]!r}: {exc}") from None
            times.append(clock() - t0)
            times_cpu.append(cpu() - c0)
            if u.size != 1 or not math.isfinite(float(u[0])):
                raise SolverError(f"the controller of circuit {self.bank.circuit_names[j]!r} "
                                  f"returned {u!r} at t = {t:.4f} s; expected one finite "
                                  "voltage [V]")
            u_out[j] = u[0]

    def _payload_gravity(self, fraction: float) -> np.ndarray:
        """Generalised gravity with every car body ``1 + fraction`` times as heavy [N, N m]."""
        mech = self.mechanics
        q = mech.Q_gravity.copy()
        nsec2 = 2 * self.train.n_sections
        q[:nsec2] *= 1.0 + fraction
        return q

    def _touchdown_within_step(self, gaps: np.ndarray, rates: np.ndarray, dt: float,
                               t_end: float) -> tuple[str, float, float, str] | None:
        """The touchdown inside the step of length ``dt`` ending at ``t_end`` [s] that made
        the bank refuse it: the gaps move linearly over a step (as the bank integrates
        them), so a gap whose end value ``s + s' dt`` is at or below the touchdown gap (at
        or above the landing gap) has crossed it within the step.
        ``(circuit, crossing time, gap there, kind)`` as :attr:`VehicleRun.touchdown`
        (:func:`limit_crossing`), or None (then the refusal has another cause)."""
        tr = self.train
        hit = limit_crossing(gaps, rates, dt_s=dt, start_s=t_end - dt,
                             touchdown_gap_m=tr.touchdown_gap_m, landing_gap_m=tr.landing_gap_m)
        if hit is None:
            return None
        j, when, gap, closed = hit
        return (self.bank.circuit_names[j], when, gap, "closed" if closed else "landed")

    def mechanics_trim_forces(self) -> np.ndarray:
        """Downward force on the guideway at every force point at the trim [N] (both sides)."""
        if self.fine:
            per_c = self.trim_force_N * self.train.sides
            return per_c[self.pole_circuit] / self.circuit_poles[self.pole_circuit]
        return self.trim_force_N * self.train.sides

    @staticmethod
    def _comfort(acc: np.ndarray, times: np.ndarray, dt: float,
                 floor: np.ndarray) -> dict[str, dict[str, float]]:
        from .comfort import comfort_indices

        out: dict[str, dict[str, float]] = {}
        if times.size < 64:
            return out
        n_sec, n_fp = acc.shape[1], floor.size
        a = acc.reshape(acc.shape[0], n_sec * n_fp)
        wk, wz = comfort_indices(a - a.mean(axis=0), 1.0 / dt)   # one FFT per record
        for s in range(n_sec):
            for p, fp in enumerate(floor):
                out[f"car{s + 1}@{fp:+.2f}L"] = {"wk_rms_m_per_s2": float(wk[s * n_fp + p]),
                                                 "sperling_wz": float(wz[s * n_fp + p])}
        return out


def check_motion_eddy_options(*, magnets: str, eddy_resistance_scale: Any) -> None:
    """Refuse the combinations a vehicle with shielded-gap ladder magnets does not fly."""
    if magnets != "reduced":
        raise InputError(f"motion_eddy = True with magnets = {magnets!r}: the shielded-gap "
                         "ladder is a reduced model's (the detailed magnets carry their eddy "
                         "currents themselves); use magnets='reduced' or motion_eddy=False")
    if eddy_resistance_scale != 1.0:
        raise InputError(f"motion_eddy = True with eddy_resistance_scale = "
                         f"{eddy_resistance_scale!r}: the factor scales eq. 8's R_ec, not the "
                         "ladder's R_a and R_2; use eddy_resistance_scale=1 or "
                         "motion_eddy=False")


def check_vehicle_eddy_modes(value: Any, *, motion_eddy: bool, magnets: str = "reduced",
                             where: str = "") -> int:
    """``eddy_modes`` of a vehicle checked: 0 (eq. 8) or 1, 2, 3 (branches of the maps'
    fitted eddy network), not with ``motion_eddy``, reduced magnets only; an
    :class:`InputError` naming the option, the value (``where``: where it came from) and
    what is allowed otherwise.  Returns it as an int."""
    if isinstance(value, (bool, np.bool_)) or value not in (0, 1, 2, 3):
        raise InputError(f"eddy_modes = {value!r}{where}; use 0 (eq. 8) or 1, 2, 3 (branches "
                         "of the maps' fitted eddy network)")
    value = int(value)
    if value and motion_eddy:
        raise InputError(f"eddy_modes = {value}{where} with motion_eddy: two eddy extensions "
                         "of eq. 8 (the eddy network, the shielded-gap ladder); use one of "
                         "them")
    if value and magnets != "reduced":
        raise InputError(f"eddy_modes = {value}{where} with magnets = {magnets!r}: the eddy "
                         "network is a reduced model's (the detailed magnets carry their "
                         "eddy currents themselves); use magnets='reduced' or eddy_modes=0")
    return value


def vehicle_eddy_modes(option: Any, magnets: Mapping[str, Any], *, file_value: Any = None,
                       motion_eddy: bool, magnet_kind: str = "reduced",
                       eddy_resistance_scale: Any = 1.0, file_where: str = "") -> dict[str, int]:
    """Which eddy network every magnet kind of a vehicle flies: kind -> ``eddy_modes`` (0:
    eq. 8), each checked by :func:`check_vehicle_eddy_modes`.

    ``option`` (the model's option or ``--eddy-modes``) wins: an int for every kind, or a
    mapping kind -> int (kinds left out take their magnet's default); else ``file_value``
    (the vehicle file's ``[magnets] eddy_modes``; ``file_where`` names it) for every kind;
    else each magnet's own default, :attr:`~maglevkit.magnets.Magnet.default_eddy_modes`
    (its magnet file's ``[reduced] eddy_modes``; ``magnets``: kind -> the loaded magnet).
    The default yields to an explicitly chosen alternative: with ``motion_eddy`` (the
    shielded-gap ladder) or detailed magnets (``magnet_kind``) every kind is 0 unless an
    option or the file asks otherwise (and then that is refused by name, as before).
    """
    if option is None and file_value is not None:
        option, where = file_value, file_where
    else:
        where = ""
    if option is None or isinstance(option, Mapping):
        given = dict(option or {})
        unknown = sorted(set(map(str, given)) - set(magnets))
        if unknown:
            raise InputError(f"eddy_modes = {option!r}: unknown magnet kinds {unknown}; use "
                             f"{sorted(magnets)} (an int applies to every kind)")
        own = not motion_eddy and magnet_kind == "reduced"
        modes = {k: given[k] if k in given else
                 (int(m.default_eddy_modes) if own else 0) for k, m in magnets.items()}
        for k in given:
            check_vehicle_eddy_modes(given[k], motion_eddy=motion_eddy, magnets=magnet_kind,
                                     where=f" (the {k} magnets)")
        return {k: int(v) for k, v in modes.items()}
    value = check_vehicle_eddy_modes(option, motion_eddy=motion_eddy, magnets=magnet_kind,
                                     where=where)
    return {k: value for k in magnets}


def check_eddy_branches(value: Any, *, motion_eddy: bool, where: str = "") -> int:
    """``eddy_branches`` of a vehicle checked: 1 (the two-state shielded-gap ladder) or 2
    (the three-state ladder, only with ``motion_eddy``); an :class:`InputError` naming
    the option, the value (``where``: where it came from) and what is allowed otherwise.
    Returns it as an int."""
    if isinstance(value, (bool, np.bool_)) or value not in (1, 2):
        raise InputError(f"eddy_branches = {value!r}{where}; use 1 (the two-state "
                         "shielded-gap ladder) or 2 (the three-state ladder), with "
                         "motion_eddy")
    if value == 2 and not motion_eddy:
        raise InputError(f"eddy_branches = 2{where} needs motion_eddy (the three-state ladder is the "
                         "shielded-gap ladder's second shielded section); give motion_eddy="
                         "True (--motion-eddy) or leave eddy_branches at 1")
    return int(value)


#: A shielded-gap ladder whose fit to the detailed model's gap and voltage responses has a
#: larger relative RMS residual (maps variable ``motion_eddy_fit_rms``; the three-state
#: ladder's ``motion_eddy3_fit_rms``, over its four weighted responses) is flown with a
#: warning: the bundled levitation magnets' fits are at 4.7-4.8 % (three-state 11.7-12.0
#: %), the guidance magnet's at 28 % (three-state 77 %; 49 % before guidesat26's network,
#: which destabilised the cross-section's guidance loops; docs/vehicle.md).
LADDER_FIT_WARNING = 0.2


def vehicle_bank(bank_type: Any, members: list[tuple[str, Any]], *, motion_eddy: bool,
                 files: dict[str, str], kind_of: dict[str, str], eddy_branches: int = 1,
                 ladder_kinds: Any = None, option: str = "motion_eddy = True ([magnets] "
                 "motion_eddy of the vehicle file, or the option)",
                 eddy_modes: int | Mapping[str, int] = 0, **options: Any) -> Any:
    """The vehicle's magnet bank; with ``motion_eddy`` its ladder members (those of
    ``ladder_kinds`` only, if given; ``eddy_branches`` 2: the three-state ladder), a
    member whose maps have no ladder refused naming the option and the magnet file, a
    poorly fitted ladder flown with a warning; with ``eddy_modes`` (an int for every
    member, or magnet kind -> int: a mixed bank, the kinds at 0 on eq. 8) the members
    with the maps' eddy network (maps without it, or diodes on a network with ``R_0 =
    inf``, refused naming the option and the magnet file)."""
    by_kind = (dict(eddy_modes) if isinstance(eddy_modes, Mapping) else
               dict.fromkeys(set(kind_of.values()), int(eddy_modes)))
    if any(by_kind.values()):
        from ..reduced.current import CurrentModel

        uniform = len(set(by_kind.values())) == 1
        name = ""
        label = (f"eddy_modes = {next(iter(by_kind.values()))}" if uniform else
                 "eddy_modes = " + ", ".join(f"{k} {m}" for k, m in by_kind.items()))

        def member(n: str, m: Any) -> Any:
            nonlocal name
            name, modes = n, by_kind[kind_of[n]]
            return CurrentModel(m, eddy_modes=modes) if modes else m

        try:
            if uniform:   # every member on the network: the bank's own option
                return bank_type(members, eddy_modes=by_kind[kind_of[members[0][0]]],
                                 **options)
            # mixed: the network's kinds as CurrentModel members (they keep their
            # eddy_modes), the others eq. 8
            return bank_type([(n, member(n, m)) for n, m in members], **options)
        except InputError as exc:
            text = str(exc)
            if text.startswith("member '"):
                name = text.split("'", 2)[1]
            kind = kind_of.get(name)
            where = f"the {kind} magnet {files[kind]!r}" if kind in files else "a magnet"
            raise InputError(f"{label}: {where} cannot fly with the eddy network: "
                             f"{text}") from None
    if not motion_eddy:
        return bank_type(members, **options)
    from ..reduced.current import CurrentModel

    name = ""

    def ladder_member(n: str, m: Any) -> Any:
        nonlocal name
        name = n
        return (CurrentModel(m, motion_eddy=True, eddy_branches=eddy_branches)
                if ladder_kinds is not None and kind_of[n] in ladder_kinds else m)

    try:
        # with ladder_kinds: those kinds as ladder members, the others eq. 8
        members = [(n, ladder_member(n, m)) for n, m in members]
        bank = bank_type(members, motion_eddy=ladder_kinds is None,
                         eddy_branches=eddy_branches if ladder_kinds is None else 1,
                         **options)
    except InputError as exc:
        text = str(exc)
        if text.startswith("member '"):
            name = text.split("'", 2)[1]
        kind = kind_of.get(name)
        where = f"the {kind} magnet {files[kind]!r}" if kind in files else "a magnet"
        raise InputError(f"{option}: {where} cannot fly with the shielded-gap "
                         f"ladder: {text}") from None
    warned: set[str] = set()
    for n, m in members:
        kind = kind_of[n]
        maps = m.maps if isinstance(m, CurrentModel) else m
        if kind in warned or (ladder_kinds is not None and kind not in ladder_kinds):
            continue
        ds = maps.dataset
        var = "motion_eddy3_fit_rms" if eddy_branches == 2 else "motion_eddy_fit_rms"
        fit = float(np.max(ds[var].values)) if var in ds else math.nan
        if fit > LADDER_FIT_WARNING:
            warned.add(kind)
            warnings.warn(f"{option}: the {kind} magnet {files[kind]!r}'s "
                          f"{'three-state ' if eddy_branches == 2 else ''}shielded-gap "
                          f"ladder fits the detailed model's gap and voltage responses with "
                          f"{100 * fit:.0f} % RMS residual (above {100 * LADDER_FIT_WARNING:.0f} "
                          "%): its eddy currents under gap motion are not those of the "
                          "detailed model, and its control loops may go unstable (the "
                          "bundled guidance magnet's did at 49 %); motion_eddy = \"levitation\" "
                          "flies "
                          "only the levitation magnets with the ladder", MaglevkitWarning,
                          stacklevel=external_stacklevel())
    return bank


def _scaled_resistances(maps: Any, r_el: float, r_ec: float) -> Any:
    """A copy of ``maps`` with ``R_el`` x ``r_el`` and every eddy resistance x ``r_ec``:
    eq. 8's ``R_ec`` variables and the eddy network's ``R_0`` and ``R_k`` (an eddy path's
    resistance is proportional to the iron's resistivity; the inductances stay)."""
    ds = maps.dataset.copy()
    eddy = ("eddy_network_r0_ohm", "eddy_network_resistance_ohm")
    for name in ds.data_vars:
        factor = (r_el if name == "resistance_ohm" else
                  r_ec if str(name).startswith("eddy_resistance") or name in eddy else None)
        if factor is not None:
            ds[name] = ds[name].copy(data=ds[name].values * float(factor))
    return type(maps)(ds)


class VehicleRunInterrupted(KeyboardInterrupt):
    """Ctrl-C during the time loop of :meth:`VehicleModel.run` or
    :meth:`~maglevkit.vehicle.crossrun.CrossSectionModel.run`: a ``KeyboardInterrupt``
    carrying the run up to the last whole step (``run``, a :class:`VehicleRun` or a
    ``CrossSectionRun``, whose dataset's ``interrupted`` attribute says where it stopped)."""

    def __init__(self, run: Any) -> None:
        super().__init__(run.dataset.attrs.get("interrupted", "interrupted"))
        self.run = run

    def __reduce__(self) -> tuple[Any, tuple[Any]]:
        return (type(self), (self.run,))      # picklable (e.g. from a worker process)


def run_vehicle(train: TrainData, *, speed_m_per_s: float, duration_s: float, dt_s: float = 1e-3,
                rigid: bool = False, irregularity: Any = None, failures: Sequence[Failure] = (),
                magnets: str = "reduced", maps_cache: Any = None, progress: bool = False,
                guideway: Any = None) -> VehicleRun:
    """Build a :class:`VehicleModel` and run it (see :meth:`VehicleModel.run`).

    Parameters
    ----------
    train : TrainData
        The vehicle (from :func:`~maglevkit.vehicle.load_vehicle`).
    speed_m_per_s : float
        Constant speed [m/s], finite and >= 0.
    duration_s : float
        Run length [s], finite, > 0 and at least two steps.
    dt_s : float, default 1e-3
        Fixed time step [s], finite and > 0.
    rigid : bool, default False
        Run on a rigid guideway instead of the flexible spans.
    irregularity : Profile or None, default None
        Guideway irregularity ``r(x)`` [m] (positive downward), see
        :mod:`maglevkit.vehicle.irregularities`; None: a smooth guideway.
    failures : sequence of Failure, default ()
        Circuits switched off (voltage 0) from a time on.
    magnets : {"reduced", "detailed"}, default "reduced"
        Reduced current-based magnets (one force per circuit) or detailed flux-based ones
        (one gap and force per pole; only the Python loop).
    maps_cache : path or None, default None
        Directory of the cached characteristic maps (None: the default cache,
        :mod:`maglevkit.vehicle.mapcache`).
    progress : bool, default False
        Progress on stderr.
    guideway : Guideway or GuidewayData, optional
        The guideway (see :class:`VehicleModel`); default the bundled guideway file.

    Returns
    -------
    VehicleRun

    Raises
    ------
    InputError
        Bad arguments (see :class:`VehicleModel` and :meth:`VehicleModel.run`).
    OutOfRangeError, VehicleRunInterrupted
        As :meth:`VehicleModel.run`.
    """
    model = VehicleModel(train, guideway=guideway, rigid=rigid, magnets=magnets,
                         maps_cache=maps_cache)
    return model.run(speed_m_per_s=speed_m_per_s, duration_s=duration_s, dt_s=dt_s,
                     irregularity=irregularity, failures=failures, progress=progress)



def parse_irregularity(text: str, *, span_length_m: float) -> Any:
    """A guideway irregularity from a short spec (parts joined by ``+``):

    * ``sag:A`` - span-periodic sag of midspan amplitude ``A`` [m] (negative: camber);
    * ``joints:H`` - steps of height ``H`` [m] at the stator-pack joints (alternating);
    * ``random:RMS[:SEED]`` - random profile of the German track PSD shape over wavelengths
      1-100 m, scaled to the RMS ``RMS`` [m] (seed default 0);
    * ``none``.

    Example: ``sag:0.5e-3+random:0.3e-3:7``.
    """
    from .irregularities import GermanTrackPSD, JointSteps, RandomProfile, SpanSag

    parts = [p.strip() for p in str(text).split("+") if p.strip()]
    if not parts:
        raise InputError("irregularity: empty spec; use e.g. sag:0.5e-3+random:0.3e-3 or none")
    prof: Any = None
    for p in parts:
        if p == "none":
            continue
        kind, _, rest = p.partition(":")
        vals = rest.split(":") if rest else []
        try:
            nums = [float(x) for x in vals]
        except ValueError:
            raise InputError(f"irregularity part {p!r}: values must be numbers") from None
        if kind in ("sag", "joints", "random") and nums:
            check_plausible({"irregularity": {kind: nums[0]}},
                            {f"irregularity.{kind}": RUN_PLAUSIBLE[f"irregularity.{kind}"]},
                            f"irregularity {p!r} (--irregularity)", stacklevel=3)
        if kind == "sag" and len(nums) == 1:
            new: Any = SpanSag(nums[0], span_length_m)
        elif kind == "joints" and len(nums) == 1:
            new = JointSteps(nums[0])
        elif kind == "random" and len(nums) in (1, 2) and nums[0] > 0:
            seed = int(nums[1]) if len(nums) == 2 else 0
            lo, hi = 2 * np.pi / 100.0, 2 * np.pi / 1.0
            base = GermanTrackPSD()
            var = base.variance_m2(lo, hi)
            psd = GermanTrackPSD(A_v_m_rad=base.A_v_m_rad * nums[0] ** 2 / var)
            new = RandomProfile(psd, lo, hi, seed=seed)
        else:
            raise InputError(f"irregularity part {p!r}: use sag:A, joints:H, random:RMS[:SEED] "
                             "(metres) or none, joined by '+'")
        prof = new if prof is None else prof + new
    return prof
