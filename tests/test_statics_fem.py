"""The U-magnet's cell network (``discretisation = "grid"``) against the 2-D FEM (issue 12).

The FEM numbers below are recorded from ``python benchmarks/fem_u_magnet.py`` (section 1
of docs/validation_fem.md; that script regenerates them, ``--cache FILE`` keeps them in a
JSON file): AISI 1008, refine = 1, whose own discretisation error is < 0.1 %
(h/2 mesh study, virtual work vs Maxwell stress, docs/validation_fem.md sec. 4).
Errors (EMC - FEM)/FEM measured over the whole grid 4-20 mm x 5-80 A:

    network           force [%]        flux linkage [%]
    lumped            -7.6 ... +3.9    -7.9 ... +0.1     (the default)
    grid              -3.2 ... +4.3    -5.6 ... +0.3
    grid + coil_air   -2.6 ... +5.9    -4.3 ... +0.3

The physics checks of the new network and its new element (closed forms, co-energy,
reciprocity, the pole-flux bookkeeping of parallel coils) need no FEM.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

import maglevkit as mk
from maglevkit.circuit import AirGap, Coil, FringePermeance
from maglevkit.errors import ParameterError, ParameterFileError
from maglevkit.magnets.u_magnet import build_u_magnet
from maglevkit.materials import MU0, ConstantPermeability

from .conftest import build_u, u_params

# (s [mm], I [A]): (F_FEM [N], psi_FEM [Wb], err F grid [%], err psi grid [%],
#                   err F lumped [%], err psi lumped [%]) -- measured, see the docstring
RECORDED = {
    (4, 20): (4371.70, 3.47364, -1.71, -1.50, -6.95, -4.10),
    (8, 40): (3913.42, 3.86137, -2.35, -2.97, -7.59, -5.51),    # the knee
    (12, 40): (2686.64, 3.64769, -3.15, -3.27, -7.48, -5.47),   # largest grid force error < 0
    (4, 80): (7884.90, 4.69331, -1.84, -4.38, -7.12, -6.99),    # deep saturation (2.6 T)
    (20, 5): (26.91, 0.46114, +4.32, -0.11, +3.88, -0.30),      # largest grid force error > 0
    (20, 80): (2409.63, 4.26762, +3.28, -5.62, -1.42, -7.92),   # largest grid psi error
}

# The EMC is deterministic (Newton to ~1e-13) and the recorded FEM values carry 5-6
# digits, so the measured errors reproduce to ~0.01 pp; 0.3 pp catches any change of the
# network that moves an error by more (e.g. a 1 % change of a leakage permeance moves the
# low-current psi by ~0.3-0.5 pp), in either direction.
MARGIN = 0.3


def _quiet_build(**magnet: object) -> mk.Magnet:
    with warnings.catch_warnings():          # the added keys carry no provenance entry
        warnings.simplefilter("ignore", mk.ProvenanceWarning)
        return build_u(magnet=dict(magnet))


@pytest.fixture(scope="module")
def grid() -> mk.Magnet:
    return _quiet_build(discretisation="grid")


@pytest.fixture(scope="module")
def lumped() -> mk.Magnet:
    return build_u()


def _solve(mag: mk.Magnet, s: float, current: float) -> tuple[float, float]:
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=current)
    return float(np.ravel(sol.force_N)[0]), float(np.ravel(sol.flux_linkage_Wb)[0])


@pytest.mark.parametrize("point", sorted(RECORDED))
def test_grid_network_against_recorded_fem(grid: mk.Magnet, lumped: mk.Magnet,
                                           point: tuple[int, int]) -> None:
    s, current = point[0] * 1e-3, float(point[1])
    f_fem, psi_fem, ef, ep, ef_l, ep_l = RECORDED[point]
    force, psi = _solve(grid, s, current)
    assert 100 * (force / f_fem - 1) == pytest.approx(ef, abs=MARGIN)
    assert 100 * (psi / psi_fem - 1) == pytest.approx(ep, abs=MARGIN)
    force_l, psi_l = _solve(lumped, s, current)
    assert 100 * (force_l / f_fem - 1) == pytest.approx(ef_l, abs=MARGIN)
    assert 100 * (psi_l / psi_fem - 1) == pytest.approx(ep_l, abs=MARGIN)


def test_grid_network_is_better_at_the_knee_and_in_saturation(grid: mk.Magnet,
                                                              lumped: mk.Magnet) -> None:
    """Where the lumped network is worst (knee, saturation) the grid's error is at most
    half of it in force and at most 0.8 times in flux linkage (measured ratios: force
    0.10 ... 0.42, psi 0.37 ... 0.71 at the five points of 20-80 A below 20 mm here)."""
    for point in ((4, 20), (8, 40), (12, 40), (4, 80)):
        s, current = point[0] * 1e-3, float(point[1])
        f_fem, psi_fem = RECORDED[point][:2]
        fg, pg = _solve(grid, s, current)
        fl, pl = _solve(lumped, s, current)
        assert abs(fg / f_fem - 1) <= 0.5 * abs(fl / f_fem - 1)
        assert abs(pg / psi_fem - 1) <= 0.8 * abs(pl / psi_fem - 1)


def test_coil_air_against_recorded_fem() -> None:
    """``coil_air``: psi in deep saturation closer to the FEM, force higher (measured:
    4 mm / 80 A  F +2.52 %, psi -1.69 %; 20 mm / 80 A  F +5.88 %, psi -4.27 %; 8 mm / 5 A
    unchanged from grid: F -0.45 %, psi +0.25 %); windows as above."""
    mag = _quiet_build(discretisation="grid", coil_air=True)
    for point, ef, ep in (((4, 80), 2.52, -1.69), ((20, 80), 5.88, -4.27)):
        f_fem, psi_fem = RECORDED[point][:2]
        force, psi = _solve(mag, point[0] * 1e-3, float(point[1]))
        assert 100 * (force / f_fem - 1) == pytest.approx(ef, abs=MARGIN)
        assert 100 * (psi / psi_fem - 1) == pytest.approx(ep, abs=MARGIN)


def test_coil_air_carries_no_flux_with_unsaturated_iron() -> None:
    """The coil-air path and its leg link form a loop without MMF, so its flux is
    G x (the link's iron drop): with linear iron of mu_r = 1e9 every coil-air branch
    carries ~1e-9 of the pole flux (measured < 1e-9; bound 1e-6)."""
    params = u_params()
    params["magnet"].update(material="stiff", discretisation="grid", coil_air=True)
    params["rail"]["material"] = "stiff"
    _, net = build_u_magnet(params, {"stiff": ConstantPermeability(1e9)},
                            mk.ModelOptions(eddy_currents=False))
    sol = mk.solve_statics(net, gaps_m=0.008, currents_A=20.0)
    flux = dict(zip(net.branch_names, np.ravel(sol.branch_flux_Wb), strict=True))
    air = [abs(v) for k, v in flux.items() if k.startswith("coil_air_")]
    pole = abs(sum(v for k, v in flux.items() if k.startswith("gap_left_")))
    assert len(air) == 2 * 2 * 6 and max(air) < 1e-6 * pole     # 6 links touch the coil


# ------------------------------------------------------------------ physics of the network


def test_fringe_permeance_closed_form() -> None:
    """G = mu0 w int_0^r dx / (s + pi x/2) (Roters: quarter circle + straight line), by
    quadrature, and the same as the fringe term of AirGap."""
    w, r = 0.1, 0.01
    for s in (0.002, 0.01, 0.03):
        el = FringePermeance("f", gap_input="g", width_m=w, radius_m=r)
        ref = MU0 * w * quad(lambda x, s=s: 1.0 / (s + math.pi * x / 2.0), 0.0, r)[0]
        assert el.permeance(s) == pytest.approx(ref, rel=1e-12)
        with_edge = AirGap("a", gap_input="g", pole_area_m2=3e-3, fringe_edges=((w, r),))
        bare = AirGap("b", gap_input="g", pole_area_m2=3e-3)
        assert el.permeance(s) == pytest.approx(with_edge.permeance(s) - bare.permeance(s),
                                                rel=1e-12)
        assert el.gap == "g"


@pytest.mark.parametrize("kwargs", [dict(width_m=0.0), dict(radius_m=-1e-3), dict(gap_input="")])
def test_fringe_permeance_bad_input(kwargs: dict) -> None:
    with pytest.raises(ParameterError):
        FringePermeance("f", **{"gap_input": "g", "width_m": 0.1, "radius_m": 0.01, **kwargs})
    with pytest.raises(ParameterError, match="needs a gap"):
        FringePermeance("f", gap_input="g", width_m=0.1, radius_m=0.01).permeance(None)


def test_grid_network_textbook_limit() -> None:
    """Nearly ideal iron (mu_r = 1e9), no leakage, no fringing: the parallel gap tubes
    under the pole add up to L = mu0 n^2 A/(2 s) and F = mu0 (n I)^2 A/(4 s^2).  The iron
    adds ~0.4 m / 1e9 to the 2 s of air: < 1e-7 relative (bound 1e-6)."""
    params = u_params()
    params["magnet"].update(material="stiff", discretisation="grid")
    params["rail"]["material"] = "stiff"
    _, net = build_u_magnet(params, {"stiff": ConstantPermeability(1e9)},
                            mk.ModelOptions(leakage=False, fringing=False, eddy_currents=False))
    n, area = 600.0, 0.03 * 0.1
    for s, current in ((0.004, 10.0), (0.015, 30.0)):
        sol = mk.solve_statics(net, gaps_m=s, currents_A=current)
        assert float(sol.flux_linkage_Wb[0]) / current == pytest.approx(
            MU0 * n**2 * area / (2 * s), rel=1e-6)
        assert float(sol.force_N) == pytest.approx(MU0 * (n * current) ** 2 * area / (4 * s**2),
                                                   rel=1e-6)


def test_grid_network_refuses_the_rail_split() -> None:
    # the grid has the ladder on its cell links (tests/test_eddy_grid.py); the lumped
    # network's rail split does not apply to it (its cells resolve the rail's flux)
    with pytest.raises(ParameterFileError, match="does not apply"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", mk.ProvenanceWarning)
            build_u(magnet={"discretisation": "grid"}, eddy_currents=True,
                    eddy_model="ladder_split")


def test_grid_network_refuses_ideal_iron() -> None:
    with pytest.raises(ParameterFileError, match="finite permeability"):
        _quiet_build(discretisation="grid", material="ideal")


@pytest.mark.parametrize(("s", "current"), [(0.004, 80.0)])     # deep saturation (2.6 T)
def test_grid_force_is_coenergy_derivative(grid: mk.Magnet, s: float, current: float) -> None:
    """F = -dW'/ds at constant current, W' = I psi - W with W from the element energies.

    Central difference, h = 1e-6 m: truncation ~(h/s)^2 ~ 1e-8, rounding ~1e-10; measured
    below 1e-8 on the lumped network (tests/test_statics.py); bound 5e-8."""
    h = 1e-6
    wp = mk.coenergy(grid, gaps_m=s + h, currents_A=current)
    wm = mk.coenergy(grid, gaps_m=s - h, currents_A=current)
    force, _ = _solve(grid, s, current)
    assert force == pytest.approx(-(wp - wm) / (2 * h), rel=5e-8)


@pytest.mark.parametrize(("s", "current"), [(0.008, 40.0), (0.004, 80.0)])
def test_grid_reciprocity(grid: mk.Magnet, s: float, current: float) -> None:
    """dF/dI = -dpsi/ds (Maxwell relation of W'): each exact (implicit-function) derivative
    against a central difference of the other quantity (steps 1e-7 m, 1e-4 A: truncation
    and rounding < 1e-7 relative; bound 1e-6)."""
    sol = mk.solve_statics(grid, gaps_m=s, currents_A=current)
    hs, hi = 1e-7, 1e-4
    _, psi_p = _solve(grid, s + hs, current)
    _, psi_m = _solve(grid, s - hs, current)
    f_p, _ = _solve(grid, s, current + hi)
    f_m, _ = _solve(grid, s, current - hi)
    dpsi_ds = (psi_p - psi_m) / (2 * hs)
    df_di = (f_p - f_m) / (2 * hi)
    # both poles' gaps move together here: sum the per-pole derivatives
    assert float(np.sum(sol.dforce_dcurrent_N_per_A)) == pytest.approx(-dpsi_ds, rel=1e-6)
    assert float(np.sum(sol.dpsi_dgap_Wb_per_m)) == pytest.approx(-df_di, rel=1e-6)


def test_grid_pole_flux_is_flux_linkage_per_pole_turn(grid: mk.Magnet,
                                                      lumped: mk.Magnet) -> None:
    """eta (paper eq. 5) = sum of the two pole fluxes = psi / (n/2) for both networks: the
    grid's parallel column coils give ``pole_turns = n/2``, so the turns of the columns
    (3x the winding's) do not divide the pole flux by 3."""
    for mag in (grid, lumped):
        sol = mk.solve_statics(mag, gaps_m=0.008, currents_A=40.0)
        eta = mag.network.pole_flux_matrix.T @ np.ravel(sol.branch_flux_Wb)
        assert float(eta[0]) == pytest.approx(float(sol.flux_linkage_Wb[0]) / 300.0, rel=1e-12)
    turns = sum(c.turns for c in grid.network.circuits[0].coils)
    assert turns == pytest.approx(3 * 600.0, rel=1e-12)     # 3 columns per leg


def test_coil_pole_turns_bad_input() -> None:
    with pytest.raises(ParameterError, match="pole name"):
        Coil("b", 10.0, pole_turns=5.0)
    with pytest.raises(ParameterError, match="pole_turns"):
        Coil("b", 10.0, pole="p", pole_turns=0.0)


def test_grid_eddy_elements_dissipate_as_the_lumped_part() -> None:
    """Each leg link's eddy element is scaled so that a uniform dB/dt in the leg
    dissipates what the lumped leg element does per length: sum_b G_b A_b^2 / l_b over the
    parallel links of one row = G A^2 / l of the whole leg (exact)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mk.ProvenanceWarning)
        g = build_u(magnet={"discretisation": "grid"}, eddy_currents=True).network
        lum = build_u(eddy_currents=True).network
    seg = lum.branch("leg_left_2")
    g_l = next(e for e in seg.elements if e.eddy_conductance > 0)
    iron_l = next(e for e in seg.elements if e.area is not None)
    ref = g_l.eddy_conductance * iron_l.area**2 / iron_l.length_m
    row = [b for b in g.branches if b.name.startswith("frame_v_") and b.name.endswith("_3")
           and any(e.eddy_conductance > 0 for e in b.elements)]
    left = [b for b in row if int(b.name.split("_")[2]) < 3]
    assert len(left) == 3
    total = 0.0
    for b in left:
        ec = next(e for e in b.elements if e.eddy_conductance > 0)
        iron = next(e for e in b.elements if e.area is not None)
        total += ec.eddy_conductance * iron.area**2 / iron.length_m
    assert total == pytest.approx(ref, rel=1e-12)


@pytest.mark.parametrize(("key", "value", "match"), [
    ("discretisation", "fine", "expected one of 'lumped', 'grid'"),
    ("grid_columns", 13, "at most 12"),
    ("grid_columns", 0, "grid_columns"),
])
def test_grid_options_bad_input(key: str, value: object, match: str) -> None:
    with pytest.raises(ParameterFileError, match=match):
        _quiet_build(**{"discretisation": "grid", key: value})


@pytest.mark.parametrize(("disc", "key", "value"), [("grid", "coil_segments", 5),
                                                    ("lumped", "grid_columns", 3),
                                                    ("lumped", "coil_air", True)])
def test_keys_of_the_other_network_are_refused(disc: str, key: str, value: object) -> None:
    """A key that the chosen network would ignore is an error, not silently dropped."""
    with pytest.raises(ParameterFileError, match=f"{key} does not apply"):
        _quiet_build(**{"discretisation": disc, key: value})


@pytest.mark.slow
def test_grid_network_builds_maps_and_flux_model(grid: mk.Magnet) -> None:
    """The reduction and the dynamic model take the grid network (maps ~20 s, FluxModel
    with its 132 eddy elements ~30 s to build: slow)."""
    maps = mk.build_maps(grid, gaps_m=np.linspace(0.004, 0.02, 4),
                         currents_A=np.linspace(0.0, 80.0, 4), progress=False)
    force, psi = _solve(grid, 0.004 + 2 * 0.016 / 3, 80.0 / 3)
    f_map = maps.variable("force_N", "coil")
    assert np.isfinite(f_map).all()
    assert float(f_map[2, 1]) == pytest.approx(force, rel=1e-9)
    assert float(maps.variable("flux_linkage_Wb", "coil")[2, 1]) == pytest.approx(psi, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mk.ProvenanceWarning)
        model = mk.FluxModel(build_u(magnet={"discretisation": "grid"}, eddy_currents=True))
    assert len(model.eddy_branch_names) == 132     # legs 2 x 3 x 9 vertical, yoke 3 x 11, rail 3 x 15
