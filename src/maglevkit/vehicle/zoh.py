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

__all__ = ["exact_zoh_step"]


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
