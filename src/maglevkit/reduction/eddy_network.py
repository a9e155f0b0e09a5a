"""An RL eddy network for the current-based model: Fig. 8 with more than one eddy mode.

The paper's Fig. 8 (eq. 8) puts one resistor ``R_ec`` in parallel with the inductance
``L~(s, I_L)``.  Here the eddy branch is a Foster admittance (docs/reduction.md)::

    Y_e(p) = 1/R_0 + sum_k 1/(R_k + p L_k),      k = 1..m

in parallel with ``L~``, so that per circuit (``U = R_el I + U_L``)::

    U_L      = (U - R_el (I_L + sum_k I_k)) / (1 + R_el/R_0)
    L~ dI_L/dt = U_L - dL/ds I_L ds/dt
    L_k dI_k/dt = U_L - R_k I_k
    I        = I_L + U_L/R_0 + sum_k I_k  =  (U - U_L)/R_el

At fixed gap and for a small voltage step the network is linear; this module gives its
step response in closed form (:func:`network_step_response`) and fits ``R_0, R_k, L_k``
to a step response of the detailed model (:func:`fit_eddy_network`).  ``m = 0`` with
``R_0 = R_ec`` is eq. 8.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..magnets.base import REDUCED_EDDY_MODES

__all__ = ["EDDY_NETWORK_MODES", "EddyNetworkFit", "fit_eddy_network", "network_step_response"]

#: The numbers of RL branches the maps store a fit for (``CurrentModel(eddy_modes=m)``):
#: the nonzero values of :data:`maglevkit.magnets.base.REDUCED_EDDY_MODES`.
EDDY_NETWORK_MODES = tuple(m for m in REDUCED_EDDY_MODES if m)


def network_step_response(t: np.ndarray, *, ltilde: float, r_el: float, r0: float,
                          rk: np.ndarray, lk: np.ndarray) -> np.ndarray:
    """Coil-current response ``dI(t)/dU`` [A/V] of the network to a unit voltage step at
    ``t = 0`` (all states at rest before), in closed form.

    The states ``z = (I_L, I_1..I_m)`` obey ``M z' = S z + e dU/a`` with
    ``M = diag(L~, L_1..L_m)``, ``S = -(R_el/a) e e^T - diag(0, R_1..R_m)`` (symmetric,
    negative definite: an RL network has real, negative natural frequencies) and
    ``a = 1 + R_el/R_0``; with ``W = M^-1/2 S M^-1/2 = Q diag(lam) Q^T``:
    ``z(t) = M^-1/2 Q diag((exp(lam t) - 1)/lam) Q^T M^-1/2 e dU/a`` and
    ``dI = dU (1 - 1/a)/R_el + e^T z/a``.

    Parameters
    ----------
    t : array_like
        Times after the step [s] (>= 0).
    ltilde : float
        Differential inductance ``L~`` of the main branch [H], > 0 (keyword only, like
        all that follow).
    r_el : float
        Circuit resistance ``R_el`` [ohm], > 0.
    r0 : float
        Resistance ``R_0`` of the instantaneous eddy path [ohm] (``inf``: none).
    rk : array_like (m,)
        Resistances ``R_1 .. R_m`` of the eddy branches [ohm], > 0.
    lk : array_like (m,)
        Inductances ``L_1 .. L_m`` of the eddy branches [H], > 0.

    Returns
    -------
    ndarray
        ``dI(t) / dU`` [A/V], shape of ``t``.  Inputs are not checked.
    """
    rk = np.atleast_1d(np.asarray(rk, dtype=float))
    lk = np.atleast_1d(np.asarray(lk, dtype=float))
    t = np.asarray(t, dtype=float)
    a = 1.0 + (r_el / r0 if np.isfinite(r0) else 0.0)
    n = rk.size + 1
    e = np.ones(n)
    m_half = 1.0 / np.sqrt(np.concatenate(([ltilde], lk)))
    s = -(r_el / a) * np.outer(e, e) - np.diag(np.concatenate(([0.0], rk)))
    w = m_half[:, None] * s * m_half[None, :]
    lam, q = np.linalg.eigh(0.5 * (w + w.T))
    v = q.T @ (m_half * e) / a                       # (n,)
    g = np.expm1(np.outer(t, lam)) / lam             # (n_t, n)
    z = (g * v) @ q.T * m_half                       # (n_t, n)
    return (1.0 - 1.0 / a) / r_el + z.sum(axis=1) / a


@dataclass(frozen=True)
class EddyNetworkFit:
    """Fitted eddy network of one circuit (``m`` modes).

    Attributes
    ----------
    r0_ohm : float
        Series-free resistor ``R_0`` (``inf``: no instantaneous current jump).
    resistance_ohm, inductance_H : ndarray (m,)
        ``R_k``, ``L_k`` of the ``m`` RL branches (ordered by ``L_k/R_k``, fastest first).
    rms_residual : float
        RMS of (model - data) over the fitted samples, relative to the step's final value.
    max_residual : float
        Largest |model - data| over the samples, relative to the step's final value.
    """

    r0_ohm: float
    resistance_ohm: np.ndarray
    inductance_H: np.ndarray
    rms_residual: float
    max_residual: float


#: R_0 above this multiple of R_el counts as "no jump" (stored as inf): its jump
#: ``dU/(R_el + R_0)`` is then below 1e-4 of the step's final value.
_R0_OPEN = 1e4


def fit_eddy_network(t: np.ndarray, response: np.ndarray, *, ltilde: float, r_el: float,
                     modes: int, r_ec_guess: float, weights: np.ndarray | None = None,
                     start: EddyNetworkFit | None = None) -> EddyNetworkFit:
    """Least-squares fit of ``R_0, R_k, L_k`` (``k = 1..modes``) to a step response.

    Parameters
    ----------
    t, response : ndarray
        Sample times [s] after the step and the detailed model's ``dI/dU`` [A/V] there.
    ltilde, r_el : float
        ``L~`` at the operating point [H] (from the maps; fixed) and ``R_el`` [ohm].
    modes : int
        Number of RL branches ``m >= 1``.
    r_ec_guess : float
        The single-exponential ``R_ec`` (starting point).
    weights : ndarray, optional
        Per-sample weights of the residual (default 1).
    start : EddyNetworkFit, optional
        A fit with ``modes - 1`` branches to start from (its branches are kept, a faster
        one is added); ignored with another number of branches.

    Returns
    -------
    EddyNetworkFit
        Branches ordered by time constant ``L_k / R_k`` (fastest first); ``R_0 = inf``
        when the fit opens the instantaneous path.

    Notes
    -----
    The parameters are fitted as logarithms (all stay positive: a physical RL network),
    with scipy's trust-region least squares; the residual is relative to the final
    value ``1/R_el``.  Inputs are not checked.
    """
    from scipy.optimize import least_squares

    t = np.asarray(t, dtype=float)
    y = np.asarray(response, dtype=float) * r_el           # relative to the final value
    w = np.ones_like(t) if weights is None else np.asarray(weights, dtype=float)
    tau_slow = ltilde / r_el
    if start is not None and start.resistance_ohm.size == modes - 1:
        r0 = min(start.r0_ohm, _R0_OPEN * r_el)
        tau_old = start.inductance_H / start.resistance_ohm
        tau_new = float(np.min(tau_old)) / 5.0
        rk = np.concatenate((start.resistance_ohm, [3.0 * r_ec_guess * modes]))
        lk = np.concatenate((start.inductance_H, [3.0 * r_ec_guess * modes * tau_new]))
    else:
        r0 = 3.0 * r_ec_guess
        tau = tau_slow * np.geomspace(3e-2, 3e-3, modes)
        rk = np.full(modes, r_ec_guess * modes)
        lk = rk * tau
    x0 = np.log(np.concatenate(([r0], rk, lk)))
    lo = np.log(np.concatenate(([1e-3 * r_el], np.full(modes, 1e-3 * r_el),
                                np.full(modes, 1e-9 * ltilde))))
    hi = np.log(np.concatenate(([_R0_OPEN * r_el * 10], np.full(modes, 1e6 * r_el),
                                np.full(modes, 10.0 * ltilde))))
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)

    def resid(x: np.ndarray) -> np.ndarray:
        p = np.exp(x)
        model = network_step_response(t, ltilde=ltilde, r_el=r_el, r0=p[0],
                                      rk=p[1:modes + 1], lk=p[modes + 1:]) * r_el
        return w * (model - y)

    sol = least_squares(resid, x0, bounds=(lo, hi), x_scale=1.0, xtol=1e-12, ftol=1e-12,
                        gtol=1e-12, max_nfev=4000)
    p = np.exp(sol.x)
    r0, rk, lk = float(p[0]), p[1:modes + 1], p[modes + 1:]
    order = np.argsort(lk / rk)
    rk, lk = rk[order], lk[order]
    if r0 >= _R0_OPEN * r_el:
        r0 = float("inf")
    err = network_step_response(t, ltilde=ltilde, r_el=r_el, r0=r0, rk=rk, lk=lk) * r_el - y
    return EddyNetworkFit(r0, rk, lk, float(np.sqrt(np.mean(err**2))), float(np.max(np.abs(err))))
