# ruff: noqa: B023  (the Newton helpers are defined and used within one time step)
"""Transient 2-D finite-element reference of the U-magnet with solid iron (issue 12, part 3).

Magnetodynamics of the cross-section in the vector potential ``A_z`` (half model x >= 0,
mirror symmetry, ``A = 0`` on the outer boundary of the air box)::

    sigma (dA/dt - u_b) - div( nu(|grad A|) grad A ) = J_coil      in conducting body b
                          - div( nu grad A )          = J_coil      elsewhere
    int_b sigma (dA/dt - u_b) dA = 0                                (zero net current per body)
    U = R I + dpsi/dt,   psi = depth sum_k sign_k (n/2)/(t_c h_c) int_k A dA

``E_z = -(dA/dt - u_b)``: ``u_b`` is the constant (per body) gradient of the electric
potential along z that makes the body's net current zero, the 2-D picture of eddy currents
that close at the far ends of a long body.  Two conducting bodies: the U-core (legs and yoke,
one solid piece) and the rail.  The coil is driven by a voltage through its resistance; its
current is an unknown of the same Newton system.

Discretisation: P1 triangles on a structured tensor mesh from ``fem_u_magnet.py`` (grid lines
on every material boundary) refined to cells of ``h_surface`` at every iron surface (graded
by 20 % per cell), lumped (row-sum) conductor mass, variable-step BDF2 in time (implicit Euler
for the first step) on a geometric time grid, Newton's method with the full Jacobian of the
nonlinear reluctivity (``dnu/dB`` from H(B)) and a backtracking line search at every step.
The element loops are vectorised by hand (P1 gradients are constant per element), so a step
costs one sparse LU per Newton iteration.

Outputs: coil current, flux linkage, eddy power per body, magnetic energy; an energy balance
``int U I = int R I^2 + int P_eddy + Delta W`` checks the discretisation.

``python benchmarks/fem_u_magnet_transient.py --fem PART`` runs the FEM (PART = ``cases``:
the voltage steps, ``study``: mesh and time-step convergence, ``noeddy``: the steps with
sigma = 0) and rewrites ``benchmarks/results/fem_transient_PART.json`` (``--only K,..``
runs some cases into part files, ``--merge`` joins them); without ``--fem`` it compares the
recorded FEM with the flux model (lumped, ladder and ladder_split eddy models on the
lumped network, lumped and ladder on the cell network with Roters tubes and with the air
as cells) and rewrites ``docs/figures/fem-transient-steps.png`` and the transient section
of ``docs/validation_fem.md`` (between the markers).  Every model run is written to
``benchmarks/results/model_transient/``; the slow variants (``RECORDED_MODELS``: the grid
ladder, ~15-30 min per step on the dense IDAS form it was recorded with, and the air-cell
network, 1-3 min per step) are only read from there (``--model LABEL --only K`` runs and
records them; ``--model "sigma 0, cells"`` the air cells against the sigma = 0 FEM),
``--reuse`` reads every recorded run instead of rerunning it.
Needs the optional extra ``validation`` (scikit-fem, only for the tensor mesh).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # threaded BLAS on 1e4 vectors: spin-waits
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem_u_magnet import (  # noqa: E402
    GEOM,
    MU0,
    Geometry,
    Reluctivity,
    _cap,
    _grid_1d,
    body_regions,
)

import maglevkit as mk  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = {part: ROOT / "benchmarks" / "results" / f"fem_transient_{part}.json"
           for part in ("cases", "study", "noeddy")}
RESULTS_DIR = ROOT / "benchmarks" / "results"


# ---------------------------------------------------------------------------------------
# mesh
# ---------------------------------------------------------------------------------------


def build_mesh(s: float, h_surface: float = 1e-4, g: Geometry = GEOM):
    """Tensor mesh of the half model, cells of ``h_surface`` at every iron surface."""
    from skfem import MeshTri

    hf = min(s / 6.0, 1.0e-3)
    hs = min(h_surface, hf)
    hm, hi, hmax, grade = 1.0e-3, 4.0e-3, 0.06, 0.2
    # x: iron surfaces at the leg faces and the rail end; coil edges
    xp = np.array([0.0, g.xi - g.coil_thickness, g.xi, g.xo, g.xo + g.coil_thickness,
                   0.5 * g.rail_width, 0.5 * g.rail_width + 0.01])
    xs = np.array([hi, hm, hs, hs, hm, hs, hi])
    x = _grid_1d(xp, xs, 0.0, g.box_half_width, hmax, grade)
    x = _cap(x, 0.0, xp[-1], hi)
    yc0 = g.coil_gap_to_pole_face
    yl, yt = g.leg_height, g.leg_height + g.yoke_thickness
    ya = _grid_1d(np.array([0.0, yc0, yc0 + g.coil_height, yl, yt]),
                  np.array([hs, hm, hm, hs, hs]), 0.0, yt + g.box_above, hmax, grade)
    ya = _cap(ya, 0.0, yt, hi)
    ng = max(6, int(math.ceil(s / hf - 1e-9)))
    # gap: graded towards both iron faces (pole face and rail top)
    yg = _grid_1d(np.array([-s, 0.0]), np.array([hs, hs]), -s, 0.0, hf, grade)
    if yg.size - 1 < ng:
        yg = np.linspace(-s, 0.0, ng + 1)
    yb = _grid_1d(np.array([0.0, -g.rail_thickness]), np.array([hs, hs]),
                  -g.box_below, 0.0, hmax, grade)
    yb = _cap(yb, -g.rail_thickness, 0.0, hi) - s
    y = np.unique(np.round(np.concatenate([yb, yg, ya]), 12))
    return MeshTri.init_tensor(x, y)


# ---------------------------------------------------------------------------------------
# P1 assembly (vectorised)
# ---------------------------------------------------------------------------------------


class P1:
    """Gradients, areas and sparse index pattern of P1 triangles."""

    def __init__(self, mesh) -> None:
        p, t = mesh.p, mesh.t
        self.t = t
        x, y = p[0][t], p[1][t]                      # (3, ne)
        det = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0])
        self.area = 0.5 * np.abs(det)
        # grad lambda_i = (y_j - y_k, x_k - x_j)/det (cyclic)
        gx = np.array([y[1] - y[2], y[2] - y[0], y[0] - y[1]]) / det
        gy = np.array([x[2] - x[1], x[0] - x[2], x[1] - x[0]]) / det
        self.gx, self.gy = gx, gy
        self.n = p.shape[1]
        self.rows = np.repeat(t, 3, axis=0).ravel()      # (9 ne): i index
        self.cols = np.tile(t, (3, 1)).ravel()           # j index
        self.nodal_area = np.bincount(t.ravel(), np.repeat(self.area[None] / 3, 3, 0).ravel(),
                                      self.n)

    def grad(self, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a = A[self.t]
        return (a * self.gx).sum(0), (a * self.gy).sum(0)

    def lumped(self, mask: np.ndarray) -> np.ndarray:
        """Row-sum mass vector int_mask v_i over the elements in ``mask``."""
        w = np.where(mask, self.area, 0.0) / 3.0
        return np.bincount(self.t.ravel(), np.repeat(w[None], 3, 0).ravel(), self.n)

    def stiffness(self, nu: np.ndarray, c: np.ndarray, ax: np.ndarray, ay: np.ndarray):
        """K_ij = int nu grad_i.grad_j + c (ga.grad_i)(ga.grad_j)."""
        gx, gy = self.gx, self.gy
        dg = gx * ax + gy * ay                            # (3, ne)
        k = (nu * self.area)[None, None] * (gx[:, None] * gx[None] + gy[:, None] * gy[None])
        k = k + (c * self.area)[None, None] * (dg[:, None] * dg[None])
        return sp.csr_matrix((k.ravel(), (self.rows, self.cols)), shape=(self.n, self.n))

    def residual(self, nu: np.ndarray, ax: np.ndarray, ay: np.ndarray) -> np.ndarray:
        r = (nu * self.area)[None] * (self.gx * ax + self.gy * ay)
        return np.bincount(self.t.ravel(), r.ravel(), self.n)


# ---------------------------------------------------------------------------------------
# transient solver
# ---------------------------------------------------------------------------------------


@dataclass
class Transient:
    """Time histories of one FEM run (SI)."""

    time_s: np.ndarray
    current_A: np.ndarray
    psi_Wb: np.ndarray
    eddy_power_core_W: np.ndarray
    eddy_power_rail_W: np.ndarray
    energy_W: np.ndarray          # stored magnetic energy [J]
    nodes: int
    newton_max: int
    energy_residual: float        # |int UI - int RI^2 - int P - dW| / int UI
    wall_s: float
    meta: dict = field(default_factory=dict)

    @property
    def eddy_power_W(self) -> np.ndarray:
        return self.eddy_power_core_W + self.eddy_power_rail_W


def spd_solve(K, b: np.ndarray) -> np.ndarray:
    """``K^-1 b`` for a symmetric positive definite sparse ``K`` (SuperLU, symmetric mode)."""
    lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
    return lu.solve(b)


def static_newton(fe, free: np.ndarray, coeffs, src: np.ndarray, iron: np.ndarray, tol: float,
                  where: str) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Magnetostatic A for the source ``src`` by Newton with a halving line search, from the
    field of a nearly ideal iron (nu = 1e-3 on ``iron``); ``coeffs(A)`` gives the element
    fields and reluctivities (``ax, ay, _, nu, c``); ``where`` names the case in the error."""
    nu0 = np.where(iron, 1e-3, 1.0)
    z = np.zeros_like(nu0)
    A = np.zeros(fe.n)
    A[free] = spd_solve(fe.stiffness(nu0, z, z, z)[free][:, free], src[free])
    scale = np.linalg.norm(src[free])
    for _ in range(80):
        ax, ay, _, nu, c = coeffs(A)
        r = fe.residual(nu, ax, ay) - src
        rel = np.linalg.norm(r[free]) / scale
        if rel < tol:
            return A
        dA = np.zeros(fe.n)
        dA[free] = spd_solve(fe.stiffness(nu, c, ax, ay)[free][:, free], -r[free])
        step = 1.0
        while True:
            An = A + step * dA
            ax, ay, _, nu, _ = coeffs(An)
            rn = np.linalg.norm((fe.residual(nu, ax, ay) - src)[free]) / scale
            if rn < rel or step < 1 / 64:
                break
            step *= 0.5
        A = An
    raise RuntimeError(f"static Newton did not converge at {where}")



def bdf2_history(times: np.ndarray, n: int, hist_A: list) -> tuple[float, np.ndarray]:
    """Variable-step BDF2 for step ``n`` (BDF1 at ``n = 1``): ``dA/dt ~ a0 A_n + hist``
    from the previous solutions ``hist_A`` (the last one or two used) on the grid
    ``times`` [s]; used by every transient FEM here (U-magnet, TR09, guidance)."""
    h = times[n] - times[n - 1]
    if n == 1:
        return 1.0 / h, -hist_A[-1] / h
    w = h / (times[n - 1] - times[n - 2])
    return ((1 + 2 * w) / ((1 + w) * h),
            (-(1 + w) * hist_A[-1] + w * w / (1 + w) * hist_A[-2]) / h)

def bordered_newton(x: np.ndarray, res_jac, border: tuple, norm, *, nf: int, a0: float,
                    cache: dict, tol: float, owner, trace: bool = False):  # type: ignore[no-untyped-def]
    """One implicit time step's modified Newton solve of the bordered system
    ``[[K, Bc], [Br, Dd]]`` by its Schur complement (K symmetric positive definite: SuperLU
    in symmetric mode; the border: the bodies' or groups' potentials and the circuits'
    currents), with a halving line search.  The factorisation (``cache``) is kept while the
    step's ``a0`` is the same and the residual falls by at least 4x per iteration; every
    factorisation counts in ``owner.factorisations``.  ``res_jac(x, need_jac)`` gives the
    residual and (when asked) ``K``; ``norm(r)`` the scaled residual.  Returns ``(x, rel,
    iterations)``; raises where the step does not converge."""
    Bc, Br, Dd = border

    def factor(K):  # type: ignore[no-untyped-def]
        lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
        kb = lu.solve(Bc)
        cache.update(lu=lu, kb=kb, S=Dd - Br @ kb, a0=a0)
        owner.factorisations += 1

    def solve(r):  # type: ignore[no-untyped-def]
        kr = cache["lu"].solve(r[:nf])
        dy = np.linalg.solve(cache["S"], r[nf:] - Br @ kr)
        return -np.concatenate([kr - cache["kb"] @ dy, dy])

    fresh = cache.get("a0") != a0
    r, J = res_jac(x, need_jac=fresh)
    if fresh:
        factor(J)
    rel = norm(r)
    it = 0
    while True:
        it += 1
        dx = solve(r)
        stp = 1.0
        while True:
            xn = x + stp * dx
            rn, _ = res_jac(xn, need_jac=False)
            reln = norm(rn)
            if reln < max(rel, 1e-14) or stp < 1 / 64:
                break
            stp *= 0.5
        slow = reln > 0.25 * rel
        x, r, rel = xn, rn, reln
        if trace:
            print(f"    it {it} step {stp} rel {rel:.3e} dI {dx[-1]:.3e}", flush=True)
        small = np.linalg.norm(stp * dx[:nf]) <= 1e-9 * np.linalg.norm(x[:nf])
        if (rel < tol and small) or it >= 40:
            break
        if slow:
            _, J = res_jac(x)
            factor(J)
    return x, rel, it


def time_grid(t_end: float, dt0: float, block: int, dt_max: float) -> np.ndarray:
    """Steps of ``dt0`` doubling every ``block`` steps up to ``dt_max`` (then constant)."""
    t, dt, out, k = 0.0, dt0, [0.0], 0
    while t < t_end * (1 - 1e-12):
        t = min(t + dt, t_end)
        out.append(t)
        k += 1
        if k % block == 0:
            dt = min(2.0 * dt, dt_max)
    return np.array(out)


class UMagnetFem:
    """Static and transient P1 FEM of the U-magnet half model at a fixed gap."""

    def __init__(self, s: float, *, h_surface: float = 1e-4, sigma: float | None = None,
                 resistance: float = 2.0, material: str = "AISI 1008",
                 g: Geometry = GEOM) -> None:
        self.s, self.g = s, g
        self.mesh = build_mesh(s, h_surface, g)
        self.fe = P1(self.mesh)
        core, rail, sign = body_regions(self.mesh, s, g)
        self.iron = core | rail
        mat = mk.get_material(material)
        self.sigma = 1.0 / float(mat.resistivity_ohm_m) if sigma is None else sigma
        self.R = resistance
        self.rel = Reluctivity(None, material)
        self.mat = mat
        # energy density table w(B) = int_0^B H dB (trapezoid on a fine grid)
        bb = np.concatenate([np.linspace(0.0, 3.0, 30001), np.linspace(3.0, 20.0, 3401)[1:]])
        hh = np.asarray(mat.field_strength(bb), dtype=float)
        self._wb = bb
        self._tb = bb
        self._tnu, self._tc = self.rel.nu_r(bb)
        self._w = np.concatenate([[0.0], np.cumsum(0.5 * (hh[1:] + hh[:-1]) * np.diff(bb))])
        fe = self.fe
        self.m_core, self.m_rail = fe.lumped(core), fe.lumped(rail)
        self.vol_core, self.vol_rail = self.m_core.sum(), self.m_rail.sum()
        self.nside = 0.5 * g.turns
        self.ac = g.coil_thickness * g.coil_height
        w = sign * fe.area / 3.0
        self.bsign = np.bincount(fe.t.ravel(), np.repeat(w[None], 3, 0).ravel(), fe.n)
        # psi = kpsi . A (both halves)
        self.kpsi = 2.0 * g.depth * self.nside / self.ac * self.bsign
        p = self.mesh.p
        bnd = self.mesh.boundary_nodes()
        fixed = bnd[p[0, bnd] > 1e-9]                   # A = 0 except on the symmetry line
        self.free = np.setdiff1d(np.arange(fe.n), fixed)
        self.iron_e = self.iron

    # -- material coefficients per element (tables of fem_u_magnet.Reluctivity.nu_r on a
    #    fine grid; linear interpolation, 1e-4 T steps up to 3 T)
    def _coeffs(self, A: np.ndarray):
        ax, ay = self.fe.grad(A)
        b = np.hypot(ax, ay)
        nu_i = np.interp(b, self._tb, self._tnu)
        c_i = np.interp(b, self._tb, self._tc)
        nu = np.where(self.iron_e, nu_i, 1.0)
        c = np.where(self.iron_e, c_i, 0.0)
        return ax, ay, b, nu, c

    def energy(self, A: np.ndarray) -> float:
        """Stored magnetic energy W = int int_0^B H dB [J] (both halves)."""
        ax, ay = self.fe.grad(A)
        b = np.hypot(ax, ay)
        w = np.where(self.iron_e, np.interp(b, self._wb, self._w), b**2 / (2 * MU0))
        return float(2.0 * self.g.depth * np.sum(w * self.fe.area))

    def static(self, current: float, tol: float = 1e-10) -> np.ndarray:
        """Magnetostatic A at coil current ``current`` [A]."""
        src = MU0 * self.nside * current / self.ac * self.bsign
        return static_newton(self.fe, self.free, self._coeffs, src, self.iron_e, tol,
                             f"s={self.s}, I={current}")

    def step_response(self, i0: float, i1: float, times: np.ndarray,
                      tol: float = 1e-9, verbose: bool = False) -> Transient:
        """Voltage step U: R i0 -> R i1 at t = 0 from the static state at i0."""
        t_wall = time.perf_counter()
        fe, free = self.fe, self.free
        nf = free.size
        U = self.R * i1
        A = self.static(i0)
        mc, mr = self.m_core[free], self.m_rail[free]
        ms = self.m_core + self.m_rail
        msig = MU0 * self.sigma * ms[free]                 # mu0-scaled conductor mass
        kps = self.kpsi[free]
        bs = MU0 * self.nside / self.ac * self.bsign[free]
        hist_A = [A.copy()]
        cache: dict = {}
        self.factorisations = 0
        I, uc, ur = i0, 0.0, 0.0
        out_I, out_psi, out_pc, out_pr, out_W = [i0], [self.kpsi @ A], [0.0], [0.0], [self.energy(A)]
        nmax = 0
        for n in range(1, times.size):
            a0, hist = bdf2_history(times, n, hist_A)
            x = np.concatenate([A[free], [uc, ur, I]])
            scaleA = MU0 * self.nside * max(abs(i0), abs(i1)) / self.ac * np.linalg.norm(
                self.bsign[free])

            def res_jac(x, need_jac=True):
                Af = np.zeros(fe.n)
                Af[free] = x[:nf]
                uc_, ur_, I_ = x[nf:]
                ax, ay, _, nu, c = self._coeffs(Af)
                adot = a0 * x[:nf] + hist[free]
                ra = (fe.residual(nu, ax, ay)[free] + MU0 * self.sigma
                      * (mc * (adot - uc_) + mr * (adot - ur_)) - bs * I_)
                rc = mc @ adot - self.vol_core * uc_
                rr = mr @ adot - self.vol_rail * ur_
                rI = self.R * I_ + kps @ adot - U
                r = np.concatenate([ra, [rc, rr, rI]])
                if not need_jac:
                    return r, None
                K = fe.stiffness(nu, c, ax, ay)[free][:, free] + sp.diags(a0 * msig)
                return r, K

            # bordered Newton system [[K, Bc], [Br, Dd]] by its Schur complement: K is
            # symmetric positive definite (SuperLU in symmetric mode), 3 border columns
            Bc = np.stack([-MU0 * self.sigma * mc, -MU0 * self.sigma * mr, -bs], axis=1)
            Br = np.stack([a0 * mc, a0 * mr, a0 * kps], axis=0)
            Dd = np.diag([-self.vol_core, -self.vol_rail, self.R])

            def norm(r):
                # the body rows are linear (solved exactly by every Newton step)
                return max(np.linalg.norm(r[:nf]) / scaleA, abs(r[nf + 2]) / max(abs(U), 1e-9))

            # modified Newton: the factorisation is kept while the step size is the same
            # and the residual falls by at least 4x per iteration
            x, rel, it = bordered_newton(x, res_jac, (Bc, Br, Dd), norm, nf=nf, a0=a0,
                                         cache=cache, tol=tol, owner=self,
                                         trace=verbose > 1)
            if rel > 1e3 * tol:
                raise RuntimeError(f"Newton failed at t={times[n]:.3e}: residual {rel:.2e}")
            nmax = max(nmax, it)
            A = np.zeros(fe.n)
            A[free] = x[:nf]
            uc, ur, I = x[nf:]
            adot = a0 * A + hist
            adot[~np.isin(np.arange(fe.n), free)] = 0.0
            pc = 2 * self.g.depth * self.sigma * float(self.m_core @ (adot - uc) ** 2)
            pr = 2 * self.g.depth * self.sigma * float(self.m_rail @ (adot - ur) ** 2)
            hist_A.append(A.copy())
            if len(hist_A) > 2:
                hist_A.pop(0)
            out_I.append(I)
            out_psi.append(self.kpsi @ A)
            out_pc.append(pc)
            out_pr.append(pr)
            out_W.append(self.energy(A))
            if verbose and n % 20 == 0:
                print(f"  t={times[n] * 1e3:8.3f} ms I={I:8.4f} A its={it}", flush=True)
        Iv, pc, pr, W = map(np.asarray, (out_I, out_pc, out_pr, out_W))
        # energy balance (rectangle rule with the step-end values, as BDF2 computes them)
        dt = np.diff(times)
        ein = float(np.sum(dt * U * Iv[1:]))
        eohm = float(np.sum(dt * self.R * Iv[1:] ** 2))
        eed = float(np.sum(dt * (pc + pr)[1:]))
        res = abs(ein - eohm - eed - (W[-1] - W[0])) / abs(ein)
        return Transient(times, Iv, np.asarray(out_psi), pc, pr, W, fe.n, nmax, res,
                         time.perf_counter() - t_wall,
                         {"s_m": self.s, "i0_A": i0, "i1_A": i1, "sigma_S_per_m": self.sigma})


# ---------------------------------------------------------------------------------------
# FEM runs -> docs/fem_transient_results.json
# ---------------------------------------------------------------------------------------

#: (label, gap [m], I0 [A], I1 [A]) of the voltage steps U = R I0 -> R I1
CASES = (("10 mm, 10 -> 20 A", 0.010, 10.0, 20.0),
         ("6 mm, 10 -> 20 A", 0.006, 10.0, 20.0),
         ("10 mm, 20 -> 50 A", 0.010, 20.0, 50.0),
         ("6 mm, 20 -> 50 A", 0.006, 20.0, 50.0))
T_END = 0.25                 # s
H_SURFACE = 4e-4             # m, production mesh (see the convergence study)
DT0, BLOCK, DT_MAX = 2e-5, 8, 4e-3
#: convergence study at 10 mm, 10 -> 20 A: (label, h_surface, dt0, block); the production
#: settings are the case itself
STUDY = (("h 0.2 mm", 2e-4, DT0, BLOCK), ("h 0.4 mm, dt/2", 4e-4, DT0 / 2, 2 * BLOCK))


def _record(r: Transient, label: str, h: float) -> dict:
    return {"label": label, "gap_m": r.meta["s_m"], "i0_A": r.meta["i0_A"],
            "i1_A": r.meta["i1_A"], "sigma_S_per_m": r.meta["sigma_S_per_m"],
            "h_surface_m": h, "nodes": r.nodes, "steps": int(r.time_s.size - 1),
            "newton_max": r.newton_max, "energy_residual": r.energy_residual,
            "wall_s": r.wall_s, "time_s": r.time_s.tolist(), "current_A": r.current_A.tolist(),
            "psi_Wb": r.psi_Wb.tolist(), "eddy_power_core_W": r.eddy_power_core_W.tolist(),
            "eddy_power_rail_W": r.eddy_power_rail_W.tolist()}


def run_fem(part: str, only: list[int] | None = None) -> dict:
    """FEM runs of ``part`` ("cases": :data:`CASES`, "study": :data:`STUDY`), or of the
    cases numbered ``only``."""
    out: dict = {"generated_by": f"benchmarks/fem_u_magnet_transient.py --fem {part}",
                 "t_end_s": T_END, "runs": []}
    sigma = 0.0 if part == "noeddy" else None          # noeddy: the same steps, sigma = 0
    if part == "study":
        runs = [(label, 0.010, 10.0, 20.0, h, dt0, block) for label, h, dt0, block in STUDY]
    else:
        runs = [(label, s, i0, i1, H_SURFACE, DT0, BLOCK)
                for k, (label, s, i0, i1) in enumerate(CASES) if only is None or k in only]
    for label, s, i0, i1, h, dt0, block in runs:
        fem = UMagnetFem(s, h_surface=h, sigma=sigma)
        r = fem.step_response(i0, i1, time_grid(T_END, dt0, block, DT_MAX))
        rec = _record(r, label, h)
        rec["dt0_s"] = dt0
        out["runs"].append(rec)
        print(f"{part} {label}: {r.nodes} nodes, {r.time_s.size - 1} steps, {r.wall_s:.0f} s, "
              f"energy residual {r.energy_residual:.1e}", flush=True)
    return out


# ---------------------------------------------------------------------------------------
# comparison with the flux model
# ---------------------------------------------------------------------------------------

#: model variants compared with the FEM: (label, load_magnet keywords, variant keywords of
#: :func:`model_magnet`: network ``discretisation``, ``air_model``, ``rail = "one-sided"``)
#: the grid with the air as cells (``air_model = "cells"``, the statics within 3 %)
CELLS = {"discretisation": "grid", "air_model": "cells"}
#: the networks of the sigma = 0 comparison: variant keywords of :func:`model_magnet`
NETWORKS = {"lumped": {}, "grid": {"discretisation": "grid"}, "cells": CELLS}
MODELS: tuple[tuple[str, dict, dict], ...] = (
    ("lumped (today)", {"eddy_model": "lumped"}, {}),
    ("ladder n = 1 (2-D slab)", {"eddy_model": "ladder", "eddy_layers": 1}, {}),
    ("ladder n = 4", {"eddy_model": "ladder", "eddy_layers": 4}, {}),
    ("ladder n = 6", {"eddy_model": "ladder", "eddy_layers": 6}, {}),
    ("ladder n = 6, rail one-sided", {"eddy_model": "ladder", "eddy_layers": 6},
     {"rail": "one-sided"}),
    ("ladder_split n = 6", {"eddy_model": "ladder_split", "eddy_layers": 6}, {}),
    ("no eddy currents", {"eddy_currents": False}, {}),
    ("grid, lumped", {"eddy_model": "lumped"}, {"discretisation": "grid"}),
    ("grid, ladder n = 4", {"eddy_model": "ladder", "eddy_layers": 4},
     {"discretisation": "grid"}),
    ("grid, ladder n = 8", {"eddy_model": "ladder", "eddy_layers": 8},
     {"discretisation": "grid"}),
    ("grid, no eddy currents", {"eddy_currents": False}, {"discretisation": "grid"}),
    ("cells, lumped", {"eddy_model": "lumped"}, CELLS),
    ("cells, ladder n = 4", {"eddy_model": "ladder", "eddy_layers": 4}, CELLS),
    ("cells, ladder n = 6", {"eddy_model": "ladder", "eddy_layers": 6}, CELLS),
    ("cells, ladder n = 8", {"eddy_model": "ladder", "eddy_layers": 8}, CELLS),
    ("cells, no eddy currents", {"eddy_currents": False}, CELLS))
#: variants too slow to rerun with every comparison (~15-20 min per step on the shared
#: machine): their model runs are recorded in ``benchmarks/results/model_transient/`` by
#: ``--model LABEL --only K`` and read back (rerun: delete the file)
RECORDED_MODELS = ("grid, ladder n = 4", "grid, ladder n = 8", "cells, lumped", "cells, ladder n = 4",
                   "cells, ladder n = 6", "cells, ladder n = 8", "cells, no eddy currents",
                   "sigma 0, cells")
MODEL_DIR = RESULTS_DIR / "model_transient"


def load_results(part: str = "cases") -> list[dict]:
    """Recorded FEM runs (written by ``--fem PART``)."""
    return json.loads(RESULTS[part].read_text())["runs"]


def rise_time(t: np.ndarray, i: np.ndarray, i0: float, i1: float, frac: float = 0.632) -> float:
    """First time [s] the current passes ``i0 + frac (i1 - i0)`` (linear interpolation)."""
    y = (i - i0) / (i1 - i0) - frac
    k = np.nonzero(y >= 0.0)[0]
    if k.size == 0 or k[0] == 0:
        return float("nan")
    j = k[0]
    return float(t[j - 1] + (t[j] - t[j - 1]) * (-y[j - 1]) / (y[j] - y[j - 1]))


def metrics(t: np.ndarray, i: np.ndarray, e_eddy: np.ndarray, ref: dict) -> dict:
    """Errors of a model response against the recorded FEM run ``ref``."""
    tf = np.asarray(ref["time_s"])
    i_f = np.asarray(ref["current_A"])
    p_f = np.asarray(ref["eddy_power_core_W"]) + np.asarray(ref["eddy_power_rail_W"])
    i0, i1 = ref["i0_A"], ref["i1_A"]
    step = i1 - i0
    im = np.interp(tf, t, i)
    late = tf >= 1e-3 - 1e-12
    e_f = np.concatenate([[0.0], np.cumsum(np.diff(tf) * p_f[1:])])
    em = np.interp(tf, t, e_eddy)
    pm = np.diff(e_eddy) / np.diff(t)
    tm = 0.5 * (t[1:] + t[:-1])
    return {"err_1ms": float((np.interp(1e-3, t, i) - np.interp(1e-3, tf, i_f)) / step),
            "err_max": float(np.max(np.abs(im - i_f)[late]) / step),
            "t63_s": rise_time(t, i, i0, i1), "t63_fem_s": rise_time(tf, i_f, i0, i1),
            "e_eddy_J": float(em[-1]), "e_eddy_fem_J": float(e_f[-1]),
            "t_peak_s": float(tm[np.argmax(pm)]) if pm.size else float("nan"),
            "t_peak_fem_s": float(tf[1:][np.argmax(p_f[1:])])}


def model_magnet(*, discretisation: str = "lumped", air_model: str = "tubes",
                 rail: str = "slab", **kw):  # type: ignore[no-untyped-def]
    """The bundled U-magnet with ``load_magnet`` options ``kw`` on the ``discretisation``
    network (the grid's air as ``air_model``); ``rail = "one-sided"`` (ladder only)
    replaces the rail's two-sided slab by a one-sided one (diffusion from the gap face
    over the rail thickness: the slab of thickness ``2 t``), a variant measured and not
    adopted (docs/validation_fem.md)."""
    from maglevkit.circuit.elements import IronPath
    from maglevkit.circuit.ladder import ladder_branches
    from maglevkit.magnets.base import ModelOptions, build_magnet

    mag = mk.load_magnet("u-magnet", **kw)
    if discretisation != "lumped":
        params = json.loads(json.dumps(mag.parameters))
        params["magnet"]["discretisation"] = discretisation
        params["provenance"]["magnet.discretisation"] = "[E] modelling choice (benchmark)"
        if air_model != "tubes":
            params["magnet"]["air_model"] = air_model
            params["provenance"]["magnet.air_model"] = "[E] modelling choice (benchmark)"
        mag = build_magnet(params, options=ModelOptions(**kw))
    if rail == "one-sided":
        net = mag.network
        tube = net.branch("rail:tube1").elements[0]
        t = float(mag.parameters["rail"]["thickness"])
        iron = IronPath("iron_rail", tube.length_m, t * float(mag.parameters["magnet"]["depth"]),
                        tube.material)
        keep = [b for b in net.branches if b.name.split(":")[0] != "rail"]
        new = ladder_branches("rail", "RL", "RR", iron, thickness_m=2.0 * t,
                              resistivity_ohm_m=float(mag.parameters["rail"].get("resistivity")
                                                or tube.material.resistivity_ohm_m),
                              layers=kw.get("eddy_layers", 6))
        mag = replace(mag, network=mk.Network((*keep, *new), net.circuits, name=net.name))
    return mag


def simulate_model(ref: dict, *, discretisation: str = "lumped", air_model: str = "tubes",
                   rail: str = "slab", **kw):  # type: ignore[no-untyped-def]
    """The flux model's response to the recorded FEM run's voltage step.  The grid
    networks run uncompiled (their C code would take minutes to compile once per
    variant; uncompiled they run in 10-60 s)."""
    mag = model_magnet(discretisation=discretisation, air_model=air_model, rail=rail, **kw)
    times = np.asarray(ref["time_s"])
    fm = mk.FluxModel(mag, rtol=1e-7, compiled="never" if discretisation != "lumped"
                      else "auto")
    res = mk.simulate(fm, times, gaps_m=ref["gap_m"], voltages_V=mag.network.resistances[0]
                      * ref["i1_A"], initial_currents_A=ref["i0_A"])
    return res


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in text).strip("_")


def model_run(ref: dict, label: str, kw: dict, var: dict, *, record: bool,
              reuse: bool = False) -> dict | None:
    """One model variant's response to the recorded step ``ref`` (time, current, eddy loss,
    core/rail eddy energy, eddy states, wall time), written to :data:`MODEL_DIR`.
    :data:`RECORDED_MODELS` (and with ``reuse`` every variant) are read from there
    (``None`` if not recorded) unless ``record``, which runs and writes them."""
    path = MODEL_DIR / f"{_slug(label)}__{_slug(ref['label'])}.json"
    if (label in RECORDED_MODELS or reuse) and not record and path.exists():
        return json.loads(path.read_text())
    if label in RECORDED_MODELS and not record:
        return None
    t0 = time.perf_counter()
    res = simulate_model(ref, **var, **kw)
    core, rail = body_energies(res) if res.eddy_branch_names else (0.0, 0.0)
    run = {"label": label, "case": ref["label"], "time_s": res.time_s.tolist(),
           "current_A": res.currents_A[:, 0].tolist(), "eddy_loss_J": res.eddy_loss_J.tolist(),
           "e_core_J": core, "e_rail_J": rail, "states": len(res.eddy_branch_names),
           "wall_s": time.perf_counter() - t0}
    MODEL_DIR.mkdir(exist_ok=True)
    path.write_text(json.dumps(run, separators=(",", ":")) + "\n")
    print(f"wrote {path}", flush=True)
    return run


def body_energies(res) -> tuple[float, float]:  # type: ignore[no-untyped-def]
    """Eddy energy [J] of the core and of the rail over the run (sum of ``V_m dphi`` of
    every eddy element, trapezoidal in time)."""
    mmf, phi = res.eddy_mmf_A, res.eddy_flux_Wb
    e = np.sum(0.5 * (mmf[1:] + mmf[:-1]) * np.diff(phi, axis=0), axis=0)
    rail = np.array([n.startswith("rail") for n in res.eddy_branch_names])
    return float(e[~rail].sum()), float(e[rail].sum())


def compare(out_md: Path | None, figure: Path | None, *, reuse: bool = False) -> dict:
    cases = load_results("cases")
    study = load_results("study") if RESULTS["study"].exists() else []
    table: dict = {}
    curves: dict = {}
    for ref in cases:
        for label, kw, var in MODELS:
            run = model_run(ref, label, kw, var, record=False, reuse=reuse)
            if run is None:
                print(f"{ref['label']} {label}: no recorded run (--model), left out", flush=True)
                continue
            t, i, e = (np.asarray(run[k]) for k in ("time_s", "current_A", "eddy_loss_J"))
            table[ref["label"], label] = metrics(t, i, e, ref)
            table[ref["label"], label].update(
                e_core_J=run["e_core_J"], e_rail_J=run["e_rail_J"], wall_s=run["wall_s"],
                e_core_fem_J=_fem_energy(ref, "eddy_power_core_W"),
                e_rail_fem_J=_fem_energy(ref, "eddy_power_rail_W"), states=run["states"])
            curves[ref["label"], label] = (t, i, e)
            print(ref["label"], label, table[ref["label"], label], flush=True)
    noeddy = load_results("noeddy") if RESULTS["noeddy"].exists() else []
    fem_t63 = {r["label"]: rise_time(np.asarray(r["time_s"]), np.asarray(r["current_A"]),
                                     r["i0_A"], r["i1_A"]) for r in cases}
    static: dict = {}
    for ref in noeddy:
        for net, var in NETWORKS.items():
            run = model_run(ref, f"sigma 0, {net}", {"eddy_currents": False}, var,
                            record=False, reuse=reuse)
            if run is None:
                print(f"{ref['label']} sigma 0, {net}: no recorded run (--model), left out",
                      flush=True)
                continue
            t, i = np.asarray(run["time_s"]), np.asarray(run["current_A"])
            tf, i_f = np.asarray(ref["time_s"]), np.asarray(ref["current_A"])
            late = tf >= 1e-3 - 1e-12
            static[ref["label"], net] = {
                "err_max": float(np.max(np.abs(np.interp(tf, t, i) - i_f)[late])
                                 / (ref["i1_A"] - ref["i0_A"])),
                "t63_s": rise_time(t, i, ref["i0_A"], ref["i1_A"]),
                "t63_fem_s": rise_time(tf, i_f, ref["i0_A"], ref["i1_A"]),
                "t63_fem_eddy_s": fem_t63[ref["label"]]}
            print(ref["label"], net, "sigma = 0", static[ref["label"], net], flush=True)
    lines = _report(cases, study, table, static)
    if out_md is not None:
        text = out_md.read_text()
        a, b = "<!-- transient:begin -->", "<!-- transient:end -->"
        block = a + "\n" + "\n".join(lines) + "\n" + b
        if a in text:
            text = text[:text.index(a)] + block + text[text.index(b) + len(b):]
        else:
            text = text.rstrip("\n") + "\n\n" + block + "\n"
        out_md.write_text(text)
        print(f"wrote {out_md}")
    if figure is not None:
        _plot(cases, curves, figure)
    return table


def _fem_energy(ref: dict, key: str) -> float:
    t, p = np.asarray(ref["time_s"]), np.asarray(ref[key])
    return float(np.sum(np.diff(t) * p[1:]))


def _t63_err(x: dict | None) -> str:
    return f"{100 * (x['t63_s'] / x['t63_fem_s'] - 1):+.1f}" if x else "-"


def _report(cases: list[dict], study: list[dict], table: dict, static: dict) -> list[str]:
    L: list[str] = []
    L.append("## 5. Transient: voltage steps with solid iron (eddy currents)\n")
    L.append("Tests: `tests/test_eddy_ladder.py`, `tests/test_eddy_grid.py` (against the "
             "recorded FEM; all steps with `-m slow`).\n")
    L.append("Generated by `python benchmarks/fem_u_magnet_transient.py` (`--fem cases`, "
             "`--fem study` and `--fem noeddy` rerun the FEM and rewrite "
             "`benchmarks/results/fem_transient_*.json`, about 3 min of CPU per run; without "
             "them it only reruns the models against the recorded FEM; the slow variants' "
             "runs (grid ladder, air-cell network: `RECORDED_MODELS`) are recorded by "
             "`--model LABEL` (`--model \"sigma 0, cells\"`: the air cells against the "
             "sigma = 0 runs) in `benchmarks/results/model_transient/`, `--reuse` reads all "
             "recorded model runs).\n")
    c0 = cases[0]
    L.append(f"FEM: the 2-D magnetodynamic problem of `benchmarks/fem_u_magnet_transient.py` "
             f"(docstring): solid U-core and rail, sigma = {c0['sigma_S_per_m']:.3g} S/m (the "
             f"material's own 1/rho, `AISI 1008`: rho = 1.5e-7 ohm m), zero net current per "
             f"body, coil driven by U through R = 2 ohm, P1 with cells of "
             f"{c0['h_surface_m'] * 1e3:g} mm at every iron surface, variable-step BDF2 from "
             f"dt = {c0['dt0_s'] * 1e6:g} us (doubling every {BLOCK} steps, at most "
             f"{DT_MAX * 1e3:g} ms), Newton at every step.  Step at t = 0 from the static state "
             f"at I0 to U = R I1; t up to {T_END:g} s.\n")
    L.append("### FEM convergence (10 mm, 10 -> 20 A)\n")
    L.append("| run | nodes | steps | I(1 ms) [A] | I(10 ms) [A] | I(50 ms) [A] | t63 [ms] | "
             "E_eddy [J] | energy balance residual | wall [s] |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    for r in [cases[0], *study]:
        t, i = np.asarray(r["time_s"]), np.asarray(r["current_A"])
        p = np.asarray(r["eddy_power_core_W"]) + np.asarray(r["eddy_power_rail_W"])
        e = float(np.sum(np.diff(t) * p[1:]))
        lab = r["label"] if r in study else f"production (h {r['h_surface_m'] * 1e3:g} mm)"
        L.append(f"| {lab} | {r['nodes']} | {r['steps']} | {np.interp(1e-3, t, i):.4f} | "
                 f"{np.interp(1e-2, t, i):.4f} | {np.interp(5e-2, t, i):.4f} | "
                 f"{rise_time(t, i, r['i0_A'], r['i1_A']) * 1e3:.2f} | {e:.3f} | "
                 f"{r['energy_residual']:.1e} | {r['wall_s']:.0f} |")
    L.append("")
    L.append("### Flux model vs FEM\n")
    L.append("err: (model - FEM) current in % of the step; max over t >= 1 ms.  t63: time to "
             "63.2 % of the step.  E_eddy: eddy loss over the run (rail: its rail part); "
             "t_peak: time of the largest eddy power.  Networks: `lumped` (default) or "
             "`grid` (`discretisation = \"grid\"`, run uncompiled) or `cells` (the grid with "
             "`air_model = \"cells\"`, uncompiled, the flux model's sparse IDAS form).  "
             "Eddy elements: the "
             "model's eddy branches; wall: build and run of the flux model on the shared "
             "machine (load 2-7; the first run of a lumped network includes compiling its C "
             "code, ~1-3 min).  Plot: `docs/figures/fem-transient-steps.png` (below).\n")
    L.append("| case | model | err at 1 ms [%] | max err t >= 1 ms [%] | t63 model / FEM [ms] "
             "| t63 err [%] | E_eddy model / FEM [J] | E_eddy err [%] | E_rail model / FEM [J] "
             "| t_peak model / FEM [ms] | eddy elements | wall [s] |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for (case, model), m in table.items():
        et = 100 * (m["t63_s"] / m["t63_fem_s"] - 1)
        ee = 100 * (m["e_eddy_J"] / m["e_eddy_fem_J"] - 1)
        L.append(f"| {case} | {model} | {100 * m['err_1ms']:+.1f} | {100 * m['err_max']:.1f} | "
                 f"{m['t63_s'] * 1e3:.2f} / {m['t63_fem_s'] * 1e3:.2f} | {et:+.1f} | "
                 f"{m['e_eddy_J']:.3f} / {m['e_eddy_fem_J']:.3f} | {ee:+.0f} | "
                 f"{m['e_rail_J']:.3f} / {m['e_rail_fem_J']:.3f} | "
                 f"{m['t_peak_s'] * 1e3:.3f} / {m['t_peak_fem_s'] * 1e3:.3f} | {m['states']} | "
                 f"{m['wall_s']:.0f} |")
    L.append("")
    if static:
        L.append("### The same steps without eddy currents (FEM with sigma = 0, model with "
                 "`eddy_currents=False`)\n")
        L.append("This isolates the static network's error (its differential inductance, "
                 "sections 1-2) from the eddy model's: the rise time of a model with eddy "
                 "currents inherits it.\n")
        L.append("Eddy factor: t63 with eddy currents / t63 without, of the model (its own "
                 "no-eddy run on the same network) and of the FEM (sigma = 0 run); its error "
                 "is the eddy model's own share of the t63 error.\n")
        pairs = (("lumped", ("ladder_split n = 6",), "lumped (today)"),
                 ("grid", ("grid, ladder n = 4", "grid, ladder n = 8"), "grid, lumped"),
                 ("cells", ("cells, ladder n = 4", "cells, ladder n = 6", "cells, ladder n = 8"),
                  "cells, lumped"))
        L.append("| case | network | max err t >= 1 ms [%] | t63 model / FEM [ms] | "
                 "t63 err [%] | eddy factor FEM | ladder (err) | lumped (err) |")
        L.append("|---|---|---|---|---|---|---|---|")
        for (case, net), m in static.items():
            _, lad_names, lum_name = next(p for p in pairs if p[0] == net)
            noe_name = "no eddy currents" if net == "lumped" else f"{net}, no eddy currents"
            lum, noe = table.get((case, lum_name)), table.get((case, noe_name))
            f_fem = m["t63_fem_eddy_s"] / m["t63_fem_s"]

            def factor(x: dict | None, name: str = "") -> str:
                if not (x and noe):
                    return "-"
                f = x["t63_s"] / noe["t63_s"]
                return f"{name}{f:.3f} ({100 * (f / f_fem - 1):+.1f} %)"

            lads = [factor(table.get((case, n)), n + ": ") for n in lad_names
                    if (case, n) in table] or ["-"]
            L.append(f"| {case} | {net} | {100 * m['err_max']:.1f} | {m['t63_s'] * 1e3:.2f} / "
                     f"{m['t63_fem_s'] * 1e3:.2f} | {_t63_err(m)} | {f_fem:.3f} | "
                     f"{'<br>'.join(lads)} | {factor(lum)} |")
        L.append("")
    L.append("![transient steps: FEM, lumped, ladder](figures/fem-transient-steps.png)\n")
    return L


def _plot(cases: list[dict], curves: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, len(cases), figsize=(4.2 * len(cases), 10.0), squeeze=False)
    styles = {"lumped (today)": ("tab:red", "--"), "ladder n = 6": ("tab:cyan", ":"),
              "ladder_split n = 6": ("tab:blue", "-"), "grid, ladder n = 4": ("tab:green", "-"),
              "grid, no eddy currents": ("tab:olive", "-."), "no eddy currents": ("0.5", "-."),
              "cells, ladder n = 8": ("tab:purple", "-"),
              "cells, no eddy currents": ("tab:pink", "-.")}
    for j, ref in enumerate(cases):
        tf = np.asarray(ref["time_s"])
        i_f = np.asarray(ref["current_A"])
        i0, i1 = ref["i0_A"], ref["i1_A"]
        pf = np.asarray(ref["eddy_power_core_W"]) + np.asarray(ref["eddy_power_rail_W"])
        ax[0, j].semilogx(tf[1:] * 1e3, (i_f[1:] - i0) / (i1 - i0),
                          "k-", lw=2.5, alpha=0.5, label="FEM")
        ax[2, j].loglog(tf[1:] * 1e3, pf[1:], "k-", lw=2.5, alpha=0.5, label="FEM")
        for label, (col, ls) in styles.items():
            if (ref["label"], label) not in curves:
                continue
            t, i, e = curves[ref["label"], label]
            ax[0, j].semilogx(t[1:] * 1e3, (i[1:] - i0) / (i1 - i0), color=col, ls=ls,
                              label=label)
            ax[1, j].semilogx(tf[1:] * 1e3, 100 * (np.interp(tf, t, i) - i_f)[1:] / (i1 - i0),
                              color=col, ls=ls, label=label)
            if not label.endswith("no eddy currents"):
                p = np.diff(e) / np.diff(t)
                ax[2, j].loglog(0.5 * (t[1:] + t[:-1]) * 1e3, np.maximum(p, 1e-6), color=col,
                                ls=ls, label=label)
        ax[0, j].set_title(ref["label"])
        ax[0, j].set_ylabel("(I - I0)/(I1 - I0)")
        ax[1, j].set_ylabel("(I - I_FEM)/(I1 - I0) [%]")
        ax[1, j].axhspan(-5, 5, color="0.9", zorder=0)
        ax[1, j].set_ylim(-20, 20)
        ax[2, j].set_ylabel("eddy power [W]")
        ax[2, j].set_xlabel("t [ms]")
        for k in range(3):
            ax[k, j].grid(True, which="both", alpha=0.3)
        ax[2, j].set_ylim(bottom=max(1e-2, pf[1:].max() * 1e-4))
    ax[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--fem", choices=("cases", "study", "noeddy"),
                    help="run that part of the FEM (a few minutes of CPU each) and rewrite "
                         "benchmarks/results/fem_transient_PART.json")
    ap.add_argument("--only", default=None,
                    help="with --fem cases: comma-separated case numbers (0-based); the runs "
                         "go to fem_transient_cases-K.json, merged by --merge")
    ap.add_argument("--merge", action="store_true",
                    help="merge fem_transient_cases-K.json into fem_transient_cases.json")
    ap.add_argument("--no-docs", action="store_true", help="do not rewrite validation_fem.md")
    ap.add_argument("--model", default=None,
                    help="run and record the model variant LABEL (one of RECORDED_MODELS) on "
                         "the cases --only (default all) into benchmarks/results/"
                         "model_transient/")
    ap.add_argument("--reuse", action="store_true",
                    help="read every model variant recorded in benchmarks/results/"
                         "model_transient/ instead of rerunning it (the tables and figure "
                         "from the recorded runs)")
    args = ap.parse_args(argv)
    if args.model:
        if args.model.startswith("sigma 0, "):
            net = args.model.removeprefix("sigma 0, ")
            spec = (args.model, {"eddy_currents": False}, NETWORKS[net])
            runs = load_results("noeddy")
        else:
            spec = next(m for m in MODELS if m[0] == args.model)
            runs = load_results("cases")
        only = range(len(runs)) if args.only is None else [int(k) for k in args.only.split(",")]
        for k in only:
            model_run(runs[k], spec[0], spec[1], spec[2], record=True)
        return
    if args.merge:
        for part in ("cases", "noeddy"):
            parts = sorted(RESULTS_DIR.glob(f"fem_transient_{part}-*.json"))
            if not parts:
                continue
            runs = [r for p in parts for r in json.loads(p.read_text())["runs"]]
            order = [c[0] for c in CASES]
            runs.sort(key=lambda r: order.index(r["label"]))
            data = {"generated_by": f"benchmarks/fem_u_magnet_transient.py --fem {part}",
                    "t_end_s": T_END, "runs": runs}
            RESULTS[part].write_text(json.dumps(data, separators=(",", ":")) + "\n")
            for p in parts:
                p.unlink()
            print(f"wrote {RESULTS[part]}")
        return
    if args.fem:
        only = None if args.only is None else [int(k) for k in args.only.split(",")]
        data = run_fem(args.fem, only)
        RESULTS_DIR.mkdir(exist_ok=True)
        path = RESULTS[args.fem] if only is None else RESULTS_DIR / (
            f"fem_transient_{args.fem}-{'_'.join(map(str, only))}.json")
        path.write_text(json.dumps(data, separators=(",", ":")) + "\n")
        print(f"wrote {path}")
        return
    compare(ROOT / "docs" / "validation_fem.md" if not args.no_docs else None,
            ROOT / "docs" / "figures" / "fem-transient-steps.png", reuse=args.reuse)


if __name__ == "__main__":
    main()
