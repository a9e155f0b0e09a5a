"""Closed-loop co-simulation: magnet model + heave mass + any gap controller."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._interrupt import check_interrupt
from ..errors import InputError, SolverError
from ..models.inputs import check_span
from ..plant import HeaveMass, HeaveState
from ..validation import real_number, renamed_keywords
from .cascade import CascadeController, GapController
from .interface import Controller, Measurement

__all__ = ["ClosedLoopResult", "closed_loop"]


@dataclass(frozen=True)
class ClosedLoopResult:
    """Time series of a closed-loop co-simulation (axis 0: time).

    Attributes
    ----------
    time_s : ndarray (n,)
        Sample instants [s], from 0 in steps of ``dt_s``.
    gap_m, gap_rate_m_per_s : ndarray (n,)
        Gap [m] and gap rate [m/s] of the heave mass (> 0: the gap opens).
    voltages_V, currents_A, flux_estimate_Wb : ndarray (n, n_circuits)
        Voltages [V] held from each sample to the next (the last row repeats the
        previous), circuit currents [A], and the controller's flux estimate [Wb] (NaN for
        controllers without one).
    pole_force_N : ndarray (n, n_gaps)
        Attractive force of each pole [N].
    force_N : ndarray (n,)
        Total magnet force [N] (sum over the poles).
    voltage_limited : ndarray (n,) of bool
        Whether a voltage hit the actuator limit in the interval starting there.
    circuit_names : tuple of str
        Names of the circuits (columns of ``voltages_V``, ``currents_A``,
        ``flux_estimate_Wb``).
    gap_names : tuple of str
        Names of the gap inputs (columns of ``pole_force_N``).
    gap_ref_m : ndarray (n,) or None
        The gap reference [m] at each sample.
    controller_time_s : (n,)
        Wall-clock time of each controller update [s] (the last row repeats the previous).
    diagnostics : dict of str to ndarray (n, ...)
        The controller's :meth:`~maglevkit.control.interface.Controller.diagnostics`
        after each update (names carry units).
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
    gap_ref_m: np.ndarray | None = None
    controller_time_s: np.ndarray | None = None
    diagnostics: dict[str, np.ndarray] = field(default_factory=dict)

    def _gap_error_m(self, what: str) -> np.ndarray:
        if self.gap_ref_m is None:
            raise InputError(f"{what} needs the gap reference, but this result has "
                             "gap_ref_m = None (closed_loop always records it)")
        return np.abs(self.gap_m - self.gap_ref_m)

    def max_gap_deviation_m(self, start_s: float = 0.0) -> float:
        """Largest ``|s - s_ref|`` [m] from ``start_s`` on.

        Parameters
        ----------
        start_s : float, default 0.0
            Samples at times ``>= start_s`` [s] count (e.g. skip a start transient); at
            most the last sample time.

        Returns
        -------
        float
            The largest gap deviation [m].

        Raises
        ------
        InputError
            ``start_s`` not a real number or after the last sample; a result without
            ``gap_ref_m``.
        """
        start_s = real_number(start_s, "start_s", "s")
        e = self._gap_error_m("max_gap_deviation_m")
        k = self.time_s >= start_s
        if not np.any(k):
            raise InputError(f"start_s = {start_s:g} s is after the last sample "
                             f"(t = {float(self.time_s[-1]):g} s); allowed: start_s <= "
                             f"{float(self.time_s[-1]):g} s")
        return float(np.max(e[k]))

    def iae_m_s(self) -> float:
        """Integral of the absolute gap error ``int |s - s_ref| dt`` [m s] (trapezoidal).

        Raises
        ------
        InputError
            A result without ``gap_ref_m``.
        """
        e = self._gap_error_m("iae_m_s")
        return float(np.sum(0.5 * (e[1:] + e[:-1]) * np.diff(self.time_s)))

    def energy_J(self) -> float:
        """Electric energy drawn from the supply ``int sum_j U_j I_j dt`` [J] (voltage held
        over each interval, current trapezoidal; negative when energy is fed back)."""
        p_start = np.sum(self.voltages_V[:-1] * self.currents_A[:-1], axis=1)
        p_end = np.sum(self.voltages_V[:-1] * self.currents_A[1:], axis=1)
        return float(np.sum(0.5 * (p_start + p_end) * np.diff(self.time_s)))


@renamed_keywords(external_force="external_force_N", gap_reference="gap_reference_m")
def closed_loop(model: Any, vehicle: HeaveMass, controller: GapController | Controller, *,
                duration_s: float, dt_s: float, initial_gap_m: float, initial_current_A: Any,
                gap_reference_m: Callable[[float], float] | None = None,
                external_force_N: Callable[[float], float] | None = None,
                initial_flux_Wb: Any = None) -> ClosedLoopResult:
    """Co-simulate magnet model, heave mass and controller at a fixed step ``dt_s`` [s].

    Per step: the controller reads gap, gap rate, currents (sample-and-hold) and returns
    the voltages; the magnet model integrates with the voltages held and the gaps moving
    at the current rate (its ``step``); the mass integrates with the magnet force held.
    Every pole sees the same gap.

    The old keyword names ``external_force`` and ``gap_reference`` still work as deprecated
    aliases (a ``DeprecationWarning`` names the new one).

    Parameters
    ----------
    model : FluxModel or CurrentModel
        Any magnet model with ``initial_state``/``step``/``outputs`` (flux-based or
        current-based), with ``circuit_names`` and ``gap_names``.
    vehicle : HeaveMass
        The mass on the magnet (one heave degree of freedom).
    controller : GapController or Controller
        A :class:`GapController` design is run as a :class:`CascadeController` (its flux
        estimate starts at ``initial_flux_Wb`` [Wb], default the bias flux, valid when
        the run starts at the design point); any other object must implement the
        :class:`~maglevkit.control.interface.Controller` interface (``initial_flux_Wb``
        is then not allowed: give the controller its own initial estimate).
    duration_s, dt_s : float
        Run length and sample time [s], finite and > 0; ``duration_s`` must be a whole
        number of steps ``dt_s`` (to 1e-6 of a step).
    initial_gap_m : float
        Gap at the start [m], > 0 (every pole).
    initial_current_A : float or array (n_circuits,)
        Steady start: the model starts at rest at this gap and current [A].
    gap_reference_m, external_force_N : callable t -> value, optional
        Gap reference [m] (default the controller's) and external force on the mass [N]
        (positive opens the gap, like gravity); both called with the time [s].
    initial_flux_Wb : array_like (n_circuits,), optional
        Initial flux estimate [Wb] of the cascade controller built from a
        :class:`GapController`.  Required when the run does not start at the design
        point (``initial_gap_m`` and ``initial_current_A`` equal to the design's);
        not allowed with any other controller.

    Returns
    -------
    ClosedLoopResult
        ``n_steps + 1`` samples from t = 0 to ``duration_s``.

    Raises
    ------
    InputError
        Durations or steps not finite and > 0 or not a whole number of steps; a gap <= 0;
        a controller that is neither a :class:`GapController` nor a
        :class:`~maglevkit.control.interface.Controller`; ``initial_flux_Wb`` missing or
        not allowed (see above).
    SolverError
        Touchdown: the magnet would hit the rail (gap <= 0 within the next step; the
        closed loop is unstable for this case).  ``time`` and ``state`` (gap, gap rate)
        name the step.
    """
    external_force = external_force_N
    duration_s = real_number(duration_s, "duration_s", "s", positive=True)
    dt_s = real_number(dt_s, "dt_s", "s", positive=True)
    real_number(initial_gap_m, "initial_gap_m", "m", positive=True)
    if np.ndim(initial_current_A) == 0:
        real_number(initial_current_A, "initial_current_A", "A")
    check_span(0.0, duration_s, dt_s)     # the rule of simulate and scenario files
    n = int(round(duration_s / dt_s))
    # the loop runs whole steps: a duration between two step counts would silently be
    # rounded (0.5 s at dt 0.3 s ran 0.6 s); allowance 1e-6 steps for decimal rounding
    if abs(n * dt_s - duration_s) > 1e-6 * dt_s:
        raise InputError(f"duration_s = {duration_s:g} s is not a whole number of steps "
                         f"dt_s = {dt_s:g} s ({duration_s / dt_s:.6g}); use e.g. duration_s = "
                         f"{n * dt_s:g} s")
    if isinstance(controller, GapController):
        if initial_flux_Wb is None and not (
                math.isclose(initial_gap_m, controller.gap_ref_m, rel_tol=1e-12)
                and np.allclose(initial_current_A, controller.bias_current_A, rtol=1e-12,
                                atol=0.0)):
            raise InputError("give initial_flux_Wb when the run does not start at the "
                             "controller's design point")
        ctl: Controller = CascadeController(controller, initial_flux_Wb=initial_flux_Wb)
    elif isinstance(controller, Controller):
        if initial_flux_Wb is not None:
            raise InputError("initial_flux_Wb is only for a GapController design; give "
                             "other controllers their initial estimate directly")
        ctl = controller
    else:
        raise InputError("controller must be a GapController or implement the Controller "
                         f"interface (reset, update, diagnostics), got {type(controller).__name__}")
    ref = gap_reference_m or (lambda t: ctl.gap_ref_m)
    ext = external_force or (lambda t: 0.0)
    st = model.initial_state(gaps_m=initial_gap_m, currents_A=initial_current_A)
    out = model.outputs(st)
    mech = HeaveState(initial_gap_m, 0.0)
    nc, ng = len(model.circuit_names), len(model.gap_names)
    T = np.arange(n + 1) * dt_s
    S, V, R, CT = np.empty(n + 1), np.empty(n + 1), np.empty(n + 1), np.empty(n + 1)
    U, I, Psi = np.empty((n + 1, nc)), np.empty((n + 1, nc)), np.full((n + 1, nc), np.nan)
    P, lim = np.empty((n + 1, ng)), np.zeros(n + 1, dtype=bool)
    diag: dict[str, list[Any]] = {}
    S[0], V[0], I[0], P[0] = mech.gap_m, 0.0, out.currents_A, out.pole_force_N
    limit = ctl.voltage_limit_V

    def sample(k: int) -> np.ndarray:
        R[k] = ref(float(T[k]))
        meas = Measurement(float(T[k]), S[k], V[k], I[k].copy(), float(R[k]))
        if k == 0:
            ctl.reset(meas, sample_time_s=dt_s)
        t0 = time.perf_counter()
        u = np.asarray(ctl.update(meas), dtype=float).reshape(nc)
        CT[k] = time.perf_counter() - t0
        d = ctl.diagnostics()
        if "flux_estimate_Wb" in d:
            Psi[k] = d["flux_estimate_Wb"]
        for key, v in d.items():
            diag.setdefault(key, []).append(v)
        return u

    for k in range(n):
        check_interrupt()          # a deferred Ctrl-C (CLI): between steps, not in CasADi
        t = T[k]
        u = sample(k)
        lim[k] = bool(np.any(np.abs(u) >= limit))
        U[k] = u
        if not mech.gap_m + mech.gap_rate_m_per_s * dt_s > 0:
            raise SolverError(
                "TOUCHDOWN: the magnet would hit the rail within the next step",
                time_s=float(t), state={"gap_m": mech.gap_m,
                                      "gap_rate_m_per_s": mech.gap_rate_m_per_s},
                reason="the closed loop is unstable for this case (controller, "
                       "reference or disturbance)")
        force = float(out.force_N)
        st, out = model.step(st, dt_s, u, gaps_m=mech.gap_m,
                             gap_rates_m_per_s=mech.gap_rate_m_per_s)
        mech = vehicle.step(mech, dt_s, force, ext(t))
        S[k + 1], V[k + 1], I[k + 1], P[k + 1] = (
            mech.gap_m, mech.gap_rate_m_per_s, out.currents_A, out.pole_force_N)
    sample(n)           # the estimates at the end (the voltages are not applied)
    U[n] = U[n - 1]
    CT[n] = CT[n - 1]
    return ClosedLoopResult(T, S, V, U, I, Psi, P, P.sum(axis=1), lim,
                            tuple(model.circuit_names), tuple(model.gap_names), R, CT,
                            {k: np.asarray(v) for k, v in diag.items()})
