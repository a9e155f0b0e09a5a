"""Real-time iteration of the offset-free NMPC (issue 14, real time): the condensed, compiled
RTI (`RealTimeMPC`) against the reference RTI of `OffsetFreeMPC` (sparse QP, qrqp) on the
same closed-loop runs, its target calculation against the Python Newton, its fall-back."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.control import Measurement, closed_loop
from maglevkit.control.model import MagnetHeaveModel
from maglevkit.control.mpc import MPCWeights, OffsetFreeMPC
from maglevkit.control.realtime import RealTimeMPC, RealTimeMPCBatch
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

S0 = 0.010
DT = 1e-3
N = 5            # short horizon: the compile of a new horizon is the cost of these tests


@pytest.fixture(scope="module")
def setup(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    maps = mk.build_maps(u_magnet, gaps_m=np.linspace(0.004, 0.02, 17),
                         currents_A=np.linspace(0, 80, 33), progress=False)
    f0 = float(mk.solve_statics(u_magnet, gaps_m=S0, currents_A=20.0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    model = MagnetHeaveModel(maps, mass_kg=veh.mass_kg)
    opts = dict(gap_ref_m=S0, sample_time_s=DT, horizon=N, interval_s=2e-3)
    ref = OffsetFreeMPC(model, solver="rti", **opts)
    fast = RealTimeMPC(model, **opts)
    return maps, model, veh, f0, ref, fast


def _run(maps, veh, ctl, load, duration, ref=None):  # type: ignore[no-untyped-def]
    return closed_loop(mk.CurrentModel(maps), veh, ctl, duration_s=duration, dt_s=DT,
                       initial_gap_m=S0, initial_current_A=ctl.design_state[0],
                       external_force_N=load, gap_reference_m=ref)


def test_same_closed_loop_as_the_reference_rti_and_offset_free(setup) -> None:  # type: ignore[no-untyped-def]
    """+10 % unknown load: the same voltages, gaps and estimates as the reference RTI
    (the condensed QP is the same strictly convex QP), zero steady-state gap error."""
    maps, _, veh, f0, ref, fast = setup
    load = lambda t: 0.1 * f0 if t >= 0.02 else 0.0  # noqa: E731
    a = _run(maps, veh, ref, load, 0.3)
    b = _run(maps, veh, fast, load, 0.3)
    du = np.max(np.abs(a.voltages_V - b.voltages_V))
    ds = np.max(np.abs(a.gap_m - b.gap_m))
    dd = np.max(np.abs(a.diagnostics["disturbance_estimate"]
                       - b.diagnostics["disturbance_estimate"]), axis=0)
    print("du", du, "ds", ds, "dd", dd, "end error", b.gap_m[-1] - S0)
    # measured (N = 5, 300 samples): 5e-11 V, 2e-17 m, load estimate 1e-10 N: both
    # solvers are exact to rounding (active set) and the loop is stable, so rounding does
    # not grow; bounds 1e-6 V, 1e-12 m, 1e-5 N leave >= 1e4
    assert du < 1e-6
    assert ds < 1e-12
    assert dd[0] < 1e-5
    # offset-free (the 1 um); measured 3e-16 m after 0.3 s
    assert abs(b.gap_m[-1] - S0) < 1e-6
    assert np.all(np.abs(b.voltages_V) <= 440.0)
    assert b.diagnostics["disturbance_estimate"][-1, 0] == pytest.approx(0.1 * f0, rel=1e-3)
    # the compiled active-set guess solved (nearly) every QP here: no constraint active
    guess = b.diagnostics["qp_guess"]
    print("samples solved by the guess", guess.sum(), "of", guess.size)
    assert guess.mean() > 0.9


def test_same_solution_with_the_voltage_limit_active(setup) -> None:  # type: ignore[no-untyped-def]
    """A gap reference step of -2 mm drives the voltage to its 440 V limit (the QP's
    bounds active): still the reference RTI's trajectory, never beyond the limit.  (A step
    of +2 mm is held by the chopper's ``I >= 0`` rows at the current's floor instead.)"""
    maps, _, veh, _, ref, fast = setup
    step = lambda t: 0.008 if t >= 0.01 else S0  # noqa: E731
    a = _run(maps, veh, ref, None, 0.06, step)
    b = _run(maps, veh, fast, None, 0.06, step)
    at_limit = int(np.sum(np.abs(b.voltages_V[:-1, 0]) >= 440.0 - 1e-9))
    du = np.max(np.abs(a.voltages_V - b.voltages_V))
    print("samples at the limit", at_limit, "du", du)
    assert at_limit >= 2                                    # measured 3 samples at 440 V
    # the limit active: the guess (no voltage bound active) fails its check there and the
    # dense solver (qpOASES) gives the solution
    assert np.sum(b.diagnostics["qp_guess"] == 0.0) >= at_limit
    assert np.all(np.abs(b.voltages_V) <= 440.0)
    # measured 5e-11 V; bounds as in the test above
    assert du < 1e-6
    assert np.max(np.abs(a.gap_m - b.gap_m)) < 1e-12


def test_compiled_target_is_the_python_newton(setup) -> None:  # type: ignore[no-untyped-def]
    """The fixed-step compiled Newton gives the target of MagnetHeaveModel.steady_state
    from the previous target (here the design current) for loads from -30 % to +30 %."""
    _, model, _, f0, _, fast = setup
    f = fast._target_f
    for load in (-0.3 * f0, 0.0, 0.1 * f0, 0.3 * f0):
        d = np.array([load, 2.0])
        xs, us = model.steady_state(S0, d, current_guess_A=float(fast.design_state[0]))
        xt, ut, step = (np.asarray(v, dtype=float).ravel()
                        for v in f(d, S0, fast.design_state[0], model.table))
        # measured: equal to 4e-15 A / 7e-15 V (Newton converged, last step <= 5e-15 A);
        # bound 1e-9 (the Python Newton stops at a step of 1e-10 relative)
        assert np.max(np.abs(xt - xs)) < 1e-9
        assert np.max(np.abs(ut - us)) < 1e-9
        print(load, np.max(np.abs(xt - xs)), np.max(np.abs(ut - us)), step[0])
        assert abs(step[0]) < 1e-10 * xt[0]


def test_target_fallback_to_the_python_newton(setup) -> None:  # type: ignore[no-untyped-def]
    """A non-finite current guess makes the compiled Newton report a NaN step; the
    controller then takes the Python Newton's target and gives the same voltage as with a
    good guess."""
    maps, model, _, _, _, fast = setup
    meas = Measurement(0.0, S0 + 1e-4, 0.0, np.array([20.5]), S0)
    fast.reset(meas, sample_time_s=DT)
    u_good = fast.update(meas)
    fast.reset(meas, sample_time_s=DT)
    fast._one._cdata[0]["shared"][5][0] = np.nan      # the compiled Newton's current guess
    u_fallback = fast.update(meas)
    print("fallback du", np.max(np.abs(u_fallback - u_good)))
    # measured: 0.0 V (both targets are the converged Newton root); bound 1e-9 V
    assert np.max(np.abs(u_fallback - u_good)) < 1e-9
    assert np.isfinite(u_good).all()


def test_bad_options_are_refused(setup) -> None:  # type: ignore[no-untyped-def]
    _, model, _, _, _, _ = setup
    with pytest.raises(mk.ParameterError, match="qp_solver"):
        RealTimeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=N, qp_solver="ipopt")
    with pytest.raises(mk.ParameterError, match="horizon"):
        RealTimeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=0)


def test_one_ocp_solve_matches_the_reference(setup) -> None:  # type: ignore[no-untyped-def]
    """solve_ocp (one QP from the initial guess, no observer) from a disturbed state: the
    same first QP step as the reference RTI (inputs and states over the horizon)."""
    _, _, _, _, ref, fast = setup
    x0 = np.r_[22.0, S0 + 5e-4, -0.01]
    a = ref.solve_ocp(x0, [30.0, 1.0])
    b = fast.solve_ocp(x0, [30.0, 1.0])
    du = np.max(np.abs(a["inputs_V"] - b["inputs_V"]))
    ds = np.max(np.abs(a["states"][:, 1] - b["states"][:, 1]))
    print("du", du, "ds", ds)
    # measured: 6e-13 V, 9e-18 m; bounds as in the closed-loop test
    assert du < 1e-6
    assert ds < 1e-12


def test_batch_equals_each_controllers_own_update(setup) -> None:  # type: ignore[no-untyped-def]
    """RealTimeMPCBatch (one compiled call per sample for all controllers) gives each
    controller's own RealTimeMPC.update, to rounding: three controllers of two laws (two
    equal, one with other weights) fed the measurements of their own closed-loop runs
    (a load step; a 2 mm reference step that drives the voltage to its limit, the
    dense-solver fall-back inside the batch; a load step with the heavier gap weight)."""
    maps, model, veh, f0, _, _ = setup
    opts = dict(gap_ref_m=S0, sample_time_s=DT, horizon=N, interval_s=2e-3)
    heavy = MPCWeights(gap_m=1e-4)

    def make() -> list[RealTimeMPC]:
        return [RealTimeMPC(model, **opts), RealTimeMPC(model, **opts),
                RealTimeMPC(model, weights=heavy, **opts)]

    load = lambda t: 0.1 * f0 if t >= 0.005 else 0.0  # noqa: E731
    step = lambda t: 0.012 if t >= 0.01 else S0  # noqa: E731
    cases = ((load, None), (None, step), (load, None))
    runs = [_run(maps, veh, c, ld, 0.04, rf) for c, (ld, rf) in zip(make(), cases, strict=True)]
    batched = make()
    batch = RealTimeMPCBatch(batched)
    assert len(batch._groups) == 2
    gaps = np.array([r.gap_m for r in runs]).T
    cur = np.array([r.currents_A[:, 0] for r in runs]).T
    refs = np.array([r.gap_ref_m for r in runs]).T
    volts = np.array([r.voltages_V[:, 0] for r in runs]).T
    batch.reset([Measurement(0.0, S0, 0.0, cur[0, j:j + 1], S0) for j in range(3)],
                sample_time_s=DT)
    du_max, fallbacks = 0.0, 0.0
    for k in range(gaps.shape[0] - 1):
        ub = batch.update(gaps[k], cur[k], refs[k], time_s=k * DT)
        du_max = max(du_max, float(np.abs(volts[k] - ub).max()))
        fallbacks += batch.timing()["fallbacks"]
    print("batch vs single du", du_max, "fallbacks", fallbacks)
    assert fallbacks >= 2                   # the reference step drove circuit 1 to its limit
    # the same compiled law and the same dense solver, evaluated inside one function or
    # alone: equal to rounding (measured 0 V); 1e-9 V is far below the 1e-6 V between the
    # condensed and the sparse reference QP
    assert du_max < 1e-9


def test_batch_refuses_bad_controller_lists(setup) -> None:  # type: ignore[no-untyped-def]
    """No controllers, other objects, the same object twice, other sample times."""
    _, _, _, _, ref, fast = setup
    with pytest.raises(mk.ParameterError, match="non-empty sequence of RealTimeMPC"):
        RealTimeMPCBatch([])
    with pytest.raises(mk.ParameterError, match="non-empty sequence of RealTimeMPC"):
        RealTimeMPCBatch([fast, ref])
    with pytest.raises(mk.ParameterError, match="appears twice"):
        RealTimeMPCBatch([fast, fast])
    other = copy.copy(fast)          # another object with another sample time (no compile)
    other.sample_time_s = 2e-3
    with pytest.raises(mk.ParameterError, match="sample times differ"):
        RealTimeMPCBatch([fast, other])


def test_fused_qp_step_is_the_separate_functions(setup, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The prepare law with the QP data, the active-set guess and the step composed into
    one scalar-code function (``RealTimeMPC._FUSED``, structural zeros and ones of the
    condensed matrices skipped) gives the same numbers as the separate QP data, guess and
    apply functions, on every sample of a closed loop that has guessed samples and
    voltage-limited ones (the dense-solver fall-back): both evaluated on CasADi's
    virtual machine at the inputs the compiled batch of one saw."""
    maps, model, veh, f0, _, _ = setup
    opts = dict(gap_ref_m=S0, sample_time_s=DT, horizon=N, interval_s=2e-3)
    fused = RealTimeMPC(model, **opts)
    monkeypatch.setattr(RealTimeMPC, "_FUSED", False)
    separate = RealTimeMPC(model, **opts)
    f_new, f_old = fused.prepare_function, separate.prepare_function
    assert f_new.n_out() == f_old.n_out()
    step = lambda t: 0.012 if t >= 0.01 else S0  # noqa: E731
    run = _run(maps, veh, fused, lambda t: 0.1 * f0 if t >= 0.005 else 0.0, 0.04, step)
    fused.reset(Measurement(0.0, S0, 0.0, run.currents_A[0], S0), sample_time_s=DT)
    one = fused._one
    assert one is not None
    oks = []
    for k in range(run.gap_m.size - 1):
        args = one._calls[one._k].args
        ins = [np.reshape(args[i], f_new.size_in(i), order="F").copy()
               for i in range(f_new.n_in() - 1)] + [fused._table_array()]
        fused.update(Measurement(k * DT, float(run.gap_m[k]), 0.0, run.currents_A[k],
                                 float(run.gap_ref_m[k])))
        a, b = f_new(*ins), f_old(*ins)
        oks.append(float(a[4][2]))
        for q in range(f_new.n_out()):
            # the skipped terms are exact zeros and products with exact ones: the same
            # bits, so no tolerance
            assert np.array_equal(np.asarray(a[q]), np.asarray(b[q]), equal_nan=True), \
                (k, f_new.name_out(q))
    print("guessed samples", sum(oks), "of", len(oks))
    assert 0 < sum(oks) < len(oks)          # both kinds of sample were compared
