"""Independent 2-D finite-element check of the TR09 standard levitation magnet (issue 26).

A longitudinal cut of ``tr09-standard`` as maglevkit parameterises it (x along the track,
y up, pole faces at y = 0, the long stator above the gap ``s``), 2-D over the depth
``pole_width``:

* 12 pole cores ``pole_length`` x ``core_height`` at the pole pitch, alternating polarity,
  each with its coil (two sides ``coil_thickness`` x ``coil_height``, ``coil_to_face``
  below the face), the two LIG grooves (``lig_groove_width`` x ``lig_groove_depth``) cut
  into each pole face at a third of the pole length from the pole centre (the file does
  not give their position; the network does not depend on it), the pole back
  (``back_height``) from the outer edge of pole 1 to the outer edge of pole 12;
* the slotted stator: open rectangular slots ``slot_opening`` x ``slot_depth`` at the
  ``slot_pitch`` (3 per pole pitch), teeth in between, the yoke (``yoke_height``) above;
  it runs through the whole air box;
* iron: the magnet's material (cores, back) and the stator's (teeth; the yoke with the
  depth ratio pole_width/stator width, i.e. the stator's real width 0.185 m,
  ``fem_common.Reluctivity``), everything else air.

Both circuits carry the same current.  The magnet is mirror-antisymmetric about its centre
(pole 6 = -pole 7), so only x >= 0 is meshed (A even, natural condition at x = 0): the rear
circuit, poles 7-12; the front circuit mirrors it.  For the stator positions whose slot
pattern is mirror-symmetric (tooth or slot centred on the poles: ``offset`` 0 or
``slot_pitch/2``) this is exact; for the others the half model mirrors the stator at
x = 0, a defect of the slot pattern at the magnet's centre, between poles 6 and 7, where
the pole back and stator segment carry almost no flux (checked against the whole magnet,
``half=False``, in the convergence study).  ``offset`` is the distance from a pole centre
to the centre of the next tooth in +x.

Outputs per (s, I, offset): total force by the Maxwell stress averaged over the whole
air band of the gap (all horizontal lines through it), flux linkage per circuit, the
differential inductance of a circuit with both currents changing together (exact, from
the Newton tangent: ``dA/dI = K_t^-1 dJ/dI``), pole forces (the band stress over each
pole pitch), the fluxes of the iron regions (from differences of A) and their derivatives
in the current (``dflux``, from the tangent's dA/dI), and the magnetic potential drops
along lines through junction, core, gap, tooth, pole back and yoke with their current
derivatives (``mmf``; ``--diagnose S_MM I_A`` records one point at the grid's stator
positions into ``benchmarks/results/fem_tr09_diagnosis.json``; ``--core S_MM I_A`` the
same with the fluxes across the core every 10 mm of its height and in thirds of its width,
``core_y*`` and ``core_flank_lo``/``core_centre``/``core_flank_hi``, into
``benchmarks/results/fem_tr09_core.json``).

``python benchmarks/fem_tr09.py`` runs the convergence study and the grid and writes
``benchmarks/results/fem_tr09_*.json``; ``--compare`` prints the network against them.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import maglevkit as mk  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem_common import MU0, Reluctivity, cap, error_row, grid_1d, solve_nonlinear  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


@dataclass(frozen=True)
class Geometry:
    """The longitudinal cut of a levitation magnet file (all m)."""

    poles: int
    tau: float            # pole pitch
    lp: float             # pole length (along x)
    depth: float          # pole width = the 2-D depth
    hcore: float
    hc: float
    tc: float
    hf: float
    turns: float
    hb: float
    ng: int
    bg: float
    dg: float
    slot_pitch: float
    slot_open: float
    slot_depth: float
    yoke: float
    stator_width: float
    core_material: str
    stator_material: str
    box_end: float = 0.6      # air box beyond the magnet's ends [m]
    box_above: float = 0.4    # above the stator yoke
    box_below: float = 0.4    # below the pole back

    @classmethod
    def from_magnet(cls, magnet: mk.Magnet, **kw: float) -> Geometry:
        m, st = magnet.parameters["magnet"], magnet.parameters["stator"]
        return cls(int(m["poles"]), m["pole_pitch"], m["pole_length"], m["pole_width"],
                   m["core_height"], m["coil_height"], m["coil_thickness"], m["coil_to_face"],
                   m["turns_per_pole"], m["back_height"], int(m["lig_grooves"]),
                   m["lig_groove_width"], m["lig_groove_depth"], st["slot_pitch"],
                   st["slot_opening"], st["slot_depth"], st["yoke_height"], st["width"],
                   m["material"], st["material"], **kw)

    def centres(self) -> np.ndarray:
        """Pole centres, magnet centred on x = 0."""
        return (np.arange(self.poles) - 0.5 * (self.poles - 1)) * self.tau

    def grooves(self, xc: float) -> list[tuple[float, float]]:
        """x-intervals of the LIG grooves of the pole centred on ``xc``: evenly spread."""
        out = []
        for j in range(self.ng):
            c = xc - 0.5 * self.lp + self.lp * (j + 1) / (self.ng + 1)
            out.append((c - 0.5 * self.bg, c + 0.5 * self.bg))
        return out

    def slots(self, offset: float, lo: float, hi: float) -> list[tuple[float, float]]:
        """x-intervals of the stator slots in [lo, hi]; a tooth centre sits ``offset``
        from each pole centre (pole pitch = whole slot pitches)."""
        x0 = self.centres()[0] + offset + 0.5 * self.slot_pitch      # a slot centre
        k0 = math.floor((lo - x0) / self.slot_pitch) - 1
        k1 = math.ceil((hi - x0) / self.slot_pitch) + 1
        out = []
        for k in range(k0, k1 + 1):
            c = x0 + k * self.slot_pitch
            a, b = c - 0.5 * self.slot_open, c + 0.5 * self.slot_open
            if b > lo and a < hi:
                out.append((max(a, lo), min(b, hi)))
        return out


def symmetric(g: Geometry, offset: float) -> bool:
    """Is the slot pattern mirror-symmetric about the magnet centre (half model valid)?"""
    r = (2.0 * (g.centres()[g.poles // 2] + offset)) % g.slot_pitch
    return min(r, g.slot_pitch - r) < 1e-9


def build_mesh(g: Geometry, s: float, offset: float, refine: float = 1.0, half: bool = True):  # type: ignore[no-untyped-def]
    from skfem import MeshTri

    he = min(s / 4.0, 2.0e-3) / refine          # gap, pole and tooth corners
    hm = 3.0e-3 / refine                        # other material edges
    hi = 8.0e-3 / refine                        # cap inside the iron
    hmax = 0.08 / refine
    grade = 0.25
    xc = g.centres()
    x_end = xc[-1] + 0.5 * g.lp + g.tc           # magnet end (coil outer side)
    xb = x_end + g.box_end
    lo = 0.0 if half else -xb
    pts, sz = [], []
    for c in xc:
        if half and c < 0:
            continue
        for e in (c - 0.5 * g.lp, c + 0.5 * g.lp):
            pts.append(e)
            sz.append(he)
        for e in (c - 0.5 * g.lp - g.tc, c + 0.5 * g.lp + g.tc):
            pts.append(e)
            sz.append(hm)
        for a, b in g.grooves(c):
            pts += [a, b]
            sz += [hm, hm]
    for a, b in g.slots(offset, lo, xb):
        for e in (a, b):
            if lo < e < xb:
                pts.append(e)
                near = abs(e) < x_end + 0.1
                sz.append(he if near else 2.0 * hm)
    x = grid_1d(np.array(pts), np.array(sz), lo, xb, hmax, grade)
    x = cap(x, lo, x_end + 0.1, hi)
    # y: magnet below 0, gap (uniform), stator above s
    yb0 = -g.hcore - g.hb
    ym = grid_1d(np.array([yb0, -g.hcore, -g.hf - g.hc, -g.hf, -g.dg, 0.0]),
                 np.array([hm, hm, hm, hm, hm, he]), yb0 - g.box_below, 0.0, hmax, grade)
    ym = cap(ym, yb0, 0.0, hi)
    ng = max(4, int(math.ceil(s / he - 1e-9)))
    yg = np.linspace(0.0, s, ng + 1)[1:-1]
    top = g.slot_depth + g.yoke
    ys = grid_1d(np.array([0.0, g.slot_depth, top]), np.array([he, hm, hm]), 0.0,
                 top + g.box_above, hmax, grade)
    ys = cap(ys, 0.0, top, hi) + s
    y = np.unique(np.concatenate([ym, yg, ys]))
    return MeshTri.init_tensor(x, y)


def regions(mesh, g: Geometry, s: float, offset: float):  # type: ignore[no-untyped-def]
    """Element masks: magnet iron, stator teeth, stator yoke; coil current sign and
    circuit (0: front, poles 1-6; 1: rear, poles 7-12; -1: none)."""
    cx, cy = mesh.p[:, mesh.t].mean(axis=1)
    xc = g.centres()
    core = np.zeros(cx.shape, bool)
    sign = np.zeros(cx.shape)
    circ = -np.ones(cx.shape, int)
    for k, c in enumerate(xc):
        pol = 1.0 if k % 2 == 0 else -1.0
        inside = (np.abs(cx - c) < 0.5 * g.lp) & (cy > -g.hcore) & (cy < 0.0)
        for a, b in g.grooves(c):
            inside &= ~((cx > a) & (cx < b) & (cy > -g.dg))
        core |= inside
        incoil = (cy > -g.hf - g.hc) & (cy < -g.hf)
        left = incoil & (cx > c - 0.5 * g.lp - g.tc) & (cx < c - 0.5 * g.lp)
        right = incoil & (cx > c + 0.5 * g.lp) & (cx < c + 0.5 * g.lp + g.tc)
        sign[left], sign[right] = pol, -pol        # left +J, right -J: flux up for pol = +1
        circ[left | right] = 0 if k < g.poles // 2 else 1
    back = (np.abs(cx) < xc[-1] + 0.5 * g.lp) & (cy > -g.hcore - g.hb) & (cy < -g.hcore)
    teeth = (cy > s) & (cy < s + g.slot_depth)
    for a, b in g.slots(offset, cx.min() - 1.0, cx.max() + 1.0):
        teeth &= ~((cx > a) & (cx < b))
    yoke = (cy > s + g.slot_depth) & (cy < s + g.slot_depth + g.yoke)
    return core | back, teeth, yoke, sign, circ


@dataclass
class Point:
    s: float
    current: float
    offset: float
    half: bool
    dofs: int
    iterations: int
    force_N: float                  # total, both circuits
    psi_Wb: list[float]             # per circuit (front, rear)
    L_H: list[float]                # d psi_c / dI, both currents together
    coenergy_J: float
    pole_force_N: list[float]       # poles 1..12 (band stress over each pole pitch)
    flux: dict                      # region fluxes [Wb] per pole / segment
    seconds: float
    dflux: dict | None = None       # their derivatives [Wb/A] (both currents together)
    mmf: dict | None = None         # potential drops [A] and their dI [A/A] along lines


def solve(g: Geometry, s: float, current: float, offset: float = 0.0, *, refine: float = 1.0,
          half: bool | None = None, order: int = 2, tol: float = 1e-9,
          A0: np.ndarray | None = None) -> tuple[Point, np.ndarray]:
    """One FEM solution; returns the outputs and A (for a warm start)."""
    from skfem import Basis, ElementTriP1, ElementTriP2, LinearForm, asm

    t0 = time.time()
    if half is None:
        half = True
    mesh = build_mesh(g, s, offset, refine, half)
    iron, teeth, yoke, sign, circ = regions(mesh, g, s, offset)
    basis = Basis(mesh, ElementTriP2() if order == 2 else ElementTriP1())
    nqp = basis.X.shape[1]
    area = g.tc * g.hc
    parts = [(iron, Reluctivity(material=g.core_material)),
             (teeth, Reluctivity(material=g.stator_material)),
             (yoke, Reluctivity(material=g.stator_material,
                                depth_ratio=g.depth / g.stator_width))]

    @LinearForm
    def load(v, w):
        return w.sg * v

    loads = [asm(load, basis, sg=np.repeat((sign * (circ == c))[:, None], nqp, axis=1))
             for c in (0, 1)]
    jr = MU0 * g.turns / area                    # mu0 J per ampere
    rhs = jr * current * (loads[0] + loads[1])
    if half:
        D = basis.get_dofs(mesh.facets_satisfying(lambda p: p[0] > 1e-9, boundaries_only=True))
    else:
        D = basis.get_dofs(mesh.boundary_facets())
    free = np.setdiff1d(np.arange(basis.N), D.all())
    sol = solve_nonlinear(basis, parts, rhs, free, tol=tol, A0=A0, tangent=True)
    A = sol.A
    # differential inductance: dA/dI from the tangent stiffness
    import scipy.sparse.linalg as spla
    dA = np.zeros(basis.N)
    lu = spla.splu(sol.tangent.tocsc(), permc_spec="MMD_AT_PLUS_A",
                   options={"SymmetricMode": True})
    dA[free] = lu.solve(jr * (loads[0] + loads[1])[free])
    d = g.depth
    psi = [d * g.turns / area * float(ld @ A) for ld in loads]
    L = [d * g.turns / area * float(ld @ dA) for ld in loads]
    if half:                                     # the front circuit mirrors the rear one
        psi[0], L[0] = psi[1], L[1]
    ga, dx = sol.grad, basis.dx
    cx, cy = mesh.p[:, mesh.t].mean(axis=1)
    t_yy = (ga[0] ** 2 - ga[1] ** 2) / (2 * MU0)
    band = (cy > 0.0) & (cy < s)
    sym = 2.0 if half else 1.0
    fx = np.sum(t_yy * dx, axis=1) * d / s       # per element
    force = sym * float(np.sum(fx[band]))
    xc = g.centres()
    edges = np.concatenate([[-np.inf], 0.5 * (xc[1:] + xc[:-1]), [np.inf]])
    pf = [float(np.sum(fx[band & (cx > a) & (cx < b)])) for a, b in
          zip(edges[:-1], edges[1:], strict=True)]
    if half:
        pf = pf[::-1][: g.poles // 2] + pf[g.poles // 2:]
    iron_all = [iron, teeth, yoke]
    wc = b2 = sol.b**2 / (2 * MU0)
    for (mask, mat) in parts:
        q = np.repeat(mask[:, None], nqp, axis=1)
        wc = np.where(q, mat.coenergy_density(sol.b), wc)
    del b2, iron_all
    coen = sym * d * float(np.sum(wc * dx))
    flux = region_fluxes(basis, A, g, s, offset, half)
    dflux = region_fluxes(basis, dA, g, s, offset, half)
    # H and dH/dI per element (element means): mu0 H = nu B, mu0 dH = nu dB + c (B.dB) B
    # with the Newton coefficients (nu, c) of fem_common.solve_nonlinear
    dga = basis.interpolate(dA).grad
    cc = np.zeros_like(sol.b)
    for (mask, mat) in parts:
        q = np.repeat(mask[:, None], nqp, axis=1)
        cc = np.where(q, mat.nu_r(sol.b)[1], cc)
    bx, by, dbx, dby = ga[1], -ga[0], dga[1], -dga[0]
    bdb = bx * dbx + by * dby
    fields = {"mmf": ((sol.nu * bx).mean(axis=1) / MU0, (sol.nu * by).mean(axis=1) / MU0),
              "dmmf": ((sol.nu * dbx + cc * bdb * bx).mean(axis=1) / MU0,
                       (sol.nu * dby + cc * bdb * by).mean(axis=1) / MU0)}
    mmf = {tag: mmf_drops(mesh, hxy, g, s, offset, half) for tag, hxy in fields.items()}
    pt = Point(s, current, offset, bool(half), int(basis.N), sol.iterations, force, psi, L, coen,
               pf, flux, time.time() - t0, dflux, mmf)
    return pt, A


def mmf_drops(mesh, hxy: tuple[np.ndarray, np.ndarray], g: Geometry, s: float,  # type: ignore[no-untyped-def]
              offset: float, half: bool, n: int = 400) -> dict:
    """Magnetic potential drops ``int H . dl`` [A] (absolute values) per pole along
    straight lines, H = nu B from each element's mean field (midpoint rule on ``n``
    points per line; ``hxy`` the element means of H, or of dH/dI for the incremental
    drops).  With c the pole centre, ``y_b`` the pole back's mid-line, ``y_t``
    the tooth tips (``s``), ``y_y`` the yoke's mid-line: ``corner`` (c, y_b) -> (c,
    -core_height); ``core`` (c, -core_height) -> (c, 0) (the core above and along the
    coil and the shoe); ``gap`` (c, 0) -> (c_t, y_t), c_t the centre of the tooth nearest
    to the pole centre; ``teeth`` (c_t, y_t) -> (c_t, y_y); ``back`` (c, y_b) -> (c + tau/2,
    y_b); ``yoke`` (c, y_y) -> (c + tau/2, y_y).  Between the face and the yoke no current
    flows, so ``gap + teeth`` does not depend on the path."""
    find = mesh.element_finder()
    hx, hy = hxy
    xc = g.centres()
    keep = [k for k in range(g.poles) if not half or xc[k] > 0]
    slots = g.slots(offset, xc[0] - g.tau, xc[-1] + g.tau)
    tooth_c = np.array([0.5 * (slots[i][1] + slots[i + 1][0]) for i in range(len(slots) - 1)])
    yb, yy = -g.hcore - 0.5 * g.hb, s + g.slot_depth + 0.5 * g.yoke

    def drop(p: tuple[float, float], q: tuple[float, float]) -> float:
        t = (np.arange(n) + 0.5) / n
        x, y = p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])
        e = find(x, y)
        return float(np.sum(hx[e] * (q[0] - p[0]) + hy[e] * (q[1] - p[1])) / n)

    out: dict[str, dict[str, float]] = {}
    for k in keep:
        c = xc[k]
        ct = float(tooth_c[np.argmin(np.abs(tooth_c - c))])
        vals = {"corner": drop((c, yb), (c, -g.hcore)), "core": drop((c, -g.hcore), (c, 0.0)),
                "gap": drop((c, 0.0), (ct, s)), "teeth": drop((ct, s), (ct, yy))}
        if k + 1 < g.poles:
            vals["back"] = drop((c, yb), (c + 0.5 * g.tau, yb))
            vals["yoke"] = drop((c, yy), (c + 0.5 * g.tau, yy))
        for tag, v in vals.items():
            out.setdefault(tag, {})[str(k + 1)] = v
    return out


def region_fluxes(basis, A: np.ndarray, g: Geometry, s: float, offset: float,  # type: ignore[no-untyped-def]
                  half: bool) -> dict:
    """Fluxes [Wb] (absolute values) per pole from differences of A along lines:
    ``core`` at mid-coil height, ``shoe`` between coil and face, ``face`` just below the
    face, ``gap`` at mid-gap over the pole pitch (window centre to window centre),
    ``back`` in the pole back at each window centre, ``yoke`` in the stator yoke there,
    ``tooth_max_B`` the largest tooth flux density at mid-tooth height within the pole
    pitch and ``tip_max_B`` at the tooth tips, ``teeth`` the sum of the tooth fluxes at
    mid-tooth height over the pole pitch (its three teeth) and ``tooth_mid`` the flux of
    the tooth nearest to the pole centre there."""
    xc = g.centres()
    keep = [k for k in range(g.poles) if not half or xc[k] > 0]
    eps = 1e-7
    pts: list[tuple[float, float]] = []
    tags: list[tuple[str, int]] = []

    def pair(tag: str, k: int, p: tuple[float, float], q: tuple[float, float]) -> None:
        pts.extend([p, q])
        tags.append((tag, k))

    ymid = -g.hf - 0.5 * g.hc
    for k in keep:
        c = xc[k]
        a, b = c - 0.5 * g.lp + eps, c + 0.5 * g.lp - eps
        pair("core", k, (a, ymid), (b, ymid))
        # along the core: every 10 mm from the face to the back's underside; across it at
        # mid-coil: the outer thirds (flanks) and the centre third
        for ymm in range(10, int(round(g.hcore * 1e3)) + 1, 10):
            yy = -min(ymm * 1e-3, g.hcore - eps)
            pair(f"core_y{ymm}", k, (a, yy), (b, yy))
        third = (b - a) / 3.0
        pair("core_flank_lo", k, (a, ymid), (a + third, ymid))
        pair("core_centre", k, (a + third, ymid), (b - third, ymid))
        pair("core_flank_hi", k, (b - third, ymid), (b, ymid))
        pair("shoe", k, (a, -0.5 * g.hf), (b, -0.5 * g.hf))
        pair("face", k, (a, -eps), (b, -eps))
        lo_w, hi_w = c - 0.5 * g.tau, c + 0.5 * g.tau
        pair("gap", k, (max(lo_w, eps) if half else lo_w, 0.5 * s), (hi_w, 0.5 * s))
        if k + 1 < g.poles:
            xw = c + 0.5 * g.tau
            pair("back", k, (xw, -g.hcore - g.hb + eps), (xw, -g.hcore - eps))
            pair("yoke", k, (xw, s + g.slot_depth + eps), (xw, s + g.slot_depth + g.yoke - eps))
    # teeth within each pole pitch
    slots = g.slots(offset, xc[0] - g.tau, xc[-1] + g.tau)
    teeth = [(slots[i][1], slots[i + 1][0]) for i in range(len(slots) - 1)]
    tooth_tags = []
    for k in keep:
        c = xc[k]
        for a, b in teeth:
            m = 0.5 * (a + b)
            if c - 0.5 * g.tau <= m < c + 0.5 * g.tau and (not half or a > 0):
                for tag, y in (("tooth", s + 0.5 * g.slot_depth), ("tip", s + eps)):
                    pts.extend([(a + eps, y), (b - eps, y)])
                    tooth_tags.append((tag, k, b - a, abs(m - c)))
    P = np.array(pts).T
    val = basis.probes(P) @ A
    d = g.depth
    out: dict[str, dict[int, float]] = {}
    for i, (tag, k) in enumerate(tags):
        out.setdefault(tag, {})[k + 1] = d * abs(val[2 * i + 1] - val[2 * i])
    base = 2 * len(tags)
    nearest: dict[int, float] = {}
    for j, (tag, k, w, dc) in enumerate(tooth_tags):
        phi = d * abs(val[base + 2 * j + 1] - val[base + 2 * j])
        key = f"{tag}_max_B"
        out.setdefault(key, {})
        out[key][k + 1] = max(out[key].get(k + 1, 0.0), phi / (d * w))
        if tag == "tooth":
            out.setdefault("teeth", {})
            out["teeth"][k + 1] = out["teeth"].get(k + 1, 0.0) + phi
            if dc < nearest.get(k, math.inf):
                nearest[k] = dc
                out.setdefault("tooth_mid", {})[k + 1] = phi
    return {tag: {str(k): v for k, v in vals.items()} for tag, vals in out.items()}


# ---------------------------------------------------------------------------------------
# the network
# ---------------------------------------------------------------------------------------


def cut_magnet(name: str = "tr09-standard", flux_paths: str = "split") -> mk.Magnet:
    """The magnet's network as a longitudinal cut (``end_effects = false``) with the given
    ``flux_paths`` (``"split"``: the paths checked against this FEM; ``"paper"``: the
    former default), without eddy elements."""
    base = mk.load_magnet(name, eddy_currents=False)
    params = dict(base.parameters)
    params["magnet"] = {**params["magnet"], "end_effects": False, "flux_paths": flux_paths}
    params["provenance"] = {**params["provenance"],
                            "magnet.end_effects": "[E] modelling choice: 2-D cut",
                            "magnet.flux_paths": "[E] modelling choice"}
    return mk.build_magnet(params, options=base.options, source=base.source)


def network(magnet: mk.Magnet, s: float, current: float) -> dict:
    """The network's statics at one point: force, psi, L (both currents together),
    pole forces and branch fluxes."""
    sol = mk.solve_statics(magnet, gaps_m=s, currents_A=[current, current])
    L = np.asarray(sol.differential_inductance_H).reshape(2, 2).sum(axis=1)
    return {"force_N": float(np.ravel(sol.force_N)[0]),
            "psi_Wb": [float(v) for v in np.ravel(sol.flux_linkage_Wb)],
            "L_H": [float(v) for v in L],
            "pole_force_N": [float(v) for v in np.ravel(sol.pole_force_N)],
            "flux": dict(zip(sol.branch_names, map(float, np.ravel(sol.branch_flux_Wb)),
                             strict=True))}


def _save(name: str, data: object) -> Path:
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"fem_tr09_{name}.json"
    path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    return path


def _load(name: str) -> object:
    return json.loads((RESULTS / f"fem_tr09_{name}.json").read_text())


GAPS_MM = (6.0, 10.0, 20.0)
CURRENTS_A = (10.0, 33.5, 50.0, 80.0, 100.0)
#: the full grid (``--grid --full``): 8 gaps x 6 currents = 48 points, the first grid's 15
#: among them
GAPS_FULL_MM = (6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0)
CURRENTS_FULL_A = (10.0, 20.0, 33.5, 50.0, 80.0, 100.0)
#: mesh of the grid (sizes / 0.7; the convergence study measures what this costs)
GRID_REFINE = 0.7
#: stator positions [m]: tooth centred on the poles, a quarter slot pitch on, slot
#: centred.  Averaged with weights 1, 2, 1: four positions evenly over one slot pitch, as
#: three quarters on (0.0645) is the mirror image of a quarter on (measured: 10 mm/10 A,
#: 3668.0 vs 3668.1 N, psi 5.6499 vs 5.6501 Wb).
OFFSETS = (0.0, 0.0215, 0.043)
WEIGHTS = (0.25, 0.5, 0.25)


def _key(s: float, current: float, offset: float, refine: float = 1.0, order: int = 2,
         box: float = 1.0, half: bool = True) -> str:
    return (f"s{s * 1e3:g}_I{current:g}_o{offset * 1e3:g}"
            + (f"_r{refine:g}" if refine != 1.0 else "") + (f"_p{order}" if order != 2 else "")
            + (f"_box{box:g}" if box != 1.0 else "") + ("" if half else "_full"))


def run(g: Geometry, name: str, points: list[tuple[float, float, float]], *,
        refine: float = 1.0, order: int = 2, box: float = 1.0, half: bool = True) -> dict:
    """Solve ``points`` (s [m], I [A], offset [m]) not yet in ``fem_tr09_NAME.json``,
    saving after each; consecutive points on one mesh start from the previous A."""
    path = RESULTS / f"fem_tr09_{name}.json"
    data = json.loads(path.read_text()) if path.exists() else {}
    gb = Geometry(**{**g.__dict__, "box_end": g.box_end * box, "box_above": g.box_above * box,
                     "box_below": g.box_below * box})
    prev: tuple[float, float, float, np.ndarray] | None = None
    for s, current, off in points:
        key = _key(s, current, off, refine, order, box, half)
        if key in data:
            continue
        A0 = None
        if prev is not None and prev[0] == s and prev[1] == off:
            A0 = prev[3] * (current / prev[2])
        pt, A = solve(gb, s, current, off, refine=refine, order=order, A0=A0, half=half)
        prev = (s, off, current, A)
        data[key] = pt.__dict__
        _save(name, data)
        print(f"{key}: F {pt.force_N:.1f} N psi {pt.psi_Wb[1]:.4f} L {pt.L_H[1]:.4f} "
              f"({pt.dofs} dofs, {pt.iterations} it, {pt.seconds:.0f} s)", flush=True)
    return data


def averaged(data: dict, s: float, current: float) -> dict | None:
    """Mean over the stator positions (:data:`OFFSETS`, :data:`WEIGHTS`) of force, psi and
    L (rear circuit) at (s, I), or None if a position is missing."""
    pts = [data.get(_key(s, current, o, GRID_REFINE)) for o in OFFSETS]
    if any(p is None for p in pts):
        return None
    out = {k: float(np.dot(WEIGHTS, [p[k] if k == "force_N" else p[k][1] for p in pts]))
           for k in ("force_N", "psi_Wb", "L_H")}
    out["pole_force_N"] = list(np.dot(WEIGHTS, [p["pole_force_N"] for p in pts]))
    return out


def compare(magnet: mk.Magnet, data: dict, gaps_mm=GAPS_MM, currents=CURRENTS_A  # type: ignore[no-untyped-def]
            ) -> list[dict]:
    """Network vs FEM (position average) per point: errors in % ((net - FEM)/FEM)."""
    rows = []
    for smm in gaps_mm:
        for i in currents:
            fem = averaged(data, smm * 1e-3, i)
            if fem is None:
                continue
            net = network(magnet, smm * 1e-3, i)
            # the rear circuit (index 1), whose psi and L the FEM record holds (averaged())
            rows.append(error_row(smm, i, fem, force_N=net["force_N"], psi_Wb=net["psi_Wb"][1],
                                  L_H=net["L_H"][1]))
    return rows


def densities(magnet: mk.Magnet, data: dict, s: float, current: float) -> list[dict]:
    """Mean flux densities [T] per pole (rear circuit, poles 7-12) and region: FEM
    (position average) and network.  Regions: core (mid-coil), shoe (between coil and
    face; network: the core segment there), teeth (FEM: the most loaded tooth of the
    pole pitch at mid-height and at the tips; network: the gap branch's tooth element),
    pole back and stator yoke (the segment towards the next pole)."""
    g = Geometry.from_magnet(magnet)
    pts = [data[_key(s, current, o, GRID_REFINE)] for o in OFFSETS]
    net = network(magnet, s, current)["flux"]
    d = g.depth
    nseg = int(magnet.parameters["magnet"].get("coil_segments", 3))
    h = g.hc / nseg
    y_nodes = [g.hf + (j + 0.5) * h for j in range(nseg)]

    def core_flux(p: str, y: float) -> float:
        """Network core flux at depth y below the face (the segment holding y)."""
        if f"core_{p}" in net:                       # the core in one branch
            return abs(net[f"core_{p}"])
        return abs(net[f"core_{p}_{sum(yn < y for yn in y_nodes)}"])

    rows = []
    for k in range(g.poles // 2 + 1, g.poles + 1):
        def fem(tag: str, area: float | None, k: int = k) -> float:
            vals = [p["flux"][tag].get(str(k)) for p in pts]
            if any(v is None for v in vals):
                return float("nan")
            return float(np.dot(WEIGHTS, vals)) / (area if area else 1.0)
        p, q = f"p{k:02d}", f"p{k + 1:02d}"
        teeth = g.lp * d * (1.0 - g.slot_open / g.slot_pitch)
        rows.append({
            "pole": k,
            "core": (fem("core", g.lp * d),
                     core_flux(p, g.hf + 0.5 * g.hc - 1e-9) / (g.lp * d)),
            "shoe": (fem("shoe", g.lp * d), core_flux(p, 0.5 * g.hf) / (g.lp * d)),
            "teeth": (fem("tooth_max_B", None), abs(net.get(f"teeth_{p}", net[f"gap_{p}"])) / teeth),
            "tips": (fem("tip_max_B", None), float("nan")),
            "back": (fem("back", g.hb * d),
                     abs(net.get(f"back_{p}_{q}", float("nan"))) / (g.hb * d)),
            "yoke": (fem("yoke", g.yoke * g.stator_width),
                     abs(net.get(f"stator_{p}_{q}", float("nan"))) / (g.yoke * g.stator_width)),
        })
    return rows


def table(rows: list[dict]) -> str:
    lines = ["| s [mm] | I [A] | F_FEM [kN] | err F [%] | psi_FEM [Wb] | err psi [%] "
             "| L_FEM [H] | err L [%] |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['s_mm']:g} | {r['I_A']:g} | {r['F_fem'] / 1e3:.2f} | {r['eF']:+.1f} "
                     f"| {r['psi_fem']:.3f} | {r['epsi']:+.1f} | {r['L_fem']:.3f} "
                     f"| {r['eL']:+.1f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--magnet", default="tr09-standard")
    ap.add_argument("--probe", nargs=3, type=float, metavar=("S_MM", "I_A", "OFFSET_MM"))
    ap.add_argument("--refine", type=float, default=1.0)
    ap.add_argument("--flux-paths", default="split", help="network to compare: split, paper")
    ap.add_argument("--grid", action="store_true", help="the gap x current x offset grid")
    ap.add_argument("--compare", action="store_true", help="network vs the recorded grid")
    ap.add_argument("--full", action="store_true",
                    help="with --grid/--compare: the 48-point grid (GAPS_FULL_MM x CURRENTS_FULL_A)")
    ap.add_argument("--convergence", action="store_true", help="mesh, order, box, half model")
    ap.add_argument("--diagnose", nargs=2, type=float, metavar=("S_MM", "I_A"),
                    help="one point at the grid's stator positions with the incremental "
                         "region fluxes, into fem_tr09_diagnosis.json")
    ap.add_argument("--core", nargs=2, type=float, metavar=("S_MM", "I_A"),
                    help="one point at the grid's stator positions with the fluxes along "
                         "the core's height and across its width, into fem_tr09_core.json")
    args = ap.parse_args(argv)
    mag = cut_magnet(args.magnet, args.flux_paths)
    g = Geometry.from_magnet(mag)
    if args.probe:
        s, current, off = args.probe
        pt, _ = solve(g, s * 1e-3, current, off * 1e-3, refine=args.refine)
        net = network(mag, s * 1e-3, current)
        print(json.dumps(pt.__dict__, indent=1))
        print(f"network: F {net['force_N']:.1f} N, psi {net['psi_Wb']}, L {net['L_H']}")
        return
    if args.compare:
        grid = (GAPS_FULL_MM, CURRENTS_FULL_A) if args.full else (GAPS_MM, CURRENTS_A)
        print(table(compare(mag, _load("grid"), *grid)))  # type: ignore[arg-type]
    if args.convergence:
        # mesh (sizes / 0.7, 1, 1.4), element order, air box, and the half model at a
        # position whose slot pattern is not mirror-symmetric against the whole magnet
        for r in (GRID_REFINE, 1.0, 1.4):
            run(g, "convergence", [(0.010, 80.0, 0.0)], refine=r)
        run(g, "convergence", [(0.010, 80.0, 0.0)], refine=1.4, order=1)
        run(g, "convergence", [(0.010, 80.0, 0.0)], refine=GRID_REFINE, box=1.5)
        run(g, "convergence", [(0.010, 80.0, 0.0215)], refine=GRID_REFINE, half=False)
    if args.core:
        sd, idiag = args.core
        run(g, "core", [(sd * 1e-3, idiag, o) for o in OFFSETS], refine=GRID_REFINE)
    if args.diagnose:
        sd, idiag = args.diagnose
        run(g, "diagnosis", [(sd * 1e-3, idiag, o) for o in OFFSETS], refine=GRID_REFINE)
    if args.grid:
        order = (10.0, 20.0, 6.0)                # the most telling gaps first
        currents = CURRENTS_A
        if args.full:                            # the new gaps first, then the 20 A rows
            order = (8.0, 12.0, 14.0, 16.0, 18.0, 6.0, 10.0, 20.0)
            currents = CURRENTS_FULL_A
        pts = [(s * 1e-3, i, o) for s in order for o in OFFSETS for i in currents]
        run(g, "grid", pts, refine=GRID_REFINE)


if __name__ == "__main__":
    main()
