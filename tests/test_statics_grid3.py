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
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import maglevkit as mk

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
        sol = mk.solve_statics(mag, gaps=s * 1e-3, currents=float(current))
        value = (float(np.ravel(sol.force_N)[0]), float(np.ravel(sol.flux_linkage_Wb)[0]))[col]
        out.append(100.0 * (value / FEM[s, current][col] - 1.0))
    return out[0], out[1], out[2]


@pytest.fixture(scope="module")
def errors() -> dict[int, tuple[float, float, float]]:
    return {n: _errors(_grid(n)) for n in MEASURED}


@pytest.mark.parametrize("columns", sorted(MEASURED))
def test_grid_errors_against_recorded_fem(errors: dict, columns: int) -> None:
    for got, want in zip(errors[columns], MEASURED[columns], strict=True):
        assert got == pytest.approx(want, abs=MARGIN)


def test_grid_converges_in_columns(errors: dict) -> None:
    """Refining the cells changes the saturated results by less each time (measured steps
    3 -> 4 -> 5: force 1.18, 0.23 pp; psi 0.44, 0.23 pp): a converging discretisation,
    whose limit is ~0.1-0.2 pp beyond the 5-column value (6 columns: -3.4 %, -4.9 %).
    Measured step ratios 0.19 (force) and 0.52 (psi); bounds 0.5 and 0.7."""
    f = [errors[n][0] for n in (3, 4, 5)]
    p = [errors[n][1] for n in (3, 4, 5)]
    assert abs(f[2] - f[1]) < 0.5 * abs(f[1] - f[0])
    assert abs(p[2] - p[1]) < 0.7 * abs(p[1] - p[0])
    # and both move the same way: the 3-column force is too high in deep saturation
    assert f[0] > f[1] > f[2] and p[0] < p[1] < p[2]


def test_large_gap_force_error_is_the_air_model(errors: dict) -> None:
    """With unsaturated iron at 20 mm the force error (+4.3 %) is the same for every cell
    count (measured spread 0.016 pp; bound 0.05 pp): refining the iron cannot remove
    it, it sits in the air paths (fringing and flank tubes)."""
    spread = np.ptp([errors[n][2] for n in MEASURED])
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
