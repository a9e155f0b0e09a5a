"""Virtual experiments on the flux model: voltage step response, L~ from a step (paper IV-B).

The paper identifies the small-signal differential inductance ``L~(s, I)`` from the time
constant of the current after a small voltage step at a fixed gap.  Around an operating
point the reduced model (paper eq. 8, docs/sources.md sec. 5) is a resistor ``R_el`` in series
with ``L~`` shunted by the eddy-current resistance ``R_ec``::

    dI(t) = dU/R_el - (dU/R_el - dI_0) exp(-t / tau),   dI_0 = dU / (R_el + R_ec)
    tau   = L~ (R_el + R_ec) / (R_el R_ec)   =>   L~ = tau R_el (1 - dI_0 / dI_inf)

so the current jump ``dI_0`` gives ``R_ec`` and the time constant gives ``L~``.  Without
eddy currents ``dI_0 = 0`` and ``L~ = tau R_el``.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, SolverError
from ..validation import real_number, renamed_keywords, whole_number
from .flux import FluxModel, SimulationResult, check_options, simulate_flux
from .statics import solve_statics

__all__ = ["InductanceEstimate", "StepFit", "voltage_step_response",
           "differential_inductance_from_step", "fit_step_response"]


def _model(model: Any, options: dict[str, Any]) -> FluxModel:
    check_options(options, "the step experiment")
    if isinstance(model, FluxModel):
        return model.with_options(**options) if options else model
    return FluxModel(model, **options)


@renamed_keywords(gap="gap_m", voltage="voltage_V", initial_current="initial_current_A",
                  duration="duration_s", dt="dt_s")
def voltage_step_response(model: Any, *, gap_m: Any, voltage_V: Any, initial_current_A: Any = 0.0,
                          duration_s: float, dt_s: float, **options: Any) -> SimulationResult:
    """Current and force after a voltage step at ``t = 0`` at a fixed gap.

    The magnet starts at the static operating point with ``initial_current_A`` (held by
    ``U = R I``); from ``t = 0`` the circuits get ``voltage_V``.

    Old keyword names (``gap``, ``voltage``, ``initial_current``, ``duration``, ``dt``) are
    deprecated aliases for one release.

    Parameters
    ----------
    model : FluxModel, Magnet or Network
        The magnet model (a Magnet or Network is wrapped in a :class:`FluxModel` with
        ``options``; a FluxModel's own options are overridden by ``options``).
    gap_m : float, sequence or mapping
        Fixed gap(s) [m], > 0.
    voltage_V : float, sequence or mapping
        Voltage(s) after the step [V].
    initial_current_A : float, sequence or mapping
        Current(s) before the step [A].
    duration_s, dt_s : float
        Simulated time and output step [s].
    **options
        FluxModel options (``saturation``, ``eddy_currents``, ``rtol``, ...).
    """
    fm = _model(model, options)
    st = fm.initial_state(gaps_m=gap_m, currents_A=initial_current_A)
    return simulate_flux(fm, (0.0, duration_s), dt_s=dt_s, gaps_m=st.gaps_m, voltages_V=voltage_V,
                    initial_state=st)


@dataclass(frozen=True)
class InductanceEstimate:
    """Result of :func:`differential_inductance_from_step` (one circuit).

    Attributes
    ----------
    inductance_H : float
        ``L~ = tau R_el (1 - dI_0/dI_inf)`` [H], the paper's differential inductance.
    apparent_inductance_H : float
        ``tau R_el`` [H] (what a fit ignoring the eddy-current jump reports).
    time_constant_s : float
        Fitted ``tau`` [s].
    current_jump_A : float
        Instantaneous current jump ``dI_0`` [A] (0 without eddy currents).
    final_current_change_A : float
        ``dI_inf = dU / R_el`` [A].
    eddy_resistance_ohm : float
        ``R_ec = dU/dI_0 - R_el`` [ohm] (inf without eddy currents).
    fit_rms : float
        RMS of the log-linear fit residual (relative deviation from one exponential).
    response : SimulationResult
        The simulated step.
    """

    inductance_H: float
    apparent_inductance_H: float
    time_constant_s: float
    current_jump_A: float
    final_current_change_A: float
    eddy_resistance_ohm: float
    fit_rms: float
    response: SimulationResult


@renamed_keywords(gap="gap_m", current="current_A")
def differential_inductance_from_step(model: Any, *, gap_m: float, current_A: float,
                                      relative_step: float = 1e-3, circuit: int = 0,
                                      samples_per_tau: int = 200, n_tau: float = 6.0,
                                      rtol: float = 1e-9, atol: float = 1e-11,
                                      **options: Any) -> InductanceEstimate:
    """Identify ``L~(s, I)`` from the time constant of a small voltage step (paper IV-B).

    The circuit ``circuit`` is held at ``current_A`` at the (uniform) ``gap_m``, then
    its voltage steps by ``dU = R_el dI_inf`` with ``dI_inf = relative_step x max(|I|,
    1 A)``; the other circuits keep their voltage.  ``log(dI_inf - dI(t))`` is fitted by
    a straight line (least squares) over the samples with ``2 % < remaining < 98 %``.

    The time window (``n_tau`` time constants, ``samples_per_tau`` samples each) is
    sized with the statics' ``dpsi/dI``; that estimate is not used in the result.

    Old keyword names (``gap``, ``current``) are deprecated aliases for one release.

    Parameters
    ----------
    model : FluxModel, Magnet or Network
        The magnet model (a Magnet or Network is wrapped in a :class:`FluxModel`).
    gap_m : float
        Gap of every pole [m], > 0 (keyword only, like all that follow).
    current_A : float
        Operating current of every circuit [A] before the step.
    relative_step : float, default 1e-3
        Size of the final current change relative to ``max(|I|, 1 A)`` [-], in
        (0, 0.1): small enough for the response to be linear.
    circuit : int, default 0
        Index of the circuit whose voltage steps, ``0 .. n_circuits - 1``.
    samples_per_tau : int, default 200
        Output samples per estimated time constant (whole number >= 1).
    n_tau : float, default 6.0
        Length of the simulated window in estimated time constants, > 0.
    rtol, atol : float, default 1e-9 and 1e-11
        Integrator tolerances of the flux model [-] (``atol`` relative to the model's
        nominal scales, see :class:`FluxModel`); tighter than the FluxModel defaults,
        because the step is small.
    **options
        Further FluxModel options (``saturation``, ``eddy_currents``, ...).

    Returns
    -------
    InductanceEstimate

    Raises
    ------
    InputError
        ``relative_step`` outside (0, 0.1), ``samples_per_tau`` not a whole number
        >= 1, ``n_tau`` not > 0, ``circuit`` not an index of a circuit, unknown
        options or bad gap or current.
    SolverError
        Fewer than 10 samples between 2 % and 98 % of the step (window too short or
        too coarse), a response that is not a decaying exponential, or a failed
        simulation.
    """
    if not 0.0 < real_number(relative_step, "relative_step") < 0.1:
        raise InputError(f"relative_step = {relative_step!r} must lie in (0, 0.1)")
    samples_per_tau = whole_number(samples_per_tau, "samples_per_tau", minimum=1)
    n_tau = real_number(n_tau, "n_tau", positive=True)
    fm = _model(model, {"rtol": rtol, "atol": atol, **options})
    nc = len(fm.circuit_names)
    if isinstance(circuit, bool) or not isinstance(circuit, numbers.Integral) \
            or not 0 <= circuit < nc:
        raise InputError(f"circuit = {circuit!r} must be an index in 0..{nc - 1}")
    st = fm.initial_state(gaps_m=gap_m, currents_A=current_A)
    R = fm.resistances
    sol = solve_statics(fm.network, gaps_m=st.gaps_m, currents_A=st.currents_A)
    l_est = float(sol.differential_inductance_H[circuit, circuit])
    r_par = R[circuit]
    tau_est = max(l_est, 1e-12) / r_par
    di_inf = relative_step * max(abs(float(st.currents_A[circuit])), 1.0)
    U = R * st.currents_A
    U[circuit] += r_par * di_inf
    dt = tau_est / samples_per_tau
    res = simulate_flux(fm, (0.0, n_tau * tau_est), dt_s=dt, gaps_m=st.gaps_m, voltages_V=U,
                   initial_state=st)
    di = res.currents_A[:, circuit] - st.currents_A[circuit]
    t = res.time_s
    sel = t > 0.0
    try:
        fit = fit_step_response(t[sel], di[sel] / di_inf)
    except SolverError as exc:
        raise SolverError(str(exc).split(";")[0], state={"gap_m": gap_m, "current_A": current_A},
                          reason=exc.reason) from None
    tau = fit.time_constant_s
    jump = fit.jump_fraction * di_inf
    # Without eddy currents the jump is zero; the fit's intercept then has the size of
    # the fit error, so it is not used.
    if not fm.has_eddy_currents:
        jump = 0.0
    r_ec = math.inf if jump <= 0.0 else r_par * di_inf / jump - r_par
    return InductanceEstimate(
        inductance_H=tau * r_par * (1.0 - max(jump, 0.0) / di_inf),
        apparent_inductance_H=tau * r_par,
        time_constant_s=tau, current_jump_A=jump, final_current_change_A=di_inf,
        eddy_resistance_ohm=r_ec, fit_rms=fit.rms, response=res)


@dataclass(frozen=True)
class StepFit:
    """A single-exponential fit of a normalised step response (:func:`fit_step_response`).

    Attributes
    ----------
    time_constant_s : float
        ``tau`` [s].
    jump_fraction : float
        ``dI_0/dI_inf``: the jump at ``t = 0`` the fit extrapolates, relative to the final
        change (0 without eddy currents, up to the fit's error).
    rms : float
        RMS of the residual of ``log(1 - x)`` (relative deviation from one exponential).
    """

    time_constant_s: float
    jump_fraction: float
    rms: float


def fit_step_response(time_s: np.ndarray, response: np.ndarray) -> StepFit:
    """Fit ``x(t) = 1 - (1 - x_0) exp(-t/tau)`` to a normalised step response (paper IV-B).

    ``response`` is ``dI(t)/dI_inf`` at ``time_s > 0``; ``log(1 - x)`` is fitted by a
    straight line (least squares) over the samples with ``2 % < 1 - x < 98 %``.

    Raises
    ------
    SolverError
        Fewer than 10 usable samples, or no decaying exponential.
    """
    t = np.asarray(time_s, dtype=float)
    remaining = 1.0 - np.asarray(response, dtype=float)
    sel = np.isfinite(remaining) & (remaining > 0.02) & (remaining < 0.98)
    if np.count_nonzero(sel) < 10:
        raise SolverError("too few samples to fit the step-response time constant",
                          reason=f"{np.count_nonzero(sel)} usable samples (2-98 % of the step)")
    A = np.vstack((np.ones(np.count_nonzero(sel)), t[sel])).T
    coef, *_ = np.linalg.lstsq(A, np.log(remaining[sel]), rcond=None)
    fit = A @ coef - np.log(remaining[sel])
    tau = -1.0 / float(coef[1]) if coef[1] != 0.0 else math.inf
    if not (tau > 0.0 and math.isfinite(tau)):
        raise SolverError("step response is not a decaying exponential", reason=f"tau = {tau}")
    return StepFit(time_constant_s=tau, jump_fraction=1.0 - math.exp(float(coef[0])),
                   rms=float(np.sqrt(np.mean(fit**2))))
