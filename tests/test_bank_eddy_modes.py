"""The bank with eddy-network members (``CurrentModel(maps, eddy_modes=m)``,
``MagnetBank(..., eddy_modes=m)``): the same law as the single model (docs/bank.md,
"Eddy-network members"), its compiled kernels against the reference path, the stepper,
mixed banks against their members, the FMU, the state layout and the refusals.

The maps are ``tr09-standard`` with the diffusing eddy ladder (``eddy_model = "ladder"``,
the network for which ``eddy_modes=2`` is the reduced model that follows the detailed
one; docs/decisions.md, eddydefault26), on a small grid.  The reference is the single
model, which integrates the same law (``eddy_network_rhs``, ``eddy_network_coil_current``)
with its own RK4 on CasADi B-splines; the bank reads per-cell bicubic tables, equal to
the B-spline to rounding.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError, OutOfRangeError
from maglevkit.reduced.bank import EDDY_NETWORK_PARAMETERS, MagnetBank

from .conftest import open_fmu
from .test_bank_ladder3 import assert_bank_law_is_the_models, equal_bit_for_bit

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 60.0, 7)
DT = 1e-3          # the network's RK4 limit on these maps is above 1 ms: one sub-step
I0 = 30.0
# bicubic tables vs B-splines agree to ~4e-14 relative (docs/decisions.md, "The reduced
# model's compiled tables"); 200 steps on ~30 A accumulate a few 1e-14 A (measured
# 5e-14 A), so 1e-12 leaves a margin of 20 and still catches any law difference (the
# branch currents are ~0.1-0.3 A, their rates ~1e2 A/s)
TOL_A = 1e-12
TOL_REL_F = 1e-12


@pytest.fixture(scope="module")
def lmaps() -> mk.CharacteristicMaps:
    magnet = mk.load_magnet("tr09-standard", eddy_model="ladder")
    return mk.build_maps(magnet, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


def _drive(k: int, r_el: float, f_hz: float = 50.0) -> tuple[float, float, float]:
    """Voltage [V], gap at the start of step ``k`` [m] and its secant rate [m/s]: a
    voltage step of +20 % at 10 mm for 50 steps, then a gap sine 10 +- 1 mm."""
    u = r_el * I0 * 1.2
    if k < 50:
        return u, 0.010, 0.0
    t0, t1 = (k - 50) * DT, (k - 49) * DT
    g0 = 0.010 + 0.001 * np.sin(2 * np.pi * f_hz * t0)
    g1 = 0.010 + 0.001 * np.sin(2 * np.pi * f_hz * t1)
    return u, g0, (g1 - g0) / DT


@pytest.mark.parametrize("compiled", ["never", "auto"])
def test_bank_of_one_network_member_equals_current_model(lmaps, compiled: str) -> None:
    """Step and stepper of a bank of one ``CurrentModel(eddy_modes=2)`` follow the model
    through a voltage step and a 50 Hz gap sine: I_L, both branch currents, the coil
    current and the force to 1e-12; the stepper equals the step bit for bit (the same
    compiled function); the bank option builds the same circuits."""
    cm = mk.CurrentModel(lmaps, eddy_modes=2)
    bank = MagnetBank({"m": cm}, compiled=compiled)
    assert bank.n_eddy_states == 2 and bank.eddy_modes == 2 and not bank.motion_eddy
    assert bank.max_step_s == cm.max_step_s
    st = bank.initial_state(gaps_m=0.010, currents_A=I0)
    assert st.eddy_currents_A is not None and st.eddy_currents_A.shape == (2, 2)
    assert np.all(st.eddy_currents_A == 0.0)
    cs = cm.initial_state(gaps_m=0.010, currents_A=I0)
    stepper = bank.stepper(st, DT)
    ng = len(cm.gap_names)
    r_el = float(bank.resistance_ohm[0])
    for k in range(200):
        u, g0, gd = _drive(k, r_el)
        st, out = bank.step(st, DT, u, g0, gd)
        stepper.advance(u, g0, gd)
        cs, co = cm.step(cs, DT, u, np.full(ng, g0), np.full(ng, gd))
        assert cs.eddy_currents_A is not None and st.eddy_currents_A is not None
        assert np.max(np.abs(st.inductor_currents_A - cs.inductor_currents_A)) < TOL_A
        assert np.max(np.abs(st.eddy_currents_A - cs.eddy_currents_A)) < TOL_A
        assert np.max(np.abs(out.currents_A - co.currents_A)) < TOL_A
        assert np.max(np.abs(out.circuit_force_N / co.circuit_force_N - 1.0)) < TOL_REL_F
        assert np.array_equal(stepper.inductor_currents_A, st.inductor_currents_A)
        assert np.array_equal(stepper.eddy_currents_A, st.eddy_currents_A)
        assert np.array_equal(stepper.circuit_force_N, out.circuit_force_N)
    # both branches are at work (the 50 Hz sine drives ~0.1 A through each)
    assert np.all(np.abs(cs.eddy_currents_A) > 1e-2)
    assert bank.compiled is (compiled == "auto")
    opt = MagnetBank({"m": lmaps}, eddy_modes=2, compiled="never")
    assert np.array_equal(opt.circuit_parameters, bank.circuit_parameters)
    assert opt.max_step_s == bank.max_step_s


def test_compiled_kernels_equal_the_reference_path(lmaps) -> None:
    """The SIMD lanes, CasADi's own C and CasADi's virtual machine evaluate the same
    function: equal bit for bit (the lanes' arithmetic is the graph's, compiled without
    contraction), here with three branches (three eddy states per circuit)."""
    banks = [MagnetBank({"a": lmaps, "b": lmaps}, eddy_modes=3, compiled=c, codegen=g)
             for c, g in (("never", "lanes"), ("auto", "lanes"), ("auto", "casadi"))]
    assert banks[0].n_eddy_states == 3
    states = [b.initial_state(gaps_m=0.010, currents_A=[I0, I0, 25.0, 25.0]) for b in banks]
    r_el = float(banks[0].resistance_ohm[0])
    for k in range(120):
        u, g0, gd = _drive(k, r_el, 200.0)
        res = [b.step(s, DT, [u, u, u * 0.9, u * 0.9], [g0, g0, 0.011, 0.011],
                      [gd, gd, -gd, -gd])
               for b, s in zip(banks, states, strict=True)]
        states = equal_bit_for_bit(res)
    assert banks[1].compiled and banks[2].compiled
    assert states[0].eddy_currents_A is not None
    assert np.all(np.abs(states[0].eddy_currents_A) > 1e-4)


@pytest.mark.parametrize("compiled", ["never", "auto"])
def test_mixed_bank_equals_its_members_on_their_own(lmaps, compiled: str) -> None:
    """A bank of an eq. 8, a two-state ladder, a one-branch and a two-branch network
    member: every circuit follows its own law, bit for bit as a bank of that member alone
    with the same sub-step (the kernel selects the law per circuit exactly; unused eddy
    states stay exactly 0 and add exact zeros)."""
    two = mk.CurrentModel(lmaps, motion_eddy=True)
    net1 = mk.CurrentModel(lmaps, eddy_modes=1)
    net2 = mk.CurrentModel(lmaps, eddy_modes=2)
    members = {"eq8": lmaps, "two": two, "net1": net1, "net2": net2}
    bank = MagnetBank(members, compiled=compiled)
    assert bank.n_eddy_states == 2 and bank.eddy_modes == 2 and bank.motion_eddy
    alone = [MagnetBank({"m": m}, compiled=compiled, max_step_s=bank.max_step_s)
             for m in members.values()]
    st = bank.initial_state(gaps_m=0.010, currents_A=I0)
    sa = [b.initial_state(gaps_m=0.010, currents_A=I0) for b in alone]
    r_el = float(bank.resistance_ohm[0])
    for k in range(120):
        u, g0, gd = _drive(k, r_el)
        st, out = bank.step(st, DT, u, g0, gd)
        res = [b.step(s, DT, u, g0, gd) for b, s in zip(alone, sa, strict=True)]
        sa = [r[0] for r in res]
        assert st.eddy_currents_A is not None
        for j, (s1, o1) in enumerate(res):
            c = slice(2 * j, 2 * j + 2)          # two circuits per member
            assert np.array_equal(st.inductor_currents_A[c], s1.inductor_currents_A)
            assert np.array_equal(out.currents_A[c], o1.currents_A)
            assert np.array_equal(out.circuit_force_N[c], o1.circuit_force_N)
            e = st.eddy_currents_A[c]
            if j == 0:
                assert np.all(e == 0.0)
            elif j in (1, 2):                      # one eddy state: (n,) on their own
                assert np.array_equal(e[:, 0], s1.eddy_currents_A) and np.all(e[:, 1] == 0.0)
            else:
                assert np.array_equal(e, s1.eddy_currents_A)
    assert np.all(np.abs(st.eddy_currents_A[2:, 0]) > 1e-3)


@pytest.mark.parametrize("kinds", ["eq8", "mixed"])
def test_outputs_are_the_output_function_bit_for_bit(lmaps, kinds: str) -> None:
    """``bank.outputs`` (from its second call every circuit inlined into one graph,
    netperf) gives the bits of
    ``output_function`` (the circuit function mapped over the circuits, whose law
    test_model_functions_equal_current_model ties to the single model) at a state away
    from rest with nonzero eddy states, in an eq. 8 bank and a mixed one (eq. 8, two-state
    ladder, one- and two-branch network: every law's output selection)."""
    members: dict[str, object] = {"eq8": lmaps, "eq8b": lmaps}
    if kinds == "mixed":
        members = {"eq8": lmaps, "two": mk.CurrentModel(lmaps, motion_eddy=True),
                   "net1": mk.CurrentModel(lmaps, eddy_modes=1),
                   "net2": mk.CurrentModel(lmaps, eddy_modes=2)}
    bank = MagnetBank(members, compiled="never")
    rng = np.random.default_rng(7)
    n = bank.n_circuits
    st = bank.initial_state(gaps_m=0.0093, currents_A=I0)
    il = I0 * (1.0 + 0.3 * rng.uniform(-1.0, 1.0, n))
    st = dataclasses.replace(st, inductor_currents_A=il)
    args = [il, 200.0 * rng.uniform(-1.0, 1.0, n), bank.circuit_gaps(st.gaps_m)]
    if kinds == "mixed":
        e = rng.uniform(-0.5, 0.5, (n, bank.n_eddy_states))
        e[:2] = 0.0                  # the eq. 8 member's states stay 0 in a run
        e[2:6, 1] = 0.0              # so do the unused second states of the one-state kinds
        st = dataclasses.replace(st, eddy_currents_A=e)
        args.append(e)
    ref = bank.output_function(*args)
    for _ in range(2):               # the first call maps, the second takes the inlined graph
        out = bank.outputs(st, args[1])
        assert np.array_equal(out.currents_A, np.asarray(ref[0]).ravel())
        assert np.array_equal(out.circuit_force_N, np.asarray(ref[1]).ravel())
    assert bank._inlined_outputs is not None
    if kinds == "mixed":             # the eddy states are in use
        plain = bank.output_function(*args[:3], 0.0 * args[3])
        assert np.all(np.abs(np.asarray(plain[0]).ravel()[2:] - out.currents_A[2:]) > 1e-3)


def test_model_functions_equal_current_model(lmaps) -> None:
    """``ode_function``, ``output_function`` and ``ladder_expressions`` of a network bank
    are the single model's law (``CurrentModel.ode``/``outputs_fun``) at a state away
    from rest, to 1e-12 relative (tables vs B-splines)."""
    cm = mk.CurrentModel(lmaps, eddy_modes=2)
    bank = MagnetBank({"m": cm}, compiled="never")
    il, u, s, sd = np.array([31.0, 28.0]), np.array([90.0, 40.0]), 0.0093, 0.05
    e = np.array([[0.4, -0.7], [0.1, 0.2]])
    sv = np.full(2, s)
    refs = assert_bank_law_is_the_models(bank, cm, il, u, sv, np.full(2, sd), e)
    # the branch currents are in use: the coil current differs from eq. 8's at e = 0
    assert abs(refs[0][0] - np.asarray(bank.output_function(il, u, sv, 0 * e)[0])[0, 0]) > 0.1
    rows = bank.circuit_parameters
    q = rows.shape[0] - len(EDDY_NETWORK_PARAMETERS) - 4
    assert np.all(rows[q] == 2.0)                # the branch count row


@pytest.mark.parametrize("via", ["model", "option"])
def test_fmu_of_a_network_member_equals_the_bank(lmaps, tmp_path, via: str) -> None:
    """The exported FMU carries the branch currents: a voltage step at a fixed gap, then
    a 50 Hz gap sine (communication steps of 0.5 ms, one RK4 sub-step each as in the
    bank); its coil current and force equal the bank's to 1e-12 relative (the same
    kernel, compiled by a different compiler run)."""
    pytest.importorskip("fmpy")
    from maglevkit.export import export_fmu

    cm = mk.CurrentModel(lmaps, eddy_modes=2)
    source = cm if via == "model" else lmaps
    extra = {} if via == "model" else {"eddy_modes": 2}
    exported = export_fmu(source, tmp_path / "net.fmu", start_gaps_m=0.010,
                          initial_currents_A=I0, **extra)
    fmu, vr, _ = open_fmu(exported, tmp_path / "x")
    bank = MagnetBank({"m": cm}, compiled="never")
    r_el = float(bank.resistance_ohm[0])
    u_names, s_names, sd_names = (exported.input_names[2 * b:2 * b + 2] for b in range(3))
    out_names = exported.output_names[:4]
    fmu.setReal([vr[n] for n in u_names], [r_el * I0] * 2)
    fmu.exitInitializationMode()
    st = bank.initial_state(gaps_m=0.010, currents_A=I0)
    h = 5e-4
    worst = 0.0
    for k in range(160):
        u = r_el * I0 * 1.2
        if k < 60:
            g0, gd = 0.010, 0.0
        else:
            t0 = (k - 60) * h
            g0 = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t0)
            gd = (0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * (t0 + h)) - g0) / h
        fmu.setReal([vr[n] for n in (*u_names, *s_names, *sd_names)],
                    [u, u, g0, g0, gd, gd])
        fmu.doStep(k * h, h)
        st, out = bank.step(st, h, u, g0, gd)
        got = np.array(fmu.getReal([vr[n] for n in out_names]))
        ref = np.concatenate([out.currents_A, out.circuit_force_N])
        worst = max(worst, float(np.max(np.abs(got - ref) / np.abs(ref))))
    fmu.terminate()
    fmu.freeInstance()
    assert worst <= 1e-12
    # the branch currents were at work, so an eq. 8 FMU would differ
    assert st.eddy_currents_A is not None and np.all(np.abs(st.eddy_currents_A) > 1e-2)


def test_one_branch_state_layout_and_range_check(lmaps) -> None:
    """One branch per circuit is the bank's one-eddy-state shape ``(n_circuits,)``; a
    state of another shape is refused by name; leaving the current range is an
    OutOfRangeError as for eq. 8 circuits (the force current is ``I_L``)."""
    bank = MagnetBank({"m": lmaps}, eddy_modes=1, compiled="never")
    st = bank.initial_state(gaps_m=0.010, currents_A=I0)
    assert st.eddy_currents_A is not None and st.eddy_currents_A.shape == (2,)
    with pytest.raises(InputError, match=r"eddy-network members.*eddy_currents_A of shape \(2,\)"):
        bank.step(dataclasses.replace(st, eddy_currents_A=np.zeros((2, 2))), DT, 0.0)
    top = bank.initial_state(gaps_m=0.010, currents_A=59.0)
    with pytest.raises(OutOfRangeError, match="current"):
        for _ in range(50):
            top, _ = bank.step(top, DT, float(bank.resistance_ohm[0]) * 80.0)


def test_refusals(lmaps, tmp_path) -> None:
    """The two eddy extensions together, bad ``eddy_modes``, eq. 8-only entry
    points and a bank given to ``export_fmu`` with ``eddy_modes`` are refused by name."""
    from maglevkit.export import export_fmu

    # diodes: tests/test_network_freewheel.py (allowed with a finite fitted R_0)
    with pytest.raises(InputError, match="motion_eddy=True with eddy_modes=2"):
        MagnetBank({"m": lmaps}, eddy_modes=2, motion_eddy=True)
    for bad in (4, -1, True, 1.5):
        with pytest.raises(InputError, match="eddy_modes = "):
            MagnetBank({"m": lmaps}, eddy_modes=bad)
    bank = MagnetBank({"m": lmaps}, eddy_modes=2, compiled="never")
    with pytest.raises(InputError, match="run_steps.*eddy_modes.*step or stepper"):
        bank.run_steps(np.full(2, I0), np.full((1, 2), 0.01), np.zeros((1, 2)),
                       np.zeros((1, 2)), 1e-3)
    with pytest.raises(InputError, match="circuit_expressions.*ladder_expressions"):
        bank.circuit_expressions(0, 1.0, 0.01, 0.0, 0.0, bank.table)
    with pytest.raises(InputError, match="eddy_modes = 2 applies to members given as maps"):
        export_fmu(bank, tmp_path / "unused.fmu", eddy_modes=2)
    # maps without an eddy network (a magnet without eddy currents) name the member
    plain = mk.build_maps(mk.load_magnet("u-magnet", eddy_currents=False), gaps_m=GAPS,
                          currents_A=np.linspace(0, 40, 5), progress=False)
    with pytest.raises(InputError, match="member 'p': .*no eddy network.*eddy_modes=0"):
        MagnetBank({"p": plain}, eddy_modes=2)


def test_three_state_ladder_on_maps_without_a_current_jump_names_the_reason(lmaps) -> None:
    """Ladder maps have no three-state fit because the network has no current jump: the
    message says so and points to eddy_modes (it used to say the magnet had no eddy
    currents), for the CurrentModel and the bank."""
    assert np.all(np.isinf(lmaps.dataset["eddy_resistance_ohm"].values))
    with pytest.raises(InputError, match="no current jump|has none") as exc:
        mk.CurrentModel(lmaps, motion_eddy=True, eddy_branches=2)
    assert "eddy_modes=2" in str(exc.value) and "no eddy currents" not in str(exc.value)
    with pytest.raises(InputError, match="member 'm': eddy_branches=2.*eddy_modes=2"):
        MagnetBank({"m": lmaps}, motion_eddy=True, eddy_branches=2)


def test_mixed_with_three_state_ladder_and_three_branches() -> None:
    """Three eddy states per circuit (a three-branch network) next to a three-state
    ladder, a one-branch network and eq. 8 (u-magnet maps with the lumped eddy element,
    where every extension has a fit): each circuit bit for bit as its member alone (the
    ladder's third state and the small network's last two stay exactly 0)."""
    u_maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=GAPS,
                           currents_A=np.linspace(0.0, 40.0, 9), progress=False)
    members = {"eq8": u_maps, "three": mk.CurrentModel(u_maps, motion_eddy=True, eddy_branches=2),
               "net1": mk.CurrentModel(u_maps, eddy_modes=1),
               "net3": mk.CurrentModel(u_maps, eddy_modes=3)}
    # the reference path (the compiled kernels equal it bit for bit: tested above)
    bank = MagnetBank(members, compiled="never")
    assert bank.n_eddy_states == 3 and bank.eddy_modes == 3
    alone = [MagnetBank({"m": m}, compiled="never", max_step_s=bank.max_step_s)
             for m in members.values()]
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    sa = [b.initial_state(gaps_m=0.010, currents_A=20.0) for b in alone]
    u = float(bank.resistance_ohm[0]) * 22.0
    dt = 2e-4
    for k in range(100):
        g0 = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * k * dt)
        gd = (0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * (k + 1) * dt) - g0) / dt
        st, out = bank.step(st, dt, u, g0, gd)
        res = [b.step(s, dt, u, g0, gd) for b, s in zip(alone, sa, strict=True)]
        sa = [r[0] for r in res]
        assert st.eddy_currents_A is not None
        for j, (s1, o1) in enumerate(res):
            assert st.inductor_currents_A[j] == s1.inductor_currents_A[0]
            assert out.currents_A[j] == o1.currents_A[0]
            assert out.circuit_force_N[j] == o1.circuit_force_N[0]
            e, e1 = st.eddy_currents_A[j], s1.eddy_currents_A
            width = 0 if e1 is None else (1 if e1.ndim == 1 else e1.shape[1])
            if width:
                assert np.array_equal(e[:width], np.asarray(e1).reshape(-1))
            assert np.all(e[width:] == 0.0)
    assert np.all(np.abs(st.eddy_currents_A[1:, 0]) > 1e-4)


def test_pole_gap_inputs_and_simulate(lmaps) -> None:
    """With one gap input per pole (the bank's general path) a network member still
    follows the CurrentModel (1e-12: the poles' mean gap may round differently), and
    ``simulate`` records the branch currents as ``(n_t, n_circuits, m)``, equal to the
    model's."""
    cm = mk.CurrentModel(lmaps, eddy_modes=2)
    bank = MagnetBank({"m": cm}, compiled="never", gap_inputs="pole")
    assert not bank.compiled_fast_path
    t = np.arange(0, 81) * DT
    gaps = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t)
    ng = len(cm.gap_names)
    u = float(bank.resistance_ohm[0]) * I0 * 1.1
    ref = cm.simulate(t, gaps_m=np.repeat(gaps[:, None], ng, axis=1), voltages_V=u,
                      initial_currents_A=I0)
    got = bank.simulate(t, gaps_m=np.repeat(gaps[:, None], bank.n_gaps, axis=1),
                        voltages_V=u, initial_currents_A=I0)
    assert got.eddy_currents_A is not None and got.eddy_currents_A.shape == (81, 2, 2)
    np.testing.assert_allclose(got.currents_A, ref.currents_A, rtol=0, atol=TOL_A)
    np.testing.assert_allclose(got.eddy_currents_A, ref.eddy_currents_A, rtol=0, atol=TOL_A)
    assert np.max(np.abs(ref.eddy_currents_A)) > 1e-2
