"""TR09 standard levitation magnet against its recorded 2-D FEM (issue 26).

The FEM (benchmarks/fem_tr09.py: longitudinal cut of ``tr09-standard``, 12 poles, coils,
LIG grooves, pole back, slotted stator, averaged over the stator position) is recorded in
benchmarks/results/fem_tr09_grid.json; the network with ``end_effects = false`` (the same
2-D cut) and ``flux_paths = "split"`` is compared with it here without rerunning the FEM;
the former network (``"paper"``, still the default) is held to its measured errors too.
One FEM point is re-solved as a regression of the script itself.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from .conftest import HAVE_SKFEM, SKIP_FEM_VAR, load_script

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "fem_tr09.py"
needs_fem = pytest.mark.skipif(not HAVE_SKFEM, reason="scikit-fem not installed and "
                               f"{SKIP_FEM_VAR}=1: FEM validation skipped on request")


def _fem():  # type: ignore[no-untyped-def]
    return load_script(_PATH)


# Measured network errors (network - FEM)/FEM [%]: force, flux linkage, differential
# inductance (both circuits' currents together).  Signed windows: each must stay within
# MARGIN percentage points of its measured value, either way.  The network is
# deterministic (Newton to ~1e-12) and the recorded FEM does not change, so 0.3 pp only
# covers round-off of the table; any change of the TR09 network that moves an error more
# must re-measure it (and say why in docs/validation_fem.md).
MARGIN = 0.3
MEASURED = {
    # (s [mm], I [A]): (err F, err psi, err L); "split" with the stator yoke split at the
    # face edges (window teeth per side), the end poles' back end face and underside to
    # the stator beyond the magnet, their outer flank strips along the whole coil
    # (docs/validation_fem.md, 2026-12-02, continued), the air through the coils'
    # cross-section beside the cores and the slots at the face edges between the face's
    # teeth and the window's ("The coils' cross-section and the slots at the face edges").
    # Every point beyond the first grid (6/10/20 mm x 10/33.5/50/80/100 A) was solved after
    # these paths were chosen (held out).  Since fringe26 the flank's tubes to the stator
    # follow the conformal map of a pole edge over a plane and end at window/pi
    # (docs/validation_fem.md, "The flank's fringe at large gaps"); chosen on the 6/10/20
    # mm region fluxes and the 10 A column, the other points moved as measured (force at
    # 20 mm +3.1 ... +3.4 % -> +1.5 ... +1.9 %).
    (6.0, 10.0): (+0.9, +0.6, +0.6),
    (6.0, 20.0): (+1.1, +0.7, +1.0),
    (6.0, 33.5): (+1.7, +1.0, +0.4),
    (6.0, 50.0): (-0.1, +0.2, -1.8),
    (6.0, 80.0): (+1.3, +0.3, +1.4),
    (6.0, 100.0): (+2.4, +0.3, -0.3),
    (8.0, 10.0): (+0.4, +0.7, +0.7),
    (8.0, 20.0): (+0.5, +0.7, +0.8),
    (8.0, 33.5): (+0.9, +0.9, +1.5),
    (8.0, 50.0): (+0.3, +0.7, -2.6),
    (8.0, 80.0): (-1.1, +0.1, +0.5),
    (8.0, 100.0): (-0.6, +0.1, -0.1),
    (10.0, 10.0): (+0.2, +0.7, +0.7),
    (10.0, 20.0): (+0.3, +0.7, +0.8),
    (10.0, 33.5): (+0.5, +0.8, +1.3),
    (10.0, 50.0): (+0.7, +1.0, +0.5),
    (10.0, 80.0): (-1.5, +0.2, -1.5),
    (10.0, 100.0): (-1.7, +0.1, -0.8),
    (12.0, 10.0): (+0.2, +0.8, +0.8),
    (12.0, 20.0): (+0.2, +0.8, +0.8),
    (12.0, 33.5): (+0.4, +0.8, +1.1),
    (12.0, 50.0): (+0.7, +1.0, +1.2),
    (12.0, 80.0): (-0.8, +0.5, -2.6),
    (12.0, 100.0): (-1.7, +0.2, -2.0),
    (14.0, 10.0): (+0.4, +0.8, +0.8),
    (14.0, 20.0): (+0.4, +0.8, +0.9),
    (14.0, 33.5): (+0.5, +0.9, +1.0),
    (14.0, 50.0): (+0.7, +1.0, +1.3),
    (14.0, 80.0): (+0.2, +0.8, -1.5),
    (14.0, 100.0): (-1.1, +0.4, -2.8),
    (16.0, 10.0): (+0.6, +0.8, +0.8),
    (16.0, 20.0): (+0.7, +0.8, +0.9),
    (16.0, 33.5): (+0.7, +0.9, +1.0),
    (16.0, 50.0): (+0.9, +1.0, +1.4),
    (16.0, 80.0): (+1.0, +1.0, +0.4),
    (16.0, 100.0): (-0.0, +0.7, -2.7),
    (18.0, 10.0): (+1.0, +0.8, +0.8),
    (18.0, 20.0): (+1.0, +0.8, +0.8),
    (18.0, 33.5): (+1.1, +0.8, +0.9),
    (18.0, 50.0): (+1.2, +0.9, +1.3),
    (18.0, 80.0): (+1.4, +1.0, +1.2),
    (18.0, 100.0): (+1.0, +0.9, -1.4),
    (20.0, 10.0): (+1.5, +0.8, +0.8),
    (20.0, 20.0): (+1.5, +0.8, +0.8),
    (20.0, 33.5): (+1.5, +0.8, +0.9),
    (20.0, 50.0): (+1.7, +0.9, +1.1),
    (20.0, 80.0): (+1.9, +1.0, +1.1),
    (20.0, 100.0): (+1.9, +1.0, +0.3),
}


def test_network_against_recorded_fem() -> None:
    """Reads the recorded FEM only (about 1.3 s; no scikit-fem needed), so it is in the fast suite."""
    fem = _fem()
    mag = fem.cut_magnet("tr09-standard", "split")
    rows = {(r["s_mm"], r["I_A"]): r for r in fem.compare(
        mag, fem._load("grid"), fem.GAPS_FULL_MM, fem.CURRENTS_FULL_A)}
    assert set(MEASURED) <= set(rows)
    for key, (ef, epsi, el) in MEASURED.items():
        r = rows[key]
        for name, got, want in (("F", r["eF"], ef), ("psi", r["epsi"], epsi),
                                ("L", r["eL"], el)):
            assert want - MARGIN <= got <= want + MARGIN, (key, name, got)
    # the aims into deep saturation at every point: force and flux linkage within 3 %, L
    # within 5 %.  Until fringe26 the force at 20 mm was +3.1 ... +3.4 % at every current
    # (Roters' flank tubes up to window/2) and held to 3.5 % there; now +1.5 ... +1.9 %.
    # History of the deep-saturation errors (6-10 mm, 80-100 A): first split network force
    # -6.8 ... -9.6 %, L -15.5 ... -19 %; then -3.6 ... -5.3 %, -8.4 ... -12.3 %; then
    # -1.6 ... -3.7 %, -4.3 ... -7.9 %; then -1.1 ... +2.7 %, -3.2 ... -0.5 %; now
    # -1.7 ... +2.4 %, -1.5 ... +1.4 %
    for (s, i), r in rows.items():
        assert abs(r["epsi"]) < 3.0 and abs(r["eL"]) < 5.0, (s, i)
        assert abs(r["eF"]) < 3.0, (s, i)


# The former network ("paper"): force, psi, L errors at three points (the early
# saturation, docs/validation_fem.md "before").
PAPER = {(10.0, 33.5): (-9.3, -11.3, -10.8), (10.0, 80.0): (-19.4, -15.1, -29.4),
         (6.0, 80.0): (-22.1, -17.2, -21.4)}


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


# Potential drops [A] along lines (FEM: benchmarks/fem_tr09.py --diagnose, position average
# of the recorded line integrals; network: its branches' iron drops), rear pole 9.  The
# evidence for the two changes of 2026-12-02: the core-back junction (the network counted
# it in the core and the pole back) and the face teeth (the network's remaining excess).
DIAGNOSIS = {
    # (s [mm], I [A]): {region: (FEM, network)}
    # network values since fringe26 (the flank's conformal tubes up to window/pi): the
    # core's drop 3145 -> 3063 and 2673 -> 2597 A, gap + teeth 15954 -> 16103, 12529 ->
    # 12667 and 6315 -> 6324 A
    (10.0, 100.0): {"junction+core": (3186, 3063), "gap+teeth": (16230, 16103)},
    (6.0, 80.0): {"junction+core": (2941, 2597), "gap+teeth": (12678, 12667)},
    (20.0, 33.5): {"junction+core": (153, 140), "gap+teeth": (6347, 6324)},
}


@pytest.mark.slow
def test_potential_drops_against_recorded_fem_lines() -> None:
    """The network's iron drops along the pole (core from the face to the pole back's
    underside, plus the junction the FEM line crosses up to the back's mid-line) and
    from the face to the yoke (gap + teeth, path-independent in the current-free air and
    teeth) against the FEM's line integrals: signed windows of 50 A around the measured
    values (deterministic network, recorded FEM; the table is rounded to 1 A), and how
    close they are: gap + teeth within 2 %; junction + core within 20 % (the FEM's line
    runs through the core's centre, whose flux is 2-4 % above the network's mean core
    flux deep in saturation: -4 % at 10 mm / 100 A, -12 % at 6 mm / 80 A (before
    fringe26 -1 and -9 %: fewer flank strips take flux off the upper core); the former
    network: +6 % and -26 %, its junction alone 1064 A against the FEM's 367 A at 10 mm /
    100 A)."""
    import numpy as np

    import maglevkit as mk

    fem = _fem()
    data = fem._load("diagnosis")
    mag = fem.cut_magnet("tr09-standard", "split")
    for (smm, i), regions in DIAGNOSIS.items():
        s = smm * 1e-3
        pts = [data[fem._key(s, i, o, fem.GRID_REFINE)] for o in fem.OFFSETS]

        def line(tags: tuple[str, ...], pts: list = pts) -> float:
            return float(np.dot(fem.WEIGHTS, [sum(abs(p["mmf"]["mmf"][t]["9"]) for t in tags)
                                              for p in pts]))

        sol = mk.solve_statics(mag, gaps_m=s, currents_A=[i, i])
        flux = dict(zip(sol.branch_names, np.ravel(sol.branch_flux_Wb), strict=True))
        drop = {e.name: abs(float(e.mmf_drop(flux[br.name], s)))
                for br in mag.network.branches for e in br.elements
                if isinstance(e, (mk.IronPath, mk.AirGap))}
        core = sum(v for k, v in drop.items() if k.startswith("iron_core_p09_"))
        got = {"junction+core": (line(("corner", "core")), core),
               "gap+teeth": (line(("gap", "teeth")), drop["gap_p09"] + drop["iron_teeth_p09"])}
        for key, (f_want, n_want) in regions.items():
            f_got, n_got = got[key]
            assert abs(f_got - f_want) <= 50 and abs(n_got - n_want) <= 50, (smm, i, key, got)
            tol = 0.20 if key == "junction+core" else 0.02
            assert abs(n_got / f_got - 1) < tol, (smm, i, key, got)
