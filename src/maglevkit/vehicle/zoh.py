"""The exact zero-order-hold step of a linear system (one source for the vehicle's parts).

For ``x' = A x + B u`` with ``u`` held over a step ``dt``::

    x+ = Ad x + Bd u,   Ad = exp(A dt),   Bd = int_0^dt exp(A s) ds B

both from one matrix exponential of the augmented matrix
``expm([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, I]]`` (Van Loan's block form).  Used by the
heave-pitch mechanics (:class:`~maglevkit.vehicle.mechanics.VehicleMechanics`), the
guideway spans' modes (:class:`~maglevkit.vehicle.guideway.BeamSpan`) and the planar
multibody system of the cross-section
(:class:`~maglevkit.vehicle.multibody.PlanarMultibody`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["exact_zoh_step", "second_order_state_matrices"]


def exact_zoh_step(a: Any, b: Any, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(Ad, Bd)`` of ``x' = A x + B u`` for ``u`` held over ``dt_s`` (module docstring).

    Parameters
    ----------
    a : array_like (n, n)
        System matrix ``A`` [1/s] (units of the state's rates over the state).
    b : array_like (n, m)
        Input matrix ``B`` (state rate per input).
    dt_s : float
        Step [s]; checked by the caller (finite, > 0).

    Returns
    -------
    (Ad, Bd) : ndarray (n, n), ndarray (n, m)
        New, writable arrays (copies of the exponential's blocks).
    """
    import scipy.linalg

    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    n2, n = b.shape
    aug = np.zeros((n2 + n, n2 + n))
    aug[:n2, :n2] = a * dt_s
    aug[:n2, n2:] = b * dt_s
    e = scipy.linalg.expm(aug)
    return e[:n2, :n2].copy(), e[:n2, n2:].copy()


def second_order_state_matrices(m: Any, k: Any, c: Any, *,
                                damping: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(A, Bq)`` of ``M q'' + C q' + K q = Q`` with a diagonal mass matrix, state
    ``x = [q; q']``: ``A = [[0, I], [-M^-1 K, -M^-1 C]]``, ``Bq = [0; M^-1]``.

    The one form the heave-pitch mechanics and the planar multibody system share (their
    exact steps then go through :func:`exact_zoh_step`).

    Parameters
    ----------
    m : array_like (n, n)
        Mass matrix (diagonal; only its diagonal is used) [kg] or [kg m^2].
    k : array_like (n, n)
        Stiffness matrix [N/m] (or per radian).
    c : array_like (n, n)
        Damping matrix [N s/m] (or per radian).
    damping : bool, default True
        Include ``-M^-1 C``; False: the undamped system (keyword only).

    Returns
    -------
    (A, Bq) : ndarray (2 n, 2 n), ndarray (2 n, n)
    """
    m = np.asarray(m, dtype=float)
    n = m.shape[0]
    minv = np.diag(1.0 / np.diag(m))
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -minv @ np.asarray(k, dtype=float)
    if damping:
        a[n:, n:] = -minv @ np.asarray(c, dtype=float)
    bq = np.zeros((2 * n, n))
    bq[n:] = minv
    return a, bq
