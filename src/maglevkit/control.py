"""Gap control: a cascade PID gap controller and closed-loop co-simulation.

The controller is the classic EMS cascade: an outer PID loop on the gap sets a current
reference common to all circuits, an inner proportional current loop with resistive
feed-forward sets each circuit's voltage::

    e     = s - s_ref                      (gap too large -> more current)
    I_ref = I_0 s_ref/s_0 + k_p e + k_d ds/dt + k_i int e dt
    U_j   = R_j I_ref + k_c (I_ref - I_j),  limited to |U_j| <= U_max (chopper limit)

:func:`design_gap_controller` places the gains from the magnet's linearisation at the
operating point (exact statics sensitivities): with ``K_s = -dF/ds`` (negative stiffness)
and ``K_i = dF/dI``, the gap loop ``m e'' = (K_s - K_i k_p) e - K_i k_d e'`` gets the
natural frequency ``omega`` and damping ``zeta``; the current loop gets the bandwidth
``k_c / L~``.  The bias current follows the reference gap (``I_0 s_ref/s_0``, exact for
``F ~ (I/s)^2``): without this feed-forward a proportional loop around the unstable
plant has the static gain ``K_i k_p / (K_i k_p - K_s)`` (2.65 for the TR09 magnet at 5 Hz)
from reference to gap, and only the slow integrator would correct it.
:func:`closed_loop` co-simulates any magnet model that has the ``initial_state``/``step``
interface (flux-based or current-based) with a
:class:`~maglevkit.vehicle.HeaveMass`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import InputError, ParameterError
from .models.statics import solve_statics
from .vehicle import HeaveMass, HeaveState

__all__ = ["GapController", "ClosedLoopResult", "design_gap_controller", "closed_loop"]


@dataclass(frozen=True)
class GapController:
    """Cascade PID gap controller (see module docstring).

    Attributes
    ----------
    gap_ref_m, current_bias_A : float
        Design gap s_0 [m] (the default reference) and the bias current I_0 [A] there.
    kp_A_per_m, kd_A_s_per_m, ki_A_per_m_s : float
        Gap-loop gains.
    kc_V_per_A : float
        Current-loop gain.
    resistances_ohm : tuple of float
        Circuit resistances for the feed-forward ``R I_ref``.
    voltage_limit_V : float
        Actuator limit |U| <= U_max (chopper supply).
    """

    gap_ref_m: float
    current_bias_A: float
    kp_A_per_m: float
    kd_A_s_per_m: float
    ki_A_per_m_s: float
    kc_V_per_A: float
    resistances_ohm: tuple[float, ...]
    voltage_limit_V: float = 440.0

    def __post_init__(self) -> None:
        for k in ("gap_ref_m", "current_bias_A", "kp_A_per_m", "kd_A_s_per_m", "ki_A_per_m_s",
                  "kc_V_per_A", "voltage_limit_V"):
            v = getattr(self, k)
            if not math.isfinite(v):
                raise ParameterError(f"{k} = {v!r} must be finite")
        if self.gap_ref_m <= 0 or self.voltage_limit_V <= 0 or self.kc_V_per_A < 0:
            raise ParameterError("gap_ref_m and voltage_limit_V must be > 0, kc_V_per_A >= 0")

    def voltages(self, gap_m: float, gap_rate_m_per_s: float, integral_m_s: float,
                 currents_A: np.ndarray, gap_ref_m: float | None = None) -> np.ndarray:
        """Circuit voltages [V] for the measured gap, gap rate, error integral and currents."""
        ref = self.gap_ref_m if gap_ref_m is None else gap_ref_m
        e = gap_m - ref
        i_ref = (self.current_bias_A * ref / self.gap_ref_m + self.kp_A_per_m * e
                 + self.kd_A_s_per_m * gap_rate_m_per_s + self.ki_A_per_m_s * integral_m_s)
        r = np.asarray(self.resistances_ohm)
        u = r * i_ref + self.kc_V_per_A * (i_ref - np.asarray(currents_A))
        return np.clip(u, -self.voltage_limit_V, self.voltage_limit_V)


def design_gap_controller(magnet: Any, *, mass_kg: float, gap_m: float, current_A: float,
                          bandwidth_hz: float = 5.0, damping: float = 0.7,
                          current_bandwidth_hz: float = 50.0,
                          voltage_limit_V: float = 440.0) -> GapController:
    """Place the cascade gains from the linearised magnet at ``(gap_m, current_A)``.

    Uses the exact statics sensitivities with all gaps equal and every circuit at the same
    current.  The integral gain is ``k_p omega / 5`` (a slow integrator that removes the
    static offset without spoiling the damping).
    """
    for name, v in (("mass_kg", mass_kg), ("bandwidth_hz", bandwidth_hz),
                    ("current_bandwidth_hz", current_bandwidth_hz), ("damping", damping)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{name} = {v!r} must be a finite number > 0")
    sol = solve_statics(magnet, gaps=gap_m, currents=current_A)
    k_s = -float(sol.dforce_dgap_N_per_m.sum())           # > 0: negative stiffness
    k_i = float(sol.dforce_dcurrent_N_per_A.sum())
    l_diff = float(np.max(sol.common_differential_inductance_H))
    net = getattr(magnet, "network", magnet)
    r = tuple(float(v) for v in net.resistances)
    omega = 2 * math.pi * bandwidth_hz
    kp = (mass_kg * omega**2 + k_s) / k_i
    kd = 2 * damping * mass_kg * omega / k_i
    kc = max(0.0, 2 * math.pi * current_bandwidth_hz * l_diff - min(r))
    return GapController(gap_m, current_A, kp, kd, kp * omega / 5.0, kc, r, voltage_limit_V)


@dataclass(frozen=True)
class ClosedLoopResult:
    """Time series of a closed-loop co-simulation (axis 0: time).

    Attributes
    ----------
    time_s : (n,)
    gap_m, gap_rate_m_per_s : (n,)
    voltages_V, currents_A : (n, n_circuits)
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
    pole_force_N: np.ndarray
    force_N: np.ndarray
    voltage_limited: np.ndarray
    circuit_names: tuple[str, ...]
    gap_names: tuple[str, ...]


def closed_loop(model: Any, vehicle: HeaveMass, controller: GapController, *, duration_s: float,
                dt_s: float, initial_gap_m: float, initial_current_A: float,
                gap_reference: Callable[[float], float] | None = None,
                external_force: Callable[[float], float] | None = None) -> ClosedLoopResult:
    """Co-simulate magnet model, heave mass and controller at a fixed step ``dt_s`` [s].

    Per step: the controller reads gap, gap rate and currents (sample-and-hold), the
    magnet model integrates with the voltages held and the gaps moving at the current rate
    (its ``step``), the mass integrates with the magnet force held.  Every pole sees the
    same gap (rigid heave).
    """
    if not (math.isfinite(duration_s) and duration_s > 0 and math.isfinite(dt_s) and dt_s > 0):
        raise InputError("duration_s and dt_s must be finite numbers > 0")
    n = int(round(duration_s / dt_s))
    if n < 1:
        raise InputError("duration_s must be at least one step dt_s")
    ref = gap_reference or (lambda t: controller.gap_ref_m)
    ext = external_force or (lambda t: 0.0)
    st = model.initial_state(gaps=initial_gap_m, currents=initial_current_A)
    out = model.outputs(st)
    mech = HeaveState(initial_gap_m, 0.0)
    integral = 0.0
    nc, ng = len(model.circuit_names), len(model.gap_names)
    T = np.arange(n + 1) * dt_s
    S, V = np.empty(n + 1), np.empty(n + 1)
    U, I = np.empty((n + 1, nc)), np.empty((n + 1, nc))
    P, lim = np.empty((n + 1, ng)), np.zeros(n + 1, dtype=bool)
    S[0], V[0], I[0], P[0] = mech.gap_m, 0.0, out.currents_A, out.pole_force_N
    for k in range(n):
        t = T[k]
        u = controller.voltages(mech.gap_m, mech.gap_rate_m_per_s, integral, I[k], ref(t))
        lim[k] = bool(np.any(np.abs(u) >= controller.voltage_limit_V))
        U[k] = u
        force = float(out.force_N)
        st, out = model.step(st, dt_s, u, gaps=mech.gap_m, gap_rates=mech.gap_rate_m_per_s)
        integral += (mech.gap_m - ref(t)) * dt_s
        mech = vehicle.step(mech, dt_s, force, ext(t))
        if not mech.gap_m > 0:
            raise InputError(f"the magnet hit the rail at t = {T[k + 1]:.4g} s (gap "
                             f"{mech.gap_m:.3g} m); the controller is unstable for this case")
        S[k + 1], V[k + 1], I[k + 1], P[k + 1] = (mech.gap_m, mech.gap_rate_m_per_s,
                                                  out.currents_A, out.pole_force_N)
    U[n] = U[n - 1]
    return ClosedLoopResult(T, S, V, U, I, P, P.sum(axis=1), lim, tuple(model.circuit_names),
                            tuple(model.gap_names))
