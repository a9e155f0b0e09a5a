"""The bank with shielded-gap ladder members (``motion_eddy``): the same law as
``CurrentModel(maps, motion_eddy=True)`` (docs/bank.md, "Shielded-gap ladder members").

The reference is the single model, which integrates the same ladder with its own RK4 on
CasADi B-splines (the bank: per-cell bicubic tables, equal to the B-spline to rounding);
mixed banks against their members on their own; the eq. 8 layout left as it was; refusals.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.export import export_fmu
from maglevkit.reduced.bank import MOTION_EDDY_PARAMETERS, MagnetBank
from maglevkit.reduced.core import MotionEddyLadder

from .conftest import open_fmu

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 40.0, 9)
DT = 2e-4          # 2 RK4 sub-steps of the u-magnet ladder's ~1.4e-4 s limit
# bicubic tables vs B-splines agree to ~4e-14 relative (docs/decisions.md, "The reduced
# model's compiled tables"); 200 steps accumulate at most a few 1e-14 A on ~20 A
TOL_A = 1e-12
TOL_REL_F = 1e-12


#: A force share set by hand (the u-magnet's own is refused by build_maps, 0), so that every
#: path below (bank, lanes, FMU, control model) evaluates F(s, I_L + gamma I_e).
GAMMA = -0.3


def u_maps_with_force_share(gamma: float) -> mk.CharacteristicMaps:
    """The u-magnet's maps on GAPS x CURRENTS with the ladder's force share set to
    ``gamma`` (its own is 0, checked here)."""
    maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)
    assert maps.dataset["motion_eddy_force_share"].values[0] == 0.0
    return mk.CharacteristicMaps(maps.dataset.assign(
        motion_eddy_force_share=("circuit", np.array([gamma]))))


@pytest.fixture(scope="module")
def u_maps() -> mk.CharacteristicMaps:
    return u_maps_with_force_share(GAMMA)


def gap_sine(k: int, f_hz: float = 50.0, dt_s: float = DT) -> tuple[float, float]:
    """Gap at the start of step ``k`` of ``dt_s`` [m] (10 mm, 1 mm amplitude at
    ``f_hz``) and its secant rate over the step [m/s]."""
    t0, t1 = k * dt_s, (k + 1) * dt_s
    g0 = 0.010 + 0.001 * np.sin(2 * np.pi * f_hz * t0)
    g1 = 0.010 + 0.001 * np.sin(2 * np.pi * f_hz * t1)
    return g0, (g1 - g0) / dt_s


@pytest.mark.parametrize("compiled", ["never", "auto"])
def test_bank_of_one_ladder_member_equals_current_model(u_maps, compiled: str) -> None:
    """Step and stepper of a bank of one ``CurrentModel(maps, motion_eddy=True)`` follow
    the model itself under a 50 Hz gap sine at constant voltage: I_L, I_e, the coil current
    and the force to 1e-12 (the two lookups' rounding), the stepper equal to the step bit
    for bit (the same compiled function)."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    bank = MagnetBank({"m": cm}, compiled=compiled)
    assert bank.motion_eddy and bank.max_step_s == cm.max_step_s
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    assert st.eddy_currents_A is not None and np.all(st.eddy_currents_A == 0.0)
    cs = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    stepper = bank.stepper(st, DT)
    u = float(bank.resistance_ohm[0]) * 20.0
    ng = len(cm.gap_names)
    for k in range(200):
        g0, gd = gap_sine(k)
        st, out = bank.step(st, DT, u, g0, gd)
        stepper.advance(u, g0, gd)
        cs, co = cm.step(cs, DT, u, np.full(ng, g0), np.full(ng, gd))
        assert cs.eddy_currents_A is not None and st.eddy_currents_A is not None
        assert abs(st.inductor_currents_A[0] - cs.inductor_currents_A[0]) < TOL_A
        assert abs(st.eddy_currents_A[0] - cs.eddy_currents_A[0]) < TOL_A
        assert abs(out.currents_A[0] - co.currents_A[0]) < TOL_A
        assert abs(out.circuit_force_N[0] / co.circuit_force_N[0] - 1.0) < TOL_REL_F
        assert np.array_equal(stepper.inductor_currents_A, st.inductor_currents_A)
        assert np.array_equal(stepper.eddy_currents_A, st.eddy_currents_A)
        assert np.array_equal(stepper.currents_A, out.currents_A)
    # the shielding current is really there (not a ladder that stayed at rest): at 50 Hz
    # its amplitude on the u-magnet is a few 10 mA
    assert abs(cs.eddy_currents_A[0]) > 1e-3
    assert np.array_equal(stepper.state.eddy_currents_A, st.eddy_currents_A)


def test_bank_option_and_simulate_equal_current_model(u_maps) -> None:
    """``MagnetBank(maps, motion_eddy=True)`` builds the same ladder as a CurrentModel
    member, and ``simulate`` (stepper path) follows ``CurrentModel.simulate``."""
    bank = MagnetBank({"m": u_maps}, motion_eddy=True, compiled="never")
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    t = np.arange(0, 101) * DT
    gaps = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t)
    u = float(bank.resistance_ohm[0]) * 20.0
    sim = bank.simulate(t, gaps_m=gaps[:, None], voltages_V=u)
    ref = cm.simulate(t, gaps_m=np.repeat(gaps[:, None], len(cm.gap_names), axis=1),
                      voltages_V=u)
    assert sim.eddy_currents_A is not None and ref.eddy_currents_A is not None
    assert np.max(np.abs(sim.inductor_currents_A[:, 0] - ref.inductor_currents_A[:, 0])) < TOL_A
    assert np.max(np.abs(sim.eddy_currents_A[:, 0] - ref.eddy_currents_A[:, 0])) < TOL_A
    assert np.max(np.abs(sim.currents_A[:, 0] - ref.currents_A[:, 0])) < TOL_A
    assert np.array_equal(sim.final_state.eddy_currents_A, sim.eddy_currents_A[-1])
    # the parameter rows of the ladder: flag, R_2, L_u, beta, gamma of the maps
    par = bank.circuit_parameters
    lad = MotionEddyLadder.from_maps(u_maps, resistance_ohm=bank.resistance_ohm)
    assert par.shape[0] == 13 + len(MOTION_EDDY_PARAMETERS)
    assert tuple(par[13:, 0]) == (1.0, lad.shielding_resistance_ohm[0],
                                  lad.unshielded_inductance_H[0], lad.unshielded_share[0],
                                  lad.force_share[0])
    assert lad.unshielded_share[0] != 0.0     # the u-magnet's ladder has one (the bank carries it)
    assert lad.force_share[0] == GAMMA       # the bank carries it (set in the fixture)
    assert bank.eddy_resistance_ohm[0] == lad.jump_resistance_ohm[0]


@pytest.mark.parametrize("gap_inputs", ["circuit", "pole"])
def test_mixed_bank_equals_its_members_on_their_own(u_maps, gap_inputs: str) -> None:
    """A bank of a ladder member and an eq. 8 member: each circuit follows its own law.
    The ladder circuit equals CurrentModel(motion_eddy=True); the eq. 8 circuit equals a
    bank of eq. 8 alone with the same (ladder-limited) sub-step bit for bit (measured:
    also compiled) and keeps I_e = 0.  With
    one gap input per pole the bank takes its general path (step, not the fast kernel)."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    bank = MagnetBank({"ladder": cm, "eq8": u_maps}, compiled="never", gap_inputs=gap_inputs)
    eq8 = MagnetBank({"eq8": u_maps}, compiled="never", max_step_s=bank.max_step_s)
    assert bank.max_step_s == cm.max_step_s and not eq8.motion_eddy
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    s8 = eq8.initial_state(gaps_m=0.010, currents_A=20.0)
    cs = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    u = float(bank.resistance_ohm[0]) * 20.0
    ng = len(cm.gap_names)
    for k in range(100):
        g0, gd = gap_sine(k)
        st, out = bank.step(st, DT, u, np.full(bank.n_gaps, g0), np.full(bank.n_gaps, gd))
        s8, o8 = eq8.step(s8, DT, u, g0, gd)
        cs, co = cm.step(cs, DT, u, np.full(ng, g0), np.full(ng, gd))
        assert abs(st.inductor_currents_A[0] - cs.inductor_currents_A[0]) < TOL_A
        assert abs(out.currents_A[0] - co.currents_A[0]) < TOL_A
        # the eq. 8 circuit: the same arithmetic (if_else picks eq. 8 exactly, + 0.0 of
        # I_e in the coil current is exact): bit-identical with circuit gap inputs (pole
        # inputs average the poles' gaps, which may round)
        tol = 0.0 if gap_inputs == "circuit" else TOL_A
        assert abs(st.inductor_currents_A[1] - s8.inductor_currents_A[0]) <= tol
        assert abs(out.currents_A[1] - o8.currents_A[0]) <= tol
        assert abs(out.circuit_force_N[1] - o8.circuit_force_N[0]) <= tol * 1e3
        assert st.eddy_currents_A is not None and st.eddy_currents_A[1] == 0.0
    # and the ladder circuit differs from eq. 8 (the point of it)
    assert abs(st.inductor_currents_A[0] - st.inductor_currents_A[1]) > 1e-3


def test_eq8_banks_keep_their_layout(u_maps) -> None:
    """Without ladder members nothing changes: no eddy state, 13 parameter rows, the
    kernel's five inputs and nine outputs."""
    bank = MagnetBank({"m": u_maps}, compiled="never")
    assert not bank.motion_eddy
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    assert st.eddy_currents_A is None
    assert bank.circuit_parameters.shape[0] == 13
    f = bank.step_function(1e-3)
    assert (f.n_in(), f.n_out()) == (5, 9)
    st, _ = bank.step(st, 1e-3, 20.0 * bank.resistance_ohm, 0.01, 0.01)
    assert st.eddy_currents_A is None and bank.stepper(st, 1e-3).eddy_currents_A is None
    lad = MagnetBank({"m": u_maps}, motion_eddy=True, compiled="never").step_function(1e-3)
    assert (lad.n_in(), lad.n_out()) == (6, 10)
    assert lad.name_in(5) == "I_e" and lad.name_out(9) == "I_e_next"


def test_refusals(u_maps, tmp_path) -> None:
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    # freewheel with ladder members is built since gapforce26
    # (tests/test_reduced_motion_eddy.py::test_freewheel_diodes_on_ladder_members)
    assert MagnetBank({"m": cm}, freewheel=True, compiled="never").motion_eddy
    with pytest.raises(InputError, match="motion_eddy = 'yes'"):
        MagnetBank({"m": u_maps}, motion_eddy="yes", compiled="never")  # type: ignore[arg-type]
    bank = MagnetBank({"m": cm}, compiled="never")
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(InputError, match="run_steps.*motion_eddy.*step or stepper"):
        bank.run_steps(st.inductor_currents_A, np.full((2, 1), 0.01), np.full((2, 1), 40.0),
                       np.zeros((2, 1)), np.full(2, 1e-3))
    with pytest.raises(InputError, match="circuit_expressions.*ladder_expressions"):
        bank.circuit_expressions(0, 20.0, 0.01, 40.0, 0.0, bank.table)
    eq8_state = MagnetBank({"m": u_maps}, compiled="never").initial_state(gaps_m=0.01,
                                                                          currents_A=20.0)
    with pytest.raises(InputError, match="eddy_currents_A of shape"):
        bank.step(eq8_state, 1e-3, 40.0)
    with pytest.raises(InputError, match="freewheel=False"):
        export_fmu(MagnetBank({"m": u_maps}, freewheel=True, compiled="never"),
                   tmp_path / "unused.fmu")
    with pytest.raises(InputError, match="ladder_expressions needs a bank with"):
        MagnetBank({"m": u_maps}, compiled="never").ladder_expressions(
            0, 20.0, 0.0, 0.01, 40.0, 0.0, bank.table)


def fmu_next_to_bank(exported: Any, cm: mk.CurrentModel, tmp_path: Any
                     ) -> tuple[Any, dict[str, int], MagnetBank, float, Any]:
    """Open the ``exported`` FMU of ``cm`` (built at 10 mm, 20 A), check that it sub-steps
    at ``cm``'s stable step, set its voltage to hold 20 A and leave initialisation; next to
    it a reference-path bank of ``cm`` in its initial state at 10 mm, 20 A. Returns (fmu,
    value references, bank, that voltage [V], bank state)."""
    fmu, vr, start = open_fmu(exported, tmp_path / "x")
    assert float(start["max_substep"]) == cm.max_step_s
    bank = MagnetBank({"m": cm}, compiled="never")
    u = float(bank.resistance_ohm[0]) * 20.0
    fmu.setReal([vr[exported.input_names[0]]], [u])
    fmu.exitInitializationMode()
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    return fmu, vr, bank, u, st


def test_fmu_of_a_ladder_member_equals_the_bank(u_maps, tmp_path) -> None:
    """The exported FMU carries I_e: under a 50 Hz gap sine (communication steps of
    0.5 ms, the ladder's 1.4e-4 s sub-step: 4 sub-steps, the FMU's loop of one-sub-step
    kernels against the bank's unrolled step) its coil current and force equal the bank's
    to 1e-12 relative (the same kernel; only the sub-steps' start gaps are computed as
    s + sdot k h/n instead of chained)."""
    pytest.importorskip("fmpy")
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    exported = export_fmu(cm, tmp_path / "ladder.fmu", start_gaps_m=0.010,
                          initial_currents_A=20.0)
    u_name, s_name, sd_name = exported.input_names
    i_name, f_name = exported.output_names[:2]
    fmu, vr, bank, u, st = fmu_next_to_bank(exported, cm, tmp_path)
    h = 5e-4
    worst = 0.0
    for k in range(80):
        t0 = k * h
        g0 = 0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * t0)
        gd = (0.010 + 0.001 * np.sin(2 * np.pi * 50.0 * (t0 + h)) - g0) / h
        fmu.setReal([vr[s_name], vr[sd_name]], [g0, gd])
        fmu.doStep(t0, h)
        st, out = bank.step(st, h, u, g0, gd)
        got = np.array(fmu.getReal([vr[i_name], vr[f_name]]))
        ref = np.array([out.currents_A[0], out.circuit_force_N[0]])
        worst = max(worst, float(np.max(np.abs(got - ref) / np.abs(ref))))
    fmu.terminate()
    fmu.freeInstance()
    assert worst <= 1e-12
    # and the ladder was at work: I_e moved, so eq. 8 would differ
    assert st.eddy_currents_A is not None and abs(st.eddy_currents_A[0]) > 1e-3


def test_ladder_lanes_equal_casadi_code_and_the_virtual_machine(u_maps) -> None:
    """With a compiler, a ladder bank runs the SIMD lanes (its RK4 over the pair
    ``(I_L, I_e)`` is a scalar graph); lanes, CasADi's C and the virtual machine give the
    same numbers bit for bit (the lanes translate the graph instruction by instruction,
    compiled without contraction), in a mixed bank of three."""
    from maglevkit.models.compiled import find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler")
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    members = {"l": cm, "e": u_maps, "l2": cm}
    banks = [MagnetBank(members, compiled="never"), MagnetBank(members, compiled="auto"),
             MagnetBank(members, compiled="auto", codegen="casadi")]
    assert banks[1].compiled_step_library(DT) is not None
    assert banks[2].compiled_step_library(DT) is None
    states = [b.initial_state(gaps_m=0.010, currents_A=20.0) for b in banks]
    u = float(banks[0].resistance_ohm[0]) * 20.0
    for k in range(60):
        g0, gd = gap_sine(k)
        outs = []
        for j, b in enumerate(banks):
            states[j], o = b.step(states[j], DT, u, g0, gd)
            outs.append(o)
        for j in (1, 2):
            assert np.array_equal(states[j].inductor_currents_A, states[0].inductor_currents_A)
            assert np.array_equal(states[j].eddy_currents_A, states[0].eddy_currents_A)
            assert np.array_equal(outs[j].currents_A, outs[0].currents_A)
            assert np.array_equal(outs[j].circuit_force_N, outs[0].circuit_force_N)
    assert states[0].eddy_currents_A is not None and states[0].eddy_currents_A[1] == 0.0


def test_cli_exports_the_ladder(u_maps, tmp_path) -> None:
    """``maglevkit export fmu ... --motion-eddy`` builds the ladder FMU (MOTION_EDDY 1 in
    its config, max_substep at the ladder's stable step); without the flag eq. 8."""
    import zipfile

    from typer.testing import CliRunner

    from maglevkit.cli import app

    maps_file = u_maps.to_netcdf(tmp_path / "u.nc")
    runner = CliRunner()
    for extra, expect in (([], "#define MOTION_EDDY 0"), (["--motion-eddy"],
                                                          "#define MOTION_EDDY 1")):
        out = tmp_path / f"u{len(extra)}.fmu"
        res = runner.invoke(app, ["export", "fmu", "u-magnet", str(maps_file), "-o", str(out),
                                  *extra])
        assert res.exit_code == 0, res.output
        with zipfile.ZipFile(out) as zf:
            config = zf.read("sources/config.h").decode()
        assert expect in config
    assert repr(mk.CurrentModel(u_maps, motion_eddy=True).max_step_s) in config
    with pytest.raises(InputError, match="motion_eddy=True applies to members given as maps"):
        export_fmu(MagnetBank({"m": u_maps}, compiled="never"), tmp_path / "x.fmu",
                   motion_eddy=True)


# ---------------------------------------------------------------- the MPC's model
S0 = 0.010


@pytest.fixture(scope="module")
def heave():  # type: ignore[no-untyped-def]
    """A ladder magnet on a heave mass carrying it at 10 mm / 20 A (maps as tests/test_mpc.py)."""
    from maglevkit.control.model import MagnetHeaveModel
    from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.004, 0.02, 17),
                         currents_A=np.linspace(0, 80, 33), progress=False)
    maps = mk.CharacteristicMaps(maps.dataset.assign(   # the force share set by hand, as above
        motion_eddy_force_share=("circuit", np.array([GAMMA]))))
    f0 = float(mk.solve_statics(mag, gaps_m=S0, currents_A=20.0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    cm = mk.CurrentModel(maps, motion_eddy=True)
    return cm, veh, f0, MagnetHeaveModel(cm, mass_kg=veh.mass_kg, compiled="never")


def test_heave_model_carries_the_ladder(heave) -> None:  # type: ignore[no-untyped-def]
    """State ``[I_L, s, s', I_e]``: the steady state has I_e = 0 and no rates; the
    right-hand side and measurement equal the single CurrentModel's ladder (B-splines,
    ``spline_rhs``) off equilibrium; the RK4 sub-steps follow the ladder's stable step."""
    cm, veh, f0, model = heave
    assert (model.nx, model.n_eddy) == (4, 1)
    xs, us = model.steady_state(S0)
    assert xs[3] == 0.0 and xs[2] == 0.0
    d0 = np.zeros(model.nd)
    r = np.asarray(model.rhs(xs, us, d0, model.table)).ravel()
    # equilibrium: the force balance is solved to 1e-10 A (Newton), so the acceleration is
    # ~1e-10 of g x dF/dI / F; the currents' rates vanish to rounding
    assert np.all(np.abs(r[[0, 3]]) < 1e-9) and abs(r[1]) == 0.0 and abs(r[2]) < 1e-6
    x = np.r_[23.0, S0 + 4e-4, -0.02, 0.3]
    u = np.r_[35.0]
    rhs, meas = model.spline_rhs()
    ref, ym = np.asarray(rhs(x, u, d0)).ravel(), np.asarray(meas(x, u, d0)).ravel()
    got = np.asarray(model.rhs(x, u, d0, model.table)).ravel()
    y = np.asarray(model.measurement(x, u, d0, model.table)).ravel()
    # bicubic tables vs B-splines: ~4e-14 relative
    assert np.max(np.abs(got - ref) / np.maximum(np.abs(ref), 1.0)) < 1e-11
    assert np.max(np.abs(y - ym) / np.maximum(np.abs(ym), 1e-3)) < 1e-11
    # and the ladder's rates are CurrentModel's own ODE
    di, de = (np.asarray(v).ravel() for v in cm.ode(x[0], u, x[1], x[2], x[3]))
    assert abs(got[0] / di[0] - 1.0) < 1e-11 and abs(got[3] / de[0] - 1.0) < 1e-11
    assert model.rk4_substeps(2e-3, 1) == math.ceil(2e-3 / cm.max_step_s)


def test_sqp_and_ipopt_peer_agree_on_the_ladder(heave) -> None:  # type: ignore[no-untyped-def]
    """The OCP from a disturbed state with I_e != 0: Gauss-Newton SQP on the bank's tables
    against IPOPT on CurrentModel's B-splines (as tests/test_mpc.py does for eq. 8)."""
    from maglevkit.control.mpc import OffsetFreeMPC

    _, _, _, model = heave
    opts = dict(gap_ref_m=S0, sample_time_s=1e-3, horizon=10, interval_s=2e-3)
    x0 = np.r_[22.0, S0 + 5e-4, -0.01, 0.2]
    sqp = OffsetFreeMPC(model, solver="sqp", **opts).solve_ocp(x0, [30.0, 1.0])
    ipo = OffsetFreeMPC(model, solver="ipopt", **opts).solve_ocp(x0, [30.0, 1.0])
    # measured 2e-9 V and 2e-15 m (x0 without I_e); bounds as tests/test_mpc.py
    assert np.max(np.abs(sqp["inputs_V"] - ipo["inputs_V"])) < 1e-3
    assert np.max(np.abs(sqp["states"][:, 1] - ipo["states"][:, 1])) < 1e-9
    assert sqp["states"].shape[1] == 4


@pytest.mark.slow
def test_offset_free_mpc_on_a_ladder_plant(heave) -> None:  # type: ignore[no-untyped-def]
    """+10 % load on the ladder plant (CurrentModel(maps, motion_eddy=True)), the MPC's
    model and observer carrying I_e: the gap returns to the reference (< 1 um, the
    issue-14 bound; measured 6e-16 m)."""
    from maglevkit.control import closed_loop
    from maglevkit.control.model import MagnetHeaveModel
    from maglevkit.control.mpc import OffsetFreeMPC

    cm, veh, f0, _ = heave
    model = MagnetHeaveModel(cm, mass_kg=veh.mass_kg)
    ctl = OffsetFreeMPC(model, gap_ref_m=S0, sample_time_s=1e-3, horizon=20,
                        interval_s=2e-3, solver="sqp")
    r = closed_loop(cm, veh, ctl, duration_s=0.3, dt_s=1e-3, initial_gap_m=S0,
                    initial_current_A=ctl.design_state[0],
                    external_force_N=lambda t: 0.1 * f0 if t >= 0.02 else 0.0)
    assert abs(r.gap_m[-1] - S0) < 1e-6
    assert np.max(np.abs(r.gap_m - S0)) < 2e-4


def test_ladder_member_beside_a_detailed_member(u_maps) -> None:
    """A ladder member and a detailed FluxModel member: the general path (step) and the
    stepper behind it agree exactly; I_e is NaN for the detailed member's circuit and the
    ladder circuit's equals the ladder bank of one."""
    cm = mk.CurrentModel(u_maps, motion_eddy=True)
    bank = MagnetBank({"l": cm, "d": mk.FluxModel(mk.load_magnet("u-magnet"))},
                      compiled="never")
    alone = MagnetBank({"l": cm}, compiled="never")
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    sa = alone.initial_state(gaps_m=0.010, currents_A=20.0)
    assert st.eddy_currents_A is not None
    assert st.eddy_currents_A[0] == 0.0 and np.isnan(st.eddy_currents_A[1])
    stepper = bank.stepper(st, 1e-3)
    u = float(bank.resistance_ohm[0]) * 21.0
    for _ in range(3):
        st, out = bank.step(st, 1e-3, u, 0.010, 0.02)
        sa, _ = alone.step(sa, 1e-3, u, 0.010, 0.02)
        stepper.advance(u, 0.010, 0.02)
    assert np.array_equal(stepper.eddy_currents_A, st.eddy_currents_A, equal_nan=True)
    assert np.array_equal(stepper.currents_A, out.currents_A)
    assert st.eddy_currents_A[0] == sa.eddy_currents_A[0] and abs(sa.eddy_currents_A[0]) > 1e-2
