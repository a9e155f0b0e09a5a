"""The bank with three-state ladder members (``CurrentModel(maps, motion_eddy=True,
eddy_branches=2)``, ``MagnetBank(..., motion_eddy=True, eddy_branches=2)``): the same law
as the single model (docs/bank.md, "Shielded-gap ladder members"), its compiled kernel
against the reference path, mixed banks against their members, the diode law, the force
current's range check and the state layout.

The reference is the single model, which integrates the same law (``eq8_shielded_gap3_rhs``,
``ladder3_force_current``) with its own RK4 on CasADi B-splines; the bank reads per-cell
bicubic tables, equal to the B-spline to rounding.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError, OutOfRangeError
from maglevkit.reduced.bank import MOTION_EDDY3_PARAMETERS, MOTION_EDDY_PARAMETERS, MagnetBank
from maglevkit.reduced.current import motion_eddy3_parameters

from .test_bank_motion_eddy import fmu_next_to_bank, gap_sine, u_maps_with_force_share

DT = 2e-4          # 2 RK4 sub-steps of the u-magnet three-state ladder's ~1.5e-4 s limit
# bicubic tables vs B-splines agree to ~4e-14 relative (docs/decisions.md, "The reduced
# model's compiled tables"); 200 steps accumulate a few 1e-14 A on ~20 A (measured
# 5e-14), so 1e-12 leaves a margin of 20 and still catches any law difference (the
# eddy states are ~0.1 A)
TOL_A = 1e-12
TOL_REL_F = 1e-12
#: A force share set by hand on the two-state ladder (the u-magnet's own is 0), so that its
#: force current differs from I_L
GAMMA = -0.3


@pytest.fixture(scope="module")
def u_maps() -> mk.CharacteristicMaps:
    return u_maps_with_force_share(GAMMA)


@pytest.mark.parametrize("compiled", ["never", "auto"])
def test_bank_of_one_three_state_member_equals_current_model(u_maps, compiled: str) -> None:
    """Step and stepper of a bank of one three-state ``CurrentModel`` follow the model
    under a 50 Hz gap sine at constant voltage: I_L, I_e1, I_e2, the coil current and the
    force to 1e-12; the stepper equals the step bit for bit (the same compiled function)."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    bank = MagnetBank({"m": cm}, compiled=compiled)
    assert bank.motion_eddy and bank.n_eddy_states == 2 and bank.max_step_s == cm.max_step_s
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    assert st.eddy_currents_A is not None and st.eddy_currents_A.shape == (1, 2)
    assert np.all(st.eddy_currents_A == 0.0)
    cs = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    stepper = bank.stepper(st, DT)
    assert stepper.eddy_currents_A is not None and stepper.eddy_currents_A.shape == (1, 2)
    u = float(bank.resistance_ohm[0]) * 20.0
    ng = len(cm.gap_names)
    for k in range(200):
        g0, gd = gap_sine(k, dt_s=DT)
        st, out = bank.step(st, DT, u, g0, gd)
        stepper.advance(u, g0, gd)
        cs, co = cm.step(cs, DT, u, np.full(ng, g0), np.full(ng, gd))
        assert cs.eddy_currents_A is not None and st.eddy_currents_A is not None
        assert abs(st.inductor_currents_A[0] - cs.inductor_currents_A[0]) < TOL_A
        assert np.max(np.abs(st.eddy_currents_A - cs.eddy_currents_A)) < TOL_A
        assert abs(out.currents_A[0] - co.currents_A[0]) < TOL_A
        assert abs(out.circuit_force_N[0] / co.circuit_force_N[0] - 1.0) < TOL_REL_F
        assert np.array_equal(stepper.inductor_currents_A, st.inductor_currents_A)
        assert np.array_equal(stepper.eddy_currents_A, st.eddy_currents_A)
        assert np.array_equal(stepper.circuit_force_N, out.circuit_force_N)
    # both eddy states are at work (50 Hz on the u-magnet: ~0.1 A each)
    assert np.all(np.abs(cs.eddy_currents_A) > 1e-2)
    assert np.array_equal(stepper.state.eddy_currents_A, st.eddy_currents_A)
    # the bank option builds the same circuit as the CurrentModel member (same rows)
    opt = MagnetBank({"m": u_maps}, motion_eddy=True, eddy_branches=2, compiled="never")
    assert np.array_equal(opt.circuit_parameters, bank.circuit_parameters)
    assert opt.max_step_s == bank.max_step_s


def equal_bit_for_bit(res: list[tuple[Any, Any]]) -> list[Any]:
    """Assert that the (state, outputs) of one step of several banks agree bit for bit
    with the first's: inductor and eddy currents, coil currents and circuit forces.
    Returns the states."""
    states = [r[0] for r in res]
    for st, out in res[1:]:
        assert np.array_equal(st.inductor_currents_A, states[0].inductor_currents_A)
        assert np.array_equal(st.eddy_currents_A, states[0].eddy_currents_A)
        assert np.array_equal(out.currents_A, res[0][1].currents_A)
        assert np.array_equal(out.circuit_force_N, res[0][1].circuit_force_N)
    return states


def test_compiled_kernels_equal_the_reference_path(u_maps) -> None:
    """The SIMD lanes, CasADi's own C and CasADi's virtual machine evaluate the same
    function: equal bit for bit (the lanes' arithmetic is the graph's, compiled without
    contraction)."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    banks = [MagnetBank({"a": cm, "b": cm}, compiled=c, codegen=g)
             for c, g in (("never", "lanes"), ("auto", "lanes"), ("auto", "casadi"))]
    states = [b.initial_state(gaps_m=0.010, currents_A=[20.0, 25.0]) for b in banks]
    u = float(banks[0].resistance_ohm[0]) * np.array([20.0, 27.0])
    for k in range(100):
        g0, gd = gap_sine(k, 200.0, dt_s=DT)
        res = [b.step(s, DT, u, [g0, 0.011], [gd, -gd]) for b, s in zip(banks, states,
                                                                        strict=True)]
        states = equal_bit_for_bit(res)
    assert banks[1].compiled and banks[2].compiled
    assert np.all(np.abs(states[0].eddy_currents_A) > 1e-3)


@pytest.mark.parametrize("compiled", ["never", "auto"])
def test_mixed_bank_equals_its_members_on_their_own(u_maps, compiled: str) -> None:
    """A bank of an eq. 8, a two-state and a three-state member: every circuit follows
    its own law, bit for bit as a bank of that member alone with the same sub-step (the
    kernel selects the law per circuit exactly; the second eddy state stays 0 in the
    two-state circuit, both in the eq. 8 one)."""
    two = mk.CurrentModel(u_maps, motion_eddy=True)
    three = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    bank = MagnetBank({"eq8": u_maps, "two": two, "three": three}, compiled=compiled)
    assert bank.n_eddy_states == 2
    assert bank.max_step_s == min(two.max_step_s, three.max_step_s)
    alone = [MagnetBank({"m": m}, compiled=compiled, max_step_s=bank.max_step_s)
             for m in (u_maps, two, three)]
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    sa = [b.initial_state(gaps_m=0.010, currents_A=20.0) for b in alone]
    u = float(bank.resistance_ohm[0]) * 21.0
    for k in range(100):
        g0, gd = gap_sine(k, dt_s=DT)
        st, out = bank.step(st, DT, u, g0, gd)
        res = [b.step(s, DT, u, g0, gd) for b, s in zip(alone, sa, strict=True)]
        sa = [r[0] for r in res]
        for j, (s1, o1) in enumerate(res):
            assert st.inductor_currents_A[j] == s1.inductor_currents_A[0]
            assert out.currents_A[j] == o1.currents_A[0]
            assert out.circuit_force_N[j] == o1.circuit_force_N[0]
        assert st.eddy_currents_A is not None
        assert np.all(st.eddy_currents_A[0] == 0.0) and st.eddy_currents_A[1, 1] == 0.0
        assert st.eddy_currents_A[1, 0] == sa[1].eddy_currents_A[0]
        assert np.array_equal(st.eddy_currents_A[2], sa[2].eddy_currents_A[0])
    assert abs(st.eddy_currents_A[1, 0]) > 1e-3


def assert_bank_law_is_the_models(bank: MagnetBank, cm: mk.CurrentModel, il: Any, u: Any,
                                  s: Any, sd: Any, e: np.ndarray) -> list[np.ndarray]:
    """Assert that ``bank``'s ``ode_function``, ``output_function`` and (for circuit 0)
    ``ladder_expressions`` equal ``cm``'s ``ode``/``outputs_fun`` at coil currents ``il``
    [A], voltages ``u`` [V], gaps ``s`` [m], gap rates ``sd`` [m/s] and eddy states ``e``
    (n_circuits, n_eddy) [A], to 1e-12 relative (tables vs B-splines; as the arguments are
    given to both: scalars for one circuit or per-circuit arrays). Returns ``cm``'s
    outputs (coil current, force), raveled."""
    import casadi as ca

    d_il, d_e = (np.asarray(v) for v in bank.ode_function(il, u, s, sd, e))
    ref_il, ref_e = (np.asarray(v).ravel() for v in cm.ode(il, u, s, sd, e.ravel()))
    assert d_e.shape == e.shape
    np.testing.assert_allclose(d_il.ravel(), ref_il, rtol=1e-12)
    np.testing.assert_allclose(d_e.ravel(), ref_e, rtol=1e-12)
    outs = [np.asarray(v).ravel() for v in bank.output_function(il, u, s, e)]
    refs = [np.asarray(v).ravel() for v in cm.outputs_fun(il, u, s, e.ravel())]
    for got, want in zip(outs, refs, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-12)
    n_e = e.shape[1]
    ie = ca.MX.sym("I_e", n_e)
    first = [float(np.ravel(x)[0]) for x in (il, s, u, sd)]
    ex = bank.ladder_expressions(0, first[0], ie, first[1], first[2], first[3],
                                 ca.MX(ca.DM(bank.table)))
    f = ca.Function("f", [ie], [ex[0], ex[1], ex[2], ex[3]])
    got = [np.asarray(v).ravel() for v in f(e[0])]
    np.testing.assert_allclose(got[0], ref_il[:1], rtol=1e-12)
    np.testing.assert_allclose(got[1], ref_e[:n_e], rtol=1e-12)
    np.testing.assert_allclose(got[2], refs[0][:1], rtol=1e-12)
    np.testing.assert_allclose(got[3], refs[1][:1], rtol=1e-12)
    return refs


def test_model_functions_equal_current_model(u_maps) -> None:
    """``ode_function``, ``output_function`` and ``ladder_expressions`` of a three-state
    bank are the single model's law (``CurrentModel.ode``/``outputs_fun``) at a state
    away from rest, to 1e-12 relative (tables vs B-splines)."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    bank = MagnetBank({"m": cm}, compiled="never")
    il, u, s, sd, e = 23.0, 50.0, 0.0093, 0.05, np.array([[0.4, -0.7]])
    refs = assert_bank_law_is_the_models(bank, cm, il, u, s, sd, e)
    # the force current is in use: the force differs from F(s, I_L) (shares c_1, c_2)
    assert abs(refs[1][0] - np.asarray(bank.output_function(il, u, s, 0 * e)[1]).item()) > 1e-3


def test_freewheel_diodes_on_three_state_members(u_maps) -> None:
    """The diode law of the three-state ladder is eq. 8's of the terminal current
    ``I_u = I_L + I_e1 + I_e2`` (docs/equations.md section 8): commanding -200 V from
    20 A, the coil current stops at 0 (within rounding) and stays there, bank and
    CurrentModel alike (to 1e-12 A); without diodes it reverses."""
    diode = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2, freewheel=True)
    plain = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    bank = MagnetBank({"m": diode}, freewheel=True, compiled="never")
    t = np.arange(0, 201) * 5e-5
    sim = diode.simulate(t, gaps_m=0.010, voltages_V=-200.0, initial_currents_A=20.0)
    ref = bank.simulate(t, gaps_m=0.010, voltages_V=-200.0, initial_currents_A=20.0)
    np.testing.assert_allclose(sim.currents_A, ref.currents_A, rtol=0, atol=1e-12)
    assert ref.eddy_currents_A is not None and ref.eddy_currents_A.shape == (201, 1, 2)
    np.testing.assert_allclose(sim.eddy_currents_A, ref.eddy_currents_A, rtol=0, atol=1e-12)
    coil = sim.currents_A[:, 0]
    assert coil.min() >= -1e-9            # the diodes hold I >= 0 (rounding only)
    assert np.sum(coil < 1e-9) > 50       # it reached 0 and stayed there
    # the terminal current decays through R_a alone while the diodes block: I_u >= 0
    i_u = sim.inductor_currents_A[:, 0] + sim.eddy_currents_A[:, 0].sum(axis=1)
    assert i_u.min() >= -1e-9
    free = plain.simulate(t[:21], gaps_m=0.010, voltages_V=-200.0, initial_currents_A=20.0)
    assert free.currents_A[-1, 0] < -1.0


@pytest.mark.parametrize("branches", [1, 2])
def test_force_current_is_range_checked(u_maps, branches: int) -> None:
    """The force is read at the force current (``I_L + gamma I_e``; three states ``I_L +
    c_1 I_e1 + c_2 I_e2``), so it is checked against the maps' current range as ``I_L``
    is: a state with I_L inside the maps (39 A of 0..40 A) but the force current outside
    (about 41-42 A) is refused by the bank and the CurrentModel, or extrapolated with a
    warning; the same state with the eddy currents' signs flipped is fine."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=branches)
    par, _ = motion_eddy3_parameters(u_maps, cm.resistance_ohm)
    # eddy states that push the force current up by 2-3 A
    e_out = np.array([-10.0]) if branches == 1 else np.array([[10.0 * np.sign(par["c_1"][0]),
                                                               0.0]])
    cs = dataclasses.replace(cm.initial_state(gaps_m=0.010, currents_A=39.0),
                             eddy_currents_A=e_out)
    u = 39.0 * float(cm.resistance_ohm[0])
    ng = len(cm.gap_names)
    with pytest.raises(OutOfRangeError, match="force current"):
        cm.step(cs, 1e-5, u, np.full(ng, 0.010))
    for extrapolate in (False, True):
        bank = MagnetBank({"m": u_maps}, motion_eddy=True, eddy_branches=branches,
                          compiled="never", extrapolate=extrapolate)
        st0 = bank.initial_state(gaps_m=0.010, currents_A=39.0)
        st = dataclasses.replace(st0, eddy_currents_A=e_out.reshape(st0.eddy_currents_A.shape))
        if extrapolate:
            with pytest.warns(UserWarning, match="extrapolating"):
                st1, _ = bank.step(st, 1e-5, u, 0.010)
            assert 0.0 < st1.inductor_currents_A[0] < 40.0     # I_L itself stayed inside
        else:
            with pytest.raises(OutOfRangeError, match="current 4[12]"):
                bank.step(st, 1e-5, u, 0.010)
    # flipped: the force current is ~36-37 A, inside the maps
    flipped = dataclasses.replace(cs, eddy_currents_A=-e_out)
    cm.step(flipped, 1e-5, u, np.full(ng, 0.010))
    bank = MagnetBank({"m": u_maps}, motion_eddy=True, eddy_branches=branches,
                      compiled="never")
    st0 = bank.initial_state(gaps_m=0.010, currents_A=39.0)
    st = dataclasses.replace(st0, eddy_currents_A=-e_out.reshape(st0.eddy_currents_A.shape))
    bank.step(st, 1e-5, u, 0.010)


def test_layout_options_and_refusals(u_maps) -> None:
    """The three-state bank's parameter rows, kernel signature and state checks; the
    option's refusals; two-state banks keep their layout."""
    bank = MagnetBank({"m": u_maps}, motion_eddy=True, eddy_branches=2, compiled="never")
    par = bank.circuit_parameters
    p3, step_s = motion_eddy3_parameters(u_maps, bank.resistance_ohm)
    assert par.shape[0] == 13 + len(MOTION_EDDY_PARAMETERS) + len(MOTION_EDDY3_PARAMETERS)
    assert par[13, 0] == 2.0 and par[8, 0] == p3["a"][0]
    assert tuple(par[14:, 0]) == tuple(float(p3[q][0]) for q in (
        "r_2", "l_u", "beta", "c_1", "r_3", "l_2", "beta_2", "c_2"))
    assert bank.max_step_s == step_s and bank.eddy_resistance_ohm[0] == p3["r_a"][0]
    f = bank.step_function(1e-3)
    assert (f.n_in(), f.n_out()) == (6, 10)
    assert f.size_in(5) == (1, 2) and f.size_out(9) == (1, 2)
    one = bank.circuit_step_function(2)
    assert one.size_in(6) == (2, 1)
    assert [one.name_out(k) for k in (6, 7)] == ["I_e1_next", "I_e2_next"]
    two = MagnetBank({"m": u_maps}, motion_eddy=True, compiled="never")
    assert two.n_eddy_states == 1 and two.step_function(1e-3).size_in(5) == (1, 1)
    assert two.initial_state(gaps_m=0.01, currents_A=20.0).eddy_currents_A.shape == (1,)
    assert MagnetBank({"m": u_maps}, compiled="never").n_eddy_states == 0
    st2 = two.initial_state(gaps_m=0.01, currents_A=20.0)
    with pytest.raises(InputError, match=r"eddy_currents_A of shape \(1, 2\)"):
        bank.step(st2, 1e-3, 40.0)
    with pytest.raises(InputError, match=r"eddy_currents_A of shape \(1,\)"):
        two.step(bank.initial_state(gaps_m=0.01, currents_A=20.0), 1e-3, 40.0)
    for bad, needle in ((3, "eddy_branches = 3"), (True, "eddy_branches = True")):
        with pytest.raises(InputError, match=needle):
            MagnetBank({"m": u_maps}, motion_eddy=True, eddy_branches=bad)
    with pytest.raises(InputError, match="needs motion_eddy=True"):
        MagnetBank({"m": u_maps}, eddy_branches=2)
    old = mk.CharacteristicMaps(u_maps.dataset.drop_vars(
        [v for v in u_maps.dataset.data_vars if str(v).startswith("motion_eddy3_")]))
    with pytest.raises(InputError, match="member 'm': eddy_branches=2.*rebuild"):
        MagnetBank({"m": old}, motion_eddy=True, eddy_branches=2)


def test_current_model_eddy_state_shapes(u_maps) -> None:
    """One eddy state per circuit has shape ``(n_circuits,)`` in CurrentModel as in the
    bank (time series ``(n_t, n_circuits)``); the old ``(n_circuits, 1)`` is still read,
    with a DeprecationWarning, to the same numbers."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    st = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    assert st.eddy_currents_A.shape == (1,)
    new = dataclasses.replace(st, eddy_currents_A=np.array([0.3]))
    old = dataclasses.replace(st, eddy_currents_A=np.array([[0.3]]))
    s1, o1 = cm.step(new, 1e-3, 40.0)
    with pytest.warns(DeprecationWarning, match=r"\(n_circuits, 1\).*deprecated"):
        s2, o2 = cm.step(old, 1e-3, 40.0)
    assert np.array_equal(s1.eddy_currents_A, s2.eddy_currents_A)
    assert s1.eddy_currents_A.shape == (1,) and o1.currents_A[0] == o2.currents_A[0]
    sim = cm.simulate(np.arange(0, 5) * 1e-3, gaps_m=0.010, voltages_V=40.0)
    assert sim.eddy_currents_A.shape == (5, 1)
    three = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    sim3 = three.simulate(np.arange(0, 5) * 1e-3, gaps_m=0.010, voltages_V=40.0)
    assert sim3.eddy_currents_A.shape == (5, 1, 2)
    with pytest.raises(InputError, match=r"expected shape \(1, 2\)"):
        three.step(dataclasses.replace(sim3.final_state, eddy_currents_A=np.zeros(2)), 1e-3,
                   40.0)


@pytest.mark.parametrize("via", ["model", "option"])
def test_fmu_of_a_three_state_member_equals_the_bank(u_maps, tmp_path, via: str) -> None:
    """The exported FMU carries I_e1 and I_e2: a 50 Hz gap sine, then a voltage step of
    +20 % at a fixed gap (communication steps of 0.5 ms: 4 sub-steps of the ladder's
    ~1.5e-4 s, the FMU's loop of one-sub-step kernels against the bank's unrolled step):
    its coil current and force equal the bank's to 1e-12 relative (the same kernel; only
    the sub-steps' start gaps are computed as s + sdot k h/n instead of chained)."""
    pytest.importorskip("fmpy")
    from maglevkit.export import export_fmu

    cm = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    source = cm if via == "model" else u_maps
    extra = {} if via == "model" else {"motion_eddy": True, "eddy_branches": 2}
    exported = export_fmu(source, tmp_path / "ladder3.fmu", start_gaps_m=0.010,
                          initial_currents_A=20.0, **extra)
    u_name, s_name, sd_name = exported.input_names
    i_name, f_name = exported.output_names[:2]
    fmu, vr, bank, u, st = fmu_next_to_bank(exported, cm, tmp_path)
    h = 5e-4
    worst = [0.0, 0.0]
    peak = 0.0
    for k in range(120):
        t0 = k * h
        if k < 60:               # gap sine at constant voltage
            g0 = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t0)
            gd = (0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * (t0 + h)) - g0) / h
        else:                    # voltage step at the gap reached
            g0, gd, u = float(st.gaps_m[0]), 0.0, float(bank.resistance_ohm[0]) * 24.0
        fmu.setReal([vr[u_name], vr[s_name], vr[sd_name]], [u, g0, gd])
        fmu.doStep(t0, h)
        st, out = bank.step(st, h, u, g0, gd)
        got = np.array(fmu.getReal([vr[i_name], vr[f_name]]))
        ref = np.array([out.currents_A[0], out.circuit_force_N[0]])
        part = int(k >= 60)
        worst[part] = max(worst[part], float(np.max(np.abs(got - ref) / np.abs(ref))))
        assert st.eddy_currents_A is not None
        peak = max(peak, float(np.min(np.abs(st.eddy_currents_A))))
    fmu.terminate()
    fmu.freeInstance()
    assert max(worst) <= 1e-12
    # both eddy states were at work, so a two-state or eq. 8 FMU would differ
    assert peak > 1e-3


def test_general_path_and_failed_stepper_step(u_maps) -> None:
    """With one gap input per pole (the bank's general path, ``step`` per member) a
    three-state member still follows the CurrentModel (1e-12, the poles' mean gap may
    round); a stepper step that leaves the maps raises and leaves the stepper at the last
    good step, both eddy states included."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2)
    bank = MagnetBank({"m": cm}, compiled="never", gap_inputs="pole")
    assert not bank.compiled_fast_path
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    cs = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    u = float(bank.resistance_ohm[0]) * 20.0
    ng = bank.n_gaps
    for k in range(50):
        g0, gd = gap_sine(k, dt_s=DT)
        st, out = bank.step(st, DT, u, np.full(ng, g0), np.full(ng, gd))
        cs, co = cm.step(cs, DT, u, np.full(ng, g0), np.full(ng, gd))
        assert np.max(np.abs(st.eddy_currents_A - cs.eddy_currents_A)) < TOL_A
        assert abs(out.currents_A[0] - co.currents_A[0]) < TOL_A
    assert np.all(np.abs(st.eddy_currents_A) > 1e-3)
    fast = MagnetBank({"m": cm}, compiled="never")
    stepper = fast.stepper(fast.initial_state(gaps_m=0.010, currents_A=20.0), DT)
    for k in range(20):
        g0, gd = gap_sine(k, dt_s=DT)
        stepper.advance(u, g0, gd)
    before = stepper.state
    with pytest.raises(OutOfRangeError):
        stepper.advance(u, 0.0139, 50.0)          # the gap leaves the maps (14 mm)
    after = stepper.state
    assert after.time_s == before.time_s
    assert np.array_equal(after.eddy_currents_A, before.eddy_currents_A)
    assert np.array_equal(after.inductor_currents_A, before.inductor_currents_A)
