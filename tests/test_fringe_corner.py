"""The face's corner flux of a pole edge with the coil beside its flank and a window's
centre plane (``edge_corner_per_mu0``, ``EdgeCornerPermeance``; issue 25, u20c25) against
an independent finite-difference solution of the same 2-D field, its limits, and the
window map against a direct quadrature of its Schwarz-Christoffel derivative."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.integrate import quad
from scipy.optimize import brentq

from maglevkit.circuit.elements import (
    EdgeCornerPermeance,
    edge_corner_per_mu0,
    edge_flank_parameter,
    edge_window_height,
    edge_window_parameter,
)
from maglevkit.errors import ParameterError
from maglevkit.materials import MU0

FREE = (2.0 - 2.0 * math.log(2.0)) / math.pi


def _face_excess_fd(n: int, r: float, h: float, a: float | None = None,
                    left: float = 4.0, right: float = 12.0, top: float = 14.0) -> float:
    """Finite differences (5-point Laplacian, spacing 1/n) of the field of a right-angled
    pole edge at s = 1 over a plane: face (y = 1, x <= 0) at 1, flank (x = 0, y >= 1) at 1
    up to the coil at height r above the face, falling linearly to 0 over its height h,
    0 above; the plane y = 0 at 0; with ``a`` a centre plane x = a at 0, otherwise a closed
    box side at x = ``right``; the other box sides closed (no flux).  Returns the face's
    flux per unit depth and mu0 beyond the uniform field, over the face from x = 1 - left
    (three gaps from the closed left side, where the field is uniform) to the edge."""
    d = 1.0 / n
    right = a if a is not None else right
    nx, ny = int(round((left + right) * n)) + 1, int(round(top * n)) + 1
    x, y = -left + d * np.arange(nx), d * np.arange(ny)
    X, Y = np.meshgrid(x, y, indexing="ij")
    pole = (X <= 1e-12) & (Y >= 1.0 - 1e-12)
    fixed = pole | (Y <= 1e-12)
    if a is not None:
        fixed |= X >= a - 1e-12
    deficit = np.clip((Y - 1.0 - r) / h, 0.0, 1.0)
    value = np.where(pole, np.where(np.abs(X) < 1e-12, 1.0 - deficit, 1.0), 0.0)
    free = ~fixed
    index = -np.ones((nx, ny), dtype=int)
    index[free] = np.arange(int(free.sum()))
    I, J = np.nonzero(free)
    K = index[I, J]
    rows, cols, data = [np.arange(K.size)], [np.arange(K.size)], []
    diag, rhs = np.zeros(K.size), np.zeros(K.size)
    for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        ii, jj = I + di, J + dj
        inside = (ii >= 0) & (ii < nx) & (jj >= 0) & (jj < ny)
        diag[inside] += 1.0
        ii, jj, k = ii[inside], jj[inside], K[inside]
        fx = fixed[ii, jj]
        np.add.at(rhs, k[fx], value[ii[fx], jj[fx]])
        rows.append(k[~fx])
        cols.append(index[ii[~fx], jj[~fx]])
        data.append(-np.ones(int((~fx).sum())))
    A = sp.csc_matrix((np.concatenate([diag, *data]), (np.concatenate(rows),
                                                       np.concatenate(cols))),
                      shape=(K.size, K.size))
    phi = value.copy()
    phi[free] = spla.spsolve(A, rhs)
    length = left - 1.0
    face = np.nonzero((x <= 1e-12) & (x >= -length - 1e-12))[0]
    weights = np.ones(face.size)
    weights[[0, -1]] = 0.5
    return float(np.sum(weights * (1.0 - phi[face, n - 1]))) - length


def test_corner_law_against_finite_differences() -> None:
    """The bundled U-magnet's proportions at 20 mm in units of the gap (coil 0.5 s above the
    face, 2.5 s high, window half 1.5 s).  The corner's field is singular (r^(-1/3)), so
    the finite differences converge as h^(2/3) (spacing s/8, s/16, s/32: free edge 0.118,
    0.144, 0.162); extrapolated from s/12 and s/24 with that order, the free edge is 0.1915
    against 0.1953 (2 %: the extrapolation of the corner itself), and the coil's and the
    window's shares -- differences to the free edge, where the corner's error cancels --
    0.0254 / 0.0502 / 0.0421 against 0.0252 / 0.0500 / 0.0419 (0.3-0.8 %).  Tolerances:
    1.5 % on the shares, 3 % on the free edge."""
    order = 2.0 ** (-2.0 / 3.0)
    cases = {"free": (1e3, 1.0, None), "coil": (0.5, 2.5, None),
             "coil and window": (0.5, 2.5, 1.5), "window": (1e3, 1.0, 1.5)}
    fd = {}
    for name, (r, h, a) in cases.items():
        coarse, fine = _face_excess_fd(12, r, h, a), _face_excess_fd(24, r, h, a)
        fd[name] = fine + (fine - coarse) * order / (1.0 - order)
    law = {name: float(edge_corner_per_mu0(1.0, 1.0, r, h, a))
           for name, (r, h, a) in cases.items()}
    assert law["free"] == pytest.approx(FREE, abs=1e-6)   # the coil 1000 s up: 1.3e-7
    assert fd["free"] == pytest.approx(FREE, rel=3e-2)
    for name in ("coil", "coil and window", "window"):
        share = fd[name] - fd["free"]
        assert share == pytest.approx(law[name] - law["free"], rel=1.5e-2), name
        assert share > 0.02, name          # a real share, not round-off


def test_corner_law_limits() -> None:
    """Coil far up the flank, window far away: the plain map's 0.195.  A coil of vanishing
    height (the flank steps from V to 0 at r): ``c_0 + ln(1 + 1/v(r)^2)/pi``, the kernel's
    closed form.  Without a coil (flank at V to infinity) the window's term alone is
    ``(2/pi)[(a/s) atan(s/a) - ln 2 + ln(1 + s^2/a^2)/2]``, checked here against the face's
    limit computed by quadrature of the map, ``lim (1/pi) ln(1/|t|) - |x(t)|/s``."""
    assert float(edge_corner_per_mu0(1.0, 0.01, 5.0, 1.0)) == pytest.approx(FREE, abs=1e-6)
    assert float(edge_corner_per_mu0(1.0, 0.01, 0.01, 0.05, 1e4)) == pytest.approx(
        float(edge_corner_per_mu0(1.0, 0.01, 0.01, 0.05)), abs=1e-6)
    v = float(edge_flank_parameter(0.8, 1.0))
    step = float(edge_corner_per_mu0(1.0, 1.0, 0.8, 1e-7))
    assert step == pytest.approx(FREE + math.log(1.0 + 1.0 / v**2) / math.pi, rel=1e-6)
    for s, a in ((1.0, 1.5), (1.0, 0.4), (1.0, 8.0)):
        alpha = (a / s) ** 2

        def integrand(sig: float, alpha: float = alpha) -> float:
            # (1/pi) int_0^1 [1 - sqrt(1 - t) sqrt(alpha)/sqrt(alpha + t)] dt/t: the face's
            # log(1/|t|) less its x(t)/s, both from the corner t = -1
            return (1.0 - math.sqrt(1.0 - sig) * math.sqrt(alpha / (alpha + sig))) / sig / math.pi

        want = quad(integrand, 0.0, 1.0, epsabs=1e-13)[0]
        assert float(edge_corner_per_mu0(1.0, s, 1e3, 1.0, a)) == pytest.approx(want, rel=1e-9)


def test_window_map_height_and_inverse() -> None:
    """The flank height of the window map against a direct quadrature of ``|dz/dt|`` on the
    flank (``(a/pi) sqrt(T - 1)/(T sqrt(alpha + T))``, ``T = 1 + v^2``; 1e-10), the free
    edge's ``(2s/pi)(v - atan v)`` for a far plane, and the Newton inverse against a
    bracketing root finder (1e-12)."""
    for s, a in ((0.004, 0.03), (0.02, 0.03), (0.02, 0.005)):
        alpha = (a / s) ** 2
        for v in (0.05, 0.7, 3.0, 40.0):
            want = a / math.pi * quad(
                lambda T, alpha=alpha: math.sqrt(T - 1.0) / (T * math.sqrt(alpha + T)),
                1.0, 1.0 + v * v, epsabs=1e-15, limit=200)[0]
            assert float(edge_window_height(v, s, a)) == pytest.approx(want, rel=1e-10)
        for y in (0.01 * s, 0.3 * s, 2.0 * s, 5.0 * a):
            root = brentq(lambda v, y=y, s=s, a=a: float(edge_window_height(v, s, a)) - y,
                          1e-9, 1e12, xtol=1e-300, rtol=1e-15)
            assert float(edge_window_parameter(y, s, a)) == pytest.approx(root, rel=1e-12)
    assert float(edge_window_height(2.0, 0.01, 1e6)) == pytest.approx(
        float(edge_window_height(2.0, 0.01)), rel=1e-9)


def test_corner_element_numpy_casadi_and_errors() -> None:
    """The element sums its edges; NumPy arrays, scalars and CasADi give the same value,
    CasADi's gap derivative equals a central difference (1e-6), the term grows with the gap
    (the U-magnet: 0.397 -> 0.466 mu0 w for both edges, 4 -> 20 mm); bad input names the
    field and the value."""
    el = EdgeCornerPermeance("c", gap_input="left", width_m=0.1, coil_from_m=0.01,
                             coil_height_m=0.05, window_halves_m=(0.03, math.inf))
    gaps = np.array([0.004, 0.012, 0.020])
    per_w = np.asarray(el.permeance(gaps)) / (MU0 * 0.1)
    want = [float(edge_corner_per_mu0(1.0, g, 0.01, 0.05, 0.03) + edge_corner_per_mu0(
        1.0, g, 0.01, 0.05)) for g in gaps]
    assert per_w == pytest.approx(want, rel=1e-12)
    assert np.all(np.diff(per_w) > 0.02)
    sym = ca.SX.sym("s")
    f = ca.Function("g", [sym], [el.permeance(sym), ca.jacobian(el.permeance(sym), sym)])
    value, slope = (float(x) for x in f(0.012))
    assert value == pytest.approx(float(el.permeance(0.012)), rel=1e-12)
    d = 1e-7
    fd = (float(el.permeance(0.012 + d)) - float(el.permeance(0.012 - d))) / (2 * d)
    assert slope == pytest.approx(fd, rel=1e-6)
    with pytest.raises(ParameterError, match="needs a gap value"):
        el.permeance()
    with pytest.raises(ParameterError, match="window_halves_m entry -0.03"):
        EdgeCornerPermeance("c", window_halves_m=(-0.03,))
    with pytest.raises(ParameterError, match="coil_height_m"):
        EdgeCornerPermeance("c", coil_height_m=0.0)
    with pytest.raises(ParameterError, match="non-empty tuple"):
        EdgeCornerPermeance("c", window_halves_m=())
