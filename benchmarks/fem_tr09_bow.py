"""2-D finite-element check of the TR09 bow levitation magnet (issue 26): per-circuit statics.

maglevkit parameterises ``tr09-bow`` pole by pole exactly as ``tr09-standard`` (the same
``[magnet]`` and ``[stator]`` values; the file has no other end geometry): only the feeding
differs, three circuits of four poles (c1: poles 1-4, c2: 5-8, c3: 9-12) instead of two of
six.  With equal currents the field, the force and the pole forces are therefore the
standard magnet's (benchmarks/fem_tr09.py, whose machinery this reuses unchanged: geometry,
mesh, regions, Newton, band stress); what the bow adds is the split of the flux linkage
between an end circuit (holding an end pole) and the middle circuit (spanning the magnet's
centre), and the differential inductance of each.  This script records, per point,
the flux linkage of every pole's coil (``N d/A int A`` over its two coil sides, signed
with the pole's polarity) and its derivative in the current, all currents together
(``dA/dI = K_t^-1 dJ/dI`` from the Newton tangent at the solution, as fem_tr09.solve).

The half model (x >= 0, poles 7-12; mirror-antisymmetric magnet) holds for equal currents:
pole 13 - k links what pole k links, so c3 = poles 9-12, c2 = 2 x (poles 7 + 8), c1 = c3.

``python benchmarks/fem_tr09_bow.py --grid`` records the gap x current x stator-position
grid of fem_tr09 (the same points, mesh and averaging) into
``benchmarks/results/fem_tr09_bow.json``; ``--convergence`` 10 mm / 80 A, tooth centred,
on fem_tr09's finer mesh (refine 1; the grid's is 0.7, cells 1/0.7 times as large);
``--compare`` prints the network (``end_effects = false``; ``--flux-paths``) against the
recorded results without any FEM solve.
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

import maglevkit as mk  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem_common import MU0, Reluctivity, solve_nonlinear  # noqa: E402
from fem_tr09 import (  # noqa: E402
    CURRENTS_A,
    GAPS_MM,
    GRID_REFINE,
    OFFSETS,
    WEIGHTS,
    Geometry,
    build_mesh,
    cut_magnet,
    regions,
    solve,
)

RESULTS = Path(__file__).resolve().parent / "results"
PATH = RESULTS / "fem_tr09_bow.json"
#: the bow file's circuits, poles 1-12 (checked against the file in :func:`circuits`)
ASSIGNMENT = (1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3)


def key(s: float, current: float, offset: float, refine: float = GRID_REFINE) -> str:
    """Record key of one point (s [m], I [A], offset [m], mesh refinement)."""
    return f"s{s * 1e3:g}_I{current:g}_o{offset * 1e3:g}_r{refine:g}"


def pole_linkages(g: Geometry, s: float, current: float, offset: float, *,
                  refine: float = GRID_REFINE) -> dict:
    """One FEM point: fem_tr09.solve plus every meshed pole's flux linkage and its
    derivative in the current (all currents together)."""
    import scipy.sparse.linalg as spla
    from skfem import Basis, ElementTriP2, LinearForm, asm

    t0 = time.time()
    pt, A = solve(g, s, current, offset, refine=refine)
    mesh = build_mesh(g, s, offset, refine, True)
    iron, teeth, yoke, sign, _ = regions(mesh, g, s, offset)
    basis = Basis(mesh, ElementTriP2())
    nqp = basis.X.shape[1]
    parts = [(iron, Reluctivity(material=g.core_material)),
             (teeth, Reluctivity(material=g.stator_material)),
             (yoke, Reluctivity(material=g.stator_material,
                                depth_ratio=g.depth / g.stator_width))]
    cx = mesh.p[0, mesh.t].mean(axis=0)

    @LinearForm
    def load(v, w):  # type: ignore[no-untyped-def]
        return w.sg * v

    xc = g.centres()
    poles = [k for k in range(g.poles) if xc[k] > 0]
    loads = {k + 1: asm(load, basis, sg=np.repeat(
        (sign * (np.abs(cx - xc[k]) < 0.5 * g.tau))[:, None], nqp, axis=1)) for k in poles}
    total = sum(loads.values())
    jr = MU0 * g.turns / (g.tc * g.hc)
    D = basis.get_dofs(mesh.facets_satisfying(lambda p: p[0] > 1e-9, boundaries_only=True))
    free = np.setdiff1d(np.arange(basis.N), D.all())
    # the Newton tangent at the recorded solution (converged: no iteration)
    sol = solve_nonlinear(basis, parts, jr * current * total, free, tol=1e-9, A0=A,
                          tangent=True)
    dA = np.zeros(basis.N)
    lu = spla.splu(sol.tangent.tocsc(), permc_spec="MMD_AT_PLUS_A",
                   options={"SymmetricMode": True})
    dA[free] = lu.solve(jr * total[free])
    scale = g.depth * g.turns / (g.tc * g.hc)
    psi = {str(k): scale * float(ld @ A) for k, ld in loads.items()}
    dpsi = {str(k): scale * float(ld @ dA) for k, ld in loads.items()}
    return {"s": s, "current": current, "offset": offset, "refine": refine,
            "dofs": pt.dofs, "iterations": pt.iterations, "force_N": pt.force_N,
            "pole_force_N": pt.pole_force_N, "psi_rear_Wb": pt.psi_Wb[1],
            "L_rear_H": pt.L_H[1], "psi_pole_Wb": psi, "L_pole_H": dpsi,
            "seconds": time.time() - t0}


def circuits(p: dict) -> dict:
    """Per-circuit flux linkage and L (all currents together) of one recorded point."""
    psi, L = p["psi_pole_Wb"], p["L_pole_H"]
    c3 = sum(psi[str(k)] for k in (9, 10, 11, 12))
    c2 = 2.0 * (psi["7"] + psi["8"])
    l3 = sum(L[str(k)] for k in (9, 10, 11, 12))
    l2 = 2.0 * (L["7"] + L["8"])
    return {"psi_Wb": [c3, c2, c3], "L_H": [l3, l2, l3]}


def run(g: Geometry, points: list[tuple[float, float, float]], refine: float = GRID_REFINE
        ) -> dict:
    """Solve the points not yet in ``fem_tr09_bow.json``, saving after each."""
    data = json.loads(PATH.read_text()) if PATH.exists() else {}
    for s, current, off in points:
        k = key(s, current, off, refine)
        if k in data:
            continue
        p = pole_linkages(g, s, current, off, refine=refine)
        data[k] = p
        RESULTS.mkdir(exist_ok=True)
        PATH.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
        c = circuits(p)
        print(f"{k}: F {p['force_N']:.1f} N psi {c['psi_Wb'][1]:.4f}/{c['psi_Wb'][2]:.4f} "
              f"L {c['L_H'][1]:.4f}/{c['L_H'][2]:.4f} ({p['dofs']} dofs, "
              f"{p['seconds']:.0f} s)", flush=True)
    return data


def load() -> dict:
    """The recorded points."""
    return json.loads(PATH.read_text())


def averaged(data: dict, s: float, current: float) -> dict | None:
    """Position average (fem_tr09's offsets and weights) of force and the per-circuit
    psi and L at (s, I); None if a position is missing."""
    pts = [data.get(key(s, current, o)) for o in OFFSETS]
    if any(p is None for p in pts):
        return None
    cs = [circuits(p) for p in pts]
    return {"force_N": float(np.dot(WEIGHTS, [p["force_N"] for p in pts])),
            "psi_Wb": list(np.dot(WEIGHTS, [c["psi_Wb"] for c in cs])),
            "L_H": list(np.dot(WEIGHTS, [c["L_H"] for c in cs])),
            "psi_rear_Wb": float(np.dot(WEIGHTS, [p["psi_rear_Wb"] for p in pts]))}


def network(magnet: mk.Magnet, s: float, current: float) -> dict:
    """The bow network's statics at one point, all three currents equal."""
    n = len(magnet.parameters["circuits"]["names"])
    sol = mk.solve_statics(magnet, gaps_m=s, currents_A=[current] * n)
    L = np.asarray(sol.differential_inductance_H).reshape(n, n).sum(axis=1)
    return {"force_N": float(np.ravel(sol.force_N)[0]),
            "psi_Wb": [float(v) for v in np.ravel(sol.flux_linkage_Wb)],
            "L_H": [float(v) for v in L]}


def compare(magnet: mk.Magnet, data: dict, gaps_mm=GAPS_MM, currents=CURRENTS_A  # type: ignore[no-untyped-def]
            ) -> list[dict]:
    """Network vs FEM per point, errors in % ((net - FEM)/FEM): force, and psi and L of
    the end circuit c3 and the middle circuit c2."""
    rows = []
    for smm in gaps_mm:
        for i in currents:
            fem = averaged(data, smm * 1e-3, i)
            if fem is None:
                continue
            net = network(magnet, smm * 1e-3, i)
            row = {"s_mm": smm, "I_A": i, "F_fem": fem["force_N"],
                   "eF": 100 * (net["force_N"] / fem["force_N"] - 1)}
            for c, tag in ((2, "end"), (1, "mid")):
                row[f"psi_{tag}"] = fem["psi_Wb"][c]
                row[f"L_{tag}"] = fem["L_H"][c]
                row[f"epsi_{tag}"] = 100 * (net["psi_Wb"][c] / fem["psi_Wb"][c] - 1)
                row[f"eL_{tag}"] = 100 * (net["L_H"][c] / fem["L_H"][c] - 1)
            rows.append(row)
    return rows


def table(rows: list[dict]) -> str:
    """Markdown table of :func:`compare` rows."""
    lines = ["| s [mm] | I [A] | F_FEM [kN] | err F [%] | psi_FEM end / mid [Wb] "
             "| err psi end / mid [%] | L_FEM end / mid [H] | err L end / mid [%] |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['s_mm']:g} | {r['I_A']:g} | {r['F_fem'] / 1e3:.2f} | {r['eF']:+.1f} "
            f"| {r['psi_end']:.3f} / {r['psi_mid']:.3f} "
            f"| {r['epsi_end']:+.1f} / {r['epsi_mid']:+.1f} "
            f"| {r['L_end']:.4f} / {r['L_mid']:.4f} | {r['eL_end']:+.1f} / {r['eL_mid']:+.1f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--grid", action="store_true", help="the gap x current x offset grid")
    ap.add_argument("--gaps-mm", nargs="+", type=float, default=(10.0, 20.0, 6.0),
                    help="gaps of the grid, in this order")
    ap.add_argument("--currents", nargs="+", type=float, default=CURRENTS_A,
                    help="currents of the grid [A]")
    ap.add_argument("--convergence", action="store_true",
                    help="10 mm / 80 A, tooth centred, on the finer mesh (refine 1)")
    ap.add_argument("--compare", action="store_true", help="network vs the recorded grid")
    ap.add_argument("--flux-paths", default="split", help="network to compare: split, paper")
    args = ap.parse_args(argv)
    mag = cut_magnet("tr09-bow", args.flux_paths)
    assert tuple(mag.parameters["circuits"]["assignment"]) == ASSIGNMENT
    g = Geometry.from_magnet(mag)
    if args.grid:
        run(g, [(s * 1e-3, i, o) for s in args.gaps_mm for o in OFFSETS
                for i in args.currents])
    if args.convergence:
        run(g, [(0.010, 80.0, 0.0)], refine=1.0)
    if args.compare:
        print(table(compare(mag, load())))


if __name__ == "__main__":
    main()
