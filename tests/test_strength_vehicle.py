"""Independent checks of the vehicle mechanics, the vehicle run loop, the random
irregularities and the MPC / observer, added where the mutation check (tools/mutation.py,
docs/decisions.md) found errors that the other tests let through.

Every test compares with something the code under test does not compute itself:

* closed forms: the car bodies' static sink on their air springs, the frames' pitch
  inertia by the parallel-axis theorem, the one-interval MPC as the LQR of the
  linearisation (Riccati equation solved here by a doubling algorithm, not scipy's
  Schur method);
* a second method: an adaptive ODE solver for the mechanics' zero-order-hold step, the
  textbook Kalman step written out in NumPy for the EKF, ``Guideway.step`` replaying the
  run's recorded forces over recycled spans, finite differences of the recorded gaps and
  car-body motion for the gap rates and floor accelerations the run computes;
* an ensemble property: uniform random phases make the random profile zero-mean and
  stationary across seeds.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
import scipy.integrate

import maglevkit as mk
from maglevkit.control.model import DISTURBANCES, MagnetHeaveModel
from maglevkit.control.mpc import MPCWeights, OffsetFreeMPC
from maglevkit.control.observers import ExtendedKalmanFilter
from maglevkit.vehicle import STANDARD_GRAVITY, GermanTrackPSD, Guideway, RandomProfile
from maglevkit.vehicle.mechanics import VehicleMechanics
from maglevkit.vehicle.simulation import VehicleModel
from maglevkit.vehicle.train import load_vehicle


def _slot_mechanics(train: Any) -> VehicleMechanics:
    slots = train.magnet_slots()
    return VehicleMechanics(train, [s.centre_m for s in slots], [s.frame for s in slots])


# ------------------------------------------------------------------ mechanics and train data
def test_car_bodies_sink_by_weight_over_air_spring_stiffness() -> None:
    """Standing trim with the frames held at their nominal position: every car body (same
    mass, same springs) sinks by ``(m_body + m_payload) g / (n k_s)`` with ``n`` the air
    springs under it; the joints stay unloaded (equal sink), no pitch."""
    tr = load_vehicle()
    mech = _slot_mechanics(tr)
    q, _ = mech.static_trim(np.ones(mech.B.shape[1]))
    ns = tr.n_sections
    n_springs = tr.n_frames_per_section * len(tr.spring_positions_m)
    sink = (tr.car_body_mass_kg + tr.payload_kg) * STANDARD_GRAVITY / (
        n_springs * tr.spring_stiffness_N_per_m)
    # one linear solve of a 6 x 6 system: rounding (measured 2.2e-16 relative, sink
    # 0.244 m, the static deflection of a ~1.1 Hz suspension); bound 1e-12
    np.testing.assert_allclose(q[0:2 * ns:2], sink, rtol=1e-12)
    assert np.abs(q[1:2 * ns:2]).max() < 1e-12 * sink / tr.section_length_m
    assert not q[2 * ns:].any()                       # frames at z = theta = 0


def test_mechanics_zoh_step_matches_an_ode_solver_with_held_forces() -> None:
    """``x+ = Ad x + Bd Q`` of the damped train under gravity and held magnet forces
    against DOP853 on ``M q'' + C q' + K q = Q`` (rtol 1e-12) over one step, for a
    typical and a long step."""
    mech = _slot_mechanics(load_vehicle())
    n = mech.n_dof
    rng = np.random.default_rng(7)
    x0 = np.r_[rng.normal(0, 1e-3, n), rng.normal(0, 1e-2, n)]
    forces = rng.normal(6e4, 5e3, mech.B.shape[1])
    gen = mech.Q_gravity - mech.B @ forces
    minv = 1.0 / np.diag(mech.M)

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        return np.r_[x[n:], minv * (gen - mech.K @ x[:n] - mech.C @ x[n:])]

    for dt in (1e-3, 2e-2):
        ad, bd = mech.discretize(dt)
        got = ad @ x0 + bd @ gen
        ref = scipy.integrate.solve_ivp(rhs, (0.0, dt), x0, method="DOP853", rtol=1e-12,
                                        atol=1e-16).y[:, -1]
        for part in (slice(0, n), slice(n, 2 * n)):    # displacements, velocities
            change = ref[part] - x0[part]
            err = np.abs(got[part] - ref[part]).max() / np.abs(change).max()
            # measured <= 1.8e-14 of the change over the step (both methods at
            # rounding); bound 1e-8.  Bd over dt/2 is off by 24-47 %.
            assert err < 1e-8, (dt, part, err)


def test_frame_and_car_body_inertia_by_the_parallel_axis_theorem() -> None:
    """Frame pitch inertia = own inertia + magnets as point masses (both sides) at their
    slot centres about the frame centre; car body = own + uniform payload ``m L^2/12``
    (here by quadrature of the line mass)."""
    tr = load_vehicle()
    mech = _slot_mechanics(tr)
    ns = tr.n_sections
    slots = tr.magnet_slots()
    for f in range(tr.n_frames):
        on = [s for s in slots if s.frame == f]
        xc = float(mech.body_centres_m[ns + f])
        j = tr.frame_pitch_inertia_kg_m2 + sum(tr.sides * tr.magnet_mass_kg * (s.centre_m - xc) ** 2
                                               for s in on)
        m = tr.frame_mass_kg + tr.sides * tr.magnet_mass_kg * len(on)
        # sums of a few products: rounding (bound 1e-12)
        assert mech.body_inertia_kg_m2[ns + f] == pytest.approx(j, rel=1e-12)
        assert mech.body_mass_kg[ns + f] == pytest.approx(m, rel=1e-12)
        # the frame's centre of mass is its centre: the magnets sit symmetrically
        assert sum(s.centre_m - xc for s in on) == pytest.approx(0.0, abs=1e-12)
    half = 0.5 * tr.section_length_m
    x = np.linspace(-half, half, 2001)
    payload = scipy.integrate.simpson(x ** 2 * tr.payload_kg / tr.section_length_m, x=x)
    # Simpson's rule is exact for x^2 (rounding only); bound 1e-10
    np.testing.assert_allclose(mech.body_inertia_kg_m2[:ns],
                               tr.car_body_pitch_inertia_kg_m2 + payload, rtol=1e-10)


# ------------------------------------------------------------------ one vehicle run
V_RUN = 500 / 3.6          # m/s
T_RUN = 0.4                # s: the nose reaches a recycled span at ~0.30 s


@pytest.fixture(scope="module")
def recorded_run() -> dict[str, Any]:
    """The elastic TR09 at 500 km/h over a random profile for 0.5 s, with the gaps and
    gap rates handed to the magnet bank at every step recorded by a wrapper."""
    model = VehicleModel(load_vehicle())
    # German track PSD shape over 1-100 m scaled to 0.3 mm RMS (as the CLI's random:0.3e-3),
    # 200 components to keep the profile evaluations cheap
    lo, hi = 2 * math.pi / 100.0, 2 * math.pi / 1.0
    base = GermanTrackPSD()
    psd = GermanTrackPSD(A_v_m_rad=base.A_v_m_rad * 0.3e-3 ** 2 / base.variance_m2(lo, hi))
    prof = RandomProfile(psd, lo, hi, n_components=200, seed=1)
    calls: list[tuple[np.ndarray, np.ndarray]] = []
    bank_step = model.bank.step

    def spy(state: Any, dt: float, u: Any, gaps: Any, rates: Any, **kw: Any) -> Any:
        calls.append((np.array(gaps, dtype=float), np.broadcast_to(
            np.asarray(rates, dtype=float), np.shape(gaps)).copy()))
        return bank_step(state, dt, u, gaps, rates, **kw)

    model.bank.step = spy  # type: ignore[method-assign]
    try:
        # the NumPy loop (the reference; the compiled step calls the bank inside its own
        # kernel, so the spy would see nothing there): tests/test_vehicle_compiled.py
        # holds the compiled step equal to this loop
        res = model.run(speed_m_per_s=V_RUN, duration_s=T_RUN, irregularity=prof,
                        loop="python")
    finally:
        del model.bank.step
    assert res.touchdown is None, res.report()
    assert len(calls) == res.dataset.time.size       # one bank step per time step
    gaps = np.array([c[0] for c in calls[1:]])        # calls[0]: the discarded warm-up step
    rates = np.array([c[1] for c in calls[1:]])
    ds = res.dataset
    x = (float(ds.attrs["nose_position_at_t0_m"]) + V_RUN * ds.time.values[:, None]
         - model.circuit_xi_m[None, :])                # circuit positions on the guideway
    # r: the irregularity plus the girders' built-in precamber (the bundled guideway
    # file's; the run adds it to the irregularity, as a camber is the same term of the gap)
    full = prof + model.guideway.built_in_profile
    return {"model": model, "run": res, "gaps": gaps, "rates": rates, "x": x,
            "r": full.elevation_m(x), "r_x": full.slope(x)}


def test_gap_rate_is_the_time_derivative_of_the_gap(recorded_run: dict[str, Any]) -> None:
    """The gap rate handed to the magnets (frame motion, guideway rate with the moving-load
    term ``v dw/dx``, irregularity rate ``v dr/dx``) against central differences of the
    gaps handed to them, away from the piers (where ``dw/dx`` jumps).

    The profile's part is taken out exactly first (``d(s + r)/dt = s' + v dr/dx`` with
    the profile's own slope): its wavelengths down to 1 m pass at 139 Hz, where a
    central difference over 2 ms is off by up to 1e-3 m/s."""
    g, r = recorded_run["gaps"], recorded_run["rates"]
    dt = float(recorded_run["run"].dataset.attrs["dt_s"])
    n = g.shape[0]
    x, r_x = recorded_run["x"][:n], recorded_run["r_x"][:n]
    g_smooth = g + recorded_run["r"][:n]
    r_smooth = r + V_RUN * r_x
    fd = (g_smooth[2:] - g_smooth[:-2]) / (2 * dt)
    span = recorded_run["model"].guideway.span.length_m
    origin = recorded_run["model"].guideway.origin_m
    xm = x[1:-1]
    off = np.abs(((xm - origin) / span + 0.5) % 1.0 - 0.5) * span
    away = off > V_RUN * dt                           # no pier within the difference
    assert away.mean() > 0.95
    err = np.abs(fd - r_smooth[1:-1])[away]
    scale = np.abs(r[1:-1][away]).max()
    print(f"gap rate vs central difference: max {err.max():.3e} m/s (median "
          f"{np.median(err):.1e}), rates up to {scale:.3e} m/s, profile rate up to "
          f"{np.abs(V_RUN * r_x).max():.3e} m/s")
    # measured: max 4.3e-4 m/s, median 3.6e-5 m/s (the frames' acceleration jumps once
    # per step with the held magnet forces, which the central difference averages) on
    # rates up to 0.16 m/s; bound 2e-3 m/s.  A wrong sign of v dw/dx or of v dr/dx
    # (profile rates up to 0.038 m/s) is off by twice that term.
    assert err.max() < 2e-3
    assert scale > 0.03                                # the check has something to see


def test_recorded_gap_is_the_kinematic_gap(recorded_run: dict[str, Any]) -> None:
    """``s = s0 + z_f + theta_f (xi - xi_f) - w - r`` from the recorded frame motion, the
    recorded deflection and the profile at the circuit positions (down positive)."""
    run, model = recorded_run["run"], recorded_run["model"]
    ds = run.dataset
    tr = model.train
    frames = model.circuit_frame
    z = ds.frame_heave.values[:, frames]
    th = ds.frame_pitch.values[:, frames]
    lever = model.circuit_xi_m - tr.frame_centres_m[frames]
    want = tr.nominal_gap_m + z + th * lever - ds.guideway_deflection.values - recorded_run["r"]
    print(f"recorded gap vs kinematic gap: {np.abs(ds.gap.values - want).max():.1e} m")
    # the same sum in another order: rounding (measured 3e-18 m); bound 1e-12 m
    assert np.abs(ds.gap.values - want).max() < 1e-12
    assert np.abs(ds.guideway_deflection.values).max() > 1e-3   # the girders do deflect


def test_guideway_replay_over_recycled_spans(recorded_run: dict[str, Any]) -> None:
    """Guideway.step (the guideway module's own ring buffer, which resets a recycled span)
    replaying the recorded forces: the run's deflections under the circuits agree also
    after the nose has reached a span whose ring row was recycled."""
    run, model = recorded_run["run"], recorded_run["model"]
    ds = run.dataset
    gw = model.guideway
    ref = Guideway(gw.span, n_spans=gw.n_spans, origin_m=gw.origin_m)
    xi = model.circuit_xi_m
    x0 = float(ds.attrs["nose_position_at_t0_m"])
    dt = float(ds.attrs["dt_s"])
    f = ds.force.values
    st = ref.initial_state(first_span=int(ref.span_index(x0 - xi.max())))
    first0 = st.first_span
    qs = gw.span.static_modal_displacement(ref.modal_forces(st, x0 - xi,
                                                            model.mechanics_trim_forces()))
    st = type(st)(0.0, st.first_span, qs, np.zeros_like(qs))
    worst = 0.0
    for k in range(ds.sizes["time"] - 1):
        x = x0 + V_RUN * k * dt - xi
        w = ref.deflection(st, x).deflection_m
        worst = max(worst, float(np.abs(w - ds.guideway_deflection.values[k]).max()))
        st = ref.step(st, dt, x + 0.5 * V_RUN * dt, 0.5 * (f[k] + f[k + 1]))
    # a span whose row held another span before was loaded
    assert int(ds.span_index.values.max()) >= first0 + gw.n_spans
    assert float(np.abs(ds.guideway_deflection.values).max()) > 1e-3
    print(f"guideway replay: {worst:.1e} m")
    # same arithmetic in another order: measured 2e-17 m; bound 1e-12 m
    assert worst < 1e-12


def test_floor_acceleration_is_the_second_derivative_of_the_floor(
        recorded_run: dict[str, Any]) -> None:
    """The car-body floor accelerations (from the equations of motion) against the second
    central difference of the recorded floor displacement ``z + theta (xi - xi_c)``."""
    ds = recorded_run["run"].dataset
    dt = float(ds.attrs["dt_s"])
    length = recorded_run["model"].train.section_length_m
    fp = ds.floor_point.values
    disp = (ds.car_body_heave.values[:, :, None]
            + ds.car_body_pitch.values[:, :, None] * fp[None, None, :] * length)
    fd = (disp[2:] - 2 * disp[1:-1] + disp[:-2]) / dt ** 2
    acc = ds.car_body_acceleration.values[1:-1]
    err = np.abs(fd - acc).max()
    spread = np.abs(acc[:, :, 0] - acc[:, :, -1]).max()   # front vs rear floor point
    print(f"floor acceleration vs second difference: {err:.3e} m/s^2 (front - rear up to "
          f"{spread:.3e} m/s^2)")
    # measured 2.1e-4 m/s^2 (O(dt^2) of the car-body motion; the dampers pass the
    # frames' once-per-step acceleration jumps on); bound 1e-3 m/s^2, far below the
    # front-rear difference (measured up to 0.52 m/s^2) that a wrong lever arm flips
    assert err < 1e-3
    assert spread > 2e-2


# ------------------------------------------------------------------ random irregularity
def test_random_profile_ensemble_is_zero_mean_and_stationary() -> None:
    """Across seeds the random profile at fixed positions has mean 0 and the band
    variance at every position (uniform phases on [0, 2 pi) make the sum of cosines a
    zero-mean stationary process; the spatial tests see one seed only)."""
    psd = GermanTrackPSD()
    lo, hi = 2 * math.pi / 100.0, 2 * math.pi / 1.0
    x = np.array([0.0, 0.7, 1.5, 3.0, 6.0, 12.0, 25.0])
    n_seeds = 400
    r = np.array([RandomProfile(psd, lo, hi, n_components=200, seed=s)(x)
                  for s in range(n_seeds)])
    var = psd.variance_m2(lo, hi)
    z = r.mean(axis=0) / math.sqrt(var / n_seeds)
    ratio = r.var(axis=0) / var
    print("ensemble mean / its standard error:", np.round(z, 2), "variance ratio:",
          np.round(ratio, 3))
    # the sample mean of 400 seeds has the standard error sqrt(var / 400): bound 4 of
    # them (measured |z| <= 1.1); the sample variance's relative standard error is
    # ~sqrt(2/400) = 7 % for Gaussian-like sums: bound 30 % (measured 0.89 ... 1.02).
    # Phases on [0, pi) put the mean at -(2/pi) sum a_k sin(Omega_k x): 23-37 standard
    # errors at 0.7-12 m, 5 at 25 m (computed for these seeds).
    assert np.abs(z).max() < 4.0
    assert np.abs(ratio - 1).max() < 0.3


# ------------------------------------------------------------------ MPC and observer
S_REF = 0.010


@pytest.fixture(scope="module")
def heave(u_magnet: mk.Magnet) -> tuple[Any, float]:
    maps = mk.build_maps(u_magnet, gaps_m=np.linspace(0.004, 0.02, 17),
                         currents_A=np.linspace(0, 80, 33), progress=False)
    f0 = float(mk.solve_statics(u_magnet, gaps_m=S_REF, currents_A=20.0).force_N)
    return maps, f0 / STANDARD_GRAVITY


def test_target_is_an_equilibrium_with_the_reference_as_measured_gap(
        heave: tuple[Any, float]) -> None:
    """The target calculation under all four disturbances at once: the model's right-hand
    side vanishes at ``(x_t, u_t, d)`` and the *measured* gap there is the reference."""
    maps, mass = heave
    model = MagnetHeaveModel(maps, mass_kg=mass, disturbances=DISTURBANCES, compiled="never")
    nc = model.n_circuits
    d = np.r_[0.08 * mass * STANDARD_GRAVITY, np.full(nc, 3.0), 2e-4, np.full(nc, 0.4)]
    ref = 0.0105
    xt, ut = model.steady_state(ref, d)
    xdot = np.asarray(model.rhs(xt, ut, d, model.table), dtype=float).ravel()
    y = np.asarray(model.measurement(xt, ut, d, model.table), dtype=float).ravel()
    print("xdot at the target", xdot, "measured gap", y[0])
    # exact up to the Newton tolerance (|dI| < 1e-9 A) and rounding: measured
    # |dI_L/dt| = 0 A/s, |s''| 1.8e-15 m/s^2; bounds 1e-6 A/s and 1e-8 m/s^2.  A sign
    # error in the voltage or force disturbance gives -60 A/s or -1.57 m/s^2.
    assert np.abs(xdot[:nc]).max() < 1e-6
    assert xdot[nc] == 0.0                        # s' = 0 at the target
    assert abs(xdot[nc + 1]) < 1e-8
    assert y[0] == pytest.approx(ref, abs=1e-15)  # measured gap = reference (gap sensor)
    assert xt[nc] == pytest.approx(ref - 2e-4, abs=1e-15)


def test_ekf_step_is_the_textbook_kalman_step(heave: tuple[Any, float]) -> None:
    """One EKF sample against the extended Kalman filter written out in NumPy from the
    model's own linearisation: ``P- = F P F' + Q``, ``K = P- H' (H P- H' + R)^-1``,
    ``z+ = z- + K (y - h(z-))``, ``P+ = (I - K H) P-`` (the standard form; the EKF uses
    Joseph's form, equal for this gain)."""
    maps, mass = heave
    model = MagnetHeaveModel(maps, mass_kg=mass, compiled="never")
    nx, nd, nc = model.nx, model.nd, model.n_circuits
    T = 1e-3
    ekf = ExtendedKalmanFilter(model, sample_time_s=T)
    xs, us = model.steady_state(S_REF)
    z0 = np.r_[xs + np.r_[np.full(nc, 1.0), 2e-4, 5e-3], 50.0, np.full(nc, 1.5)]
    rng = np.random.default_rng(5)
    sd = np.r_[np.full(nc, 1.0), 1e-3, 1e-2, 0.1 * mass * STANDARD_GRAVITY, np.full(nc, 10.0)]
    corr = np.eye(nx + nd) + 0.3 * (lambda a: a @ a.T)(rng.normal(size=(nx + nd, 2)))
    corr /= np.sqrt(np.outer(np.diag(corr), np.diag(corr)))
    P0 = corr * np.outer(sd, sd)
    ekf.reset(z0[:nx], z0[nx:], covariance=P0)
    u_prev = us + 3.0
    y = np.r_[xs[nc] + 1e-4, np.full(nc, xs[0] + 0.5)]
    z1 = ekf.update(y, u_prev).copy()
    P1 = ekf.covariance.copy()
    # reference
    x, d = z0[:nx], z0[nx:]
    lin = model.linearize(x, u_prev, d, h=T)
    xp = np.asarray(model.discrete(T, 1)(x, u_prev, d, model.table), dtype=float).ravel()
    F = np.block([[lin["A"], lin["Bd"]], [np.zeros((nd, nx)), np.eye(nd)]])
    Pm = F @ P0 @ F.T + ekf.Q
    lp = model.linearize(xp, u_prev, d, h=T)
    H = np.hstack([lp["C"], lp["Cd"]])
    yp = np.asarray(model.measurement(xp, u_prev, d, model.table), dtype=float).ravel()
    S = H @ Pm @ H.T + ekf.R
    K = np.linalg.solve(S, H @ Pm).T
    z_ref = np.r_[xp, d] + K @ (y - yp)
    P_ref = (np.eye(nx + nd) - K @ H) @ Pm
    P_ref = 0.5 * (P_ref + P_ref.T)
    dz = np.abs(z1 - z_ref) / sd
    dp = np.abs(P1 - P_ref) / np.outer(sd, sd)
    print(f"EKF vs textbook: state {dz.max():.2e}, covariance {dp.max():.2e} (in units of "
          "the prior standard deviations)")
    # the same formulas in another arrangement (Joseph vs standard form, CasADi vs
    # NumPy): measured 3.6e-15 (state) and 5.6e-16 (covariance) in units of the prior
    # standard deviations; bounds 1e-8 and 1e-6 (rounding of the 5 x 5 algebra with
    # entries over 9 decades).
    assert dz.max() < 1e-8
    assert dp.max() < 1e-6
    assert np.abs(z1 - np.r_[xp, d]).max() > 0     # the correction did something


def _dare_doubling(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Stabilising solution of the discrete algebraic Riccati equation by the structure-
    preserving doubling algorithm (Chu, Fan, Lin 2005), quadratically convergent."""
    n = a.shape[0]
    ak, gk, hk = a.copy(), b @ np.linalg.solve(r, b.T), q.copy()
    for _ in range(100):
        w = np.linalg.inv(np.eye(n) + gk @ hk)
        a_next = ak @ w @ ak
        g_next = gk + ak @ w @ gk @ ak.T
        h_next = hk + ak.T @ hk @ w @ ak
        done = np.abs(h_next - hk).max() <= 1e-14 * np.abs(h_next).max()
        ak, gk, hk = a_next, 0.5 * (g_next + g_next.T), 0.5 * (h_next + h_next.T)
        if done:
            return hk
    raise AssertionError("doubling did not converge")


@pytest.fixture(scope="module")
def one_interval_mpc(heave: tuple[Any, float]) -> OffsetFreeMPC:
    maps, mass = heave
    model = MagnetHeaveModel(maps, mass_kg=mass, compiled="never")
    return OffsetFreeMPC(model, gap_ref_m=S_REF, sample_time_s=1e-3, horizon=1, solver="sqp",
                         tol=1e-12, max_iter=50)


def test_one_interval_mpc_is_the_lqr_of_the_linearisation(
        one_interval_mpc: OffsetFreeMPC) -> None:
    """With the terminal cost ``P`` of the infinite-horizon LQR, a horizon of one interval
    gives the LQR input ``u - u_t = -(R + B'PB)^-1 B'PA (x - x_t)`` for small deviations
    (constraints inactive); ``Q``, ``R`` from the weights' definition (Bryson's rule),
    ``P`` by doubling (not scipy)."""
    mpc = one_interval_mpc
    model = mpc.model
    nc = model.n_circuits
    T = mpc.sample_time_s
    xt, ut = mpc.design_state, mpc.design_input
    w = MPCWeights()
    q = np.diag(np.r_[np.full(nc, w.current_A ** -2), w.gap_m ** -2, w.gap_rate_m_per_s ** -2])
    r = np.eye(model.nu) * w.voltage_V ** -2
    lin = model.linearize(xt, ut, h=T)
    # scaled coordinates (A, 1 mm, 1 cm/s; 100 V) for the doubling iteration
    sx, su = np.r_[np.full(nc, 1.0), 1e-3, 1e-2], np.full(model.nu, 100.0)
    a_s = lin["A"] * sx[None, :] / sx[:, None]
    b_s = lin["B"] * su[None, :] / sx[:, None]
    p_s = _dare_doubling(a_s, b_s, q * np.outer(sx, sx), r * np.outer(su, su))
    p = p_s / np.outer(sx, sx)
    k = np.linalg.solve(r + lin["B"].T @ p @ lin["B"], lin["B"].T @ p @ lin["A"])
    mism = []
    for scale in (1.0, 0.5):
        dx = scale * np.r_[np.full(nc, 0.02), 2e-7, 2e-5]
        sol = mpc.solve_ocp(xt + dx)
        du = sol["inputs_V"][0] - ut
        lqr = -k @ dx
        mism.append(float(np.abs(du - lqr).max() / np.abs(lqr).max()))
    print("one-interval MPC vs LQR (relative):", mism, "LQR input", -k @ dx)
    # the nonlinearity of the model makes the mismatch second order: measured 4.2e-4 at
    # the full and 2.1e-4 at half the deviation; bound 2e-3.  R x1.05 in the Riccati
    # equation alone moves the LQR input by 3.2 %.  The doubling P equals scipy's
    # solve_discrete_are to 7e-15 (relative).
    assert mism[0] < 2e-3 and mism[1] < 2e-3
    assert mism[1] < 0.75 * mism[0]                  # shrinks with the deviation


def test_mpc_inputs_saturate_exactly_at_the_voltage_limit(
        one_interval_mpc: OffsetFreeMPC) -> None:
    """Far from the target the unconstrained optimum lies beyond the chopper's limits on
    either side: the MPC's input is then the limit itself, +440 V with the magnet 2.5 mm
    too far from the rail; 2.5 mm too close, the larger of -440 V and the two-quadrant
    chopper's floor, the voltage at which the coil current is zero (each side's bound is
    active)."""
    import casadi as ca

    mpc = one_interval_mpc
    m = mpc.model
    nc = m.n_circuits
    x, uu, d = ca.MX.sym("x", m.nx), ca.MX.sym("u", m.nu), ca.MX.sym("d", m.nd)
    coil = ca.Function("coil", [x, uu, d], [m.coil_currents(x, uu, d)])
    xt = mpc.design_state
    for dgap, sign in ((2.5e-3, 1.0), (-2.5e-3, -1.0)):
        x0 = xt.copy()
        x0[nc] += dgap
        u = mpc.solve_ocp(x0)["inputs_V"][0]
        i0 = np.asarray(coil(x0, u, np.zeros(m.nd))).ravel()
        print(f"gap {dgap:+.1e} m: u = {u}, u - limit = "
              f"{float(u[0] - sign * mpc.voltage_limit_V):.1e} V, coil current {i0}")
        # the QP's bound is exact up to its tolerance (measured 5.7e-14 V from +440 V, and
        # the coil current 0 to 1e-14 A at the floor); bounds 440 uV (1e-6 of the limit,
        # what solve() accepts before it raises) and 1e-9 A.  An upper bound x1.05 lets
        # the QP go to 462 V.
        at_limit = np.abs(u - sign * mpc.voltage_limit_V) < 1e-6 * mpc.voltage_limit_V
        at_floor = (sign < 0) & (np.abs(i0) < 1e-9)
        assert np.all(at_limit | at_floor), (u, i0)
        if sign > 0:
            assert np.all(at_limit), u
