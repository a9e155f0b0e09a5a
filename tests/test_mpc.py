"""Offset-free NMPC on the reduced magnet model (issue 14): offset-free tracking, constraints,
observer convergence, an IPOPT peer on the same OCP, the detectability rank condition."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.control import CascadeController, Controller, closed_loop, design_gap_controller
from maglevkit.control.model import MagnetHeaveModel
from maglevkit.control.mpc import OffsetFreeMPC
from maglevkit.control.observers import ExtendedKalmanFilter
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

S0 = 0.010
DT = 1e-3


@pytest.fixture(scope="module")
def setup(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    maps = mk.build_maps(u_magnet, gaps_m=np.linspace(0.004, 0.02, 17),
                         currents_A=np.linspace(0, 80, 33), progress=False)
    i0 = 20.0
    f0 = float(mk.solve_statics(u_magnet, gaps_m=S0, currents_A=i0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    model = MagnetHeaveModel(maps, mass_kg=veh.mass_kg)
    plain = MagnetHeaveModel(maps, mass_kg=veh.mass_kg, disturbances=())
    return u_magnet, maps, model, plain, veh, f0


def _mpc(model: MagnetHeaveModel, **kw):  # type: ignore[no-untyped-def]
    opts = dict(gap_ref_m=S0, sample_time_s=DT, horizon=20, interval_s=2e-3, solver="rti")
    opts.update(kw)
    return OffsetFreeMPC(model, **opts)


def test_both_controllers_share_the_interface(setup) -> None:  # type: ignore[no-untyped-def]
    mag, _, model, _, veh, _ = setup
    ctl = _mpc(model)
    design = design_gap_controller(mag, mass_kg=veh.mass_kg, gap_m=S0, current_A=20.0)
    assert isinstance(ctl, Controller)
    assert isinstance(CascadeController(design), Controller)


def test_offset_free_under_an_unknown_load(setup) -> None:  # type: ignore[no-untyped-def]
    """+10 % load on the reduced plant: with the disturbance model the gap returns to the
    reference (< 1 um, the issue's bound); plain NMPC keeps an offset."""
    _, maps, model, plain, veh, f0 = setup
    plant = mk.CurrentModel(maps)
    load = lambda t: 0.1 * f0 if t >= 0.02 else 0.0  # noqa: E731
    runs = {}
    for name, m in (("offset-free", model), ("plain", plain)):
        ctl = _mpc(m)
        runs[name] = closed_loop(plant, veh, ctl, duration_s=0.5, dt_s=DT, initial_gap_m=S0,
                                 initial_current_A=ctl.design_state[0], external_force_N=load)
    free, nominal = runs["offset-free"], runs["plain"]
    print("offset-free end error", free.gap_m[-1] - S0, "plain", nominal.gap_m[-1] - S0)
    # measured: 5e-18 m (the plant is the controller's model, the loop converges to its
    # fixed point) against the 1 um; plain NMPC 211 um, bound 20 um
    assert abs(free.gap_m[-1] - S0) < 1e-6
    assert abs(nominal.gap_m[-1] - S0) > 2e-5
    for r in runs.values():
        assert np.all(np.abs(r.voltages_V) <= 440.0)
    # the force disturbance estimate is the load
    d = free.diagnostics["disturbance_estimate"][-1]
    assert d[0] == pytest.approx(0.1 * f0, rel=1e-3)     # exact model: estimate = load


@pytest.mark.slow
def test_offset_free_on_the_detailed_plant(setup) -> None:  # type: ignore[no-untyped-def]
    """Model mismatch: the plant is the detailed flux model with eddy currents, the
    controller model the reduced one; +10 % load."""
    mag, _, model, plain, veh, f0 = setup
    plant = mk.FluxModel(mag)
    load = lambda t: 0.1 * f0 if t >= 0.02 else 0.0  # noqa: E731
    ends = {}
    for name, m in (("offset-free", model), ("plain", plain)):
        ctl = _mpc(m)
        r = closed_loop(plant, veh, ctl, duration_s=0.6, dt_s=DT, initial_gap_m=S0,
                        initial_current_A=ctl.design_state[0], external_force_N=load)
        ends[name] = r.gap_m[-1] - S0
        assert np.all(np.abs(r.voltages_V) <= 440.0)
    print(ends)
    # measured: 1.7e-17 m (n_d = n_y: zero steady innovation) against 1 um; plain 211 um
    assert abs(ends["offset-free"]) < 1e-6
    assert abs(ends["plain"]) > 2e-5


def test_min_gap_constraint_in_a_large_disturbance(setup) -> None:  # type: ignore[no-untyped-def]
    """A load drop of 30 % pulls the magnet towards the rail: the MPC with min_gap_m =
    9.9 mm nearly holds it (it can cut the flux only as fast as the two-quadrant chopper
    allows, ``U >= -R_ec I_L``, not with -440 V), the cascade on the same run comes within
    7 mm (60 % puts the cascade on the rail)."""
    mag, maps, model, _, veh, f0 = setup
    plant = mk.CurrentModel(maps)
    drop = lambda t: -0.3 * f0 if t >= 0.02 else 0.0  # noqa: E731
    # qpOASES: with the chopper's I >= 0 rows active, CasADi's qrqp ("Failed to calculate
    # search direction") and OSQP (iteration limit) fail on this run's QP at t = 0.03 s
    ctl = _mpc(model, min_gap_m=0.0099, qp_solver="qpoases")
    mpc = closed_loop(plant, veh, ctl, duration_s=0.3, dt_s=DT, initial_gap_m=S0,
                      initial_current_A=ctl.design_state[0], external_force_N=drop)
    design = design_gap_controller(mag, mass_kg=veh.mass_kg, gap_m=S0, current_A=20.0)
    cas = closed_loop(mk.CurrentModel(maps), veh, design, duration_s=0.3, dt_s=DT,
                      initial_gap_m=S0,
                      initial_current_A=20.0, external_force_N=drop)
    for name, r in (("mpc", mpc), ("cascade", cas)):
        print(name, "min gap", r.gap_m.min(), "max dev", r.max_gap_deviation_m(),
              "IAE", r.iae_m_s(), "energy", r.energy_J())
    assert np.all(np.abs(mpc.voltages_V) <= 440.0)
    # the flux is cut at the chopper's floor, far from the -440 V limit (measured -153 V)
    assert mpc.voltages_V.min() > -300.0
    # soft constraint at the 2 ms shooting nodes, one RTI iteration per 1 ms sample, the
    # flux cut limited by the chopper: measured 44 um below 9.9 mm (4.8 um with a
    # four-quadrant -440 V); bound 60 um
    assert mpc.gap_m.min() >= 0.0099 - 6e-5
    # measured: cascade min 6.97 mm, max deviation 3.0 mm against the MPC's 0.11 mm
    assert cas.gap_m.min() < 0.0099 - 1e-3
    assert cas.max_gap_deviation_m() > 10 * mpc.max_gap_deviation_m()
    assert cas.iae_m_s() > mpc.iae_m_s()


def test_observer_converges_on_the_detailed_plant(setup) -> None:  # type: ignore[no-untyped-def]
    """The EKF alone on measurements of the detailed plant (eddy currents) under the
    cascade controller with a +10 % load, started 1 mm and 3 A off."""
    mag, _, model, _, veh, f0 = setup
    design = design_gap_controller(mag, mass_kg=veh.mass_kg, gap_m=S0, current_A=20.0)
    r = closed_loop(mk.FluxModel(mag), veh, design, duration_s=0.4, dt_s=DT,
                    initial_gap_m=S0, initial_current_A=20.0,
                    external_force_N=lambda t: 0.1 * f0 if t >= 0.02 else 0.0)
    ekf = ExtendedKalmanFilter(model, sample_time_s=DT)
    ekf.reset(np.r_[17.0, S0 + 1e-3, 0.0])
    err = []
    for k in range(r.time_s.size):
        u_prev = r.voltages_V[k - 1] if k else np.array([40.0])
        z = ekf.update(np.r_[r.gap_m[k], r.currents_A[k]], u_prev)
        err.append((z[1] - r.gap_m[k], z[2] - r.gap_rate_m_per_s[k], z[0] - r.currents_A[k, 0]))
    e = np.array(err)
    print("initial", e[0], "final", e[-1], "d", z[3:])
    # measured at 0.4 s: gap 7e-11 m, rate 1e-7 m/s, load estimate 0.05 % off; the
    # bounds leave 10x or more (the start errors are 1 mm, 1.6 mm/s after one sample)
    assert abs(e[-1, 0]) < 1e-6
    assert abs(e[-1, 1]) < 1e-4
    assert abs(z[3] - 0.1 * f0) < 0.02 * f0


def test_ipopt_peer_gives_the_same_solution(setup) -> None:  # type: ignore[no-untyped-def]
    """The same OCP from a disturbed state: Gauss-Newton SQP (bank tables, qrqp) against
    IPOPT (exact Hessian, B-spline maps)."""
    _, _, model, _, _, _ = setup
    x0 = np.r_[22.0, S0 + 5e-4, -0.01]
    sqp = _mpc(model, solver="sqp", horizon=10).solve_ocp(x0, [30.0, 1.0])
    ipo = _mpc(model, solver="ipopt", horizon=10).solve_ocp(x0, [30.0, 1.0])
    du = np.max(np.abs(sqp["inputs_V"] - ipo["inputs_V"]))
    dx = np.max(np.abs(sqp["states"][:, 1] - ipo["states"][:, 1]))
    print("du", du, "ds", dx, sqp["iterations"], ipo["iterations"])
    # measured: 3e-9 V and 2e-15 m (tables vs B-splines agree to rounding; both solvers
    # at tight tolerances); bounds 1 mV and 1 nm
    assert du < 1e-3
    assert dx < 1e-9


def test_a_disturbance_model_that_is_not_detectable_is_refused(setup) -> None:  # type: ignore[no-untyped-def]
    _, maps, _, _, veh, _ = setup
    bad = MagnetHeaveModel(maps, mass_kg=veh.mass_kg, disturbances=("force", "gap_sensor"))
    with pytest.raises(mk.ParameterError, match=r"not detectable: rank"):
        _mpc(bad)
    many = MagnetHeaveModel(maps, mass_kg=veh.mass_kg,
                            disturbances=("force", "voltage", "current_sensor"))
    with pytest.raises(mk.ParameterError, match="only 2 measurements"):
        _mpc(many)
    with pytest.raises(mk.ParameterError, match="disturbances"):
        MagnetHeaveModel(maps, mass_kg=veh.mass_kg, disturbances=("wind",))
