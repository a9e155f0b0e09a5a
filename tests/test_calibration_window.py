"""The U-magnet's lumped ``flux_paths = "window"`` network (issue 25, u20c25): the split
network with the edges' air from the conformal map -- the window-limited flank, its upper
part straight to the window's centre plane, and the face's corner flux growing with the
gap (``EdgeCornerPermeance``) -- and the calibration's held-out check on the 2-D FEM
(fit 4-12 mm, held out 14-20 mm; benchmarks/fem_u_magnet_calibration.py;
docs/validation_fem.md, "The face's corner flux from geometry")."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest

import maglevkit as mk
from maglevkit.calibration import DEFAULT_PARAMETERS, calibrate, select_parameters
from maglevkit.circuit.elements import EdgeCornerPermeance, edge_corner_per_mu0, edge_flank_per_mu0
from maglevkit.errors import ParameterFileError
from maglevkit.magnets import build_magnet
from maglevkit.magnets.u_magnet import WindowFringeGap
from maglevkit.materials import MU0
from maglevkit.parameter_files import read_parameter_file

ROOT = Path(__file__).resolve().parents[1]
FEM_2MM = ROOT / "benchmarks" / "results" / "u_magnet_fem_statics_2mm.csv"
HOLD_M = [0.014, 0.016, 0.018, 0.020]


def _params(**magnet: Any) -> dict:
    params, _ = read_parameter_file("u-magnet", what="magnet")
    return {**params, "magnet": {**params["magnet"], **magnet},
            "provenance": {**params.get("provenance", {}),
                           **{f"magnet.{k}": "[E] test variant" for k in magnet}}}


@pytest.fixture(scope="module")
def window() -> mk.Magnet:
    return build_magnet(_params(flux_paths="window"),
                        options=mk.ModelOptions(eddy_currents=False))


def test_window_paths_are_the_documented_elements(window: mk.Magnet) -> None:
    """The gap: face, the outer flank by the map, the window's flank by the map up to
    ``x_w = (2/pi)(a - s atan(a/s))`` and above it straight across ``a`` (written out here
    from the formulas); the corner branch both edges' ``edge_corner_per_mu0``; the rest is
    the split network's (same branches but for the corner)."""
    d, wp, r, a, hc = 0.100, 0.030, 0.010, 0.030, 0.050
    els = {e.name: e for b in window.network.branches for e in b.elements}
    gap = els["gap_left"]
    assert isinstance(gap, WindowFringeGap)
    for s in (0.004, 0.012, 0.020):
        x_w = 2.0 / math.pi * (a - s * math.atan(a / s))
        inner = (edge_flank_per_mu0(d, r, s) if x_w >= r
                 else edge_flank_per_mu0(d, x_w, s) + d * (r - x_w) / a)
        want = MU0 * (wp * d / s + edge_flank_per_mu0(d, r, s) + inner)
        assert float(gap.permeance(s)) == pytest.approx(float(want), rel=1e-12)
    corner = els["edge_corner_left"]
    assert isinstance(corner, EdgeCornerPermeance)
    for s in (0.004, 0.020):
        want = MU0 * (edge_corner_per_mu0(d, s, r, hc, a) + edge_corner_per_mu0(d, s, r, hc))
        assert float(corner.permeance(s)) == pytest.approx(float(want), rel=1e-12)
    split = build_magnet(_params(flux_paths="split"), options=mk.ModelOptions(eddy_currents=False))
    names = {b.name for b in window.network.branches}
    split_names = {b.name for b in split.network.branches}
    assert names - split_names == {"edge_corner_left", "edge_corner_right"}
    assert split_names - names == {"edge_cylinders_left", "edge_cylinders_right"}


def test_window_flank_is_continuous_where_the_window_takes_over(window: mk.Magnet) -> None:
    """Where ``x_w`` passes ``r`` (s = 12.0 mm for the bundled magnet) the flank's two laws
    meet with equal value (the map's tube and the straight path both end at the rail's
    potential): the permeance's one-sided slopes agree to 1e-3 (a kink of the slope only,
    from ``min``), and the force at 80 A steps no more than its neighbours (u20mm25's
    "window" takeover stepped -136 N against -60 N there)."""
    gap = {e.name: e for b in window.network.branches for e in b.elements}["gap_left"]
    a, r = 0.030, 0.010
    s0 = float(np.interp(r, [2.0 / math.pi * (a - s * math.atan(a / s)) for s in
                             (0.0125, 0.0115)], [0.0125, 0.0115]))
    h = 1e-6
    left = (float(gap.permeance(s0)) - float(gap.permeance(s0 - h))) / h
    right = (float(gap.permeance(s0 + h)) - float(gap.permeance(s0))) / h
    assert right == pytest.approx(left, rel=1e-3)
    force = [float(mk.solve_statics(window, gaps_m=s, currents_A=80.0).force_N)
             for s in (0.0115, 0.01175, 0.012, 0.01225, 0.0125)]
    steps = np.diff(force)
    assert np.all(steps < 0) and steps.min() > 1.3 * steps.max()


def test_window_builds_with_symbolic_geometry() -> None:
    """The design optimisation's builder with CasADi geometry: the window's take-over and
    the corner law stay symbolic and equal the numeric build."""
    from maglevkit.circuit.assembly import assemble
    from maglevkit.magnets.base import take
    from maglevkit.magnets.u_magnet import MAGNET_SCHEMA, RAIL_SCHEMA, lumped_network

    base = mk.load_magnet("u-magnet", eddy_currents=False)
    m = take({**base.parameters["magnet"], "flux_paths": "window"}, MAGNET_SCHEMA, "magnet")
    r = take(base.parameters["rail"], RAIL_SCHEMA, "rail")
    p = ca.SX.sym("p", 2)
    m.update(pole_width=p[0], window_width=p[1])
    core = base.network.branches[0].elements[0].material
    net = lumped_network(m, r, core, core, mk.ModelOptions(eddy_currents=False))
    gaps = {e.name: e for b in net.branches for e in b.elements}
    f = ca.Function("g", [p], [gaps["gap_left"].permeance(0.016),
                               gaps["edge_corner_left"].permeance(0.016)])
    numeric = build_magnet(_params(flux_paths="window", pole_width=0.032, window_width=0.064),
                           options=mk.ModelOptions(eddy_currents=False))
    want = {e.name: e for b in numeric.network.branches for e in b.elements}
    got = f([0.032, 0.064])
    assert float(got[0]) == pytest.approx(float(want["gap_left"].permeance(0.016)), rel=1e-12)
    assert float(got[1]) == pytest.approx(float(want["edge_corner_left"].permeance(0.016)),
                                          rel=1e-12)
    assert assemble(net) is not None


@pytest.mark.parametrize(("magnet", "eddy_model", "match"), [
    ({"flux_paths": "window", "end_effects": True}, "lumped",
     r"flux_paths = \"window\" is a 2-D cross-section's network .* end_effects = true"),
    ({"flux_paths": "window"}, "ladder", r"flux_paths = \"window\" has lumped eddy elements "
                                         r"only \(eddy_model 'ladder'"),
])
def test_bad_window_options_refused(magnet: dict, eddy_model: str, match: str) -> None:
    with pytest.raises(ParameterFileError, match=match):
        build_magnet(_params(**magnet), options=mk.ModelOptions(eddy_model=eddy_model))


@pytest.mark.slow
def test_held_out_within_2_percent_with_the_set_chosen_on_the_fit_range(window: mk.Magnet
                                                                         ) -> None:
    """Issue 25's aim: fit 4-12 mm, every held-out point at 14-20 mm within 2 %, force and
    flux linkage.  The set is chosen without the held-out gaps: leave-one-gap-out CV on
    4-12 mm ranks all five static factors first (1.27 %, measured over all 31 subsets by
    ``fem_u_magnet_calibration.py --variants``; here the first two of that ranking are
    re-scored, 10 fits), then the fit: measured force -1.79 ... +0.10 %, flux linkage
    -0.78 ... +0.64 % held out (fit range 0.75 / 0.56 %); the window's bounds leave
    0.2 pp for solver round-off across platforms.  k_H 0.32: the network's rail and yoke
    take 2-10x the FEM's MMF (docs/validation_fem.md, u20mm25), which the iron scale
    absorbs."""
    five = tuple(DEFAULT_PARAMETERS)
    four = ("leakage_factor", "fringing_factor", "gap_offset_m", "iron_field_scale")
    ranked = select_parameters(window, FEM_2MM, holdout_gaps_m=HOLD_M, sets=[four, five])
    assert tuple(ranked[0].parameters) == five
    assert ranked[0].worst == pytest.approx(0.0127, abs=5e-4)
    assert ranked[1].worst > ranked[0].worst + 0.004
    res = calibrate(window, FEM_2MM, parameters=list(five), holdout_gaps_m=HOLD_M)
    assert res.converged and res.undetermined == () and res.bounds_active == ()
    force = [x["relative_error"] for x in res.holdout if x["quantity"] == "force_N"]
    psi = [x["relative_error"] for x in res.holdout if x["quantity"] == "flux_linkage_Wb"]
    assert len(force) == len(psi) == 16
    assert -0.0199 < min(force) and max(force) < 0.003
    assert -0.0098 < min(psi) and max(psi) < 0.0084
    assert res.max_error("holdout") < 0.02
    assert res.values["iron_field_scale"] == pytest.approx(0.317, abs=0.01)
