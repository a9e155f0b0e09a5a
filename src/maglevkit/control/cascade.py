"""Gap control: a flux-based cascade gap controller and closed-loop co-simulation.

Inner loop on the flux linkage, outer PID loop on the gap::

    psi_hat' = U - R I                         (flux estimate from Faraday's law, eq. 3)
    e        = s - s_ref                       (gap too large -> more flux)
    rho      = k_p (s - s_0 - b (s_ref - s_0)) + k_d d + k_i int e dt
    d        = (1 - beta) ds/dt + beta u'        (damping input; beta = velocity_blend)
    psi_ref  = psi_0 (1 + rho)                 (every circuit, relative to its bias flux)
    U_j      = R_j I_j + k_psi (psi_ref,j - psi_hat,j),   |U_j| <= U_max (chopper limit)
    U_j      = max(U_j, 0)  where I_j <= 0          (two-quadrant chopper: I >= 0)

The two-quadrant chopper cannot reverse the coil current: once a circuit's current is at
zero, a negative command does not act (the freewheeling diodes block; the terminal
voltage is the one that holds ``I = 0``), and integrating it would wind the flux estimate
down below the real flux.  So where the measured current is at zero the law does not
command below 0 V (``GapController.two_quadrant``; False: a four-quadrant supply).

Why flux and not current: with eddy currents a current loop is satisfied almost at once
through the eddy-current path (``R_ec`` in the paper's Fig. 8) while the flux, which makes
the force, lags by ``L~/R_ec`` (0.13 s for the estimated TR09 magnet) -- too slow for a
gap loop of a few hertz.  The flux follows the voltage directly (Faraday), whatever the
eddy currents, and at constant flux an EMS magnet has almost no negative stiffness
(``F ~ psi^2`` for ideal iron, independent of the gap).

:func:`design_gap_controller` places the gains from the exact statics sensitivities at the
operating point: with ``K_rho = sum_j (dF/dpsi_j) psi_0,j`` and the stiffness at constant
flux ``F_s = dF/ds|_psi``, the gap loop ``m e'' = -(K_rho k_p + F_s) e - K_rho k_d e'``
gets the natural frequency ``omega`` and damping ``zeta``; ``k_i = k_p omega / 5``.
:class:`CascadeController` is the sampled-data form (the shared controller interface,
:class:`~maglevkit.control.interface.Controller`): it integrates the flux estimate and the
error integral between samples.

The damping input ``d`` blends the measured gap rate ``ds/dt`` with the magnet's absolute
vertical velocity ``u'`` (positive downward, as the gap; in an EMS vehicle from an
accelerometer, in the vehicle model the frame state): :func:`damping_input`.  On a rigid,
even track the two are equal (``s = s_0 + u``); on an elastic guideway the gap rate jumps
at every pier by ``v`` times the slope change there, which ``beta = 0`` (the default) feeds
straight into the flux demand (docs/vehicle.md, "Gap-controller damping").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, ParameterError
from ..models.statics import solve_statics
from ..validation import real_number
from .interface import Measurement

__all__ = ["ZERO_CURRENT_A", "CascadeController", "GapController", "damping_input",
           "design_gap_controller"]

#: a measured coil current at or below this [A] counts as zero for the two-quadrant law
#: (the plant's diodes hold I at zero to rounding, ~1e-16 A)
ZERO_CURRENT_A = 1e-6


def damping_input(gap_rate_m_per_s: Any, absolute_velocity_m_per_s: Any,
                  velocity_blend: Any) -> Any:
    """The cascade's damping input ``d = (1 - beta) ds/dt + beta u'`` [m/s].

    Element-wise on floats, NumPy arrays and CasADi expressions: the one expression that
    :class:`GapController` and the vehicle models' vectorised cascades evaluate.

    Parameters
    ----------
    gap_rate_m_per_s : float, array_like or CasADi
        Measured gap rate ``ds/dt`` [m/s] (> 0: the gap opens).
    absolute_velocity_m_per_s : float, array_like or CasADi
        The magnet's absolute vertical velocity ``u'`` [m/s], positive downward (the
        direction that opens the gap).
    velocity_blend : float, array_like or CasADi
        ``beta`` in [0, 1] [-]: 0 the gap rate only, 1 the absolute velocity only (not
        checked here; :class:`GapController` checks its own).

    Returns
    -------
    float, ndarray or CasADi
        ``d`` [m/s]; ``beta = 0`` returns the gap rate bit for bit.
    """
    return gap_rate_m_per_s + velocity_blend * (absolute_velocity_m_per_s - gap_rate_m_per_s)


@dataclass(frozen=True)
class GapController:
    """Flux-based cascade gap controller (see module docstring).

    Attributes
    ----------
    gap_ref_m : float
        Design gap s_0 [m] (the default reference).
    flux_bias_Wb : tuple of float
        Bias flux linkage psi_0 of each circuit [Wb].
    bias_current_A : float
        The design current I_0 [A] at which psi_0 holds.
    kp_per_m, kd_s_per_m, ki_per_m_s : float
        Gap-loop gains on the relative flux command ``rho``.
    kflux_per_s : float
        Flux-loop bandwidth k_psi [1/s].
    resistances_ohm : tuple of float
        Circuit resistances [ohm] (resistive feed-forward and flux estimate).
    voltage_limit_V : float
        Actuator limit ``|U| <= U_max`` (chopper supply).
    setpoint_weight : float
        Set-point weight b of the proportional term (0: I-PD form, reference changes act
        through the integrator only and do not kick the flux; 1: plain PID).
    velocity_blend : float
        ``beta`` in [0, 1] [-]: the share of the magnet's absolute velocity in the damping
        input (:func:`damping_input`; 0: the gap rate only).
    two_quadrant : bool
        The supply is a two-quadrant chopper (default True): where a circuit's measured
        current is at zero (<= :data:`ZERO_CURRENT_A`) its command is not below 0 V.
        False: a four-quadrant supply (the current may reverse).
    """

    gap_ref_m: float
    flux_bias_Wb: tuple[float, ...]
    bias_current_A: float
    kp_per_m: float
    kd_s_per_m: float
    ki_per_m_s: float
    kflux_per_s: float
    resistances_ohm: tuple[float, ...]
    voltage_limit_V: float = 440.0
    setpoint_weight: float = 0.0
    velocity_blend: float = 0.0
    two_quadrant: bool = True

    def __post_init__(self) -> None:
        for k in ("gap_ref_m", "bias_current_A", "kp_per_m", "kd_s_per_m", "ki_per_m_s",
                  "kflux_per_s", "voltage_limit_V", "setpoint_weight", "velocity_blend"):
            real_number(getattr(self, k), k, error=ParameterError)
        if not 0.0 <= self.velocity_blend <= 1.0:
            raise ParameterError(f"velocity_blend = {self.velocity_blend!r}: allowed 0 ... 1 "
                                 "(0: damping from the gap rate, 1: from the absolute velocity)")
        if self.gap_ref_m <= 0 or self.voltage_limit_V <= 0 or self.kflux_per_s <= 0:
            raise ParameterError("gap_ref_m, voltage_limit_V and kflux_per_s must be > 0")
        if not isinstance(self.two_quadrant, (bool, np.bool_)):
            raise ParameterError(f"two_quadrant = {self.two_quadrant!r}: allowed True (a "
                                 "two-quadrant chopper, I >= 0) or False (four quadrants)")
        if len(self.flux_bias_Wb) != len(self.resistances_ohm):
            raise ParameterError("flux_bias_Wb and resistances_ohm need one value per circuit")

    def voltages(self, gap_m: float, gap_rate_m_per_s: float, integral_m_s: float,
                 currents_A: np.ndarray, flux_estimate_Wb: np.ndarray,
                 gap_ref_m: float | None = None, *,
                 absolute_velocity_m_per_s: float | None = None) -> np.ndarray:
        """Circuit voltages [V] from the measured gap, gap rate, error integral, currents
        and the flux estimate.

        Parameters
        ----------
        gap_m : float
            Measured gap s [m].
        gap_rate_m_per_s : float
            Measured gap rate ds/dt [m/s] (> 0: the gap opens).
        integral_m_s : float
            Integral of the gap error ``s - s_ref`` over time [m s].
        currents_A : array_like (n_circuits,)
            Measured circuit currents [A] (resistive feed-forward ``R I``).
        flux_estimate_Wb : array_like (n_circuits,)
            Estimated flux linkage of each circuit [Wb].
        gap_ref_m : float, optional
            Gap reference [m] for this sample; ``None`` (default): the design gap
            :attr:`gap_ref_m`.  Acts through the proportional term only with the weight
            :attr:`setpoint_weight` (and through ``integral_m_s``, which the caller keeps).
        absolute_velocity_m_per_s : float, optional
            The magnet's absolute vertical velocity [m/s], positive downward, blended into
            the damping input by :attr:`velocity_blend` (:func:`damping_input`); ``None``
            (default): the gap rate stands for it (exact on a rigid, even track).

        Returns
        -------
        ndarray (n_circuits,)
            Voltages [V], clipped to ``[-voltage_limit_V, voltage_limit_V]``, and not below
            0 V where the current is at zero (:attr:`two_quadrant`).

        Notes
        -----
        No input checks (this is called once per controller sample); arrays of the wrong
        length raise numpy's broadcasting ``ValueError``.
        """
        ref = self.gap_ref_m if gap_ref_m is None else gap_ref_m
        s0 = self.gap_ref_m
        rho = (self.kp_per_m * (gap_m - s0 - self.setpoint_weight * (ref - s0))
               + self.kd_s_per_m * damping_input(
                   gap_rate_m_per_s, gap_rate_m_per_s if absolute_velocity_m_per_s is None
                   else absolute_velocity_m_per_s, self.velocity_blend)
               + self.ki_per_m_s * integral_m_s)
        psi_ref = np.asarray(self.flux_bias_Wb) * (1.0 + rho)
        r = np.asarray(self.resistances_ohm)
        i = np.asarray(currents_A)
        u = r * i + self.kflux_per_s * (psi_ref - flux_estimate_Wb)
        u = np.clip(u, -self.voltage_limit_V, self.voltage_limit_V)
        if self.two_quadrant:         # the chopper cannot drive the current below zero
            u = np.where((i <= ZERO_CURRENT_A) & (u < 0.0), 0.0, u)
        return u


def design_gap_controller(magnet: Any, *, mass_kg: float, gap_m: float, current_A: float,
                          bandwidth_hz: float = 5.0, damping: float = 0.7,
                          flux_bandwidth_hz: float = 30.0,
                          voltage_limit_V: float = 440.0,
                          velocity_blend: float = 0.0) -> GapController:
    """Place the gains from the linearised magnet at ``(gap_m, current_A)`` (all gaps equal,
    every circuit at the same current; exact statics sensitivities).

    Parameters
    ----------
    magnet : Magnet or Network
        The magnet (or its equivalent magnetic circuit, or a model with a ``network``)
        whose statics are solved at the operating point.
    mass_kg : float
        Mass carried by this magnet [kg], > 0 (the gap loop ``m e'' = ...``).
    gap_m : float
        Design gap s_0 [m], > 0; every gap input of the magnet at this value.  Becomes
        the controller's default reference.
    current_A : float
        Design (bias) current I_0 [A] of every circuit; it should carry ``mass_kg`` at
        ``gap_m`` (not checked: the gains are only placed around this point).
    bandwidth_hz : float, default 5.0
        Natural frequency f = omega / 2 pi of the closed gap loop [Hz], > 0.
    damping : float, default 0.7
        Damping ratio zeta of the gap loop [-], > 0.
    flux_bandwidth_hz : float, default 30.0
        Bandwidth of the inner flux loop [Hz], > 0 (``k_psi = 2 pi f``); keep it well
        above ``bandwidth_hz``.
    voltage_limit_V : float, default 440.0
        Actuator limit ``|U| <= U_max`` [V], > 0 (chopper supply).
    velocity_blend : float, default 0.0
        Share ``beta`` in [0, 1] [-] of the magnet's absolute velocity in the damping
        input (:func:`damping_input`); the gains do not depend on it (on the rigid track
        of the design the two velocities are equal).

    Returns
    -------
    GapController
        ``k_p = (m omega^2 - F_s) / K_rho``, ``k_d = 2 zeta m omega / K_rho``,
        ``k_i = k_p omega / 5``.

    Raises
    ------
    InputError
        ``mass_kg``, ``bandwidth_hz``, ``flux_bandwidth_hz``, ``damping`` or
        ``voltage_limit_V`` not a finite real number > 0; bad gap or current (from
        :func:`~maglevkit.models.statics.solve_statics`); an operating point without
        force gain ``K_rho <= 0`` (e.g. zero current) or where the bandwidth gives
        ``k_p <= 0`` (the error names the operating point).
    SolverError
        If the statics at the operating point cannot be solved.
    """
    for name, v in (("mass_kg", mass_kg), ("bandwidth_hz", bandwidth_hz),
                    ("flux_bandwidth_hz", flux_bandwidth_hz), ("damping", damping),
                    ("voltage_limit_V", voltage_limit_V)):
        real_number(v, name, positive=True)
    sol = solve_statics(magnet, gaps_m=gap_m, currents_A=current_A)
    dF_dI = sol.dforce_dcurrent_N_per_A.sum(axis=0)            # (n_c,) total force per I_j
    dF_ds = float(sol.dforce_dgap_N_per_m.sum())               # uniform gap, constant I
    L = np.asarray(sol.differential_inductance_H)              # dpsi/dI
    dpsi_ds = sol.dpsi_dgap_Wb_per_m.sum(axis=-1)              # uniform gap
    dF_dpsi = np.linalg.solve(L.T, dF_dI)                       # at constant gap
    dF_ds_psi = dF_ds - float(dF_dpsi @ dpsi_ds)               # at constant flux
    psi0 = np.asarray(sol.flux_linkage_Wb)
    k_rho = float(dF_dpsi @ psi0)
    omega = 2 * math.pi * bandwidth_hz
    point = (f"operating point gap_m = {float(gap_m):g} m, "
             f"current_A = {np.asarray(current_A, dtype=float).tolist()} A")
    if not (math.isfinite(k_rho) and k_rho > 0.0):
        raise InputError(f"design_gap_controller: at the {point} the force does not grow "
                         f"with the flux (K_rho = sum_j dF/dpsi_j psi_0,j = {k_rho:g} N; "
                         "must be > 0): give a bias current that carries the load")
    # m e'' = -dF = -(K_rho rho + dF/ds|_psi e)  ->  K_rho k_p + dF/ds|_psi = m omega^2
    kp = (mass_kg * omega**2 - dF_ds_psi) / k_rho
    if not (math.isfinite(kp) and kp > 0.0):
        f_min = math.sqrt(max(dF_ds_psi, 0.0) / mass_kg) / (2 * math.pi)
        raise InputError(f"design_gap_controller: at the {point} the gap gain kp = {kp:g} "
                         f"1/m (must be > 0): the stiffness at constant flux dF/ds = "
                         f"{dF_ds_psi:g} N/m exceeds m omega^2 = {mass_kg * omega**2:g} N/m; "
                         f"allowed: bandwidth_hz = {bandwidth_hz:g} Hz above {f_min:.4g} Hz")
    kd = 2 * damping * mass_kg * omega / k_rho
    net = getattr(magnet, "network", magnet)
    return GapController(gap_m, tuple(float(v) for v in psi0), float(current_A), kp, kd,
                         kp * omega / 5.0,
                         2 * math.pi * flux_bandwidth_hz,
                         tuple(float(v) for v in net.resistances), voltage_limit_V,
                         velocity_blend=velocity_blend)




class CascadeController:
    """The cascade controller as a sampled-data ``Controller`` (flux estimate and error
    integral as its internal state; the interface is :class:`maglevkit.control.Controller`).

    Between samples ``k`` and ``k+1`` (sample time ``T``)::

        psi_hat <- psi_hat + T (U_k - R (I_k + I_k+1) / 2)      (trapezoidal in I)
        int e   <- int e + T (s_k - s_ref,k)

    Parameters
    ----------
    design : GapController
        Gains and limits.
    initial_flux_Wb : array (n_circuits,), optional
        Flux estimate at the start [Wb] (default: the design's bias flux, valid when the
        run starts at the design point).
    """

    def __init__(self, design: GapController, *, initial_flux_Wb: object = None) -> None:
        if not isinstance(design, GapController):
            raise InputError(f"design must be a GapController, got {type(design).__name__}")
        self.design = design
        n = len(design.flux_bias_Wb)
        self._psi0 = (np.asarray(design.flux_bias_Wb, dtype=float) if initial_flux_Wb is None
                      else np.asarray(initial_flux_Wb, dtype=float).reshape(n))
        self._r = np.asarray(design.resistances_ohm)
        self._dt = math.nan
        self.flux_estimate_Wb = self._psi0.copy()
        self._integral = 0.0
        self._last: tuple[Measurement, np.ndarray] | None = None

    @property
    def gap_ref_m(self) -> float:
        return self.design.gap_ref_m

    @property
    def voltage_limit_V(self) -> float:
        return self.design.voltage_limit_V

    def reset(self, measurement: Measurement, *, sample_time_s: float) -> None:
        """Start a run: flux estimate back to its initial value, error integral to zero.

        Parameters
        ----------
        measurement : Measurement
            The measurement at the start of the run (not used: the flux estimate starts
            from ``initial_flux_Wb`` or the design's bias flux).
        sample_time_s : float
            Sample time T [s], finite and > 0 (keyword only).

        Raises
        ------
        InputError
            ``sample_time_s`` not finite or <= 0.
        """
        if not (math.isfinite(sample_time_s) and sample_time_s > 0):
            raise InputError(f"sample_time_s = {sample_time_s!r} must be a finite number > 0")
        self._dt = float(sample_time_s)
        self.flux_estimate_Wb = self._psi0.copy()
        self._integral = 0.0
        self._last = None

    def update(self, measurement: Measurement) -> np.ndarray:
        """Advance the flux estimate and the error integral to this sample and return the
        voltages to hold until the next.

        Parameters
        ----------
        measurement : Measurement
            Gap [m], gap rate [m/s], currents [A] and gap reference [m] at this sample.

        Returns
        -------
        ndarray (n_circuits,)
            Circuit voltages [V], within ``+-voltage_limit_V``.

        Raises
        ------
        InputError
            If :meth:`reset` has not been called.
        """
        if not math.isfinite(self._dt):
            raise InputError("call reset() before update()")
        i_now = np.asarray(measurement.currents_A, dtype=float)
        if self._last is not None:
            prev, u_prev = self._last
            self.flux_estimate_Wb = self.flux_estimate_Wb + self._dt * (
                u_prev - self._r * 0.5 * (np.asarray(prev.currents_A) + i_now))
            self._integral += (prev.gap_m - prev.gap_ref_m) * self._dt
        u = self.design.voltages(measurement.gap_m, measurement.gap_rate_m_per_s,
                                 self._integral, i_now, self.flux_estimate_Wb,
                                 measurement.gap_ref_m,
                                 absolute_velocity_m_per_s=measurement.absolute_velocity_m_per_s)
        self._last = (measurement, u)
        return u

    def diagnostics(self) -> Mapping[str, float | np.ndarray]:
        return {"flux_estimate_Wb": self.flux_estimate_Wb.copy(),
                "gap_error_integral_m_s": self._integral}
