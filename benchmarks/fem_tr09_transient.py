# ruff: noqa: B023  (the Newton helpers are defined and used within one time step)
"""Voltage-step transient 2-D FEM of the TR09 levitation magnets with solid iron (issue 26).

The longitudinal cut of ``benchmarks/fem_tr09.py`` (its geometry, tensor mesh and regions,
unchanged: 12 cores, coils, LIG grooves, pole back, slotted stator through the air box;
half model x >= 0, the magnet mirror-antisymmetric) made magnetodynamic in the vector
potential ``A_z`` as the U-magnet's transient FEM (``benchmarks/fem_u_magnet_transient.py``:
its P1 assembly, time grid, BDF2 and modified Newton)::

    sigma (dA/dt - u_g) - div( nu(|grad A|) grad A ) = J_coil    in conductor group g
                          - div( nu grad A )          = J_coil    elsewhere
    int_g sigma (dA/dt - u_g) dA = 0                              (zero net current per group)
    U_c = R_c I_c + dpsi_c/dt                                     (per circuit)

**Conductors: what maglevkit's network models as conducting.**  The levitation builder
(``magnets/levitation.py``) puts a solid-bar eddy element (``EddyCurrent.solid_rectangular``,
the magnet material's own resistivity, ``9SMnPb28``: 1.5e-7 ohm m) on every core segment
(flux along the core, the eddy currents circling it in the core's horizontal section) and on
every pole-back segment between neighbouring poles (flux along the track, the currents
circling it in the back's vertical section); the stator is a laminated pack without eddy
elements.  The FEM models the same: cores and pole back solid with sigma = 1/rho, the
stator (teeth, yoke) non-conducting.  In 2-D the eddy currents flow along z and close at
the ends of the body across the track; "the same conductors" fixes where they close:

* ``groups = "slices"`` (default, the network's loops): every horizontal slice of a core
  (one mesh row) and every vertical slice of the pole back (one mesh column) carries zero
  net current: the loops circle the core's vertical flux within the core's section and the
  back's flux along the track within the back's section, as the network's eddy elements do;
* ``groups = "one"``: the cores and the back one solid body with one zero-net-current
  condition (also loops that run along z in one core and back in another, closing through
  the back's end faces; the network has no such loop): a sensitivity check.

The zero-current conditions are eliminated exactly (``u_g`` is the group mean of ``dA/dt``
with the lumped mass), so each group adds the dense block ``-b_g b_g^T / |g|`` to the
lumped conductor mass; only the circuits' currents border the sparse Newton system.

**Circuits.**  Every pole's coil as in fem_tr09 (``turns_per_pole`` over each coil side);
each circuit driven by a voltage step through its resistance, ``R_c = n_c *
resistance_per_pole``, as the network's electric circuits: at t = 0 from the static state at
I0 to ``U_c = R_c I1``.  The half model holds the circuits with poles in x > 0: the
standard magnet's rear circuit (poles 7-12); the bow magnet's c3 (poles 9-12) and the half
of c2 (poles 7-8, half its resistance and voltage; by symmetry c1 = c3).

**Stator position.**  One position, a quarter slot pitch from tooth-centred (``offset``
21.5 mm): of fem_tr09's three positions its statics are nearest the position average the
network's Carter coefficient stands for (10 mm / 33.5 A: psi +0.4 %, force +1.8 %,
docs/validation_fem.md); the half model's slot-pattern defect at the centre is measured
there at 3e-5 (fem_tr09).  ``--offset`` runs another position.

Outputs per run: circuit currents, flux linkages, the total force (Maxwell stress over the
gap band, both halves), eddy power in cores and back, stored energy; the energy balance
``int U I = int R I^2 + int P_eddy + Delta W`` checks the discretisation.

``python benchmarks/fem_tr09_transient.py --fem`` runs the cases (``--only K``: some of
them, ``--magnet tr09-bow``, ``--study``: the mesh and time-step convergence) into
``benchmarks/results/fem_tr09_transient.json``; without ``--fem`` it compares the recorded
FEM with maglevkit's ``FluxModel`` (no FEM solve).  Needs the optional extra
``validation`` (scikit-fem, only for the tensor mesh).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem_common import MU0, Reluctivity  # noqa: E402
from fem_tr09 import Geometry, build_mesh, cut_magnet, regions  # noqa: E402
from fem_u_magnet_transient import (  # noqa: E402
    P1,
    bdf2_history,
    bordered_newton,
    rise_time,
    static_newton,
    time_grid,
)

import maglevkit as mk  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
PATH = RESULTS / "fem_tr09_transient.json"

#: stator position [m] (a quarter slot pitch: nearest the position average, see docstring)
OFFSET = 0.0215
#: (label, gap [m], I0 [A], I1 [A]) of the voltage steps U = R I0 -> R I1 per circuit:
#: across the nominal point (31.7 A) below the knee (45 A at 10 mm), at the nominal gap and
#: a larger one; and from the nominal point into saturation
CASES = (("10 mm, 20 -> 40 A", 0.010, 20.0, 40.0),
         ("14 mm, 20 -> 40 A", 0.014, 20.0, 40.0),
         ("10 mm, 30 -> 60 A", 0.010, 30.0, 60.0))
#: groups with more nodes are bordered unknowns instead of dense blocks
BIG = 400
T_END = 3.0                  # s, ~7 electric time constants L/R = 0.61 H / 1.3 ohm
REFINE = 1.0                 # fem_tr09's mesh sizes / REFINE
DT0, BLOCK, DT_MAX = 5e-5, 8, 2e-2
#: convergence study on case 0: (label, refine, dt0, block, dt_max)
STUDY = (("mesh x 1.5", 1.5, DT0, BLOCK, DT_MAX),
         ("dt / 2", REFINE, DT0 / 2, 2 * BLOCK, DT_MAX / 2))


class Tr09Transient:
    """P1 magnetodynamics of a levitation magnet's half model at one gap and stator
    position (see the module docstring)."""

    def __init__(self, magnet: mk.Magnet, s: float, offset: float = OFFSET, *,
                 refine: float = REFINE, groups: str = "slices",
                 sigma: float | None = None) -> None:
        g = Geometry.from_magnet(magnet)
        self.g, self.s = g, s
        self.mesh = build_mesh(g, s, offset, refine, True)
        fe = self.fe = P1(self.mesh)
        iron, teeth, yoke, sign, _ = regions(self.mesh, g, s, offset)
        cx, cy = self.mesh.p[:, self.mesh.t].mean(axis=1)
        self.parts = [(iron, Reluctivity(material=g.core_material)),
                      (teeth, Reluctivity(material=g.stator_material)),
                      (yoke, Reluctivity(material=g.stator_material,
                                         depth_ratio=g.depth / g.stator_width))]
        # nu, dnu/dB and energy density tables per part (1e-4 T steps to 3 T)
        bb = np.concatenate([np.linspace(0.0, 3.0, 30001), np.linspace(3.0, 20.0, 3401)[1:]])
        self._bb = bb
        self._tab = []
        for _, rel in self.parts:
            nu, c = rel.nu_r(bb)
            w = bb * bb * nu / MU0 - rel.coenergy_density(bb)      # int_0^B H dB
            self._tab.append((nu, c, w))
        self.part = np.full(cx.shape, -1)
        for j, (mask, _) in enumerate(self.parts):
            self.part[mask] = j
        m = magnet.parameters["magnet"]
        mat = mk.get_material(g.core_material)
        rho = m.get("resistivity") or mat.resistivity_ohm_m
        self.sigma = 1.0 / float(rho) if sigma is None else float(sigma)
        # conductors: cores and pole back, in groups of zero net current
        back = iron & (cy < -g.hcore)
        core = iron & ~back
        xs, ys = np.unique(self.mesh.p[0]), np.unique(self.mesh.p[1])
        col, row = np.searchsorted(xs, cx), np.searchsorted(ys, cy)
        xc = g.centres()
        pole = np.argmin(np.abs(cx[:, None] - xc[None, :]), axis=1)
        gid = np.full(cx.shape, -1)
        if self.sigma == 0.0:
            groups = "none"
        if groups == "none":
            keys = np.full(cx.shape, -1)
            keys[np.nonzero(core | back)[0][:1]] = 0     # one dummy group (sigma = 0)
        elif groups == "slices":
            keys = np.where(core, pole * 100000 + row, -1)
            keys = np.where(back, 10**7 + col, keys)
        elif groups == "one":
            keys = np.where(core | back, 0, -1)
        else:
            raise ValueError(f"groups = {groups!r}; allowed: 'slices', 'one'")
        cond = keys >= 0
        _, gid[cond] = np.unique(keys[cond], return_inverse=True)
        self.groups, self.ngroups = groups, int(gid.max()) + 1
        self.core_e, self.back_e = core, back
        # per group: b_g[i] = int_g phi_i (lumped), |g|; S = sum_g diag(b_g) - b_g b_g^T/|g|
        t = fe.t
        w = fe.area / 3.0
        ei = np.nonzero(cond)[0]
        rows = t[:, ei].ravel()
        grp = np.tile(gid[ei], 3)
        bg = sp.csr_matrix((np.tile(w[ei], 3), (grp, rows)), shape=(self.ngroups, fe.n))
        bg.sum_duplicates()
        vol = np.asarray(bg.sum(axis=1)).ravel()
        self.bg, self.vol = bg, vol
        diag = np.asarray(bg.sum(axis=0)).ravel()
        # groups of more than BIG nodes (``"one"``) border the Newton system with their u_g
        # instead of a dense block
        big = np.diff(bg.indptr) > BIG
        self.big = np.nonzero(big)[0]
        small = sp.diags((~big).astype(float)) @ bg
        self.S = (sp.diags(diag) - small.T @ sp.diags(1.0 / vol) @ small).tocsr()
        # eddy power split: which groups are in the back
        gb = np.zeros(self.ngroups, bool)
        gb[np.unique(gid[back & cond])] = groups == "slices"
        self.group_back = gb
        # circuits of the half model: poles in x > 0, grouped by the file's assignment
        assign = magnet.parameters["circuits"]["assignment"]
        rp = float(m["resistance_per_pole"])
        half = [k for k in range(g.poles) if xc[k] > 0]
        circ_ids = sorted({assign[k] for k in half})
        self.circuits = []
        nside = g.turns / (g.tc * g.hc)
        for c in circ_ids:
            poles = [k for k in half if assign[k] == c]
            mask = (sign != 0) & np.isin(pole, poles)
            sv = np.where(mask, sign, 0.0) * fe.area / 3.0
            bs = np.bincount(t.ravel(), np.repeat(sv[None], 3, 0).ravel(), fe.n)
            self.circuits.append({"id": c, "poles": [k + 1 for k in poles],
                                  "R": rp * len(poles), "src": MU0 * nside * bs,
                                  "kpsi": g.depth * nside * bs})
        p = self.mesh.p
        bnd = self.mesh.boundary_nodes()
        fixed = bnd[p[0, bnd] > 1e-9]                   # A = 0 except on x = 0
        self.free = np.setdiff1d(np.arange(fe.n), fixed)
        self.band = (cy > 0.0) & (cy < s)

    # -- fields
    def _coeffs(self, A: np.ndarray):  # type: ignore[no-untyped-def]
        ax, ay = self.fe.grad(A)
        b = np.hypot(ax, ay)
        nu = np.ones_like(b)
        c = np.zeros_like(b)
        for j, (tn, tc, _) in enumerate(self._tab):
            q = self.part == j
            nu[q] = np.interp(b[q], self._bb, tn)
            c[q] = np.interp(b[q], self._bb, tc)
        return ax, ay, b, nu, c

    def energy(self, A: np.ndarray) -> float:
        """Stored magnetic energy of the half model [J]."""
        ax, ay = self.fe.grad(A)
        b = np.hypot(ax, ay)
        w = b * b / (2 * MU0)
        for j, (_, _, tw) in enumerate(self._tab):
            q = self.part == j
            w[q] = np.interp(b[q], self._bb, tw)
        return float(self.g.depth * np.sum(w * self.fe.area))

    def force(self, A: np.ndarray) -> float:
        """Total force of the magnet (both halves) [N]: Maxwell stress over the gap band."""
        ax, ay = self.fe.grad(A)
        tyy = (ax**2 - ay**2) / (2 * MU0)
        return float(2.0 * self.g.depth / self.s * np.sum((tyy * self.fe.area)[self.band]))

    def eddy_power(self, adot: np.ndarray) -> tuple[float, float]:
        """Eddy power [W] of the half model in the cores and in the pole back."""
        bx = self.bg @ adot
        pg = self.sigma * self.g.depth * ((self.bg @ (adot * adot)) - bx * bx / self.vol)
        return float(pg[~self.group_back].sum()), float(pg[self.group_back].sum())

    def static(self, currents: list[float], tol: float = 1e-10) -> np.ndarray:
        """Magnetostatic A at the circuits' currents [A]."""
        src = sum(c["src"] * i for c, i in zip(self.circuits, currents, strict=True))
        return static_newton(self.fe, self.free, self._coeffs, src, self.part >= 0, tol,
                             f"s={self.s}")

    def step_response(self, i0: float, i1: float, times: np.ndarray, tol: float = 1e-9,
                      verbose: int = 0) -> dict:
        """Voltage step of every circuit, ``U_c: R_c i0 -> R_c i1`` at t = 0 from the static
        state at i0."""
        t_wall, cpu = time.perf_counter(), time.process_time()
        fe, free = self.fe, self.free
        nf, nc = free.size, len(self.circuits)
        U = np.array([c["R"] * i1 for c in self.circuits])
        R = np.array([c["R"] for c in self.circuits])
        A = self.static([i0] * nc)
        Sf = (MU0 * self.sigma) * self.S[free][:, free]
        nb = self.big.size                                   # bordered groups: u_g unknown
        Gb = (MU0 * self.sigma) * self.bg[self.big][:, free].toarray().T if nb else np.zeros(
            (nf, 0))                                         # (nf, nb)
        vb = (MU0 * self.sigma) * self.vol[self.big]
        src = np.stack([c["src"][free] for c in self.circuits], axis=1)   # (nf, nc)
        kps = np.stack([c["kpsi"][free] for c in self.circuits], axis=0)  # (nc, nf)
        kpsi_all = np.stack([c["kpsi"] for c in self.circuits], axis=0)
        scaleA = np.linalg.norm(src.sum(axis=1)) * max(abs(i0), abs(i1))
        hist_A = [A.copy()]
        cache: dict = {}
        I = np.full(nc, i0)
        out = {"time_s": [0.0], "current_A": [I.tolist()], "psi_Wb": [(kpsi_all @ A).tolist()],
               "force_N": [self.force(A)], "eddy_power_core_W": [0.0],
               "eddy_power_back_W": [0.0], "energy_J": [self.energy(A)]}
        nmax, self.factorisations = 0, 0
        for n in range(1, times.size):
            a0, hist = bdf2_history(times, n, hist_A)
            histf = hist[free]
            Shist = Sf @ histf
            x = np.concatenate([A[free], np.zeros(nb), I])

            def res_jac(x, need_jac=True):
                Af = np.zeros(fe.n)
                Af[free] = x[:nf]
                ub, I_ = x[nf:nf + nb], x[nf + nb:]
                ax, ay, _, nu, c = self._coeffs(Af)
                rA = (fe.residual(nu, ax, ay)[free] + a0 * (Sf @ x[:nf]) + Shist
                      - src @ I_ - Gb @ ub)
                ru = Gb.T @ (a0 * x[:nf] + histf) - vb * ub
                rI = R * I_ + kps @ (a0 * x[:nf] + histf) - U
                r = np.concatenate([rA, ru, rI])
                if not need_jac:
                    return r, None
                K = fe.stiffness(nu, c, ax, ay)[free][:, free] + a0 * Sf
                return r, K

            Bc = np.hstack([-Gb, -src])                 # d rA / d (u, I)
            Br = a0 * np.vstack([Gb.T, kps])            # d (ru, rI) / d A
            Dd = np.diag(np.concatenate([-vb, R]))

            def norm(r):
                return max(np.linalg.norm(r[:nf]) / scaleA,
                           float(np.max(np.abs(r[nf + nb:]) / np.abs(U))))

            x, rel, it = bordered_newton(x, res_jac, (Bc, Br, Dd), norm, nf=nf, a0=a0,
                                         cache=cache, tol=tol, owner=self)
            if rel > 1e3 * tol:
                raise RuntimeError(f"Newton failed at t={times[n]:.3e}: residual {rel:.2e}")
            nmax = max(nmax, it)
            A = np.zeros(fe.n)
            A[free] = x[:nf]
            I = x[nf + nb:].copy()
            adot = a0 * A + hist
            adot[np.setdiff1d(np.arange(fe.n), free)] = 0.0
            pc, pb = self.eddy_power(adot)
            hist_A.append(A.copy())
            if len(hist_A) > 2:
                hist_A.pop(0)
            out["time_s"].append(float(times[n]))
            out["current_A"].append(I.tolist())
            out["psi_Wb"].append((kpsi_all @ A).tolist())
            out["force_N"].append(self.force(A))
            out["eddy_power_core_W"].append(pc)
            out["eddy_power_back_W"].append(pb)
            out["energy_J"].append(self.energy(A))
            if verbose and n % 20 == 0:
                print(f"  t={times[n] * 1e3:9.3f} ms I={I} its={it}", flush=True)
        Iv = np.asarray(out["current_A"])
        dt = np.diff(times)
        p = np.asarray(out["eddy_power_core_W"]) + np.asarray(out["eddy_power_back_W"])
        W = np.asarray(out["energy_J"])
        ein = float(np.sum(dt * (Iv[1:] @ U)))
        eohm = float(np.sum(dt * ((Iv[1:] ** 2) @ R)))
        eed = float(np.sum(dt * p[1:]))
        out.update(nodes=int(fe.n), steps=int(times.size - 1), newton_max=nmax,
                   factorisations=self.factorisations,
                   energy_residual=abs(ein - eohm - eed - (W[-1] - W[0])) / abs(ein),
                   wall_s=time.perf_counter() - t_wall, cpu_s=time.process_time() - cpu,
                   circuits=[{"id": c["id"], "poles": c["poles"], "R_ohm": c["R"]}
                             for c in self.circuits],
                   groups=self.groups, n_groups=self.ngroups, sigma_S_per_m=self.sigma)
        return out


# ---------------------------------------------------------------------------------------
# FEM runs
# ---------------------------------------------------------------------------------------


def _compact(x):  # type: ignore[no-untyped-def]
    """The record's numbers to 9 significant digits (far below the FEM's own error)."""
    if isinstance(x, float):
        return float(f"{x:.9g}")
    if isinstance(x, list):
        return [_compact(v) for v in x]
    if isinstance(x, dict):
        return {k: _compact(v) for k, v in x.items()}
    return x


def _load() -> dict:
    return json.loads(PATH.read_text()) if PATH.exists() else {}


def run_fem(magnet_name: str, runs: list[tuple], *, groups: str = "slices",
            offset: float = OFFSET, sigma0: bool = False, verbose: int = 0) -> None:
    """Solve ``runs`` (label, s, i0, i1, refine, dt0, block, dt_max) not yet recorded
    (``sigma0``: without eddy currents, the static network's share of the transient)."""
    mag = cut_magnet(magnet_name)
    for label, s, i0, i1, refine, dt0, block, dt_max in runs:
        key = (f"{magnet_name} | {label} | {'sigma 0' if sigma0 else groups} | "
               f"o{offset * 1e3:g}")
        data = _load()
        if key in data:
            continue
        fem = Tr09Transient(mag, s, offset, refine=refine, groups=groups,
                            sigma=0.0 if sigma0 else None)
        print(f"{key}: {fem.fe.n} nodes, {fem.ngroups} groups", flush=True)
        r = fem.step_response(i0, i1, time_grid(T_END, dt0, block, dt_max), verbose=verbose)
        r.update(magnet=magnet_name, label=label, eddy=not sigma0, gap_m=s, i0_A=i0, i1_A=i1, refine=refine,
                 dt0_s=dt0, block=block, dt_max_s=dt_max, offset_m=offset)
        data = _load()
        data[key] = _compact(r)
        RESULTS.mkdir(exist_ok=True)
        PATH.write_text(json.dumps(data, separators=(",", ":")) + "\n")
        print(f"{key}: {r['steps']} steps, {r['cpu_s']:.0f} s CPU, energy residual "
              f"{r['energy_residual']:.1e}, t63 "
              f"{rise_time(np.asarray(r['time_s']), np.asarray(r['current_A'])[:, -1], i0, i1):.4f} s",
              flush=True)


# ---------------------------------------------------------------------------------------
# maglevkit's FluxModel on the same steps
# ---------------------------------------------------------------------------------------


def slab_factor(thickness: float, depth: float) -> float:
    """Eddy conductance of a bar ``thickness`` x ``depth`` (Saint-Venant) over that of the
    2-D slab of the same thickness (infinitely deep): the across-track share of the eddy
    loops' resistance, the 3-D term a 2-D cut leaves out."""
    from maglevkit.circuit.elements import rectangle_torsion_constant

    return rectangle_torsion_constant(thickness, depth) / (depth * thickness**3 / 3.0)


def slab_variant(magnet: mk.Magnet) -> mk.Magnet:
    """The magnet's network with its lumped core and pole-back eddy elements as 2-D slabs
    (across x: the pole length for a core, the back height for the back) instead of the
    builder's bars with the Saint-Venant factor of the finite width: a benchmark variant
    (not a maglevkit option) that isolates the 3-D factor."""
    from dataclasses import replace

    from maglevkit.circuit.elements import EddyCurrent

    m = magnet.parameters["magnet"]
    lp, wp, hb, wb = m["pole_length"], m["pole_width"], m["back_height"], m["back_width"]
    f_core, f_back = 1.0 / slab_factor(lp, wp), 1.0 / slab_factor(hb, wb)

    def el(e, f):  # type: ignore[no-untyped-def]
        return replace(e, conductance_S=f * e.conductance_S) if isinstance(e, EddyCurrent) else e

    net = magnet.network
    branches = tuple(replace(b, elements=tuple(el(e, f_back if "back" in e.name else f_core)
                                               for e in b.elements)) for b in net.branches)
    return replace(magnet, network=mk.Network(branches, net.circuits, name=net.name))


def network_magnet(name: str, variant: str) -> mk.Magnet:
    """The network compared with the FEM: ``variant`` one of :data:`VARIANTS`."""
    spec = VARIANTS[variant]
    base = mk.load_magnet(name, **spec["options"])
    mag = base
    if spec["cut"]:
        params = dict(base.parameters)
        params["magnet"] = {**params["magnet"], "end_effects": False}
        params["provenance"] = {**params["provenance"],
                                "magnet.end_effects": "[E] modelling choice: 2-D cut"}
        mag = mk.build_magnet(params, options=base.options, source=base.source)
    return slab_variant(mag) if spec.get("slab") else mag


#: networks held against the FEM (``options``: of ``load_magnet``): the bundled file as
#: shipped (``end_effects = true``, split, lumped eddy elements with the Saint-Venant factor
#: of the finite width); its longitudinal cut (``end_effects = false``: the 2-D partner of
#: the FEM's statics); the cut with 2-D slab lumped elements (benchmark variant); the
#: ladder (``eddy_model = "ladder"``: 2-D slabs on the cut, Saint-Venant on the bundled).
#: The lumped rows name their eddy model: the files name the ladder since switch26m.
_LUMPED = {"eddy_model": "lumped"}
VARIANTS: dict[str, dict] = {
    "bundled": {"cut": False, "options": _LUMPED},
    "bundled, ladder n = 6": {"cut": False, "options": {"eddy_model": "ladder",
                                                        "eddy_layers": 6}},
    "cut": {"cut": True, "options": _LUMPED},
    "cut, slab": {"cut": True, "slab": True, "options": _LUMPED},
    "cut, ladder n = 4": {"cut": True, "options": {"eddy_model": "ladder", "eddy_layers": 4}},
    "cut, ladder n = 6": {"cut": True, "options": {"eddy_model": "ladder", "eddy_layers": 6}},
    "cut, ladder n = 8": {"cut": True, "options": {"eddy_model": "ladder", "eddy_layers": 8}},
    "cut, no eddy currents": {"cut": True, "options": {"eddy_currents": False}},
}


def simulate_network(ref: dict, variant: str, *, rtol: float = 1e-7) -> dict:
    """The flux model's response to the recorded FEM step ``ref``: time [s], currents of
    the circuits the FEM holds [A] (standard: rear; bow: c2, c3), total force [N]."""
    mag = network_magnet(ref["magnet"], variant)
    times = np.asarray(ref["time_s"])
    R = np.asarray(mag.network.resistances)
    fm = mk.FluxModel(mag, rtol=rtol, compiled="never")
    res = mk.simulate(fm, times, gaps_m=ref["gap_m"], voltages_V=R * ref["i1_A"],
                      initial_currents_A=[ref["i0_A"]] * R.size)
    ids = [c["id"] - 1 for c in ref["circuits"]]
    return {"time_s": res.time_s, "current_A": res.currents_A[:, ids],
            "force_N": np.asarray(res.force_N).reshape(res.time_s.size, -1).sum(axis=1)}


def errors(ref: dict, run: dict) -> dict:
    """Current error in % of the step (at 1 ms, and the largest for t >= 1 ms, over the
    circuits), t63 model / FEM per circuit, force error at 1 ms / largest in % of the
    force step."""
    tf = np.asarray(ref["time_s"])
    i_f = np.asarray(ref["current_A"])
    f_f = np.asarray(ref["force_N"])
    i0, i1 = ref["i0_A"], ref["i1_A"]
    late = tf >= 1e-3 - 1e-12
    out: dict = {"err_1ms": [], "err_max": [], "t63_s": [], "t63_fem_s": []}
    for c in range(i_f.shape[1]):
        im = np.interp(tf, run["time_s"], run["current_A"][:, c])
        out["err_1ms"].append(float(np.interp(1e-3, tf, im - i_f[:, c]) / (i1 - i0)))
        out["err_max"].append(float(np.max(np.abs(im - i_f[:, c])[late]) / (i1 - i0)))
        out["t63_s"].append(rise_time(tf, im, i0, i1))
        out["t63_fem_s"].append(rise_time(tf, i_f[:, c], i0, i1))
    fm = np.interp(tf, run["time_s"], run["force_N"])
    dF = f_f[-1] - f_f[0]
    out["force_err_max"] = float(np.max(np.abs(fm - f_f)[late]) / dF)
    out["force_end_err"] = float(fm[-1] / f_f[-1] - 1)
    out["force_start_err"] = float(fm[0] / f_f[0] - 1)
    return out


def compare(magnet_name: str, variants: list[str], key_filter: str = "") -> list[dict]:
    rows = []
    for key, ref in _load().items():
        if (ref["magnet"] != magnet_name or key_filter not in key
                or ref["label"] not in {c[0] for c in CASES}):     # not the study's runs
            continue
        for v in variants:
            if VARIANTS[v]["options"].get("eddy_currents", True) != ref.get("eddy", True):
                continue
            t0 = time.process_time()
            e = errors(ref, simulate_network(ref, v))
            e.update(key=key, variant=v, cpu_s=time.process_time() - t0)
            rows.append(e)
            print(f"{key} [{v}]: err 1 ms {_pc(e['err_1ms'])}, max {_pc(e['err_max'])}, "
                  f"t63 {_ms(e['t63_s'])} / {_ms(e['t63_fem_s'])} ms "
                  f"({_pc([a / b - 1 for a, b in zip(e['t63_s'], e['t63_fem_s'], strict=True)])}), "
                  f"force max {100 * e['force_err_max']:.1f} % of step, start/end "
                  f"{100 * e['force_start_err']:+.1f}/{100 * e['force_end_err']:+.1f} %",
                  flush=True)
    return rows


def convergence(magnet_name: str = "tr09-standard") -> list[dict]:
    """The study runs against the production run of case 0: current difference in % of
    the step (largest for t >= 1 ms) and t63."""
    data = _load()
    lab = CASES[0][0]
    base = data[f"{magnet_name} | {lab} | slices | o{OFFSET * 1e3:g}"]
    tb, ib = np.asarray(base["time_s"]), np.asarray(base["current_A"])[:, -1]
    i0, i1 = base["i0_A"], base["i1_A"]
    rows = []
    for key, r in data.items():
        if r["magnet"] != magnet_name or not r["label"].startswith(lab):
            continue
        t, i = np.asarray(r["time_s"]), np.asarray(r["current_A"])[:, -1]
        late = tb >= 1e-3 - 1e-12
        rows.append({"key": key, "nodes": r["nodes"], "steps": r["steps"],
                     "groups": r.get("n_groups"), "cpu_s": r["cpu_s"],
                     "energy_residual": r["energy_residual"],
                     "i_10ms": float(np.interp(1e-2, t, i)),
                     "i_100ms": float(np.interp(0.1, t, i)),
                     "t63_s": rise_time(t, i, i0, i1),
                     "diff_max": float(np.max(np.abs(np.interp(tb, t, i) - ib)[late])
                                       / (i1 - i0)),
                     "force_0_N": r["force_N"][0], "force_end_N": r["force_N"][-1]})
    return rows


def report(magnet_name: str, variants: list[str]) -> str:
    """Markdown tables: the FEM's convergence and the networks against the FEM."""
    L = ["| FEM run | nodes | groups | steps | I(10 ms) [A] | I(100 ms) [A] | t63 [ms] | "
         "max diff vs production run, t >= 1 ms [% of step] | F(0) / F(end) [kN] | "
         "energy residual | CPU [s] |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in convergence(magnet_name):
        L.append(f"| {r['key'].split(' | ', 1)[1].replace(' | ', ', ')} | {r['nodes']} | "
                 f"{r['groups']} | "
                 f"{r['steps']} | {r['i_10ms']:.3f} | {r['i_100ms']:.3f} | "
                 f"{r['t63_s'] * 1e3:.1f} | {100 * r['diff_max']:.2f} | "
                 f"{r['force_0_N'] / 1e3:.2f} / {r['force_end_N'] / 1e3:.2f} | "
                 f"{r['energy_residual']:.1e} | {r['cpu_s']:.0f} |")
    L += ["", "| FEM case | network | err at 1 ms [% of step] | max err t >= 1 ms [% of step] "
          "| t63 model / FEM [ms] | t63 err [%] | force: max err [% of step] | "
          "force at t = 0 / end [%] |", "|---|---|---|---|---|---|---|---|"]
    mean = position_mean(magnet_name)
    if mean is not None:
        L_mean = []
        for v in variants:
            if not VARIANTS[v]["options"].get("eddy_currents", True):
                continue
            e = errors(mean, simulate_network(mean, v))
            et = [a / b - 1 for a, b in zip(e["t63_s"], e["t63_fem_s"], strict=True)]
            L_mean.append(f"| {mean['label']}, position mean | {v} | {_pc(e['err_1ms'])} | "
                          f"{' / '.join(f'{100 * x:.1f}' for x in e['err_max'])} | "
                          f"{_ms(e['t63_s'])} / {_ms(e['t63_fem_s'])} | {_pc(et)} | "
                          f"{100 * e['force_err_max']:.1f} | "
                          f"{100 * e['force_start_err']:+.1f} / {100 * e['force_end_err']:+.1f} |")
    for r in compare(magnet_name, variants, " | slices | o21.5") + compare(
            magnet_name, [v for v in variants if "no eddy" in v], " | sigma 0 | o21.5"):
        et = [a / b - 1 for a, b in zip(r["t63_s"], r["t63_fem_s"], strict=True)]
        case = r["key"].split(" | ")[1] + (", sigma = 0" if "sigma 0" in r["key"] else "")
        L.append(f"| {case} | {r['variant']} | {_pc(r['err_1ms'])} | "
                 f"{' / '.join(f'{100 * x:.1f}' for x in r['err_max'])} | "
                 f"{_ms(r['t63_s'])} / {_ms(r['t63_fem_s'])} | {_pc(et)} | "
                 f"{100 * r['force_err_max']:.1f} | {100 * r['force_start_err']:+.1f} / "
                 f"{100 * r['force_end_err']:+.1f} |")
    if mean is not None:
        L += L_mean
    return "\n".join(L)


def position_mean(magnet_name: str = "tr09-standard") -> dict | None:
    """Case 0 averaged over the stator positions of fem_tr09 (0, 1/4, 1/2 slot pitch with
    weights 1, 2, 1: four positions evenly over one slot pitch), if all are recorded (the
    runs share one time grid)."""
    data = _load()
    lab = CASES[0][0]
    runs = [data.get(f"{magnet_name} | {lab} | slices | o{o:g}") for o in (0, 21.5, 43)]
    if any(r is None for r in runs):
        return None
    w = (0.25, 0.5, 0.25)
    out = dict(runs[1])                                       # type: ignore[arg-type]
    for k in ("current_A", "force_N"):
        out[k] = sum(wi * np.asarray(r[k]) for wi, r in zip(w, runs, strict=True))  # type: ignore[index]
    return out


def figure(path: Path, variants: tuple[str, ...] = ("cut", "cut, ladder n = 6")) -> None:
    """Current (normalised to the step) and its error against the FEM, per standard case."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = _load()
    refs = [data[f"tr09-standard | {c[0]} | slices | o{OFFSET * 1e3:g}"] for c in CASES]
    fig, ax = plt.subplots(2, len(refs), figsize=(4.2 * len(refs), 6.5), squeeze=False)
    styles = {"cut": ("tab:red", "--"), "cut, ladder n = 6": ("tab:blue", "-")}
    for j, ref in enumerate(refs):
        tf = np.asarray(ref["time_s"])
        i_f = np.asarray(ref["current_A"])[:, 0]
        i0, i1 = ref["i0_A"], ref["i1_A"]
        ax[0, j].semilogx(tf[1:] * 1e3, (i_f[1:] - i0) / (i1 - i0), "k-", lw=2.5, alpha=0.5,
                          label="FEM")
        for v in variants:
            run = simulate_network(ref, v)
            col, ls = styles.get(v, ("tab:green", ":"))
            im = np.interp(tf, run["time_s"], run["current_A"][:, 0])
            ax[0, j].semilogx(tf[1:] * 1e3, (im[1:] - i0) / (i1 - i0), color=col, ls=ls,
                              label=f"network: {v}")
            ax[1, j].semilogx(tf[1:] * 1e3, 100 * (im - i_f)[1:] / (i1 - i0), color=col,
                              ls=ls)
        ax[0, j].set_title(f"TR09 standard, {ref['label']}")
        ax[0, j].set_ylabel("(I - I0)/(I1 - I0)")
        ax[1, j].set_ylabel("(I - I_FEM)/(I1 - I0) [%]")
        ax[1, j].axhspan(-5, 5, color="0.9", zorder=0)
        ax[1, j].set_ylim(-20, 20)
        ax[1, j].set_xlabel("t [ms]")
        for k in range(2):
            ax[k, j].grid(True, which="both", alpha=0.3)
    ax[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    print(f"wrote {path}")


def _pc(v: list[float]) -> str:
    return " / ".join(f"{100 * x:+.1f} %" for x in v)


def _ms(v: list[float]) -> str:
    return " / ".join(f"{1e3 * x:.1f}" for x in v)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--magnet", default="tr09-standard")
    ap.add_argument("--fem", action="store_true", help="run the FEM cases")
    ap.add_argument("--study", action="store_true", help="mesh and time-step convergence")
    ap.add_argument("--only", default=None, help="comma-separated case numbers")
    ap.add_argument("--groups", default="slices", choices=("slices", "one"))
    ap.add_argument("--offset", type=float, default=OFFSET * 1e3, help="stator offset [mm]")
    ap.add_argument("--refine", type=float, default=REFINE)
    ap.add_argument("--sigma0", action="store_true", help="the steps without eddy currents")
    ap.add_argument("-v", "--verbose", type=int, default=0)
    ap.add_argument("--compare", nargs="*", default=None, metavar="VARIANT",
                    help="the network variants (default all) against the recorded FEM")
    ap.add_argument("--filter", default="", help="with --compare: record keys containing this")
    ap.add_argument("--figure", action="store_true",
                    help="docs/figures/fem-tr09-transient.png from the record")
    ap.add_argument("--report", nargs="*", default=None, metavar="VARIANT",
                    help="markdown tables: FEM convergence and the variants (default all)")
    args = ap.parse_args(argv)
    only = None if args.only is None else [int(k) for k in args.only.split(",")]
    if args.fem:
        runs = [(lab, s, i0, i1, args.refine, DT0, BLOCK, DT_MAX)
                for k, (lab, s, i0, i1) in enumerate(CASES) if only is None or k in only]
        if args.refine != REFINE:
            runs = [(f"{r[0]}, mesh x {args.refine:g}", *r[1:]) for r in runs]
        run_fem(args.magnet, runs, groups=args.groups, offset=args.offset * 1e-3,
                sigma0=args.sigma0, verbose=args.verbose)
    if args.study:
        lab, s, i0, i1 = CASES[0]
        run_fem(args.magnet, [(f"{lab}, {sl}", s, i0, i1, rf, d0, bl, dm)
                              for sl, rf, d0, bl, dm in STUDY],
                groups=args.groups, offset=args.offset * 1e-3, verbose=args.verbose)
    if args.compare is not None:
        compare(args.magnet, args.compare or list(VARIANTS), args.filter)
    if args.figure:
        figure(Path(__file__).resolve().parents[1] / "docs" / "figures" /
               "fem-tr09-transient.png")
    if args.report is not None:
        print(report(args.magnet, args.report or list(VARIANTS)))


if __name__ == "__main__":
    main()
