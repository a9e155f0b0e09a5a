"""Characteristic maps as per-cell polynomial tables (the magnet bank's interpolation).

A map ``f(s, I)`` on a regular grid ``s_k = s_0 + k ds``, ``I_l = I_0 + l dI`` is stored
cell by cell as the coefficients of a polynomial in the cell's normalised coordinates
``t = (s - s_k)/ds``, ``w = (I - I_l)/dI`` (both in ``[0, 1)`` inside the cell)::

    f(s, I) = sum_{p, q = 0..d} c[k, l, p, q] t^p w^q          (d = 3 bicubic, 1 bilinear)

Evaluation is then a cell index (two ``floor``), one gather of ``(d + 1)^2`` coefficients
and a polynomial: about 20x cheaper than CasADi's B-spline evaluation (knot search and
basis recursion), and it codegenerates to plain C.

Interpolation methods (all three reproduce the grid values exactly):

``"bicubic"``
    The tensor-product cubic spline with not-a-knot end conditions (C2).  This is the
    same function as CasADi's ``interpolant(..., "bspline")`` on the same data (measured
    agreement 4e-14 relative), i.e. the interpolation the current-based model always used.
``"monotone"``
    C1 bicubic Hermite patches with Fritsch-Carlson (PCHIP) node slopes along each axis:
    along every grid line the interpolant is the monotone PCHIP curve of the data, so it
    does not overshoot at the saturation knee.
``"bilinear"``
    C0, the cheapest.

The accuracy each costs is measured against maps computed on a finer grid in
``benchmarks/bench_bank.py`` (BENCHMARKS.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError

__all__ = ["INTERPOLATION_METHODS", "N_TABLE_MAPS", "CellTable", "cell_lookup", "cell_table", "gap_cell_part"]

INTERPOLATION_METHODS = ("bicubic", "monotone", "bilinear")


@dataclass(frozen=True)
class CellTable:
    """Per-cell polynomial coefficients of one or more maps on one regular grid.

    Attributes
    ----------
    s0_m, ds_m : float
        First grid gap and gap spacing [m].
    i0_A, di_A : float
        First grid current and current spacing [A].
    coefficients : ndarray (n_cells_s, n_cells_i, n_maps, d + 1, d + 1)
        ``c[k, l, m, p, q]``: coefficient of ``t^p w^q`` of map ``m`` in cell ``(k, l)``
        (units of the map).
    degree : int
        ``d``: 3 (bicubic, monotone) or 1 (bilinear).
    """

    s0_m: float
    ds_m: float
    i0_A: float
    di_A: float
    coefficients: np.ndarray
    degree: int

    @property
    def n_cells(self) -> tuple[int, int]:
        return int(self.coefficients.shape[0]), int(self.coefficients.shape[1])

    def evaluate(self, s: np.ndarray, i: np.ndarray) -> np.ndarray:
        """All maps at points ``(s, i)`` (NumPy reference evaluation), shape (..., n_maps).

        Outside the grid the edge cell's polynomial is continued (as in the kernel).
        """
        s, i = np.broadcast_arrays(np.asarray(s, dtype=float), np.asarray(i, dtype=float))
        ns, ni = self.n_cells
        u = (s - self.s0_m) / self.ds_m
        v = (i - self.i0_A) / self.di_A
        k = np.clip(np.floor(u), 0, ns - 1).astype(int)
        lc = np.clip(np.floor(v), 0, ni - 1).astype(int)
        t, w = u - k, v - lc
        d = self.degree
        tp = t[..., None] ** np.arange(d + 1)
        wq = w[..., None] ** np.arange(d + 1)
        c = self.coefficients[k, lc]                       # (..., n_maps, d+1, d+1)
        return np.einsum("...mpq,...p,...q->...m", c, tp, wq)


def _regular_step(axis: np.ndarray, what: str) -> float:
    axis = np.asarray(axis, dtype=float)
    if axis.ndim != 1 or axis.size < 4:
        raise InputError(f"{what} grid needs at least 4 points, got {axis.size}")
    d = np.diff(axis)
    step = float(d.mean())
    if not (step > 0 and np.allclose(d, step, rtol=1e-9, atol=0.0)):
        raise InputError(f"{what} grid must be regular (equidistant, increasing) for the "
                         "per-cell tables; rebuild the maps on a regular grid")
    return step


def _spline_coefficients(x: np.ndarray, y: np.ndarray, axis: int, method: str) -> np.ndarray:
    """Per-interval cubic coefficients along ``axis`` in the normalised coordinate.

    Returns an array with a new leading axis of length 4 (power 0..3) and ``axis``
    shortened by one (intervals).
    """
    from scipy.interpolate import CubicSpline, PchipInterpolator

    h = float(x[1] - x[0])
    if method == "bicubic":
        pp = CubicSpline(x, y, axis=axis, bc_type="not-a-knot")
    else:
        pp = PchipInterpolator(x, y, axis=axis)
    # PPoly.c[m] multiplies (x - x_k)^(3 - m); in t = (x - x_k)/h the power p = 3 - m
    # gets the factor h^p
    c = np.asarray(pp.c)[::-1]
    return c * (h ** np.arange(4)).reshape((4,) + (1,) * (c.ndim - 1))


def cell_table(s_axis: np.ndarray, i_axis: np.ndarray, maps: np.ndarray, *,
               method: str = "bicubic") -> CellTable:
    """Per-cell polynomial table of maps given on a regular grid.

    Parameters
    ----------
    s_axis : array (n_s,)
        Gap grid [m] (regular).
    i_axis : array (n_i,)
        Current grid [A] (regular).
    maps : array (n_maps, n_s, n_i)
        Map values on the grid.
    method : {"bicubic", "monotone", "bilinear"}
        Interpolation (module docstring).

    Returns
    -------
    CellTable
    """
    if method not in INTERPOLATION_METHODS:
        raise InputError(f"interpolation = {method!r}; use one of {list(INTERPOLATION_METHODS)}")
    s_axis = np.asarray(s_axis, dtype=float)
    i_axis = np.asarray(i_axis, dtype=float)
    ds = _regular_step(s_axis, "gap")
    di = _regular_step(i_axis, "current")
    v = np.asarray(maps, dtype=float)
    if v.shape[1:] != (s_axis.size, i_axis.size):
        raise InputError(f"maps of shape {v.shape[1:]} do not match the grid "
                         f"({s_axis.size}, {i_axis.size})")
    if not np.isfinite(v).all():
        raise InputError("maps contain non-finite values; rebuild them")
    if method == "bilinear":
        f00, f10 = v[:, :-1, :-1], v[:, 1:, :-1]
        f01, f11 = v[:, :-1, 1:], v[:, 1:, 1:]
        c = np.zeros(v.shape[:1] + (s_axis.size - 1, i_axis.size - 1, 2, 2))
        c[..., 0, 0] = f00
        c[..., 1, 0] = f10 - f00
        c[..., 0, 1] = f01 - f00
        c[..., 1, 1] = f11 - f10 - f01 + f00
        coef = np.moveaxis(c, 0, 2)
        return CellTable(float(s_axis[0]), ds, float(i_axis[0]), di, coef, 1)
    if method == "bicubic":
        # tensor product of 1-D not-a-knot splines: the s-polynomial coefficients of
        # every current node, splined along the current axis (interpolation is linear,
        # so this is exactly the tensor-product spline)
        # (scipy's PPoly puts the power and interval axes first)
        a = _spline_coefficients(s_axis, v, 1, method)          # (4p, cs, m, n_i)
        b = _spline_coefficients(i_axis, a, 3, method)          # (4q, ci, 4p, cs, m)
        coef = np.transpose(b, (3, 1, 4, 2, 0))                 # (cs, ci, m, p, q)
        return CellTable(float(s_axis[0]), ds, float(i_axis[0]), di, np.ascontiguousarray(coef), 3)
    return _monotone_table(s_axis, i_axis, v, ds, di)


def _monotone_table(s_axis: np.ndarray, i_axis: np.ndarray, v: np.ndarray, ds: float,
                    di: float) -> CellTable:
    """C1 bicubic Hermite patches from PCHIP node derivatives (normalised coordinates)."""
    from scipy.interpolate import PchipInterpolator

    fs = PchipInterpolator(s_axis, v, axis=1).derivative()(s_axis) * ds       # df/dt
    fi = PchipInterpolator(i_axis, v, axis=2).derivative()(i_axis) * di       # df/dw
    # twist: mean of the two one-sided estimates
    fsi = 0.5 * (PchipInterpolator(i_axis, fs, axis=2).derivative()(i_axis) * di
                 + PchipInterpolator(s_axis, fi, axis=1).derivative()(s_axis) * ds)
    # Hermite corner data per cell: F[a, b] with a, b in {0, 1} (cell corners)
    def corners(x: np.ndarray) -> np.ndarray:
        return np.stack([np.stack([x[:, :-1, :-1], x[:, :-1, 1:]], -1),
                         np.stack([x[:, 1:, :-1], x[:, 1:, 1:]], -1)], -2)  # (m, cs, ci, 2, 2)
    # G = [[f, f_w], [f_t, f_tw]] block matrix at the corners; c = H G H^T with the
    # cubic Hermite basis matrix H (rows: powers, columns: [f(0), f(1), f'(0), f'(1)])
    f, ft, fw, ftw = corners(v), corners(fs), corners(fi), corners(fsi)
    g = np.zeros(f.shape[:3] + (4, 4))
    g[..., :2, :2] = f
    g[..., :2, 2:] = fw
    g[..., 2:, :2] = ft
    g[..., 2:, 2:] = ftw
    h = np.array([[1.0, 0.0, 0.0, 0.0],
                  [0.0, 0.0, 1.0, 0.0],
                  [-3.0, 3.0, -2.0, -1.0],
                  [2.0, -2.0, 1.0, 1.0]])
    c = np.einsum("pa,...ab,qb->...pq", h, g, h)
    coef = np.ascontiguousarray(np.moveaxis(c, 0, 2))
    return CellTable(float(s_axis[0]), ds, float(i_axis[0]), di, coef, 3)


# ----------------------------------------------------------------------------- kernel lookup
# The compiled table lookup of the magnet bank's kernel, written once as CasADi expressions
# (the bank's step, its ODE function and the vehicle's and FMU's code all come from it).
# Kernel parameters ``p`` (MagnetBank.circuit_parameters): p[0] s0 [m], p[1] 1/ds [1/m],
# p[2] gap cells, p[3] I0 [A], p[4] 1/dI [1/A], p[5] current cells, p[6] table offset.
N_TABLE_MAPS = 3
"""Maps per cell in the kernel's table: ``L~``, ``dL/ds``, ``F``."""


def gap_cell_part(s: Any, p: Any, degree: int) -> tuple[Any, tuple[Any, ...]]:
    """The gap half of a kernel table lookup at gap ``s`` [m] (CasADi expressions).

    The gap does not depend on the current, so this half stays off the integrator's chain
    of dependent operations: the table offset of the gap cell's row (``p[6] + k_s
    n_i (d + 1)^2 N``, a whole number, exact in floating point) and the powers ``t^0..t^d``
    of the local coordinate ``t = (s - s_k)/ds``.  The cell index is clamped to the
    table (the edge cell's polynomial continues outside it, NaN included).

    Parameters
    ----------
    s : casadi.MX
        Gap [m].
    p : casadi.MX or DM
        The circuit's kernel parameters (above).
    degree : int
        ``d``: 3 (bicubic, monotone) or 1 (bilinear).

    Returns
    -------
    (casadi.MX, tuple of casadi.MX)
        Row offset, and ``(1, t, .., t^d)`` [-].
    """
    import casadi as ca

    us = (s - p[0]) * p[1]
    ks = ca.fmin(ca.fmax(ca.floor(us), 0), p[2] - 1)
    t = us - ks
    nk = (degree + 1) ** 2
    return p[6] + ks * (p[5] * (N_TABLE_MAPS * nk)), _powers(t, degree)


def _powers(x: Any, degree: int) -> tuple[Any, ...]:
    out: list[Any] = [1.0, x]
    for _ in range(2, degree + 1):
        out.append(out[-1] * x)
    return tuple(out[:degree + 1])


def _power_sum(c: list[Any], x: tuple[Any, ...]) -> Any:
    """``sum_k c_k x^k`` with the powers given, summed pairwise (a short dependency
    chain: the products in parallel, then a tree of additions)."""
    terms = [c[0]] + [c[k] * x[k] for k in range(1, len(c))]
    while len(terms) > 1:
        terms = [terms[j] + terms[j + 1] if j + 1 < len(terms) else terms[j]
                 for j in range(0, len(terms), 2)]
    return terms[0]


def cell_lookup(cell: tuple[Any, tuple[Any, ...]], i: Any, p: Any, table: Any, degree: int,
                maps: Sequence[int] = (0, 1, 2), *, hint: Any = None) -> tuple[list[Any], Any]:
    """Maps ``maps`` of the kernel's table at the gap cell ``cell`` (:func:`gap_cell_part`)
    and current ``i`` [A] (CasADi expressions).

    ``f = sum_q w^q (sum_p c_pq t^p)``: the inner sums over the gap powers first (their
    coefficients are gathered as soon as the current's cell is known), then the outer one
    over the powers of ``w = (I - I_l)/dI``, each summed pairwise (:func:`_power_sum`).

    Parameters
    ----------
    cell : (casadi.MX, tuple of casadi.MX)
        From :func:`gap_cell_part`.
    i : casadi.MX
        Current [A].
    p : casadi.MX or DM
        The circuit's kernel parameters.
    table : casadi.MX
        The table (per cell map-major, then the ``(d + 1)^2`` coefficients ``t^p w^q``).
    degree : int
        ``d``.
    maps : sequence of int
        Which of ``L~`` [H], ``dL/ds`` [H/m], ``F`` [N] (0, 1, 2).
    hint : casadi.MX, optional
        A guess of the current's cell index (e.g. the cell of an earlier RK4 stage).  The
        index used is ``if_else(k == hint, hint, k)``, the same number ``k`` either way,
        so the values do not change; the lanes' C turns this select into a branch on
        "every lane guessed right" (:mod:`.lanes`), so that the gather and the gap sums
        need not wait for ``k`` (only the branch does).

    Returns
    -------
    (list of casadi.MX, casadi.MX)
        The maps' values, in their units, and the current's cell index ``k`` (for the
        ``hint`` of a later lookup).
    """
    import casadi as ca

    d = degree
    nk = (d + 1) ** 2
    row, tp = cell
    ui = (i - p[3]) * p[4]
    ki = ca.fmin(ca.fmax(ca.floor(ui), 0), p[5] - 1)
    k = ki if hint is None else ca.if_else(ki == hint, hint, ki)
    wq = _powers(ui - k, d)
    base = row + k * (N_TABLE_MAPS * nk)
    idx = np.concatenate([np.arange(m * nk, (m + 1) * nk) for m in maps]).astype(float)
    c = table[base + ca.DM(idx)]
    out = []
    for j, _ in enumerate(maps):
        g = [_power_sum([c[j * nk + pp * (d + 1) + q] for pp in range(d + 1)], tp)
             for q in range(d + 1)]
        out.append(_power_sum(g, wq))
    return out, ki
