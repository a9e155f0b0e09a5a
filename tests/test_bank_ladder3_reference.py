"""The bank's three-state ladder with freewheeling diodes against an independent
integration of docs/equations.md section 8 (review6).

tests/test_bank_ladder3.py compares the bank with ``CurrentModel``, which evaluates the
same law functions (``eq8_shielded_gap3_rhs``, ``ladder3_force_current``,
``shielded_gap_freewheel_voltage``); a mistake in those would pass there.  Here the ladder
is written again from the docs, in its mesh currents ``(I_u, I_2, I_L)`` with the node
voltage ``V_A`` from Kirchhoff's current law at node A and the diode as ``I >= 0``, and
integrated by scipy's LSODA at 1e-11.  The maps' ``L~``, ``dL/ds`` and force are replaced
by bilinear functions of gap and current, which every cubic interpolant reproduces
exactly, so no interpolation stands between the two.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import maglevkit as mk
from maglevkit.reduced.bank import MagnetBank

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 40.0, 9)
T_END = 0.03


def _lt(s: np.ndarray, i: np.ndarray, lm: float) -> np.ndarray:
    """L~ [H]: bilinear in gap and current around the U-magnet's value at 10 mm / 20 A."""
    return lm * (1 - 30 * (s - 0.010)) * (1 - 0.004 * (i - 20))


def _dl(s: np.ndarray, i: np.ndarray, lm: float) -> np.ndarray:
    """dL/ds [H/m], the gap derivative of :func:`_lt`."""
    return -30 * lm * (1 - 0.004 * (i - 20)) + 0 * s


def _force(s: np.ndarray, i: np.ndarray, fm: float) -> np.ndarray:
    """F [N]: bilinear, ``fm`` at 10 mm / 20 A."""
    return fm * (i / 20) * (1 - 100 * (s - 0.010))


@pytest.fixture(scope="module")
def bilinear_maps() -> tuple[mk.CharacteristicMaps, float, float]:
    maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)
    ds = maps.dataset
    lm = float(ds["inductance_H"].sel(gap=0.010, current=20.0).values[0])
    fm = float(ds["force_N"].sel(gap=0.010, current=20.0).values[0])
    s, i = np.meshgrid(GAPS, CURRENTS, indexing="ij")
    dims = ("circuit", "gap", "current")
    ds = ds.assign(inductance_H=(dims, _lt(s, i, lm)[None]),
                   dL_ds_H_per_m=(dims, _dl(s, i, lm)[None]),
                   force_N=(dims, _force(s, i, fm)[None]))
    return mk.CharacteristicMaps(ds), lm, fm


def _gap(t: float) -> float:
    return 0.010 + 0.001 * np.sin(2 * np.pi * 50 * t)


def _voltage(t: float, r_el: float) -> float:
    # hold, a -1000 V command the diodes must clamp (the coil current would reverse
    # within a step), then a step up
    return r_el * 20.0 if t < 5e-3 else (-1000.0 if t < 12e-3 else r_el * 30.0)


def _errors(maps: mk.CharacteristicMaps, lm: float, fm: float, dt: float
            ) -> tuple[dict[str, float], int, float]:
    """Largest differences bank - reference over the run, the number of steps that ended
    with the diodes conducting, and the smallest coil current of the bank."""
    ds = maps.dataset

    def val(name: str) -> float:
        return float(ds[f"motion_eddy3_{name}"].values[0])

    r_el = float(ds["resistance_ohm"].values[0])
    r_a, l_u = val("jump_resistance_ohm"), val("unshielded_inductance_H")
    r_2, l_2 = val("shielding_resistance_ohm"), val("inner_inductance_H")
    r_3 = val("inner_shielding_resistance_ohm")
    beta, beta_2 = val("unshielded_share"), val("inner_share")
    c_1, c_2 = val("force_share_1"), val("force_share_2")

    def rhs(t: float, y: np.ndarray, u: float, g0: float, gd: float, t0: float) -> list[float]:
        i_u, i_2, i_l = y
        s = g0 + gd * (t - t0)
        # node A: (U - V_A)/R_el = V_A/R_a + I_u; the diodes keep (U - V_A)/R_el >= 0,
        # i.e. the terminal voltage is at least V_A's open-circuit value -R_a I_u
        u_eff = max(u, -r_a * i_u)
        v_a = (u_eff / r_el - i_u) / (1 / r_el + 1 / r_a)
        emf = _dl(s, i_l, lm) * i_l * gd
        return [(v_a - r_2 * (i_u - i_2) - beta * emf) / l_u,
                (r_2 * (i_u - i_2) - r_3 * (i_2 - i_l) - beta_2 * emf) / l_2,
                (r_3 * (i_2 - i_l) - (1 - beta - beta_2) * emf)
                / (_lt(s, i_l, lm) - l_u - l_2)]

    bank = MagnetBank({"m": maps}, motion_eddy=True, eddy_branches=2, freewheel=True,
                      compiled="never")
    st = bank.initial_state(gaps_m=_gap(0.0), currents_A=20.0)
    y = np.array([20.0, 20.0, 20.0])
    err = dict.fromkeys(("I_L", "I_e1", "I_e2", "I", "F"), 0.0)
    clamped, coil_min = 0, np.inf
    for k in range(int(round(T_END / dt))):
        t0 = k * dt
        u = _voltage(t0 + 0.5 * dt, r_el)
        g0 = _gap(t0)
        gd = (_gap(t0 + dt) - g0) / dt       # the bank's gap is linear over the step
        st, out = bank.step(st, dt, u, g0, gd)
        y = solve_ivp(rhs, (t0, t0 + dt), y, args=(u, g0, gd, t0), method="LSODA",
                      rtol=1e-11, atol=1e-11).y[:, -1]
        i_u, i_2, i_l = y
        u_eff = max(u, -r_a * i_u)
        clamped += u_eff > u
        coil = (u_eff / r_a + i_u) / (1 + r_el / r_a)
        force = _force(g0 + gd * dt, i_l + c_1 * (i_2 - i_l) + c_2 * (i_u - i_2), fm)
        assert st.eddy_currents_A is not None
        for key, got, want in (("I_L", st.inductor_currents_A[0], i_l),
                               ("I_e1", st.eddy_currents_A[0, 0], i_2 - i_l),
                               ("I_e2", st.eddy_currents_A[0, 1], i_u - i_2),
                               ("I", out.currents_A[0], coil),
                               ("F", out.circuit_force_N[0], force)):
            err[key] = max(err[key], abs(float(got) - float(want)))
        coil_min = min(coil_min, float(out.currents_A[0]))
    return err, clamped, coil_min


def test_three_state_bank_with_diodes_converges_to_the_independent_integration(
        bilinear_maps: tuple[mk.CharacteristicMaps, float, float]) -> None:
    maps, lm, fm = bilinear_maps
    bank = MagnetBank({"m": maps}, motion_eddy=True, eddy_branches=2, compiled="never")
    # both steps below are one RK4 sub-step each (the ladder's stable step is ~1.7e-4 s),
    # so halving the step halves the RK4 step
    assert bank.max_step_s > 1e-4
    coarse, n_coarse, _ = _errors(maps, lm, fm, 1e-4)
    fine, n_fine, coil_min = _errors(maps, lm, fm, 5e-5)
    # the diodes conducted over the -1000 V command (70 resp. 140 steps), holding the coil
    # current at 0 (rounding only)
    assert n_coarse >= 60 and n_fine >= 120
    assert coil_min > -1e-9
    # the same law: the differences are RK4's truncation, 4th order (measured ratios
    # 18-20, 2^4 = 16); a wrong term would leave an O(1) difference that does not shrink
    for key in fine:
        assert coarse[key] / fine[key] > 10.0, (key, coarse, fine)
    # and small: measured 2.8e-4 A on I_e2 (the eddy currents swing by ~8 A), 6e-6 A on
    # I_L, 1.0e-5 A on the coil current, 3e-3 N on ~1 kN; bounds 4x
    assert fine["I_e2"] < 1.2e-3 and fine["I_e1"] < 6e-4 and fine["I_L"] < 3e-5
    assert fine["I"] < 6e-5 and fine["F"] < 1.2e-2

