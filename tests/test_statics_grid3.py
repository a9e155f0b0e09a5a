"""The U-magnet cell network (``discretisation = "grid"``) against the 2-D FEM: its own
convergence in ``grid_columns`` and what the FEM's flux linkage is made of (issue 12,
part 2; docs/validation_fem.md, sections "Convergence of the grid network" and "What the
flux linkage is made of").

FEM numbers recorded from ``python benchmarks/fem_u_magnet.py`` (run of 2026-12-02,
refine = 1, FEM discretisation error < 0.1 %, docs/validation_fem.md sec. 4).  Errors
(EMC - FEM)/FEM measured with that run (docs/validation_fem.md, convergence table):

    grid_columns        3       4       5       6
    F  4 mm / 80 A    -1.9    -3.0    -3.3    -3.4     (%)
    psi 20 mm / 80 A  -5.6    -5.2    -5.0    -4.9
    F 20 mm / 5 A     +4.3    +4.3    +4.3    +4.3

So the network converges (the force steps shrink: 1.2, 0.2, 0.1 pp), the 3-column force in deep
saturation is ~1.5 pp better than the converged network's by discretisation luck, and
the low-current force at 20 mm does not depend on the cells at all: it is the air model's
(Roters tubes) error.  The FEM decomposition (slow test) shows the flux inside the coil
sides that the network cannot count: +3.1 % of psi at 4 mm / 80 A, -0.8 % at 20 mm / 5 A.

``air_model = "cells"`` (the air as cells too) is within 3 % of the FEM in force and flux
linkage at all 20 points (-2.0 ... +2.8 %, -2.4 ... -0.1 %) and at the 5 points of a second
geometry (-1.7 ... +2.4 %, -2.3 ... -0.2 %); its FEM checks are slow (the network has 2812
branches), the default run checks its physics on a coarse version (599 branches).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.circuit import GapLayerPermeance
from maglevkit.errors import ParameterError, ParameterFileError
from maglevkit.materials import MU0

from .conftest import build_u
from .test_fem_validation import _fem, needs_fem

# (s [mm], I [A]): (F_FEM [N], psi_FEM [Wb]) -- recorded, see the docstring.  (The older
# recording in tests/test_statics_fem.py differs by <= 0.05 % at 4 mm / 80 A.)
FEM = {
    (4, 80): (7888.42, 4.69554),
    (20, 80): (2409.81, 4.26773),
    (20, 5): (26.9114, 0.461136),
}

# measured errors [%] per grid_columns: F at 4 mm / 80 A, psi at 20 mm / 80 A, F at 20 mm / 5 A
MEASURED = {
    3: (-1.86, -5.62, +4.32),
    4: (-3.04, -5.19, +4.30),
    5: (-3.27, -4.96, +4.31),
}

# The network is deterministic (Newton to ~1e-13) and the FEM values above carry 5-6
# digits, so a measured error reproduces to ~0.01 pp; 0.15 pp catches any change of the
# network that moves it by more (the steps between column counts are 0.1-1.1 pp).
MARGIN = 0.15


def _grid(columns: int) -> mk.Magnet:
    with warnings.catch_warnings():          # the added keys carry no provenance entry
        warnings.simplefilter("ignore", mk.ProvenanceWarning)
        return build_u(magnet={"discretisation": "grid", "grid_columns": columns})


def _errors(mag: mk.Magnet) -> tuple[float, float, float]:
    out = []
    for (s, current), col in (((4, 80), 0), ((20, 80), 1), ((20, 5), 0)):
        sol = mk.solve_statics(mag, gaps_m=s * 1e-3, currents_A=float(current))
        value = (float(np.ravel(sol.force_N)[0]), float(np.ravel(sol.flux_linkage_Wb)[0]))[col]
        out.append(100.0 * (value / FEM[s, current][col] - 1.0))
    return out[0], out[1], out[2]


@pytest.fixture(scope="module")
def errors() -> dict[int, tuple[float, float, float]]:
    return {n: _errors(_grid(n)) for n in (3, 4)}


@pytest.fixture(scope="module")
def errors5(errors: dict) -> dict[int, tuple[float, float, float]]:
    return {**errors, 5: _errors(_grid(5))}


@pytest.mark.parametrize("columns", [3, 4])
def test_grid_errors_against_recorded_fem(errors: dict, columns: int) -> None:
    for got, want in zip(errors[columns], MEASURED[columns], strict=True):
        assert got == pytest.approx(want, abs=MARGIN)


@pytest.mark.slow
def test_grid_converges_in_columns(errors5: dict) -> None:
    """Refining the cells changes the saturated results by less each time (measured steps
    3 -> 4 -> 5: force 1.18, 0.23 pp; psi 0.44, 0.23 pp): a converging discretisation,
    whose limit is ~0.1-0.2 pp beyond the 5-column value (6 columns: -3.4 %, -4.9 %).
    Measured step ratios 0.19 (force) and 0.52 (psi); bounds 0.5 and 0.7."""
    for got, want in zip(errors5[5], MEASURED[5], strict=True):
        assert got == pytest.approx(want, abs=MARGIN)
    f = [errors5[n][0] for n in (3, 4, 5)]
    p = [errors5[n][1] for n in (3, 4, 5)]
    assert abs(f[2] - f[1]) < 0.5 * abs(f[1] - f[0])
    assert abs(p[2] - p[1]) < 0.7 * abs(p[1] - p[0])
    # and both move the same way: the 3-column force is too high in deep saturation
    assert f[0] > f[1] > f[2] and p[0] < p[1] < p[2]


def test_large_gap_force_error_is_the_air_model(errors: dict) -> None:
    """With unsaturated iron at 20 mm the force error (+4.3 %) is the same for every cell
    count (measured spread 0.016 pp; bound 0.05 pp): refining the iron cannot remove
    it, it sits in the air paths (fringing and flank tubes)."""
    spread = np.ptp([errors[n][2] for n in (3, 4)])
    assert spread < 0.05
    assert errors[3][2] > 3.0                # outside the 3 % aim, as recorded


@needs_fem
@pytest.mark.slow
def test_fem_flux_linkage_decomposition() -> None:
    """psi = turn-weighted leg flux + the coil sides' own vertical flux (flux_diagnostics of
    the FEM script): the parts add up to psi (measured closure 1.2e-5: the quadrature of
    200 x 24 probes; bound 1e-4); in deep saturation the coil sides add +3.1 % (measured
    outer +1.5 %, window +1.6 %), which a network with its turns on the iron links misses;
    at 20 mm / 5 A they subtract 0.8 % (the flank leakage crossing the sides links fewer
    turns than the leg below it)."""
    fem = _fem()
    for (s, current), share in (((0.004, 80.0), (2.9, 3.3)), ((0.020, 5.0), (-1.0, -0.6))):
        d = fem.flux_diagnostics(s, current)
        total = d["psi_leg"] + d["psi_outer"] + d["psi_window"]
        assert total == pytest.approx(d["psi"], rel=1e-4)
        bundles = 100.0 * (d["psi_outer"] + d["psi_window"]) / d["psi"]
        assert share[0] < bundles < share[1]


# ------------------------------------------------------------------ air_model = "cells"

# measured errors [%] of the grid network with air_model = "cells" (defaults: 4 gap rows,
# 0.2 m box, 3 columns) against the FEM: (s [mm], I [A]): (err F, err psi).  Over all 20
# points of docs/validation_fem.md: F -2.0 ... +2.8 %, psi -2.4 ... -0.1 % (within 3 %).
CELLS_FEM = {
    (4, 5): (566.545, 1.25312),
    (20, 5): FEM[20, 5],
    (12, 40): (2686.72, 3.64773),
    (4, 80): FEM[4, 80],
    (20, 80): FEM[20, 80],
}
CELLS_MEASURED = {
    (4, 5): (-1.80, -2.03),       # lowest psi of the grid's cells at 4 mm
    (20, 5): (-1.46, -2.45),      # lowest psi overall; the tubes' worst force (+4.3 %)
    (12, 40): (+1.50, -0.64),     # the knee
    (4, 80): (+2.83, -0.10),      # highest force (deep saturation, 2.6 T)
    (20, 80): (+2.72, -0.59),     # the tubes' worst psi (-5.6 %)
}


def _cells(**keys: object) -> mk.Magnet:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mk.ProvenanceWarning)
        return build_u(magnet={"discretisation": "grid", "air_model": "cells", **keys})


@pytest.mark.slow
def test_air_cells_against_recorded_fem() -> None:
    """The air-cell network (2812 branches, ~40 s to build the equations: slow) at five
    points of the FEM grid, including the worst ones (4 mm / 5 A psi, 4 mm / 80 A force)."""
    mag = _cells()
    for point, (f_fem, psi_fem) in CELLS_FEM.items():
        sol = mk.solve_statics(mag, gaps_m=point[0] * 1e-3, currents_A=float(point[1]))
        ef = 100.0 * (float(np.ravel(sol.force_N)[0]) / f_fem - 1.0)
        ep = 100.0 * (float(np.ravel(sol.flux_linkage_Wb)[0]) / psi_fem - 1.0)
        want_f, want_p = CELLS_MEASURED[point]
        assert ef == pytest.approx(want_f, abs=MARGIN)
        assert ep == pytest.approx(want_p, abs=MARGIN)
        assert abs(ef) < 3.0 and abs(ep) < 3.0      # the aim, met at all 20 points


@pytest.fixture(scope="module")
def coarse_cells() -> mk.Magnet:
    # one iron cell across the pole, 2 gap rows, 0.09 m box: 599 branches, ~10 s to build
    return _cells(grid_columns=1, air_gap_rows=2, air_margin=0.09)


def _solve(mag: mk.Magnet, s: float, current: float) -> tuple[float, float]:
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=current)
    return float(np.ravel(sol.force_N)[0]), float(np.ravel(sol.flux_linkage_Wb)[0])


def test_air_cells_force_is_coenergy_derivative(coarse_cells: mk.Magnet) -> None:
    """F = -dW'/ds at constant current with the gap rows' lateral links (GapLayerPermeance,
    whose share of the force is repulsive) in the energy: central difference, h = 1e-6 m,
    truncation ~(h/s)^2 ~ 1e-8 (measured on the tube network < 1e-8; bound 5e-8)."""
    s, current, h = 0.008, 40.0, 1e-6
    wp = mk.coenergy(coarse_cells, gaps_m=s + h, currents_A=current)
    wm = mk.coenergy(coarse_cells, gaps_m=s - h, currents_A=current)
    force, _ = _solve(coarse_cells, s, current)
    assert force == pytest.approx(-(wp - wm) / (2 * h), rel=5e-8)


def test_air_cells_reciprocity_and_pole_flux(coarse_cells: mk.Magnet) -> None:
    """dF/dI = -dpsi/ds (Maxwell relation of W'), steps 1e-7 m and 1e-4 A (truncation and
    rounding < 1e-7 relative; bound 1e-6); and the pole flux of eq. 5 is psi/(n/2) with the
    coil sides' partial turns counted (pole_turns = n/2; exact up to rounding)."""
    s, current = 0.008, 40.0
    sol = mk.solve_statics(coarse_cells, gaps_m=s, currents_A=current)
    _, psi_p = _solve(coarse_cells, s + 1e-7, current)
    _, psi_m = _solve(coarse_cells, s - 1e-7, current)
    f_p, _ = _solve(coarse_cells, s, current + 1e-4)
    f_m, _ = _solve(coarse_cells, s, current - 1e-4)
    assert float(np.sum(sol.dforce_dcurrent_N_per_A)) == pytest.approx(
        -(psi_p - psi_m) / 2e-7, rel=1e-6)
    assert float(np.sum(sol.dpsi_dgap_Wb_per_m)) == pytest.approx(-(f_p - f_m) / 2e-4, rel=1e-6)
    eta = coarse_cells.network.pole_flux_matrix.T @ np.ravel(sol.branch_flux_Wb)
    assert float(eta[0]) == pytest.approx(float(sol.flux_linkage_Wb[0]) / 300.0, rel=1e-12)


@pytest.mark.parametrize(("keys", "options", "match"), [
    ({"air_model": "mesh"}, {}, "expected one of 'tubes', 'cells'"),
    ({"air_model": "cells", "air_gap_rows": 9}, {}, "at most 8"),
    ({"air_model": "cells", "air_gap_rows": 0}, {}, "air_gap_rows"),
    ({"air_model": "cells", "air_margin": -0.1}, {}, "air_margin"),
    ({"air_gap_rows": 2}, {}, "applies to air_model"),
    ({"air_model": "cells", "coil_air": True}, {}, "remove coil_air"),
    ({"air_model": "cells"}, {"leakage": False}, "cannot be switched off"),
    ({"air_model": "cells"}, {"fringing": False}, "cannot be switched off"),
])
def test_air_cells_bad_input(keys: dict, options: dict, match: str) -> None:
    with pytest.raises(ParameterFileError, match=match):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mk.ProvenanceWarning)
            build_u(magnet={"discretisation": "grid", **keys}, **options)


@pytest.mark.parametrize("key", ["air_model", "air_gap_rows", "air_margin"])
def test_air_keys_are_refused_by_the_lumped_network(key: str) -> None:
    value = {"air_model": "cells", "air_gap_rows": 2, "air_margin": 0.1}[key]
    with pytest.raises(ParameterFileError, match=f"{key} does not apply"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mk.ProvenanceWarning)
            build_u(magnet={key: value})


def test_gap_layer_permeance() -> None:
    """G = mu0 w s/l, linear in the gap (so its force share phi^2/2 dR/ds is repulsive);
    bad geometry is refused."""
    el = GapLayerPermeance("g", gap_input="left", width_m=0.1, length_m=0.005)
    for s in (0.004, 0.02):
        assert el.permeance(s) == pytest.approx(MU0 * 0.1 * s / 0.005, rel=1e-15)
    assert el.gap == "left"
    with pytest.raises(ParameterError, match="needs a gap"):
        el.permeance(None)
    for bad in ({"width_m": 0.0}, {"length_m": -1.0}, {"gap_input": ""}):
        with pytest.raises(ParameterError):
            GapLayerPermeance("g", **{"gap_input": "s", "width_m": 0.1, "length_m": 0.01, **bad})


# A second geometry (GEOM2 of benchmarks/fem_u_magnet.py), not used to choose the air
# cells' settings: FEM recorded from the same run, (s [mm], I [A]): (F [N], psi [Wb]), and
# the air cells' measured errors [%].  At all 5 points of docs/validation_fem.md: force
# -1.7 ... +2.4 %, psi -2.3 ... -0.2 % (tubes: -6.1 ... +0.7 %, -5.9 ... +0.5 %).
GEOM2 = dict(pole_width=0.025, leg_height=0.065, yoke_thickness=0.025, window_width=0.070,
             coil_thickness=0.012, coil_height=0.045, coil_gap_to_pole_face=0.008)
GEOM2_RAIL = dict(thickness=0.025, width=0.150)
GEOM2_FEM = {
    (15, 10): (166.637, 0.942866, -1.66, -2.30),    # lowest psi
    (10, 30): (2108.17, 2.87825, +1.23, -0.72),     # the knee (tubes -6.1 %, -3.9 %)
    (6, 60): (4595.96, 3.67605, +2.42, -0.21),      # highest force
}


@pytest.mark.slow
def test_air_cells_on_a_second_geometry() -> None:
    """The settings chosen on the example geometry hold on another one (~40 s: slow)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mk.ProvenanceWarning)
        mag = build_u(magnet={"discretisation": "grid", "air_model": "cells", **GEOM2},
                      rail=GEOM2_RAIL)
    for (s, current), (f_fem, psi_fem, want_f, want_p) in GEOM2_FEM.items():
        force, psi = _solve(mag, s * 1e-3, float(current))
        ef, ep = 100.0 * (force / f_fem - 1.0), 100.0 * (psi / psi_fem - 1.0)
        assert ef == pytest.approx(want_f, abs=MARGIN)
        assert ep == pytest.approx(want_p, abs=MARGIN)
        assert abs(ef) < 3.0 and abs(ep) < 3.0
