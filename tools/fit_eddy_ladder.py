"""Fit the dimensionless coefficients of the slab eddy-current ladder (docs/equations.md 1a).

The surface impedance of a conducting slab of half-thickness b (flux along it, both faces
exposed), in magnetic-circuit form with the DC permeance P0 = mu A/l, is
``Z P0 = z coth z``, ``z^2 = s tau``, ``tau = mu sigma b^2``.  The nested-tube ladder has
``Z P0 = z^2 w_1 + 1/(a_1 + 1/(z^2 w_2 + 1/(a_2 + ...  1/(z^2 w_n + 1/a_n))))`` with tube
fractions a_k (sum 1) and eddy weights w_k.  This script fits a_k, w_k > 0 (log-parameters)
by least squares on ``log(Z_ladder/Z_exact)`` over ``omega tau`` in [1e-2, 1e5] (200 points
per decade... log-spaced) and prints the table pasted into ``maglevkit.circuit.ladder``.

Run: ``python tools/fit_eddy_ladder.py`` (a few seconds).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

BAND = (1e-2, 1e5)


def zeta(z2, a, w):
    """Dimensionless ladder impedance Z P0 at z^2 = s tau."""
    zz = z2 * w[-1] + 1.0 / a[-1]
    for k in range(len(a) - 2, -1, -1):
        zz = z2 * w[k] + 1.0 / (a[k] + 1.0 / zz)
    return zz


def fit(n: int, band=BAND):
    om = np.logspace(np.log10(band[0]), np.log10(band[1]), 400)
    z2 = 1j * om
    z = np.sqrt(z2)
    ex = z / np.tanh(z)

    def unpack(p):
        a = np.exp(p[:n])
        return a / a.sum(), np.exp(p[n:])

    def f(p):
        a, w = unpack(p)
        r = np.log(zeta(z2, a, w) / ex)
        return np.concatenate([r.real, r.imag])

    best = None
    for q in (1.5, 2.0, 2.5, 3.0, 4.0):
        d = q ** np.arange(n)
        a = d / d.sum()
        xi = np.concatenate([[0.0], np.cumsum(a)])
        w = (1 - xi[:-1]) / 3 * (1 - ((1 - xi[1:]) / (1 - xi[:-1])) ** 3)
        p0 = np.concatenate([np.log(a), np.log(w)])
        r = least_squares(f, p0, bounds=(-25.0, 3.0), xtol=1e-15, ftol=1e-15, gtol=1e-15,
                          max_nfev=5000)
        if best is None or r.cost < best.cost:
            best = r
    a, w = unpack(best.x)
    err = np.abs(zeta(z2, a, w) / ex - 1).max()
    return a, w, err


if __name__ == "__main__":
    for n in range(2, 9):
        a, w, err = fit(n)
        print(f"    {n}: (({', '.join(f'{v:.10g}' for v in a)}),")
        print(f"        ({', '.join(f'{v:.10g}' for v in w)})),  # max |Z/Z_exact - 1| = {err:.2e}")
