"""Shared pieces of the 2-D magnetostatic FEM checks (benchmarks/fem_u_magnet.py,
benchmarks/fem_tr09.py): graded tensor grids, the iron's reluctivity from a maglevkit B-H
record, and Newton's method for

    -div( nu(|grad A|) grad A ) = J_z      (vector potential A_z, scikit-fem)

with the full Jacobian (incl. ``dnu/dB``), a backtracking line search and sparse direct
solves.  Needs the optional extra ``validation`` (scikit-fem).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

import maglevkit as mk

MU0 = 4e-7 * math.pi


# ---------------------------------------------------------------------------------------
# grids
# ---------------------------------------------------------------------------------------


def grid_1d(points: np.ndarray, sizes: np.ndarray, lo: float, hi: float, hmax: float,
            grade: float) -> np.ndarray:
    """Graded 1-D grid on [lo, hi] containing all ``points`` (sizes ``sizes`` there).

    Local target size ``h(x) = min(hmax, min_i(sizes_i + grade |x - points_i|))``; each
    interval between consecutive break points gets ``ceil(int dx/h)`` cells, distributed
    by inverting the cumulative ``int dx/h``.
    """
    brk = np.unique(np.concatenate([[lo, hi], points[(points > lo) & (points < hi)]]))
    out = [np.array([lo])]
    for a, b in zip(brk[:-1], brk[1:], strict=True):
        t = np.linspace(a, b, 2001)
        h = np.minimum(hmax, np.min(sizes[:, None] + grade * np.abs(t[None, :] - points[:, None]),
                                    axis=0))
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (1 / h[1:] + 1 / h[:-1]) * np.diff(t))])
        n = max(1, int(math.ceil(cum[-1] - 1e-9)))
        out.append(np.interp(np.linspace(0, cum[-1], n + 1)[1:], cum, t))
    return np.concatenate(out)


def cap(x: np.ndarray, lo: float, hi: float, h: float) -> np.ndarray:
    """Subdivide cells of the sorted grid ``x`` inside [lo, hi] longer than ``h``."""
    out = [x[:1]]
    for a, b in zip(x[:-1], x[1:], strict=True):
        n = 1
        if a >= lo - 1e-12 and b <= hi + 1e-12 and b - a > h:
            n = int(math.ceil((b - a) / h))
        out.append(np.linspace(a, b, n + 1)[1:])
    return np.concatenate(out)


# ---------------------------------------------------------------------------------------
# material
# ---------------------------------------------------------------------------------------


class Reluctivity:
    """nu(B) = H(B)/B of a material (or a constant mu_r), scaled by mu0 (nu_r).

    ``depth_ratio`` k = (depth of the 2-D model) / (real depth of the part) represents a
    part wider than the model's depth: its real flux density is ``k B`` for the model's
    ``B``, so ``H_model(B) = H(k B)``, with energy and co-energy densities ``w(k B)/k``
    (the energy of the real part, per model volume).
    """

    def __init__(self, mu_r: float | None = None, material: str = "AISI 1008",
                 depth_ratio: float = 1.0) -> None:
        self.mu_r = mu_r
        self.k = float(depth_ratio)
        self.mat = mk.get_material(material)
        # co-energy table w'(B) = B H - int_0^B H dB (for the virtual-work check)
        b = np.concatenate([np.linspace(0.0, 3.0, 30001), np.linspace(3.0, 20.0, 3401)[1:]])
        h = self._h_real(b)
        w = np.concatenate([[0.0], np.cumsum(0.5 * (h[1:] + h[:-1]) * np.diff(b))])
        self._b, self._wc = b, b * h - w

    def _h_real(self, b: np.ndarray) -> np.ndarray:
        if self.mu_r is not None:
            return b / (MU0 * self.mu_r)
        return np.asarray(self.mat.field_strength(b), dtype=float)

    def _h(self, b: np.ndarray) -> np.ndarray:
        return self._h_real(self.k * b) if self.k != 1.0 else self._h_real(b)

    def nu_r(self, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return mu0*nu(B) and mu0*(dnu/dB)/B (the Newton coefficient)."""
        if self.mu_r is not None and self.k == 1.0:
            return np.full_like(b, 1.0 / self.mu_r), np.zeros_like(b)
        bb = np.maximum(b, 1e-6)
        db = 1e-6 * np.maximum(bb, 1e-2)
        hp, hm = self._h(bb + db), self._h(bb - db)
        h = self._h(bb)
        nu = h / bb
        dnu_db = ((hp - hm) / (2 * db) - nu) / bb       # d(H/B)/dB = (H' - H/B)/B
        return MU0 * nu, MU0 * dnu_db / bb

    def coenergy_density(self, b: np.ndarray) -> np.ndarray:
        if self.mu_r is not None and self.k == 1.0:
            return b**2 / (2 * MU0 * self.mu_r)
        if self.k == 1.0:
            return np.interp(b, self._b, self._wc)
        return np.interp(self.k * b, self._b, self._wc) / self.k


# ---------------------------------------------------------------------------------------
# solver
# ---------------------------------------------------------------------------------------


class SPDSolver:
    """Sparse direct solves of the symmetric positive definite Newton systems (SuperLU)."""

    def __init__(self) -> None:
        self.factorisations = 0
        self.lu = None

    def solve(self, K, b: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
        self.lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A",
                            options={"SymmetricMode": True})
        self.factorisations += 1
        return self.lu.solve(b)


@dataclass
class NewtonResult:
    A: np.ndarray                 # vector potential [Wb/m] at the DOFs
    grad: np.ndarray              # grad A at the quadrature points (2, elements, points)
    b: np.ndarray                 # |B| [T] at the quadrature points
    nu: np.ndarray                # mu0 * nu at the quadrature points
    iterations: int
    residual: float
    factorisations: int
    tangent: object               # Jacobian at the solution (free DOFs) or None


def solve_nonlinear(basis, parts: Sequence[tuple[np.ndarray, Reluctivity]],  # type: ignore[no-untyped-def]
                    rhs: np.ndarray, free: np.ndarray, *, tol: float = 1e-8,
                    A0: np.ndarray | None = None, max_iterations: int = 60,
                    tangent: bool = False) -> NewtonResult:
    """Newton's method for ``-div(nu grad A) = J`` (``rhs`` = the assembled ``mu0 J``).

    ``parts``: (element mask, material) per nonlinear region; all other elements are air.
    ``free``: the DOFs without the Dirichlet condition A = 0.  Starts from ``A0`` or from
    the linear solution with mu_r = 1000 in every part; stops at a relative residual
    below ``tol``.  ``tangent``: also return the Jacobian at the solution (free DOFs): the
    incremental stiffness, ``dA/dI = K_t^-1 d(rhs)/dI`` (differential inductance).
    """
    from skfem import BilinearForm, LinearForm, asm
    from skfem.helpers import dot, grad

    nqp = basis.X.shape[1]
    masks = [np.repeat(mask[:, None], nqp, axis=1) for mask, _ in parts]

    @BilinearForm
    def jac(u, v, w):
        return w.nu * dot(grad(u), grad(v)) + w.c * dot(w.ga, grad(u)) * dot(w.ga, grad(v))

    @LinearForm
    def resid(v, w):
        return w.nu * dot(w.ga, grad(v))

    def coeffs(A: np.ndarray):  # type: ignore[no-untyped-def]
        ga = basis.interpolate(A).grad
        b = np.sqrt(ga[0] ** 2 + ga[1] ** 2)
        nu = np.ones_like(b)
        c = np.zeros_like(b)
        for q, (_, mat) in zip(masks, parts, strict=True):
            nu_i, c_i = mat.nu_r(b)
            nu = np.where(q, nu_i, nu)
            c = np.where(q, c_i, c)
        return ga, b, nu, c

    def residual(A: np.ndarray):  # type: ignore[no-untyped-def]
        cf = coeffs(A)
        return asm(resid, basis, nu=cf[2], ga=cf[0]) - rhs, cf

    if A0 is not None and A0.shape == (basis.N,):
        A = A0.copy()
    else:
        nu0 = np.ones((basis.mesh.t.shape[1], nqp))
        for q in masks:
            nu0 = np.where(q, 1e-3, nu0)
        K = asm(jac, basis, nu=nu0, c=np.zeros_like(nu0), ga=np.zeros((2, *nu0.shape)))
        A = np.zeros(basis.N)
        A[free] = SPDSolver().solve(K[free][:, free], rhs[free])
    rnorm0 = np.linalg.norm(rhs[free])
    r, cf = residual(A)
    rel = np.linalg.norm(r[free]) / rnorm0
    it = 0
    solver = SPDSolver()
    while rel > tol and it < max_iterations:
        it += 1
        Kf = asm(jac, basis, nu=cf[2], c=cf[3], ga=cf[0])[free][:, free]
        dA = np.zeros(basis.N)
        dA[free] = solver.solve(Kf, -r[free])
        step = 1.0
        while True:
            An = A + step * dA
            rn, cfn = residual(An)
            reln = np.linalg.norm(rn[free]) / rnorm0
            if reln < rel * (1 - 1e-4 * step) or step < 1 / 64:
                break
            step *= 0.5
        A, r, cf, rel = An, rn, cfn, reln
    if rel > tol:
        raise RuntimeError(f"Newton did not converge: residual {rel:.2e}")
    kt = asm(jac, basis, nu=cf[2], c=cf[3], ga=cf[0])[free][:, free] if tangent else None
    ga, b, nu, _ = cf
    return NewtonResult(A, ga, b, nu, it, rel, solver.factorisations, kt)


def error_row(s_mm: float, current_A: float, fem: dict, *, force_N: float, psi_Wb: float,
              L_H: float) -> dict:
    """One point of a network-vs-FEM comparison: the FEM's force [N], flux linkage [Wb] and
    differential inductance [H] and the network's errors against them in %
    (``(net - FEM)/FEM``), as the magnets' ``compare`` tables read them."""
    return {"s_mm": s_mm, "I_A": current_A, "F_fem": fem["force_N"],
            "psi_fem": fem["psi_Wb"], "L_fem": fem["L_H"],
            "eF": 100 * (force_N / fem["force_N"] - 1),
            "epsi": 100 * (psi_Wb / fem["psi_Wb"] - 1),
            "eL": 100 * (L_H / fem["L_H"] - 1)}

