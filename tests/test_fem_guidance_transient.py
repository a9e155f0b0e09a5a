"""Guidance magnet: voltage steps with solid iron against its recorded transient 2-D FEM.

The FEM (benchmarks/fem_guidance_transient.py: the cross-section of benchmarks/fem_guidance.py
with the magnet and the rail as conducting bodies, the coil driven through the section's
resistance; the U-magnet transient FEM's method) is recorded in
benchmarks/results/fem_guidance_transient.json; the flux model is held to its measured
errors against it here without rerunning the FEM (docs/validation_fem.md, "Guidance magnet:
voltage-step transient").  Each window is signed: the lower and upper bound around the
measured value, so that a change of the network, the eddy elements or the record in either
direction has to re-measure them.  The model and the record are deterministic; the windows'
half width (0.5 pp of the step for currents, 1 pp for t63) covers the integrator
(``rtol = 1e-7``) and the tables' rounding, nothing else.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .conftest import load_script

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "fem_guidance_transient.py"


def _script():  # type: ignore[no-untyped-def]
    return load_script(_PATH)


def _record() -> dict:
    return json.loads((_PATH.parent / "results" / "fem_guidance_transient.json").read_text())


def test_recorded_fem_is_converged() -> None:
    """The FEM's own error, from its mesh and time-step study at 10 mm / 10 -> 20 A."""
    mod = _script()
    data = _record()
    base = data["cases"]["runs"][0]
    assert base["label"] == "10 mm, 10 -> 20 A"
    changes = {r["label"]: mod.fem_change(r, base) for r in data["study"]["runs"]}
    # measured: mesh x 1.5 0.24 %, dt / 2 0.011 % of the step for t >= 1 ms; the model
    # comparisons below judge errors of >= 0.4 % of the step against aims of 5 %
    assert set(changes) == {"10 mm, 10 -> 20 A, mesh x 1.5", "10 mm, 10 -> 20 A, dt / 2"}
    assert all(c < 3e-3 for c in changes.values()), changes
    t63 = {r["label"]: mod.rise_time(np.asarray(r["time_s"]), np.asarray(r["current_A"]),
                                     r["i0_A"], r["i1_A"])
           for r in [base, *data["study"]["runs"]]}
    # measured 521.44 / 521.92 / 521.59 ms: within 0.1 % of each other
    assert max(t63.values()) / min(t63.values()) - 1 < 2e-3, t63
    # energy balance of every run (rectangle rule on the BDF2 steps): measured 2.9e-4 ...
    # 6.8e-4
    runs = [r for part in data.values() for r in part["runs"]]
    assert all(r["energy_residual"] < 1e-3 for r in runs)
    # the recorded circuit is the bundled network's (both sections alike, one circuit each)
    assert all(r["resistance_ohm"] == 1.5 for r in runs)


# (case, model) -> measured (err at 1 ms, max err for t >= 1 ms, both in % of the step;
# t63 error in %), docs/validation_fem.md (re-measured by guide26 on its split network: the
# yoke-leg bends, the flanks landing beside the face, the rail beside the face in pieces;
# the eddy elements over the parts' material lengths; and by guidesat26: the top fringe from
# the yoke-leg corner and the window's tubes beside the coil from the legs' yoke ends move
# the 2-D cut's t63 by +0.2 ... +1.2 pp, its flux linkage 0.2-0.6 pp higher)
MEASURED = {
    ("10 mm, 10 -> 20 A", "2-D cut, lumped"): (+11.1, 11.7, +10.4),
    ("6 mm, 10 -> 20 A", "2-D cut, lumped"): (+11.1, 11.8, +12.8),
    ("10 mm, 20 -> 50 A", "2-D cut, lumped"): (+11.1, 11.2, +13.7),
    ("10 mm, 10 -> 20 A", "2-D cut, ladder n = 6"): (-0.5, 0.6, +1.4),
    ("6 mm, 10 -> 20 A", "2-D cut, ladder n = 6"): (-0.4, 1.0, +2.4),
    ("10 mm, 20 -> 50 A", "2-D cut, ladder n = 6"): (-0.5, 1.3, +5.1),
    ("10 mm, 10 -> 20 A", "2-D cut, ladder n = 8"): (-0.5, 0.6, +1.6),
    ("6 mm, 10 -> 20 A", "2-D cut, ladder n = 8"): (-0.5, 1.0, +2.6),
    ("10 mm, 20 -> 50 A", "2-D cut, ladder n = 8"): (-0.5, 0.9, +3.4),
    ("10 mm, 10 -> 20 A", "bundled, lumped"): (+11.4, 13.4, +1.7),
    ("6 mm, 10 -> 20 A", "bundled, lumped"): (+11.4, 13.6, +6.3),
    ("10 mm, 20 -> 50 A", "bundled, lumped"): (+11.4, 12.8, +11.3),
    ("10 mm, 10 -> 20 A", "bundled, ladder n = 8"): (-0.3, 1.9, -6.3),
    ("6 mm, 10 -> 20 A", "bundled, ladder n = 8"): (-0.3, 1.0, -2.9),
    ("10 mm, 20 -> 50 A", "bundled, ladder n = 8"): (-0.3, 1.8, -3.6),
}
#: the same networks without eddy currents against the FEM with sigma = 0: (max err, t63 err)
MEASURED_STATIC = {
    ("10 mm, 10 -> 20 A", "2-D cut"): (0.2, +0.6),
    ("6 mm, 10 -> 20 A", "2-D cut"): (0.5, +1.2),
    ("10 mm, 20 -> 50 A", "2-D cut"): (0.6, +0.6),
    ("10 mm, 10 -> 20 A", "bundled"): (2.7, -7.0),
    ("6 mm, 10 -> 20 A", "bundled"): (1.7, -4.4),
    ("10 mm, 20 -> 50 A", "bundled"): (2.2, +0.9),
}


def _within(value: float, measured: float, half: float) -> bool:
    return measured - half <= value <= measured + half


def _errors(mod, ref: dict, mag) -> tuple[float, float, float]:  # type: ignore[no-untyped-def]
    run = mod.model_step(ref, mag)
    m = mod.metrics(run["time_s"], run["current_A"], run["eddy_loss_J"], ref)
    return (100 * m["err_1ms"], 100 * m["err_max"], 100 * (m["t63_s"] / m["t63_fem_s"] - 1))


def test_ladder_meets_the_aims_where_the_lumped_elements_jump() -> None:
    """One recorded step (10 mm, 10 -> 20 A) on the 2-D cut, in the fast suite: issue 26's
    aims (current within 5 % of the step for t >= 1 ms, t63 within 5 %) met by
    ``eddy_model = "ladder"`` (measured 0.6 % and +1.6 %), missed by the lumped elements,
    whose current jumps at t = 0+ (measured +11.1 % of the step at 1 ms, t63 +10.4 %)."""
    mod = _script()
    ref = _record()["cases"]["runs"][0]
    assert ref["label"] == "10 mm, 10 -> 20 A"
    ladder = _errors(mod, ref, mod.MODELS["2-D cut, ladder n = 8"]())
    lumped = _errors(mod, ref, mod.MODELS["2-D cut, lumped"]())
    assert ladder[1] < 5.0 and abs(ladder[2]) < 5.0, ladder
    assert lumped[0] > 9.0 and lumped[2] > 5.0, lumped


def test_guidance_ladder_structure() -> None:
    """``eddy_model = "ladder"`` on the guidance kind: n tubes per solid part (per section
    four half legs, two pole bars, the yoke, the rail's middle and, since guide26, its four
    pieces beside each face), statics those of the lumped
    network, ``coil_air`` across the whole yoke, the Saint-Venant factor only with
    ``end_effects``, ``"ladder_split"`` refused."""
    import maglevkit as mk
    from maglevkit.errors import InputError

    lumped = mk.load_magnet("tr-guidance", eddy_model="lumped")   # the file's is the ladder
    ladder = mk.load_magnet("tr-guidance", eddy_model="ladder", eddy_layers=3)
    count = [sum(int(g > 0) for g in m.network.eddy_conductances) for m in (lumped, ladder)]
    # lumped: 4 half legs (the bars' iron inside), the yoke, the rail's middle and its 8
    # pieces beside the faces; ladder: those 14 parts and the two bars, 3 tubes each
    assert count == [2 * 14, 2 * 16 * 3], count
    coil_air = ladder.network.branch("coil_air_1")
    assert (coil_air.start, coil_air.end) == ("YL1", "YU1")
    assert "EY1" not in {b.end for b in ladder.network.branches}
    for gap, current in ((0.006, 50.0), (0.010, 32.0), (0.020, 80.0)):
        a = mk.solve_statics(lumped, gaps_m=gap, currents_A=[current, current])
        b = mk.solve_statics(ladder, gaps_m=gap, currents_A=[current, current])
        # parallel tubes of one material and length carry one flux density: the same
        # statics up to the solver's tolerance (measured ~1e-11 relative on the U-magnet)
        assert np.allclose(b.pole_force_N, a.pole_force_N, rtol=1e-8)
        assert np.allclose(b.flux_linkage_Wb, a.flux_linkage_Wb, rtol=1e-8)
    # the yoke's outermost eddy element: the 2-D slab on the cut, times J_rect/J_slab of
    # the merged yokes' 0.9 m x 70 mm section in the bundled file (measured 0.951)
    mod = _script()
    cut = mod.guidance_magnet(end_effects=False, eddy_model="ladder", eddy_layers=3)
    g = [m.network.eddy_conductances[m.network.branch_names.index("yoke_1")]
         for m in (ladder, cut)]
    assert g[0] / g[1] == pytest.approx(0.951, abs=1e-3)
    with pytest.raises(InputError, match="ladder_split.*guidance_magnet.*'ladder' or"):
        mk.load_magnet("tr-guidance", eddy_model="ladder_split")


@pytest.mark.slow
def test_flux_model_against_recorded_fem() -> None:
    """The lumped eddy elements jump (+11.1 % of the step at 1 ms, up to 11.8 % off: the
    5 % aim is missed) and rise 10-14 % slow on the 2-D cut; ``eddy_model = "ladder"`` (the
    slab ladder on every solid part) meets both aims (n = 8: current within 1.0 % of the
    step, t63 +1.6 ... +3.4 %; n = 6 +5.1 % in saturation).  The bundled file's air paths
    over the yokes' depth (``end_effects = true``) are a 3-D term the 2-D FEM lacks:
    without eddy currents they make the rise 4.4-7.0 % fast below the knee, which offsets
    the lumped eddy elements' slow rise there and makes the bundled ladder 3-6 % fast."""
    mod = _script()
    data = _record()
    mags = {label: make() for label, make in mod.MODELS.items()}
    static = {"2-D cut": mod.guidance_magnet(end_effects=False, eddy_currents=False),
              "bundled": mod.guidance_magnet(eddy_currents=False)}
    noeddy = {r["label"]: r for r in data["noeddy"]["runs"]}
    for ref in data["cases"]["runs"]:
        for (case, label), (e1, emax, et63) in MEASURED.items():
            if case != ref["label"]:
                continue
            got = _errors(mod, ref, mags[label])
            assert _within(got[0], e1, 0.5), (case, label, got)
            assert _within(got[1], emax, 0.5), (case, label, got)
            assert _within(got[2], et63, 1.0), (case, label, got)
            if label.startswith("2-D cut, ladder n = 8"):
                # issue 26's aims: current within 5 % of the step, t63 within 5 %
                assert got[1] < 5.0 and abs(got[2]) < 5.0, (case, label, got)
        for (case, net), (emax, et63) in MEASURED_STATIC.items():
            if case != ref["label"]:
                continue
            fem = noeddy[case]
            run = mod.model_step(fem, static[net])
            m = mod.metrics(run["time_s"], run["current_A"], run["eddy_loss_J"], fem)
            assert _within(100 * m["err_max"], emax, 0.5), (case, net, m)
            assert _within(100 * (m["t63_s"] / m["t63_fem_s"] - 1), et63, 1.0), (case, net, m)


@pytest.mark.slow   # ~2 min wall under load: two map sets (lumped, 8-layer ladder), 6 runs
def test_bundled_reduced_model_against_recorded_fem() -> None:
    """The reduced model the bundled file names (guideswitch: the 8-layer ladder's maps with
    the 3-branch eddy network) against the FEM's voltage steps, both sections stepped like
    the FEM's section: within issue 26's 5 % of the step for t >= 1 ms (measured on the
    vehicle maps 4.2 / 2.4 / 3.9 %), no jump at 1 ms (-0.0 / -0.3 / -0.0 %).  The former
    default (lumped elements, eq. 8) jumps by ``dU/(R_el + R_ec)``: +18.5 % of the step at
    1 ms at every step (measured).  An independent check of the whole chain: the FEM knows
    neither the network nor the reduction."""
    import maglevkit as mk

    mod = _script()
    data = _record()
    # maps spanning the three steps (6 and 10 mm, 10-50 A) with margin for the RK4 stages
    grid = dict(gaps_m=np.linspace(0.005, 0.012, 8), currents_A=np.linspace(0.0, 60.0, 31),
                progress=False)
    bundled = mk.load_magnet("tr-guidance")
    assert (bundled.options.eddy_model, bundled.default_eddy_modes) == ("ladder", 3)
    now = mk.CurrentModel(mk.build_maps(bundled, **grid), eddy_modes=3)
    before = mk.CurrentModel(mk.build_maps(mk.load_magnet("tr-guidance", eddy_model="lumped"),
                                           **grid))
    r_el = bundled.network.resistances
    for ref in data["cases"]["runs"]:
        got = {}
        for label, model in (("now", now), ("before", before)):
            res = mk.simulate(model, np.asarray(ref["time_s"]), gaps_m=ref["gap_m"],
                              voltages_V=r_el * ref["i1_A"], initial_currents_A=ref["i0_A"])
            m = mod.metrics(res.time_s, res.currents_A[:, 0], np.zeros_like(res.time_s), ref)
            got[label] = (100 * m["err_1ms"], 100 * m["err_max"])
        # bounds: the aim (5 %) for the network, 1 pp at 1 ms (measured <= 0.4 pp on these
        # and on the vehicle maps); the former model at least 15 % (measured 18.5 %)
        assert got["now"][1] < 5.0 and abs(got["now"][0]) < 1.0, (ref["label"], got)
        assert got["before"][0] > 15.0, (ref["label"], got)
