"""Issue 23, item 4 (a realistic default run): the girders' precamber, the cascade's damping
input blended with the magnet's absolute velocity, and the choppers' freewheeling diodes in
the plant, each against an independent reference."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.control import damping_input, design_gap_controller
from maglevkit.errors import InputError, OutOfRangeError, ParameterError, ParameterFileError
from maglevkit.plant import STANDARD_GRAVITY
from maglevkit.reduced.bank import MagnetBank
from maglevkit.vehicle import load_guideway, load_vehicle
from maglevkit.vehicle.data import parse_guideway
from maglevkit.vehicle.guideway import BeamSpan, Guideway
from maglevkit.vehicle.mapcache import vehicle_maps
from maglevkit.vehicle.simulation import Failure, VehicleModel

# ---------------------------------------------------------------- precamber


def _uniform_load_line(x: np.ndarray, q: float, length: float, ei: float) -> np.ndarray:
    """Textbook deflection line of a simply supported beam under a uniform load ``q``
    (down positive): ``w = q x (L^3 - 2 L x^2 + x^3) / (24 EI)``."""
    return q * x * (length ** 3 - 2 * length * x ** 2 + x ** 3) / (24 * ei)


def _uniform_load_slope(x: np.ndarray, q: float, length: float, ei: float) -> np.ndarray:
    return q * (length ** 3 - 6 * length * x ** 2 + 4 * x ** 3) / (24 * ei)


def test_precamber_cancels_the_uniform_load_line_and_its_pier_kink() -> None:
    """A girder precambered by its uniform-load midspan deflection is straight under that
    load: camber + deflection line = 0 everywhere, and so is the slope at both piers (no
    kink there, where the bare line turns by ``q L^3 / (24 EI)`` on each side)."""
    length, ei, q = 24.768, 4.0e10, 22.0e3
    span = BeamSpan(length, ei, 7500.0)
    a = span.uniform_load_midspan_deflection_m(q)
    assert a == pytest.approx(5 * q * length ** 4 / (384 * ei), rel=1e-15)
    span_c = dataclasses.replace(span, precamber_m=a)
    gw = Guideway(span_c, origin_m=3.0)
    prof = gw.built_in_profile
    x = np.linspace(0.0, length, 401)
    w = _uniform_load_line(x, q, length, ei)
    # the two polynomials in another arrangement: rounding (~1e-18 m on 2.7e-3 m)
    assert np.abs(prof.elevation_m(3.0 + x) + w).max() < 1e-15
    assert np.abs(prof.elevation_m(3.0 + x + 2 * length) + w).max() < 1e-15   # every span
    # slopes just after and just before a pier: the bare line has +-q L^3/(24 EI), the
    # precambered girder none (bound 1e-12 rad against 4.6e-4 rad)
    kink = q * length ** 3 / (24 * ei)
    assert _uniform_load_slope(np.array([0.0]), q, length, ei)[0] == pytest.approx(kink)
    for xi in (0.0, length * (1 - 1e-12)):
        total = (prof.slope(3.0 + xi) + _uniform_load_slope(np.array([xi]), q, length, ei))
        assert abs(float(np.squeeze(total))) < 1e-12
    # and against the span's own modal statics (the sine series of the same load,
    # truncated at 5 modes: its midspan value converges as 1/j^5, measured 2e-5 relative)
    qf = q * length * (1 - np.cos(np.arange(1, 6) * math.pi)) / (np.arange(1, 6) * math.pi)
    w_modal = span_c.static_modal_displacement(qf) @ np.sin(np.arange(1, 6) * math.pi / 2)
    assert w_modal == pytest.approx(a, rel=1e-4)


def test_bundled_guideway_precamber_is_the_static_line_under_the_train() -> None:
    """[D] in the file: 5 q L^4 / (384 EI) with the TR09's 170 t over 75.8 m."""
    data = load_guideway()
    span = data.span
    q = 170e3 * STANDARD_GRAVITY / 75.8
    assert span.precamber_m == 2.7e-3
    # the file rounds 2.694 mm to the published 2.7 mm: within 0.5 %
    assert span.uniform_load_midspan_deflection_m(q) == pytest.approx(span.precamber_m,
                                                                      rel=5e-3)
    assert "[D]" in data.provenance["guideway.precamber"]
    assert data.guideway().built_in_profile.amplitude_m == -2.7e-3
    assert data.guideway(rigid=True).built_in_profile is None       # an ideal, even track
    flat = dataclasses.replace(span, precamber_m=0.0)
    assert Guideway(flat).built_in_profile is None
    # optional key: a file without it has no precamber; bad values name the key
    base = {"span_length": 24.768, "mass_per_length": 7500.0, "bending_stiffness": 4e10,
            "damping_ratio": 0.01, "modes": 5}
    assert parse_guideway({"guideway": base}).span.precamber_m == 0.0
    with pytest.raises(ParameterFileError, match="precamber"):
        parse_guideway({"guideway": {**base, "precamber": "2.7 mm"}})
    with pytest.raises(ParameterError, match="precamber_m"):
        BeamSpan(24.768, 4e10, 7500.0, precamber_m=math.nan)


# ---------------------------------------------------------------- damping input


def test_damping_input_blends_linearly_and_is_the_gap_rate_at_zero() -> None:
    rate = np.array([0.1, -0.05, 0.0, 3e-17])
    vel = np.array([-0.2, 0.05, 1.0, 7.0])
    assert np.array_equal(damping_input(rate, vel, 0.0), rate)      # bit for bit
    np.testing.assert_allclose(damping_input(rate, vel, 1.0), vel, rtol=0, atol=1e-15)
    np.testing.assert_allclose(damping_input(rate, vel, 0.25), 0.75 * rate + 0.25 * vel,
                               rtol=0, atol=1e-15)


def test_single_magnet_results_do_not_change_with_the_blend() -> None:
    """Without an absolute velocity measured (a single magnet on a rigid track, where it
    equals the gap rate) the blended cascade gives the same voltages and the same run."""
    magnet = mk.load_magnet("u-magnet")
    point = dict(mass_kg=150.0, gap_m=0.010, current_A=20.0)
    plain = design_gap_controller(magnet, **point)
    blended = design_gap_controller(magnet, **point, velocity_blend=0.5)
    assert (blended.kp_per_m, blended.kd_s_per_m) == (plain.kp_per_m, plain.kd_s_per_m)
    psi = np.asarray(plain.flux_bias_Wb) * 1.01
    args = (0.0101, 0.03, 1e-5, np.array([20.0, 20.0][:len(psi)]), psi)
    assert np.array_equal(plain.voltages(*args), blended.voltages(*args))
    assert np.array_equal(plain.voltages(*args),
                          blended.voltages(*args, absolute_velocity_m_per_s=0.03))
    # with an absolute velocity, only the D term changes: k_d beta (u' - s') psi0 k_psi
    du = blended.voltages(*args, absolute_velocity_m_per_s=0.01) - plain.voltages(*args)
    want = (plain.kflux_per_s * np.asarray(plain.flux_bias_Wb) * plain.kd_s_per_m * 0.5
            * (0.01 - 0.03))
    np.testing.assert_allclose(du, want, rtol=1e-9)
    with pytest.raises(ParameterError, match="velocity_blend"):
        dataclasses.replace(plain, velocity_blend=1.5)


def test_vehicle_on_a_rigid_even_track_is_blind_to_the_blend() -> None:
    """Rigid guideway, no irregularity: every force point's gap rate is its absolute
    velocity, so the blend changes nothing (bit for bit, NumPy loop) even when a failed
    circuit shakes the frames."""
    train = load_vehicle()
    runs = []
    for blend in (0.0, 0.5):
        model = VehicleModel(dataclasses.replace(train, control_velocity_blend=blend),
                             rigid=True, compiled="never")
        res = model.run(speed_m_per_s=100.0, duration_s=0.08,
                        failures=[Failure("s2m4/front", 0.01)], loop="python")
        runs.append(res.dataset)
    for name in ("gap", "current", "voltage"):
        assert np.array_equal(runs[0][name].values, runs[1][name].values), name
    assert float(np.ptp(runs[0].gap.values)) > 1e-5            # the failure did move them


def test_vehicle_file_velocity_blend_is_checked() -> None:
    from maglevkit.vehicle.train import parse_vehicle

    train = load_vehicle()
    assert train.control_velocity_blend == 0.5
    assert "control.velocity_blend" in train.provenance
    params = mk.parameter_files.read_parameter_file("tr09", what="vehicle", folder="vehicle",
                                                    table="vehicle")[0]
    bad = {**params, "control": {**params["control"], "velocity_blend": 2.0}}
    with pytest.raises(ParameterFileError, match="velocity_blend"):
        parse_vehicle(bad)
    none = {**params, "control": {k: v for k, v in params["control"].items()
                                  if k != "velocity_blend"},
            "provenance": {k: v for k, v in params["provenance"].items()
                           if k != "control.velocity_blend"}}
    assert parse_vehicle(none).control_velocity_blend == 0.0


# ---------------------------------------------------------------- freewheeling diodes


@pytest.fixture(scope="module")
def tr09_maps() -> mk.CharacteristicMaps:
    return vehicle_maps(mk.load_magnet("tr09-standard"))


def _discharge(maps: mk.CharacteristicMaps, *, freewheel: bool, dt: float,
               duration: float, voltage_V: float = -440.0
               ) -> tuple[MagnetBank, np.ndarray, np.ndarray, float]:
    bank = MagnetBank({"m": maps}, compiled="never", freewheel=freewheel)
    state = bank.initial_state(gaps_m=0.010, currents_A=33.5)
    i_l0 = state.inductor_currents_A.copy()
    u = voltage_V * np.ones(bank.n_circuits)
    il, coil = [i_l0], [bank.outputs(state, u).currents_A]
    for _ in range(int(round(duration / dt))):
        state, out = bank.step(state, dt, u)
        il.append(state.inductor_currents_A.copy())
        coil.append(out.currents_A)
    return bank, np.array(il), np.array(coil), float(bank.eddy_resistance_ohm[0])


@pytest.mark.parametrize("voltage", [-440.0, -70.0])
def test_diode_holds_the_coil_current_at_zero_and_the_energy_balances(tr09_maps,
                                                                      voltage: float) -> None:
    """A negative voltage on a charged coil (33.5 A) at a fixed gap: the coil current
    falls to 0 and stays there (never negative), the flux decays through the eddy path;
    the magnetic energy at the start goes back to the supply and into R_el and R_ec.
    -U_max = -440 V is below -R_ec I_L = -137 V: the diodes take over at once (I = 0
    from the start, all the energy into R_ec); -70 V drives I from 12.5 A down to 0
    first (energy into the supply and both resistances)."""
    dt, duration = 1e-4, 0.8
    bank, il, coil, r_ec = _discharge(tr09_maps, freewheel=True, dt=dt, duration=duration,
                                      voltage_V=voltage)
    # I = (U_eff/R_ec + I_L)/a with U_eff = -R_ec I_L: zero up to rounding (1e-13 A)
    assert coil.min() >= -1e-12
    assert np.all(il > 0.0)                      # I_L decays through R_ec, never crosses 0
    reached = np.flatnonzero(coil.max(axis=1) < 1e-9)
    # measured: at once at -440 V, after 0.114 s at -70 V
    assert reached.size and reached[0] * dt < (0.2 if voltage > -137.0 else 1e-4)
    assert np.all(coil[reached[0]:].max(axis=1) < 1e-9)    # and stays there
    # without the diodes the same command drives the inductor current below zero, out of
    # the maps (which start at 0 A), within ~50 ms
    with pytest.raises(OutOfRangeError, match="current -"):
        _discharge(tr09_maps, freewheel=False, dt=1e-3, duration=0.2)
    # energy: W(I_L) = int_0^I_L i L~(s, i) di at the fixed gap (L~ = dpsi/dI_L, eq. 8)
    grid = np.linspace(0.0, float(il[0].max()), 4001)
    r_el = bank.resistance_ohm
    out = bank.output_function
    for j in range(bank.n_circuits):
        lt = np.array([float(out(np.full(bank.n_circuits, i), np.zeros(bank.n_circuits),
                                 np.full(bank.n_circuits, 0.010))[2][j]) for i in grid])

        def energy(i_l: float, lt: np.ndarray = lt) -> float:
            g = grid[grid <= i_l]
            return float(np.trapezoid(g * lt[:g.size], g)
                         + 0.5 * (i_l - g[-1]) * (i_l + g[-1]) * lt[g.size - 1])
        w0, w1 = energy(il[0, j]), energy(il[-1, j])
        c, x = coil[:, j], il[:, j]
        to_supply = np.trapezoid(-voltage * c, dx=dt)
        in_r = np.trapezoid(r_el[j] * c ** 2 + r_ec * (c - x) ** 2, dx=dt)
        # trapezoidal sums of the RK4 trajectory at 0.1 ms steps, the kink where the
        # diode takes over within a step, the quadrature of W: measured <= 5.6e-5 of W0;
        # bound 1e-3 (leaving out the R_el loss at -70 V, measured 7.3 J = 2.4 % of W0, fails it)
        print(f"U = {voltage} V: W0 {w0:.4f} J, to the supply {to_supply:.4f} J, in R "
              f"{in_r:.4f} J, left {w1:.4f} J: off by {(to_supply + in_r + w1) / w0 - 1:.1e}")
        assert to_supply + in_r + w1 == pytest.approx(w0, rel=1e-3), (w0, to_supply, in_r, w1)
        assert in_r > 0.05 * w0
        assert to_supply > 0.05 * w0 if voltage > -137.0 else to_supply < 1e-9 * w0


def test_freewheel_option_is_a_switch(tr09_maps) -> None:
    with pytest.raises(InputError, match="freewheel"):
        MagnetBank({"m": tr09_maps}, freewheel="yes")      # type: ignore[arg-type]
    # off (default) and on equal while the current stays positive
    on = MagnetBank({"m": tr09_maps}, compiled="never", freewheel=True)
    off = MagnetBank({"m": tr09_maps}, compiled="never")
    st = on.initial_state(gaps_m=0.010, currents_A=33.5)
    u = on.resistance_ohm * 33.5 + 50.0
    assert np.array_equal(on.step(st, 1e-3, u)[1].currents_A, off.step(st, 1e-3, u)[1].currents_A)


# ---------------------------------------------------------------- the aims (issue 23, item 4)


@pytest.mark.slow
def test_bundled_train_meets_the_realism_aims() -> None:
    """Smooth elastic guideway at 400 km/h: no coil current below 10 % of its own mean
    after the start transient, gaps within +-1 mm (measured: >= 57.6 % of the mean,
    -0.77/+0.75 mm).  500 km/h over the bundled irregularity with a failed circuit, seed
    0, 12 s: no gap below 5 mm (measured 7.29 mm; docs/decisions.md)."""
    from maglevkit.vehicle.simulation import parse_irregularity

    model = VehicleModel(load_vehicle())
    res = model.run(speed_m_per_s=400 / 3.6, duration_s=2.0)
    ds = res.dataset
    sel = ds.time.values >= 0.5
    cur = ds.current.values[sel]
    assert (cur >= 0.1 * cur.mean(axis=0)).all()
    assert np.abs(ds.gap.values[sel] - 0.010).max() < 1e-3
    prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:0",
                              span_length_m=model.guideway.span.length_m)
    res = model.run(speed_m_per_s=500 / 3.6, duration_s=12.0, irregularity=prof,
                    failures=[Failure("s1m7/front", 0.5)])
    assert res.touchdown is None
    assert min(res.min_gap_m.values()) > 5e-3
