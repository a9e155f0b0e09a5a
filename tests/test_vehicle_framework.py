"""The vehicle framework: the one time-loop runner (vehicle/framework.py) and the step's
parts (stepkernel.build_vehicle_parts) against independent references, and the
cross-section model's Ctrl-C on the shared runner."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest

from maglevkit.vehicle.framework import run_blocks, run_steps
from maglevkit.vehicle.guideway import GuidewayState
from maglevkit.vehicle.simulation import VehicleModel, VehicleRunInterrupted
from maglevkit.vehicle.train import load_vehicle

from .conftest import interrupt_after_steps


def _rotation_block(nb: int, angle: float) -> Any:
    """x_{k+1} = A x_k + p_k (A a rotation), record (x_k, p_k); nb steps per call."""
    a = ca.DM([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    s, p, c = ca.MX.sym("S", 2), ca.MX.sym("P", 1, nb), ca.MX.sym("C", 1)
    x: Any = s
    recs = []
    for j in range(nb):
        recs.append(ca.vertcat(x, p[0, j]))
        x = c[0] * ca.mtimes(a, x) + p[0, j]
    return ca.Function("rot", [s, p, c], [x, ca.horzcat(*recs)])


def test_run_blocks_records_every_step_and_stops_at_the_checked_event() -> None:
    nb, n, angle = 4, 13, 0.3
    fun = _rotation_block(nb, angle)
    n_rows = -(-(n + 1) // nb) * nb
    inputs = np.zeros((n_rows, 1))
    inputs[7, 0] = 1.0                     # a kick at step 7: the event the check looks for
    x0 = np.array([1.0, 0.0])
    looked: list[int] = []

    def look(k0: int, rows: np.ndarray) -> bool:
        looked.append(k0)
        return bool((rows[:, 2] != 0).any())

    checked: list[int] = []

    def check(k: int, row: np.ndarray, final: bool) -> tuple[int, Any] | None:
        checked.append(k)
        return (k, "kick") if row[2] != 0 else None

    out, rec = run_blocks(fun, state=x0, inputs=inputs, constants=np.array([1.0]),
                          n_steps=n, n_record=3, block_steps=nb, look=look, check=check)
    assert (out.last_step, out.event, out.interrupted) == (7, "kick", False)
    # the blocks before the event's were looked at, not checked step by step
    assert looked == [0, 4] and checked == [4, 5, 6, 7]
    # closed form of the rotation: x_k = (cos k a, sin k a) before the kick
    k = np.arange(8)
    np.testing.assert_allclose(rec[:8, 0], np.cos(k * angle), rtol=0, atol=1e-14)
    np.testing.assert_allclose(rec[:8, 1], np.sin(k * angle), rtol=0, atol=1e-14)
    # without events the run ends at n_steps, the last (padded) block checked in full
    inputs[7, 0] = 0.0
    checked.clear()
    out, rec = run_blocks(fun, state=x0, inputs=inputs, constants=np.array([1.0]),
                          n_steps=n, n_record=3, block_steps=nb, look=look, check=check)
    assert out.last_step == n and out.event is None and checked == [12, 13]
    np.testing.assert_allclose(rec[n, :2], [math.cos(n * angle), math.sin(n * angle)],
                               atol=1e-14)
    assert out.call_s > 0 and out.wall_s >= out.call_s


def test_run_steps_keeps_the_steps_done_on_ctrl_c() -> None:
    seen: list[int] = []

    def step(k: int) -> tuple[int, Any] | None:
        if k == 6:
            raise KeyboardInterrupt
        seen.append(k)
        return None

    out = run_steps(step, n_steps=10)
    assert out.interrupted and out.last_step == 5 and seen == list(range(6))

    def early(k: int) -> tuple[int, Any] | None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):      # nothing worth keeping
        run_steps(early, n_steps=10)
    assert run_steps(lambda k: (3, "stop") if k == 3 else None, n_steps=10).last_step == 3


@pytest.fixture(scope="module")
def model() -> VehicleModel:
    return VehicleModel(load_vehicle())


def test_guideway_part_against_the_guideway_s_own_mode_shapes(model: VehicleModel) -> None:
    """The step's guideway part (angle-addition recurrence, ring rows from the positions)
    against Guideway.deflection (direct sines) for a random modal state: w, and the gap
    rate's guideway term w_t + v w_x."""
    gw = model.guideway
    parts = model.step_function(1e-3).parts
    rng = np.random.default_rng(3)
    nm, n_sp = gw.n_modes, gw.n_spans
    q, qd = rng.normal(size=(n_sp, nm)) * 1e-3, rng.normal(size=(n_sp, nm)) * 1e-2
    first = 5
    state = GuidewayState(0.0, first, q, qd)
    L = gw.span.length_m
    nc = model.bank.n_circuits
    x = gw.origin_m + L * (first + rng.uniform(0.0, n_sp, size=nc))
    v = 100.0
    ndof = model.mechanics.n_dof
    gx = np.concatenate([q, qd], axis=1).ravel()
    gap, rate, w, _, _ = (np.asarray(o).ravel() for o in parts["guideway_in"](
        np.zeros(2 * ndof), gx, x, np.zeros(nc), np.zeros(nc), v))
    d = gw.deflection(state, x)
    scale = float(np.abs(d.deflection_m).max())
    # a few ulp per recurrence step over <= n_modes steps: 1e-12 of the largest value
    np.testing.assert_allclose(w, d.deflection_m, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(gap, model.train.nominal_gap_m - d.deflection_m, rtol=0,
                               atol=1e-12 * scale)
    ref_rate = -(d.rate_m_per_s + v * d.slope)
    np.testing.assert_allclose(rate, ref_rate, rtol=0, atol=1e-12 * np.abs(ref_rate).max())


def test_train_loads_against_the_span_s_mode_shapes(model: VehicleModel) -> None:
    """The compiled step's geometry of the loads (one reference point's phase, every point's
    by angle addition, the sign flipped per span) against BeamSpan.mode_shapes at each
    point's own span coordinate (direct sines), at the step start and at mid-step, with
    points on both sides of piers and crossing one within the half step."""
    gw = model.guideway
    parts = model.step_function(1e-3).parts
    span, L = gw.span, gw.span.length_m
    xi = model.point_xi_m
    v = 140.0                                     # 7 cm per half step: pier crossings
    rng = np.random.default_rng(5)
    x_refs = gw.origin_m + L * (7.0 + rng.uniform(0.0, 20.0, 40))
    # a point exactly at a pier, and one just behind it that crosses it in the half step
    x_refs[:2] = gw.origin_m + 11 * L + xi[7], gw.origin_m + 11 * L + xi[7] - 0.03
    crossed = 0
    for x_ref in x_refs:
        out = [np.asarray(o).ravel() for o in parts["guideway_train_loads"](x_ref, v)]
        for k, x in enumerate(((x_ref - xi), (x_ref - xi) + 0.5 * v * 1e-3)):
            rows, s1, c1 = out[3 * k:3 * k + 3]
            ks = gw.span_index(x)
            np.testing.assert_array_equal(rows, np.mod(ks, gw.n_spans))
            phi, dphi = span.mode_shapes(x - (gw.origin_m + ks * L))
            # a few ulp of the angle addition on phases up to k_1 * 75 m: 1e-13
            np.testing.assert_allclose(s1, phi[:, 0], rtol=0, atol=1e-13)
            np.testing.assert_allclose(c1, dphi[:, 0] / span.wavenumbers_rad_per_m[0],
                                       rtol=0, atol=1e-13)
        crossed += int((np.asarray(out[3]) != np.asarray(out[0])).sum())
    assert crossed > 0                            # some points changed span mid-step


def test_guideway_update_part_against_guideway_step(model: VehicleModel) -> None:
    """The step's modal update (a scatter-add of the loads by ring row, the span's ZOH)
    against Guideway.step (modal forces by np.add.at, its own discretisation) from a random
    state with the loads at the mid-step positions."""
    gw = model.guideway
    parts = model.step_function(1e-3).parts
    L, nm, n_sp = gw.span.length_m, gw.n_modes, gw.n_spans
    rng = np.random.default_rng(8)
    q, qd = rng.normal(size=(n_sp, nm)) * 1e-3, rng.normal(size=(n_sp, nm)) * 1e-2
    first = 4
    x_ref = gw.origin_m + L * (first + 0.05) + model.point_xi_m.max()
    v, dt = 120.0, 1e-3
    f_bar = rng.uniform(0.5e5, 1.5e5, model.point_xi_m.size)
    geo = [np.asarray(o).ravel() for o in parts["guideway_train_loads"](x_ref, v)]
    gx = np.concatenate([q, qd], axis=1).ravel()
    (got,) = (np.asarray(o).ravel() for o in [parts["guideway_update"](gx, *geo[3:], f_bar)])
    state = GuidewayState(0.0, first, q, qd)
    ref = gw.step(state, dt, (x_ref - model.point_xi_m) + 0.5 * v * dt, f_bar)
    assert ref.first_span == first                # no recycling in this step
    want = np.concatenate([ref.modal_displacement_m, ref.modal_velocity_m_per_s], axis=1).ravel()
    # the same sums in another order and phases by angle addition: ~1e-15 relative
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())


def test_cascade_part_is_the_gap_controller_s_law(model: VehicleModel) -> None:
    """The compiled step's flux cascade (part ``"cascade"``, every circuit at once) against
    the single-circuit :class:`~maglevkit.control.GapController` written separately in
    NumPy (``U = R I + k_psi (psi_0 (1 + rho) - psi_hat)``, ``rho = k_p (s - s_0) + k_d s'
    + k_i e``), each circuit with its own gains, no limits (a 1 MV supply, four
    quadrants): the same voltages at random states."""
    from maglevkit.control import GapController

    f = model.step_function(1e-3).parts["cascade"]
    nc = model.bank.n_circuits
    s0 = model.train.nominal_gap_m
    rng = np.random.default_rng(7)
    gap = s0 + 1e-3 * rng.standard_normal(nc)
    rate = 0.05 * rng.standard_normal(nc)
    cur = model.trim_current_A * (1 + 0.1 * rng.standard_normal(nc))
    psi = model.flux_bias_Wb * (1 + 0.05 * rng.standard_normal(nc))
    integ = 1e-4 * rng.standard_normal(nc)
    got = np.asarray(f(gap, rate, cur, psi, integ)).ravel()
    g = model.gains
    for j in range(nc):
        ctl = GapController(gap_ref_m=s0, flux_bias_Wb=(float(model.flux_bias_Wb[j]),),
                            bias_current_A=float(model.trim_current_A[j]),
                            kp_per_m=float(g["kp_per_m"][j]), kd_s_per_m=float(g["kd_s_per_m"][j]),
                            ki_per_m_s=float(g["ki_per_m_s"][j]),
                            kflux_per_s=float(g["kflux_per_s"][j]),
                            resistances_ohm=(float(model.bank.resistance_ohm[j]),),
                            voltage_limit_V=1e6, two_quadrant=False)
        ref = ctl.voltages(float(gap[j]), float(rate[j]), float(integ[j]), cur[j:j + 1],
                           psi[j:j + 1])
        # the same arithmetic in the same order (CasADi's virtual machine vs NumPy):
        # measured equal; 1e-13 relative allows a different rounding of the sums
        assert got[j] == pytest.approx(float(ref[0]), rel=1e-13, abs=1e-12)


def test_voltage_limits_part_against_its_rules(model: VehicleModel) -> None:
    """|U| <= U_max, the chopper's U >= -R_ec I_L, failed circuits at 0 V, NaN kept."""
    f = model.step_function(1e-3).parts["voltage_limits"]
    nc = model.bank.n_circuits
    umax = model.train.voltage_limit_V
    r_ec = model.eddy_resistance_ohm
    u = np.linspace(-2 * umax, 2 * umax, nc)
    u[3] = np.nan
    i_l = np.full(nc, 20.0)
    fail = np.full(nc, np.inf)
    fail[10] = 0.5
    got = np.asarray(f(u, i_l, np.full(nc, 30.0), 1.0, fail)).ravel()
    ref = np.maximum(np.clip(u, -umax, umax), -r_ec * i_l)
    ref[3] = np.nan
    ref[10] = 0.0
    np.testing.assert_array_equal(got, ref)


def test_window_schedule_equals_advancing_the_guideway_step_by_step(
        model: VehicleModel) -> None:
    """The run's window computed at once against Guideway.advance applied per step."""
    gw = model.guideway
    L = gw.span.length_m
    rear = gw.origin_m + L * 1.3 + np.arange(400) * 0.11 * L
    front = rear + (gw.n_spans - 1.5) * L
    first_k, keep, k_out = gw.window_schedule(rear, front, first_span=1)
    state = gw.initial_state(first_span=1)
    nm = gw.n_modes
    state = GuidewayState(0.0, 1, np.ones((gw.n_spans, nm)), np.ones((gw.n_spans, nm)))
    for k in range(rear.size):
        new = gw.advance(state, float(rear[k]))
        assert new.first_span == first_k[k]
        reset = new.modal_displacement_m[:, 0] == 0.0
        np.testing.assert_array_equal(keep[k] == 0.0, reset & (state.modal_displacement_m[:, 0]
                                                               != 0.0))
        state = GuidewayState(0.0, new.first_span, np.ones((gw.n_spans, nm)),
                              np.ones((gw.n_spans, nm)))
    assert k_out == -1
    _, _, k_out = gw.window_schedule(rear, rear + gw.n_spans * L, first_span=1)
    assert k_out == 0                      # loads beyond the window from the start



@pytest.mark.parametrize("loop", ["compiled", "python"])
def test_cross_section_ctrl_c_keeps_the_run_up_to_there(
        loop: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from maglevkit.vehicle.crossrun import CrossSectionModel

    cs = CrossSectionModel()
    kw: dict[str, Any] = dict(speed_m_per_s=400 / 3.6, duration_s=0.4, loop=loop)
    full = cs.run(**kw)
    interrupt_after_steps(monkeypatch, 150)
    with pytest.raises(VehicleRunInterrupted) as err:
        cs.run(**kw, progress=True)
    part = err.value.run
    ds, ref = part.dataset, full.dataset
    n = ds.sizes["time"]
    assert 100 <= n < ref.sizes["time"]     # whole blocks of 50 in the compiled loop
    assert ds.attrs["interrupted"].startswith("Ctrl-C: the run stopped at t = ")
    for name in ref.data_vars:
        if name == "voltage":    # the last record's voltage: its step was not taken
            np.testing.assert_array_equal(ds[name].values[:-1], ref[name].values[:n - 1])
            continue
        np.testing.assert_array_equal(ds[name].values, ref[name].values[:n], err_msg=name)
    part.to_netcdf(tmp_path / "part.nc")


@pytest.mark.slow
def test_heave_pitch_mechanics_is_a_planar_multibody_checked_by_sympy() -> None:
    """VehicleMechanics' matrices are its multibody description's (``system``), and the
    multibody's own sympy.physics.mechanics derivation (exact rotations, Lagrange) gives
    them too; the heave-pitch ``B`` is the multibody's ``-B`` (force points along -z).
    ~15 s of sympy: slow; the fast check is test_vehicle's mechanics.derive_sympy on a
    small train, which now checks the multibody-composed matrices."""
    from maglevkit.vehicle.mechanics import VehicleMechanics
    from maglevkit.vehicle.multibody import PlanarMultibody, derive_sympy

    tr = load_vehicle()
    tr = dataclasses.replace(tr, n_sections=1)
    mech = VehicleMechanics(tr, [3.0, 9.0, 20.5], [0, 1, 2])
    assert isinstance(mech.system, PlanarMultibody)
    ref = derive_sympy(mech.system)
    g = mech.gravity_m_per_s2
    for key, val, want in (("M", mech.M, ref["M"]), ("K", mech.K, ref["K"]),
                           ("C", mech.C, ref["C"]), ("B", mech.B, -ref["B"]),
                           ("Q_gravity", mech.Q_gravity, ref["G"] @ np.array([0.0, g]))):
        # rounding of sums of products of ~1e6 numbers: 1e-12 of the largest entry
        np.testing.assert_allclose(val, want, rtol=0, atol=1e-12 * np.abs(want).max(),
                                   err_msg=key)


def test_part_evaluator_equals_a_plain_call_and_densifies_structural_zeros() -> None:
    from maglevkit.vehicle.framework import PartEvaluator

    x, y = ca.MX.sym("x", 3), ca.MX.sym("y")
    f = ca.Function("f", [x, y], [x * y + 1.0, ca.MX.zeros(3), ca.sin(x)])
    ev = PartEvaluator(f)
    a = np.array([0.5, -1.0, 2.0])
    got = ev(a, 3.0)
    want = [np.asarray(o, dtype=float).ravel() for o in f(a, 3.0)]
    assert [g.shape for g in got] == [(3,), (3,), (3,)]
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
    got[0][0] = 99.0                        # outputs are the caller's copies
    np.testing.assert_array_equal(ev(a, 3.0)[0], want[0])
