"""Unit-carrying input names (issue 22, item 7): the old names stay as deprecated aliases
that give the same numbers."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.validation import renamed_keywords

GAPS = np.linspace(0.006, 0.016, 6)
CURRENTS = np.linspace(0.0, 60.0, 7)


@pytest.fixture(scope="module")
def u_maps(u_magnet: mk.Magnet) -> mk.CharacteristicMaps:
    return mk.build_maps(u_magnet, gaps_m=GAPS, currents_A=CURRENTS, progress=False)


def test_helper_translates_warns_and_refuses_both() -> None:
    @renamed_keywords(dt="dt_s")
    def f(x: float, dt_s: float = 1.0) -> float:
        return x * dt_s

    with warnings.catch_warnings():
        warnings.simplefilter("error")            # the new name: no warning at all
        assert f(2.0, dt_s=3.0) == 6.0 and f(2.0, 3.0) == 6.0
    with pytest.warns(DeprecationWarning, match=r"f: dt= is deprecated, use dt_s="):
        assert f(2.0, dt=3.0) == 6.0
    with pytest.raises(InputError, match=r"give dt_s= only"):
        f(2.0, dt=3.0, dt_s=3.0)


def test_current_model_step_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    cm = mk.CurrentModel(u_maps)
    st = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    new, out_new = cm.step(st, dt_s=2e-3, voltages_V=50.0, gaps_m=0.0101,
                           gap_rates_m_per_s=0.05)
    with pytest.warns(DeprecationWarning, match=r"use voltages_V="):
        old, out_old = cm.step(st, dt=2e-3, voltages=50.0, gaps=0.0101, gap_rates=0.05)
    # the same call underneath: equal bit for bit
    assert np.array_equal(new.inductor_currents_A, old.inductor_currents_A)
    assert np.array_equal(out_new.circuit_force_N, out_old.circuit_force_N)


def test_bank_step_and_stepper_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    bank = mk.MagnetBank({"a": u_maps, "b": u_maps})
    st = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    u = bank.resistance_ohm * 22.0
    _, o_new = bank.step(st, 1e-3, u, gaps_m=0.0101, gap_rates_m_per_s=0.01)
    with pytest.warns(DeprecationWarning, match=r"use gaps_m="):
        _, o_old = bank.step(st, 1e-3, u, gaps=0.0101, gap_rates=0.01)
    assert np.array_equal(o_new.circuit_force_N, o_old.circuit_force_N)
    s_new = bank.stepper(st, dt_s=1e-3)
    with pytest.warns(DeprecationWarning, match=r"use dt_s="):
        s_old = bank.stepper(st, dt=1e-3)
    s_new.advance(voltages_V=u, gaps_m=0.0101, gap_rates_m_per_s=0.01)
    with pytest.warns(DeprecationWarning, match=r"use gap_rates_m_per_s="):
        s_old.advance(voltages=u, gaps=0.0101, gap_rates=0.01)
    assert np.array_equal(s_new.circuit_force_N, s_old.circuit_force_N)
    # and equal to the bank's own step (the stepper is the same kernel)
    assert np.array_equal(s_new.circuit_force_N, o_new.circuit_force_N)
    with pytest.raises(InputError, match=r"give voltages_V= only"):
        s_new.advance(voltages=u, voltages_V=u)


# ---- the rest of item 7: simulate, initial_state, HeaveMass.step, closed_loop ----------------
def test_simulate_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    """``mk.simulate`` and ``CurrentModel.simulate``: the old names give the same run, bit for
    bit (the wrapper only renames), with one warning naming every new keyword."""
    cm = mk.CurrentModel(u_maps)
    new = dict(dt_s=1e-3, gaps_m=lambda t: 0.010 + 0.001 * t, voltages_V=45.0,
               gap_rates_m_per_s=0.001, initial_currents_A=20.0)
    old = dict(dt=1e-3, gaps=new["gaps_m"], voltages=45.0, gap_rates=0.001,
               initial_currents=20.0)
    ref = mk.simulate(cm, (0.0, 0.02), **new)
    with pytest.warns(DeprecationWarning, match=r"simulate: gaps= is deprecated, use gaps_m=;.*"
                                                r"initial_currents= is deprecated, use "
                                                r"initial_currents_A="):
        top = mk.simulate(cm, (0.0, 0.02), **old)
    with pytest.warns(DeprecationWarning, match=r"CurrentModel.simulate: .*use dt_s="):
        own = cm.simulate((0.0, 0.02), **old)
    for res in (top, own):
        assert np.array_equal(res.currents_A, ref.currents_A)
        assert np.array_equal(res.force_N, ref.force_N)
    with pytest.raises(InputError, match=r"give gaps_m= only"):
        mk.simulate(cm, (0.0, 0.02), gaps=0.01, gaps_m=0.01, voltages_V=45.0)


def test_bank_simulate_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    bank = mk.MagnetBank({"a": u_maps, "b": u_maps})
    u = bank.resistance_ohm * 22.0
    ref = mk.simulate(bank, (0.0, 0.01), dt_s=1e-3, gaps_m=0.010, voltages_V=u,
                      initial_currents_A=20.0)
    with pytest.warns(DeprecationWarning, match=r"MagnetBank.simulate: .*use voltages_V="):
        old = bank.simulate((0.0, 0.01), dt=1e-3, gaps=0.010, voltages=u, initial_currents=20.0)
    assert np.array_equal(old.currents_A, ref.currents_A)


def test_initial_state_old_names_equal_new(u_magnet: mk.Magnet,
                                           u_maps: mk.CharacteristicMaps) -> None:
    """CurrentModel, MagnetBank and FluxModel: ``gaps``/``currents``/``time`` are aliases of
    ``gaps_m``/``currents_A``/``time_s``."""
    fm = mk.FluxModel(u_magnet.with_options(eddy_currents=False))
    for model in (mk.CurrentModel(u_maps), mk.MagnetBank({"a": u_maps}), fm):
        new = model.initial_state(gaps_m=0.011, currents_A=25.0, time_s=0.5)
        with pytest.warns(DeprecationWarning, match=r"initial_state: gaps= is deprecated, use "
                                                    r"gaps_m=; currents= .*use currents_A=; "
                                                    r"time= .*use time_s="):
            old = model.initial_state(gaps=0.011, currents=25.0, time=0.5)
        assert old.time_s == new.time_s == 0.5
        for field in dataclasses.fields(new):       # every array of the state, bit for bit
            a, b = getattr(old, field.name), getattr(new, field.name)
            if isinstance(a, np.ndarray) and a.dtype.kind == "f":
                assert np.array_equal(a, b, equal_nan=True), field.name
            else:
                assert repr(a) == repr(b), field.name
        with pytest.raises(InputError, match=r"give time_s= only"):
            model.initial_state(gaps_m=0.011, currents_A=25.0, time=0.5, time_s=0.5)


def test_heave_mass_step_old_dt_equals_new() -> None:
    mass = mk.vehicle.HeaveMass(100.0)
    st = mk.vehicle.HeaveState(0.01, 0.0)
    new = mass.step(st, dt_s=1e-3, magnet_force_N=900.0)
    with pytest.warns(DeprecationWarning, match=r"HeaveMass.step: dt= is deprecated, use dt_s="):
        old = mass.step(st, dt=1e-3, magnet_force_N=900.0)
    assert old == new


def test_closed_loop_old_external_force_equals_new(u_magnet: mk.Magnet,
                                                   u_maps: mk.CharacteristicMaps) -> None:
    from maglevkit.control import closed_loop, design_gap_controller

    s0, i0 = 0.01, 20.0
    f0 = float(mk.solve_statics(u_magnet, gaps_m=s0, currents_A=i0).force_N)
    veh = mk.vehicle.HeaveMass(f0 / mk.vehicle.STANDARD_GRAVITY)
    ctl = design_gap_controller(u_magnet, mass_kg=veh.mass_kg, gap_m=s0, current_A=i0)
    common = dict(duration_s=0.02, dt_s=1e-3, initial_gap_m=s0, initial_current_A=i0)
    cm = mk.CurrentModel(u_maps)

    def load(t: float) -> float:
        return 0.1 * f0 if t >= 0.005 else 0.0

    new = closed_loop(cm, veh, ctl, external_force_N=load, **common)
    with pytest.warns(DeprecationWarning, match=r"closed_loop: external_force= is deprecated, "
                                                r"use external_force_N="):
        old = closed_loop(cm, veh, ctl, external_force=load, **common)
    assert np.array_equal(old.gap_m, new.gap_m)


# ---- statics and maps: gaps/currents -> gaps_m/currents_A (the grid axes of build_maps too) ---
def test_solve_statics_and_coenergy_old_names_equal_new(u_magnet: mk.Magnet) -> None:
    """The wrapper only renames: the same solution bit for bit, on a point and on a grid."""
    new = mk.solve_statics(u_magnet, gaps_m=0.011, currents_A=25.0)
    with pytest.warns(DeprecationWarning, match=r"solve_statics: gaps= is deprecated, use "
                                                r"gaps_m=; currents= .*use currents_A="):
        old = mk.solve_statics(u_magnet, gaps=0.011, currents=25.0)
    for field in dataclasses.fields(new):
        a, b = getattr(old, field.name), getattr(new, field.name)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b, equal_nan=True), field.name
    g_new = mk.solve_statics(u_magnet, gaps_m=GAPS[:3], currents_A=CURRENTS[:2], grid=True)
    with pytest.warns(DeprecationWarning, match=r"use gaps_m="):
        g_old = mk.solve_statics(u_magnet, gaps=GAPS[:3], currents=CURRENTS[:2], grid=True)
    assert np.array_equal(g_old.force_N, g_new.force_N)
    w_new = mk.coenergy(u_magnet, gaps_m=0.011, currents_A=25.0)
    with pytest.warns(DeprecationWarning, match=r"coenergy: gaps= is deprecated"):
        assert mk.coenergy(u_magnet, gaps=0.011, currents=25.0) == w_new
    e_new = mk.magnetic_energy(u_magnet, new.branch_flux_Wb, new.gaps_m)
    with pytest.warns(DeprecationWarning, match=r"magnetic_energy: branch_flux= is deprecated"):
        assert mk.magnetic_energy(u_magnet, branch_flux=new.branch_flux_Wb,
                                  gaps=new.gaps_m) == e_new
    with pytest.warns(DeprecationWarning, match=r"pole_force_eq6: flux= .*use flux_Wb=; "
                                                r"area= .*use area_m2="):
        assert mk.pole_force_eq6(flux=1e-3, area=4e-4) == mk.pole_force_eq6(1e-3, 4e-4)
    with pytest.raises(InputError, match=r"give gaps_m= only"):
        mk.solve_statics(u_magnet, gaps=0.011, gaps_m=0.011, currents_A=25.0)


def test_circuit_pole_groups_old_names_equal_new() -> None:
    from maglevkit.models.statics import circuit_pole_groups

    tr09 = mk.load_magnet("tr09-standard")      # two circuits: the grouping is solved

    new = circuit_pole_groups(tr09, gap_m=0.01, current_A=20.0)
    with pytest.warns(DeprecationWarning, match=r"gap= is deprecated, use gap_m=; "
                                                r"current= is deprecated, use current_A="):
        assert circuit_pole_groups(tr09, gap=0.01, current=20.0) == new


def test_build_maps_old_names_equal_new(u_magnet: mk.Magnet,
                                        u_maps: mk.CharacteristicMaps) -> None:
    """``build_maps(gaps=, currents=)`` gives the same maps (every variable, the coordinates
    and the attributes the caches key on); the dataset's own names (``gap``, ``current``
    coordinates) did not change, so stored maps load as before."""
    with pytest.warns(DeprecationWarning, match=r"build_maps: gaps= is deprecated, use gaps_m="):
        old = mk.build_maps(u_magnet, gaps=GAPS, currents=CURRENTS, progress=False)
    assert set(old.dataset.data_vars) == set(u_maps.dataset.data_vars)
    for name in u_maps.dataset.data_vars:
        assert np.array_equal(old.dataset[name].values, u_maps.dataset[name].values,
                              equal_nan=True), name
    assert np.array_equal(old.gaps_m, u_maps.gaps_m)
    assert np.array_equal(old.currents_A, u_maps.currents_A)
    assert old.dataset.attrs == u_maps.dataset.attrs
    assert set(u_maps.dataset.coords) >= {"gap", "current"}


# ---- the experiments and identifications on the detailed model ----------------------------
def test_voltage_step_response_old_names_equal_new(u_magnet: mk.Magnet) -> None:
    lin = u_magnet.with_options(eddy_currents=False, saturation=False)
    new = mk.voltage_step_response(lin, gap_m=0.01, voltage_V=30.0, initial_current_A=10.0,
                                   duration_s=0.01, dt_s=1e-3)
    with pytest.warns(DeprecationWarning, match=r"voltage_step_response: gap= is deprecated, "
                                                r"use gap_m=; voltage= .*use voltage_V=; "
                                                r"initial_current= .*; duration= .*; dt= .*"):
        old = mk.voltage_step_response(lin, gap=0.01, voltage=30.0, initial_current=10.0,
                                       duration=0.01, dt=1e-3)
    assert np.array_equal(old.currents_A, new.currents_A)
    assert np.array_equal(old.force_N, new.force_N)


def test_step_inductance_and_characteristics_old_names_equal_new(u_magnet: mk.Magnet) -> None:
    from maglevkit.models import coupling_ratios, force_exponent, saturation_knee

    lin = u_magnet.with_options(eddy_currents=False)
    opts = dict(samples_per_tau=10, n_tau=2.0)
    new = mk.differential_inductance_from_step(lin, gap_m=0.01, current_A=20.0, **opts)
    with pytest.warns(DeprecationWarning, match=r"differential_inductance_from_step: gap= "):
        old = mk.differential_inductance_from_step(lin, gap=0.01, current=20.0, **opts)
    assert old.inductance_H == new.inductance_H
    cur = np.array([10.0, 30.0])
    with pytest.warns(DeprecationWarning, match=r"force_exponent: .*use currents_A="):
        assert np.array_equal(force_exponent(u_magnet, gap=0.01, currents=cur),
                              force_exponent(u_magnet, gap_m=0.01, currents_A=cur))
    with pytest.warns(DeprecationWarning, match=r"saturation_knee: .*use max_current_A="):
        assert (saturation_knee(u_magnet, gap=0.01, max_current=200.0, points=20)
                == saturation_knee(u_magnet, gap_m=0.01, max_current_A=200.0, points=20))
    with pytest.warns(DeprecationWarning, match=r"coupling_ratios: .*use current_A="):
        assert np.array_equal(coupling_ratios(u_magnet, gap=0.01, current=20.0).ratio,
                              coupling_ratios(u_magnet, gap_m=0.01, current_A=20.0).ratio)


def test_eddy_identification_old_names_equal_new(u_magnet: mk.Magnet) -> None:
    from maglevkit.reduction import current_jump_admittance, eddy_resistance, flux_held_ramp

    with pytest.warns(DeprecationWarning, match=r"eddy_resistance: gap= .*use current_A="):
        assert np.array_equal(eddy_resistance(u_magnet, gap=0.01, current=20.0),
                              eddy_resistance(u_magnet, gap_m=0.01, current_A=20.0))
    with pytest.warns(DeprecationWarning, match=r"current_jump_admittance: gap= "):
        assert np.array_equal(current_jump_admittance(u_magnet, gap=0.01, current=20.0),
                              current_jump_admittance(u_magnet, gap_m=0.01, current_A=20.0))
    lin = u_magnet.with_options(eddy_currents=False)
    new = flux_held_ramp(lin, gap_m=0.01, current_A=20.0, gap_change_m=2e-4, duration_s=0.05,
                         samples=10)
    with pytest.warns(DeprecationWarning, match=r"flux_held_ramp: .*gap_change= is deprecated, "
                                                r"use gap_change_m=; duration= .*duration_s="):
        old = flux_held_ramp(lin, gap=0.01, current=20.0, gap_change=2e-4, duration=0.05,
                             samples=10)
    assert np.array_equal(old.currents_A, new.currents_A)


def test_dl_ds_from_ramp_old_names_equal_new(u_magnet: mk.Magnet) -> None:
    from maglevkit.reduction import dl_ds_from_ramp

    lin = u_magnet.with_options(eddy_currents=False)
    common = dict(samples=10, relative_gap_change=0.02)
    new = dl_ds_from_ramp(lin, gap_m=0.01, current_A=0.0, inductance_H=0.05, duration_s=0.05,
                          zero_current_A=1e-3, **common)
    with pytest.warns(DeprecationWarning, match=r"dl_ds_from_ramp: .*inductance= is deprecated, "
                                                r"use inductance_H=;.*zero_current_A="):
        old = dl_ds_from_ramp(lin, gap=0.01, current=0.0, inductance=0.05, duration=0.05,
                              zero_current=1e-3, **common)
    assert old.dL_ds_H_per_m == new.dL_ds_H_per_m and old.current_A == new.current_A == 1e-3
    assert np.array_equal(old.response.currents_A, new.response.currents_A)


# ---- the comparison scenario's fields and the closed loop's gap reference --------------------
def test_helper_on_a_dataclass_renames_constructor_and_reads_old_attributes() -> None:
    @renamed_keywords(gaps="gaps_m")
    @dataclasses.dataclass(frozen=True)
    class Case:
        name: str
        gaps_m: float = 0.0

    with warnings.catch_warnings():
        warnings.simplefilter("error")            # the new names: no warning at all
        assert Case("a", gaps_m=0.01) == Case("a", 0.01)
    with pytest.warns(DeprecationWarning, match=r"Case: gaps= is deprecated, use gaps_m="):
        old = Case("a", gaps=0.01)
    assert old == Case("a", gaps_m=0.01)
    with pytest.warns(DeprecationWarning, match=r"Case: \.gaps is deprecated, use \.gaps_m"):
        assert old.gaps == 0.01
    with pytest.raises(InputError, match=r"give gaps_m= only"):
        Case("a", gaps=0.01, gaps_m=0.01)
    with pytest.raises(TypeError, match=r"already defines"):
        renamed_keywords(gaps_m="x")(Case)


def test_comparison_scenario_old_fields_equal_new(u_magnet: mk.Magnet,
                                                  u_maps: mk.CharacteristicMaps) -> None:
    """``ComparisonScenario(gaps=, voltages=, gap_reference=)`` builds the same case (equal
    dataclasses) and ``.gaps``/``.voltages``/``.gap_reference`` read the new fields; the
    comparison run on it gives the same numbers bit for bit."""
    from maglevkit.compare import ComparisonScenario, compare_models

    ref = lambda t: 0.01 + (5e-4 if t >= 0.005 else 0.0)    # noqa: E731
    u0 = float(u_magnet.network.resistances[0]) * 20.0
    new = ComparisonScenario("open", "a step", 0.01, 1e-3, gaps_m=0.01, voltages_V=u0 * 1.1,
                             initial_current_A=20.0)
    with pytest.warns(DeprecationWarning, match=r"ComparisonScenario: gaps= is deprecated, use "
                                                r"gaps_m=; voltages= .*use voltages_V="):
        old = ComparisonScenario("open", "a step", 0.01, 1e-3, gaps=0.01, voltages=u0 * 1.1,
                                 initial_current_A=20.0)
    assert old == new
    with pytest.warns(DeprecationWarning, match=r"\.voltages is deprecated, use \.voltages_V"):
        assert old.voltages == new.voltages_V
    with pytest.warns(DeprecationWarning, match=r"\.gaps is deprecated, use \.gaps_m"):
        assert old.gaps == new.gaps_m
    with pytest.warns(DeprecationWarning, match=r"gap_reference= is deprecated, use "
                                                r"gap_reference_m="):
        closed = ComparisonScenario("closed", "", 0.01, 1e-3, gap_reference=ref, kind="closed")
    assert closed.gap_reference_m is ref
    fm = mk.FluxModel(u_magnet.with_options(eddy_currents=False))
    cm = mk.CurrentModel(u_maps)
    r_new, r_old = (compare_models(fm, cm, [sc], gap_m=0.01, current_A=20.0, repeat=0)[0]
                    for sc in (new, old))
    assert np.array_equal(r_new.reduced_currents_A, r_old.reduced_currents_A)
    assert np.array_equal(r_new.detailed_forces_N, r_old.detailed_forces_N)


def test_closed_loop_old_gap_reference_equals_new(u_magnet: mk.Magnet,
                                                  u_maps: mk.CharacteristicMaps) -> None:
    from maglevkit.control import closed_loop, design_gap_controller

    s0, i0 = 0.01, 20.0
    f0 = float(mk.solve_statics(u_magnet, gaps_m=s0, currents_A=i0).force_N)
    veh = mk.vehicle.HeaveMass(f0 / mk.vehicle.STANDARD_GRAVITY)
    ctl = design_gap_controller(u_magnet, mass_kg=veh.mass_kg, gap_m=s0, current_A=i0)
    common = dict(duration_s=0.02, dt_s=1e-3, initial_gap_m=s0, initial_current_A=i0)
    cm = mk.CurrentModel(u_maps)

    def ref(t: float) -> float:
        return s0 + (5e-4 if t >= 0.005 else 0.0)

    new = closed_loop(cm, veh, ctl, gap_reference_m=ref, **common)
    with pytest.warns(DeprecationWarning, match=r"closed_loop: gap_reference= is deprecated, "
                                                r"use gap_reference_m="):
        old = closed_loop(cm, veh, ctl, gap_reference=ref, **common)
    assert np.array_equal(old.gap_m, new.gap_m)
    assert np.array_equal(old.gap_ref_m, new.gap_ref_m)


def test_scenario_file_old_fields_read_new() -> None:
    """``mk.Scenario``: ``.voltages``/``.gaps`` read ``voltages_V``/``gaps_m``; the old
    constructor keywords build an equal scenario (the file's tables keep their names)."""
    sc = mk.load_scenario("step")
    with pytest.warns(DeprecationWarning, match=r"Scenario: \.voltages is deprecated, use "
                                                r"\.voltages_V"):
        assert sc.voltages is sc.voltages_V
    with pytest.warns(DeprecationWarning, match=r"Scenario: \.gaps is deprecated"):
        assert sc.gaps is sc.gaps_m
    with pytest.warns(DeprecationWarning, match=r"Scenario: voltages= is deprecated"):
        old = mk.Scenario(sc.duration_s, sc.dt_s, voltages=sc.voltages_V, gaps=sc.gaps_m,
                          initial_current_A=sc.initial_current_A,
                          model_options=sc.model_options, solver_options=sc.solver_options,
                          source=sc.source)
    assert old == sc


def test_plausibility_warnings_point_at_the_callers_line(u_magnet: mk.Magnet) -> None:
    """A wrapper of renamed_keywords adds a frame; the range check's warning still names
    the user's line (``external_stacklevel``), not a line inside maglevkit; and
    ``PlausibleRange.check(gaps=, currents=)`` is an alias of ``gaps_m=``/``currents_A=``."""
    fm = mk.FluxModel(u_magnet.with_options(eddy_currents=False))
    for call in (lambda: mk.solve_statics(u_magnet, gaps_m=5.0, currents_A=20.0),
                 lambda: fm.initial_state(gaps_m=5.0, currents_A=20.0)):
        with pytest.warns(mk.PlausibilityWarning, match=r"gap 5 m is larger") as rec:
            call()
        assert [w.filename for w in rec] == [__file__]
    rng = u_magnet.plausible_range
    with pytest.warns(mk.PlausibilityWarning) as rec:
        rng.check(gaps_m=5.0, currents_A=1e6, where="x")
    assert len(rec) == 2 and all(w.filename == __file__ for w in rec)
    with pytest.warns(DeprecationWarning, match=r"check: gaps= is deprecated, use gaps_m=; "
                                                r"currents= is deprecated, use currents_A="):
        with pytest.warns(mk.PlausibilityWarning) as rec_old:
            rng.check(gaps=5.0, currents=1e6, where="x")
    assert [str(w.message) for w in rec_old if w.category is mk.PlausibilityWarning] \
        == [str(w.message) for w in rec]


# ---- the reduced models' helpers: gaps_m, voltages_V, dt_s ------------------------------------
def test_reduced_helpers_old_names_equal_new(u_maps: mk.CharacteristicMaps) -> None:
    from maglevkit.reduced import BankStepper

    cm = mk.CurrentModel(u_maps)
    bank = mk.MagnetBank({"a": u_maps, "b": u_maps})
    g = np.array([0.010, 0.011])
    with pytest.warns(DeprecationWarning, match=r"substitute_gaps: gaps= is deprecated"):
        assert np.array_equal(cm.substitute_gaps(gaps=g), cm.substitute_gaps(gaps_m=g))
    st = cm.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.warns(DeprecationWarning, match=r"CurrentModel.outputs: voltages= is "
                                                r"deprecated, use voltages_V="):
        o_old = cm.outputs(st, voltages=45.0)
    assert np.array_equal(o_old.force_N, cm.outputs(st, voltages_V=45.0).force_N)
    gb = np.linspace(0.010, 0.011, bank.n_gaps)
    with pytest.warns(DeprecationWarning, match=r"circuit_gaps: gaps= is deprecated"):
        assert np.array_equal(bank.circuit_gaps(gaps=gb), bank.circuit_gaps(gaps_m=gb))
    with pytest.warns(DeprecationWarning, match=r"pole_gaps: gaps= is deprecated"):
        assert np.array_equal(bank.pole_gaps(gaps=gb), bank.pole_gaps(gaps_m=gb))
    bs = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    u = bank.resistance_ohm * 22.0
    with pytest.warns(DeprecationWarning, match=r"MagnetBank.outputs: voltages= is deprecated"):
        b_old = bank.outputs(bs, voltages=u)
    assert np.array_equal(b_old.circuit_force_N, bank.outputs(bs, voltages_V=u).circuit_force_N)
    with pytest.warns(DeprecationWarning, match=r"BankStepper.__init__: dt= is deprecated, "
                                                r"use dt_s="):
        s_old = BankStepper(bank, bs, dt=1e-3)
    s_new = BankStepper(bank, bs, dt_s=1e-3)
    assert s_old.dt_s == s_new.dt_s == 1e-3
    for name in ("step_function", "step_kernel"):
        with pytest.warns(DeprecationWarning, match=rf"{name}: dt= is deprecated, use dt_s="):
            f_old = getattr(bank, name)(dt=1e-3)
        f_new = getattr(bank, name)(dt_s=1e-3)
        assert f_old.name() == f_new.name() and f_old.n_in() == f_new.n_in()
    with pytest.warns(DeprecationWarning, match=r"compiled_step_library: dt= is deprecated"):
        lib_old = bank.compiled_step_library(dt=1e-3)
    lib_new = bank.compiled_step_library(dt_s=1e-3)
    assert (lib_old is None) == (lib_new is None)


# ---- plant and vehicle helpers: gravity_m_per_s2, acceleration_m_per_s2, omega_*_rad_per_m ---
def test_plant_and_vehicle_helpers_old_names_equal_new() -> None:
    from maglevkit.vehicle.comfort import iso2631_weighted_rms, sperling_index
    from maglevkit.vehicle.guideway import BeamSpan
    from maglevkit.vehicle.irregularities import GermanTrackPSD, PowerLawPSD

    with pytest.warns(DeprecationWarning, match=r"HeaveMass: gravity= is deprecated, use "
                                                r"gravity_m_per_s2="):
        old = mk.vehicle.HeaveMass(100.0, gravity=3.7)
    assert old == mk.vehicle.HeaveMass(100.0, gravity_m_per_s2=3.7)
    with pytest.warns(DeprecationWarning, match=r"HeaveMass: \.gravity is deprecated"):
        assert old.gravity == 3.7
    span = BeamSpan(length_m=31.0, mass_per_length_kg_per_m=3000.0,
                    bending_stiffness_N_m2=2e10)
    with pytest.warns(DeprecationWarning, match=r"self_weight_sag_m: gravity= is deprecated"):
        assert span.self_weight_sag_m(gravity=9.0) == span.self_weight_sag_m(gravity_m_per_s2=9.0)
    t = np.arange(512) / 256.0
    a = 0.3 * np.sin(2 * np.pi * 4.0 * t)
    for f in (iso2631_weighted_rms, sperling_index):
        with pytest.warns(DeprecationWarning, match=r"acceleration= is deprecated, use "
                                                    r"acceleration_m_per_s2="):
            assert f(acceleration=a, sample_rate_Hz=256.0) == f(a, 256.0)
    for psd in (GermanTrackPSD(), PowerLawPSD(1e-8, exponent=0.5)):
        with pytest.warns(DeprecationWarning, match=r"variance_m2: omega_min= is deprecated, "
                                                    r"use omega_min_rad_per_m=; omega_max="):
            assert psd.variance_m2(omega_min=0.1, omega_max=2.0) == psd.variance_m2(0.1, 2.0)


# ---- the audit: a new unit-less quantity name in the public API fails ------------------------
def _unit_audit():  # type: ignore[no-untyped-def]
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "tools" / "unit_name_audit.py"
    spec = importlib.util.spec_from_file_location("unit_name_audit", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_audit_recognises_units_and_quantities() -> None:
    audit = _unit_audit()
    for name in ("gap_m", "dt_s", "voltages_V", "gap_rates_m_per_s", "kd_s_per_m", "area_m2",
                 "bending_stiffness_N_m2", "omega_min_rad_per_m", "inertia_kg_m2"):
        assert audit.has_unit(name), name
    for name in ("gap", "gaps", "dt", "current", "max_current", "initial_currents", "s", "m"):
        assert not audit.has_unit(name), name
    for name in ("gap", "initial_current", "external_force", "dt", "gap_change", "duration"):
        assert audit.names_quantity(name), name
    for name in ("name", "samples", "method", "circuit", "seed"):
        assert not audit.names_quantity(name), name


def test_public_api_has_no_new_unit_less_quantity_names() -> None:
    """Every keyword of a public callable that names a physical quantity carries its unit,
    or is listed with a reason (dimensionless, a name, a switch, a symbol; or deferred)."""
    audit = _unit_audit()
    bad = audit.violations()
    assert not bad, ("public parameters naming a quantity without its unit (rename with "
                     "validation.renamed_keywords, or list in tools/unit_name_audit.py with "
                     "a reason):\n" + "\n".join(f"{k}: {', '.join(v)}"
                                                for k, v in sorted(bad.items())))
    assert not audit.stale_allowances(), ("listed in tools/unit_name_audit.py but no longer "
                                          f"found (remove): {audit.stale_allowances()}")
    for table in (audit.ALLOWED, audit.DEFERRED):
        assert all(isinstance(r, str) and len(r) > 10 for r in table.values())   # a reason


def test_audit_would_catch_the_old_names() -> None:
    """The names this change renamed are caught by the audit's rule (so it guards them)."""
    audit = _unit_audit()
    for old in ("gaps", "currents", "gap", "current", "voltage", "initial_current", "duration",
                "dt", "gap_change", "inductance", "zero_current", "max_current", "gravity",
                "acceleration", "omega_min", "gap_reference", "voltages", "pole_force", "flux",
                "area", "branch_flux"):
        assert audit.names_quantity(old) and not audit.has_unit(old), old


def test_fig7_data_and_circuit_forces_old_names_equal_new() -> None:
    from maglevkit.compare import circuit_forces
    from maglevkit.figures import fig7_data

    std = mk.load_magnet("tr09-standard")
    new = fig7_data(std, gap_m=0.0095, points=5, step_points=0)
    with pytest.warns(DeprecationWarning, match=r"fig7_data: gap= is deprecated, use gap_m="):
        old = fig7_data(std, gap=0.0095, points=5, step_points=0)
    assert old.gap_m == new.gap_m and np.array_equal(old.inductance_full, new.inductance_full)
    pf = np.arange(8.0).reshape(2, 4)
    args = (("a", "b", "c", "d"), {"x": ("a", "b"), "y": ("c", "d")}, ("x", "y"))
    with pytest.warns(DeprecationWarning, match=r"circuit_forces: pole_force= is deprecated"):
        assert np.array_equal(circuit_forces(pole_force=pf, gap_names=args[0], groups=args[1],
                                             circuits=args[2]), circuit_forces(pf, *args))
    assert np.array_equal(circuit_forces(pf, *args), [[1.0, 5.0], [9.0, 13.0]])


def test_vehicle_maps_and_comfort_indices_old_names_equal_new(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from maglevkit.vehicle.comfort import comfort_indices, lateral_comfort_indices
    from maglevkit.vehicle.mapcache import vehicle_maps

    t = np.arange(512) / 256.0
    a = (0.3 * np.sin(2 * np.pi * 4.0 * t))[:, None]
    for f in (comfort_indices, lateral_comfort_indices):
        with pytest.warns(DeprecationWarning, match=r"acceleration= is deprecated"):
            old = f(acceleration=a, sample_rate_Hz=256.0)
        assert all(np.array_equal(o, n) for o, n in zip(old, f(a, 256.0), strict=True))
    lin = mk.load_magnet("u-magnet").with_options(eddy_currents=False)
    g, c = np.linspace(0.006, 0.016, 4), np.linspace(0.0, 40.0, 4)
    new = vehicle_maps(lin, cache_dir=tmp_path, gaps_m=g, currents_A=c)
    with pytest.warns(DeprecationWarning, match=r"vehicle_maps: gaps= is deprecated, use "
                                                r"gaps_m=; currents= .*currents_A="):
        old = vehicle_maps(lin, cache_dir=tmp_path, gaps=g, currents=c)   # from the cache
    assert np.array_equal(old.dataset["force_N"].values, new.dataset["force_N"].values)


# ---- units22b: the last deferred names (circuit, materials, element laws, mechanics, simulate,
# SolverError) ---------------------------------------------------------------------------------
# rename_element_fields: skip   (this file uses the old names on purpose)
def test_circuit_resistance_old_name_equals_new() -> None:
    from maglevkit.reduction.maps import network_hash

    coils = (mk.Coil("core", 100.0),)
    new = mk.Circuit("c", resistance_ohm=1.5, coils=coils)
    with pytest.warns(DeprecationWarning, match=r"Circuit: resistance= is deprecated, use "
                                                r"resistance_ohm="):
        old = mk.Circuit("c", resistance=1.5, coils=coils)
    assert old == new and repr(old) == repr(new)
    with pytest.warns(DeprecationWarning, match=r"\.resistance is deprecated, use "
                                                r"\.resistance_ohm"):
        assert new.resistance == 1.5
    with pytest.raises(InputError, match=r"give resistance_ohm= only"):
        mk.Circuit("c", resistance=1.5, resistance_ohm=1.5, coils=coils)
    # the same network (its identity) whichever name built the circuit
    branches = (mk.Branch("core", "A", "B", (mk.IronPath("i", length_m=0.2,
                                                          cross_section_m2=1e-3),)),
                mk.Branch("air", "B", "A", (mk.AirGap("g", gap_input="s",
                                                       pole_area_m2=1e-3),)))
    assert network_hash(mk.Network(branches, (old,))) == network_hash(mk.Network(branches, (new,)))
    assert np.array_equal(mk.Network(branches, (old,)).resistances, [1.5])


@pytest.mark.parametrize("make", [
    lambda **kw: mk.SoftMagneticMaterial(1000.0, 1.5, 0.5, 0.5, 5.0, **kw),
    lambda **kw: mk.ConstantPermeability(1000.0, **kw),
    lambda **kw: mk.IdealIron(**kw),
    lambda **kw: mk.TabulatedBH((0.0, 100.0, 1000.0), (0.0, 1.0, 1.5), **kw),
], ids=["SoftMagneticMaterial", "ConstantPermeability", "IdealIron", "TabulatedBH"])
def test_material_resistivity_old_name_equals_new(make) -> None:  # type: ignore[no-untyped-def]
    new = make(resistivity_ohm_m=1.5e-7)
    with pytest.warns(DeprecationWarning, match=r": resistivity= is deprecated, use "
                                                r"resistivity_ohm_m="):
        old = make(resistivity=1.5e-7)
    assert old == new and repr(old) == repr(new) and new.resistivity_ohm_m == 1.5e-7
    with pytest.warns(DeprecationWarning, match=r"\.resistivity is deprecated, use "
                                                r"\.resistivity_ohm_m"):
        assert new.resistivity == 1.5e-7


def test_tabulated_from_csv_old_resistivity_equals_new(tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "steel.csv"
    path.write_text("0 0\n100 1.0\n1000 1.5\n")
    new = mk.TabulatedBH.from_csv(path, resistivity_ohm_m=2e-7)
    with pytest.warns(DeprecationWarning, match=r"from_csv: resistivity= is deprecated"):
        old = mk.TabulatedBH.from_csv(path, resistivity=2e-7)
    assert old == new and new.resistivity_ohm_m == 2e-7


def _law_elements() -> list[mk.Element]:
    """One element of every law class (slotted where the class can be), and the calibrated
    wrappers of circuit/factors.py around an air gap and an iron path."""
    from maglevkit.circuit.elements import FringePermeance, GapLayerPermeance
    from maglevkit.circuit.factors import CalibratedIron, CalibratedLinear

    iron = mk.IronPath("i", length_m=0.2, cross_section_m2=1e-3)
    air = mk.AirGap("g", gap_input="s", pole_area_m2=1e-3, slot_pitch_m=0.086,
                    slot_opening_m=0.035, fringe_edges=((0.05, 0.02),))
    return [iron, air, mk.LeakagePermeance("l", value_H=2e-7),
            mk.GapLeakage("gl", gap_input="s", width_m=0.1, radius_m=0.02),
            FringePermeance("f", gap_input="s", width_m=0.1, radius_m=0.03),
            GapLayerPermeance("lay", gap_input="s", width_m=0.1, length_m=0.005),
            mk.EddyCurrent("e", conductance_S=3.0),
            CalibratedLinear("cg", inner=air, leakage=1.1, fringing=1.2, offset=1e-4),
            CalibratedIron("ci", inner=iron, field_scale=1.1, saturation_scale=0.9)]


def test_element_law_old_keywords_equal_new() -> None:
    """``permeance(gap=)``, ``mmf_drop(flux=, gap=)``, ``energy(flux=, gap=)`` (and the air
    gap's ``effective_gap``/``fringe_permeance``) are deprecated aliases: the same float
    operations, so equal bit for bit to the new keywords and to positional calls."""
    from maglevkit.circuit.elements import LinearElement

    s, phi = 0.011, 1.2e-3
    checked = 0
    for el in _law_elements():
        laws = [("mmf_drop", {"flux": phi, "gap": s}, {"flux_Wb": phi, "gap_m": s}),
                ("energy", {"flux": phi, "gap": s}, {"flux_Wb": phi, "gap_m": s})]
        if isinstance(el, LinearElement):
            laws.append(("permeance", {"gap": s}, {"gap_m": s}))
        if isinstance(el, mk.AirGap):
            laws += [("effective_gap", {"gap": s}, {"gap_m": s}),
                     ("fringe_permeance", {"gap": s}, {"gap_m": s})]
        for method, old_kw, new_kw in laws:
            law = getattr(el, method)
            new = law(**new_kw)
            assert new == law(*new_kw.values())
            with pytest.warns(DeprecationWarning, match=rf"{method}: .*{list(old_kw)[-1]}= is "
                                                        rf"deprecated, use "
                                                        rf"{list(new_kw)[-1]}="):
                old = law(**old_kw)
            assert np.array_equal(old, new), (el.name, method)
            checked += 1
    assert checked == 9 * 2 + 6 + 2      # every law of the 9 elements (6 linear, 1 air gap)


def test_carter_coefficient_old_keywords_equal_new() -> None:
    from maglevkit.circuit.elements import carter_coefficient

    new = carter_coefficient(gap_m=0.01, slot_pitch_m=0.086, slot_opening_m=0.035)
    with pytest.warns(DeprecationWarning, match=r"carter_coefficient: gap= is deprecated, use "
                                                r"gap_m=; slot_pitch= .*slot_opening= is "
                                                r"deprecated, use slot_opening_m="):
        old = carter_coefficient(gap=0.01, slot_pitch=0.086, slot_opening=0.035)
    assert old == new == carter_coefficient(0.01, 0.086, 0.035)


def test_vehicle_mechanics_old_gravity_equals_new() -> None:
    from maglevkit.vehicle.mechanics import VehicleMechanics

    train = mk.vehicle.load_vehicle()
    args = (train, [3.0, 9.0, 20.5], [0, 1, 2])
    new = VehicleMechanics(*args, gravity_m_per_s2=3.7)
    with pytest.warns(DeprecationWarning, match=r"VehicleMechanics: gravity= is deprecated, "
                                                r"use gravity_m_per_s2="):
        old = VehicleMechanics(*args, gravity=3.7)
    assert np.array_equal(old.Q_gravity, new.Q_gravity)
    # g enters Q_gravity linearly: the standard g's is the same vector scaled
    std = VehicleMechanics(*args)
    assert np.allclose(new.Q_gravity * (mk.vehicle.STANDARD_GRAVITY / 3.7), std.Q_gravity,
                       rtol=1e-14, atol=0.0)        # one rounding per entry
    with pytest.warns(DeprecationWarning, match=r"\.gravity is deprecated, use "
                                                r"\.gravity_m_per_s2"):
        assert old.gravity == 3.7


def test_simulate_old_time_grid_name_equals_new(u_magnet: mk.Magnet,
                                                 u_maps: mk.CharacteristicMaps) -> None:
    """``t=`` is the deprecated name of ``times_s=`` in ``mk.simulate``, the reduced
    models' ``simulate`` and ``simulate_flux``; positional grids need no name at all."""
    from maglevkit.models.flux import simulate_flux

    cm = mk.CurrentModel(u_maps)
    bank = mk.MagnetBank({"a": u_maps})
    fm = mk.FluxModel(u_magnet.with_options(eddy_currents=False))
    common = dict(gaps_m=0.010, voltages_V=45.0, dt_s=1e-3, initial_currents_A=20.0)
    for where, run in (("simulate", lambda **kw: mk.simulate(cm, **kw, **common)),
                       ("CurrentModel.simulate", lambda **kw: cm.simulate(**kw, **common)),
                       ("MagnetBank.simulate", lambda **kw: bank.simulate(**kw, **common)),
                       ("simulate_flux", lambda **kw: simulate_flux(fm, **kw, **common))):
        new = run(times_s=(0.0, 0.004))
        with pytest.warns(DeprecationWarning, match=rf"{where}: t= is deprecated, use times_s="):
            old = run(t=(0.0, 0.004))
        assert np.array_equal(old.time_s, new.time_s) and new.time_s.size == 5
        assert np.array_equal(old.currents_A, new.currents_A), where
    with pytest.raises(InputError, match=r"give times_s= only"):
        mk.simulate(cm, t=(0.0, 0.004), times_s=(0.0, 0.004), **common)


def test_solver_error_old_time_equals_new() -> None:
    new = mk.SolverError("failed", time_s=0.25, reason="x")
    with pytest.warns(DeprecationWarning, match=r"SolverError: time= is deprecated, use "
                                                r"time_s="):
        old = mk.SolverError("failed", time=0.25, reason="x")
    assert old.time_s == new.time_s == 0.25 and str(old) == str(new)
    assert "at t = 0.25 s" in str(new)
    with pytest.warns(DeprecationWarning, match=r"\.time is deprecated, use \.time_s"):
        assert new.time == 0.25
    with pytest.raises(InputError, match=r"give time_s= only"):
        mk.SolverError("failed", time=0.25, time_s=0.25)
    with pytest.raises(TypeError, match=r"unexpected keyword argument 'times'"):
        mk.SolverError("failed", times=0.25)


def test_audit_scans_the_time_grid_and_exception_keywords() -> None:
    """The audit catches a bare ``t`` and reads exported exceptions' constructors, so
    ``simulate(t)`` and ``SolverError(time=)`` could not come back unnoticed."""
    audit = _unit_audit()
    assert audit.names_quantity("t") and not audit.has_unit("t")
    assert audit.names_quantity("time") and audit.has_unit("times_s")
    inits = audit.exception_constructors()
    assert "maglevkit.errors.SolverError" in inits
    found = audit.findings()
    assert "maglevkit.errors.SolverError" not in found          # time_s carries its unit
    assert not any("t" in params for params in found.values())
    assert audit.DEFERRED == {}
