"""Energy balance, steady state vs statics, differential inductance (paper Fig. 7)."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.models.signals import Sine, Step


def test_energy_balance_moving_gap_saturation_eddy(u_magnet: mk.Magnet) -> None:
    """E_in = E_ohm + E_eddy + Delta W + E_mech over a saturating transient, gap moving."""
    res = mk.simulate(u_magnet, (0.0, 0.15), dt=2e-4,
                      gaps={"left": Sine(0.010, 0.002, 15.0), "right": Sine(0.011, -0.0015, 7.0)},
                      voltages=Step(20.0, 90.0, 0.01), initial_currents=10.0)
    assert res.currents_A.max() > 35.0          # into saturation (dpsi/dI falls 3x at 40 A)
    eb = res.energy_balance()
    assert eb.eddy_J > 0.0 and abs(eb.mechanical_J) > 1e-3 * eb.electrical_J
    # The balance is an identity of the continuous model; numerically it is limited by
    # the quadrature/state error (rtol 1e-6): measured 1.7e-5.  Required: 1e-4 (the issue).
    assert eb.relative_residual < 1e-4
    # the cumulative series are monotone where they must be
    assert np.all(np.diff(res.ohmic_loss_J) >= 0) and np.all(np.diff(res.eddy_loss_J) >= 0)


def test_energy_balance_moving_gap_radau(u_magnet: mk.Magnet) -> None:
    res = mk.simulate(u_magnet, (0.0, 0.05), dt=2e-4, gaps=Sine(0.010, 0.002, 20.0),
                      voltages=60.0, initial_currents=10.0, method="radau")
    # fixed-step Radau IIA(5) at 0.2 ms: local errors ~1e-9, balance well within 1e-4
    assert res.energy_balance().relative_residual < 1e-4


@pytest.mark.parametrize("eddy", [True, False])
def test_steady_state_reproduces_statics(u_magnet: mk.Magnet, eddy: bool) -> None:
    fm = mk.FluxModel(u_magnet, eddy_currents=eddy)
    gaps, i1 = [0.009, 0.012], 37.0
    st = fm.initial_state(gaps=gaps, currents=12.0)
    tau = 0.15   # s, > L~/R * (1 + R/R_ec) at the start; 2 s = 13 tau -> e^-13 ~ 2e-6
    res = mk.simulate(fm, (0.0, 2.0), dt=5e-3, gaps=gaps,
                      voltages=fm.resistances * i1, initial_state=st)
    sol = mk.solve_statics(u_magnet, gaps=gaps, currents=i1)
    assert tau > 0
    # remaining transient e^-13 and IDAS error (~1e-5) -> 1e-4 relative
    assert res.currents_A[-1, 0] == pytest.approx(i1, rel=1e-4)
    np.testing.assert_allclose(res.branch_flux_Wb[-1], sol.branch_flux_Wb, rtol=1e-4, atol=1e-9)
    np.testing.assert_allclose(res.pole_force_N[-1], sol.pole_force_N, rtol=2e-4)
    np.testing.assert_allclose(res.flux_linkage_Wb[-1], sol.flux_linkage_Wb, rtol=1e-4)
    # and the outputs at the static state itself are exactly the statics
    out = fm.outputs(fm.initial_state(gaps=gaps, currents=i1))
    np.testing.assert_allclose(out.pole_force_N, sol.pole_force_N, rtol=1e-12)
    np.testing.assert_allclose(out.branch_flux_Wb, sol.branch_flux_Wb, rtol=1e-12)
    np.testing.assert_allclose(out.eddy_mmf_A, 0.0, atol=1e-8)


@pytest.mark.parametrize(("gap", "current"), [(0.008, 5.0), (0.010, 20.0), (0.012, 40.0)])
def test_step_inductance_equals_statics_without_eddies(u_magnet: mk.Magnet, gap: float,
                                                       current: float) -> None:
    est = mk.differential_inductance_from_step(u_magnet, gap=gap, current=current,
                                               eddy_currents=False)
    sol = mk.solve_statics(u_magnet, gaps=gap, currents=current)
    # Two independent methods (time constant of a 0.1 % step vs implicit-function dpsi/dI);
    # the issue asks for 1 %; measured agreement ~0.2 % (step nonlinearity, fit).
    assert est.inductance_H == pytest.approx(sol.differential_inductance_H[0, 0], rel=1e-2)
    assert est.current_jump_A == 0.0


def test_inductance_with_eddies_has_jump_and_same_l_tilde(u_magnet: mk.Magnet) -> None:
    with_e = mk.differential_inductance_from_step(u_magnet, gap=0.01, current=20.0)
    without = mk.differential_inductance_from_step(u_magnet, gap=0.01, current=20.0,
                                                   eddy_currents=False)
    assert with_e.current_jump_A > 0.05 * with_e.final_current_change_A
    assert 0.0 < with_e.eddy_resistance_ohm < np.inf
    # paper IV-B: L~ does not depend on eddy currents; the U-magnet has two eddy time
    # constants (leakage loop) fitted by one exponential: measured agreement ~0.1 %.
    assert with_e.inductance_H == pytest.approx(without.inductance_H, rel=2e-2)
    # the apparent inductance tau R_el is larger by ~(1 + R_el/R_ec)
    assert with_e.apparent_inductance_H > 1.1 * with_e.inductance_H


def test_fig7_behaviour(u_magnet: mk.Magnet) -> None:
    """Saturation: L~ falls with current.  No saturation, no eddies: constant L~."""
    currents = [5.0, 20.0, 40.0]
    full = [mk.differential_inductance_from_step(u_magnet, gap=0.0095, current=i)
            for i in currents]
    lin = [mk.differential_inductance_from_step(u_magnet, gap=0.0095, current=i,
                                                saturation=False, eddy_currents=False)
           for i in currents]
    lf = np.array([e.inductance_H for e in full])
    ll = np.array([e.inductance_H for e in lin])
    assert np.all(np.diff(lf) < 0.0)
    assert lf[-1] < 0.5 * lf[0]                       # strong saturation at 40 A
    # constant to the identification accuracy (0.1 % steps, fit): 0.5 %
    assert np.ptp(ll) < 5e-3 * ll.mean()
    # "generally smaller" (paper Sec. III): below the full model's measured (apparent)
    # inductance at nominal currents; in deep saturation the full model drops below it.
    app = np.array([e.apparent_inductance_H for e in full])
    assert np.all(ll[:2] < app[:2])
    assert ll[-1] > app[-1]
