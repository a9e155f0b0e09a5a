"""Gap control: a flux-based cascade gap controller and closed-loop co-simulation.

Inner loop on the flux linkage, outer PID loop on the gap::

    psi_hat' = U - R I                         (flux estimate from Faraday's law, eq. 3)
    e        = s - s_ref                       (gap too large -> more flux)
    rho      = k_p (s - s_0 - b (s_ref - s_0)) + k_d ds/dt + k_i int e dt
    psi_ref  = psi_0 (1 + rho)                 (every circuit, relative to its bias flux)
    U_j      = R_j I_j + k_psi (psi_ref,j - psi_hat,j),   |U_j| <= U_max (chopper limit)

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
:func:`closed_loop` co-simulates any magnet model with the ``initial_state``/``step``
interface (flux-based or current-based) with a :class:`~maglevkit.vehicle.HeaveMass`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import InputError, ParameterError
from .models.inputs import check_span
from .models.statics import solve_statics
from .validation import real_number
from .vehicle import HeaveMass, HeaveState

__all__ = ["GapController", "ClosedLoopResult", "design_gap_controller", "closed_loop"]


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
        Actuator limit |U| <= U_max (chopper supply).
    setpoint_weight : float
        Set-point weight b of the proportional term (0: I-PD form, reference changes act
        through the integrator only and do not kick the flux; 1: plain PID).
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

    def __post_init__(self) -> None:
        for k in ("gap_ref_m", "bias_current_A", "kp_per_m", "kd_s_per_m", "ki_per_m_s",
                  "kflux_per_s", "voltage_limit_V", "setpoint_weight"):
            real_number(getattr(self, k), k, error=ParameterError)
        if self.gap_ref_m <= 0 or self.voltage_limit_V <= 0 or self.kflux_per_s <= 0:
            raise ParameterError("gap_ref_m, voltage_limit_V and kflux_per_s must be > 0")
        if len(self.flux_bias_Wb) != len(self.resistances_ohm):
            raise ParameterError("flux_bias_Wb and resistances_ohm need one value per circuit")

    def voltages(self, gap_m: float, gap_rate_m_per_s: float, integral_m_s: float,
                 currents_A: np.ndarray, flux_estimate_Wb: np.ndarray,
                 gap_ref_m: float | None = None) -> np.ndarray:
        """Circuit voltages [V] from the measured gap, gap rate, error integral, currents
        and the flux estimate."""
        ref = self.gap_ref_m if gap_ref_m is None else gap_ref_m
        s0 = self.gap_ref_m
        rho = (self.kp_per_m * (gap_m - s0 - self.setpoint_weight * (ref - s0))
               + self.kd_s_per_m * gap_rate_m_per_s + self.ki_per_m_s * integral_m_s)
        psi_ref = np.asarray(self.flux_bias_Wb) * (1.0 + rho)
        r = np.asarray(self.resistances_ohm)
        u = r * np.asarray(currents_A) + self.kflux_per_s * (psi_ref - flux_estimate_Wb)
        return np.clip(u, -self.voltage_limit_V, self.voltage_limit_V)


def design_gap_controller(magnet: Any, *, mass_kg: float, gap_m: float, current_A: float,
                          bandwidth_hz: float = 5.0, damping: float = 0.7,
                          flux_bandwidth_hz: float = 30.0,
                          voltage_limit_V: float = 440.0) -> GapController:
    """Place the gains from the linearised magnet at ``(gap_m, current_A)`` (all gaps equal,
    every circuit at the same current; exact statics sensitivities)."""
    for name, v in (("mass_kg", mass_kg), ("bandwidth_hz", bandwidth_hz),
                    ("flux_bandwidth_hz", flux_bandwidth_hz), ("damping", damping),
                    ("voltage_limit_V", voltage_limit_V)):
        real_number(v, name, positive=True)
    sol = solve_statics(magnet, gaps=gap_m, currents=current_A)
    dF_dI = sol.dforce_dcurrent_N_per_A.sum(axis=0)            # (n_c,) total force per I_j
    dF_ds = float(sol.dforce_dgap_N_per_m.sum())               # uniform gap, constant I
    L = np.asarray(sol.differential_inductance_H)              # dpsi/dI
    dpsi_ds = sol.dpsi_dgap_Wb_per_m.sum(axis=-1)              # uniform gap
    dF_dpsi = np.linalg.solve(L.T, dF_dI)                       # at constant gap
    dF_ds_psi = dF_ds - float(dF_dpsi @ dpsi_ds)               # at constant flux
    psi0 = np.asarray(sol.flux_linkage_Wb)
    k_rho = float(dF_dpsi @ psi0)
    omega = 2 * math.pi * bandwidth_hz
    # m e'' = -dF = -(K_rho rho + dF/ds|_psi e)  ->  K_rho k_p + dF/ds|_psi = m omega^2
    kp = (mass_kg * omega**2 - dF_ds_psi) / k_rho
    kd = 2 * damping * mass_kg * omega / k_rho
    net = getattr(magnet, "network", magnet)
    return GapController(gap_m, tuple(float(v) for v in psi0), float(current_A), kp, kd,
                         kp * omega / 5.0,
                         2 * math.pi * flux_bandwidth_hz,
                         tuple(float(v) for v in net.resistances), voltage_limit_V)


@dataclass(frozen=True)
class ClosedLoopResult:
    """Time series of a closed-loop co-simulation (axis 0: time).

    Attributes
    ----------
    time_s : (n,)
    gap_m, gap_rate_m_per_s : (n,)
    voltages_V, currents_A, flux_estimate_Wb : (n, n_circuits)
    pole_force_N : (n, n_gaps)
    force_N : (n,)
    voltage_limited : (n,) bool
        Whether a voltage hit the actuator limit in the interval starting there.
    """

    time_s: np.ndarray
    gap_m: np.ndarray
    gap_rate_m_per_s: np.ndarray
    voltages_V: np.ndarray
    currents_A: np.ndarray
    flux_estimate_Wb: np.ndarray
    pole_force_N: np.ndarray
    force_N: np.ndarray
    voltage_limited: np.ndarray
    circuit_names: tuple[str, ...]
    gap_names: tuple[str, ...]


def closed_loop(model: Any, vehicle: HeaveMass, controller: GapController, *, duration_s: float,
                dt_s: float, initial_gap_m: float, initial_current_A: float,
                gap_reference: Callable[[float], float] | None = None,
                external_force: Callable[[float], float] | None = None,
                initial_flux_Wb: Any = None) -> ClosedLoopResult:
    """Co-simulate magnet model, heave mass and controller at a fixed step ``dt_s`` [s].

    Per step: the controller reads gap, gap rate, currents and its flux estimate
    (sample-and-hold); the magnet model integrates with the voltages held and the gaps moving
    at the current rate (its ``step``); the mass integrates with the magnet force held; the
    flux estimate integrates ``U - R I`` (trapezoidal in I).  Every pole sees the same gap.
    The flux estimate starts at ``initial_flux_Wb`` [Wb] (default: the controller's bias
    flux, valid when the run starts at the controller's design point).
    """
    duration_s = real_number(duration_s, "duration_s", "s", positive=True)
    dt_s = real_number(dt_s, "dt_s", "s", positive=True)
    real_number(initial_gap_m, "initial_gap_m", "m", positive=True)
    real_number(initial_current_A, "initial_current_A", "A")
    check_span(0.0, duration_s, dt_s)     # the rule of simulate and scenario files
    n = int(round(duration_s / dt_s))
    # the loop runs whole steps: a duration between two step counts would silently be
    # rounded (0.5 s at dt 0.3 s ran 0.6 s); allowance 1e-6 steps for decimal rounding
    if abs(n * dt_s - duration_s) > 1e-6 * dt_s:
        raise InputError(f"duration_s = {duration_s:g} s is not a whole number of steps "
                         f"dt_s = {dt_s:g} s ({duration_s / dt_s:.6g}); use e.g. duration_s = "
                         f"{n * dt_s:g} s")
    ref = gap_reference or (lambda t: controller.gap_ref_m)
    ext = external_force or (lambda t: 0.0)
    st = model.initial_state(gaps=initial_gap_m, currents=initial_current_A)
    out = model.outputs(st)
    if initial_flux_Wb is None:
        if not (math.isclose(initial_gap_m, controller.gap_ref_m, rel_tol=1e-12)
                        and math.isclose(initial_current_A, controller.bias_current_A, rel_tol=1e-12)):
            raise InputError("give initial_flux_Wb when the run does not start at the "
                             "controller's design point")
        psi_hat = np.asarray(controller.flux_bias_Wb, dtype=float)
    else:
        psi_hat = np.asarray(initial_flux_Wb, dtype=float).reshape(len(controller.flux_bias_Wb))
    r = np.asarray(controller.resistances_ohm)
    mech = HeaveState(initial_gap_m, 0.0)
    integral = 0.0
    nc, ng = len(model.circuit_names), len(model.gap_names)
    T = np.arange(n + 1) * dt_s
    S, V = np.empty(n + 1), np.empty(n + 1)
    U, I, Psi = np.empty((n + 1, nc)), np.empty((n + 1, nc)), np.empty((n + 1, nc))
    P, lim = np.empty((n + 1, ng)), np.zeros(n + 1, dtype=bool)
    S[0], V[0], I[0], P[0], Psi[0] = mech.gap_m, 0.0, out.currents_A, out.pole_force_N, psi_hat
    for k in range(n):
        t = T[k]
        u = controller.voltages(mech.gap_m, mech.gap_rate_m_per_s, integral, I[k], psi_hat,
                                ref(t))
        lim[k] = bool(np.any(np.abs(u) >= controller.voltage_limit_V))
        U[k] = u
        if not mech.gap_m + mech.gap_rate_m_per_s * dt_s > 0:
            raise InputError(f"the magnet hit the rail at t = {t:.4g} s (gap {mech.gap_m:.3g} m); "
                             "the controller is unstable for this case")
        force = float(out.force_N)
        st, out = model.step(st, dt_s, u, gaps=mech.gap_m, gap_rates=mech.gap_rate_m_per_s)
        psi_hat = psi_hat + dt_s * (u - r * 0.5 * (I[k] + out.currents_A))
        integral += (mech.gap_m - ref(t)) * dt_s
        mech = vehicle.step(mech, dt_s, force, ext(t))
        S[k + 1], V[k + 1], I[k + 1], P[k + 1], Psi[k + 1] = (
            mech.gap_m, mech.gap_rate_m_per_s, out.currents_A, out.pole_force_N, psi_hat)
    U[n] = U[n - 1]
    return ClosedLoopResult(T, S, V, U, I, Psi, P, P.sum(axis=1), lim,
                            tuple(model.circuit_names), tuple(model.gap_names))
