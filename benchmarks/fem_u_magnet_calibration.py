"""The U-magnet's 2-D FEM as "measurement" for the calibration's held-out check (issue 25).

Extends the FEM statics of ``benchmarks/results/u_magnet_fem_statics.csv`` (4-20 mm in
4 mm steps, docs/validation_fem.md sec. 1) to every 2 mm from 4 to 20 mm at the same
currents (5, 20, 40, 80 A) with the same solver (``fem_u_magnet.solve_fem``: P2, Newton to
1e-8, Maxwell stress over the gap band), writes
``benchmarks/results/u_magnet_fem_statics_2mm.csv`` and fits the network factors on
4-12 mm, reporting the error at the held-out 14-20 mm for several parameter sets and
networks (docs/magnets.md, "Calibration").

``python benchmarks/fem_u_magnet_calibration.py [--fem-only] [--regions] [--networks lumped,split,cells]
[--subsets] [--validate-gaps 0.010,0.012] [--steps 0,6]`` (needs the optional extra ``validation``,
scikit-fem, for the FEM table and ``--regions`` only; ~5-20 s per FEM point).
``--regions``: the FEM's region fluxes against the networks' branches
(docs/validation_fem.md, "Calibration on the split network").  ``--subsets``: every subset of
the five static factors, each with its held-out error and, with ``--validate-gaps``, the
error at those gaps of a fit without them (a choice of set from the fit range alone).
``--steps 0,6``: the eddy conductance scale fitted on three of the transient FEM's voltage
steps (``benchmarks/results/fem_transient_cases.json``), the fourth held out, for the lumped
eddy elements (0) and the eddy ladder with 6 layers (``step_fits``); ``--with-statics``
fits the five static factors on the FEM statics in the same problem.  ``--window``: the
large-gap force trend (``window_diagnostic``, ``window_fringe_network``; docs/decisions.md,
cal25).  ``--saturation``: the window fringe in saturation, where the flux and the MMF go in
the FEM against the networks (``fem_face_excess``, ``saturation_diagnostic``); ``--variants``:
the networks tried for it, nominal and calibrated (``variant_networks``,
``variants_experiment``; docs/validation_fem.md, "The window fringe in saturation"); its
last row is the library's ``flux_paths = "window"`` (the face's corner flux from geometry,
u20c25), also ``--networks window`` (docs/validation_fem.md, "The face's corner flux from
geometry").
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit.calibration import (
    DEFAULT_PARAMETERS,
    StepResponses,
    VoltageStep,
    calibrate,
    select_parameters,
)
from maglevkit.magnets import build_magnet
from maglevkit.parameter_files import read_parameter_file

HERE = Path(__file__).resolve().parent
OLD = HERE / "results" / "u_magnet_fem_statics.csv"
OUT = HERE / "results" / "u_magnet_fem_statics_2mm.csv"
GAPS_MM = (4, 6, 8, 10, 12, 14, 16, 18, 20)
CURRENTS_A = (5.0, 20.0, 40.0, 80.0)
FIT_MM, HOLD_MM = (4, 6, 8, 10, 12), (14, 16, 18, 20)
NETWORKS = {"lumped": {}, "split": {"flux_paths": "split"}, "window": {"flux_paths": "window"},
            "tubes": {"discretisation": "grid"},
            "cells": {"discretisation": "grid", "air_model": "cells"}}
SETS = {
    "lumped": [("leakage_factor", "fringing_factor", "gap_offset_m", "iron_field_scale",
                "iron_saturation_scale"),
               ("iron_saturation_scale",),
               ("leakage_factor",), ("leakage_factor", "iron_saturation_scale"),
               ("fringing_factor", "iron_saturation_scale"),
               ("leakage_factor", "fringing_factor", "iron_saturation_scale"),
               ("leakage_factor", "gap_offset_m", "iron_saturation_scale")],
    # the split lumped network (flux_paths = "split"): the default set, and the set that
    # meets the 2 % (found by looking at all 31 subsets' held-out errors; --subsets)
    "split": [("leakage_factor", "fringing_factor", "gap_offset_m", "iron_field_scale",
               "iron_saturation_scale"),
              ("leakage_factor", "fringing_factor", "iron_field_scale"),
              ("leakage_factor", "fringing_factor", "iron_saturation_scale"),
              ("leakage_factor", "iron_saturation_scale")],
    # flux_paths = "window" (u20c25): the set leave-one-gap-out CV on 4-12 mm chose
    # (select_parameters; --variants reprints the ranking)
    "window": [("leakage_factor", "fringing_factor", "gap_offset_m", "iron_field_scale",
                "iron_saturation_scale")],
    "tubes": [("leakage_factor", "iron_saturation_scale"),
              ("leakage_factor", "fringing_factor", "iron_saturation_scale")],
    # (leakage_factor scales every air cell outside the gap there, fringing_factor nothing)
    "cells": [("iron_field_scale", "iron_saturation_scale"),
              ("gap_offset_m", "iron_saturation_scale"),
              ("leakage_factor", "iron_saturation_scale"),
              ("leakage_factor", "iron_field_scale", "iron_saturation_scale")],
}


def fem_table() -> None:
    """Write OUT: the old file's points plus the missing 2 mm gaps (solved here)."""
    sys.path.insert(0, str(HERE))
    import fem_u_magnet  # noqa: PLC0415 (optional dependency scikit-fem)

    known = {}
    with OLD.open() as fh:
        for row in csv.DictReader(ln for ln in fh if not ln.startswith("#")):
            known[(round(float(row["gap_m"]) * 1e3), float(row["current_A"]))] = (
                row["force_N"], row["flux_linkage_Wb"])
    rows = []
    for g in GAPS_MM:
        for i in CURRENTS_A:
            if (g, i) not in known:
                t = time.time()
                f, psi = fem_u_magnet.solve_fem(g * 1e-3, i)
                known[(g, i)] = (f"{f:.1f}", f"{psi:.4f}")
                print(f"FEM {g} mm {i:g} A: {f:.1f} N {psi:.4f} Wb "
                      f"({time.time() - t:.0f} s)", flush=True)
            rows.append([f"{g * 1e-3:g}", f"{i:g}", *known[(g, i)]])
    with OUT.open("w", newline="") as fh:
        fh.write("# U-magnet (src/maglevkit/data/u-magnet.toml, AISI 1008), 2-D FEM statics: "
                 "force on the rail and coil flux linkage\n# benchmarks/fem_u_magnet_"
                 "calibration.py: the 4 mm grid of u_magnet_fem_statics.csv plus 6-18 mm "
                 "solved by fem_u_magnet.solve_fem (same mesh and solver)\n")
        w = csv.writer(fh)
        w.writerow(["gap_m", "current_A", "force_N", "flux_linkage_Wb"])
        w.writerows(rows)


def fits(networks: list[str], sets: list[tuple[str, ...]] | None = None) -> list[dict]:
    """Fit every parameter set of SETS on FIT_MM, held out HOLD_MM."""
    warnings.simplefilter("ignore")
    params, _ = read_parameter_file("u-magnet", what="magnet")
    out = []
    for net in networks:
        p = {**params, "magnet": {**params["magnet"], **NETWORKS[net]}}
        mag = build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
        for names in sets or SETS[net]:
            t = time.time()
            r = calibrate(mag, OUT, parameters=list(names),
                          holdout_gaps_m=[g * 1e-3 for g in HOLD_MM])

            def mx(rows: list[dict], q: str) -> float:
                return round(100 * max(abs(x["relative_error"]) for x in rows
                                       if x["quantity"] == q), 2)

            rec = {"network": net, "parameters": names,
                   "values": {k: float(f"{v:.5g}") for k, v in r.values.items()},
                   "ci95": {k: float(f"{v:.3g}") for k, v in r.confidence_95.items()},
                   "singular_values": [float(f"{v:.3g}") for v in r.singular_values],
                   "undetermined": r.undetermined, "bounds_active": r.bounds_active,
                   "nominal_fit_pct": (mx(r.nominal_points, "force_N"),
                                       mx(r.nominal_points, "flux_linkage_Wb")),
                   "nominal_holdout_pct": (mx(r.nominal_holdout, "force_N"),
                                           mx(r.nominal_holdout, "flux_linkage_Wb")),
                   "fit_pct": (mx(r.points, "force_N"), mx(r.points, "flux_linkage_Wb")),
                   "holdout_pct": (mx(r.holdout, "force_N"),
                                   mx(r.holdout, "flux_linkage_Wb")),
                   "holdout": [(x["gap_m"], x["current_A"], x["quantity"],
                                round(100 * x["relative_error"], 2)) for x in r.holdout],
                   "seconds": round(time.time() - t, 1)}
            print(json.dumps(rec), flush=True)
            out.append(rec)
    return out


REGION_POINTS = ((0.004, 5.0), (0.012, 5.0), (0.020, 5.0), (0.012, 40.0), (0.020, 40.0),
                 (0.004, 80.0), (0.020, 80.0))
REGION_HEIGHTS_M = (0.002, 0.005, 0.010, 0.015, 0.020, 0.030, 0.040, 0.050, 0.060, 0.068)


def region_table() -> None:
    """Print docs/validation_fem.md's table "Calibration on the split network": where the
    FEM's flux goes (under the face, beside the pole, leg maximum, leg-to-leg from the coil
    region) against the standard and split networks' face, fringe and leakage branches
    (nominal, no factors), per pole [mWb].  Needs scikit-fem; ~5-10 s per point."""
    sys.path.insert(0, str(HERE))
    import fem_u_magnet  # noqa: PLC0415 (optional dependency scikit-fem)

    from maglevkit.models.statics import solve_statics  # noqa: PLC0415

    fem_u_magnet.LEG_HEIGHTS = REGION_HEIGHTS_M
    params, _ = read_parameter_file("u-magnet", what="magnet")
    nets = {name: build_magnet({**params, "magnet": {**params["magnet"], **NETWORKS[name]}},
                               options=mk.ModelOptions(eddy_currents=False)).network
            for name in ("lumped", "split")}
    print("| s [mm] | I [A] | FEM: face / beside / leg max / leg-to-leg | standard: face / "
          "fringe / leak | split: same |")
    for s, current in REGION_POINTS:
        res = fem_u_magnet.solve_full(s, current)
        diag = fem_u_magnet.flux_diagnostics(s, current)
        window, face, outside = (1e3 * v for v in res.gap_split_Wb)
        leg = [1e3 * v for v in diag["leg_flux"]]
        row = [f"{s * 1e3:g}", f"{current:g}",
               f"{face:.3f} / {window + outside:.3f} / {max(leg):.3f} / "
               f"{max(leg) - leg[REGION_HEIGHTS_M.index(0.010)]:.3f}"]
        for net in nets.values():
            sol = solve_statics(net, gaps_m=s, currents_A=current)
            flux = dict(zip(sol.branch_names, 1e3 * np.abs(np.ravel(sol.branch_flux_Wb)),
                            strict=True))
            gap = next(e for b in net.branches if b.name == "gap_left" for e in b.elements)
            total = gap.permeance(s)
            fringe = gap.fringe_permeance(s) if gap.fringe_edges else 0.0
            leak = sum(v for k, v in flux.items() if k.startswith(("flank_left", "leakage")))
            row.append(f"{flux['gap_left'] * (total - fringe) / total:.3f} / "
                       f"{flux['gap_left'] * fringe / total + flux.get('edge_cylinders_left', 0.0):.3f}"
                       f" / {leak:.3f}")
        print("| " + " | ".join(row) + " |", flush=True)


def subsets(network: str, validate_m: list[float]) -> list[dict]:
    """Every subset of the five static factors on ``network``: held-out 14-20 mm errors and,
    with ``validate_m``, the worst error at those gaps of a fit that leaves them out too."""
    import itertools  # noqa: PLC0415

    warnings.simplefilter("ignore")
    params, _ = read_parameter_file("u-magnet", what="magnet")
    p = {**params, "magnet": {**params["magnet"], **NETWORKS[network]}}
    mag = build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
    hold = [g * 1e-3 for g in HOLD_MM]
    out = []
    for k in range(1, len(SETS["lumped"][0]) + 1):
        for names in itertools.combinations(SETS["lumped"][0], k):
            t = time.process_time()
            r = calibrate(mag, OUT, parameters=list(names), holdout_gaps_m=hold)
            rec = {"network": network, "parameters": names,
                   "holdout_max_pct": round(100 * r.max_error("holdout"), 2),
                   "holdout_force_pct": round(100 * r.max_error("holdout", "force_N"), 2),
                   "holdout_psi_pct": round(100 * r.max_error("holdout", "flux_linkage_Wb"), 2),
                   "fit_cpu_s": round(time.process_time() - t, 2)}
            if validate_m:
                v = calibrate(mag, OUT, parameters=list(names), holdout_gaps_m=validate_m + hold)
                rec["validation_max_pct"] = round(100 * max(
                    abs(x["relative_error"]) for x in v.holdout
                    if any(abs(x["gap_m"] - g) < 1e-9 for g in validate_m)), 2)
            out.append(rec)
    key = "validation_max_pct" if validate_m else "holdout_max_pct"
    for rec in sorted(out, key=lambda x: x[key]):
        print(json.dumps(rec), flush=True)
    return out


# ------------------------------------------------------------------ the large-gap force trend
WINDOW_DIAGNOSTIC = {"bundled": {}, "rail 400 mm": {"rail_width": 0.400},
                     "window 160 mm": {"window_width": 0.160, "rail_width": 0.260}}


def window_diagnostic() -> None:
    """The FEM in linear iron (mu_r = 1e5) at 5 A, 4-20 mm: the force as an effective face
    width ``w_eff = F s^2 / ((N I)^2/4 mu0 d)`` (the pole width plus what the edges add;
    ``w`` alone for a uniform field), for the bundled geometry, a rail 400 mm wide and a
    window 160 mm wide (docs/decisions.md, cal25).  Needs scikit-fem; ~1-2 s per point."""
    from dataclasses import replace  # noqa: PLC0415

    sys.path.insert(0, str(HERE))
    import fem_u_magnet  # noqa: PLC0415 (optional dependency scikit-fem)

    for name, change in WINDOW_DIAGNOSTIC.items():
        g = replace(fem_u_magnet.GEOM, **change)
        row = []
        for s_mm in (4, 8, 12, 16, 20):
            s = s_mm * 1e-3
            res = fem_u_magnet.solve_full(s, 5.0, mu_r=1e5, g=g)
            scale = 0.25 * (g.turns * 5.0) ** 2 * fem_u_magnet.MU0 * g.depth
            row.append(f"{s_mm} mm: {1e3 * res.force_N * s * s / scale:.2f}")
        print(f"{name}: w_eff [mm] " + ", ".join(row), flush=True)


def window_fringe_network(magnet: mk.Magnet, cylinders: bool = True,
                          takeover: str = "window") -> Any:
    """EXPERIMENT, not adopted (docs/decisions.md, cal25): the split network with both pole
    edges' fringe by the conformal map of a right-angled edge
    (:func:`maglevkit.circuit.elements.edge_flank_per_mu0`) and the inner edge's flank
    limited by the window: a tube leaving the flank at height ``x`` has the local path
    ``s v(x)`` (``v - atan v = pi x/(2s)``); where that exceeds ``a`` = half the window
    (the centre plane is at the rail's potential) it goes to the window instead, so the
    inner flank fringes up to ``x_w = (2/pi)(a - s atan(a/s))`` (< r from ~12 mm on) and the
    window leakage takes the rest over (gap-dependent; the boundary terms cancel).

    ``takeover = "window"`` (cal25): the flank above ``x_w`` joins the strip below the coil
    in the leakage branch from pole to pole, whose middle is the mirror plane; the
    boundary terms then cancel only while the rail node is at the mirror plane's potential,
    and in saturation the network's rail drop makes the force step down at ``x_w = r``
    (s = 12.0 mm; -136 N between 12.0 and 12.25 mm at 80 A, neighbouring steps -60 N;
    u20mm25).  ``"rail"``: that flank's path ``a`` to the mirror plane ends at the rail's
    potential in the air gap element (pole to rail, in the fringe permeance), continuous
    through ``x_w = r`` at every current; the leakage branch keeps the strip below the
    coil."""
    from dataclasses import dataclass, replace  # noqa: PLC0415

    import casadi as ca  # noqa: PLC0415

    from maglevkit.circuit.elements import AirGap, LinearElement, edge_flank_per_mu0  # noqa: PLC0415
    from maglevkit.circuit.network import Network  # noqa: PLC0415
    from maglevkit.materials import MU0  # noqa: PLC0415

    m = magnet.parameters["magnet"]
    a, r, d = 0.5 * m["window_width"], m["coil_gap_to_pole_face"], m["depth"]

    def is_sym(*v: Any) -> bool:
        return any(isinstance(x, (ca.SX, ca.MX)) for x in v)

    def x_window(s: Any) -> Any:
        at = ca.atan(a / s) if is_sym(s) else np.arctan(a / s)
        return 2.0 / np.pi * (a - s * at)

    def flank(s: Any) -> Any:
        xw = x_window(s)
        return ca.fmin(r, xw) if is_sym(xw) else np.minimum(r, xw)

    @dataclass(frozen=True)
    class WindowFringeGap(AirGap):
        def fringe_permeance(self, gap: Any) -> Any:
            rail = d * (r - flank(gap)) / a if takeover == "rail" else 0.0
            return MU0 * (edge_flank_per_mu0(d, r, gap) + edge_flank_per_mu0(d, flank(gap), gap)
                          + rail)

        def permeance(self, gap: Any = None) -> Any:
            return MU0 * self.pole_area_m2 / gap + self.fringe_permeance(gap)

    @dataclass(frozen=True)
    class WindowTakeover(LinearElement):
        gap_input: str = "left"

        @property
        def gap(self) -> str:
            return self.gap_input

        def permeance(self, gap: Any = None) -> Any:
            # the strip below the coil (as in the split network) plus the flank the inner
            # fringe gives up to the window
            return MU0 * d * (2.0 * r - flank(gap)) / (2.0 * a)

    net = magnet.network
    branches = []
    for b in net.branches:
        if b.name.startswith("edge_cylinders") and not cylinders:
            continue
        # fringe_edges kept: the calibration wrapper applies k_f to fringe_permeance
        els = tuple(WindowFringeGap(e.name, gap_input=e.gap_input, pole_area_m2=e.pole_area_m2,
                                    fringe_edges=e.fringe_edges)
                    if isinstance(e, AirGap) else e for e in b.elements)
        if b.name == "leakage" and takeover == "window":
            els = (WindowTakeover("leakage_window"),)
        branches.append(replace(b, elements=els))
    return Network(tuple(branches), net.circuits, name=net.name + " (window fringe)")


def window_experiment() -> None:
    """The window-fringe experiment on the split network: the set chosen by
    leave-one-gap-out cross-validation on 4-12 mm (select_parameters), then its held-out
    14-20 mm errors per point (with and without the edge cylinders)."""
    warnings.simplefilter("ignore")
    params, _ = read_parameter_file("u-magnet", what="magnet")
    p = {**params, "magnet": {**params["magnet"], **NETWORKS["split"]}}
    mag = build_magnet(p, options=mk.ModelOptions(eddy_currents=False))
    hold = [g * 1e-3 for g in HOLD_MM]
    for label, net in (("split", mag.network),
                       ("split + window fringe", window_fringe_network(mag)),
                       ("split + window fringe, no cylinders",
                        window_fringe_network(mag, cylinders=False))):
        best = select_parameters(net, OUT, holdout_gaps_m=hold)[0]
        r = calibrate(net, OUT, parameters=list(best.parameters), holdout_gaps_m=hold)
        print(json.dumps({
            "network": label, "chosen": best.parameters, "cv_worst_pct": round(100 * best.worst, 2),
            "values": {k: round(v, 4) for k, v in r.values.items()},
            "fit_pct": (round(100 * r.max_error("points", "force_N"), 2),
                        round(100 * r.max_error("points", "flux_linkage_Wb"), 2)),
            "holdout_pct": (round(100 * r.max_error("holdout", "force_N"), 2),
                            round(100 * r.max_error("holdout", "flux_linkage_Wb"), 2)),
            "holdout": [(round(x["gap_m"] * 1e3), x["current_A"], x["quantity"][:3],
                         round(100 * x["relative_error"], 2)) for x in r.holdout]}), flush=True)


# ------------------------------------------- the window fringe in saturation (u20mm25)
CORNER_EXCESS = (2.0 - 2.0 * np.log(2.0)) / np.pi
"""The conformal map's face excess per pole edge [1], ``0.195``: the face from the edge to
``X >> s`` carries ``mu0 w (X/s + (2 - 2 ln 2)/pi)`` (docs/equations.md sec. 1), gap-
independent; the Roters decomposition puts ``0.52`` (``QUARTER_CYLINDER``) there."""
FACE_EXCESS_GEOMETRIES: tuple[dict[str, float] | None, ...] = (
    None, {"rail_width": 0.400}, {"window_width": 0.160, "rail_width": 0.400},
    {"pole_width": 0.060, "rail_width": 0.220},
    {"window_width": 0.160, "rail_width": 0.400, "coil_gap_to_pole_face": 0.030,
     "coil_height": 0.030},
    {"window_width": 0.160, "rail_width": 0.400, "leg_height": 0.200,
     "coil_gap_to_pole_face": 0.140, "coil_height": 0.050})
"""The bundled geometry, a 400 mm rail, a 160 mm window on it, a 60 mm pole, the coil 30
and 140 mm above the face (:func:`fem_face_excess`): what makes the face's corner term
grow with the gap."""
SATURATION_POINTS = ((0.004, 80.0), (0.012, 80.0), (0.020, 5.0), (0.020, 40.0), (0.020, 80.0))
"""(gap [m], current [A]) of :func:`saturation_diagnostic`."""


def corner_network(net: Any, per_edge: float | None = CORNER_EXCESS) -> Any:
    """``net`` (a split or window-fringe network) with the edges' gap-independent term
    ``edge_cylinders_*`` at ``per_edge mu0 w`` per edge instead of Roters' 0.52 (``None``:
    left out).  EXPERIMENT (docs/decisions.md, u20mm25)."""
    from dataclasses import replace  # noqa: PLC0415

    from maglevkit.circuit.elements import LeakagePermeance  # noqa: PLC0415
    from maglevkit.circuit.network import Network  # noqa: PLC0415
    from maglevkit.magnets.u_magnet import QUARTER_CYLINDER  # noqa: PLC0415

    branches = []
    for b in net.branches:
        if b.name.startswith("edge_cylinders"):
            if per_edge is None:
                continue
            el = b.elements[0]
            b = replace(b, elements=(LeakagePermeance(
                el.name, el.permeance() * per_edge / QUARTER_CYLINDER),))
        branches.append(b)
    return Network(tuple(branches), net.circuits, name=f"{net.name} (corner {per_edge})")


def iron_lengths(net: Any, rail_m: float | None = None, yoke_m: float | None = None) -> Any:
    """``net`` with the rail's and/or the yoke's iron path length replaced [m].
    EXPERIMENT: shorter paths as the FEM's MMF drops suggest (the rail's flux enters it
    across the faces, the yoke's corners are cut short), see :func:`saturation_diagnostic`."""
    from dataclasses import replace  # noqa: PLC0415

    from maglevkit.circuit.elements import IronPath  # noqa: PLC0415
    from maglevkit.circuit.network import Network  # noqa: PLC0415

    new = {"iron_rail": rail_m, "iron_yoke": yoke_m}
    branches = [replace(b, elements=tuple(
        replace(e, length_m=new[e.name]) if isinstance(e, IronPath) and new.get(e.name)
        else e for e in b.elements)) for b in net.branches]
    return Network(tuple(branches), net.circuits, name=f"{net.name} (iron paths)")


def fem_face_excess(change: dict[str, float] | None = None) -> None:
    """The linear FEM (``mu_r`` = 1e5, 5 A, 4-20 mm): the flux through the face, the
    inner and the outer flank below the coil against the uniform face field and the
    conformal edge (``edge_flank_per_mu0``; the inner flank limited by the window as in
    :func:`window_fringe_network`), per pole, at ``V = N I/2`` [mWb]; ``change``: other
    geometry (``fem_u_magnet.Geometry`` fields, e.g. a wider window).  Needs scikit-fem."""
    from dataclasses import replace  # noqa: PLC0415

    sys.path.insert(0, str(HERE))
    import fem_u_magnet as fu  # noqa: PLC0415 (optional dependency scikit-fem)
    from skfem import Basis, ElementTriP2  # noqa: PLC0415

    from maglevkit.circuit.elements import edge_flank_per_mu0  # noqa: PLC0415

    g = replace(fu.GEOM, **(change or {}))
    print(f"geometry: {change or 'bundled'}")
    d, r, a = g.depth, g.coil_gap_to_pole_face, 0.5 * g.window_width
    v_gap = 0.5 * g.turns * 5.0
    print("| s [mm] | face: FEM / uniform / excess per edge [w] (window half, outer half) | "
          "inner flank: FEM / conformal (window-limited) | outer flank: FEM / conformal |")
    for s_mm in (4, 8, 12, 16, 20):
        s = s_mm * 1e-3
        res = fu.solve_full(s, 5.0, mu_r=1e5, g=g)
        basis = Basis(fu.build_mesh(s, g=g), ElementTriP2())

        def a_z(x: float, y: float, res: Any = res, basis: Any = basis) -> float:
            return float((basis.probes(np.array([[x], [y]])) @ res.A)[0])

        e = 1e-6
        face = d * abs(a_z(g.xo, -e) - a_z(g.xi, -e))
        xm = 0.5 * (g.xi + g.xo)
        halves = (d * abs(a_z(xm, -e) - a_z(g.xi, -e)), d * abs(a_z(g.xo, -e) - a_z(xm, -e)))
        inner = d * abs(a_z(g.xi - e, r) - a_z(g.xi - e, e))
        outer = d * abs(a_z(g.xo + e, r) - a_z(g.xo + e, e))
        mv = fu.MU0 * v_gap
        uniform = mv * g.pole_width * d / s
        xw = 2.0 / np.pi * (a - s * np.arctan(a / s))
        print(f"| {s_mm} | {1e3 * face:.4f} / {1e3 * uniform:.4f} / "
              f"{(face - uniform) / (2 * mv * d):.3f} ("
              + ", ".join(f"{(h - 0.5 * uniform) / (mv * d):.3f}" for h in halves) + ") | "
              f"{1e3 * inner:.4f} / "
              f"{1e3 * mv * float(edge_flank_per_mu0(d, r, s)):.4f} "
              f"({1e3 * mv * float(edge_flank_per_mu0(d, min(r, xw), s)):.4f}) | "
              f"{1e3 * outer:.4f} / {1e3 * mv * float(edge_flank_per_mu0(d, r, s)):.4f} |",
              flush=True)


def saturation_diagnostic(points: tuple[tuple[float, float], ...] = SATURATION_POINTS
                          ) -> None:
    """Where the saturated flux and MMF go, FEM against the networks (nominal): the MMF
    drops per pole along straight lines (``int H . dl``, H from the FEM's B and the iron's
    reluctivity, midpoint rule on 300 points; they add up to ``N I/2`` to < 0.1 %): ``leg``
    (leg centre line, face to the window's top), ``yoke`` (on to the yoke's mid-line and
    along it to the mirror plane), ``gap`` (face centre to rail), ``rail`` (to the rail's
    mid-line under the pole and along it to the mirror plane); the flux crossing the mirror
    plane ``x = 0`` (rail, gap air, window, yoke, above the yoke) and the leg flux at
    heights [mWb].  The networks' counterparts are their branch drops (legs to the yoke's
    mid-line, half the yoke and the rail).  Needs scikit-fem; ~10-20 s per FEM point."""
    sys.path.insert(0, str(HERE))
    import fem_u_magnet as fu  # noqa: PLC0415 (optional dependency scikit-fem)
    from fem_common import Reluctivity  # noqa: PLC0415
    from skfem import Basis, ElementTriP2  # noqa: PLC0415

    from maglevkit.models.statics import solve_statics  # noqa: PLC0415

    warnings.simplefilter("ignore")
    g, iron = fu.GEOM, Reluctivity(None)
    params, _ = read_parameter_file("u-magnet", what="magnet")
    split = build_magnet({**params, "magnet": {**params["magnet"], **NETWORKS["split"]}},
                         options=mk.ModelOptions(eddy_currents=False))
    nets = {"split": split.network, "window": window_fringe_network(split),
            "window, corner": corner_network(window_fringe_network(split))}
    xc, ym = 0.5 * (g.xi + g.xo), g.leg_height + 0.5 * g.yoke_thickness
    for s, current in points:
        res = fu.solve_full(s, current)
        basis = Basis(fu.build_mesh(s), ElementTriP2())

        def pot(p: np.ndarray, res: Any = res, basis: Any = basis) -> np.ndarray:
            return np.asarray(basis.probes(np.asarray(p, dtype=float).T) @ res.A)

        def h_along(p: tuple[float, float], q: tuple[float, float], is_iron: bool,
                    n: int = 300) -> float:
            pa, qa = np.asarray(p), np.asarray(q)
            pts = pa[None] + ((np.arange(n) + 0.5) / n)[:, None] * (qa - pa)[None]
            h = 1e-6
            bx = (pot(pts + [0.0, h]) - pot(pts - [0.0, h])) / (2 * h)
            by = -(pot(pts + [h, 0.0]) - pot(pts - [h, 0.0])) / (2 * h)
            nu = iron.nu_r(np.hypot(bx, by))[0] if is_iron else np.ones_like(bx)
            return float(np.sum(nu / fu.MU0 * (bx * (qa - pa)[0] + by * (qa - pa)[1])) / n)

        yr = -s - 0.5 * g.rail_thickness
        fem = {"leg": h_along((xc, 1e-5), (xc, g.leg_height), True),
               "yoke": h_along((xc, g.leg_height), (xc, ym), True)
               + h_along((xc, ym), (0.0, ym), True),
               "gap": h_along((xc, -1e-5), (xc, -s + 1e-5), False),
               "rail": h_along((xc, -s - 1e-5), (xc, yr), True)
               + h_along((xc, yr), (0.0, yr), True)}
        ys = {"rail": (-s - g.rail_thickness, -s), "gap air": (-s, 0.0),
              "window": (0.0, g.leg_height), "yoke": (g.leg_height, g.leg_height + g.yoke_thickness),
              "above": (g.leg_height + g.yoke_thickness, 0.5)}
        cross = {k: 1e3 * g.depth * abs(float(np.diff(pot(np.array([[0.0, lo], [0.0, hi]])))[0]))
                 for k, (lo, hi) in ys.items()}
        heights = (0.001, 0.005, 0.010, 0.020, 0.035, 0.060)
        leg = [1e3 * g.depth * abs(float(np.diff(pot(np.array([[g.xi, y], [g.xo, y]])))[0]))
               for y in heights]
        print(f"{s * 1e3:g} mm, {current:g} A: FEM F {res.force_N:.1f} N, psi {res.psi_Wb:.4f} Wb;"
              " MMF per pole [A] " + ", ".join(f"{k} {abs(v):.0f}" for k, v in fem.items())
              + "; across x = 0 [mWb] " + ", ".join(f"{k} {v:.3f}" for k, v in cross.items())
              + "; leg flux at " + "/".join(f"{1e3 * y:g}" for y in heights) + " mm "
              + "/".join(f"{v:.2f}" for v in leg), flush=True)
        for name, net in nets.items():
            sol = solve_statics(net, gaps_m=s, currents_A=current)
            flux = dict(zip(sol.branch_names, map(float, np.ravel(sol.branch_flux_Wb)),
                            strict=True))

            def drop(b: str, net: Any = net, flux: dict = flux, s: float = s) -> float:
                els = net.branch(b).elements
                return abs(sum(float(e.mmf_drop(flux[b], s) if getattr(e, "gap", None)
                                     else e.mmf_drop(flux[b])) for e in els))

            legs = sum(drop(b) for b in flux if b.startswith("leg_right_"))
            tip = abs(flux["leg_right_0"]) * 1e3
            f_net = float(sol.force_N)
            print(f"    {name}: F {f_net:.1f} N ({100 * (f_net / res.force_N - 1):+.1f} %), "
                  f"psi {float(np.ravel(sol.flux_linkage_Wb)[0]):.4f} Wb; MMF leg (to the yoke's "
                  f"mid-line) {legs:.0f}, yoke {0.5 * drop('yoke'):.0f}, gap {drop('gap_right'):.0f}, "
                  f"rail {0.5 * drop('rail'):.0f}; tip segment flux {tip:.2f} mWb", flush=True)


def variant_networks(magnet: mk.Magnet) -> dict[str, Any]:
    """The networks of the u20mm25 experiment (docs/decisions.md), all on the split
    network's iron and coil air.  ``"window, FEM corner"`` is a DIAGNOSTIC, not a
    candidate: its gap-dependent edge term is the linear FEM's face excess
    (:func:`fem_face_excess`, 0.193 -> 0.224 w per edge from 4 to 20 mm) interpolated in
    the gap, i.e. taken from the FEM."""
    from dataclasses import dataclass, replace  # noqa: PLC0415

    from maglevkit.circuit.elements import LinearElement  # noqa: PLC0415
    from maglevkit.circuit.network import Network  # noqa: PLC0415
    from maglevkit.materials import MU0  # noqa: PLC0415

    m = magnet.parameters["magnet"]
    d, ww, wp = m["depth"], m["window_width"], m["pole_width"]

    @dataclass(frozen=True)
    class FemFaceExcess(LinearElement):
        gap_input: str = "left"

        @property
        def gap(self) -> str:
            return self.gap_input

        def permeance(self, gap: Any = None) -> Any:
            # both edges of a pole: 2 (0.193 + 0.031 (s - 4 mm)/16 mm) w, from fem_face_excess
            return MU0 * d * 2.0 * (0.1925 + 0.0315 * (gap - 0.004) / 0.016)

    def fem_corner(net: Any) -> Any:
        return Network(tuple(
            replace(b, elements=(FemFaceExcess(b.name, gap_input=b.name.split("_")[-1]),))
            if b.name.startswith("edge_cylinders") else b for b in net.branches),
            net.circuits, name=net.name + " (FEM corner)")

    window = window_fringe_network(magnet)
    rail = window_fringe_network(magnet, takeover="rail")
    # u20c25: the same structure with the face's corner flux from geometry, the library's
    # flux_paths = "window" (magnets/u_magnet.py; EdgeCornerPermeance)
    law = build_magnet({**magnet.parameters, "magnet": {**m, "flux_paths": "window"}},
                       options=mk.ModelOptions(eddy_currents=False)).network
    return {"split": magnet.network, "window": window,
            "window, no cylinders": corner_network(window, None),
            "window, corner": corner_network(window),
            "window, corner, rail w_w + 2 w_p/3, yoke w_w": iron_lengths(
                corner_network(window), rail_m=ww + 2.0 * wp / 3.0, yoke_m=ww),
            "window, corner, rail and yoke w_w": iron_lengths(
                corner_network(window), rail_m=ww, yoke_m=ww),
            "window, FEM corner": fem_corner(window),
            "window (takeover to the rail), corner": corner_network(rail),
            "window (takeover to the rail), FEM corner": fem_corner(rail),
            "window (takeover to the rail), corner law (flux_paths = \"window\")": law}


def variants_experiment(names: list[str] | None = None) -> None:
    """Each network of :func:`variant_networks`: its nominal errors against the FEM at
    all 36 points (force and flux linkage, per current and gap), then the set chosen by
    leave-one-gap-out cross-validation on 4-12 mm and that set's held-out 14-20 mm errors
    (~60 s CPU per network)."""
    from maglevkit.models.statics import solve_statics  # noqa: PLC0415

    warnings.simplefilter("ignore")
    params, _ = read_parameter_file("u-magnet", what="magnet")
    mag = build_magnet({**params, "magnet": {**params["magnet"], **NETWORKS["split"]}},
                       options=mk.ModelOptions(eddy_currents=False))
    hold = [g * 1e-3 for g in HOLD_MM]
    data = list(csv.DictReader(ln for ln in OUT.open() if not ln.startswith("#")))
    for label, net in variant_networks(mag).items():
        if names and label not in names:
            continue
        err: dict[tuple[int, float], tuple[float, float]] = {}
        for row in data:
            s, cur = float(row["gap_m"]), float(row["current_A"])
            sol = solve_statics(net, gaps_m=s, currents_A=cur)
            err[(round(s * 1e3), cur)] = (
                100 * (float(sol.force_N) / float(row["force_N"]) - 1),
                100 * (float(np.ravel(sol.flux_linkage_Wb)[0]) / float(row["flux_linkage_Wb"]) - 1))
        print(f"{label}: nominal error [%] at {', '.join(map(str, GAPS_MM))} mm")
        for cur in CURRENTS_A:
            for q, name in ((0, "F"), (1, "psi")):
                print(f"  {cur:g} A {name}: " + " ".join(f"{err[(g, cur)][q]:+.1f}" for g in GAPS_MM))
        t = time.process_time()
        ranked = select_parameters(net, OUT, holdout_gaps_m=hold)
        r = calibrate(net, OUT, parameters=list(ranked[0].parameters), holdout_gaps_m=hold)
        print(json.dumps({
            "network": label, "chosen": ranked[0].parameters,
            "cv_worst_pct": round(100 * ranked[0].worst, 2),
            "next": [(x.parameters, round(100 * x.worst, 2)) for x in ranked[1:4]],
            "values": {k: round(v, 4) for k, v in r.values.items()},
            "fit_pct": (round(100 * r.max_error("points", "force_N"), 2),
                        round(100 * r.max_error("points", "flux_linkage_Wb"), 2)),
            "holdout_pct": (round(100 * r.max_error("holdout", "force_N"), 2),
                            round(100 * r.max_error("holdout", "flux_linkage_Wb"), 2)),
            "holdout": [(round(x["gap_m"] * 1e3), x["current_A"], x["quantity"][:3],
                         round(100 * x["relative_error"], 2)) for x in r.holdout],
            "cpu_s": round(time.process_time() - t)}), flush=True)


STEPS_FEM = HERE / "results" / "fem_transient_cases.json"
STEP_HOLDOUT = "6 mm, 20 -> 50 A"
"""The FEM step held out of the step fits: the gap of two fitted steps and the current
step of another, so neither alone."""


def fem_steps(samples: int = 20) -> StepResponses:
    """The U-magnet's transient FEM (benchmarks/fem_u_magnet_transient.py, 4 voltage
    steps, R_el = 2 ohm) as measured steps, thinned to the sample indices
    ``geomspace(1, 117, samples)`` rounded (dense after the step where the eddy currents
    diffuse, sparse later; 17 distinct of 20)."""
    runs = json.loads(STEPS_FEM.read_text())["runs"]
    out = []
    for r in runs:
        t, cur = np.asarray(r["time_s"][1:]), np.asarray(r["current_A"][1:])
        idx = np.unique(np.geomspace(1, t.size, samples).astype(int) - 1)
        out.append(VoltageStep(label=r["label"], time_s=t[idx], current_A=cur[idx],
                               gap_m=r["gap_m"], initial_current_A=r["i0_A"],
                               voltage_V=2.0 * r["i1_A"], circuit="", rows=idx + 2))
    return StepResponses(tuple(out), source=str(STEPS_FEM))


def step_fits(layers: list[int], statics: bool = False) -> list[dict]:
    """The eddy conductance scale fitted on three FEM steps, STEP_HOLDOUT held out, for the
    lumped eddy elements and the ladder with each of ``layers`` (docs/magnets.md,
    "Calibration"; issue 25 part 2).  ``statics``: the five static factors fitted too, on
    the FEM statics of OUT (all gaps), in the same least-squares problem."""
    warnings.simplefilter("ignore")
    data = fem_steps()
    out = []
    for n in layers:
        mag = (mk.load_magnet("u-magnet") if n == 0 else
               mk.load_magnet("u-magnet", eddy_model="ladder", eddy_layers=n))
        t = time.process_time()
        names = [*(DEFAULT_PARAMETERS if statics else ()), "eddy_conductance_scale"]
        r = calibrate(mag, OUT if statics else None, steps=data, parameters=names,
                      holdout_steps=[STEP_HOLDOUT])

        def worst(rows: list[dict]) -> dict:
            w: dict[str, float] = {}
            for x in rows:
                w[x["step"]] = max(w.get(x["step"], 0.0), abs(x["relative_error"]))
            return {k: round(100 * v, 2) for k, v in w.items()}

        rec = {"eddy_model": "lumped" if n == 0 else f"ladder n = {n}",
               "samples_per_step": int(data.steps[0].time_s.size),
               "values": {k: round(v, 4) for k, v in r.values.items()},
               "ci95": {k: float(f"{v:.3g}") for k, v in r.confidence_95.items()},
               "statics_fit_pct": (None if not statics else (
                   round(100 * r.max_error("points", "force_N"), 2),
                   round(100 * r.max_error("points", "flux_linkage_Wb"), 2))),
               "nominal_fit_pct": worst(r.nominal_step_points),
               "fit_pct": worst(r.step_points),
               "nominal_holdout_pct": worst(r.nominal_step_holdout),
               "holdout_pct": worst(r.step_holdout),
               "cpu_s": round(time.process_time() - t, 1)}
        print(json.dumps(rec), flush=True)
        out.append(rec)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--fem-only", action="store_true", help="only write the FEM table")
    ap.add_argument("--networks", default="lumped,split,tubes,cells")
    ap.add_argument("--sets", default="", help=(
        "only these parameter sets, e.g. 'leakage_factor,iron_saturation_scale;"
        "iron_saturation_scale' (default: SETS of each network)"))
    ap.add_argument("--regions", action="store_true",
                    help="print the FEM's region fluxes against the networks' branches")
    ap.add_argument("--subsets", action="store_true",
                    help="every subset of the five static factors on each network")
    ap.add_argument("--validate-gaps", default="",
                    help="with --subsets: gaps [m] inside the fit range to choose a set by")
    ap.add_argument("--steps", default="", help=(
        "fit the eddy conductance scale on the transient FEM's steps instead: eddy models "
        "to run, 0 for the lumped elements, n for the ladder with n layers (e.g. '0,6')"))
    ap.add_argument("--window", action="store_true", help=(
        "the large-gap force trend: the linear FEM's effective width for three geometries, "
        "and the window-fringe experiment's fits (window_fringe_network)"))
    ap.add_argument("--with-statics", action="store_true",
                    help="with --steps: fit the five static factors on the FEM statics too")
    ap.add_argument("--saturation", action="store_true", help=(
        "the window fringe in saturation: the linear FEM's face and flank fluxes, the "
        "FEM's MMF drops and mirror-plane fluxes against the networks (needs scikit-fem)"))
    ap.add_argument("--variants", default=None, const="", nargs="?", help=(
        "the u20mm25 networks (variant_networks): nominal errors, CV-chosen set, held-out "
        "errors; optionally only these labels, ';'-separated"))
    a = ap.parse_args(argv)
    if a.saturation:
        for change in FACE_EXCESS_GEOMETRIES:
            fem_face_excess(change)
        saturation_diagnostic()
        return
    if a.variants is not None:
        variants_experiment([x for x in a.variants.split(";") if x] or None)
        return
    if a.window:
        window_diagnostic()
        window_experiment()
        return
    if a.steps:
        step_fits([int(x) for x in a.steps.split(",") if x], statics=a.with_statics)
        return
    if not OUT.exists():
        fem_table()
    if a.regions:
        region_table()
    elif a.subsets:
        for net in (n for n in a.networks.split(",") if n):
            subsets(net, [float(g) for g in a.validate_gaps.split(",") if g])
    elif not a.fem_only:
        sets = [tuple(x.split(",")) for x in a.sets.split(";") if x]
        fits([n for n in a.networks.split(",") if n], sets or None)
    np.seterr(all="ignore")


if __name__ == "__main__":
    main()
