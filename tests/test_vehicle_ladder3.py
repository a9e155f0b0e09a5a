"""Vehicles and the MPC model with the three-state shielded-gap ladder (``motion_eddy=True,
eddy_branches=2``; docs/equations.md section 8, "Three states"; docs/vehicle.md): compiled
step against the reference loop for both vehicles, the vehicle's currents replayed by
``CurrentModel(maps, motion_eddy=True, eddy_branches=2)`` and held against the detailed
flux model next to eq. 8 and the two-state ladder, the MPC model's state order against the
single model's, an offset-free NMPC on the three-state plant, the options in the vehicle
file and the CLI and their refusals."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from maglevkit.errors import InputError, MaglevkitWarning, ParameterFileError
from maglevkit.vehicle.simulation import VehicleModel, VehicleRun
from maglevkit.vehicle.train import load_vehicle, parse_vehicle

from .test_vehicle_compiled import heave_pitch_runs, loops_agree
from .test_vehicle_motion_eddy import (
    lumped_tr09,
    lumped_train,
    nmpc_runs,
    record_bank_inputs,
    replay_circuits,
)

# Compiled and reference loops do the same arithmetic in another order (the bound of
# tests/test_vehicle_motion_eddy.py; measured here 3.5e-14 of a variable's largest value
# on the heave-pitch run below)
RTOL = 1e-10


def heave_pitch_with_two_eddy_states(m: VehicleModel) -> VehicleRun:
    """The heave-pitch scenario (heave_pitch_runs, RTOL) on a vehicle with two eddy states
    per circuit: the compiled step's state holds 2 n_c of them (column-major), the
    reference loop's dataset records them per circuit as I_e1, I_e2 (the compiled loop's
    in the same layout), both start at 0 and move (peaks > 0.5 A) and differ (by > 0.1 A,
    so that a swap of the two or of circuits in the column-major block shows as an O(1)
    difference between the loops), and the coil current never reverses (the chopper floor
    U >= -R_a I_u, the diodes). Returns the reference loop's run."""
    nc = m.bank.n_circuits
    lay = m.step_function(1e-3).layout
    assert lay.state["I_e"].stop - lay.state["I_e"].start == 2 * nc
    rc, rp = heave_pitch_runs(m, RTOL)
    ie = rp.dataset.eddy_current
    assert ie.dims == ("time", "circuit", "eddy_state") and ie.shape[1:] == (nc, 2)
    assert list(ie.eddy_state.values) == ["I_e1", "I_e2"]
    assert np.array_equal(rc.dataset.eddy_current.dims, ie.dims)
    peaks = np.abs(ie.values).max(axis=(0, 1))
    assert float(np.abs(ie.values[0]).max()) == 0.0 and peaks.min() > 0.5
    assert abs(peaks[0] - peaks[1]) > 0.1
    assert float(rp.dataset.current.values.min()) >= -1e-12
    return rp


def test_heave_pitch_compiled_step_carries_both_eddy_states() -> None:
    """400 km/h, elastic guideway, sag + random irregularity, a circuit failure: the
    compiled step with I_e1, I_e2 in its state (2 n_c entries, column-major) equals the
    reference loop (bank.step with the bank's (n_c, 2) state) to RTOL, both eddy states
    are recorded per circuit and move, the coil current stays >= 0."""
    m = VehicleModel(lumped_train(), motion_eddy=True, eddy_branches=2)
    assert m.bank.n_eddy_states == 2 and m.eddy_branches == 2
    # measured peaks of I_e1, I_e2: 3.1 A and 3.9 A
    rp = heave_pitch_with_two_eddy_states(m)
    assert "three-state" in rp.dataset.attrs["magnets"]


def test_three_state_vehicle_replayed_and_held_against_the_detailed_model() -> None:
    """A 50 Hz guideway wave (0.05 mm at 400 km/h, rigid guideway), as
    tests/test_vehicle_motion_eddy.py for the two-state ladder: circuit s2m4's gaps, gap
    rates and voltages as the three-state vehicle's bank received them, replayed through
    ``CurrentModel(maps, motion_eddy=True, eddy_branches=2)`` (the vehicle's coil and
    eddy currents to rounding) and, as the independent reference, through the detailed
    ``FluxModel`` of the same network, next to eq. 8 and the two-state ladder: the
    three-state ladder follows the detailed model closest."""
    from maglevkit.models.flux import FluxModel
    from maglevkit.reduced.current import CurrentModel
    from maglevkit.vehicle.irregularities import HarmonicProfile

    v, f = 400 / 3.6, 50.0
    m = VehicleModel(lumped_train(), rigid=True, motion_eddy=True, eddy_branches=2)
    run, calls = record_bank_inputs(m, speed_m_per_s=v, duration_s=0.3,
                                    irregularity=HarmonicProfile(0.05e-3, v / f))
    ds = run.dataset
    names = list(ds.circuit.values)
    idx = [names.index("s2m4/front"), names.index("s2m4/rear")]
    assert float(ds.current.values.min()) > 5.0      # the diodes never conduct
    maps = m.maps["standard"]
    h = m.bank.max_step_s
    models = (CurrentModel(maps, motion_eddy=True, eddy_branches=2, max_step_s=h),
              CurrentModel(maps, motion_eddy=True, max_step_s=h),
              CurrentModel(maps, max_step_s=h), FluxModel(m.magnets["standard"]))
    cur, eddy = replay_circuits(m, run, calls, ["s2m4/front", "s2m4/rear"], models, (2, 2))
    veh_i, veh_e = ds.current.values[:, idx], ds.eddy_current.values[:, idx]
    # the same law and sub-steps, only the pole -> circuit gap average in between:
    # measured 2.8e-14 A (coil, ~50 A) and 1.3e-15 A (eddy); bound ~1e-12 relative
    assert np.abs(cur[0] - veh_i).max() <= 1e-12 * np.abs(veh_i).max()
    assert np.abs(eddy - veh_e).max() <= 1e-12 * np.abs(veh_i).max()
    assert np.abs(veh_e).max() > 0.1
    # against the detailed model after the start (0.1 s): RMS error over both circuits
    # measured 0.31 / 0.81 / 1.93 A (three-state / two-state / eq. 8; the current varies
    # by 7.4 A RMS); the front circuit's 50 Hz fundamental per gap 196 / 201 / 232 / 190
    # A/m at 79.5 / 86.6 / 89.3 / 80.7 deg (three / two / eq. 8 / detailed)
    t = ds.time.values
    sel = t >= 0.1
    err = [float(np.sqrt(np.mean((cur[j, sel] - cur[3, sel]) ** 2))) for j in range(3)]
    assert err[0] < 0.6 * err[1] < 0.6 * err[2], err
    ph = np.exp(-2j * np.pi * f * t[sel])
    gap = ds.gap.values[sel, idx[0]]
    gain = 2 * np.mean((gap - gap.mean()) * ph)

    def fundamental(x: np.ndarray) -> complex:
        return complex(2 * np.mean((x - x.mean()) * ph) / gain)

    z = [fundamental(cur[j, sel, 0]) for j in range(4)]
    phase_err = [abs(math.degrees(np.angle(z[j] / z[3]))) for j in range(3)]
    # measured 1.1 / 5.9 / 8.7 deg: the three-state ladder within the 5 deg
    assert phase_err[0] < 3.0 and phase_err[0] < phase_err[1] < phase_err[2], phase_err
    assert abs(abs(z[0]) / abs(z[3]) - 1) < abs(abs(z[1]) / abs(z[3]) - 1)


def test_mpc_model_carries_both_eddy_states_and_flies_a_heave_mass() -> None:
    """``MagnetHeaveModel`` of a three-state bank (one TR09 circuit, as the vehicle's
    NMPCs): state ``[I_L, s, s', I_e1, I_e2]``; its derivative (the bank's cell tables,
    the bank's law) equals the single model's (B-splines, CurrentModel's own circuit-by-
    circuit eddy order) at a state with distinct eddy currents, and the offset-free NMPC
    on it holds the three-state plant at the reference under a +10 % load."""
    import maglevkit as mk
    from maglevkit.control import closed_loop
    from maglevkit.control.model import MagnetHeaveModel
    from maglevkit.control.mpc import OffsetFreeMPC
    from maglevkit.reduced.bank import MagnetBank
    from maglevkit.reduction.maps import CharacteristicMaps
    from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass
    from maglevkit.vehicle.mapcache import vehicle_maps

    full = vehicle_maps(mk.load_magnet(lumped_tr09()["tr09-standard"]))
    maps = CharacteristicMaps(full.dataset.isel(circuit=[0]))
    eq8 = mk.CurrentModel(maps)
    gaps0 = np.full(len(eq8.gap_names), 0.010)
    f0 = float(np.sum(eq8.outputs(eq8.initial_state(gaps_m=gaps0, currents_A=[40.0]))
                      .force_N))
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    bank = MagnetBank({"m": maps}, motion_eddy=True, eddy_branches=2, compiled="never")
    model = MagnetHeaveModel(bank, mass_kg=veh.mass_kg)
    assert (model.eddy_states, model.n_eddy, model.nx) == (2, 2, 5)
    rhs, _ = model.spline_rhs()
    x = np.array([40.0, 0.0101, 0.02, 1.5, -2.5])
    u, d = np.array([30.0]), np.zeros(model.nd)
    a = np.array(model.rhs(x, u, d, model.table)).ravel()
    b = np.array(rhs(x, u, d)).ravel()
    # bicubic tables vs B-splines: ~4e-14 relative (docs/decisions.md, "The reduced
    # model's compiled tables"; measured 4e-15 here); a swapped I_e1/I_e2 is O(1)
    assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max(), (a, b)
    assert abs(a[3] - a[4]) > 10.0          # the two eddy derivatives differ
    ctl = OffsetFreeMPC(model, gap_ref_m=0.010, sample_time_s=1e-3, horizon=20,
                        interval_s=2e-3, solver="rti")
    plant = mk.CurrentModel(maps, motion_eddy=True, eddy_branches=2)
    res = closed_loop(plant, veh, ctl, duration_s=1.5, dt_s=1e-3, initial_gap_m=0.010,
                      initial_current_A=ctl.design_state[0],
                      external_force_N=lambda t: 0.1 * f0 if t >= 0.02 else 0.0)
    # offset-free: the gap back within the 1 um after the 10 % load step (the
    # plant is the controller's model on B-splines instead of tables; measured 0.24 um
    # at 1.5 s, 0.77 um at 1.0 s: the 3-t heave mass settles slowly)
    assert abs(res.gap_m[-1] - 0.010) < 1e-6, res.gap_m[-1]
    assert np.abs(res.gap_m - 0.010).max() < 1e-3          # measured 0.22 mm
    assert np.all(np.abs(res.voltages_V) <= 440.0)
    est = res.diagnostics["disturbance_estimate"][-1][0]
    assert est == pytest.approx(0.1 * f0, rel=0.02)         # measured 1.004 x the load


def test_cross_section_compiled_step_carries_both_eddy_states() -> None:
    """The cross-section with three-state ladder levitation magnets (``"levitation"``;
    the guidance magnet's three-state fit is worse than its two-state one, so ``True``
    warns, measured 77 %): compiled block step and NumPy loop agree to RTOL under a gust
    and a rail wave, the levitation eddy states move, the guidance ones stay exactly 0."""
    from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind
    from maglevkit.vehicle.irregularities import HarmonicProfile

    lumped, guidance = lumped_tr09()["tr09-standard"], lumped_tr09()["tr-guidance"]
    model = CrossSectionModel(levitation_magnet=lumped, guidance_magnet=guidance,
                              motion_eddy="levitation",
                              eddy_branches=2)
    assert model.bank.n_eddy_states == 2
    kw: dict[str, Any] = dict(speed_m_per_s=400 / 3.6, duration_s=0.5,
                              crosswind=Crosswind(5e3, rise_s=0.2, hold_s=0.1, start_s=0.2),
                              lateral=HarmonicProfile(0.2e-3, 100.0))
    a = loops_agree(model, RTOL, **kw)[1].dataset
    lev, gui = a.levitation_eddy_current, a.guidance_eddy_current
    assert lev.dims == ("time", "levitation_circuit", "eddy_state")
    assert float(np.abs(lev.values).max()) > 0.05 and float(np.abs(gui.values).max()) == 0.0
    assert "three-state" in a.attrs["magnets"]
    with pytest.warns(MaglevkitWarning,
                      match="guidance magnet '.*tr-guidance-lumped.toml'.*three-state"):
        CrossSectionModel(levitation_magnet=lumped, guidance_magnet=guidance, motion_eddy=True,
                          eddy_branches=2)


def test_options_in_the_file_and_their_refusals() -> None:
    """``[magnets] eddy_branches`` in the vehicle file; 3, a bool, or 2 without
    motion_eddy are refused naming the option and the value, on the API and the file."""
    from maglevkit.parameter_files import read_parameter_file
    from maglevkit.vehicle.crossrun import CrossSectionModel

    params, label = read_parameter_file("tr09", what="vehicle", folder="vehicle",
                                        table="vehicle")
    both = {**params, "magnets": {"motion_eddy": True, "eddy_branches": 2}}
    assert parse_vehicle(both, label).eddy_branches == 2
    assert parse_vehicle(params, label).eddy_branches == 1
    for bad, words in (({"motion_eddy": True, "eddy_branches": 3}, ("eddy_branches = 3",)),
                       ({"eddy_branches": 2}, ("eddy_branches = 2", "motion_eddy")),
                       ({"motion_eddy": True, "eddy_branches": 1.5}, ("eddy_branches",))):
        with pytest.raises(ParameterFileError) as exc:
            parse_vehicle({**params, "magnets": bad}, label)
        for w in words:
            assert w in str(exc.value), (bad, str(exc.value))
    train = load_vehicle()
    for kw, words in (({"motion_eddy": True, "eddy_branches": 3}, ("eddy_branches = 3", "1", "2")),
                      ({"motion_eddy": True, "eddy_branches": True}, ("eddy_branches = True",)),
                      ({"motion_eddy": False, "eddy_branches": 2}, ("eddy_branches = 2",
                                                                     "motion_eddy"))):
        with pytest.raises(InputError) as exc:
            VehicleModel(train, rigid=True, **kw)
        for w in words:
            assert w in str(exc.value), (kw, str(exc.value))
    with pytest.raises(InputError, match="eddy_branches = 2 needs motion_eddy"):
        CrossSectionModel(eddy_branches=2)
    with pytest.raises(InputError, match="eddy_branches = 0"):
        CrossSectionModel(motion_eddy="levitation", eddy_branches=0)


def test_cli_takes_the_option(tmp_path: Any) -> None:
    """``maglevkit vehicle run --motion-eddy --eddy-branches 2`` flies the three-state
    ladder and writes both eddy states; 3, or 2 without --motion-eddy, fail naming it."""
    import xarray as xr
    from typer.testing import CliRunner

    from maglevkit.cli import app

    out = tmp_path / "run.nc"
    base = ["vehicle", "run", lumped_tr09()["tr09"], "--rigid", "--duration", "0.01",
            "--no-progress"]
    res = CliRunner().invoke(app, [*base, "--motion-eddy", "--eddy-branches", "2", "-o",
                                   str(out)])
    assert res.exit_code == 0, res.output
    with xr.open_dataset(out) as ds:
        assert ds.eddy_current.dims == ("time", "circuit", "eddy_state")
        assert "three-state" in ds.attrs["magnets"]
    for extra, words in ((["--motion-eddy", "--eddy-branches", "3"], ("eddy_branches = 3",)),
                         (["--eddy-branches", "2"], ("eddy_branches = 2", "motion_eddy"))):
        res = CliRunner().invoke(app, [*base, *extra])
        assert res.exit_code != 0
        for w in words:
            assert w in res.output, (extra, res.output)
    res = CliRunner().invoke(app, ["vehicle", "run", "--vehicle", "tr09-cross-section",
                                   "--duration", "0.01", "--no-progress", "--eddy-branches",
                                   "2"])
    assert res.exit_code != 0 and "eddy_branches = 2" in res.output, res.output


@pytest.mark.slow
def test_nmpc_flies_the_three_state_ladder_and_its_compiled_blocks_are_the_numpy_loop() -> None:
    """controller="mpc" with three-state ladder magnets (one section, 400 km/h, bundled
    irregularity, 0.3 s), as the two-state ladder's test in
    tests/test_vehicle_motion_eddy.py: every prediction model carries I_e1, I_e2, no
    touchdown, and the run in compiled blocks equals the NumPy loop (bound 1e-7 of each
    variable's largest value, as there; measured 7.5e-9 (I_e), 7.3e-9 (voltage))."""
    import dataclasses

    train = dataclasses.replace(lumped_train(), n_sections=1)
    m = VehicleModel(train, controller="mpc", motion_eddy=True, eddy_branches=2)
    assert all(c.model.n_eddy == 2 * c.model.n_circuits
               for c in m.circuit_controllers.values())
    a = nmpc_runs(m)
    assert float(np.abs(a.dataset.eddy_current.values).max()) > 1.0    # measured 8.2 A
