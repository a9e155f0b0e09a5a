"""Freewheeling diodes on eddy-network circuits (``eddy_modes`` with ``freewheel=True``;
docs/bank.md, "Eddy-network members"): the clamp ``U_eff = max(U, -R_0 (I_L + sum I_k))``
against an independent integration of the network written from the circuit, the bank
against ``CurrentModel``, and the refusal of ``R_0 = inf``.

The maps are ``tr09-standard`` with the diffusing eddy ladder on a small grid (fitted
``R_0`` 125 / 294 ohm for one / two branches: finite, so the clamp is exact).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.reduced.bank import MagnetBank

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 60.0, 7)
GAP = 0.010
I0 = 30.0
U_DOWN = -300.0     # far below -R_0 (I_L + sum I_k): the diodes block within ~30 ms
T_UP = 0.01         # s of +20 % voltage, then U_DOWN


@pytest.fixture(scope="module")
def lmaps() -> mk.CharacteristicMaps:
    magnet = mk.load_magnet("tr09-standard", eddy_model="ladder")
    return mk.build_maps(magnet, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


def _voltage(t: float, r_el: float) -> float:
    return r_el * I0 * 1.2 if t < T_UP - 1e-12 else U_DOWN


def _reference(lmaps: mk.CharacteristicMaps, cm: mk.CurrentModel, m: int, j: int,
               t_end: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Circuit ``j`` at a fixed gap by LSODA, written from the circuit of Fig. 8 with the
    network in place of R_ec (not from the library's law functions): KCL at the coil node
    ``I = I_L + U_L/R_0 + sum I_k`` with ``U_L = U - R_el I``, the diode ``I_d = max(I, 0)``
    (then ``U_L = R_0 (I_d - I_L - sum I_k)``), ``L~ dI_L/dt = U_L``, ``L_k L~/L~_ref dI_k/dt
    = U_L - R_k I_k``.  Only ``L~(s, I_L)`` is the model's (its spline of the maps).
    Returns times, coil current and states."""
    ds = lmaps.dataset
    r_0 = float(ds["eddy_network_r0_ohm"].sel(eddy_modes=m).values[j])
    r_k = np.asarray(ds["eddy_network_resistance_ohm"].sel(eddy_modes=m).values[j, :m])
    l_k = np.asarray(ds["eddy_network_inductance_H"].sel(eddy_modes=m).values[j, :m])
    l_ref = float(ds["eddy_network_reference_inductance_H"].values[j])
    r_el = float(cm.core.resistance_ohm[j])
    nc = len(cm.circuit_names)
    x = ca.MX.sym("x", nc)
    lt_fun = ca.Function("lt", [x], [cm.outputs_fun(x, ca.DM.zeros(nc), ca.DM.ones(nc) * GAP,
                                                    ca.DM.zeros(nc * m))[2]])

    def coil(t: float, y: np.ndarray) -> tuple[float, float]:
        u = _voltage(t, r_el)
        i = (y[0] + y[1:].sum() + u / r_0) / (1.0 + r_el / r_0)
        i_d = max(i, 0.0)
        return i_d, r_0 * (i_d - y[0] - y[1:].sum())

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        _, u_l = coil(t, y)
        lt = float(lt_fun(np.full(nc, y[0]))[j])
        return np.concatenate([[u_l / lt], (u_l - r_k * y[1:]) / (l_k * lt / l_ref)])

    y0 = np.concatenate([[I0], np.zeros(m)])
    sol = [solve_ivp(rhs, (t0, t1), y0, method="LSODA", rtol=1e-10, atol=1e-10,
                     t_eval=np.linspace(t0, t1, int(round((t1 - t0) / 1e-4)) + 1))
           for t0, t1 in ((0.0, T_UP), (T_UP, t_end))]
    # two pieces: the voltage jump at T_UP is a kink LSODA should not step across
    sol[1] = solve_ivp(rhs, (T_UP, t_end), sol[0].y[:, -1], method="LSODA", rtol=1e-10,
                       atol=1e-10, t_eval=sol[1].t)
    ys = np.hstack([sol[0].y, sol[1].y[:, 1:]])
    ts = np.concatenate([sol[0].t, sol[1].t[1:]])
    # the coil current at the end of each step under that step's voltage (as the model
    # reports it): the left limit at the voltage jump
    return ts, np.array([coil(tt - 1e-9, yy)[0] for tt, yy in zip(ts, ys.T, strict=True)]), ys


@pytest.mark.parametrize("m", [1, 2])
def test_clamp_against_an_independent_integration(lmaps, m: int) -> None:
    """``CurrentModel(eddy_modes=m, freewheel=True)`` through a voltage step down to -300 V
    (the diodes block at ~30 ms, then ``I_L`` and the branches relax through ``R_0`` with
    the coil current held at 0) follows LSODA of the circuit; without the diodes the coil
    current goes negative (the clamp is what is tested)."""
    dt = 1e-4
    t_end = 0.06
    cm = mk.CurrentModel(lmaps, eddy_modes=m, freewheel=True)
    plain = mk.CurrentModel(lmaps, eddy_modes=m)
    r_el = float(cm.core.resistance_ohm[0])
    ng = len(cm.gap_names)
    st = cm.initial_state(gaps_m=GAP, currents_A=I0)
    sp = plain.initial_state(gaps_m=GAP, currents_A=I0)
    coil, states, coil_plain = [], [], []
    for k in range(round(t_end / dt)):
        u = _voltage(k * dt, r_el)
        st, out = cm.step(st, dt, u, np.full(ng, GAP), np.zeros(ng))
        sp, op = plain.step(sp, dt, u, np.full(ng, GAP), np.zeros(ng))
        assert st.eddy_currents_A is not None
        coil.append(out.currents_A[0])
        coil_plain.append(op.currents_A[0])
        states.append(np.concatenate([[st.inductor_currents_A[0]],
                                      np.reshape(st.eddy_currents_A, (-1, m))[0]]))
    ts, i_ref, y_ref = _reference(lmaps, cm, m, 0, t_end)
    coil_a, states_a = np.array(coil), np.array(states)
    blocked = i_ref[1:] == 0.0
    # the clamp is active over a third of the run, and without it the current reverses
    assert blocked.sum() > 100 and min(coil_plain) < -5.0
    # the model's coil current is exactly 0 where blocked, up to rounding of ~30 A sums
    assert np.max(np.abs(coil_a[blocked])) < 1e-12
    # RK4 at 0.1 ms vs LSODA at 1e-10: measured 4e-9 A (coil) and 1.2e-5 / 4.5e-5 A (states,
    # m = 1 / 2: the clamp's kink inside a step is integrated at first order there); 1e-3 A
    # of a 30 A current is the bound.  A wrong clamp (R_el in place of R_0, or the branch
    # sum left out of the floor) moves the states by amps.
    assert np.max(np.abs(coil_a - i_ref[1:])) < 1e-3
    assert np.max(np.abs(states_a - y_ref[:, 1:].T)) < 1e-3


def test_bank_equals_current_model_with_diodes(lmaps) -> None:
    """The bank's compiled kernel and its reference path with ``freewheel=True`` equal
    ``CurrentModel(eddy_modes=2, freewheel=True)`` through the blocking phase to 1e-12 A
    (tables vs B-splines: ~5e-14 A measured; docs/decisions.md, modesbank26), and a bank
    given the maps with the option builds the same members."""
    cm = mk.CurrentModel(lmaps, eddy_modes=2, freewheel=True)
    r_el = float(cm.core.resistance_ohm[0])
    ng = len(cm.gap_names)
    banks = [MagnetBank({"m": cm}, freewheel=True),
             MagnetBank({"m": cm}, freewheel=True, compiled="never"),
             MagnetBank({"m": lmaps}, eddy_modes=2, freewheel=True)]
    states = [b.initial_state(gaps_m=GAP, currents_A=I0) for b in banks]
    cs = cm.initial_state(gaps_m=GAP, currents_A=I0)
    zero_seen = False
    for k in range(80):
        u = _voltage(k * 1e-3, r_el)
        cs, co = cm.step(cs, 1e-3, u, np.full(ng, GAP), np.zeros(ng))
        zero_seen |= bool(np.all(np.abs(co.currents_A) < 1e-12))
        for n, b in enumerate(banks):
            states[n], out = b.step(states[n], 1e-3, u, GAP, 0.0)
            assert np.max(np.abs(states[n].inductor_currents_A - cs.inductor_currents_A)) < 1e-12
            assert np.max(np.abs(states[n].eddy_currents_A - cs.eddy_currents_A)) < 1e-12
            assert np.max(np.abs(out.currents_A - co.currents_A)) < 1e-12
    assert zero_seen


def test_infinite_r0_refused_by_name(lmaps) -> None:
    """Maps whose fitted network has ``R_0 = inf`` (no current jump) are refused with the
    diodes, naming the circuits and the reason, by the model and the bank; without the
    diodes they run."""
    ds = lmaps.dataset.copy(deep=True)
    r0 = ds["eddy_network_r0_ohm"].values
    r0[1, :] = np.inf
    ds["eddy_network_r0_ohm"] = (ds["eddy_network_r0_ohm"].dims, r0)
    inf_maps = mk.CharacteristicMaps(ds)
    with pytest.raises(InputError, match=r"freewheel=True on eddy-network circuits \['rear'\] "
                                         r"whose fitted R_0 is inf"):
        mk.CurrentModel(inf_maps, eddy_modes=2, freewheel=True)
    with pytest.raises(InputError, match=r"member 'm': freewheel=True .*\['rear'\].*constraint"):
        MagnetBank({"m": inf_maps}, eddy_modes=2, freewheel=True)
    MagnetBank({"m": inf_maps}, eddy_modes=2)
