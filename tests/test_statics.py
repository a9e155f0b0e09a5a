"""Statics of the equivalent magnetic circuit: closed-form limits, exactness, saturation."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import maglevkit as mk
from maglevkit.circuit import assemble
from maglevkit.materials import MU0

from .conftest import build_u

N_TURNS, AREA = 600.0, 0.030 * 0.100  # bundled U-magnet: turns, pole face [m^2]


@pytest.mark.parametrize("s", [0.004, 0.01, 0.02])
@pytest.mark.parametrize("current", [0.5, 20.0, 300.0])
def test_ideal_iron_matches_textbook(s: float, current: float) -> None:
    """mu -> inf, no leakage/fringing: F = mu0 (nI)^2 A/(4 s^2), L = mu0 n^2 A/(2 s)."""
    mag = build_u(material="ideal", fringing=False, leakage=False)
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=current)
    f_exact = MU0 * (N_TURNS * current) ** 2 * AREA / (4 * s * s)
    l_exact = MU0 * N_TURNS**2 * AREA / (2 * s)
    # a linear 2-loop solve in double precision: agreement to ~1e-15; 1e-9 is the brief's bound
    assert sol.force_N == pytest.approx(f_exact, rel=1e-9)
    assert sol.differential_inductance_H[0, 0] == pytest.approx(l_exact, rel=1e-9)
    assert sol.flux_linkage_Wb[0] == pytest.approx(l_exact * current, rel=1e-9)
    assert sol.apparent_inductance_H[0] == pytest.approx(l_exact, rel=1e-9)
    # each pole carries half the force, and the paper's eq. 6 (mu_r -> inf) gives the same
    np.testing.assert_allclose(sol.pole_force_N, f_exact / 2, rtol=1e-9)
    gap_flux = sol.branch_flux("gap_left")
    assert mk.pole_force_eq6(gap_flux, AREA) == pytest.approx(f_exact / 2, rel=1e-9)


def test_constant_mu_iron_is_series_reluctances() -> None:
    mu = 700.0
    mag = build_u(material="ideal", fringing=False, leakage=False)
    net = mag.network
    lin = mk.ConstantPermeability(mu)
    branches = tuple(
        replace(b, elements=tuple(replace(e, material=lin) if isinstance(e, mk.IronPath) else e
                                  for e in b.elements))
        for b in net.branches
    )
    net = mk.Network(branches, net.circuits)
    s, current = 0.008, 30.0
    r_total = 2 * s / (MU0 * AREA)
    for b in net.branches:
        for e in b.elements:
            if isinstance(e, mk.IronPath):
                r_total += e.length_m / (MU0 * mu * e.cross_section_m2)
    sol = mk.solve_statics(net, gaps_m=s, currents_A=current)
    assert sol.differential_inductance_H[0, 0] == pytest.approx(N_TURNS**2 / r_total, rel=1e-12)
    phi = N_TURNS * current / r_total
    assert sol.force_N == pytest.approx(2 * phi**2 / (2 * MU0 * AREA), rel=1e-12)
    # eq. 6 with finite mu_r differs from the co-energy force by the factor (mu_r - 1)/mu_r
    eq6 = 2 * mk.pole_force_eq6(phi, AREA, mu_r=mu)
    assert eq6 / sol.force_N == pytest.approx((mu - 1) / mu, rel=1e-12)


def _kirchhoff_residuals(mag: mk.Magnet, sol: mk.StaticSolution) -> tuple[float, float]:
    net = mag.network
    eq = assemble(net)
    node = float(np.max(np.abs(net.incidence_matrix @ sol.branch_flux_Wb)))
    r = ca.Function("r", [eq.x, eq.s, eq.I], [eq.residual])
    loop = float(np.max(np.abs(np.asarray(r(sol.loop_flux_Wb, sol.gaps_m, sol.currents_A)))))
    return node, loop


def _series_loop(s: float) -> tuple[mk.Magnet, list[tuple[float, float]], float, float]:
    """The U-magnet without leakage: one series loop (legs, yoke, rail, two gaps).

    Returns the magnet, (length, area) of every iron part, the permeance of one gap
    (with fringing) and the total turns, read from the network's elements."""
    mag = build_u(leakage=False)
    net = mag.network
    assert net.n_loops == 1
    iron = [(e.length_m, e.cross_section_m2) for b in net.branches for e in b.elements
            if isinstance(e, mk.IronPath)]
    gaps = [e for b in net.branches for e in b.elements if isinstance(e, mk.AirGap)]
    assert len(gaps) == 2 and gaps[0].permeance(s) == gaps[1].permeance(s)
    turns = sum(c.turns * c.polarity for c in net.circuits[0].coils) / 2   # each leg: n/2
    return mag, iron, float(gaps[0].permeance(s)), float(turns)


def _loop_flux(iron: list, g: float, theta: float, material: mk.Material) -> float:
    """Scalar root of  sum_k l_k H(phi/A_k) + 2 phi/G = theta  (Brent's method, no Newton,
    no loop matrix, no CasADi): the independent solution of the series loop."""
    from scipy.optimize import brentq

    def mmf(phi: float) -> float:
        return sum(length * float(material.field_strength(phi / area))
                   for length, area in iron) + 2.0 * phi / g - theta

    upper = theta * g / 2.0                      # the flux without any iron drop
    return float(brentq(mmf, 0.0, upper, xtol=1e-300, rtol=1e-15, maxiter=500))


@pytest.mark.parametrize(("s", "current"), [(0.010, 30.0), (0.005, 80.0)])
def test_single_saturable_loop_against_a_scalar_root_solve(s: float, current: float) -> None:
    """Independent second method for the saturable statics (replaces a check that only
    re-evaluated the solver's own residual): the leakage-free U-magnet is one series
    loop, so the flux solves one scalar equation (Brent's bracketing method on the
    element laws).  Flux, flux linkage, L~ = dpsi/dI and the co-energy force
    F = -d/ds int_0^I psi(i) di (Gauss-Legendre quadrature of the scalar solutions,
    central difference in s) are compared with the package's Newton solution and its
    exact (implicit-function) derivatives.  At 5 mm / 80 A the legs carry > 2 T.

    Tolerances (bound ~10x the measured error and the error estimate): both solutions
    are converged to ~1e-15 (Brent rtol 1e-15): flux measured 2e-16, bound 1e-14.  L~ by a
    central difference at h = 1e-4 I: truncation (h/I)^2/6 x (curvature of psi(I)) ~ 5e-9,
    measured 3e-9 (30 A) and 4.5e-9 (80 A), bound 5e-8.  Force: the 80-point quadrature
    of psi(i) through the knee is exact to ~1e-12 (40 points: 4e-7 at 80 A), the central
    difference at h = 1e-6 s has rounding ~eps W'/(h F) ~ 1e-10: measured 1.0e-10 and
    1.6e-10, bound 2e-9.  A 5 % error in any element law, the loop assembly or the force
    is 1e7x above these bounds."""
    steel = mk.get_material("AISI 1008")
    mag, iron, g, n_leg = _series_loop(s)
    n = 2.0 * n_leg                                   # 600 turns around the loop
    sol = mk.solve_statics(mag, gaps_m=s, currents_A=current)
    phi = _loop_flux(iron, g, n * current, steel)
    assert np.allclose(np.abs(sol.branch_flux_Wb), phi, rtol=1e-14, atol=0.0)
    assert float(sol.flux_linkage_Wb[0]) == pytest.approx(n * phi, rel=1e-14)
    if current == 80.0:
        assert float(np.nanmax(np.abs(sol.branch_flux_density_T))) > 2.0   # deep saturation
    h = 1e-4 * current
    l_fd = n * (_loop_flux(iron, g, n * (current + h), steel)
                - _loop_flux(iron, g, n * (current - h), steel)) / (2 * h)
    assert float(sol.differential_inductance_H[0, 0]) == pytest.approx(l_fd, rel=5e-8)

    x, w = np.polynomial.legendre.leggauss(80)
    nodes, weights = 0.5 * current * (x + 1.0), 0.5 * current * w

    def coenergy_by_quadrature(gap: float) -> float:
        _, iron_g, g_g, _ = _series_loop(gap)
        return float(sum(wk * n * _loop_flux(iron_g, g_g, n * ik, steel)
                         for ik, wk in zip(nodes, weights, strict=True)))

    hs = 1e-6 * s
    f_fd = -(coenergy_by_quadrature(s + hs) - coenergy_by_quadrature(s - hs)) / (2 * hs)
    assert float(sol.force_N) == pytest.approx(f_fd, rel=2e-9)


@pytest.mark.parametrize(("gaps", "current"), [((0.006, 0.012), 25.0), ((0.004, 0.005), 80.0)])
def test_force_gap_derivative_against_finite_differences(u_magnet: mk.Magnet, gaps: tuple,
                                                         current: float) -> None:
    """dF_k/ds_l at constant current (implicit function theorem) against central
    differences of the solved pole forces, one gap at a time, uneven gaps, into deep
    saturation.  h = 1e-7 m: truncation ~(h/s)^2 ~ 1e-9, rounding ~1e-16 F/(h dF/ds)
    ~ 1e-10 (Newton converges to ~1e-15); measured 1.1e-10 and 1.3e-10 of max |dF/ds|;
    bound 2e-9.  The cross terms (21 % and 9 % of the diagonal, measured) are checked too."""
    sol = mk.solve_statics(u_magnet, gaps_m=list(gaps), currents_A=current)
    h = 1e-7
    fd = np.empty((2, 2))
    for col in range(2):
        plus, minus = np.array(gaps, dtype=float), np.array(gaps, dtype=float)
        plus[col] += h
        minus[col] -= h
        two = mk.solve_statics(u_magnet, gaps_m=np.stack([plus, minus]), currents_A=current)
        fd[:, col] = (two.pole_force_N[0] - two.pole_force_N[1]) / (2 * h)
    exact = sol.dforce_dgap_N_per_m
    assert np.max(np.abs(exact - fd)) < 2e-9 * np.max(np.abs(fd))
    # the cross term is real (flux redistributes between the poles), not a zero both agree on
    assert abs(fd[0, 1]) > 0.05 * abs(fd[0, 0])


@pytest.mark.parametrize(("s", "current"), [(0.01, 20.0), (0.004, 80.0), (0.006, 200.0),
                                             (0.02, 5.0)])
def test_coenergy_force_matches_finite_difference_of_coenergy(u_magnet: mk.Magnet, s: float,
                                                              current: float) -> None:
    """F = -dW'/ds at constant current; W' = I psi - W with W integrated from the B-H law.

    Central difference with h = 1e-6 m: truncation ~ (h/s)^2 ~ 1e-8, rounding
    ~ eps W'/(h F) ~ 1e-10 (the W integral of the B-H law ~1e-13): measured 1.3e-9 ...
    4.7e-9 (deep saturation included); bound 5e-8.
    """
    h = 1e-6
    wp = mk.coenergy(u_magnet, gaps_m=s + h, currents_A=current)
    wm = mk.coenergy(u_magnet, gaps_m=s - h, currents_A=current)
    sol = mk.solve_statics(u_magnet, gaps_m=s, currents_A=current)
    assert sol.force_N == pytest.approx(-(wp - wm) / (2 * h), rel=5e-8)


@pytest.mark.parametrize(("s", "current"), [(0.01, 20.0), (0.004, 80.0), (0.006, 200.0)])
def test_reciprocity_and_inductance_against_finite_differences(u_magnet: mk.Magnet, s: float,
                                                               current: float) -> None:
    """dF/dI = -dpsi/ds (both signs from F = -dW'/ds, psi = dW'/dI).

    Each exact (implicit-function) derivative is compared with a central difference of
    the *other* quantity; steps 1e-7 m and 1e-4 A give truncation and rounding errors
    below 1e-7 relative, so 1e-6 is the bound.
    """
    sol = mk.solve_statics(u_magnet, gaps_m=s, currents_A=current)
    hs, hi = 1e-7, 1e-4
    psi_s = mk.solve_statics(u_magnet, gaps_m=[[s + hs] * 2, [s - hs] * 2],
                             currents_A=current).flux_linkage_Wb
    f_i = mk.solve_statics(u_magnet, gaps_m=s, currents_A=[[current + hi], [current - hi]]).force_N
    psi_i = mk.solve_statics(u_magnet, gaps_m=s,
                             currents_A=[[current + hi], [current - hi]]).flux_linkage_Wb
    dpsi_ds_fd = (psi_s[0, 0] - psi_s[1, 0]) / (2 * hs)
    df_di_fd = (f_i[0] - f_i[1]) / (2 * hi)
    df_di = sol.dforce_dcurrent_N_per_A.sum(axis=0)[0]
    dpsi_ds = sol.dpsi_dgap_Wb_per_m.sum(axis=-1)[0]
    assert df_di == pytest.approx(-dpsi_ds_fd, rel=1e-6)
    assert dpsi_ds == pytest.approx(-df_di_fd, rel=1e-6)
    assert sol.differential_inductance_H[0, 0] == pytest.approx(
        (psi_i[0, 0] - psi_i[1, 0]) / (2 * hi), rel=1e-6)


def test_saturation_gives_a_knee_and_linear_iron_stays_quadratic(u_magnet: mk.Magnet) -> None:
    currents = np.array([1.0, 2.0, 20.0, 40.0, 80.0])
    sat = mk.solve_statics(u_magnet, gaps_m=[0.01], currents_A=currents, grid=True).force_N[0]
    lin_mag = build_u(saturation=False)
    lin = mk.solve_statics(lin_mag, gaps_m=[0.01], currents_A=currents, grid=True).force_N[0]
    # linear network: F proportional to I^2 to rounding
    np.testing.assert_allclose(lin / currents**2, lin[0] / currents[0] ** 2, rtol=1e-10)
    # saturable iron: near-quadratic at low current (the Roschke mu_r rises slightly from
    # mu_i, so F(2I)/F(I) is a little above 4) ...
    assert 3.9 < sat[1] / sat[0] < 4.6
    # ... and a knee: doubling 40 -> 80 A gains far less than the quadratic factor 4
    assert sat[4] / sat[3] < 1.6
    # F/I^2 falls by more than half from low current to deep saturation
    assert (sat[4] / 80.0**2) < 0.5 * (sat[1] / 2.0**2)


def _max_mu_network(net: mk.Network) -> mk.Network:
    """Replace each saturable material by a constant mu_r = its maximum mu_r(B)."""
    b = np.linspace(1e-6, 3.0, 30001)
    out = []
    for br in net.branches:
        els = []
        for e in br.elements:
            if isinstance(e, mk.IronPath):
                mu_max = float(np.max(e.material.relative_permeability(b)))
                e = replace(e, material=mk.ConstantPermeability(mu_max))
            els.append(e)
        out.append(replace(br, elements=tuple(els)))
    return mk.Network(tuple(out), net.circuits)


@settings(max_examples=25, deadline=None)
@given(
    pole_width=st.floats(0.01, 0.06), window=st.floats(0.03, 0.12), depth=st.floats(0.05, 0.3),
    yoke=st.floats(0.01, 0.05), rail=st.floats(0.01, 0.05), s=st.floats(0.002, 0.03),
    current=st.floats(0.1, 200.0), material=st.sampled_from(["AISI 1008", "RFe80", "M350-50A"]),
)
def test_saturated_force_never_exceeds_unsaturated(pole_width: float, window: float, depth: float,
                                                   yoke: float, rail: float, s: float,
                                                   current: float, material: str) -> None:
    """Saturable iron has mu(B) <= mu_max, so its force is bounded by the linear model at
    mu_max and by ideal iron; both bounds hold at every operating point (1e-9 slack for
    rounding of the iterative solve)."""
    geo = {"pole_width": pole_width, "window_width": window, "depth": depth,
           "yoke_thickness": yoke, "coil_thickness": 0.2 * window}
    mag = build_u(material=material, magnet=geo,
                  rail={"thickness": rail, "width": window + 2 * pole_width + 0.02})
    sat = mk.solve_statics(mag, gaps_m=s, currents_A=current)
    node, loop = _kirchhoff_residuals(mag, sat)
    assert loop <= 1e-9 * N_TURNS * current
    f_max_mu = mk.solve_statics(_max_mu_network(mag.network), gaps_m=s, currents_A=current).force_N
    ideal = build_u(material="ideal", magnet=geo,
                    rail={"thickness": rail, "width": window + 2 * pole_width + 0.02})
    f_ideal = mk.solve_statics(ideal, gaps_m=s, currents_A=current).force_N
    assert sat.force_N <= f_max_mu * (1 + 1e-9)
    assert f_max_mu <= f_ideal * (1 + 1e-9)


def test_grid_and_batches_are_consistent(u_magnet: mk.Magnet) -> None:
    gaps = np.array([0.005, 0.012])
    currents = np.array([0.0, 15.0, 60.0])
    grid = mk.solve_statics(u_magnet, gaps_m=gaps, currents_A=currents, grid=True)
    assert grid.force_N.shape == (2, 3)
    assert grid.differential_inductance_H.shape == (2, 3, 1, 1)
    assert grid.dpsi_dgap_Wb_per_m.shape == (2, 3, 1, 2)
    for i, s in enumerate(gaps):
        for j, c in enumerate(currents):
            one = mk.solve_statics(u_magnet, gaps_m={"left": s, "right": s}, currents_A={"coil": c})
            # same computation, different batching: identical to rounding
            assert one.force_N == pytest.approx(grid.force_N[i, j], rel=1e-12, abs=1e-12)
            np.testing.assert_allclose(one.branch_flux_Wb, grid.branch_flux_Wb[i, j], rtol=1e-12,
                                       atol=1e-18)
    assert np.all(grid.force_N[:, 0] == 0.0)


def test_continuation_fallback_reaches_the_same_solution(u_magnet: mk.Magnet) -> None:
    from maglevkit.models.statics import _solver

    solver = _solver(u_magnet.network)
    s, current = np.array([0.004, 0.004]), np.array([250.0])
    x_cont = solver._continuation(s, current)
    direct = mk.solve_statics(u_magnet, gaps_m=s, currents_A=current)
    np.testing.assert_allclose(x_cont, direct.loop_flux_Wb, rtol=1e-9)


def test_uneven_gaps_move_force_to_the_smaller_gap(u_magnet: mk.Magnet) -> None:
    sol = mk.solve_statics(u_magnet, gaps_m={"left": 0.006, "right": 0.012}, currents_A=25.0)
    assert sol.pole_force_N[0] > sol.pole_force_N[1] > 0.0
