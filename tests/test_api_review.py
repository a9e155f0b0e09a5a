"""Review findings on the public API: raw Python errors, unchecked values, bools taken as
numbers, unstable results reported as bad input (each test names the finding it pins)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk


@pytest.fixture(scope="module")
def u_lin() -> mk.Magnet:
    """The bundled U-magnet without eddy currents (cheap transients)."""
    return mk.load_magnet("u-magnet", eddy_currents=False)


# ------------------------------------------------------------ closed loop (control/loop)
def _short_run(u_lin: mk.Magnet, **kw):  # type: ignore[no-untyped-def]
    from maglevkit.control import closed_loop, design_gap_controller
    from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

    f0 = float(mk.solve_statics(u_lin, gaps_m=0.01, currents_A=10.0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    ctl = design_gap_controller(u_lin, mass_kg=veh.mass_kg, gap_m=0.01, current_A=10.0)
    return f0, closed_loop(mk.FluxModel(u_lin), veh, ctl, dt_s=1e-3, initial_gap_m=0.01,
                           initial_current_A=10.0, **kw)


def test_gap_metrics_refuse_start_after_the_end_and_missing_reference(u_lin) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    _, res = _short_run(u_lin, duration_s=0.01)
    assert res.max_gap_deviation_m(0.01) >= 0.0          # the last sample still counts
    # was: numpy ValueError "zero-size array to reduction operation maximum"
    with pytest.raises(mk.InputError, match=r"start_s = 0.5 s is after the last sample "
                                            r"\(t = 0.01 s\)"):
        res.max_gap_deviation_m(0.5)
    with pytest.raises(mk.InputError, match=r"start_s \[s\] = True \(bool\)"):
        res.max_gap_deviation_m(True)
    # was: AssertionError (or nothing under python -O)
    bare = dataclasses.replace(res, gap_ref_m=None)
    with pytest.raises(mk.InputError, match="gap_ref_m = None"):
        bare.iae_m_s()
    with pytest.raises(mk.InputError, match="gap_ref_m = None"):
        bare.max_gap_deviation_m()


def test_closed_loop_touchdown_is_a_solver_error_not_bad_input(u_lin) -> None:  # type: ignore[no-untyped-def]
    # a pull 20x the weight towards the rail: the loop cannot hold it and the magnet
    # closes onto the rail; was: InputError (the inputs were fine, the run was unstable)
    f0 = float(mk.solve_statics(u_lin, gaps_m=0.01, currents_A=10.0).force_N)
    with pytest.raises(mk.SolverError, match=r"TOUCHDOWN.*at t = .* s; state: gap_m=") as exc:
        _short_run(u_lin, duration_s=0.5, external_force_N=lambda t: -20 * f0)
    assert not isinstance(exc.value, mk.InputError)
    assert exc.value.time_s is not None and exc.value.time_s < 0.5
    assert exc.value.state["gap_m"] > 0.0


# ------------------------------------------------------- gap controller design (cascade)
def test_gap_controller_design_refuses_gains_without_sign(u_lin, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from maglevkit.control import cascade, design_gap_controller

    # was: ZeroDivisionError (0 A: no flux, K_rho = 0)
    with pytest.raises(mk.InputError, match=r"operating point gap_m = 0.01 m, current_A = "
                                            r"0.0 A .*K_rho = .* = 0 N; must be > 0"):
        design_gap_controller(u_lin, mass_kg=100.0, gap_m=0.01, current_A=0.0)
    # a magnet whose force grows with the gap at constant flux (F_s > m omega^2): the
    # formula gave kp < 0 (an unstable loop) without a word
    real = cascade.solve_statics

    class Stiff:
        def __init__(self, sol):  # type: ignore[no-untyped-def]
            self._sol = sol

        def __getattr__(self, name):  # type: ignore[no-untyped-def]
            return getattr(self._sol, name)

        @property
        def dforce_dgap_N_per_m(self):  # type: ignore[no-untyped-def]
            return self._sol.dforce_dgap_N_per_m + 1e9

    monkeypatch.setattr(cascade, "solve_statics", lambda *a, **k: Stiff(real(*a, **k)))
    with pytest.raises(mk.InputError, match=r"current_A = 10.0 A the gap gain kp = -.* 1/m "
                                            r"\(must be > 0\).*bandwidth_hz = 5 Hz above"):
        design_gap_controller(u_lin, mass_kg=100.0, gap_m=0.01, current_A=10.0)


# --------------------------------------------------------------- vehicle map cache key
def test_map_cache_key_separates_gaps_from_currents_and_checks_the_grid(u_lin, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import shutil

    from maglevkit.vehicle.mapcache import maps_path, vehicle_maps

    # was: one hash of concatenate([gaps, currents]): these two grids shared a file
    a = maps_path(u_lin, np.array([0.008, 0.01]), np.array([0.0, 10.0, 20.0]), tmp_path)
    b = maps_path(u_lin, np.array([0.008, 0.01, 0.0]), np.array([10.0, 20.0]), tmp_path)
    assert a != b
    # a stale file under the name (another grid) is rebuilt, not returned
    g1, c1 = np.linspace(0.008, 0.011, 4), np.linspace(0.0, 30.0, 5)
    g2, c2 = np.linspace(0.008, 0.012, 5), np.linspace(0.0, 30.0, 4)
    vehicle_maps(u_lin, cache_dir=tmp_path, gaps_m=g1, currents_A=c1)
    shutil.copy(maps_path(u_lin, g1, c1, tmp_path), maps_path(u_lin, g2, c2, tmp_path))
    maps = vehicle_maps(u_lin, cache_dir=tmp_path, gaps_m=g2, currents_A=c2)
    np.testing.assert_array_equal(maps.gaps_m, g2)
    np.testing.assert_array_equal(maps.currents_A, c2)
    again = vehicle_maps(u_lin, cache_dir=tmp_path, gaps_m=g2, currents_A=c2)   # now cached
    np.testing.assert_array_equal(again.currents_A, c2)
    with pytest.raises(mk.InputError, match=r"gaps \[m\] = True \(bool\)"):
        vehicle_maps(u_lin, cache_dir=tmp_path, gaps_m=True)


# ---------------------------------------------------- bools are not numbers (ints)
def test_ramp_identification_refuses_bools_and_empty_poles(u_lin) -> None:  # type: ignore[no-untyped-def]
    from maglevkit.reduction.transient import dl_ds_from_ramp, flux_held_ramp

    # was: True taken as 1 s / circuit 1; poles=[] an IndexError
    with pytest.raises(mk.InputError, match=r"duration \[s\] = True \(bool\)"):
        flux_held_ramp(u_lin, gap_m=0.01, current_A=1.0, gap_change_m=1e-4, duration_s=True)
    with pytest.raises(mk.InputError, match=r"samples = True \(bool\)"):
        flux_held_ramp(u_lin, gap_m=0.01, current_A=1.0, gap_change_m=1e-4, duration_s=1.0,
                       samples=True)
    with pytest.raises(mk.InputError, match=r"circuit = True \(bool\)"):
        dl_ds_from_ramp(u_lin, gap_m=0.01, current_A=10.0, circuit=True)
    ng = len(u_lin.network.gap_names)
    for poles in ([], [ng], [0, 0]):
        with pytest.raises(mk.InputError, match=rf"poles = {re.escape(repr(poles))}: expected at least one "
                                                rf"distinct gap-input index in 0..{ng - 1}"):
            dl_ds_from_ramp(u_lin, gap_m=0.01, current_A=10.0, poles=poles)
    with pytest.raises(mk.InputError, match=r"poles = True \(bool\)"):
        dl_ds_from_ramp(u_lin, gap_m=0.01, current_A=10.0, poles=[True])


def test_mechanics_discretize_takes_numpy_ints_not_bools() -> None:
    from maglevkit.vehicle.mechanics import VehicleMechanics
    from maglevkit.vehicle.train import load_vehicle

    train = load_vehicle("tr09")
    slots = train.magnet_slots()
    mech = VehicleMechanics(train, [s.centre_m for s in slots], [s.frame for s in slots])
    with pytest.raises(mk.InputError, match=r"dt_s \[s\] = True \(bool\)"):
        mech.discretize(True)        # was: accepted as 1 s
    ad, bd = mech.discretize(np.int64(1))   # was: refused
    ad1, bd1 = mech.discretize(1.0)
    np.testing.assert_array_equal(ad, ad1)
    np.testing.assert_array_equal(bd, bd1)


# ------------------------------------------------------------------ PSD variances
def test_psd_variance_refuses_reversed_and_divergent_bands() -> None:
    from maglevkit.vehicle.irregularities import GermanTrackPSD, PowerLawPSD

    german, power = GermanTrackPSD(), PowerLawPSD(1e-8, exponent=2.0)
    assert german.variance_m2(0.0, 1.0) > 0.0               # 0 is a fine lower end here
    assert PowerLawPSD(1e-8, exponent=0.5).variance_m2(0.0, 1.0) == pytest.approx(2e-8)
    for psd in (german, power):
        # was: a negative variance
        with pytest.raises(mk.InputError, match=r"omega_max = 0.5 rad/m must be > "
                                                r"omega_min = 5 rad/m"):
            psd.variance_m2(5.0, 0.5)
        with pytest.raises(mk.InputError, match=r"omega_min \[rad/m\] = -1.0: must be >= 0"):
            psd.variance_m2(-1.0, 0.5)
        with pytest.raises(mk.InputError, match=r"omega_max \[rad/m\] = True \(bool\)"):
            psd.variance_m2(0.1, True)
    # was: ZeroDivisionError (exponent 2) / math domain error (exponent 1)
    for n in (1.0, 2.0):
        with pytest.raises(mk.InputError, match=rf"omega_min = 0 rad/m: .*exponent = {n:g} "
                                                r">= 1 diverges"):
            PowerLawPSD(1e-8, exponent=n).variance_m2(0.0, 1.0)


# ------------------------------------------------- raw Python errors -> maglevkit errors
def test_branch_flux_unknown_name(u_lin) -> None:  # type: ignore[no-untyped-def]
    sol = mk.solve_statics(u_lin, gaps_m=0.01, currents_A=10.0)
    first = sol.branch_names[0]
    assert np.isfinite(sol.branch_flux(first))
    # was: ValueError "'nope' is not in list"
    with pytest.raises(mk.InputError, match=rf"name = 'nope' is no branch of this network; "
                                            rf"allowed: {re.escape(first)}, "):
        sol.branch_flux("nope")


def test_parse_provenance_entry_of_a_missing_table() -> None:
    from maglevkit.parameter_files import parse_provenance

    params = {"magnet": {"turns": 10}, "provenance": {"rail.width": "[D]"}}
    # was: KeyError 'rail'
    with pytest.raises(mk.ParameterFileError, match=r"f.toml: \[provenance\] 'rail.width' "
                                                    r"names no value of this file; the file "
                                                    r"has no \[rail\] table"):
        parse_provenance(params, ("magnet", "rail"), "f.toml")
    assert parse_provenance({"magnet": {"turns": 10}, "provenance": {"magnet.turns": "[D]"}},
                            ("magnet", "rail"), "f.toml") == {"magnet.turns": "[D]"}


def test_static_trim_needs_two_force_points_per_frame() -> None:
    from maglevkit.vehicle.mechanics import VehicleMechanics
    from maglevkit.vehicle.train import load_vehicle

    train = load_vehicle("tr09")
    slots = train.magnet_slots()
    pts, frames = [s.centre_m for s in slots], [s.frame for s in slots]
    mech = VehicleMechanics(train, pts, frames)
    _, forces = mech.static_trim(np.ones(len(pts)))
    assert forces.sum() == pytest.approx(mech.Q_gravity[0::2].sum(), rel=1e-9)
    with pytest.raises(mk.InputError, match=rf"(?s)pole_weights = .*: expected {len(pts)} "
                                            r"numbers > 0"):
        mech.static_trim(np.zeros(len(pts)))
    # frame 1 standing on one point only: was numpy LinAlgError "Singular matrix"
    keep = [k for k, f in enumerate(frames) if f != 0 or pts[k] == pts[frames.index(0)]]
    one = VehicleMechanics(train, [pts[k] for k in keep], [frames[k] for k in keep])
    with pytest.raises(mk.InputError, match=r"static_trim: frame1 has force points at "
                                            r"\[.*\] m; each frame needs at least two"):
        one.static_trim(np.ones(len(keep)))


# ------------------------------------------------------------ unvalidated values
def test_scenario_inputs_for_only_voltages_or_gaps() -> None:
    from maglevkit.models import parse_scenario

    sc = parse_scenario({"scenario": {"duration": 1e-3, "dt": 1e-3}, "voltages": {"all": 1.0},
                         "gaps": {"all": 0.01}}, "s.toml")
    assert float(sc.inputs_for(("a",), "voltages")["a"](0.0)) == 1.0
    assert float(sc.inputs_for(("g",), "gaps")["g"](0.0)) == 0.01
    # was: any other value (a typo) silently read the gaps
    with pytest.raises(mk.InputError, match=r"which = 'voltage'; allowed: 'voltages' or 'gaps'"):
        sc.inputs_for(("a",), "voltage")


def test_network_with_options_takes_only_true_or_false(u_lin) -> None:  # type: ignore[no-untyped-def]
    net = mk.load_magnet("u-magnet").network
    assert net.with_options() is net
    assert net.with_options(eddy_currents=False) is not net
    # was: "no" is truthy and kept the eddy currents, 0 removed them
    with pytest.raises(mk.InputError, match=r"eddy_currents = 'no' \(str\): expected True or False"):
        net.with_options(eddy_currents="no")
    with pytest.raises(mk.InputError, match=r"saturation = 0 \(int\): expected True or False"):
        net.with_options(saturation=0)


def test_linear_and_ideal_materials_check_resistivity() -> None:
    from maglevkit.materials import ConstantPermeability, IdealIron

    assert ConstantPermeability(1000.0, resistivity_ohm_m=1.5e-7).resistivity_ohm_m == 1.5e-7
    assert IdealIron(resistivity_ohm_m=1.5e-7).resistivity_ohm_m == 1.5e-7
    # was: accepted (only the other materials checked it)
    for make in (lambda r: ConstantPermeability(1000.0, resistivity_ohm_m=r),
                 lambda r: IdealIron(resistivity_ohm_m=r)):
        with pytest.raises(mk.MaterialError, match=r"resistivity_ohm_m \[ohm m\] = -1e-07: must be > 0"):
            make(-1e-7)
        with pytest.raises(mk.MaterialError, match=r"resistivity_ohm_m \[ohm m\] = 'high' \(str\)"):
            make("high")
        with pytest.raises(mk.MaterialError, match=r"resistivity_ohm_m \[ohm m\] = nan: must be finite"):
            make(float("nan"))


def test_tabulated_signal_refuses_bools() -> None:
    from maglevkit.models.signals import Tabulated

    assert Tabulated((0.0, 1.0), (0.0, 2.0))(0.5) == pytest.approx(1.0)
    # was: True taken as 1 s / 1 V
    with pytest.raises(mk.InputError, match=r"tabulated signal times_s \[s\] = \(0.0, True\) "
                                            r"\(tuple\) contains a bool"):
        Tabulated((0.0, True), (0.0, 2.0))
    with pytest.raises(mk.InputError, match=r"tabulated signal values = \(False, 2.0\) "
                                            r"\(tuple\) contains a bool"):
        Tabulated((0.0, 1.0), (False, 2.0))
    with pytest.raises(mk.InputError, match="tabulated signal values .* contains a string"):
        Tabulated((0.0, 1.0), ("0", 2.0))


def test_eddy_resistance_never_negative(u_lin, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from maglevkit.reduction import parameters

    mag = mk.load_magnet("u-magnet")
    r_el = float(mag.network.resistances[0])
    assert parameters.eddy_resistance(mag, gap_m=0.01, current_A=10.0)[0] > 0.0
    # a current jump above the resistive limit (rounding or a non-passive model): was
    # returned as a negative R_ec
    nc = len(mag.network.circuits)
    monkeypatch.setattr(parameters, "current_jump_admittance",
                        lambda *a, **k: np.eye(nc) * 1.01 / r_el)
    with pytest.raises(mk.SolverError, match=r"negative R_ec = -.* ohm for circuit .*"
                                             r"reason: current-jump admittance Y_jj = .* S "
                                             r"exceeds 1/R_el"):
        parameters.eddy_resistance(mag, gap_m=0.01, current_A=10.0)


def test_saturation_knee_checks_points_and_max_current(u_lin) -> None:  # type: ignore[no-untyped-def]
    from maglevkit.models.characteristics import saturation_knee

    # was: points=True scanned one current, points=0 divided by zero, a negative
    # max_current scanned negative currents
    with pytest.raises(mk.InputError, match=r"points = True \(bool\)"):
        saturation_knee(u_lin, gap_m=0.01, max_current_A=100.0, points=True)
    with pytest.raises(mk.InputError, match=r"points = 1: must be a whole number >= 2"):
        saturation_knee(u_lin, gap_m=0.01, max_current_A=100.0, points=1)
    with pytest.raises(mk.InputError, match=r"max_current \[A\] = -100.0: must be > 0"):
        saturation_knee(u_lin, gap_m=0.01, max_current_A=-100.0)
    with pytest.raises(mk.InputError, match=r"max_current \[A\] = '100' \(str\)"):
        saturation_knee(u_lin, gap_m=0.01, max_current_A="100")


def test_heave_model_mass_and_gravity_refuse_bools() -> None:
    from maglevkit.control.model import MagnetHeaveModel

    # was: mass_kg=True accepted as 1 kg (checked before the maps are looked at)
    with pytest.raises(mk.ParameterError, match=r"mass_kg \[kg\] = True \(bool\)"):
        MagnetHeaveModel(None, mass_kg=True)
    with pytest.raises(mk.ParameterError, match=r"gravity \[m/s\^2\] = -1.0: must be >= 0"):
        MagnetHeaveModel(None, mass_kg=100.0, gravity=-1.0)


def test_failure_time_checked_at_construction() -> None:
    # a NaN failure time never failed the circuit (min(inf, nan) is inf in the run)
    from maglevkit.vehicle.simulation import Failure

    assert Failure("s2m4/front", 0.5).time_s == 0.5
    for bad in (float("nan"), -1.0, True, "0.5"):
        with pytest.raises(mk.InputError, match="time_s"):
            Failure("s2m4/front", bad)   # type: ignore[arg-type]
    with pytest.raises(mk.InputError, match="circuit"):
        Failure("", 0.5)


def test_load_maps_without_its_identity_attributes(tmp_path: Path) -> None:
    # a maps file without magnet_hash / pole_groups was a KeyError on first use
    import numpy as np

    import maglevkit as mk
    from maglevkit.errors import ParameterFileError

    maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.004, 0.02, 5),
                         currents_A=np.linspace(0.0, 80.0, 5), progress=False)
    ds = maps.dataset.copy()
    del ds.attrs["magnet_hash"]
    path = tmp_path / "m.nc"
    ds.to_netcdf(path)
    with pytest.raises(ParameterFileError, match="attribute magnet_hash"):
        mk.load_maps(path)


def test_mpc_refuses_bools_as_numbers() -> None:
    from maglevkit.control.mpc import OffsetFreeMPC
    from maglevkit.errors import ParameterError

    for kw, name in (({"horizon": True}, "horizon"), ({"substeps": True}, "substeps"),
                     ({"sample_time_s": True}, "sample_time_s")):
        args = {"gap_ref_m": 0.01, "sample_time_s": 1e-3, **kw}
        with pytest.raises(ParameterError, match=name):
            OffsetFreeMPC(None, **args)   # type: ignore[arg-type]  # checked before the model


def test_eddy_resistance_rounding_zero_jump_is_no_jump(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from maglevkit.reduction import parameters

    # with the eddy ladder the guidance magnet's coil links coil_air (YL -> YU) with no eddy
    # element in its path: the coil current cannot jump, the jump admittance is zero up to
    # the solve's rounding (was refused as "not passive" where the rounding came out
    # negative, -9.7e-34 S); without coil_air (leakage off) it is finite
    no_air = mk.load_magnet("tr-guidance", eddy_model="ladder", leakage=False)
    y_air = parameters.current_jump_admittance(no_air, gap_m=0.01, current_A=20.0)
    assert np.all(np.diag(y_air) * no_air.network.resistances > 1e-4)   # measured 9.1e-4
    lad = mk.load_magnet("tr-guidance").with_options(eddy_model="ladder")
    y = parameters.current_jump_admittance(lad, gap_m=0.01, current_A=20.0)
    r_el = lad.network.resistances
    assert np.all(np.abs(np.diag(y)) * r_el < 1e-12)
    assert np.all(np.isinf(parameters.eddy_resistance(lad, gap_m=0.01, current_A=20.0)))
    mag = mk.load_magnet("u-magnet")
    r0 = float(mag.network.resistances[0])
    nc = len(mag.network.circuits)
    for yjj, inf in ((-1e-30, True), (1e-13 / r0, True), (-1e-9 / r0, False)):
        monkeypatch.setattr(parameters, "current_jump_admittance",
                            lambda *a, v=yjj, **k: np.eye(nc) * v)
        if inf:
            assert np.isinf(parameters.eddy_resistance(mag, gap_m=0.01, current_A=10.0)[0])
        else:        # a clearly negative admittance is still refused
            with pytest.raises(mk.InputError, match="not passive"):
                parameters.eddy_resistance(mag, gap_m=0.01, current_A=10.0)


def test_maps_of_the_guidance_ladder_build() -> None:
    """The use the zero-jump tolerance is for: ``build_maps`` on the guidance magnet's eddy
    ladder (refused as "not passive" before it).  The jump ``R_ec`` is inf (the coil
    current cannot jump), the step-fitted one finite and positive (measured 11.8 ohm with
    two layers), and the reduced model builds on the maps."""
    lad = mk.load_magnet("tr-guidance", eddy_model="ladder", eddy_layers=2)
    maps = mk.build_maps(lad, gaps_m=np.linspace(0.006, 0.012, 4),
                         currents_A=[0.0, 20.0, 40.0, 60.0], progress=False)
    assert np.all(np.isinf(maps.dataset["eddy_resistance_ohm"].values))
    fit = np.asarray(maps.dataset["eddy_resistance_fit_ohm"].values, dtype=float)
    assert np.all(np.isfinite(fit) & (fit > 0.0)), fit
    mk.CurrentModel(maps)
