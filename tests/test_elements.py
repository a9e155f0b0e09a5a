"""Element laws against the published flux-tube formulas (facts.md sec. 3/4), computed here
independently of the package, and the physics switches of the U-magnet one at a time."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import maglevkit as mk
from maglevkit.circuit.elements import (
    AirGap,
    EdgeCornerPermeance,
    FringePermeance,
    GapLayerPermeance,
    GapLeakage,
)
from maglevkit.errors import ParameterError
from maglevkit.materials import MU0

from .conftest import build_u, u_params

# Every comparison below is between two evaluations of the same closed form (or a quadrature
# of it to ~1e-12), so 1e-12 relative is rounding, not modelling error.
RTOL = 1e-12


@pytest.mark.parametrize(("ctor", "args", "expected"), [
    ("half_cylinder", (0.2,), 0.26 * MU0 * 0.2),
    ("quarter_cylinder", (0.2,), 0.52 * MU0 * 0.2),
    ("half_hollow_cylinder", (0.2, 0.01, 0.03), MU0 * 0.2 * math.log(1 + 0.03 / 0.01) / math.pi),
    ("quarter_hollow_cylinder", (0.2, 0.01, 0.03),
     2 * MU0 * 0.2 * math.log(1 + 0.03 / 0.01) / math.pi),
    ("quarter_sphere", (0.02,), 0.077 * MU0 * 2 * 0.02),
    ("eighth_sphere", (0.02,), 0.308 * MU0 * 0.02),
    ("quarter_hollow_sphere", (0.015,), 0.25 * MU0 * 0.015),
    ("parallel_plates", (0.01, 0.05), MU0 * 0.01 / 0.05),
])
def test_roters_leakage_shapes(ctor: str, args: tuple, expected: float) -> None:
    el = getattr(mk.LeakagePermeance, ctor)("leak", *args)
    assert el.permeance() == pytest.approx(expected, rel=RTOL)


def test_gap_leakage_around_poles_is_the_modelica_formula() -> None:
    el = mk.GapLeakage("g", gap_input="s", width_m=0.1, radius_m=0.02)
    for s in (0.002, 0.01, 0.05):
        assert el.permeance(s) == pytest.approx(MU0 * 0.1 / math.pi * math.log(1 + math.pi * 0.02 / s),
                                                rel=RTOL)


@pytest.mark.parametrize("s", [0.004, 0.010, 0.020])
def test_air_gap_fringe_edge_is_the_quarter_circle_tube_to_a_plane(s: float) -> None:
    """The field line leaving the flank at height x runs a quarter circle (pi x/2) and then
    straight across the gap: dG = mu0 w dx/(s + pi x/2).  Quadrature of that tube, not the
    closed form in the code."""
    w, r, area = 0.1, 0.01, 0.003
    gap = mk.AirGap("g", gap_input="s", pole_area_m2=area, fringe_edges=((w, r),))
    tube, _ = quad(lambda x: MU0 * w / (s + math.pi * x / 2), 0.0, r, epsabs=0, epsrel=1e-13)
    assert gap.permeance(s) - MU0 * area / s == pytest.approx(tube, rel=1e-10)
    # the image construction: twice the pole-to-pole tube at distance 2 s
    image = 2 * mk.GapLeakage("i", gap_input="s", width_m=w, radius_m=r).permeance(2 * s)
    assert gap.permeance(s) - MU0 * area / s == pytest.approx(image, rel=RTOL)


ROSCHKE_FACTS = {  # facts.md sec. 4: mu_i, B_mymax, c_a, c_b, n
    "M330-50A": (500, 0.7, 24000, 9.38, 9.6),
    "AISI 1008": (200, 1.17, 8100, 2.59, 10),
    "9SMnPb28": (400, 1.488, 1200, 3, 12.5),
    "M700-100A": (1120, 1.2, 20750, 3.55, 13.15),
    "VACOFLUX 50": (3850, 1.75, 11790, 2.63, 15.02),
}


@pytest.mark.parametrize("name", sorted(ROSCHKE_FACTS))
def test_roschke_records_follow_the_published_formula(name: str) -> None:
    mu_i, b_max, c_a, c_b, n = ROSCHKE_FACTS[name]
    b = np.array([-2.2, -1.0, 0.05, 0.5, 1.0, 1.5, 2.0, 3.0])
    bn = np.abs(b / b_max)
    mu_r = 1 + (mu_i - 1 + c_a * bn) / (1 + c_b * bn + bn**n)
    mat = mk.get_material(name.lower().replace(" ", "_"))   # lookup ignores case/punctuation
    # the formula up to its polarisation peak B* (1.79-3.57 T); beyond it the record
    # continues along the tangent of slope 1/mu0 (tests/test_materials_saturation_tail.py)
    ok = np.abs(b) <= mat.tail_from_T
    assert ok.sum() >= 5
    np.testing.assert_allclose(mat.field_strength(b[ok]), (b / (MU0 * mu_r))[ok], rtol=RTOL)


# ---------------------------------------------------------------- U-magnet switches
P = u_params()["magnet"]
RAIL = u_params()["rail"]
N, D, WP = P["turns"], P["depth"], P["pole_width"]
GCP, HC, WW = P["coil_gap_to_pole_face"], P["coil_height"], P["window_width"]
OVERHANG = 0.5 * (RAIL["width"] - (WW + 2 * WP))


def _fringe(s: float) -> float:
    """Documented U-magnet fringing (docs/equations.md sec. 6): an inner edge of flank height
    GCP and an outer edge limited by the rail overhang, each along the depth."""
    return sum(2 * MU0 * D / math.pi * math.log(1 + math.pi * r / (2 * s))
               for r in (GCP, min(GCP, OVERHANG)))


@pytest.mark.parametrize("s", [0.004, 0.012, 0.020])
def test_u_magnet_fringing_alone(s: float) -> None:
    """Ideal iron, no leakage, fringing on: two equal gaps in series, L = n^2 G(s)/2."""
    mag = build_u(material="ideal", leakage=False)
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=10.0)
    g = MU0 * WP * D / s + _fringe(s)
    assert sol.differential_inductance_H[0, 0] == pytest.approx(N**2 * g / 2, rel=1e-9)


K = 5                                   # coil_segments default (docs/equations.md sec. 6)
H_STRIP = HC / K
Y_NODES = [GCP + (k + 0.5) * H_STRIP for k in range(K)]
F_NODES = [1 - (k + 0.5) / K for k in range(K)]      # share of the turns above each node


def _flank(y: float) -> float:
    """Documented flank leakage of one strip: quarter circles (path pi y/2) on the outer
    flank, and on the window flank while y <= window_width/2."""
    y0, y1 = y - H_STRIP / 2, y + H_STRIP / 2
    g = 2 * MU0 * D / math.pi * math.log(y1 / y0)
    if y0 < WW / 2:
        g += 2 * MU0 * D / math.pi * math.log(min(y1, WW / 2) / y0)
    return g


@pytest.mark.parametrize("s", [0.004, 0.012, 0.020])
def test_u_magnet_leakage_alone(s: float) -> None:
    """Ideal iron, no fringing, leakage on.  With ideal iron the node L_k of a leg sits at
    the MMF of the turns above it, f_k n I/2, so the co-energy of the linear network gives
    L = n^2 [G_gap/2 + G_tip + sum f_k^2 G_k + sum f_k^2 G_flank,k / 2] (window strips
    G_k between the legs, flank strips to the rail); derived here from the node potentials,
    not from the code.  The force is the textbook one (no leakage tube depends on s)."""
    mag = build_u(material="ideal", fringing=False)
    i = 10.0
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=i)
    a = WP * D
    g_tip = MU0 * D * GCP / WW
    g_strip = MU0 * D * H_STRIP / WW
    l_exact = N**2 * (MU0 * a / s / 2 + g_tip + sum(f * f * g_strip for f in F_NODES)
                      + 0.5 * sum(f * f * _flank(y) for f, y in zip(F_NODES, Y_NODES, strict=True)))
    assert sol.differential_inductance_H[0, 0] == pytest.approx(l_exact, rel=1e-9)
    assert sol.force_N == pytest.approx(MU0 * (N * i) ** 2 * a / (4 * s * s), rel=1e-9)
    # the window leakage tends to the classical coil_height/3 estimate (K -> oo); at K = 5
    # the midpoint sum of f^2 is 0.33 instead of 1/3
    assert sum(f * f for f in F_NODES) / K == pytest.approx(1 / 3, rel=0.011)


def test_u_magnet_saturation_switch_alone() -> None:
    """Without saturation the iron is linear at mu_i: the inductance does not depend on
    the current (to Newton's tolerance); with saturation it falls by far more."""
    lin = mk.solve_statics(build_u(saturation=False), gaps_m=0.006, currents_A=[[1.0], [80.0]])
    sat = mk.solve_statics(build_u(), gaps_m=0.006, currents_A=[[1.0], [80.0]])
    l_lin, l_sat = lin.differential_inductance_H[:, 0, 0], sat.differential_inductance_H[:, 0, 0]
    assert l_lin[1] == pytest.approx(l_lin[0], rel=1e-9)
    assert l_sat[1] < 0.5 * l_sat[0]


def test_kirchhoff_loop_law_by_hand_in_deep_saturation() -> None:
    """The MMF around the main loop (all leg segments, yoke, rail, both gaps) equals n I,
    summed from the solved branch fluxes with the documented geometry (lengths and areas
    computed here from the parameter file) and the published B-H law: a check of the
    builder's geometry and of the node laws along a leg.  The independent solution of a
    saturable loop (a scalar root solve) is test_statics.py's
    test_single_saturable_loop_against_a_scalar_root_solve."""
    mag = mk.load_magnet("u-magnet", eddy_currents=False)
    s, i = 0.005, 80.0
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=i)
    steel = mk.get_material("AISI 1008")
    c = WW + WP
    leg = P["leg_height"] + P["yoke_thickness"] / 2
    seg = [Y_NODES[0], *([H_STRIP] * (K - 1)), leg - Y_NODES[-1]]  # docs/equations.md sec. 6
    iron = {f"leg_{side}_{j}": (seg[j], WP * D) for side in ("left", "right") for j in range(K + 1)}
    iron.update({"yoke": (c, P["yoke_thickness"] * D),
                 "rail": (c + RAIL["thickness"], RAIL["thickness"] * D)})
    # the builder's iron parts have the documented lengths and areas (docs/equations.md
    # sec. 6, computed above from the parameter file): the same numbers, 1e-12 for rounding
    built = {e.name.removeprefix("iron_"): (e.length_m, e.cross_section_m2)
             for b in mag.network.branches for e in b.elements if isinstance(e, mk.IronPath)}
    assert set(built) == set(iron)
    for name, (length, area) in iron.items():
        assert built[name] == pytest.approx((length, area), rel=1e-12), name
    mmf = sum(length * float(steel.field_strength(sol.branch_flux(b) / area))
              for b, (length, area) in iron.items())
    g = MU0 * WP * D / s + _fringe(s)
    mmf += (sol.branch_flux("gap_left") + sol.branch_flux("gap_right")) / g
    # deep saturation: the legs carry > 2 T, so the iron takes a large share of n I
    assert abs(float(sol.branch_flux_density_T[sol.branch_names.index("leg_left_3")])) > 2.0
    assert float(mmf) == pytest.approx(N * i, rel=1e-9)
    # node law at the pole tips: tip-segment flux = gap flux + window leakage at the tips
    assert float(sol.branch_flux("leg_left_0")) == pytest.approx(
        float(sol.branch_flux("gap_left") + sol.branch_flux("leakage")), rel=1e-12)
    # and up the leg the flux grows by what leaves across the window and the flanks
    up = sol.branch_flux("leg_left_1") - sol.branch_flux("leg_left_0")
    assert float(up) == pytest.approx(float(sol.branch_flux("leakage_1")
                                            + sol.branch_flux("flank_left_1")), rel=1e-9)
    assert float(up) > 0


def test_air_gap_fringe_permeance_is_its_share_of_the_permeance() -> None:
    """One fringe law: the calibration's fringing factor scales AirGap.fringe_permeance."""
    from maglevkit.circuit.factors import CalibratedLinear

    plain = mk.AirGap("g", gap_input="s", pole_area_m2=0.01, slot_pitch_m=0.04, slot_opening_m=0.01)
    edged = mk.AirGap("g", gap_input="s", pole_area_m2=0.01, slot_pitch_m=0.04, slot_opening_m=0.01,
                      fringe_edges=((0.2, 0.02), (0.1, 0.01)))
    for s in (0.005, 0.012):
        f = edged.fringe_permeance(s)
        assert f > 0.0 and plain.fringe_permeance(s) == 0.0
        assert edged.permeance(s) == pytest.approx(plain.permeance(s) + f, rel=1e-14)
        cal = CalibratedLinear(name="g", inner=edged, fringing=1.5)
        assert cal.permeance(s) == pytest.approx(edged.permeance(s) + 0.5 * f, rel=1e-14)


@pytest.mark.parametrize(("make", "label"), [
    (lambda g: AirGap("e", gap_input=g, pole_area_m2=1e-3), "air gap"),
    (lambda g: GapLeakage("e", gap_input=g, width_m=0.1, radius_m=0.01), "gap leakage"),
    (lambda g: FringePermeance("e", gap_input=g, width_m=0.1, radius_m=0.01),
     "fringe permeance"),
    (lambda g: EdgeCornerPermeance("e", gap_input=g, width_m=0.1, coil_from_m=0.01,
                                   coil_height_m=0.05), "edge corner permeance"),
    (lambda g: GapLayerPermeance("e", gap_input=g, width_m=0.1, length_m=0.02),
     "gap layer permeance"),
])
def test_gap_elements_share_the_gap_input_checks(make, label) -> None:  # type: ignore[no-untyped-def]
    # tidy26: one base holds the gap boilerplate; GapLeakage lacked the gap_input check
    # (an empty name was accepted and failed later, far from its cause)
    el = make("g7")
    assert el.gap == "g7"
    assert float(el.permeance(0.01)) > 0.0
    with pytest.raises(ParameterError, match=rf"^{label} 'e': needs a gap value$"):
        el.permeance()
    with pytest.raises(ParameterError, match=rf"^{label} 'e': gap_input must be a non-empty"):
        make("")
