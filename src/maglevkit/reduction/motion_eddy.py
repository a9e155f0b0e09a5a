"""Eq. 8 with a shielded gap section: a reduced model whose motion-induced current passes
through eddy dynamics (our extension of the paper's Fig. 8; docs/reduction.md, "Gap motion").

In Fig. 8 the motion-induced voltage ``dL/ds I_L ds/dt`` sits in the same node as the
eddy resistor and the coil: whatever the gap does, the coil sees a fixed fraction
``1/(1 + R_el/R_ec)`` of the motion-induced current, with no phase.  In the detailed
network the iron's eddy currents shield the gap's flux change from the coil (the coil
current falls like ``1/f`` above ~100 Hz on the TR09 standard magnet), while a voltage
step still makes the coil current jump.  Both are kept by a ladder of three elements per
circuit, read from the coil terminals::

    U --R_el--+--L_u--+----------+
              |       |          |
             R_a     R_2    L(s, I_L), EMF dL/ds I_L ds/dt
              |       |          |
    ----------+-------+----------+

* ``R_a`` shunts the coil directly: the current jump of a voltage step (``dU/(R_el + R_a)``);
* ``L_u``: the flux linkage not behind the iron's eddy currents (leakage), constant;
* ``R_2``: the eddy currents that shield the gap section ``L(s, I_L)``, whose differential
  inductance is ``L~(s, I_L) - L_u`` and which carries the motion-induced voltage.

States per circuit: ``I_L`` (the gap section's current; force ``F(s, I_L)`` as in eq. 8)
and ``I_e = I_u - I_L`` (the shielding eddy current through ``R_2``; ``I_u`` is the
current through ``L_u``)::

    a = 1 + R_el/R_a,   V_A = (U - R_el (I_L + I_e))/a,   V_m = R_2 I_e
    (L~ - L_u) dI_L/dt = V_m - dL/ds I_L ds/dt
    L_u dI_e/dt = V_A - V_m - L_u dI_L/dt
    I = (U - V_A)/R_el

``L_u -> 0`` gives eq. 8 with ``R_ec = R_a R_2/(R_a + R_2)``.  The parameters are fitted to
the detailed model's small-signal responses (gap -> coil current and voltage -> coil
current) at one operating point: the detailed DAE is linearised there
(:func:`detailed_frequency_response`) and the ladder's closed-form transfer functions
(:func:`ladder_frequency_response`) are fitted by least squares (:func:`fit_motion_eddy`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import MaglevkitWarning, SolverError

__all__ = ["DetailedFrequencyResponse", "MotionEddyFit", "detailed_frequency_response",
           "fit_motion_eddy", "ladder_frequency_response",
           "relative_rms_residual", "FIT_FREQUENCIES_HZ"]

#: Frequencies of the fit [Hz]: 0.1 Hz .. 1 kHz, 60 points evenly spaced in log f.
FIT_FREQUENCIES_HZ = np.geomspace(0.1, 1000.0, 60)


@dataclass(frozen=True)
class DetailedFrequencyResponse:
    """Small-signal responses of the detailed (flux-based) model of one circuit.

    At the steady state with every gap at ``gap_m`` and every current at ``current_A``
    (voltages ``R_el I``), linearised exactly (CasADi AD of the DAE).

    Attributes
    ----------
    frequencies_Hz : ndarray (n_f,)
    gap_to_current_A_per_m : ndarray (n_f,), complex
        Coil current per gap of the circuit's own poles moving together [A/m].
    gap_to_force_N_per_m : ndarray (n_f,), complex
        Circuit force (its poles' sum) per gap [N/m].
    voltage_to_current_A_per_V : ndarray (n_f,), complex
        Coil current per coil voltage [A/V] (the other circuits' voltages held).
    differential_inductance_H : float
        ``L~ = dpsi_j/dI_j`` of the statics there [H].
    dpsi_ds_Wb_per_m : float
        ``dpsi_j/ds`` over the circuit's own poles [Wb/m] (``dL/ds I``).
    """

    frequencies_Hz: np.ndarray
    gap_to_current_A_per_m: np.ndarray
    gap_to_force_N_per_m: np.ndarray
    voltage_to_current_A_per_V: np.ndarray
    differential_inductance_H: float
    dpsi_ds_Wb_per_m: float


def detailed_frequency_response(net: Any, *, gap: float, current: float,
                                frequencies_Hz: Any = FIT_FREQUENCIES_HZ,
                                groups: dict[str, tuple[str, ...]] | None = None
                                ) -> list[DetailedFrequencyResponse]:
    """Linearise the detailed DAE at a steady state and evaluate its frequency responses.

    The flux model (``models/flux.py``) is ``y' = K^+ h(x, I, U, s)``, ``0 = g(y, x, I, U, s)``
    (``g = [D x - y; Q h]``) with differential ``y`` and algebraic ``z = (x, I)``; ``g_z`` is
    regular (index 1), so ``dz = -g_z^-1 (g_y dy + g_w dw)`` and
    ``(p - A) dy = B dw`` with ``A = f_y - f_z g_z^-1 g_y``, ``B = f_w - f_z g_z^-1 g_w``
    for the inputs ``w = (s, U)``.  Evaluated at ``p = 2 pi i f``.

    Parameters
    ----------
    net : Network
    gap, current : float
        Operating point: every gap [m], every circuit current [A].
    frequencies_Hz : array_like
        Frequencies [Hz].
    groups : dict, optional
        Circuit -> its poles (gap inputs); default :func:`circuit_pole_groups` there.

    Returns
    -------
    list of DetailedFrequencyResponse
        One per circuit.
    """
    import casadi as ca

    from ..circuit.assembly import assemble
    from ..models.flux import flux_dae
    from ..models.statics import circuit_pole_groups, solve_statics

    freqs = np.asarray(frequencies_Hz, dtype=float)
    d = flux_dae(net, "idas", 1e-9, 1e-11, 20000, 2, 3)
    eq = assemble(net)
    nc, ng = len(net.circuits), len(net.gap_names)
    y = ca.SX.sym("y", d.n_diff)
    U = ca.SX.sym("U", nc)
    hv = ca.vertcat(-eq.residual, U - net.resistances * eq.I)
    ydot = ca.mtimes(ca.DM(np.linalg.pinv(d.K)), hv)
    alg = ca.vertcat(ca.mtimes(ca.DM(d.D), eq.x) - y, ca.mtimes(ca.DM(d.Q), hv))
    z = ca.vertcat(eq.x, eq.I)
    w = ca.vertcat(eq.s, U)
    jac = ca.Function("detailed_linearisation", [y, z, w],
                      [ca.jacobian(ydot, y), ca.jacobian(ydot, z), ca.jacobian(ydot, w),
                       ca.jacobian(alg, y), ca.jacobian(alg, z), ca.jacobian(alg, w),
                       ca.jacobian(eq.force, z), ca.jacobian(eq.force, w)])
    sol = solve_statics(net, gaps_m=np.full(ng, gap), currents_A=np.full(nc, current))
    x0 = np.asarray(sol.loop_flux_Wb, dtype=float).ravel()
    i0 = np.asarray(sol.currents_A, dtype=float).ravel()
    s0 = np.asarray(sol.gaps_m, dtype=float).ravel()
    fy, fz, fw, gy, gz, gw, force_z, force_w = (
        np.asarray(v, dtype=float) for v in jac(d.D @ x0, np.concatenate((x0, i0)),
                                                np.concatenate((s0, net.resistances * i0))))
    try:
        gzi_gy = np.linalg.solve(gz, gy)
        gzi_gw = np.linalg.solve(gz, gw)
    except np.linalg.LinAlgError:
        raise SolverError("the detailed DAE's algebraic Jacobian is singular at the "
                          "identification point", state={"gap_m": gap, "current_A": current}
                          ) from None
    a = fy - fz @ gzi_gy
    b = fw - fz @ gzi_gw
    cz, dz = -gzi_gy, -gzi_gw
    if groups is None:
        groups = circuit_pole_groups(net, gap_m=gap, current_A=current)
    gi = {g: k for k, g in enumerate(net.gap_names)}
    eye = np.eye(a.shape[0])
    nl = d.n_loops
    out = []
    for j, c in enumerate(net.circuit_names):
        own = [gi[g] for g in groups[c]]
        win = np.zeros((ng + nc, 2))
        win[own, 0] = 1.0            # the circuit's own poles move together
        win[ng + j, 1] = 1.0         # its voltage
        res = np.empty((freqs.size, 3), dtype=complex)
        for k, f in enumerate(freqs):
            yy = np.linalg.solve(2j * np.pi * f * eye - a, b @ win)
            zz = cz @ yy + dz @ win
            force = (force_z @ zz + force_w @ win)[own].sum(axis=0)
            res[k] = (zz[nl + j, 0], force[0], zz[nl + j, 1])
        out.append(DetailedFrequencyResponse(
            freqs, res[:, 0], res[:, 1], res[:, 2],
            float(sol.differential_inductance_H[j, j]),
            float(np.asarray(sol.dpsi_dgap_Wb_per_m)[j, own].sum())))
    return out


def ladder_frequency_response(frequencies_Hz: Any, *, ltilde: float, dpsi_ds: float,
                              r_el: float, r_a: float, l_u: float, r_2: float
                              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-form small-signal responses of the shielded-gap ladder (module docstring).

    Linearised at a steady state (``I_e = 0``, ``V_m = 0``), with ``k = dL/ds I_L =
    dpsi/ds`` and ``a = 1 + R_el/R_a``; unknowns ``I_u = I_L + I_e`` and ``I_L``::

        [p L_u + R_el/a + R_2,   -R_2            ] [I_u]   [U/a     ]
        [-R_2,          p (L~ - L_u) + R_2       ] [I_L] = [-k p s  ]

        I = (1 - 1/a) U/R_el + I_u/a

    Parameters
    ----------
    frequencies_Hz : array_like
    ltilde : float
        ``L~`` [H].
    dpsi_ds : float
        ``dL/ds I_L`` [Wb/m].
    r_el, r_a, l_u, r_2 : float
        ``R_el``, ``R_a`` [ohm], ``L_u`` [H], ``R_2`` [ohm].

    Returns
    -------
    gap_to_current_A_per_m, gap_to_inductor_current_A_per_m, voltage_to_current_A_per_V : ndarray
        Complex, per frequency: ``dI/ds``, ``dI_L/ds`` (the force's current) and ``dI/dU``.
    """
    p = 2j * np.pi * np.asarray(frequencies_Hz, dtype=float)
    a = 1.0 + r_el / r_a
    m11 = p * l_u + r_el / a + r_2
    m22 = p * (ltilde - l_u) + r_2
    det = m11 * m22 - r_2 * r_2
    # gap input: rhs (0, -k p)
    iu_s = (r_2 * (-dpsi_ds * p)) / det
    il_s = (m11 * (-dpsi_ds * p)) / det
    # voltage input: rhs (1/a, 0)
    iu_u = (m22 / a) / det
    return iu_s / a, il_s, (1.0 - 1.0 / a) / r_el + iu_u / a


def relative_rms_residual(response: DetailedFrequencyResponse, gap_to_current: np.ndarray,
                          voltage_to_current: np.ndarray) -> float:
    """RMS over frequencies and both responses of ``(model - detailed)/|detailed|`` (real
    and imaginary parts; the gap response is left out where the detailed one is 0)."""
    return float(np.sqrt(np.mean(_residuals(response, gap_to_current, voltage_to_current)
                                 ** 2)))


def _residuals(response: DetailedFrequencyResponse, gap_to_current: np.ndarray,
               voltage_to_current: np.ndarray) -> np.ndarray:
    gs, gu = response.gap_to_current_A_per_m, response.voltage_to_current_A_per_V
    ns = np.abs(gs)
    # at I = 0 the gap does not move the current (dpsi/ds = 0): the voltage path only
    ws = 1.0 if np.all(ns > 0) else 0.0
    es = ws * (gap_to_current - gs) / np.where(ns > 0, ns, 1.0)
    eu = (voltage_to_current - gu) / np.abs(gu)
    return np.concatenate((es.real, es.imag, eu.real, eu.imag))


@dataclass(frozen=True)
class MotionEddyFit:
    """Fitted shielded-gap ladder of one circuit.

    Attributes
    ----------
    jump_resistance_ohm : float
        ``R_a`` [ohm].
    unshielded_inductance_H : float
        ``L_u`` [H].
    shielding_resistance_ohm : float
        ``R_2`` [ohm].
    rms_residual : float
        RMS of the residuals (each response relative to its modulus) over the fit's
        frequencies and both responses.
    max_gap_error, max_voltage_error : float
        Largest ``|model/detailed - 1|`` of the gap -> current and voltage -> current
        responses over the fit's frequencies.
    """

    jump_resistance_ohm: float
    unshielded_inductance_H: float
    shielding_resistance_ohm: float
    rms_residual: float
    max_gap_error: float
    max_voltage_error: float


def fit_motion_eddy(response: DetailedFrequencyResponse, *, r_el: float, r_ec_jump: float,
                    r_ec_fit: float) -> MotionEddyFit:
    """Least-squares fit of ``R_a``, ``L_u``, ``R_2`` to a detailed frequency response.

    Residuals: ``(model - detailed)/|detailed|`` of gap -> current and voltage -> current
    at every frequency (real and imaginary parts, equal weights).  Parameters are fitted as
    ``log R_a``, ``log R_2`` and ``logit(L_u/L~)`` (so ``0 < L_u < L~``), with scipy's
    trust-region least squares from several starts: ``R_a`` at the exact jump value
    ``r_ec_jump`` (and 3x, 1/3x), ``R_2`` such that ``R_a || R_2`` is the step fit's
    ``r_ec_fit`` (else 3 ``r_ec_fit``), ``L_u/L~`` 1 % and 5 %.

    Parameters
    ----------
    response : DetailedFrequencyResponse
    r_el : float
        ``R_el`` [ohm].
    r_ec_jump, r_ec_fit : float
        Eq. 8's ``R_ec`` from the exact jump and from the step's time constant [ohm].
    """
    from scipy.optimize import least_squares

    lt, k = response.differential_inductance_H, response.dpsi_ds_Wb_per_m
    f = response.frequencies_Hz
    gs, gu = response.gap_to_current_A_per_m, response.voltage_to_current_A_per_V

    def unpack(x: np.ndarray) -> tuple[float, float, float]:
        return float(np.exp(x[0])), float(lt / (1.0 + np.exp(-x[1]))), float(np.exp(x[2]))

    def resid(x: np.ndarray) -> np.ndarray:
        r_a, l_u, r_2 = unpack(x)
        ms, _, mu = ladder_frequency_response(f, ltilde=lt, dpsi_ds=k, r_el=r_el, r_a=r_a,
                                              l_u=l_u, r_2=r_2)
        return _residuals(response, ms, mu)

    r_a0 = r_ec_jump if np.isfinite(r_ec_jump) and r_ec_jump > 0 else 3.0 * r_ec_fit
    best = None
    for ra in (r_a0, 3.0 * r_a0, r_a0 / 3.0):
        g2 = 1.0 / r_ec_fit - 1.0 / ra
        r2 = 1.0 / g2 if g2 > 0 else 3.0 * r_ec_fit
        for frac in (0.01, 0.05):
            x0 = np.array([np.log(ra), np.log(frac / (1.0 - frac)), np.log(r2)])
            sol = least_squares(resid, x0, xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=2000)
            if best is None or sol.cost < best.cost:
                best = sol
    assert best is not None
    if best.status <= 0:
        warnings.warn(f"the motion-eddy ladder fit did not converge (status {best.status}: "
                      f"{best.message}; {best.nfev} evaluations): its R_a, L_u, R_2 are those "
                      "where it stopped (see its relative rms residual)", MaglevkitWarning,
                      stacklevel=2)
    r_a, l_u, r_2 = unpack(best.x)
    ms, _, mu = ladder_frequency_response(f, ltilde=lt, dpsi_ds=k, r_el=r_el, r_a=r_a,
                                          l_u=l_u, r_2=r_2)
    moving = bool(np.all(np.abs(gs) > 0))
    return MotionEddyFit(r_a, l_u, r_2, relative_rms_residual(response, ms, mu),
                         float(np.max(np.abs(ms / gs - 1.0))) if moving else float("nan"),
                         float(np.max(np.abs(mu / gu - 1.0))))
