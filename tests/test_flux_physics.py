"""Energy balance, steady state vs statics, differential inductance (paper Fig. 7)."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import SolverError
from maglevkit.models.signals import Ramp, Sine, Step


def test_energy_balance_moving_gap_saturation_eddy(u_magnet: mk.Magnet) -> None:
    """E_in = E_ohm + E_eddy + Delta W + E_mech over a saturating transient, gap moving."""
    res = mk.simulate(u_magnet, (0.0, 0.15), dt_s=2e-4,
                      gaps_m={"left": Sine(0.010, 0.002, 15.0), "right": Sine(0.011, -0.0015, 7.0)},
                      voltages_V=Step(20.0, 90.0, 0.01), initial_currents_A=10.0)
    assert res.currents_A.max() > 35.0          # into saturation (dpsi/dI falls 3x at 40 A)
    eb = res.energy_balance()
    assert eb.eddy_J > 0.0 and abs(eb.mechanical_J) > 1e-3 * eb.electrical_J
    # The balance is an identity of the continuous model; numerically it is limited by
    # the quadrature/state error (rtol 1e-6): measured 1.7e-5.  Required: 1e-4 (the issue).
    assert eb.relative_residual < 1e-4
    # the cumulative series are monotone where they must be
    assert np.all(np.diff(res.ohmic_loss_J) >= 0) and np.all(np.diff(res.eddy_loss_J) >= 0)


def test_energy_balance_moving_gap_radau(u_magnet: mk.Magnet) -> None:
    res = mk.simulate(u_magnet, (0.0, 0.05), dt_s=2e-4, gaps_m=Sine(0.010, 0.002, 20.0),
                      voltages_V=60.0, initial_currents_A=10.0, method="radau")
    # fixed-step Radau IIA(5) at 0.2 ms: local errors ~1e-9, balance well within 1e-4
    assert res.energy_balance().relative_residual < 1e-4


@pytest.mark.parametrize("eddy", [True, False])
def test_steady_state_reproduces_statics(u_magnet: mk.Magnet, eddy: bool) -> None:
    fm = mk.FluxModel(u_magnet, eddy_currents=eddy)
    gaps, i1 = [0.009, 0.012], 37.0
    st = fm.initial_state(gaps_m=gaps, currents_A=12.0)
    # 2 s is ~13 slowest time constants (L~/R (1 + R/R_ec) <= 0.15 s here): e^-13 ~ 2e-6
    res = mk.simulate(fm, (0.0, 2.0), dt_s=5e-3, gaps_m=gaps,
                      voltages_V=fm.resistances * i1, initial_state=st)
    # the transient has died out: the current reached U/R and stopped moving (the last
    # 0.2 s change it by < 1e-7 relative; the remaining e^-13 transient and the IDAS
    # error (~1e-5 at rtol 1e-6) bound the first check)
    assert res.currents_A[-1, 0] == pytest.approx(i1, rel=1e-4)
    assert abs(res.currents_A[-1, 0] - res.currents_A[-41, 0]) < 1e-7 * i1
    # Same currents -> same fluxes and forces: statics at the simulation's own final
    # current (an independent Newton solve of the static network).  At rest the DAE's
    # algebraic part is exactly the static network (eddy MMFs G phi' ~ 1e-11 A vs
    # n I ~ 2e4 A), so only the algebraic solve tolerances remain: measured 2e-15
    # relative; 1e-8 is 100x below rtol and would catch any force/flux inconsistency.
    sol = mk.solve_statics(u_magnet, gaps_m=gaps, currents_A=res.currents_A[-1])
    np.testing.assert_allclose(res.branch_flux_Wb[-1], sol.branch_flux_Wb, rtol=1e-8,
                               atol=1e-8 * np.abs(sol.branch_flux_Wb).max())
    np.testing.assert_allclose(res.pole_force_N[-1], sol.pole_force_N, rtol=1e-8)
    np.testing.assert_allclose(res.flux_linkage_Wb[-1], sol.flux_linkage_Wb, rtol=1e-8)
    # eddy MMFs vanish at rest (scale n I = 2.2e4 A; measured 2e-11 A)
    np.testing.assert_allclose(res.eddy_mmf_A[-1], 0.0, atol=1e-9 * 600 * i1)


def test_energy_balance_large_gap_motion(u_magnet: mk.Magnet) -> None:
    """Gaps closing 14 -> 6 mm: mechanical work is a sizeable term, bound relative to it.

    At the default rtol = 1e-6 the energy quadratures are not error-controlled (IDAS
    ``quad_err_con`` is off; turning it on costs 2.4x run time) and the mechanical term is
    only ~3e-4 accurate on this run (measured residual 3.1e-4 E_mech), which the issue's
    1e-4-of-the-largest-term criterion cannot see.  So this test uses rtol = 1e-9.
    """
    res = mk.simulate(u_magnet, (0.0, 0.12), dt_s=2e-4,
                      gaps_m={"left": Ramp(0.014, 0.006, 0.01, 0.09),
                            "right": Ramp(0.013, 0.007, 0.01, 0.09)},
                      voltages_V=40.0, initial_currents_A=20.0, rtol=1e-9, atol=1e-11)
    eb = res.energy_balance()
    assert eb.mechanical_J > 0.1 * eb.electrical_J > 0.0     # closing gaps: magnet does work
    # Residual relative to the mechanical work: measured 1.1e-6, bound 2e-5.  The magnetic
    # energy is recomputed from the branch fluxes and gaps (statics.magnetic_energy), so a
    # pole-force error of 2e-5 relative would show here: forces, fluxes and currents are
    # mutually consistent far beyond the 1 % an input-energy-relative bound allowed.
    assert abs(eb.residual_J) < 2e-5 * eb.mechanical_J
    assert eb.relative_residual < 1e-5                      # measured 1.2e-7
    # A second method for the mechanical work: trapezoidal -sum F ds of the sampled pole
    # forces and gaps vs the integrator's quadrature.  Trapezoid error O(h^2) with 400
    # intervals over the ramp: measured 3.2e-7; bound 1e-5.
    ds = np.diff(res.gaps_m, axis=0)
    f_mid = 0.5 * (res.pole_force_N[1:] + res.pole_force_N[:-1])
    w_trap = float(-(f_mid * ds).sum())
    assert w_trap == pytest.approx(eb.mechanical_J, rel=1e-5)


def test_solver_failure_mid_run_reports_time_state_reason() -> None:
    """A 1e12 V step at 5 ms: IDAS fails there; the error names time, state and reason."""
    fm = mk.FluxModel(mk.load_magnet("u-magnet"))
    with pytest.raises(SolverError) as info:
        mk.simulate(fm, (0.0, 0.01), dt_s=1e-3, gaps_m=0.01, voltages_V=Step(20.0, 1e12, 0.005))
    err = info.value
    assert err.time_s == pytest.approx(0.005, abs=1e-12)     # start of the failing interval
    np.testing.assert_allclose(err.state["voltages_V"], [1e12])
    np.testing.assert_allclose(err.state["gaps_m"], [0.01, 0.01])
    # the state is the one at 5 ms (steady state of 20 V: 10 A), not the initial one
    np.testing.assert_allclose(err.state["currents_A"], [10.0], rtol=1e-4)
    assert set(fm.differential_state_names) <= set(err.state)
    msg = str(err)
    assert "t = 0.005 s" in msg and "psi[coil]=" in msg and "voltages_V=[1e+12]" in msg
    assert "IDA" in err.reason and f"reason: {err.reason}" in msg


@pytest.mark.parametrize(("gap", "current"), [(0.008, 5.0), (0.010, 20.0), (0.012, 40.0)])
def test_step_inductance_equals_statics_without_eddies(u_magnet: mk.Magnet, gap: float,
                                                       current: float) -> None:
    est = mk.differential_inductance_from_step(u_magnet, gap_m=gap, current_A=current,
                                               eddy_currents=False)
    sol = mk.solve_statics(u_magnet, gaps_m=gap, currents_A=current)
    # Two independent methods (time constant of a 0.1 % step vs implicit-function dpsi/dI);
    # the issue asks for 1 %; measured +4e-5, -1.4e-3, -1.1e-3 at the three points (the
    # 0.1 % step measures a chord of psi(I) where L~ falls with I; fit); bound 3e-3.
    assert est.inductance_H == pytest.approx(sol.differential_inductance_H[0, 0], rel=3e-3)
    assert est.current_jump_A == 0.0


def test_inductance_with_eddies_has_jump_and_same_l_tilde(u_magnet: mk.Magnet) -> None:
    with_e = mk.differential_inductance_from_step(u_magnet, gap_m=0.01, current_A=20.0)
    without = mk.differential_inductance_from_step(u_magnet, gap_m=0.01, current_A=20.0,
                                                   eddy_currents=False)
    assert with_e.current_jump_A > 0.05 * with_e.final_current_change_A
    assert 0.0 < with_e.eddy_resistance_ohm < np.inf
    # paper IV-B: L~ does not depend on eddy currents; the U-magnet's several eddy modes
    # are fitted by one exponential: measured -1.2e-4 relative; bound 1e-3 (8x; the
    # earlier 2e-2 was 170x the measured value)
    assert with_e.inductance_H == pytest.approx(without.inductance_H, rel=1e-3)
    # the apparent inductance tau R_el is larger by ~(1 + R_el/R_ec): measured 1.276
    # (slow-mode R_ec 7.2 ohm at this point); window 1.25 ... 1.30
    assert 1.25 < with_e.apparent_inductance_H / with_e.inductance_H < 1.30


def test_fig7_behaviour(u_magnet: mk.Magnet) -> None:
    """Saturation: L~ falls with current.  No saturation, no eddies: constant L~."""
    currents = [5.0, 20.0, 40.0]
    full = [mk.differential_inductance_from_step(u_magnet, gap_m=0.0095, current_A=i)
            for i in currents]
    lin = [mk.differential_inductance_from_step(u_magnet, gap_m=0.0095, current_A=i,
                                                saturation=False, eddy_currents=False)
           for i in currents]
    lf = np.array([e.inductance_H for e in full])
    ll = np.array([e.inductance_H for e in lin])
    assert np.all(np.diff(lf) < 0.0)
    assert lf[-1] < 0.5 * lf[0]                       # strong saturation at 40 A
    # constant to the identification accuracy (0.1 % steps, fit): 0.5 %
    assert np.ptp(ll) < 5e-3 * ll.mean()
    # "generally smaller" (paper Sec. III): below the full model's measured (apparent)
    # inductance at low current (measured 0.119 vs 0.181 H at 5 A); at 20 A the U-magnet
    # is already at its knee (0.117 H), in deep saturation the full model drops far below.
    app = np.array([e.apparent_inductance_H for e in full])
    assert ll[0] < 0.8 * app[0]
    assert ll[-1] > 2.0 * app[-1]


# ---------------------------------------------------------------- eddy-current elements
RHO = 1.5e-7   # ohm m, a typical steel resistivity (facts.md sec. 5)


def test_solid_bar_eddy_conductance_limits() -> None:
    """G_ec = J l / (4 rho A^2): thin-sheet limit and the square bar's torsion constant."""
    length = 0.2
    # very flat bar b << a: G -> b^2 l / (12 rho A) (facts.md); the leading correction
    # is the factor (1 - 0.630 b/a) of the torsion constant: measured 6.3e-6, bound 1e-4
    a, b = 1.0, 1e-5
    thin = b**2 * length / (12.0 * RHO * a * b)
    for w, h in ((a, b), (b, a)):           # orientation does not matter
        g = mk.EddyCurrent.solid_rectangular("flat", w, h, length, RHO).eddy_conductance
        assert g == pytest.approx(thin, rel=1e-4)
    # b/a = 1e-2: the textbook asymptotic J = a b^3/3 (1 - 0.6302 b/a) (next terms are
    # O(exp(-pi a/b)); 0.6302 is good to ~1e-4 of the correction: measured 4.9e-7)
    b = 1e-2
    g = mk.EddyCurrent.solid_rectangular("plate", a, b, length, RHO).eddy_conductance
    assert g == pytest.approx(b**2 * length / (12 * RHO * a * b) * (1 - 0.6302 * b), rel=1e-5)
    # square bar of side s: J = 2.2492 (s/2)^4 = 0.14058 s^4 (Timoshenko), i.e.
    # G = 0.14058 l / (4 rho) for any s; 2.2492 has 5 digits (rounding <= 2.2e-5):
    # measured 1.4e-5, bound 1e-4
    for side in (0.01, 0.05):
        g = mk.EddyCurrent.solid_rectangular("sq", side, side, length, RHO).eddy_conductance
        assert g == pytest.approx(2.2492 * (side / 2) ** 4 * length / (4 * RHO * side**4),
                                  rel=1e-4)


def test_laminated_eddy_conductance() -> None:
    """G_ec = d^2 l / (12 rho A), and = a stack of N thin solid sheets in parallel."""
    d, length, width, n_sheets = 0.5e-3, 0.2, 0.1, 60
    area = n_sheets * width * d
    g = mk.EddyCurrent.laminated("lam", area, length, RHO, d).eddy_conductance
    assert g == pytest.approx(d**2 * length / (12 * RHO * area), rel=1e-12)
    # Second method: each sheet is its own flux tube with the same MMF across it, so the
    # stack's conductance is G_sheet / N (V = G_s phi_s', phi = N phi_s).  The solid
    # sheet (exact torsion series) exceeds the thin-sheet value by its finite-width
    # correction (1 - 0.6302 d/w) (d/w = 5e-3); with it they agree: measured 2.5e-7.
    sheet = mk.EddyCurrent.solid_rectangular("sheet", width, d, length, RHO).eddy_conductance
    assert sheet / n_sheets == pytest.approx(g * (1 - 0.6302 * d / width), rel=1e-5)
    with pytest.raises(mk.ParameterError, match=r"'bad': sheet_thickness_m = 0.0 must be a finite"):
        mk.EddyCurrent.laminated("bad", area, length, RHO, 0.0)


def _eddy_conductances(mag: mk.Magnet) -> dict[str, float]:
    return {e.name: e.eddy_conductance for br in mag.network.branches for e in br.elements
            if isinstance(e, mk.EddyCurrent)}


def test_laminated_u_magnet_has_small_core_eddy_currents() -> None:
    """laminated = true: core eddy conductances d^2 l/(12 rho A) from the geometry, leg by
    leg segment; the rail stays solid; the current jump after a voltage step shrinks."""
    from maglevkit.materials import get_material
    from maglevkit.reduction import eddy_resistance

    from .conftest import u_params

    p = u_params()
    solid = mk.build_magnet(p)
    p["magnet"].update(laminated=True, sheet_thickness=0.5e-3)
    lam = mk.build_magnet(p)
    m = p["magnet"]
    rho = get_material(m["material"]).resistivity_ohm_m
    d = m["sheet_thickness"]
    leg_len = m["leg_height"] + 0.5 * m["yoke_thickness"]     # leg to the yoke centre line
    leg_area = m["pole_width"] * m["depth"]
    yoke_len = m["window_width"] + m["pole_width"]             # centre line to centre line
    yoke_area = m["yoke_thickness"] * m["depth"]
    gs, gl = _eddy_conductances(solid), _eddy_conductances(lam)
    legs = {f"eddy_leg_{side}_{j}" for side in ("left", "right") for j in range(6)}
    assert set(gs) == set(gl) == legs | {"eddy_yoke", "eddy_rail"}
    for side in ("left", "right"):
        # the segments share the leg's conductance in proportion to their length
        total = sum(gl[f"eddy_leg_{side}_{j}"] for j in range(6))
        assert total == pytest.approx(d**2 * leg_len / (12 * rho * leg_area), rel=1e-12)
    assert gl["eddy_yoke"] == pytest.approx(d**2 * yoke_len / (12 * rho * yoke_area),
                                            rel=1e-12)
    for name in legs | {"eddy_yoke"}:
        assert gl[name] < 1e-3 * gs[name]                      # 0.5 mm sheets vs 30 mm bar
    assert gl["eddy_rail"] == gs["eddy_rail"]                  # the rail is always solid
    # Dynamics: right after a voltage step from rest (psi and the eddy fluxes are states,
    # so frozen) the simulated current jumps to dU / (R + R_ec), R_ec from the implicit
    # function theorem on the DAE's algebraic part (a second computation).  Over 1e-12 s
    # the following ramp adds 1e-7 (solid) and 1.1e-5 (laminated: a 2700x smaller jump)
    # relative, so bound 1e-4.
    r_el, dU = m["resistance"], 1000.0
    jumps = []
    for mag in (solid, lam):
        fm = mk.FluxModel(mag, rtol=1e-10, atol=1e-12)
        r_ec = float(eddy_resistance(mag, gap_m=0.01, current_A=0.0)[0])
        _, out = fm.step(fm.initial_state(gaps_m=0.01, currents_A=0.0), 1e-12, dU)
        assert out.currents_A[0] == pytest.approx(dU / (r_el + r_ec), rel=1e-4)
        jumps.append(out.currents_A[0])
    # laminating the core cuts the jump (the winding's flux can no longer change without
    # flux through the solid rail or the leakage paths): measured ratio 3.7e-4
    assert jumps[1] / jumps[0] < 1e-2
