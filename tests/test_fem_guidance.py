"""Guidance magnet against its recorded 2-D FEM (issue 26).

The FEM (benchmarks/fem_guidance.py: the cross-section of ``tr-guidance``, pole bars, legs,
yoke with its coil, the rail; 2-D over the section length, the yokes at their real
cross-section by a depth ratio) is recorded in benchmarks/results/fem_guidance.json; the
network (``end_effects = false``, which for this kind is the default network) is held to
its measured errors here without rerunning the FEM.  The measured errors are large: the
network lacks the leakage around the coil's back side behind the yoke (docs/validation_fem.md,
"Guidance magnet"); the windows pin them so that a change of the network or of the record
has to re-measure them.

``flux_paths = "split"`` (guidance26) adds the missing paths from geometry (air behind the
yoke, the legs' window leakage and top fringe, the coil's cross-section beside the yoke);
it is held to its own measured errors, on the grid and on ten points solved after the
paths were chosen (held out then; guide26 changed the paths looking at all 22).  guide26: the
yoke-leg bend from its conformal map, the bars' flanks with the conformal edge law landing on
the rail beside the face, the rail beside the face in pieces; checked on the field's own MMF
drops and region fluxes (``test_split_network_mmf_drops_against_the_field``, slow).
guidesat26: the legs' top fringe from the yoke-leg corner, the window's tubes beside the coil
from the legs' yoke ends (the deep-saturation force, -3.4 % at 6 mm / 100 A, now -2.6 %).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "fem_guidance.py"


def _fem():  # type: ignore[no-untyped-def]
    sys.path.insert(0, str(_PATH.parent))
    spec = importlib.util.spec_from_file_location("fem_guidance", _PATH)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("fem_guidance", mod)
    spec.loader.exec_module(mod)
    return mod


# (network - FEM)/FEM [%] of one section: force, flux linkage, differential inductance
# (both circuits' currents together).  The network is deterministic and the record fixed:
# 0.3 pp covers the table's rounding only.
MARGIN = 0.3
MEASURED = {
    (6.0, 10.0): (-5.2, -14.4, -14.3),
    (6.0, 32.0): (+4.8, -10.2, +6.6),
    (6.0, 50.0): (+8.4, -9.1, -10.9),
    (6.0, 80.0): (+7.8, -9.9, -26.2),
    (10.0, 10.0): (-3.4, -17.5, -17.4),
    (10.0, 32.0): (-0.2, -16.2, -6.7),
    (10.0, 50.0): (+13.4, -10.7, +8.4),
    (10.0, 80.0): (+15.3, -10.1, -18.3),
    (20.0, 10.0): (-0.7, -23.4, -23.4),
    (20.0, 32.0): (-0.3, -23.3, -22.6),
    (20.0, 50.0): (+5.6, -21.1, +1.0),
    (20.0, 80.0): (+29.7, -12.3, +14.3),
}


@pytest.mark.slow
def test_network_against_recorded_fem() -> None:
    fem = _fem()
    rows = {(r["s_mm"], r["I_A"]): r for r in fem.compare(fem.network_magnet(), fem.load())}
    assert set(MEASURED) == set(rows)
    for k, (ef, epsi, el) in MEASURED.items():
        r = rows[k]
        for name, got, want in (("F", r["eF"], ef), ("psi", r["epsi"], epsi),
                                ("L", r["eL"], el)):
            assert want - MARGIN <= got <= want + MARGIN, (k, name, got)
        # the flux linkage is low at every point (the missing leakage behind the yoke)
        assert r["epsi"] < -8.0, k
    # below the knee the face and its flank fringing match the field's force: within 6 %
    # at 10 A and 32 A, within 1 % at 10 and 20 mm / 32 A (the nominal current)
    for (s, i), r in rows.items():
        if i <= 32.0:
            assert abs(r["eF"]) < (1.0 if s >= 10.0 and i == 32.0 else 6.0), (s, i)


@pytest.mark.slow
def test_recorded_fem_is_converged_and_balanced() -> None:
    """The record's own checks: mesh (sizes / 1.4, / 2), P1, air box and the flux balance
    across the symmetry plane (what the yoke sends up returns beside it)."""
    data = _fem().load()
    for i in (32, 80):
        base = data[f"s10_I{i}"]
        for suf, tol in (("_r1.4", 1e-3), ("_r2", 1e-3), ("_box1.2", 3e-3)):
            p = data[f"s10_I{i}{suf}"]
            for q in ("force_N", "psi_Wb", "L_H"):
                # mesh: < 0.1 %; box 0.8 -> 1.2 m: < 0.3 % (measured 0.27 % at 80 A)
                assert abs(p[q] / base[q] - 1) < tol, (i, suf, q)
    for p in data.values():
        f = p["flux"]
        returned = f["behind"] + f["window"] + f["gap_plane"] + f["rail"] + f["beyond"]
        # A = 0 at the plane's two ends (the box), so the signed pieces add up to zero
        # exactly; with magnitudes this holds only if every piece returns (none goes up
        # beside the yoke): 0.2 % covers the probes' interpolation
        assert returned == pytest.approx(f["yoke"], rel=2e-3)


# "split": (network - FEM)/FEM [%], force, flux linkage, differential inductance; the
# grid, then the held-out points: the first five solved after the air paths were fixed,
# the last five after the iron members' lengths were too (guidance26).  Since guide26 (the
# yoke-leg bend from its conformal map, the bars' flanks by the conformal edge law landing
# beside the face, the rail beside the face in pieces) no point is held out: all 22 were
# seen while those were chosen.  Since guidesat26 the legs' top fringe leaves from the
# yoke-leg corner and the window's tubes beside the coil from the legs' yoke ends (where the
# field's flux leaves them, its outline fluxes; no factor): chosen looking at all 28 points
# (the six of HELD_OUT_GUIDE26 too).  Same 0.3 pp margin.
MEASURED_SPLIT = {
    (6.0, 10.0): (+0.5, +0.2, +0.4),
    (6.0, 32.0): (+1.0, +0.4, -3.8),
    (6.0, 50.0): (-0.4, -0.0, -2.1),
    (6.0, 80.0): (-1.7, -0.1, -0.8),
    (10.0, 10.0): (+0.2, +0.2, +0.2),
    (10.0, 32.0): (+1.5, +0.8, +0.7),
    (10.0, 50.0): (+0.2, +0.2, -2.0),
    (10.0, 80.0): (-1.0, +0.1, -0.4),
    (20.0, 10.0): (+1.4, +0.1, +0.1),
    (20.0, 32.0): (+1.8, +0.2, +0.8),
    (20.0, 50.0): (+2.4, +0.5, +0.4),
    (20.0, 80.0): (+1.4, +0.4, +0.0),
}
HELD_OUT_SPLIT = {
    (8.0, 20.0): (+0.9, +0.5, +1.5),
    (8.0, 65.0): (-0.7, +0.0, -1.1),
    (15.0, 20.0): (+0.6, +0.2, +0.4),
    (15.0, 65.0): (+0.4, +0.3, -0.8),
    (12.0, 100.0): (-1.3, +0.2, +0.2),
    (7.0, 40.0): (+0.4, +0.2, -3.0),
    (9.0, 90.0): (-1.5, +0.0, -0.2),
    (13.0, 30.0): (+1.0, +0.5, +1.6),
    (17.0, 60.0): (+1.2, +0.4, -0.9),
    (18.0, 100.0): (+0.2, +0.3, +0.4),
}

#: solved after guide26 chose its network (benchmarks/fem_guidance.py HELD_OUT_GUIDE26):
#: held out from that choice (not from guidesat26's); before guide26 -5.1 / -3.7 / -0.5 /
#: -1.0 / +0.7 / +3.2 % in force, -1.6 ... -1.0 % in psi; guide26 -3.4 / -2.5 / -0.6 / -2.3 /
#: +1.1 / +0.8 %
HELD_OUT_GUIDE26 = {
    (6.0, 100.0): (-2.6, -0.1, -0.3),
    (7.0, 80.0): (-1.5, -0.1, -0.7),
    (11.0, 55.0): (+0.1, +0.2, -1.6),
    (14.0, 100.0): (-0.9, +0.2, +0.3),
    (16.0, 35.0): (+1.4, +0.5, +1.5),
    (19.0, 70.0): (+1.4, +0.4, -0.4),
}


# not slow: the record only (no FEM solve, no scikit-fem), 0.6 s measured; the one check of
# the split network against an independent solution belongs in the fast suite (review3)
def test_split_network_against_recorded_fem() -> None:
    fem = _fem()
    mag, data = fem.network_magnet("split"), fem.load()
    rows = {(r["s_mm"], r["I_A"]): r for r in fem.compare(mag, data)}
    rows.update({(r["s_mm"], r["I_A"]): r for r in fem.compare(mag, data, points=fem.HELD_OUT)})
    want = {**MEASURED_SPLIT, **HELD_OUT_SPLIT}
    assert set(want) == set(rows)
    for k, (ef, epsi, el) in want.items():
        r = rows[k]
        for name, got, w in (("F", r["eF"], ef), ("psi", r["epsi"], epsi), ("L", r["eL"], el)):
            assert w - MARGIN <= got <= w + MARGIN, (k, name, got)
        # issue 26's aims everywhere, 6-20 mm, 10-100 A, into deep saturation: force and
        # flux linkage within 3 %, differential inductance within 5 %
        assert abs(r["eF"]) < 3.0 and abs(r["epsi"]) < 3.0 and abs(r["eL"]) < 5.0, k
    # the points held out from guide26's choice: all three within the aims, the deepest
    # saturation at the smallest gap too (6 mm / 100 A: -3.4 % before guidesat26, -2.6 %)
    held = {(r["s_mm"], r["I_A"]): r for r in fem.compare(mag, data,
                                                          points=fem.HELD_OUT_GUIDE26)}
    assert set(held) == set(HELD_OUT_GUIDE26)
    for k, (ef, epsi, el) in HELD_OUT_GUIDE26.items():
        r = held[k]
        for name, got, w in (("F", r["eF"], ef), ("psi", r["epsi"], epsi), ("L", r["eL"], el)):
            assert w - MARGIN <= got <= w + MARGIN, (k, name, got)
        assert abs(r["eF"]) < 3.0 and abs(r["epsi"]) < 3.0 and abs(r["eL"]) < 5.0, k
    # the air behind the yoke carries what the field returns behind it: within 11 % at
    # every grid point (the plate model of the back face, no factor; measured -10 ... +0 %)
    for k in MEASURED_SPLIT:
        f, n = rows[k]["flux_fem"], rows[k]["flux_net"]
        assert n["back"] == pytest.approx(f["behind"], rel=0.11), k


@pytest.mark.slow
def test_split_network_mmf_drops_against_the_field() -> None:
    """Where the MMF goes (the line integral of H along the FEM's centre path, solved anew
    here, about 5 s a point) against the split network: the magnet's iron, the gap and the
    rail beside and below the face.  In linear iron (10 A) the network's iron took 7-8 %
    more than the field before guide26 (the corners), so its gap 0.9-1.6 % less, 1.8-3.2 %
    in force; in saturation (80 A) the rail took 15-24 % more (one step for the face's entry,
    the inner flank's flux landing at the face's edge).  Measured now (guidesat26; 6 / 10 /
    20 mm): iron +0.5 / +0.7 / +0.5 % at 10 A, -0.6 / -0.1 / -0.3 % at 80 A; gap +0.3 / +0.1
    / -0.0 % at 10 A, -0.9 / -0.5 / -0.0 % at 80 A; rail -5.2 / -3.9 / -0.4 % at 10 A, +10.0
    / +6.7 / +3.1 % at 80 A (guide26: +2.2 / +1.8 / +2.1 %; more of the loop's flux now
    reaches the rail, which still takes one step per piece)."""
    fem = _fem()
    mag = fem.network_magnet("split")
    g = fem.Geometry.from_magnet(mag)
    for smm, i in ((6.0, 10.0), (6.0, 80.0), (20.0, 80.0)):
        f = fem.field_regions(g, smm * 1e-3, i)
        n = fem.network_regions(mag, smm * 1e-3, i)
        # the FEM's loop closes to N I/2 within 0.1 % (its line integral's own error)
        assert sum(f["mmf_A"].values()) == pytest.approx(150.0 * i, rel=1.5e-3)
        err = {k: n["mmf_A"][k] / f["mmf_A"][k] - 1 for k in ("iron", "gap", "rail")}
        # the gap's MMF sets the force (~ its square): within 1.5 %; the iron within 2.5 %,
        # the rail within 11 % (it takes 2-6 % of the loop's MMF: < 0.7 % of it either way)
        assert abs(err["gap"]) < 0.015, (smm, i, err)
        assert abs(err["iron"]) < 0.025, (smm, i, err)
        assert abs(err["rail"]) < 0.11, (smm, i, err)


def test_record_where_the_corner_sends_its_flux() -> None:
    """guidesat26's premise, from the record alone (the outline fluxes recorded with 16 of
    the points): the yoke-leg corner's top face sends more flux than the legs' top face at
    every point (the split network's top fringe leaves from the corner), and the window's
    flux leaves the yoke's front face for a minor share in linear iron but for most of it in
    deep saturation at the smallest gap (a quarter of the window's permeance, the tubes
    through the coil's front side, leaves from the corner: between the two)."""
    fem = _fem()
    seen, deep = 0, False
    for v in fem.load().values():
        o = v.get("outline_Wb")
        if not o or v["refine"] != 1.0 or v.get("window_depth") or v.get("behind_depth"):
            continue
        seen += 1
        corner_top = o["yoke_top"] - o["back_top"]
        leg_top = o["leg_top"] - o["yoke_top"]
        # measured 1.12-1.56 over the 16 points
        assert 1.05 < corner_top / leg_top < 1.7, (v["s"], v["current"])
        yoke_front = o["front_0"] - o["leg_inner_back"]
        window = o["front_0"] - o["bar_bottom_back"]
        share = yoke_front / window
        if v["current"] <= 20.0:            # linear iron: measured 0.15-0.19
            assert 0.1 < share < 0.25, (v["s"], v["current"], share)
        if round(v["s"] * 1e3) == 6 and v["current"] == 100.0:    # measured 0.65
            assert share > 0.5, share
            deep = True
    assert seen == 16 and deep
