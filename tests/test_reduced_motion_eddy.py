"""The shielded-gap ladder (``CurrentModel(maps, motion_eddy=True)``): eq. 8 extended so
that the motion-induced current passes through eddy dynamics (docs/reduction.md, "Gap
motion").

Closed forms (the ladder's transfer functions against the model's AD linearisation, the
limit ``L_u -> 0`` against eq. 8, fit recovery), the default left unchanged, bad input, and
the TR09 gap-sine sweep against the detailed model.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.reduced.current import eq8_shielded_gap_rhs
from maglevkit.reduction.maps import CharacteristicMaps
from maglevkit.reduction.motion_eddy import (
    FORCE_SHARE_VARIABLE,
    DetailedFrequencyResponse,
    fit_motion_eddy,
    force_share,
    ladder_force_response,
    ladder_frequency_response,
    ladder_voltage_currents,
    unshielded_share,
)

from .conftest import paper_tr09

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 40.0, 9)


def _ladder(f: object, lt: float, k: float, r_el: float, r_a: float, l_u: float, r_2: float,
            beta: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`ladder_frequency_response` with its parameters in the order of the paper's
    symbols (``L~``, ``k``, ``R_el``, ``R_a``, ``L_u``, ``R_2``)."""
    return ladder_frequency_response(f, differential_inductance_H=lt, dpsi_ds_Wb_per_m=k,
                                     resistance_ohm=r_el, jump_resistance_ohm=r_a,
                                     unshielded_inductance_H=l_u, shielding_resistance_ohm=r_2,
                                     beta=beta)


@pytest.fixture(scope="module")
def u_maps() -> CharacteristicMaps:
    return mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)


def spline_point(maps: CharacteristicMaps, gap: float, cur: float
                 ) -> tuple[float, float, float, float, float]:
    """``R_el``, ``L~``, ``k = dL/ds I_L``, ``dF/dI`` and ``dF/ds`` of circuit 0 of the maps'
    splines at a point, from eq. 8's linearisation (``A = -R_el/(a L~)``, ``E_gap_rate =
    -k/L~``); also used by tests/test_motion_eddy3.py."""
    eq8 = mk.CurrentModel(maps)
    lin8 = eq8.linearize(gap_m=gap, current_A=cur)
    r_el = float(eq8.resistance_ohm[0])
    a8 = 1.0 + r_el / float(eq8.eddy_resistance_ohm[0])
    lt = -r_el / (a8 * float(lin8.A_per_s[0, 0]))
    k = -float(lin8.E_gap_rate_A_per_m.sum()) * lt
    return (r_el, lt, k, float(lin8.C_force_N_per_A[0, 0]),
            float(lin8.D_force_gap_N_per_m.sum()))


def linear_responses(model: mk.CurrentModel, f: np.ndarray, gap: float, current: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """gap -> coil current, gap -> circuit force, voltage -> coil current, voltage ->
    circuit force of circuit 0 from ``linearize`` (every pole moving); also used by
    tests/test_motion_eddy3.py."""
    lin = model.linearize(gap_m=gap, current_A=current)
    n = lin.A_per_s.shape[0]
    eg, er = lin.E_gap_A_per_m_s.sum(axis=1), lin.E_gap_rate_A_per_m.sum(axis=1)
    out = []
    for fk in f:
        p = 2j * np.pi * fk
        xs = np.linalg.solve(p * np.eye(n) - lin.A_per_s, eg + p * er)
        xu = np.linalg.solve(p * np.eye(n) - lin.A_per_s, lin.B_A_per_V_s[:, 0])
        out.append(((lin.C_current @ xs)[0],
                    (lin.C_force_N_per_A @ xs)[0] + lin.D_force_gap_N_per_m.sum(axis=1)[0],
                    (lin.C_current @ xu)[0] + lin.D_current_A_per_V[0, 0],
                    (lin.C_force_N_per_A @ xu)[0]))   # the force has no direct U term
    arr = np.array(out)
    return arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3]


def test_ladder_transfer_functions_match_the_linearised_ode(u_maps: CharacteristicMaps) -> None:
    """``ladder_frequency_response`` (closed form) equals the AD linearisation of the ODE
    that ``CurrentModel(motion_eddy=True)`` integrates, at a point off the grid nodes."""
    gap, cur = 0.0093, 23.0
    ladder = mk.CurrentModel(u_maps, motion_eddy=True)
    r_el, lt, k, _, _ = spline_point(u_maps, gap, cur)
    ds = u_maps.dataset
    f = np.geomspace(0.2, 2000.0, 25)
    cs, _, cu, _ = linear_responses(ladder, f, gap, cur)
    ms, _, mu = ladder_frequency_response(
        f, differential_inductance_H=lt, dpsi_ds_Wb_per_m=k, resistance_ohm=r_el,
        jump_resistance_ohm=float(ds["motion_eddy_jump_resistance_ohm"].values[0]),
        unshielded_inductance_H=float(ds["motion_eddy_unshielded_inductance_H"].values[0]),
        shielding_resistance_ohm=float(ds["motion_eddy_shielding_resistance_ohm"].values[0]),
        beta=float(ds["motion_eddy_unshielded_share"].values[0]))
    # both are exact (AD vs algebra): rounding only
    assert np.max(np.abs(cs / ms - 1.0)) < 1e-9
    assert np.max(np.abs(cu / mu - 1.0)) < 1e-9
    assert ladder.linearize(gap_m=gap, current_A=cur).A_per_s.shape == (2, 2)


def test_unshielded_share_in_the_ode_and_the_closed_form(u_maps: CharacteristicMaps) -> None:
    """A share ``beta`` of the motion term in ``L_u``: the ODE's AD linearisation equals
    the closed form with that ``beta`` (and differs from ``beta = 0`` by far more than the
    rounding), and the high-frequency gap -> current response tends to the jump
    ``-beta k/(a L_u)`` that :func:`unshielded_share` inverts."""
    gap, cur, beta = 0.0093, 23.0, 0.05
    maps = CharacteristicMaps(u_maps.dataset.assign(
        motion_eddy_unshielded_share=("circuit", np.array([beta]))))
    ladder = mk.CurrentModel(maps, motion_eddy=True)
    r_el, lt, k, _, _ = spline_point(maps, gap, cur)
    ds = maps.dataset
    r_a = float(ds["motion_eddy_jump_resistance_ohm"].values[0])
    l_u = float(ds["motion_eddy_unshielded_inductance_H"].values[0])
    r_2 = float(ds["motion_eddy_shielding_resistance_ohm"].values[0])
    f = np.geomspace(0.2, 2000.0, 25)
    cs, _, _, _ = linear_responses(ladder, f, gap, cur)
    ms, _, _ = _ladder(f, lt, k, r_el, r_a, l_u, r_2, beta=beta)
    m0, _, _ = _ladder(f, lt, k, r_el, r_a, l_u, r_2)
    assert np.max(np.abs(cs / ms - 1.0)) < 1e-9        # AD vs algebra: rounding only
    assert np.max(np.abs(m0 / ms - 1.0)) > 1e-2        # beta matters at these frequencies
    # p -> oo: the jump; at 1e9 Hz the remaining 1/p terms are ~1e-6 of it
    hi, _, _ = _ladder([1e9], lt, k, r_el, r_a, l_u, r_2, beta=beta)
    jump = -beta * k / ((1.0 + r_el / r_a) * l_u)
    assert hi[0] == pytest.approx(jump, rel=1e-5)
    assert unshielded_share(jump, dpsi_ds_Wb_per_m=k, resistance_ohm=r_el,
                            jump_resistance_ohm=r_a,
                            unshielded_inductance_H=l_u) == pytest.approx(beta, rel=1e-12)


def test_force_share_in_the_model_the_closed_form_and_the_bank(u_maps: CharacteristicMaps
                                                              ) -> None:
    """A force share ``gamma`` (force ``F(s, I_L + gamma I_e)``): the AD linearisation's
    gap -> force and voltage -> force equal the closed forms with it; as ``f -> oo`` the
    gap -> force tends to the jump that :func:`force_share` inverts; the bank's kernel
    gives CurrentModel's force; the steady state's force is the statics' (``I_e = 0``)."""
    from maglevkit.reduced.bank import MagnetBank

    gap, cur, beta, gamma = 0.0093, 23.0, 0.05, -0.3
    maps = CharacteristicMaps(u_maps.dataset.assign(
        motion_eddy_unshielded_share=("circuit", np.array([beta])),
        **{FORCE_SHARE_VARIABLE: ("circuit", np.array([gamma]))}))
    ladder = mk.CurrentModel(maps, motion_eddy=True)
    r_el, lt, k, dfi, dfs = spline_point(maps, gap, cur)
    ds = maps.dataset
    r_a = float(ds["motion_eddy_jump_resistance_ohm"].values[0])
    l_u = float(ds["motion_eddy_unshielded_inductance_H"].values[0])
    r_2 = float(ds["motion_eddy_shielding_resistance_ohm"].values[0])
    a = 1.0 + r_el / r_a
    resp = DetailedFrequencyResponse(np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1), lt,
                                     k, dforce_dcurrent_N_per_A=dfi, dforce_dgap_N_per_m=dfs)
    f = np.geomspace(0.2, 2000.0, 25)
    _, fs, _, _ = linear_responses(ladder, f, gap, cur)
    ms, il, _ = _ladder(f, lt, k, r_el, r_a, l_u, r_2, beta=beta)
    closed = ladder_force_response(resp, il, a * ms - il, gamma)
    assert np.max(np.abs(fs / closed - 1.0)) < 1e-9        # AD vs algebra: rounding only
    # gamma matters: F(s, I_L) differs by far more than the rounding
    assert np.max(np.abs(ladder_force_response(resp, il) / closed - 1.0)) > 1e-2
    # voltage -> force: dF/dI (dI_L + gamma dI_e) per volt
    lin = ladder.linearize(gap_m=gap, current_A=cur)
    n = lin.A_per_s.shape[0]
    fu = np.array([(lin.C_force_N_per_A @ np.linalg.solve(2j * np.pi * fk * np.eye(n)
                                                          - lin.A_per_s,
                                                          lin.B_A_per_V_s[:, 0]))[0]
                   for fk in f])
    vil, vie = ladder_voltage_currents(f, differential_inductance_H=lt, resistance_ohm=r_el,
                                       jump_resistance_ohm=r_a, unshielded_inductance_H=l_u,
                                       shielding_resistance_ohm=r_2)
    assert np.max(np.abs(fu / (dfi * (vil + gamma * vie)) - 1.0)) < 1e-9
    # p -> oo: the held-flux jump; at 1e9 Hz the remaining 1/p terms are ~1e-6 of it
    hs, hil, _ = _ladder([1e9], lt, k, r_el, r_a, l_u, r_2, beta=beta)
    jump = complex(ladder_force_response(resp, hil, a * hs - hil, gamma)[0]).real
    assert force_share(jump, differential_inductance_H=lt, dpsi_ds_Wb_per_m=k,
                       dforce_dcurrent_N_per_A=dfi, dforce_dgap_N_per_m=dfs,
                       unshielded_inductance_H=l_u, beta=beta) == pytest.approx(gamma, rel=1e-5)
    # the bank's compiled kernel and CurrentModel agree on the force (bicubic tables vs
    # B-splines: ~1e-12 relative on these maps)
    st = ladder.initial_state(gaps_m=0.010, currents_A=20.0)
    st = dataclasses.replace(st, eddy_currents_A=np.array([0.7]))
    u = 26.0 * r_el
    ref = mk.simulate(ladder, (0.0, 0.01), dt_s=1e-3, gaps_m=lambda t: 0.010 + 0.05 * t,
                      voltages_V=u, initial_state=st)
    bank = MagnetBank({"m": ladder}, compiled="never")
    b0 = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    b0 = dataclasses.replace(b0, eddy_currents_A=np.array([0.7]))
    sim = bank.simulate((0.0, 0.01), dt_s=1e-3, gaps_m=lambda t: 0.010 + 0.05 * t,
                        voltages_V=u, initial_state=b0)
    assert np.max(np.abs(sim.member_force_N[:, 0] - ref.force_N) / np.abs(ref.force_N)) < 1e-9
    # at rest (I_e = 0) the force is the statics' map value whatever gamma
    out0 = ladder.outputs(ladder.initial_state(gaps_m=0.010, currents_A=20.0))
    out_old = mk.CurrentModel(u_maps, motion_eddy=True).outputs(
        mk.CurrentModel(u_maps, motion_eddy=True).initial_state(gaps_m=0.010, currents_A=20.0))
    assert out0.force_N == out_old.force_N


@pytest.mark.parametrize(("name", "gap", "current"), [
    ("u-magnet", 0.010, 20.0),
    pytest.param("tr09-standard", 0.011, 40.0, marks=pytest.mark.slow),   # ~8 s loaded
])
def test_jumps_against_a_microsecond_gap_ramp_of_the_flux_dae(name: str, gap: float,
                                                              current: float) -> None:
    """The detailed model's instantaneous gap -> force jump ``J`` (which fixes ``gamma``)
    and gap -> current jump ``D`` (which fixes ``beta``), from the AD linearisation's
    ``-[force_z g_z^-1 g_w + force_w]``, against an independent computation: IDAS
    integrating the flux DAE over a 0.1 um ramp of one circuit's gaps in 0.1 us at the
    steady state's voltage, fluxes and eddy fluxes having no time to move (the eddy time
    constants are ms).  Measured: U-magnet J 0.04 %; split TR09 (11 mm / 40 A, the
    ladder's identification point, J = -527 N/mm) J 0.005 %, D 0.04 %; bound 0.5 % (the
    ramp's own flux change ~T/tau ~1e-4 and IDAS's tolerances)."""
    from maglevkit.models.statics import circuit_pole_groups
    from maglevkit.reduction.motion_eddy import detailed_frequency_response

    mag = mk.load_magnet(name)
    net = mag.network
    groups = circuit_pole_groups(net, gap_m=gap, current_A=current)
    resp = detailed_frequency_response(net, gap=gap, current=current, groups=groups)[0]
    own = np.array([g in next(iter(groups.values())) for g in net.gap_names], dtype=float)
    ds, dt = 1e-7, 1e-7
    r_el = np.asarray(net.resistances, dtype=float)
    sim = mk.simulate(mk.FluxModel(mag), np.array([0.0, 0.5 * dt, dt]),
                      gaps_m=lambda t: gap + ds * min(t / dt, 1.0) * own,
                      voltages_V=r_el * current, initial_currents_A=current)
    force = np.asarray(sim.pole_force_N)[:, own > 0].sum(axis=1)
    assert (force[-1] - force[0]) / ds == pytest.approx(resp.gap_force_jump_N_per_m, rel=5e-3)
    # the held-flux stiffness is far from the statics' (what makes gamma matter)
    assert abs(resp.gap_force_jump_N_per_m) < 0.2 * abs(resp.dforce_dgap_N_per_m)
    if name == "tr09-standard":      # the lumped U-magnet's D is ~1e-11 A/m: nothing to see
        coil = np.asarray(sim.currents_A)[:, 0]
        assert (coil[-1] - coil[0]) / ds == pytest.approx(resp.gap_current_jump_A_per_m,
                                                          rel=5e-3)


def test_built_maps_keep_the_held_flux_share_aside(u_maps: CharacteristicMaps) -> None:
    """``build_maps`` stores the derived ``gamma`` in its own variable and uses 0;
    ``with_held_flux_force`` puts it in use, in a copy; maps without it are refused by
    name."""
    from maglevkit.errors import InputError
    from maglevkit.reduction.motion_eddy import HELD_FLUX_FORCE_SHARE_VARIABLE

    ds = u_maps.dataset
    assert np.all(ds[FORCE_SHARE_VARIABLE].values == 0.0)
    held = np.asarray(ds[HELD_FLUX_FORCE_SHARE_VARIABLE].values, dtype=float)
    assert np.all(np.isfinite(held))
    # the u-magnet's derived share (-1.2) costs its voltage steps too much: stored as 0,
    # and asking for it says so
    assert np.all(held == 0.0)
    with pytest.warns(mk.MaglevkitWarning, match="kept no held-flux force share"):
        used = u_maps.with_held_flux_force()
    assert np.array_equal(used.dataset[FORCE_SHARE_VARIABLE].values, held)
    assert np.all(u_maps.dataset[FORCE_SHARE_VARIABLE].values == 0.0)   # the original kept
    gamma = np.array([-0.2])
    planted = CharacteristicMaps(ds.assign(**{HELD_FLUX_FORCE_SHARE_VARIABLE:
                                              ("circuit", gamma)})).with_held_flux_force()
    from maglevkit.reduced.core import MotionEddyLadder

    lad = MotionEddyLadder.from_maps(planted,
                                     resistance_ohm=np.asarray(ds["resistance_ohm"].values))
    assert lad.force_share[0] == -0.2
    with pytest.raises(InputError, match=HELD_FLUX_FORCE_SHARE_VARIABLE):
        CharacteristicMaps(ds.drop_vars(HELD_FLUX_FORCE_SHARE_VARIABLE)).with_held_flux_force()


def test_maps_without_a_force_share_read_as_zero(u_maps: CharacteristicMaps) -> None:
    """Maps built before ``gamma`` (no ``motion_eddy_force_share``) are read with
    ``gamma = 0``: the force ``F(s, I_L)``, bit-identical to maps that hold 0."""
    ds = u_maps.dataset
    old = CharacteristicMaps(ds.drop_vars(FORCE_SHARE_VARIABLE))
    zero = CharacteristicMaps(ds.assign(**{FORCE_SHARE_VARIABLE: ("circuit", np.zeros(1))}))
    st = mk.CurrentModel(old, motion_eddy=True).initial_state(gaps_m=0.010, currents_A=20.0)
    st = dataclasses.replace(st, eddy_currents_A=np.array([0.7]))
    runs = [mk.simulate(mk.CurrentModel(m, motion_eddy=True), (0.0, 0.01), dt_s=1e-3,
                        gaps_m=lambda t: 0.010 + 0.05 * t, voltages_V=30.0, initial_state=st)
            for m in (old, zero)]
    assert np.array_equal(runs[0].force_N, runs[1].force_N)
    assert np.array_equal(runs[0].currents_A, runs[1].currents_A)


def test_freewheel_diodes_on_ladder_members(u_maps: CharacteristicMaps) -> None:
    """``MagnetBank(..., motion_eddy=True, freewheel=True)``: while the commanded voltage
    keeps the coil current positive the diodes do nothing (bit-identical to
    ``freewheel=False``); a large negative voltage from 20 A drives the coil current to 0
    and holds it there (never below), and the states follow an independent integration of
    CurrentModel's ladder ODE with the diode law written from Fig. 8
    (:func:`_check_against_the_diode_reference`)."""
    from maglevkit.reduced.bank import MagnetBank

    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    r_el = float(cm.resistance_ohm[0])
    r_a = float(u_maps.dataset["motion_eddy_jump_resistance_ohm"].values[0])
    t = np.arange(0, 201) * 5e-5
    plain = MagnetBank({"m": u_maps}, motion_eddy=True, compiled="never")
    diode = MagnetBank({"m": u_maps}, motion_eddy=True, freewheel=True, compiled="never")
    assert diode.motion_eddy and diode.freewheel
    gaps = (0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t))[:, None]
    runs = [b.simulate(t, gaps_m=gaps, voltages_V=22.0 * r_el, initial_currents_A=20.0)
            for b in (plain, diode)]
    assert np.array_equal(runs[0].currents_A, runs[1].currents_A)
    assert np.array_equal(runs[0].member_force_N, runs[1].member_force_N)
    # switching off: -300 V from 20 A at 10 mm (the coil current would reverse in ~1 ms)
    u_cmd = -300.0
    sim = diode.simulate(t, gaps_m=0.010, voltages_V=u_cmd, initial_currents_A=20.0)
    assert sim.eddy_currents_A is not None
    coil = sim.currents_A[:, 0]
    assert coil.min() >= -1e-9            # the diodes hold I >= 0 (rounding only)
    assert np.sum(coil < 1e-9) > 100      # and it reached 0 and stayed there
    # without diodes the coil current reverses (within the maps' I_L range: 2.5 ms)
    free = plain.simulate(t[:51], gaps_m=0.010, voltages_V=u_cmd, initial_currents_A=20.0)
    assert free.currents_A[-1, 0] < -1.0

    _check_against_the_diode_reference(cm, r_a, u_cmd, t, sim.inductor_currents_A[:, 0],
                                       sim.eddy_currents_A[:, 0])


def _check_against_the_diode_reference(cm: mk.CurrentModel, r_a: float, u_cmd: float,
                                       t: np.ndarray, i_l: np.ndarray, i_e: np.ndarray) -> None:
    """``I_L``, ``I_e`` [A] on ``t`` [s] of a ladder switched off with ``u_cmd`` [V] from
    20 A at a fixed 10 mm gap, against an independent LSODA integration of
    ``CurrentModel``'s ladder ODE (``cm``: ``motion_eddy=True`` without diodes) with the
    diode law written here from Fig. 8: the coil current ``(U/R_a + I_L + I_e)/a`` held at
    0 gives ``U = -R_a (I_L + I_e)``."""
    from scipy.integrate import solve_ivp

    assert cm.motion_eddy and not cm.freewheel

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        u = max(u_cmd, -r_a * (x[0] + x[1]))          # the diodes (Fig. 8's coil current)
        d_il, d_ie = cm.ode(x[0], u, 0.010, 0.0, x[1])
        return np.array([float(d_il), float(d_ie)])

    ref = solve_ivp(rhs, (0.0, t[-1]), [20.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-10,
                    method="LSODA")
    # RK4 at 50 us (sub-steps below the ladder's stable step): in the step where the
    # diodes start to conduct the kink makes it first order (measured 5.8 mA on I_e's
    # 13 A there), elsewhere ~1e-4 A; bounds 2e-2 A (the kink) and 1e-3 A (the median)
    for got, want in ((i_l, ref.y[0]), (i_e, ref.y[1])):
        assert np.max(np.abs(got - want)) < 2e-2
        assert np.median(np.abs(got - want)) < 1e-3


def test_freewheel_diodes_on_the_single_magnet_ladder(u_maps: CharacteristicMaps) -> None:
    """``CurrentModel(maps, motion_eddy=True, freewheel=True)`` (both ``lookup`` values;
    the ladder runs on the B-splines): ``simulate`` and ``step`` equal the bank with
    ``motion_eddy=True, freewheel=True`` on the same inputs, follow the same independent
    LSODA reference as the bank, hold the coil current at >= 0, and are bit-identical to
    ``freewheel=False`` while the diodes block."""
    from maglevkit.reduced.bank import MagnetBank

    plain = mk.CurrentModel(u_maps, motion_eddy=True)
    r_el = float(plain.resistance_ohm[0])
    r_a = float(u_maps.dataset["motion_eddy_jump_resistance_ohm"].values[0])
    t = np.arange(0, 201) * 5e-5
    gap = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t)
    poles = np.repeat(gap[:, None], 2, axis=1)         # the U-magnet's two pole gaps
    bank = MagnetBank({"m": u_maps}, motion_eddy=True, freewheel=True, compiled="never")
    u_cmd = -300.0                 # switching off from 20 A: the diodes conduct in ~1 ms
    for lookup in ("tables", "bspline"):
        diode = mk.CurrentModel(u_maps, motion_eddy=True, freewheel=True, lookup=lookup)
        assert diode.freewheel and diode.max_step_s == bank.max_step_s
        # diodes blocking (the coil current stays near 20 A): bit-identical to no diodes
        runs = [m.simulate(t, gaps_m=poles, voltages_V=22.0 * r_el, initial_currents_A=20.0)
                for m in (plain, diode)]
        for name in ("currents_A", "inductor_currents_A", "eddy_currents_A", "force_N"):
            assert np.array_equal(getattr(runs[0], name), getattr(runs[1], name)), name
        # the bank on the same inputs: the same ladder ODE, diode law, RK4 sub-steps
        # (both at the ladder's stable step) and bicubic maps (the bank's cell tables
        # hold the B-spline's polynomials), so only rounding differs: measured 1.4e-14 A
        # and 3e-11 N (2e-14 relative); bounds 1e-12 A and 1e-12 relative on the force
        for g_cm, g_bank in ((poles, gap[:, None]), (0.010, 0.010)):
            sim = diode.simulate(t, gaps_m=g_cm, voltages_V=u_cmd, initial_currents_A=20.0)
            ref = bank.simulate(t, gaps_m=g_bank, voltages_V=u_cmd, initial_currents_A=20.0)
            assert sim.eddy_currents_A is not None and ref.eddy_currents_A is not None
            for got, want in ((sim.currents_A, ref.currents_A),
                              (sim.inductor_currents_A, ref.inductor_currents_A),
                              (sim.eddy_currents_A, ref.eddy_currents_A)):
                np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
            np.testing.assert_allclose(sim.force_N, ref.member_force_N[:, 0], rtol=1e-12)
            coil = sim.currents_A[:, 0]
            assert coil.min() >= -1e-9            # the diodes hold I >= 0 (rounding only)
            assert np.sum(coil < 1e-9) > 100      # and it reached 0 and stayed there
        # the last run (fixed 10 mm) against the bank test's independent reference
        _check_against_the_diode_reference(plain, r_a, u_cmd, t, sim.inductor_currents_A[:, 0],
                                           sim.eddy_currents_A[:, 0])
        # step: the same numbers as simulate, and as the bank's step (bound as above)
        st = diode.initial_state(gaps_m=0.010, currents_A=20.0)
        bs = bank.initial_state(gaps_m=0.010, currents_A=20.0)
        for k in range(1, 41):
            st, out = diode.step(st, 5e-5, u_cmd, 0.010)
            bs, bout = bank.step(bs, 5e-5, u_cmd, 0.010)
            assert abs(out.currents_A[0] - sim.currents_A[k, 0]) < 1e-12
            assert abs(out.currents_A[0] - bout.currents_A[0]) < 1e-12
        assert st.eddy_currents_A is not None
        assert abs(st.eddy_currents_A[0] - sim.eddy_currents_A[40, 0]) < 1e-12


def test_vanishing_unshielded_inductance_gives_eq8() -> None:
    """``L_u -> 0``: the ladder is eq. 8 with ``R_ec = R_a || R_2`` (transfer functions and
    the right-hand side on its slow manifold)."""
    lt, k, r_el, r_a, r_2 = 0.5, -1100.0, 1.3, 5.8, 14.0
    r_ec = r_a * r_2 / (r_a + r_2)
    a = 1.0 + r_el / r_ec
    f = np.geomspace(0.1, 1000.0, 30)
    p = 2j * np.pi * f
    gs, _, gu = _ladder(f, lt, k, r_el, r_a, 1e-12, r_2)
    eq8_s = -k * p / (a * (lt * p + r_el / a))
    eq8_u = (1.0 - 1.0 / a) / r_el + 1.0 / (a * a * (lt * p + r_el / a))
    # the neglected time constant L_u/(R_el/a + R_2) ~ 7e-14 s: relative effect < 1e-9
    assert np.max(np.abs(gs / eq8_s - 1.0)) < 1e-9
    assert np.max(np.abs(gu / eq8_u - 1.0)) < 1e-9
    # on the slow manifold (dI_e/dt = 0 for L_u -> 0) dI_L/dt is eq. 8's
    i_l, u, sd = 20.0, 30.0, 0.05
    a_l = 1.0 + r_el / r_a
    # I_e from V_A = V_m (no drop across L_u)
    i_e = (u - r_el * i_l) / (a_l * r_2 + r_el)
    d_il, _ = eq8_shielded_gap_rhs(i_l, i_e, u, sd, lt, k / i_l, r_el, a_l, r_2, 1e-12, 0.0)
    # L~ - L_u differs from L~ by 2e-12 relative
    assert d_il == pytest.approx(((u - r_el * i_l) / a - k * sd) / lt, rel=1e-10)


def test_fit_recovers_a_known_ladder() -> None:
    lt, k, r_el = 0.54, -1140.0, 1.3
    true = (5.77, 0.0226, 14.7)
    f = np.geomspace(0.1, 1000.0, 60)
    gs, il, gu = _ladder(f, lt, k, r_el, true[0], true[1], true[2])
    resp = DetailedFrequencyResponse(f, gs, il * 0.0, gu, lt, k)
    fit = fit_motion_eddy(resp, resistance_ohm=r_el,
                          eddy_resistance_jump_ohm=5.0, eddy_resistance_fit_ohm=4.0)
    got = (fit.jump_resistance_ohm, fit.unshielded_inductance_H, fit.shielding_resistance_ohm)
    # noise-free data: the fit stops at its tolerance (1e-12), far below 1e-6
    assert np.allclose(got, true, rtol=1e-6)
    assert fit.rms_residual < 1e-8 and fit.max_gap_error < 1e-7


def test_fit_recovers_a_ladder_with_an_unshielded_share_from_all_three_responses() -> None:
    """A known ladder with ``beta`` (the split TR09 network's size: 7 ohm, 93 mH, 74 ohm,
    2 %), its force ``dF/dI I_L + dF/ds`` and its exact gap jump: the fit (force included,
    ``beta`` from the jump, ``L_u`` below a bound) gives it back."""
    lt, k, r_el, dfi, dfs = 0.607, -1265.0, 1.3, 1265.0, -3.49e6
    r_a, l_u, r_2, beta = 6.98, 0.093, 74.0, 0.02
    f = np.geomspace(0.1, 1000.0, 60)
    gs, il, gu = _ladder(f, lt, k, r_el, r_a, l_u, r_2, beta=beta)
    jump = -beta * k / ((1.0 + r_el / r_a) * l_u)
    resp = DetailedFrequencyResponse(f, gs, dfi * il + dfs, gu, lt, k, jump, dfi, dfs)
    fit = fit_motion_eddy(resp, resistance_ohm=r_el,
                          eddy_resistance_jump_ohm=8.2, eddy_resistance_fit_ohm=4.8,
                          max_unshielded_inductance_H=0.11, fit_force=True)
    got = (fit.jump_resistance_ohm, fit.unshielded_inductance_H, fit.shielding_resistance_ohm,
           fit.unshielded_share)
    # noise-free data: the fit stops at its tolerance (1e-12), far below 1e-6
    assert np.allclose(got, (r_a, l_u, r_2, beta), rtol=1e-6)
    assert fit.rms_residual < 1e-8 and fit.max_force_error < 1e-7
    # the bound holds: below the true L_u the fit cannot reach it and says so by its residual
    low = fit_motion_eddy(resp, resistance_ohm=r_el,
                          eddy_resistance_jump_ohm=8.2, eddy_resistance_fit_ohm=4.8,
                          max_unshielded_inductance_H=0.05, fit_force=True)
    assert low.unshielded_inductance_H < 0.05 and low.rms_residual > 1e-3


def _old(maps: CharacteristicMaps) -> CharacteristicMaps:
    """The maps as the previous version stored them (no motion_eddy_* variables)."""
    return CharacteristicMaps(maps.dataset.drop_vars(
        [v for v in maps.dataset.data_vars if str(v).startswith("motion_eddy_")]))


def test_default_is_unchanged(u_maps: CharacteristicMaps) -> None:
    """motion_eddy=False (the default) and maps without the new variables give
    bit-identical results."""
    models = [mk.CurrentModel(u_maps), mk.CurrentModel(u_maps, motion_eddy=False),
              mk.CurrentModel(_old(u_maps))]
    runs = [mk.simulate(m, (0.0, 0.1), dt_s=1e-3,
                        gaps_m=lambda t: 0.010 + 0.001 * np.sin(2 * np.pi * 5 * t),
                        voltages_V=lambda t: 40.0 if t < 0.02 else 48.0, initial_currents_A=20.0)
            for m in models]
    for r in runs[1:]:
        assert np.array_equal(r.currents_A, runs[0].currents_A)
        assert np.array_equal(r.force_N, runs[0].force_N)
        assert r.eddy_currents_A is None
    assert models[0].max_step_s == 1e-3


def test_motion_eddy_step_simulate_and_state(u_maps: CharacteristicMaps) -> None:
    model = mk.CurrentModel(u_maps, motion_eddy=True)
    st = model.initial_state(gaps_m=0.010, currents_A=20.0)
    assert st.eddy_currents_A is not None and st.eddy_currents_A.shape == (1,)
    assert np.all(st.eddy_currents_A == 0.0)
    # steady state stays (I_e = 0, I = I_L)
    st1, out = model.step(st, 1e-3, 20.0 * model.resistance_ohm)
    assert out.currents_A[0] == pytest.approx(20.0, rel=1e-12)
    assert abs(st1.eddy_currents_A[0]) < 1e-12
    # step and simulate agree (same compiled interval)
    u = 22.0 * float(model.resistance_ohm[0])
    res = mk.simulate(model, (0.0, 0.01), dt_s=1e-3, gaps_m=0.010, voltages_V=u,
                      initial_state=st)
    s = st
    for _ in range(10):
        s, o = model.step(s, 1e-3, u)
    assert np.allclose(res.final_state.eddy_currents_A, s.eddy_currents_A, rtol=1e-12,
                       atol=1e-15)
    assert res.currents_A[-1, 0] == pytest.approx(o.currents_A[0], rel=1e-12)
    assert res.eddy_currents_A is not None and res.eddy_currents_A.shape == (11, 1)
    # the jump of a voltage step is the shunt's, dU/(R_el + R_a)
    lin = model.linearize(gap_m=0.010, current_A=20.0)
    r_a = float(u_maps.dataset["motion_eddy_jump_resistance_ohm"].values[0])
    assert lin.D_current_A_per_V[0, 0] == pytest.approx(
        1.0 / (float(model.resistance_ohm[0]) + r_a), rel=1e-12)


def test_bad_input(u_maps: CharacteristicMaps) -> None:
    with pytest.raises(mk.InputError, match="motion_eddy = 'yes'.*False.*True"):
        mk.CurrentModel(u_maps, motion_eddy="yes")  # type: ignore[arg-type]
    with pytest.raises(mk.InputError, match="eddy_modes=1.*one of them"):
        mk.CurrentModel(u_maps, motion_eddy=True, eddy_modes=1)
    with pytest.raises(mk.InputError, match="eddy_resistance = 'jump'.*leave"):
        mk.CurrentModel(u_maps, motion_eddy=True, eddy_resistance="jump")
    with pytest.raises(mk.InputError, match="motion_eddy_.*rebuild"):
        mk.CurrentModel(_old(u_maps), motion_eddy=True)
    model = mk.CurrentModel(u_maps, motion_eddy=True)
    with pytest.raises(mk.InputError, match="eddy state.*eddy_currents_A"):
        model.step(mk.CurrentModel(u_maps).initial_state(gaps_m=0.01, currents_A=20.0), 1e-3, 40.0)
    from maglevkit.reduced.bank import MagnetBank

    # the bank carries the ladder now (tests/test_bank_motion_eddy.py)
    assert MagnetBank({"m": model}, compiled="never").motion_eddy
    no_eddy = mk.build_maps(mk.load_magnet("u-magnet", eddy_currents=False), gaps_m=GAPS,
                            currents_A=CURRENTS, progress=False)
    assert np.all(np.isnan(no_eddy.dataset["motion_eddy_unshielded_inductance_H"].values))
    with pytest.raises(mk.InputError, match="no eddy currents.*motion_eddy=False"):
        mk.CurrentModel(no_eddy, motion_eddy=True)


def _gap_sine_sweep(mag: mk.Magnet, frequencies: tuple[float, ...], current_A: float = 34.0,
                    *, held_flux_force: bool = False
                    ) -> dict[float, tuple[float, float, float]]:
    """Per frequency: the ladder's current error and force error relative to the
    detailed model's variation, and its current phase error [deg] against the gap sine
    10 +- 1 mm at the constant voltage of ``current_A`` (``benchmarks/bench_gap_motion.py``'s
    run; maps 12 x 41, identified at their reference point 11 mm / 40 A); with
    ``held_flux_force`` on ``maps.with_held_flux_force()``."""
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.005, 0.016, 12),
                         currents_A=np.linspace(0.0, 80.0, 41), progress=False)
    if held_flux_force:
        maps = maps.with_held_flux_force()
    fm = mk.FluxModel(mag)
    ladder = mk.CurrentModel(maps, motion_eddy=True)
    u0 = fm.resistances * current_A
    out = {}
    for f in frequencies:
        dur, dt = max(2.0 / f, 0.1), min(1.0 / (100 * f), 1e-3)

        def gaps(t: np.ndarray, f: float = f) -> np.ndarray:
            return 0.010 + 1e-3 * np.sin(2 * np.pi * f * t)

        det = mk.simulate(fm, (0.0, dur), dt_s=dt, gaps_m=gaps, voltages_V=u0)
        red = mk.simulate(ladder, (0.0, dur), dt_s=dt, gaps_m=gaps, voltages_V=u0)
        cd, cr = det.currents_A, red.currents_A
        err = np.sqrt(np.mean((cr - cd) ** 2)) / np.sqrt(np.mean((cd - cd.mean(0)) ** 2))
        fd, fr = det.pole_force_N.sum(axis=1), red.force_N
        err_f = np.sqrt(np.mean((fr - fd) ** 2)) / np.sqrt(np.mean((fd - fd.mean()) ** 2))
        t = det.time_s
        last = t >= t[-1] - 1.0 / f * max(1, math.floor(f * dur / 2))
        w = 2 * np.pi * f
        basis = np.column_stack([np.ones(last.sum()), t[last], np.sin(w * t[last]),
                                 np.cos(w * t[last])])
        zd, zr = (np.linalg.lstsq(basis, y[last, 0], rcond=None)[0] for y in (cd, cr))
        phase = math.degrees(math.atan2(zr[3], zr[2]) - math.atan2(zd[3], zd[2]))
        out[f] = (float(err), float(err_f), phase)
    return out


AIMS = {5.0: 0.05, 50.0: 0.10, 200.0: 0.20}
"""Issue 26's aims for the current error relative to its variation (phase within 5 deg up
to 100 Hz)."""


def test_tr09_gap_sine_sweep_against_the_detailed_model() -> None:
    """The issue's aims on tr09-standard (gap sine 10 +- 1 mm, constant voltage of 34 A):
    current error relative to its variation <= 5 / 10 / 20 % at 5 / 50 / 200 Hz, phase
    within 5 deg (measured 0.5 / 3.3 / 5.6 %, 0.4 / 0.6 / 2.9 deg; eq. 8: 4.9 / 43 / 161 %,
    docs/decisions.md); the force error shrinks with it (measured 0.3 / 0.9 / 1.0 %)."""
    # the lumped "paper" network, loaded explicitly (the bundled file is split since issue
    # 26): its force bound (3 %) does not hold on split (23.9 % at 50 Hz), whose sweep is
    # the slow test below
    for f, (err, err_f, phase) in _gap_sine_sweep(paper_tr09("tr09-standard"),
                                                  tuple(AIMS)).items():
        assert err <= AIMS[f], (f, err)
        assert err_f <= 0.03, (f, err_f)      # measured <= 1.0 %, eq. 8 6.5-14 % above 50 Hz
        if f <= 100.0:
            assert abs(phase) <= 5.0, (f, phase)


FORCE_AIMS = {5.0: 0.05, 50.0: 0.10, 200.0: 0.20}
"""The force aims of gapforce26 (docs/reduction.md, "Gap motion"): the force error relative
to its variation at 5 / 50 / 200 Hz."""


@pytest.mark.slow
def test_split_tr09_gap_sine_sweep_against_its_detailed_model() -> None:
    """The same sweep on the split TR09 network (``flux_paths = "split"``, 59 eddy elements)
    at the bundled file's nominal 31.7 A, as ``make bench`` (bench_gap_motion) runs it.
    Current within the aims (measured 2.8 / 7.0 / 2.9 %, phase -1.3 / +0.7 deg at 5 / 50
    Hz; eq. 8: 1.8 / 24.8 / 94.9 %); on ``maps.with_held_flux_force()`` the force within
    its aims 5 / 10 / 20 % (F(s, I_L + gamma I_e), gamma = -0.142 from the held-flux
    stiffness; measured 3.2 / 6.2 / 8.5 %; with the default gamma = 0 on the same maps
    17.8 / 38.7 % at 50 / 200 Hz; eq. 8: 2.7 / 20.3 / 46.4 %)."""
    # split since issue 26; its lumped eddy elements, as measured (the bundled file builds
    # the eddy ladder since switch26m: tests/test_gap_sweep_default.py)
    mag = mk.load_magnet("tr09-standard", eddy_model="lumped")
    assert mag.network.n_loops > 200          # the split network, not the lumped one
    assert mag.nominal_current == 31.7
    for f, (err, err_f, phase) in _gap_sine_sweep(mag, tuple(AIMS), mag.nominal_current,
                                                  held_flux_force=True).items():
        assert err <= AIMS[f], (f, err)
        assert err_f <= FORCE_AIMS[f], (f, err_f)
        if f <= 100.0:
            assert abs(phase) <= 5.0, (f, phase)
    # the default maps (gamma = 0): the current's aims hold as well; the force does not
    # follow above ~10 Hz (measured 17.8 % at 50 Hz, more than the 10 % aim)
    default = _gap_sine_sweep(mag, (50.0,), mag.nominal_current)[50.0]
    assert default[0] <= AIMS[50.0], default
    assert default[1] > FORCE_AIMS[50.0], default


def test_a_fit_that_does_not_converge_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    import scipy.optimize

    lt, k, r_el = 0.54, -1140.0, 1.3
    f = np.geomspace(0.1, 1000.0, 60)
    gs, il, gu = _ladder(f, lt, k, r_el, 5.77, 0.0226, 14.7)
    resp = DetailedFrequencyResponse(f, gs, il * 0.0, gu, lt, k)
    real = scipy.optimize.least_squares
    monkeypatch.setattr(scipy.optimize, "least_squares",
                        lambda *a, **kw: real(*a, **{**kw, "max_nfev": 1}))
    with pytest.warns(mk.MaglevkitWarning, match="ladder fit did not converge"):
        fit_motion_eddy(resp, resistance_ohm=r_el,
                                  eddy_resistance_jump_ohm=5.0, eddy_resistance_fit_ohm=4.0)


@pytest.mark.parametrize(("key", "value", "needle"), [
    ("jump_resistance_ohm", 0.0, "jump_resistance_ohm = 0.0 must be > 0"),
    ("resistance_ohm", -1.0, "resistance_ohm = -1.0 must be >= 0"),
    ("dpsi_ds_Wb_per_m", float("nan"), "dpsi_ds_Wb_per_m = nan must be finite"),
])
def test_unshielded_share_refuses_bad_input(key: str, value: float, needle: str) -> None:
    """``R_a = 0`` was a ZeroDivisionError (review3): now an InputError naming the argument."""
    from maglevkit.errors import InputError

    kw = {"dpsi_ds_Wb_per_m": -50.0, "resistance_ohm": 1.0, "jump_resistance_ohm": 8.0,
          "unshielded_inductance_H": 0.02, key: value}
    with pytest.raises(InputError, match=needle.replace("(", r"\(")):
        unshielded_share(230.0, **kw)



def test_old_keyword_names_are_deprecated_aliases() -> None:
    """The unit-less keywords of the ladder's functions still work for one release: the
    same result, with a DeprecationWarning that names the new keyword."""
    f, lt, k, r_el, r_a, l_u, r_2 = np.array([1.0, 50.0]), 0.5, -40.0, 1.2, 6.0, 0.02, 15.0
    new = _ladder(f, lt, k, r_el, r_a, l_u, r_2, beta=0.1)
    with pytest.warns(DeprecationWarning, match="ltilde= is deprecated, use "
                                                "differential_inductance_H=.*r_2= is deprecated, "
                                                "use shielding_resistance_ohm="):
        old = ladder_frequency_response(f, ltilde=lt, dpsi_ds=k, r_el=r_el, r_a=r_a, l_u=l_u,
                                        r_2=r_2, beta=0.1)
    for a, b in zip(new, old, strict=True):
        assert np.array_equal(a, b)
    kw = {"dpsi_ds_Wb_per_m": k, "resistance_ohm": r_el, "unshielded_inductance_H": l_u}
    with pytest.warns(DeprecationWarning, match="shield_resistance_ohm= is deprecated, use "
                                                "jump_resistance_ohm="):
        b_old = unshielded_share(230.0, shield_resistance_ohm=r_a, **kw)
    assert b_old == unshielded_share(230.0, jump_resistance_ohm=r_a, **kw)
    fr = np.geomspace(0.1, 1000.0, 30)
    gs, il, gu = _ladder(fr, lt, k, r_el, r_a, l_u, r_2)
    resp = DetailedFrequencyResponse(fr, gs, il * 0.0, gu, lt, k)
    fit = fit_motion_eddy(resp, resistance_ohm=r_el, eddy_resistance_jump_ohm=5.0,
                          eddy_resistance_fit_ohm=4.0)
    with pytest.warns(DeprecationWarning, match="r_el= is deprecated, use resistance_ohm=; "
                                                "r_ec_jump= is deprecated, use "
                                                "eddy_resistance_jump_ohm="):
        fit_old = fit_motion_eddy(resp, r_el=r_el, r_ec_jump=5.0, r_ec_fit=4.0)
    # every field equal (NaN where the response has no force partials)
    assert np.array_equal(dataclasses.astuple(fit_old), dataclasses.astuple(fit), equal_nan=True)
