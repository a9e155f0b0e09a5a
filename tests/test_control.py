"""Heave mass, gap controller and closed-loop co-simulation with both magnet models."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.compare import compare_models, standard_scenarios
from maglevkit.control import closed_loop, design_gap_controller
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass, HeaveState


def test_heave_mass_free_fall_is_exact() -> None:
    m = HeaveMass(100.0)
    st = HeaveState(0.01, 0.0)
    for _ in range(10):
        st = m.step(st, 1e-3, magnet_force_N=0.0)
    # constant acceleration: the update is exact up to rounding
    assert st.gap_m == pytest.approx(0.01 + 0.5 * STANDARD_GRAVITY * 0.01**2, rel=1e-12)
    assert st.gap_rate_m_per_s == pytest.approx(STANDARD_GRAVITY * 0.01, rel=1e-12)
    with pytest.raises(mk.ParameterError, match=r"mass_kg \[kg\] = 0.0: must be > 0"):
        HeaveMass(0.0)


@pytest.fixture(scope="module")
def u_setup(u_magnet: mk.Magnet):  # type: ignore[no-untyped-def]
    mag = u_magnet.with_options(eddy_currents=False)
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.004, 0.02, 17), currents_A=np.linspace(0, 80, 33))
    return mag, mk.CurrentModel(maps)


def test_gap_controller_levitates_and_tracks_a_reference(u_setup) -> None:  # type: ignore[no-untyped-def]
    mag, reduced = u_setup
    s0, i0 = 0.01, 20.0
    f0 = float(mk.solve_statics(mag, gaps_m=s0, currents_A=i0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    ctl = design_gap_controller(mag, mass_kg=veh.mass_kg, gap_m=s0, current_A=i0)
    res = closed_loop(reduced, veh, ctl, duration_s=1.5, dt_s=1e-3, initial_gap_m=s0,
                      initial_current_A=i0, gap_reference_m=lambda t: 0.011 if t >= 0.05 else s0)
    # settles at the new reference (the integrator removes the offset): within 20 um at the
    # end, and the current is the static current that carries the load there (to 0.5 %,
    # the remaining gap and acceleration error)
    assert res.gap_m.max() < 0.01105                   # I-PD form: overshoot < 5 % of the step
    assert res.gap_m[-1] == pytest.approx(0.011, abs=2e-5)
    needed = mk.solve_statics(mag, gaps_m=0.011, currents_A=np.linspace(15, 30, 301)[:, None])
    i_needed = np.interp(f0, needed.force_N, np.linspace(15, 30, 301))
    assert res.currents_A[-1, 0] == pytest.approx(i_needed, rel=5e-3)
    assert not res.voltage_limited.any()


def test_flux_control_rejects_a_load_step_with_eddy_currents(u_magnet: mk.Magnet) -> None:
    """The detailed model with eddy currents (which defeat a current-loop controller)
    stays levitated after a +10 % load step and returns to the reference gap."""
    s0, i0 = 0.01, 20.0
    f0 = float(mk.solve_statics(u_magnet, gaps_m=s0, currents_A=i0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    ctl = design_gap_controller(u_magnet, mass_kg=veh.mass_kg, gap_m=s0, current_A=i0)
    res = closed_loop(mk.FluxModel(u_magnet), veh, ctl, duration_s=0.8, dt_s=1e-3,
                      initial_gap_m=s0, initial_current_A=i0,
                      external_force_N=lambda t: 0.1 * f0 if t >= 0.05 else 0.0)
    assert res.gap_m.max() < s0 + 2e-3                  # peak deviation bounded (~1 mm)
    assert res.gap_m[-1] == pytest.approx(s0, abs=3e-5)  # integral action: back at 10 mm
    assert res.force_N[-1] == pytest.approx(1.1 * f0, rel=2e-3)


def test_without_control_the_magnet_is_unstable(u_setup) -> None:  # type: ignore[no-untyped-def]
    """Negative stiffness: a fixed voltage cannot hold a 1 % heavier mass; it falls until it
    leaves the maps' gap range (0.004-0.02 m), which the reduced model reports."""
    mag, reduced = u_setup
    f0 = float(mk.solve_statics(mag, gaps_m=0.01, currents_A=20.0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY * 1.01)
    st = reduced.initial_state(gaps_m=0.01, currents_A=20.0)
    mech = HeaveState(0.01, 0.0)
    out = reduced.outputs(st)
    with pytest.raises(mk.OutOfRangeError, match=r"substitute gap 0\.020"):
        for _ in range(1000):
            force = out.force_N
            st, out = reduced.step(st, 1e-3, 40.0, gaps_m=mech.gap_m,
                                   gap_rates_m_per_s=mech.gap_rate_m_per_s)
            mech = veh.step(mech, 1e-3, force)


def test_reduced_model_matches_detailed_on_the_standard_set(u_setup) -> None:  # type: ignore[no-untyped-def]
    """Single-circuit magnet without eddy currents: the current-based model is exact up to
    the map interpolation and integrator tolerances, so the errors are far below the
    issue's 2 % (measured ~1e-4); bound 1e-3."""
    mag, reduced = u_setup
    scenarios = [sc for sc in standard_scenarios(mag, gap_m=0.01, current_A=20.0)
                 if sc.name in ("voltage step up", "gap sine 50 Hz", "gap ramp", "closed loop")]
    results = compare_models(mag, reduced, scenarios, gap_m=0.01, current_A=20.0, repeat=0)
    assert len(results) == 4
    for r in results:
        assert r.current_error.max() < 1e-3, r.scenario.name
        assert r.force_error.max() < 1e-3, r.scenario.name
