"""TR09 standard levitation magnet against its recorded 2-D FEM (issue 26).

The FEM (benchmarks/fem_tr09.py: longitudinal cut of ``tr09-standard``, 12 poles, coils,
LIG grooves, pole back, slotted stator, averaged over the stator position) is recorded in
benchmarks/results/fem_tr09_grid.json; the network with ``end_effects = false`` (the same
2-D cut) and ``flux_paths = "split"`` is compared with it here without rerunning the FEM;
the former network (``"paper"``, still the default) is held to its measured errors too.
One FEM point is re-solved as a regression of the script itself.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import pytest

from .conftest import HAVE_SKFEM, SKIP_FEM_VAR

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "fem_tr09.py"
needs_fem = pytest.mark.skipif(not HAVE_SKFEM, reason="scikit-fem not installed and "
                               f"{SKIP_FEM_VAR}=1: FEM validation skipped on request")


def _fem():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("fem_tr09", _PATH)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("fem_tr09", mod)
    spec.loader.exec_module(mod)
    return mod


# Measured network errors (network - FEM)/FEM [%]: force, flux linkage, differential
# inductance (both circuits' currents together).  Signed windows: each must stay within
# MARGIN percentage points of its measured value, either way.  The network is
# deterministic (Newton to ~1e-12) and the recorded FEM does not change, so 0.3 pp only
# covers round-off of the table; any change of the TR09 network that moves an error more
# must re-measure it (and say why in docs/validation_fem.md).
MARGIN = 0.3
MEASURED = {
    # (s [mm], I [A]): (err F, err psi, err L)
    (6.0, 10.0): (-1.8, -0.7, -0.6),
    (6.0, 33.5): (-1.1, -0.4, -1.2),
    (6.0, 50.0): (-4.6, -2.0, -13.6),
    (6.0, 80.0): (-8.7, -4.2, -15.5),
    (6.0, 100.0): (-9.4, -4.9, -16.9),
    (10.0, 10.0): (-1.3, -0.2, -0.2),
    (10.0, 33.5): (-1.0, -0.1, +0.2),
    (10.0, 50.0): (-1.3, -0.2, -1.8),
    (10.0, 80.0): (-6.8, -2.7, -17.3),
    (10.0, 100.0): (-9.6, -4.1, -19.0),
    (20.0, 10.0): (+1.5, -0.3, -0.2),
    (20.0, 33.5): (+1.6, -0.2, -0.1),
    (20.0, 50.0): (+1.7, -0.2, +0.1),
    (20.0, 80.0): (+1.3, -0.3, -1.9),
    (20.0, 100.0): (+0.1, -1.0, -8.1),
}


@pytest.mark.slow
def test_network_against_recorded_fem() -> None:
    fem = _fem()
    mag = fem.cut_magnet("tr09-standard", "split")
    rows = {(r["s_mm"], r["I_A"]): r for r in fem.compare(mag, fem._load("grid"))}
    assert set(MEASURED) <= set(rows)
    for key, (ef, epsi, el) in MEASURED.items():
        r = rows[key]
        for name, got, want in (("F", r["eF"], ef), ("psi", r["epsi"], epsi),
                                ("L", r["eL"], el)):
            assert want - MARGIN <= got <= want + MARGIN, (key, name, got)
    # the aims below the knee (force and flux linkage within 3 %, L within 5 %): every
    # point up to 33.5 A, at 10 mm up to 50 A and at 20 mm up to 80 A
    for (s, i), r in rows.items():
        if i <= 33.5 or (s >= 10.0 and i <= 50.0) or (s >= 20.0 and i <= 80.0):
            assert abs(r["eF"]) < 3.0 and abs(r["epsi"]) < 3.0 and abs(r["eL"]) < 5.0, (s, i)


# The former network ("paper"): force, psi, L errors at three points (the early
# saturation, docs/validation_fem.md "before").
PAPER = {(10.0, 33.5): (-9.3, -11.3, -10.8), (10.0, 80.0): (-19.4, -15.1, -29.4),
         (6.0, 80.0): (-22.1, -17.2, -21.4)}


@pytest.mark.slow
def test_paper_network_against_recorded_fem() -> None:
    fem = _fem()
    rows = {(r["s_mm"], r["I_A"]): r
            for r in fem.compare(fem.cut_magnet("tr09-standard", "paper"), fem._load("grid"))}
    for key, (ef, epsi, el) in PAPER.items():
        r = rows[key]
        for name, got, want in (("F", r["eF"], ef), ("psi", r["epsi"], epsi),
                                ("L", r["eL"], el)):
            assert want - MARGIN <= got <= want + MARGIN, (key, name, got)


@pytest.mark.slow
@needs_fem
def test_fem_script_reproduces_a_recorded_point() -> None:
    """Re-solve 20 mm / 10 A, tooth centred on the poles (about 20 s): the recorded grid
    value to 1e-6 (same mesh and Newton tolerance 1e-9; round-off of the sparse solves)."""
    fem = _fem()
    g = fem.Geometry.from_magnet(fem.cut_magnet())
    rec = fem._load("grid")[fem._key(0.020, 10.0, 0.0, fem.GRID_REFINE)]
    pt, _ = fem.solve(g, 0.020, 10.0, 0.0, refine=fem.GRID_REFINE)
    assert math.isclose(pt.force_N, rec["force_N"], rel_tol=1e-6)
    assert math.isclose(pt.psi_Wb[1], rec["psi_Wb"][1], rel_tol=1e-6)
    assert math.isclose(pt.L_H[1], rec["L_H"][1], rel_tol=1e-6)
    # both force estimates of the FEM: the band stress equals the sum of the pole-pitch
    # stresses (the same integral split up) to round-off
    assert math.isclose(sum(pt.pole_force_N), pt.force_N, rel_tol=1e-9)
