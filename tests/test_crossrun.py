"""Issue 24: the cross-section vehicle with its magnets (through the bank) and gap
controllers, against independent references: the static balance, the closed-form force
balance in a steady curve, energy conservation of the exact step, offset-free rejection
of a constant lateral force, failures, and the ISO 2631-1 Wd table."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from maglevkit.errors import InputError
from maglevkit.vehicle.comfort import iso2631_wd, lateral_comfort_indices, sperling_weighting
from maglevkit.vehicle.crossrun import (
    CrossSectionModel,
    Crosswind,
    TransitionCurve,
    parse_crosswind,
    parse_curve,
)
from maglevkit.vehicle.simulation import Failure

G0 = 9.80665


@pytest.fixture(scope="module")
def model() -> CrossSectionModel:
    return CrossSectionModel()


def test_straight_level_track_stays_centred(model: CrossSectionModel) -> None:
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=0.5)
    ds = run.dataset
    d = model.data
    for v in ("car_body_y", "car_body_phi", "chassis_y", "chassis_phi"):
        # symmetric vehicle from its trim: nothing moves (rounding of the steps)
        assert float(np.abs(ds[v]).max()) < 1e-12, v
    # the air springs' preload: the car body sits at its design height (no 243 mm sag)
    assert float(np.abs(ds.car_body_z).max()) < 1e-8
    cur = ds.guidance_current.values
    np.testing.assert_allclose(cur[:, :2], cur[:, 2:], rtol=1e-12)      # left = right
    np.testing.assert_allclose(cur[-1], model.bias_A, rtol=1e-6)        # at the bias
    lev = ds.levitation_force.values
    np.testing.assert_allclose(lev[:, :2].sum(axis=1), lev[:, 2:].sum(axis=1), rtol=1e-12)
    # levitation loads = weight of everything carried (the maps' spline trim: 1e-6)
    assert lev[-1].sum() == pytest.approx(d.total_mass_kg * G0, rel=1e-6)
    assert run.touchdown is None


@pytest.mark.parametrize("speed_kmh", [200.0, 450.0])
def test_steady_curve_net_guidance_force_is_the_closed_form(model: CrossSectionModel,
                                                            speed_kmh: float) -> None:
    """R = 4000 m, 12 deg (balancing speed 328.7 km/h), 300 m transition, then the
    constant curve until the car body's lateral-roll mode (0.5 Hz) has decayed."""
    r, c, v = 4000.0, math.radians(12.0), speed_kmh / 3.6
    run = model.run(speed_m_per_s=v, duration_s=9.0, curve=TransitionCurve(r, c, 300.0))
    ds = run.dataset
    m = model.data.total_mass_kg
    lateral = m * v * v / r * math.cos(c) - m * G0 * math.sin(c)
    normal = m * v * v / r * math.sin(c) + m * G0 * math.cos(c)
    f = ds.guidance_force.values[-1]
    net = (f[2] + f[3]) - (f[0] + f[1])        # right pulls -y (inward), left +y
    assert np.sign(net) == np.sign(v - math.sqrt(G0 * r * math.tan(c)))
    # the 1 % criterion (measured 0.026 % at 200 km/h, 0.059 % at 450 km/h, the
    # same with the "paper" and the "split" guidance paths: the last of the lateral-roll
    # swing)
    assert net == pytest.approx(lateral, rel=1e-2)
    assert float(ds.levitation_force.values[-1].sum()) == pytest.approx(normal, rel=1e-3)
    # integral action on the lateral position: the chassis back at its nominal gaps
    assert abs(float(ds.chassis_y[-1])) < 5e-5
    assert run.touchdown is None
    lim = (model.touchdown_gap_m, model.landing_gap_m)
    for var in ("levitation_gap", "guidance_gap"):
        assert lim[0] < float(ds[var].min()) and float(ds[var].max()) < lim[1]


def test_exact_step_conserves_energy_without_damping_and_control(
        model: CrossSectionModel) -> None:
    """Magnets as undamped springs (no control), gravity and the preloads on, dampers off:
    the zero-order-hold step of a linear system under constant forces is exact, so
    ``T + V`` (body by body, element by element) stays constant to rounding."""
    s = model.mechanics.with_magnet_springs(2.0e6, 1.5e6)
    a = np.array([0.3, G0])
    ad, bd = s.discretize(1e-3, damping=False)
    rng = np.random.default_rng(3)
    n = s.n_dof
    x = np.concatenate([rng.normal(0, 3e-3, n), rng.normal(0, 3e-2, n)])
    q_const = s.G @ a + s.Q_preload
    e0 = float(s.energy_J(x[:n], x[n:], a))
    scale = abs(float(s.energy_J(x[:n], np.zeros(n), a)))
    worst = 0.0
    for _ in range(5000):
        x = ad @ x + bd @ q_const
        worst = max(worst, abs(float(s.energy_J(x[:n], x[n:], a)) - e0))
    # rounding over 5000 steps: measured ~1e-12 of the potential; bound 1e-9
    assert worst < 1e-9 * scale


def test_constant_lateral_force_rejected_without_offset(model: CrossSectionModel) -> None:
    f = 5.0e3
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=10.0,
                    crosswind=Crosswind(f, start_s=0.2, shape="step"))
    ds = run.dataset
    g = ds.guidance_gap.values
    diff = 0.5 * (g[:, 0] - g[:, 2])             # the chassis' lateral gap error
    peak = float(np.abs(diff).max())
    assert peak > 1e-4                           # the force does push (0.27 mm)
    # integral action: no steady-state offset; what is left in the last second is the
    # car body's slowly decaying lateral-roll swing (0.5 Hz) through the air springs
    # (measured 0.41 um = 0.15 % of the peak with the "split" guidance paths, 0.42 um with
    # "paper"; bound 2 %)
    assert float(np.abs(diff[-1000:]).max()) < 0.02 * peak
    fg = ds.guidance_force.values[-1000:].mean(axis=0)
    # the guidance pair carries the whole force in the steady state (closed form F)
    assert (fg[0] + fg[1]) - (fg[2] + fg[3]) == pytest.approx(-f, rel=1e-2)


def test_failures_guidance_and_levitation_circuit(model: CrossSectionModel) -> None:
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=1.5,
                    failures=[Failure("guidance_left/front", 0.2)])
    ds = run.dataset
    assert run.touchdown is None
    i = ds.guidance_current.sel(guidance_circuit="left/front").values
    assert i[-1] < 0.2 * model.bias_A                   # the failed circuit decays
    # its neighbour on the same magnet takes over the left side's force
    fg = ds.guidance_force.values[-1]
    assert fg[1] > 1.5 * fg[0]
    assert run.min_gap_m["guidance"] < model.s0
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=1.0,
                    failures=[Failure("levitation_right/rear", 0.1)])
    assert run.touchdown is None
    lev = run.dataset.levitation_force.values[-1]
    assert lev.sum() == pytest.approx(model.data.total_mass_kg * G0, rel=1e-2)


def test_bad_scenarios_name_the_option(model: CrossSectionModel) -> None:
    with pytest.raises(InputError, match="--curve"):
        parse_curve("4000:12")
    with pytest.raises(InputError, match="--curve"):
        parse_curve("a:b:c")
    with pytest.raises(InputError, match="superelevation"):
        parse_curve("4000:30:300")
    with pytest.raises(InputError, match="radius"):
        parse_curve("0.5:5:300")
    with pytest.raises(InputError, match="--crosswind"):
        parse_crosswind("8000:x")
    with pytest.raises(InputError, match="rise_s"):
        parse_crosswind("8000:0")
    assert parse_crosswind("5000:0.5:0:0.2:step").shape == "step"
    assert parse_curve("4000:12:300").superelevation_rad == pytest.approx(math.radians(12))
    with pytest.raises(InputError, match="no circuit .s1m1/front.; circuits are"):
        model.run(speed_m_per_s=10.0, duration_s=0.01, failures=[Failure("s1m1/front", 0)])


def test_transition_and_gust_shapes() -> None:
    c = TransitionCurve(2000.0, 0.1, 100.0, start_m=50.0)
    np.testing.assert_allclose(c.ramp([0, 50, 100, 150, 400]), [0, 0, 0.5, 1, 1])
    a = c.field(100.0, [0.0, 400.0])
    np.testing.assert_allclose(a[0], [0, G0], atol=1e-15)
    np.testing.assert_allclose(a[1], [1e4 / 2000 * math.cos(0.1) - G0 * math.sin(0.1),
                                      1e4 / 2000 * math.sin(0.1) + G0 * math.cos(0.1)])
    w = Crosswind(1000.0, rise_s=0.5, hold_s=1.0, start_s=1.0)
    np.testing.assert_allclose(w.force_N([0.9, 1.25, 1.5, 2.0, 2.75, 3.1]),
                               [0, 500, 1000, 1000, 500, 0], atol=1e-9)


def test_iso2631_wd_table_and_lateral_sperling() -> None:
    # ISO 2631-1:1997 Table 3, Wd factors x 1000 at 0.1, 0.5, 1, 2, 4 Hz: 62.4, 853, 1011,
    # 890, 512 (one unit of the last decimal: 0.3 %)
    f = np.array([0.1, 0.5, 1.0, 2.0, 4.0])
    np.testing.assert_allclose(np.abs(iso2631_wd(f)), [0.0624, 0.853, 1.011, 0.890, 0.512],
                               rtol=3e-3)
    fs, f0, amp = 200.0, 1.5, 0.3
    t = np.arange(0, 20, 1 / fs)
    wd, wz = lateral_comfort_indices((amp * np.sin(2 * np.pi * f0 * t))[:, None], fs)
    # one sine over whole periods: exact closed forms
    assert wd[0] == pytest.approx(amp / math.sqrt(2) * abs(iso2631_wd(f0)), rel=1e-9)
    b_y = 0.737 / 0.588 * float(sperling_weighting(f0))
    assert wz[0] == pytest.approx((100 * math.sqrt(2) * amp / math.sqrt(2) * b_y) ** 0.3,
                                  rel=1e-9)


def test_cli_runs_the_cross_section_and_names_bad_options(tmp_path: object) -> None:
    from pathlib import Path

    import xarray as xr
    from typer.testing import CliRunner

    from maglevkit.cli import app

    runner = CliRunner()
    out = Path(str(tmp_path)) / "x.nc"
    res = runner.invoke(app, ["vehicle", "run", "--vehicle", "tr09-cross-section",
                              "--speed-kmh", "400", "--duration", "0.3", "--curve",
                              "4000:12:50", "--crosswind", "5000:0.1:0:0.05",
                              "--irregularity", "random:0.2e-3:3",
                              "--lateral", "random:0.2e-3:1+girders:0.5e-3", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "minimum guidance gap" in res.output
    ds = xr.load_dataset(out)
    for v in ("levitation_gap", "guidance_gap", "levitation_force", "guidance_force"):
        assert ds[v].attrs["units"] in ("m", "N")
    assert ds.car_body_lateral_acceleration.attrs["units"] == "m/s^2"
    # --curve on the heave-pitch train, a bad superelevation, a bad gust: one-line errors
    for args, word in ((["--curve", "4000:12:300"], "--curve"),
                       (["--vehicle", "tr09-cross-section", "--curve", "4000:40:300"],
                        "--curve"),
                       (["--vehicle", "tr09-cross-section", "--crosswind", "1:x"],
                        "--crosswind"),
                       (["--vehicle", "tr09-cross-section", "--lateral", "girders:-1"],
                        "--lateral"),
                       (["--vehicle", "tr09-cross-section", "--rigid"], "--rigid")):
        res = runner.invoke(app, ["vehicle", "run", *args])
        assert res.exit_code == 2
        assert word in res.output and "Traceback" not in res.output


def test_irregularities_rail_offsets_and_a_touchdown_event(model: CrossSectionModel) -> None:
    from maglevkit.vehicle.crossrun import LATERAL_ALIGNMENT_PSD
    from maglevkit.vehicle.irregularities import GermanTrackPSD, JointSteps, RandomProfile

    lo, hi = 2 * np.pi / 100, 2 * np.pi / 1.0
    base = GermanTrackPSD(**LATERAL_ALIGNMENT_PSD)
    psd = GermanTrackPSD(A_v_m_rad=base.A_v_m_rad * (0.3e-3) ** 2 / base.variance_m2(lo, hi))
    lateral = (RandomProfile(psd, lo, hi, seed=1)
               + JointSteps(0.5e-3, pitch_m=24.768, pattern="random"))
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=0.6, lateral=lateral)
    ds = run.dataset
    assert run.touchdown is None
    # the rail moves the guidance gaps in opposite directions (the chassis follows it)
    g = ds.guidance_gap.values
    assert float(np.abs(g[:, 0] - 0.010).max()) > 1e-5
    # the railway spectrum at twice its RMS (several mm) closes a levitation gap: reported
    # as a touchdown at the step where the gap reaches 2 mm, not a map-range error
    # (measured: levitation_right at 0.165 s.  The unscaled spectrum, seed 2, did it with
    # eq. 8; the default eddy network keeps that run >= 8.9 mm, switch26v)
    twice = GermanTrackPSD(A_v_m_rad=4 * GermanTrackPSD().A_v_m_rad)
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=0.5,
                    vertical=RandomProfile(twice, lo, hi, seed=4))
    assert run.touchdown is not None and run.touchdown[3] == "closed"
    assert run.touchdown[2] <= model.touchdown_gap_m
    assert "TOUCHDOWN" in run.report()


def test_compiled_step_equals_the_numpy_loop(model: CrossSectionModel) -> None:
    """The compiled block step against the NumPy loop with the controllers through the
    interface: curve entry, gust, rail irregularity and a failure, every variable.  While
    the chopper does not clamp (checked: every live current well above 0), the two are
    the same arithmetic; where it clamps, the compiled flux estimate integrates the applied
    voltage and the interface controller its own command (the interface has no channel
    for the applied voltage), so they part."""
    from maglevkit.vehicle.irregularities import HarmonicProfile

    kw: dict = dict(speed_m_per_s=400 / 3.6, duration_s=0.8,
                    curve=TransitionCurve(4000.0, math.radians(12.0), 50.0),
                    crosswind=Crosswind(5e3, rise_s=0.2, hold_s=0.1, start_s=0.2),
                    lateral=HarmonicProfile(0.2e-3, 100.0),
                    failures=[Failure("guidance_left/front", 0.5)])
    a = model.run(loop="python", **kw).dataset
    b = model.run(loop="compiled", **kw).dataset
    live = np.delete(a.guidance_current.values, 0, axis=1)
    assert live.min() > 5.0 and a.levitation_current.values.min() > 5.0
    for v in a.data_vars:
        x, y = a[v].values, b[v].values
        # the same arithmetic in another order: measured <= 1.4e-13 of the largest value
        assert np.abs(x - y).max() <= 1e-10 * max(np.abs(x).max(), 1e-30), v
    with pytest.raises(InputError, match="loop"):
        model.run(speed_m_per_s=1.0, duration_s=0.01, loop="fast")


@pytest.mark.slow
def test_detailed_magnets_in_the_bank_hold_the_trim() -> None:
    """The flux-based models in the same bank (NumPy loop): the reduced model's trim
    currents give the same forces to the maps' interpolation (1e-3), and 10 ms of a
    straight run stay at the trim."""
    m = CrossSectionModel(magnets="detailed")
    run = m.run(speed_m_per_s=400 / 3.6, duration_s=0.01)
    ds = run.dataset
    assert run.touchdown is None
    lev = ds.levitation_force.values[-1].sum()
    assert lev == pytest.approx(m.data.total_mass_kg * G0, rel=1e-3)
    np.testing.assert_allclose(ds.guidance_force.values[-1], m.guidance_bias_force_N / 2,
                               rtol=1e-3)
    with pytest.raises(InputError, match="reduced"):
        m.run(speed_m_per_s=1.0, duration_s=0.01, loop="compiled")


@pytest.mark.parametrize("scenario", ["curve", "gust"])
def test_curve_entry_and_gust_at_400_kmh_keep_the_gaps_inside_their_limits(
        model: CrossSectionModel, scenario: str) -> None:
    kw: dict = ({"curve": TransitionCurve(4000.0, math.radians(12.0), 300.0, start_m=50.0)}
                if scenario == "curve" else
                {"crosswind": Crosswind(1.0e4, rise_s=0.5, hold_s=1.0, start_s=0.3)})
    run = model.run(speed_m_per_s=400 / 3.6, duration_s=6.0, **kw)
    assert run.touchdown is None
    ds = run.dataset
    for var in ("levitation_gap", "guidance_gap"):
        assert model.touchdown_gap_m < float(ds[var].min()) < model.s0
        assert model.s0 < float(ds[var].max()) < model.landing_gap_m
    # the gust is carried by the guidance pair: at the plateau's end the net guidance
    # force balances the gust and the car body's inertia (the body still swings), so
    # only its sign and order are checked here; the exact balance is the step test above
    if scenario == "gust":
        f = ds.guidance_force.values[int(1.8 / 1e-3)]
        assert 0.3e4 < (f[2] + f[3]) - (f[0] + f[1]) < 3e4


def test_compiled_loop_names_a_flagged_step_from_its_own_reason_codes(
        model: CrossSectionModel, monkeypatch: pytest.MonkeyPatch) -> None:
    """A guidance gap leaving the maps (2-22 mm) inside a step, with the touchdown limits
    moved out of the way: the compiled loop's message comes from the step's own reason
    codes through the bank's message table (issue 22 item 3), without stepping the bank
    again.  Independent reference: the bank's own step (which diagnoses itself) on the
    same step's inputs, as the loop did before.  (The NumPy loop is no reference here:
    the choppers clamp on the way out of the maps, where the two loops part, see
    test_compiled_step_equals_the_numpy_loop.)"""
    from maglevkit.errors import OutOfRangeError
    from maglevkit.reduced.bank import BankState, MagnetBank
    from maglevkit.vehicle.irregularities import HarmonicProfile

    # the guidance circuits (whose step flags) on eq. 8: their eddy states are exact zeros,
    # which the reference step below can take (raise_step_flags is given no eddy states;
    # the bundled guidance file flies the network since guideswitch)
    low = CrossSectionModel(touchdown_gap_m=1e-3, landing_gap_m=0.05,
                            eddy_modes={"guidance": 0})
    kw: dict = dict(speed_m_per_s=400 / 3.6, duration_s=0.3,
                    lateral=HarmonicProfile(15e-3, 30.0))
    low.run(**{**kw, "duration_s": 0.01}, loop="compiled")    # compile outside the patch
    step, raise_flags = MagnetBank.step, MagnetBank.raise_step_flags
    seen: list[tuple[str, str]] = []

    def no_step(*args: object, **kw: object) -> None:
        raise AssertionError("the compiled loop stepped the bank again")

    def checked(self: MagnetBank, flags: np.ndarray, **kw: Any) -> None:
        # the default mixed bank carries eddy states (the levitation magnets' network);
        # the guidance circuits, whose step flags, are eq. 8 with exact-zero eddy states,
        # so zeros are their step's own inputs (switch26v)
        n_e = self.n_eddy_states
        eddy = (np.zeros((self.n_circuits, n_e) if n_e > 1 else self.n_circuits)
                if n_e else None)
        assert self.eddy_modes == 0 or low.eddy_modes_of["guidance"] == 0
        state = BankState(kw["start_s"], np.array(kw["inductor_currents_A"]),
                          np.array(kw["gaps_m"]), eddy_currents_A=eddy)
        with pytest.raises(OutOfRangeError) as ref:
            step(self, state, kw["end_s"] - kw["start_s"], np.array(kw["voltages_V"]),
                 np.array(kw["gaps_m"]), np.array(kw["gap_rates_m_per_s"]))
        with pytest.raises(OutOfRangeError) as got:
            raise_flags(self, flags, **kw)
        seen.append((str(got.value), str(ref.value)))
        raise got.value

    monkeypatch.setattr(MagnetBank, "step", no_step)
    monkeypatch.setattr(MagnetBank, "raise_step_flags", checked)
    with pytest.raises(OutOfRangeError, match="outside the characteristic maps: member "
                                              "'guidance_") as err:
        low.run(loop="compiled", **kw)
    assert len(seen) == 1 and seen[0][0] == seen[0][1]
    assert seen[0][0] in str(err.value)
