"""Closed-form checks of the flux model on linear networks."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

import maglevkit as mk
from maglevkit.magnets import ModelOptions, build_magnet
from maglevkit.materials import MU0, ConstantPermeability

from .conftest import G_EC, R_EL, TURNS, loop_inductance, loop_network


def test_rl_step_response_matches_exponential() -> None:
    gap, U = 0.004, 30.0
    L = loop_inductance(gap)
    tau = L / R_EL
    res = mk.simulate(loop_network(eddy=False), (0.0, 5 * tau), dt_s=tau / 50, gaps_m=gap,
                      voltages_V=U, initial_currents_A=0.0)
    exact = U / R_EL * (1.0 - np.exp(-res.time_s * R_EL / L))
    # simulate runs IDAS through the hold intervals (a restart every 128 intervals); with
    # rtol = 1e-6 the error measured 5.1e-6 of the final current over these 250 intervals
    # (6e-5 when IDAS restarted at every interval).  2e-4 is still 20x below what a 1 %
    # error in L would cause (~4e-3 of the final current).
    np.testing.assert_allclose(res.currents_A[:, 0], exact, rtol=0, atol=2e-4 * U / R_EL)
    # x and I are consistent to IDAS's Newton tolerance: measured 1.5e-9 relative
    np.testing.assert_allclose(res.flux_linkage_Wb[:, 0], L * res.currents_A[:, 0], rtol=1e-8,
                               atol=1e-12)
    # Pole force of a plain pole: phi^2 / (2 mu0 A) (paper eq. 6 with mu_r -> inf).
    phi = res.branch_flux_Wb[:, 1]
    np.testing.assert_allclose(res.pole_force_N[:, 0], phi**2 / (2 * MU0 * 4e-4), rtol=1e-9)


def test_one_eddy_element_first_order_with_jump() -> None:
    """Coil + one eddy element: I(t) = U/R - (U/R - U/(R+R_ec)) exp(-t/tau)."""
    gap, U = 0.004, 30.0
    L = loop_inductance(gap)
    r_ec = TURNS**2 / G_EC
    tau = L * (R_EL + r_ec) / (R_EL * r_ec)
    fm = mk.FluxModel(loop_network(eddy=True))
    assert fm.differential_state_names == ("psi[coil]",)   # the rank-deficient case
    res = mk.simulate(fm, (0.0, 5 * tau), dt_s=tau / 50, gaps_m=gap, voltages_V=U,
                      initial_currents_A=0.0)
    t = res.time_s[1:]   # sample 0 is the left limit before the jump
    exact = U / R_EL - (U / R_EL - U / (R_EL + r_ec)) * np.exp(-t / tau)
    # same accumulated-restart error budget as above (measured ~6e-5)
    np.testing.assert_allclose(res.currents_A[1:, 0], exact, rtol=0, atol=2e-4 * U / R_EL)
    # the jump itself: right after the step the current is U/(R+R_ec)
    st = fm.initial_state(gaps_m=gap, currents_A=0.0)
    st1, out = fm.step(st, 1e-9 * tau, U)
    assert out.currents_A[0] == pytest.approx(U / (R_EL + r_ec), rel=1e-6)
    # eddy MMF = G dphi/dt = n I - Rm phi (Kirchhoff) at every sample
    rm = TURNS**2 / L
    mmf = TURNS * res.currents_A[:, 0] - rm * res.branch_flux_Wb[:, 0]
    np.testing.assert_allclose(res.eddy_mmf_A[1:, 0], mmf[1:], rtol=1e-7, atol=1e-6 * TURNS)


def test_u_magnet_ideal_iron_textbook_inductance() -> None:
    """Ideal iron, no leakage/fringing/eddies: L = mu0 n^2 A / (2 s), tau = L/R."""
    mag = mk.load_magnet("u-magnet")
    params = {**mag.parameters}
    params["magnet"] = {**params["magnet"], "material": "ideal"}
    params["rail"] = {**params["rail"], "material": "ideal"}
    lin = build_magnet(params, options=ModelOptions(fringing=False, leakage=False,
                                                    eddy_currents=False))
    m = params["magnet"]
    area = m["pole_width"] * m["depth"]
    gap, R, U = 0.01, m["resistance"], 20.0
    L = MU0 * m["turns"] ** 2 * area / (2 * gap)
    tau = L / R
    res = mk.voltage_step_response(lin, gap_m=gap, voltage_V=U, duration_s=4 * tau, dt_s=tau / 40)
    exact = U / R * (1.0 - np.exp(-res.time_s / tau))
    # 160 intervals at rtol 1e-6: measured 8.5e-7 of U/R (see the RL test)
    np.testing.assert_allclose(res.currents_A[:, 0], exact, rtol=0, atol=2e-4 * U / R)
    # textbook force F = mu0 (n I)^2 A / (4 s^2); the algebraic unknowns are consistent to
    # IDAS's Newton tolerance: measured 9.0e-9 relative, bound 3e-8
    i = res.currents_A[:, 0]
    np.testing.assert_allclose(res.force_N, MU0 * (m["turns"] * i) ** 2 * area / (4 * gap**2),
                               rtol=3e-8, atol=1e-9)


def test_radau_agrees_with_idas() -> None:
    gap, U = 0.004, 30.0
    tau = loop_inductance(gap) / R_EL
    net = loop_network(eddy=True)
    a = mk.simulate(net, (0.0, 2 * tau), dt_s=tau / 100, gaps_m=gap, voltages_V=U,
                    initial_currents_A=0.0)
    b = mk.simulate(net, (0.0, 2 * tau), dt_s=tau / 100, gaps_m=gap, voltages_V=U,
                    initial_currents_A=0.0, method="radau")
    # Radau IIA (order 5, 2 elements per step of tau/100) is ~1e-9 accurate here; the
    # difference is IDAS's accumulated restart error (measured ~9e-5 at rtol 1e-6).
    np.testing.assert_allclose(b.currents_A, a.currents_A, rtol=0, atol=2e-4 * U / R_EL)
    exact = U / R_EL - (U / R_EL - U / (R_EL + TURNS**2 / G_EC)) * np.exp(-b.time_s[1:] / (
        loop_inductance(gap) * (R_EL + TURNS**2 / G_EC) / (R_EL * TURNS**2 / G_EC)))
    np.testing.assert_allclose(b.currents_A[1:, 0], exact, rtol=0, atol=1e-7 * U / R_EL)
    assert math.isfinite(b.energy_balance().residual_J)


def test_two_time_constant_network_matches_matrix_exponential() -> None:
    """Coil + leakage branch + gap branch with an eddy element: two differential states.

    Loop fluxes: the core carries phi_c = psi/n, which splits into the leakage flux
    phi_l = phi_c - phi_g and the gap-branch flux phi_g.  By hand (Kirchhoff II and
    Faraday, all linear)::

        coil/leakage loop:  n I = Rc phi_c + Rs (phi_c - phi_g)
        leakage/gap loop:   Rs (phi_c - phi_g) = Rg phi_g + G phi_g'
        Faraday:            n phi_c' = U - R I

    i.e. ``x' = A x + b`` with ``x = (phi_c, phi_g)``, solved here by ``scipy.linalg.expm``
    independently of the model's DAE reduction and integrator.
    """
    area, l_fe, mu_r, n, r_el, s = 4e-4, 0.2, 1000.0, 200.0, 1.5, 0.004
    g_ec, g_leak, U = 2e4, 2e-7, 30.0
    net = mk.Network((
        mk.Branch("core", "A", "B", (mk.IronPath("fe", l_fe, area, ConstantPermeability(mu_r)),)),
        mk.Branch("leak", "B", "A", (mk.LeakagePermeance("lk", g_leak),)),
        mk.Branch("gap", "B", "A", (mk.AirGap("ag", gap_input="s", pole_area_m2=area),
                                    mk.EddyCurrent("ed", g_ec))),
    ), (mk.Circuit("coil", r_el, (mk.Coil("core", n),)),), name="two time constants")
    fm = mk.FluxModel(net, rtol=1e-9, atol=1e-11)
    assert fm.differential_state_names == ("psi[coil]", "phi[gap]")
    rc, rs, rg = l_fe / (MU0 * mu_r * area), 1.0 / g_leak, s / (MU0 * area)
    A = np.array([[-r_el * (rc + rs) / n**2, r_el * rs / n**2],
                  [rs / g_ec, -(rs + rg) / g_ec]])
    b = np.array([U / n, 0.0])
    lam, vec = np.linalg.eig(A)
    taus = np.sort(-1.0 / lam.real)
    assert 1e-3 < taus[0] < 2e-3 and 8e-3 < taus[1] < 10e-3    # two distinct, both resolved
    T = 5.0 * taus[1]
    res = mk.simulate(fm, (0.0, T), dt_s=T / 500, gaps_m=s, voltages_V=U, initial_currents_A=0.0)
    x_inf = -np.linalg.solve(A, b)
    x = np.array([x_inf - sla.expm(A * t) @ x_inf for t in res.time_s])
    i_exact = ((rc + rs) * x[:, 0] - rs * x[:, 1]) / n
    # both modes matter: modal amplitudes of I(t) = U/R + sum_j c_j exp(lam_j t); the fast
    # one is ~14 % of U/R, far above the 1e-6 comparison bound below
    c_row = np.array([rc + rs, -rs]) / n
    amps = -(c_row @ vec) * np.linalg.solve(vec, x_inf)
    assert np.abs(amps).min() > 0.1 * U / r_el
    # rtol 1e-9 over 500 restarted hold intervals: measured 9.7e-8 of U/R; 1e-6 leaves a
    # margin and is ~1000x below the effect of a 1 % error in any reluctance
    np.testing.assert_allclose(res.currents_A[:, 0], i_exact, rtol=0, atol=1e-6 * U / r_el)
    # the states themselves: psi = n phi_c and the eddy-branch flux phi_g (same budget
    # relative to their final values; measured 1.1e-7 and 1.3e-7)
    np.testing.assert_allclose(res.flux_linkage_Wb[:, 0], n * x[:, 0], rtol=0,
                               atol=1e-6 * n * x_inf[0])
    np.testing.assert_allclose(res.eddy_flux_Wb[:, 0], x[:, 1], rtol=0, atol=1e-6 * x_inf[1])
    # eddy MMF G phi_g' from the analytic derivative x' = A x + b (same relative budget,
    # scaled by its peak; measured 1.9e-7)
    mmf = g_ec * (x @ A.T + b)[:, 1]
    np.testing.assert_allclose(res.eddy_mmf_A[1:, 0], mmf[1:], rtol=0,
                               atol=1e-6 * np.abs(mmf).max())


def test_step_zero_order_hold_matches_exact_discrete_rl() -> None:
    """step() with a held voltage sequence vs the exact ZOH discretisation of L I' = U - R I.

    ``I_{k+1} = a I_k + (1 - a) U_k / R`` with ``a = exp(-R dt / L)``, and the electrical
    energy over a step ``U_k int I dt = U_k (I_inf dt + (I_k - I_inf) tau (1 - a))``.
    """
    gap = 0.004
    L = loop_inductance(gap)
    tau = L / R_EL
    dt = tau / 7.0
    rng = np.random.default_rng(3)
    volts = rng.uniform(-40.0, 60.0, 60)
    fm = mk.FluxModel(loop_network(eddy=False))
    st = fm.initial_state(gaps_m=gap, currents_A=2.0)
    i, e_in = 2.0, 0.0
    a = math.exp(-dt / tau)
    err_i = err_e = 0.0
    for u in volts:
        i_inf = u / R_EL
        e_in += u * (i_inf * dt + (i - i_inf) * tau * (1.0 - a))
        i = a * i + (1.0 - a) * i_inf
        st, out = fm.step(st, dt, u)
        err_i = max(err_i, abs(out.currents_A[0] - i))
        err_e = max(err_e, abs(st.energy_J[0] - e_in))
    scale_i = 60.0 / R_EL
    # 60 restarted intervals at rtol 1e-6: measured 1.4e-6 of the largest possible current
    # U_max/R; 1e-5 leaves a 7x margin and is ~100x below a 1 % error in L or a wrong hold
    # (a 1 % error in L shifts I by up to 0.37 % of the voltage change per step)
    assert err_i < 1e-5 * scale_i
    # energy quadrature on the scale U_max^2/R x elapsed time: measured 1.2e-7; bound 2e-6
    assert err_e < 2e-6 * 60.0 * scale_i * dt * volts.size
    assert st.time_s == pytest.approx(dt * volts.size, rel=1e-12)
