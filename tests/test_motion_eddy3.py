"""The three-state shielded-gap ladder (two shielded sections), linearised: its closed-form
transfer functions against an independent nodal analysis, its reduction to the two-state
ladder when the second branch vanishes, fit recovery, bad input, and (slow) the split TR09
network's gap and voltage responses against the detailed model's (docs/equations.md
section 8, "Three states")."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.reduction.motion_eddy import (
    MOTION_EDDY3_WEIGHTS,
    DetailedFrequencyResponse,
    Ladder3Response,
    MotionEddy3Fit,
    fit_motion_eddy,
    fit_motion_eddy3,
    ladder3_force_current,
    ladder3_frequency_response,
    ladder_force_response,
    ladder_frequency_response,
    ladder_voltage_currents,
)

from .conftest import load_script
from .test_reduced_motion_eddy import linear_responses, spline_point

F = np.geomspace(0.1, 1000.0, 25)
# split-TR09-like values (11 mm / 40 A fit): L~, k, R_el, R_a, L_u, R_2, L_2, R_3
LT, K, R_EL = 0.52, -1200.0, 1.2
ELEMENTS = {"jump_resistance_ohm": 9.6, "unshielded_inductance_H": 0.003,
            "shielding_resistance_ohm": 22.0, "inner_inductance_H": 0.117,
            "inner_shielding_resistance_ohm": 89.0}


def _l3(f: np.ndarray = F, **over: float) -> Ladder3Response:
    kw: dict[str, float] = {"differential_inductance_H": LT, "dpsi_ds_Wb_per_m": K, "resistance_ohm": R_EL,
          **ELEMENTS, "beta": 0.001, "inner_beta": 0.05}
    kw.update(over)
    return ladder3_frequency_response(f, **kw)


def _nodal(f: float, beta: float, beta_2: float) -> tuple[complex, complex]:
    """Modified nodal analysis of the circuit drawn in docs/equations.md section 8 (an
    independent assembly: node voltages V_A, V_B, V_C and the three inductor currents as
    unknowns, each motion EMF a source in its inductor's branch): coil current per gap and
    per voltage."""
    p = 2j * np.pi * f
    r_a, l_u = ELEMENTS["jump_resistance_ohm"], ELEMENTS["unshielded_inductance_H"]
    r_2, l_2 = ELEMENTS["shielding_resistance_ohm"], ELEMENTS["inner_inductance_H"]
    r_3, l_3 = ELEMENTS["inner_shielding_resistance_ohm"], LT - l_u - l_2
    out = []
    for u, ds in ((0.0, 1.0), (1.0, 0.0)):
        e = K * p * ds
        # unknowns: V_A, V_B, V_C, I_u, I_2, I_L
        m = np.zeros((6, 6), dtype=complex)
        rhs = np.zeros(6, dtype=complex)
        m[0, 0], m[0, 3], rhs[0] = 1 / R_EL + 1 / r_a, 1.0, u / R_EL   # KCL at A
        m[1, 1], m[1, 3], m[1, 4] = 1 / r_2, -1.0, 1.0                 # KCL at B
        m[2, 2], m[2, 4], m[2, 5] = 1 / r_3, -1.0, 1.0                 # KCL at C
        m[3, 0], m[3, 1], m[3, 3], rhs[3] = 1.0, -1.0, -p * l_u, beta * e          # L_u
        m[4, 1], m[4, 2], m[4, 4], rhs[4] = 1.0, -1.0, -p * l_2, beta_2 * e        # L_2
        m[5, 2], m[5, 5], rhs[5] = 1.0, -p * l_3, (1 - beta - beta_2) * e          # gap section
        v = np.linalg.solve(m, rhs)
        out.append((u - v[0]) / R_EL)
    return out[0], out[1]


def test_transfer_functions_match_a_nodal_analysis() -> None:
    """Two assemblies of the same circuit agree to rounding (1e-10: both are direct
    solves of well-conditioned 3x3 / 6x6 systems)."""
    r = _l3()
    ref = np.array([_nodal(f, 0.001, 0.05) for f in F])
    np.testing.assert_allclose(r.gap_to_current_A_per_m, ref[:, 0], rtol=1e-10)
    np.testing.assert_allclose(r.voltage_to_current_A_per_V, ref[:, 1], rtol=1e-10)
    # far below the electric corner R_el/L~ (0.37 Hz): eq. 8's statics, dI/dU -> 1/R_el
    # and dI/ds -> -k p/R_el (at 1e-5 Hz the next terms are ~1e-4 of these; bound 1e-3)
    low = _l3(np.array([1e-5]))
    assert low.voltage_to_current_A_per_V[0] == pytest.approx(1 / R_EL, rel=1e-3)
    p0 = 2j * np.pi * 1e-5
    assert low.gap_to_current_A_per_m[0] == pytest.approx(-K * p0 / R_EL, rel=1e-3)


def _two(r_2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return ladder_frequency_response(
        F, differential_inductance_H=LT, dpsi_ds_Wb_per_m=K, resistance_ohm=R_EL,
        jump_resistance_ohm=ELEMENTS["jump_resistance_ohm"],
        unshielded_inductance_H=ELEMENTS["unshielded_inductance_H"],
        shielding_resistance_ohm=r_2, beta=0.001)


def test_no_inner_inductance_is_the_two_state_ladder_with_parallel_shunts() -> None:
    """``L_2 = 0`` (and ``beta_2 = 0``): nodes B and C are one, ``R_2 || R_3`` its shunt;
    exact, so to rounding."""
    r_2, r_3 = ELEMENTS["shielding_resistance_ohm"], ELEMENTS["inner_shielding_resistance_ohm"]
    r = _l3(inner_inductance_H=0.0, inner_beta=0.0)
    ms, il, mu = _two(r_2 * r_3 / (r_2 + r_3))
    np.testing.assert_allclose(r.gap_to_current_A_per_m, ms, rtol=1e-10)
    np.testing.assert_allclose(r.gap_states[:, 2], il, rtol=1e-10)
    np.testing.assert_allclose(r.voltage_to_current_A_per_V, mu, rtol=1e-10)


def test_an_open_inner_shunt_is_the_two_state_ladder() -> None:
    """``R_3 -> oo`` (and ``beta_2 = 0``): ``L_2`` and the gap section are in series, the
    two-state ladder with ``R_2``.  With ``R_3 = 1e9 ohm`` the difference is of order
    ``|p| (L~ - L_u)/R_3`` < 4e-6 at 1 kHz; bound 1e-5."""
    r = _l3(inner_shielding_resistance_ohm=1e9, inner_beta=0.0)
    ms, il, mu = _two(ELEMENTS["shielding_resistance_ohm"])
    np.testing.assert_allclose(r.gap_to_current_A_per_m, ms, rtol=1e-5)
    np.testing.assert_allclose(r.gap_states[:, 2], il, rtol=1e-5)
    np.testing.assert_allclose(r.voltage_to_current_A_per_V, mu, rtol=1e-5)


def test_force_current_is_i_l_in_a_steady_state() -> None:
    got = ladder3_force_current(np.array([3.0, 4.0]), np.array([3.0, 2.0]),
                                np.array([3.0, 1.0]), (0.3, -0.2))
    assert got[0] == 3.0
    assert got[1] == pytest.approx(1.0 + 0.3 * 1.0 - 0.2 * 2.0)


def _synthetic(fit: MotionEddy3Fit) -> DetailedFrequencyResponse:
    """A 'detailed' response that is exactly a known three-state ladder."""
    jump = -fit.unshielded_share * K / ((1 + R_EL / fit.jump_resistance_ohm)
                                        * fit.unshielded_inductance_H)
    base = DetailedFrequencyResponse(F, F * 0j, F * 0j, F * 0j, LT, K, jump, 800.0, -3.7e6,
                                     float("nan"), F * 0j)
    r, gf, uf = fit.response(F, base, R_EL)
    return dataclasses.replace(base, gap_to_current_A_per_m=r.gap_to_current_A_per_m,
                               gap_to_force_N_per_m=gf,
                               voltage_to_current_A_per_V=r.voltage_to_current_A_per_V,
                               voltage_to_force_N_per_V=uf)


def test_fit_recovers_a_known_ladder() -> None:
    """The fit finds the ladder that made the responses (noise-free: residual < 1e-6,
    elements within 1e-3; beta from the jump)."""
    true = MotionEddy3Fit(9.6, 0.003, 22.0, 0.117, 89.0, 0.001, 0.05, (0.06, 0.001), 0.0)
    got = fit_motion_eddy3(_synthetic(true), resistance_ohm=R_EL, eddy_resistance_jump_ohm=7.0,
                           max_series_inductance_H=0.2)
    assert got.rms_residual < 1e-6
    for name in ("jump_resistance_ohm", "unshielded_inductance_H", "shielding_resistance_ohm",
                 "inner_inductance_H", "inner_shielding_resistance_ohm", "inner_share"):
        assert getattr(got, name) == pytest.approx(getattr(true, name), rel=1e-3), name
    assert got.force_shares == pytest.approx(true.force_shares, rel=1e-3, abs=1e-6)


@pytest.mark.parametrize(("key", "value", "needle"), [
    ("jump_resistance_ohm", 0.0, "jump_resistance_ohm = 0.0 must be > 0"),
    ("inner_shielding_resistance_ohm", -1.0, "inner_shielding_resistance_ohm = -1.0"),
    ("inner_inductance_H", 0.6, "must be below differential_inductance_H"),
    ("inner_inductance_H", -0.1, "inner_inductance_H = -0.1"),
    ("beta", float("nan"), "beta = nan must be finite"),
])
def test_bad_elements_are_refused(key: str, value: float, needle: str) -> None:
    with pytest.raises(InputError, match=needle.replace("(", r"\(")):
        _l3(**{key: value})


def test_fit_refuses_a_response_without_force() -> None:
    base = DetailedFrequencyResponse(F, F * 0j + 1, F * 0j + 1, F * 0j + 1, LT, K)
    with pytest.raises(InputError, match="force partials"):
        fit_motion_eddy3(base, resistance_ohm=R_EL, eddy_resistance_jump_ohm=7.0)


@pytest.mark.slow
def test_split_tr09_meets_the_gap_motion_aims_linearised() -> None:
    """Split TR09 network: fitted where ``build_maps`` identifies the ladder (11 mm / 40 A),
    with build_maps' weights, evaluated at the gap-motion benchmark's point (10 mm / 31.7 A)
    against the detailed model's linearisation.  The aims of issue 26 (force and current
    within 5 / 10 / 20 % at 5 / 50 / 200 Hz, current phase within 5 deg) hold (measured:
    force 1.1 / 5.7 / 9.1 %, current 0.9 / 8.2 / 15.0 %, phase +0.5 / +3.8 / -1.6 deg),
    where the two-state ladder's force with gamma = 0 misses them (1.9 / 18.0 / 38.8 %);
    its voltage -> current response is within 1.6 % at every frequency up to 1 kHz (the
    two-state ladder: 11.4 %) and its voltage -> force within 19 % (two-state, gamma = 0:
    64 %; held-flux gamma: a factor 21)."""
    from maglevkit.models.statics import circuit_pole_groups
    from maglevkit.reduction.maps import eddy_resistance
    from maglevkit.reduction.motion_eddy import FIT_FREQUENCIES_HZ, detailed_frequency_response

    # the split network with its lumped eddy elements (the bundled file builds the eddy
    # ladder since switch26m, which has no current jump to start the fit from)
    net = mk.load_magnet("tr09-standard", eddy_model="lumped").network
    f = np.concatenate((FIT_FREQUENCIES_HZ, [5.0, 50.0, 200.0]))
    fit_at = detailed_frequency_response(net, gap=0.011, current=40.0)[0]
    r_el = float(net.resistances[0])
    rj = float(eddy_resistance(net, gap_m=0.011, current_A=40.0)[0])
    fit = fit_motion_eddy3(fit_at, resistance_ohm=r_el, eddy_resistance_jump_ohm=rj,
                           max_series_inductance_H=0.12, weights=MOTION_EDDY3_WEIGHTS)
    groups = circuit_pole_groups(net, gap_m=0.010, current_A=31.7)
    det = detailed_frequency_response(net, gap=0.010, current=31.7, frequencies_Hz=f,
                                      groups=groups)[0]
    r, gf, uf = fit.response(f, det, r_el)
    for fr, aim in ((5.0, 0.05), (50.0, 0.10), (200.0, 0.20)):
        i = int(np.argmin(np.abs(f - fr)))
        ratio_i = r.gap_to_current_A_per_m[i] / det.gap_to_current_A_per_m[i]
        assert abs(gf[i] / det.gap_to_force_N_per_m[i] - 1) <= aim, fr
        assert abs(ratio_i - 1) <= aim, fr
        assert abs(np.degrees(np.angle(ratio_i))) <= 5.0, fr
    vf = det.voltage_to_force_N_per_V
    assert vf is not None
    three = np.max(np.abs(uf / vf - 1))
    # the two-state ladder as build_maps fits it (gamma = 0), same points
    two = fit_motion_eddy(fit_at, resistance_ohm=r_el, eddy_resistance_jump_ohm=rj,
                          eddy_resistance_fit_ohm=0.7 * rj, max_unshielded_inductance_H=0.12)
    il, _ = ladder_voltage_currents(
        f, differential_inductance_H=det.differential_inductance_H, resistance_ohm=r_el,
        jump_resistance_ohm=two.jump_resistance_ohm,
        unshielded_inductance_H=two.unshielded_inductance_H,
        shielding_resistance_ohm=two.shielding_resistance_ohm)
    two_vf = np.max(np.abs(det.dforce_dcurrent_N_per_A * il / vf - 1))
    assert three < 0.5 * two_vf
    _, _, two_u = ladder_frequency_response(
        f, differential_inductance_H=det.differential_inductance_H,
        dpsi_ds_Wb_per_m=det.dpsi_ds_Wb_per_m, resistance_ohm=r_el,
        jump_resistance_ohm=two.jump_resistance_ohm,
        unshielded_inductance_H=two.unshielded_inductance_H,
        shielding_resistance_ohm=two.shielding_resistance_ohm)
    gu = det.voltage_to_current_A_per_V
    assert np.max(np.abs(r.voltage_to_current_A_per_V / gu - 1)) < np.max(np.abs(two_u / gu - 1))
    ms, il_s, _ = ladder_frequency_response(
        f, differential_inductance_H=det.differential_inductance_H,
        dpsi_ds_Wb_per_m=det.dpsi_ds_Wb_per_m, resistance_ohm=r_el,
        jump_resistance_ohm=two.jump_resistance_ohm,
        unshielded_inductance_H=two.unshielded_inductance_H,
        shielding_resistance_ohm=two.shielding_resistance_ohm, beta=two.unshielded_share)
    i200 = int(np.argmin(np.abs(f - 200.0)))
    assert abs(ladder_force_response(det, il_s)[i200] / det.gap_to_force_N_per_m[i200] - 1) > 0.2


# --- CurrentModel(maps, motion_eddy=True, eddy_branches=2) --------------------------------

@pytest.fixture(scope="module")
def u_maps() -> mk.CharacteristicMaps:
    return mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.006, 0.014, 5),
                         currents_A=np.linspace(0.0, 40.0, 9), progress=False)


def test_model_transfer_functions_match_the_closed_form(u_maps: mk.CharacteristicMaps) -> None:
    """``ladder3_frequency_response`` and the force current (closed form) equal the AD
    linearisation of the ODE that ``CurrentModel(motion_eddy=True, eddy_branches=2)``
    integrates, at a point off the grid nodes (both exact: rounding only, 1e-9)."""
    from maglevkit.reduced.current import motion_eddy3_parameters

    gap, cur = 0.0093, 23.0
    model = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    r_el, lt, k, dfi, dfs = spline_point(u_maps, gap, cur)
    par, _ = motion_eddy3_parameters(u_maps, np.array([r_el]))
    p = {key: float(v[0]) for key, v in par.items()}
    f = np.geomspace(0.2, 2000.0, 25)
    cs, cf, cu, cuf = linear_responses(model, f, gap, cur)
    r = ladder3_frequency_response(
        f, differential_inductance_H=lt, dpsi_ds_Wb_per_m=k, resistance_ohm=r_el,
        jump_resistance_ohm=p["r_a"], unshielded_inductance_H=p["l_u"],
        shielding_resistance_ohm=p["r_2"], inner_inductance_H=p["l_2"],
        inner_shielding_resistance_ohm=p["r_3"], beta=p["beta"], inner_beta=p["beta_2"])
    shares = (p["c_1"], p["c_2"])
    gs, us = r.gap_states, r.voltage_states
    mf = dfi * ladder3_force_current(gs[:, 0], gs[:, 1], gs[:, 2], shares) + dfs
    muf = dfi * ladder3_force_current(us[:, 0], us[:, 1], us[:, 2], shares)
    assert np.max(np.abs(cs / r.gap_to_current_A_per_m - 1.0)) < 1e-9
    assert np.max(np.abs(cu / r.voltage_to_current_A_per_V - 1.0)) < 1e-9
    assert np.max(np.abs(cf / mf - 1.0)) < 1e-9
    assert np.max(np.abs(cuf / muf - 1.0)) < 1e-9
    assert model.linearize(gap_m=gap, current_A=cur).A_per_s.shape == (3, 3)
    assert p["c_1"] != 0.0 or p["c_2"] != 0.0      # the force current is exercised


def test_model_steady_state_and_simulation(u_maps: mk.CharacteristicMaps) -> None:
    """At rest the three-state model is eq. 8's steady state (eddy states 0, force of the
    maps at I); a voltage step settles to U/R_el (within 1e-6 relative after 50 electric
    time constants... here 2 s, L~/R_el ~ 0.06 s)."""
    model = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    st = model.initial_state(gaps_m=0.010, currents_A=20.0)
    assert np.asarray(st.eddy_currents_A).shape == (1, 2)
    assert np.all(np.asarray(st.eddy_currents_A) == 0.0)
    out = model.outputs(st)
    ref = mk.CurrentModel(u_maps).outputs(mk.CurrentModel(u_maps).initial_state(
        gaps_m=0.010, currents_A=20.0))
    np.testing.assert_allclose(out.force_N, ref.force_N, rtol=1e-12)
    r_el = float(model.resistance_ohm[0])
    t = np.linspace(0.0, 2.0, 2001)
    sim = model.simulate(t, gaps_m=0.010, voltages_V=r_el * 25.0, initial_currents_A=20.0)
    assert float(np.asarray(sim.currents_A)[-1, 0]) == pytest.approx(25.0, rel=1e-6)


@pytest.mark.parametrize(("kw", "needle"), [
    ({"eddy_branches": 3}, "eddy_branches = 3"),
    ({"eddy_branches": True}, "eddy_branches = True"),
    ({"motion_eddy": False, "eddy_branches": 2}, "needs motion_eddy=True"),
])
def test_model_option_is_checked(u_maps: mk.CharacteristicMaps, kw: dict[str, object],
                                 needle: str) -> None:
    with pytest.raises(InputError, match=needle):
        mk.CurrentModel(u_maps, **kw)  # type: ignore[arg-type]


# The bank, its stepper and the FMU carry the three-state ladder (ladder3bank):
# tests/test_bank_ladder3.py.


def test_old_maps_without_the_three_state_ladder_are_refused(u_maps: mk.CharacteristicMaps
                                                             ) -> None:
    from maglevkit.reduction.maps import MOTION_EDDY3_VARIABLES

    old = mk.CharacteristicMaps(u_maps.dataset.drop_vars(
        [v[0] for v in MOTION_EDDY3_VARIABLES]))
    mk.CurrentModel(old, motion_eddy=True)          # the two-state ladder still reads them
    with pytest.raises(InputError, match="no three-state ladder"):
        mk.CurrentModel(old, motion_eddy=True, eddy_branches=2)


@pytest.mark.slow
def test_split_tr09_three_state_ladder_against_the_detailed_model() -> None:
    """Simulated, as benchmarks/bench_gap_motion.py (bundled split TR09, 12 x 41 maps, 10 mm
    / 31.7 A): under a +-1 mm gap sine the three-state ladder meets issue 26's force and
    current aims (<= 5 / 10 / 20 % at 5 / 50 / 200 Hz; measured force 0.9 / 5.6 / 10.2 %,
    current 1.1 / 7.4 / 14.1 %, phase +0.4 / +3.5 / -2.3 deg), and the voltage step and the
    closed-loop scenario are no worse than with the two-state ladder (measured 0.88 / 0.52
    vs 2.91 / 3.59 % and 2.62 / 0.71 vs 5.74 / 1.60 %, current / force AC error)."""
    from maglevkit.compare import compare_models, standard_scenarios

    bench = load_script(Path(__file__).resolve().parents[1] / "benchmarks" / "bench_gap_motion.py")
    mag = mk.load_magnet("tr09-standard", eddy_model="lumped")   # as measured (switch26m)
    maps = mk.build_maps(mag, gaps_m=bench.GRID[0], currents_A=bench.GRID[1], progress=False)
    two = mk.CurrentModel(maps, motion_eddy=True)
    three = mk.CurrentModel(maps, motion_eddy=True, eddy_branches=2)
    i0 = bench.nominal_current(mag)
    fm = mk.FluxModel(mag)
    rows = bench.sweep(fm, {"three": three}, i0, (5.0, 50.0, 200.0))
    for row, aim in zip(rows, (0.05, 0.10, 0.20), strict=True):
        assert row["three"][2] <= aim, row["f"]     # current AC error
        assert row["three"][3] <= aim, row["f"]     # force AC error
        phase = bench._phase_deg(row["three"][0]) - bench._phase_deg(row["detailed"][0])
        assert abs(phase) <= 5.0, row["f"]
    keep = ("voltage step up", "closed loop")
    scen = [s for s in standard_scenarios(mag, gap_m=bench.GAP, current_A=i0) if s.name in keep]
    r2 = compare_models(fm, two, scen, gap_m=bench.GAP, current_A=i0)
    r3 = compare_models(fm, three, scen, gap_m=bench.GAP, current_A=i0)
    for a, b in zip(r3, r2, strict=True):
        assert np.max(a.current_error_ac) <= np.max(b.current_error_ac)
        assert np.max(a.force_error_ac) <= np.max(b.force_error_ac)


def test_model_rk4_agrees_with_cvodes_under_gap_motion(u_maps: mk.CharacteristicMaps) -> None:
    """RK4 (with the sub-step limit of ``motion_eddy3_parameters``) against CVODES (rtol
    1e-8) on the same three-state ODE: a 100 Hz +-1 mm gap sine at constant voltage,
    0.1 s at 0.1 ms steps.  RK4's local error ~(h lambda)^5 with h <= 0.1 ms; bound 1e-4
    of the current's and the force's variation."""
    rk4 = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    cv = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2, method="cvodes")
    assert rk4.max_step_s < 1e-3      # the ladder's rates limit the sub-step
    u = float(rk4.resistance_ohm[0]) * 20.0
    t = np.linspace(0.0, 0.1, 1001)

    def gaps(tt: np.ndarray) -> np.ndarray:
        return 0.010 + 1e-3 * np.sin(2 * np.pi * 100.0 * tt)

    a = rk4.simulate(t, gaps_m=gaps, voltages_V=u, initial_currents_A=20.0)
    b = cv.simulate(t, gaps_m=gaps, voltages_V=u, initial_currents_A=20.0)
    ia, ib = np.asarray(a.currents_A)[:, 0], np.asarray(b.currents_A)[:, 0]
    fa, fb = np.asarray(a.force_N), np.asarray(b.force_N)
    assert np.ptp(ib) > 0.1           # the gap moves the current
    assert np.max(np.abs(ia - ib)) < 1e-4 * np.ptp(ib)
    assert np.max(np.abs(fa - fb)) < 1e-4 * np.ptp(fb)


def test_reported_residuals_are_unweighted_and_per_response() -> None:
    """``rms_residual`` is the unweighted RMS over the four responses whatever the fit's
    weights, and ``response_residuals`` are each response's, recomputed here from
    :meth:`MotionEddy3Fit.response` (a separate code path) against a perturbed ladder."""
    true = MotionEddy3Fit(9.6, 0.003, 22.0, 0.117, 89.0, 0.001, 0.05, (0.06, 0.001), 0.0)
    det = _synthetic(true)
    # perturb the detailed responses so that no ladder fits exactly: a 5 % ripple in log f
    ripple = 1.0 + 0.05 * np.sin(3.0 * np.log(F))
    det = dataclasses.replace(det, gap_to_current_A_per_m=det.gap_to_current_A_per_m * ripple,
                              gap_to_force_N_per_m=det.gap_to_force_N_per_m / ripple)
    got = fit_motion_eddy3(det, resistance_ohm=R_EL, eddy_resistance_jump_ohm=7.0,
                           max_series_inductance_H=0.2, weights=MOTION_EDDY3_WEIGHTS)
    r, gf, uf = got.response(F, det, R_EL)
    mine = []
    for m, d in ((r.gap_to_current_A_per_m, det.gap_to_current_A_per_m),
                 (r.voltage_to_current_A_per_V, det.voltage_to_current_A_per_V),
                 (gf, det.gap_to_force_N_per_m), (uf, det.voltage_to_force_N_per_V)):
        e = (m - d) / np.abs(d)
        mine.append(np.sqrt(np.mean(np.abs(e) ** 2) / 2.0))   # real and imaginary parts
    # rounding only: the same residuals by another path
    assert got.response_residuals == pytest.approx(mine, rel=1e-9, abs=1e-12)
    assert got.rms_residual == pytest.approx(np.sqrt(np.mean(np.square(mine))), rel=1e-9)
    # the ripple cannot be fitted: a real residual, of the ripple's order (5 %)
    assert 1e-3 < got.rms_residual < 0.1
    assert 0.0 < got.series_bound_share < 1.0


def test_guidance_magnet_ladders_and_the_series_bound() -> None:
    """Issue 26 part 3 on the bundled guidance magnet at 10 mm / 32 A (docs/reduction.md,
    "Gap motion", guidance): its gap -> current lags past -180 deg within the fit's band
    (two eddy elements in series behind the gap), which the two-state ladder (one shield)
    cannot follow at any element values (residual above 20 %, the vehicles' warning), the
    three-state ladder can (below 10 % with free series inductances), but not under
    ``build_maps``' bound 0.8 x the smallest L~ of maps that reach 80 A at 5 mm (deep
    saturation; the fit then sits on the bound, residual above 25 %)."""
    from maglevkit.models.statics import solve_statics
    from maglevkit.reduction.maps import eddy_resistance
    from maglevkit.reduction.motion_eddy import (
        MAX_UNSHIELDED_SHARE_OF_MIN_L,
        detailed_frequency_response,
    )

    net = mk.load_magnet("tr-guidance", eddy_model="lumped").network
    resp = detailed_frequency_response(net, gap=0.010, current=32.0)[0]
    r_el = float(net.resistances[0])
    r_jump = float(eddy_resistance(net, gap_m=0.010, current_A=32.0)[0])
    # more than 180 deg of lag in the band (phase unwrapped from the derivative's +90 deg)
    phase = np.degrees(np.unwrap(np.angle(resp.gap_to_current_A_per_m)))
    assert phase[0] > 45.0 and phase[-1] < -180.0
    two = fit_motion_eddy(resp, resistance_ohm=r_el, eddy_resistance_jump_ohm=r_jump,
                          eddy_resistance_fit_ohm=0.55 * r_jump)
    assert two.rms_residual > 0.2 and two.max_gap_error > 0.5
    free = fit_motion_eddy3(resp, resistance_ohm=r_el, eddy_resistance_jump_ohm=r_jump,
                            weights=MOTION_EDDY3_WEIGHTS)
    assert free.rms_residual < 0.1
    # the ladder needs series inductances above what the saturated corner leaves
    lt_min = float(np.min(np.diag(np.asarray(solve_statics(
        net, gaps_m=0.005, currents_A=80.0).differential_inductance_H))))
    bound = MAX_UNSHIELDED_SHARE_OF_MIN_L * lt_min
    assert free.unshielded_inductance_H + free.inner_inductance_H > 1.5 * bound
    held = fit_motion_eddy3(resp, resistance_ohm=r_el, eddy_resistance_jump_ohm=r_jump,
                            weights=MOTION_EDDY3_WEIGHTS, max_series_inductance_H=bound)
    # measured 0.32 (unweighted; the force responses 55 %), against 0.035 free
    assert held.series_bound_share > 0.95 and held.rms_residual > 0.25


def test_common_mode_responses_are_the_sum_of_the_single_gap_ones() -> None:
    """``detailed_frequency_response(common_mode=True)``: every gap moving together is, by
    linearity, the sum of each gap moving alone (the single-gap responses through
    ``groups``), for the coil current; the statics' partials stay
    the circuit's own; and on the guidance magnet the sections' coupling shows (the common
    gap -> current differs from the own-pole one by more than 3 % in the fit's band)."""
    from maglevkit.reduction.motion_eddy import detailed_frequency_response

    net = mk.load_magnet("tr-guidance", eddy_model="lumped").network
    f = np.array([0.3, 5.0, 50.0, 300.0])
    own = detailed_frequency_response(net, gap=0.010, current=32.0, frequencies_Hz=f)
    common = detailed_frequency_response(net, gap=0.010, current=32.0, frequencies_Hz=f,
                                         common_mode=True)
    singles = [detailed_frequency_response(net, gap=0.010, current=32.0, frequencies_Hz=f,
                                           groups={c: (g,) for c in net.circuit_names})
               for g in net.gap_names]
    for j, c in enumerate(net.circuit_names):
        total = sum(s[j].gap_to_current_A_per_m for s in singles)
        # rounding only (the same linear solves, summed)
        np.testing.assert_allclose(common[j].gap_to_current_A_per_m, total, rtol=1e-9)
        assert common[j].differential_inductance_H == own[j].differential_inductance_H
        assert common[j].dpsi_ds_Wb_per_m == own[j].dpsi_ds_Wb_per_m
        assert common[j].dforce_dgap_N_per_m == own[j].dforce_dgap_N_per_m
        gap = np.abs(common[j].gap_to_current_A_per_m / own[j].gap_to_current_A_per_m - 1)
        assert np.max(gap) > 0.03, c
