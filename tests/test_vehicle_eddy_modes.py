"""Vehicles and the MPC model with the eddy network (``eddy_modes``; docs/bank.md,
"Eddy-network members", docs/vehicle.md): compiled step against the reference loop for
both vehicles, the heave-pitch vehicle's currents replayed by ``CurrentModel(maps,
eddy_modes=2, freewheel=True)``, the MPC model's right-hand side against the single
model's, the option in the vehicle file and the CLI and its refusals."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from maglevkit.errors import InputError, ParameterFileError
from maglevkit.vehicle.simulation import Failure, VehicleModel
from maglevkit.vehicle.train import load_vehicle, parse_vehicle

from .test_vehicle_compiled import loops_agree
from .test_vehicle_ladder3 import heave_pitch_with_two_eddy_states
from .test_vehicle_motion_eddy import nmpc_runs, record_bank_inputs, replay_circuits

# Compiled and reference loops do the same arithmetic in another order (the bound of
# tests/test_vehicle_ladder3.py; measured here 5.4e-14 of a variable's largest value)
RTOL = 1e-10


@pytest.fixture(scope="module")
def model() -> VehicleModel:
    return VehicleModel(load_vehicle(), eddy_modes=2)


def test_heave_pitch_compiled_step_carries_the_branch_currents(model: VehicleModel) -> None:
    """400 km/h, elastic guideway, sag + random irregularity, a circuit failure: the
    compiled step with both branch currents in its state (2 n_c entries, column-major)
    equals the reference loop (bank.step with the bank's (n_c, 2) state) to RTOL; both
    branch currents are recorded per circuit and move; the diodes are on (freewheel) and
    the coil current stays >= 0."""
    m = model
    assert m.bank.n_eddy_states == 2 and m.bank.eddy_modes == 2 and not m.bank.motion_eddy
    assert m.bank.freewheel
    # measured peaks of the branch currents: 2.7 A and 2.4 A
    rp = heave_pitch_with_two_eddy_states(m)
    assert "eddy network (eddy_modes = 2)" in rp.dataset.attrs["magnets"]


def test_vehicle_replayed_through_the_single_model(model: VehicleModel) -> None:
    """A 50 Hz guideway wave (0.05 mm at 400 km/h) and a deep voltage cut (a failure
    sets one circuit to 0 V): circuit s2m4's gaps, gap rates and voltages as the bank
    received them, replayed through ``CurrentModel(maps, eddy_modes=2, freewheel=True)``
    give the vehicle's coil and branch currents to rounding."""
    from maglevkit.reduced.current import CurrentModel
    from maglevkit.vehicle.irregularities import HarmonicProfile

    v, f = 400 / 3.6, 50.0
    m = VehicleModel(load_vehicle(), rigid=True, eddy_modes=2)
    run, calls = record_bank_inputs(m, speed_m_per_s=v, duration_s=0.2,
                                    irregularity=HarmonicProfile(0.05e-3, v / f),
                                    failures=[Failure("s2m4/front", 0.1)])
    ds = run.dataset
    names = list(ds.circuit.values)
    idx = [names.index("s2m4/front"), names.index("s2m4/rear")]
    cm = CurrentModel(m.maps["standard"], eddy_modes=2, freewheel=True,
                      max_step_s=m.bank.max_step_s)
    (cur,), eddy = replay_circuits(m, run, calls, ["s2m4/front", "s2m4/rear"], (cm,), (2, 2))
    veh_i, veh_e = ds.current.values[:, idx], ds.eddy_current.values[:, idx]
    # the same law and sub-steps, only the pole -> circuit gap average in between (the
    # three-state ladder's replay: 2.8e-14 A); bound ~1e-12 relative
    assert np.abs(cur - veh_i).max() <= 1e-12 * np.abs(veh_i).max()
    assert np.abs(eddy - veh_e).max() <= 1e-12 * np.abs(veh_i).max()
    assert np.abs(veh_e).max() > 0.1
    # the failed circuit's voltage drops to 0 V at 0.1 s: its current decays
    assert veh_i[-1, 0] < 0.8 * veh_i[90, 0]


@pytest.mark.parametrize("modes", [1, 2, 3])
def test_mpc_model_carries_the_branch_currents(modes: int) -> None:
    """``MagnetHeaveModel`` of a network bank (one TR09 circuit, as the vehicle's NMPCs):
    state ``[I_L, s, s', I_1..I_m]`` keyed on ``bank.n_eddy_states`` (the bank has no
    ladder: ``motion_eddy`` False); its derivative (the bank's cell tables) equals the
    single ``CurrentModel(maps, eddy_modes=m)``'s (B-splines) at a state with distinct
    branch currents."""
    import maglevkit as mk
    from maglevkit.control.model import MagnetHeaveModel
    from maglevkit.reduced.bank import MagnetBank
    from maglevkit.reduction.maps import CharacteristicMaps
    from maglevkit.vehicle.mapcache import vehicle_maps

    full = vehicle_maps(mk.load_magnet("tr09-standard"))
    maps = CharacteristicMaps(full.dataset.isel(circuit=[0]))
    bank = MagnetBank({"m": maps}, eddy_modes=modes, compiled="never")
    assert not bank.motion_eddy
    mdl = MagnetHeaveModel(bank, mass_kg=3000.0)
    assert (mdl.eddy_states, mdl.n_eddy, mdl.nx) == (modes, modes, 3 + modes)
    rhs, meas = mdl.spline_rhs()
    x = np.array([40.0, 0.0101, 0.02, 1.5, -2.5, 0.7][:3 + modes])
    u, d = np.array([30.0]), np.zeros(mdl.nd)
    a = np.array(mdl.rhs(x, u, d, mdl.table)).ravel()
    b = np.array(rhs(x, u, d)).ravel()
    # bicubic tables vs B-splines: ~4e-14 relative (docs/decisions.md, "The reduced
    # model's compiled tables"); a dropped or swapped branch is O(1)
    assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max(), (a, b)
    cm = mk.CurrentModel(maps, eddy_modes=modes)
    di, de = cm.ode(x[:1], u, x[1:2], x[2:3], x[3:])
    assert np.allclose(np.r_[np.array(di).ravel(), np.array(de).ravel()],
                       np.r_[a[:1], a[3:]], rtol=1e-12, atol=0.0)
    ya = np.array(mdl.measurement(x, u, d, mdl.table)).ravel()
    yb = np.array(meas(x, u, d)).ravel()
    assert np.abs(ya - yb).max() <= 1e-12 * np.abs(ya).max()
    if modes > 1:
        assert abs(a[3] - a[4]) > 10.0          # the branch derivatives differ


def test_mpc_prediction_sub_steps_follow_the_networks_stable_step() -> None:
    """The prediction model's RK4 count (``rk4_substeps``, the one rule of every MPC path)
    follows the network's own stable sub-step (``bank.eddy_step_s``), not the bank's 1 ms
    simulation cap: one RK4 step per 2 ms interval on the TR09 maps; and that one step
    predicts the MPC's horizon (N = 10) within a small part of the EKF's measurement
    spread of a 32-sub-step reference (nmpcnet; docs/control.md)."""
    import math

    import maglevkit as mk
    from maglevkit.control.model import MagnetHeaveModel
    from maglevkit.reduced.bank import MagnetBank
    from maglevkit.reduced.current import eddy_network_parameters
    from maglevkit.reduction.maps import CharacteristicMaps
    from maglevkit.vehicle.mapcache import vehicle_maps

    full = vehicle_maps(mk.load_magnet("tr09-standard"))
    maps = CharacteristicMaps(full.dataset.isel(circuit=[0]))
    bank = MagnetBank({"m": maps}, eddy_modes=2, compiled="never")
    _, step_s = eddy_network_parameters(maps, 2, bank.resistance_ohm)
    assert bank.eddy_step_s == step_s and bank.max_step_s == 1e-3
    assert 2e-3 < step_s < 4e-3                 # 2.8 ms on these maps
    mdl = MagnetHeaveModel(bank, mass_kg=600.0)
    assert mdl.rk4_substeps(2e-3, 1) == 1       # was ceil(2 ms / 1 ms) = 2
    assert mdl.rk4_substeps(2e-3, 3) == 3       # a larger request stands
    assert mdl.rk4_substeps(10e-3, 1) == math.ceil(10e-3 / step_s)   # stability still rules
    # the horizon from the trim with a 50 mm/s gap rate under voltages over the chopper's
    # range, held per 2 ms interval
    xs, _ = mdl.steady_state(0.010)
    x0 = np.asarray(xs, dtype=float).copy()
    x0[2] = 0.05
    u_seq = np.random.default_rng(7).uniform(0.0, load_vehicle().voltage_limit_V, (10, 1))
    d = np.zeros(mdl.nd)
    trajs = {}
    for n in (1, 32):
        f, xk, traj = mdl.discrete(2e-3, n), x0.copy(), []
        for u in u_seq:
            xk = np.asarray(f(xk, u, d, mdl.table)).ravel()
            traj.append(xk)
        trajs[n] = np.array(traj)
    err = np.abs(trajs[1] - trajs[32])
    assert np.ptp(trajs[32][:, 1]) > 1e-4       # the gap does move (> 0.1 mm)
    # 1 % of the EKF's default measurement spread (gap 1 um, current 10 mA); measured
    # here 0.39 nm and 1.6 uA (the vehicle's own circuit model: 1.3 nm, 13 uA; with eq. 8's
    # single step, as the NMPC always predicted, 0.9 nm, 4 uA)
    assert err[:, 1].max() < 1e-8, err[:, 1].max()
    assert err[:, 0].max() < 1e-4, err[:, 0].max()


def test_cross_section_compiled_step_carries_the_branch_currents() -> None:
    """The cross-section with every magnet on its eddy network (``eddy_modes=2``):
    compiled block step and NumPy loop agree to RTOL under a gust and a rail wave, the
    branch currents of both magnet kinds move."""
    from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind
    from maglevkit.vehicle.irregularities import HarmonicProfile

    model = CrossSectionModel(eddy_modes=2)
    assert model.bank.n_eddy_states == 2 and not model.bank.motion_eddy
    kw: dict[str, Any] = dict(speed_m_per_s=400 / 3.6, duration_s=0.3,
                              crosswind=Crosswind(5e3, rise_s=0.1, hold_s=0.1, start_s=0.05),
                              lateral=HarmonicProfile(0.2e-3, 100.0))
    a = loops_agree(model, RTOL, **kw)[1].dataset
    lev, gui = a.levitation_eddy_current, a.guidance_eddy_current
    assert lev.dims == ("time", "levitation_circuit", "eddy_state")
    assert float(np.abs(lev.values).max()) > 0.05 and float(np.abs(gui.values).max()) > 0.05
    assert "eddy network (eddy_modes = 2)" in a.attrs["magnets"]


def test_options_in_the_file_and_their_refusals() -> None:
    """``[magnets] eddy_modes`` in the vehicle file; 4, a bool, or with motion_eddy are
    refused naming the option and the value, on the API and the file; detailed magnets
    too, and a per-kind mapping with an unknown kind or a bad value; the diodes on a
    network with R_0 = inf name the magnet file."""
    from maglevkit.parameter_files import read_parameter_file
    from maglevkit.vehicle.crossrun import CrossSectionModel

    params, label = read_parameter_file("tr09", what="vehicle", folder="vehicle",
                                        table="vehicle")
    assert parse_vehicle({**params, "magnets": {"eddy_modes": 2}}, label).eddy_modes == 2
    assert parse_vehicle(params, label).eddy_modes is None      # unset: the magnets' own
    for bad, words in (({"eddy_modes": 4}, ("eddy_modes = 4",)),
                       ({"eddy_modes": 2, "motion_eddy": True}, ("eddy_modes = 2",
                                                                 "motion_eddy")),
                       ({"eddy_modes": 1.5}, ("eddy_modes",))):
        with pytest.raises(ParameterFileError) as exc:
            parse_vehicle({**params, "magnets": bad}, label)
        for w in words:
            assert w in str(exc.value), (bad, str(exc.value))
    train = load_vehicle()
    for kw, words in (({"eddy_modes": 4}, ("eddy_modes = 4", "0", "1, 2, 3")),
                      ({"eddy_modes": True}, ("eddy_modes = True",)),
                      ({"eddy_modes": 2, "motion_eddy": True}, ("eddy_modes = 2",
                                                                "motion_eddy")),
                      ({"eddy_modes": 2, "magnets": "detailed"}, ("eddy_modes = 2",
                                                                  "'detailed'")),
                      ({"eddy_modes": {"bow": 1, "front": 2}}, ("eddy_modes", "'front'",
                                                                "bow", "standard")),
                      ({"eddy_modes": {"bow": 5}}, ("eddy_modes = 5", "bow magnets"))):
        with pytest.raises(InputError) as exc:
            VehicleModel(train, rigid=True, **kw)
        for w in words:
            assert w in str(exc.value), (kw, str(exc.value))
    with pytest.raises(InputError, match="eddy_modes = 2 with motion_eddy"):
        CrossSectionModel(eddy_modes=2, motion_eddy="levitation")
    with pytest.raises(InputError, match="eddy_modes = -1"):
        CrossSectionModel(eddy_modes=-1)


def test_infinite_r0_with_the_vehicle_diodes_names_the_magnet(monkeypatch) -> None:
    """Vehicle maps whose network has ``R_0 = inf`` cannot fly behind the vehicle's
    diodes: refused naming the option, the magnet file and the reason."""
    import maglevkit as mk
    from maglevkit.reduced.bank import MagnetBank
    from maglevkit.reduction.maps import CharacteristicMaps
    from maglevkit.vehicle.mapcache import vehicle_maps
    from maglevkit.vehicle.simulation import vehicle_bank

    maps = vehicle_maps(mk.load_magnet("tr09-standard"))
    ds = maps.dataset.copy(deep=True)
    r0 = ds["eddy_network_r0_ohm"].values
    r0[:] = np.inf
    ds["eddy_network_r0_ohm"] = (ds["eddy_network_r0_ohm"].dims, r0)
    with pytest.raises(InputError, match=r"eddy_modes = 2: the standard magnet 'tr09-standard' "
                                         r"cannot fly with the eddy network: member 's1m1': "
                                         r"freewheel=True .* R_0 is inf"):
        vehicle_bank(MagnetBank, [("s1m1", CharacteristicMaps(ds))], motion_eddy=False,
                     files={"standard": "tr09-standard"}, kind_of={"s1m1": "standard"},
                     eddy_modes=2, freewheel=True, compiled="never")


@pytest.mark.slow   # 1-4 min; CLI / pool re-run of what fast tests cover (make test-all)
def test_cli_takes_the_option(tmp_path: Any) -> None:
    """``maglevkit vehicle run`` without ``--eddy-modes`` flies the magnet files' eddy
    network and writes both branch currents, ``--eddy-modes 0`` eq. 8 without them; 4,
    or 2 with --motion-eddy, fail naming it."""
    import xarray as xr
    from typer.testing import CliRunner

    from maglevkit.cli import app

    out = tmp_path / "run.nc"
    base = ["vehicle", "run", "tr09", "--rigid", "--duration", "0.01", "--no-progress"]
    # unset: the magnet files' default (the bundled TR09: 2 branches)
    res = CliRunner().invoke(app, [*base, "-o", str(out)])
    assert res.exit_code == 0, res.output
    with xr.open_dataset(out) as ds:
        assert ds.eddy_current.dims == ("time", "circuit", "eddy_state")
        assert ds.eddy_state.size == 2
        assert "eddy network (eddy_modes = 2)" in ds.attrs["magnets"]
    res = CliRunner().invoke(app, [*base, "--eddy-modes", "0", "-o", str(out), "--force"])
    assert res.exit_code == 0, res.output
    with xr.open_dataset(out) as ds:
        assert "eddy_current" not in ds and "eddy network" not in ds.attrs["magnets"]
    for extra, words in ((["--eddy-modes", "4"], ("eddy_modes = 4",)),
                         (["--eddy-modes", "2", "--motion-eddy"], ("eddy_modes = 2",
                                                                   "motion_eddy"))):
        res = CliRunner().invoke(app, [*base, *extra])
        assert res.exit_code != 0
        for w in words:
            assert w in res.output, (extra, res.output)


@pytest.mark.slow
def test_nmpc_flies_the_eddy_network_and_its_compiled_blocks_are_the_numpy_loop() -> None:
    """controller="mpc" with network magnets (one section, 400 km/h, bundled
    irregularity, 0.3 s), as the ladders' tests: every prediction model carries both
    branch currents per circuit, no touchdown, and the run in compiled blocks equals the
    NumPy loop (bound 1e-7 of each variable's largest value, as there)."""
    import dataclasses

    train = dataclasses.replace(load_vehicle(), n_sections=1)
    m = VehicleModel(train, controller="mpc", eddy_modes=2)
    assert all(c.model.n_eddy == 2 * c.model.n_circuits and not c.model.bank.motion_eddy
               for c in m.circuit_controllers.values())
    a = nmpc_runs(m)
    assert float(np.abs(a.dataset.eddy_current.values).max()) > 0.5
