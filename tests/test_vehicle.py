"""The vehicle model of issue 13: vehicle file, heave-pitch mechanics, vehicle runs, CLI.

Independent references: the equations of motion derived separately by
sympy.physics.mechanics (Lagrange) against the composed matrices; energy conservation of
the undamped, unforced springs-only model integrated by an adaptive Runge-Kutta method;
the static weight balance of a standing train (sum of forces = weight, frame loads from
the masses alone); the guideway replayed by the guideway module's own ``Guideway.step``
with the recorded magnet forces.
"""

from __future__ import annotations

import copy
import sys
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.integrate
from typer.testing import CliRunner

from maglevkit.errors import InputError, ParameterFileError
from maglevkit.vehicle import STANDARD_GRAVITY, Guideway, load_guideway
from maglevkit.vehicle.mechanics import VehicleMechanics, derive_sympy
from maglevkit.vehicle.simulation import (
    Failure,
    VehicleModel,
    parse_failure,
    parse_irregularity,
)
from maglevkit.vehicle.train import load_vehicle, parse_vehicle

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def _params() -> dict[str, Any]:
    text = (resources.files("maglevkit") / "data" / "vehicle" / "tr09.toml").read_text()
    return copy.deepcopy(tomllib.loads(text))


def _slot_mechanics(train: Any) -> VehicleMechanics:
    slots = train.magnet_slots()
    return VehicleMechanics(train, [s.centre_m for s in slots], [s.frame for s in slots])


# ------------------------------------------------------------------ vehicle file
def test_bundled_vehicle_file_values_and_provenance() -> None:
    tr = load_vehicle()
    assert tr.n_sections == 3 and tr.magnets_per_side == 8
    assert tr.section_length_m == pytest.approx(24.768)
    assert tr.magnet_length_m == pytest.approx(12 * 0.258)
    assert tr.nominal_gap_m == 0.010
    # empty section 170 t / 3 = 56.7 t [P]: car body + frames + magnets
    empty = tr.car_body_mass_kg + tr.n_frames_per_section * tr.frame_total_mass_kg
    assert empty == pytest.approx(170e3 / 3, rel=1e-3)
    slots = tr.magnet_slots()
    assert [s.kind for s in slots].count("bow") == 2
    assert slots[0].kind == slots[-1].kind == "bow"
    # every value has a provenance tag
    p = _params()
    for table, values in p.items():
        if table == "provenance":
            continue
        for key in values:
            tag = tr.provenance.get(f"{table}.{key}", "")
            assert tag[:3] in ("[P]", "[R]", "[E]"), f"{table}.{key} has no provenance tag"


@pytest.mark.parametrize("change, match", [
    (lambda p: p["car_body"].update(colour=1), r"unknown key\(s\) \['colour'\]"),
    (lambda p: p["frame"].pop("magnet_mass"), "missing required key 'magnet_mass'"),
    (lambda p: p.pop("joint"), r"missing the \[joint\] table"),
    (lambda p: p.update(extra={}), r"unknown table\(s\) \['extra'\]"),
    (lambda p: p["vehicle"].update(magnets_per_side=7), "multiple of"),
    (lambda p: p["secondary"].update(positions=[-9.0, 1.0]), "must lie on their frame"),
    (lambda p: p["vehicle"].update(touchdown_gap=0.02), "below nominal_gap"),
    (lambda p: p["vehicle"].update(landing_gap=0.005), "above nominal_gap"),
    (lambda p: p["provenance"].update({"frame.colour": "[E]"}), "names no value"),
])
def test_vehicle_file_errors_name_the_key(change: Any, match: str) -> None:
    p = _params()
    change(p)
    with pytest.raises(ParameterFileError, match=match):
        parse_vehicle(p, "test.toml")


def test_load_vehicle_unknown_name() -> None:
    with pytest.raises(ParameterFileError, match="no vehicle file 'nope'"):
        load_vehicle("nope")


# ------------------------------------------------------------------ mechanics
def test_mass_matrix_spd_and_stiffness_symmetric() -> None:
    mech = _slot_mechanics(load_vehicle())
    assert mech.n_dof == 2 * (3 + 12)
    np.linalg.cholesky(mech.M)                       # positive definite (raises otherwise)
    np.testing.assert_array_equal(mech.M, mech.M.T)
    np.testing.assert_allclose(mech.K, mech.K.T, rtol=0, atol=0)
    np.testing.assert_allclose(mech.C, mech.C.T, rtol=0, atol=0)
    # without the magnets the train floats free: 3 car bodies (6 DOF) linked by 2 vertical
    # point joints (hinges, 2 constraints) leave 4 rigid-body modes, the frames hang on
    # their air springs; so K has exactly 4 zero eigenvalues (|ev| ~ 1e-8 measured, 1e-6
    # of the largest as bound), the others positive
    ev = np.linalg.eigvalsh(mech.K)
    assert np.sum(np.abs(ev) < 1e-6 * ev.max()) == 4 and ev.min() > -1e-6 * ev.max()


def test_mechanics_against_sympy_lagrange_small_train() -> None:
    """Composed matrices = sympy.physics.mechanics' Lagrange equations (exact rotation,
    linearised), on a 2-section train with one frame per section (fast)."""
    p = _params()
    p["vehicle"].update(sections=2, frames_per_section=1, magnets_per_side=2)
    p["secondary"]["positions"] = [-5.0, 2.0]          # asymmetric: couples heave and pitch
    tr = parse_vehicle(p)
    mech = VehicleMechanics(tr, [3.0, 9.0, 20.5, 30.0], [0, 0, 1, 1])
    ref = derive_sympy(mech)
    for key in ("M", "K", "C", "Q_gravity", "B"):
        # rounding of sums of products of ~1e6 numbers: 1e-12 of the largest entry
        np.testing.assert_allclose(getattr(mech, key), ref[key], rtol=0,
                                   atol=1e-12 * np.abs(ref[key]).max(), err_msg=key)
    # the exact (planar rigid body) mass matrix does not depend on the state
    np.testing.assert_allclose(ref["mass_matrix_q"], mech.M, rtol=1e-14)


@pytest.mark.slow
def test_mechanics_against_sympy_full_train() -> None:
    """The same on the bundled 3-section train (30 DOF; sympy takes minutes)."""
    mech = _slot_mechanics(load_vehicle())
    ref = derive_sympy(mech)
    for key in ("M", "K", "C", "Q_gravity", "B"):
        np.testing.assert_allclose(getattr(mech, key), ref[key], rtol=0,
                                   atol=1e-12 * np.abs(ref[key]).max(), err_msg=key)


def test_energy_conserved_springs_only() -> None:
    """No damping, gravity or control: kinetic + spring energy (summed body by body and
    element by element) is conserved, integrated by DOP853 and by the exact ZOH step."""
    mech = _slot_mechanics(load_vehicle())
    n = mech.n_dof
    rng = np.random.default_rng(3)
    q0 = rng.normal(0, 2e-3, n)
    qd0 = rng.normal(0, 2e-2, n)
    minv = 1.0 / np.diag(mech.M)

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x[n:], -minv * (mech.K @ x[:n])])

    e0 = float(mech.energy_J(q0, qd0))
    sol = scipy.integrate.solve_ivp(rhs, (0, 20.0), np.concatenate([q0, qd0]), method="DOP853",
                                    rtol=1e-11, atol=1e-14, t_eval=np.linspace(0, 20, 401))
    e = mech.energy_J(sol.y[:n].T, sol.y[n:].T)
    # measured drift 3e-10 relative over 20 s (~20 periods of the car-body modes); bound 1e-8
    assert np.abs(e / e0 - 1).max() < 1e-8
    ad, _ = mech.discretize(1e-3, damping=False)
    x = np.concatenate([q0, qd0])
    worst = 0.0
    for _k in range(20):
        for _j in range(500):
            x = ad @ x
        worst = max(worst, abs(float(mech.energy_J(x[:n], x[n:])) / e0 - 1))
    # exact propagator: rounding only (measured ~1e-12 after 10^4 steps); bound 1e-9
    assert worst < 1e-9
    # with the dampers the energy falls (a check that can fail if C had the wrong sign)
    ad_c, _ = mech.discretize(1e-3, damping=True)
    x = np.concatenate([q0, qd0])
    for _j in range(2000):
        x = ad_c @ x
    assert float(mech.energy_J(x[:n], x[n:])) < 0.5 * e0


def test_casadi_rhs_equals_numpy() -> None:
    mech = _slot_mechanics(load_vehicle())
    f = mech.casadi_rhs()
    rng = np.random.default_rng(0)
    q, qd = rng.normal(0, 1e-3, mech.n_dof), rng.normal(0, 1e-2, mech.n_dof)
    forces = rng.normal(3e4, 1e3, mech.B.shape[1])
    xdot = np.asarray(f(np.concatenate([q, qd]), forces)).ravel()
    np.testing.assert_allclose(xdot[mech.n_dof:], mech.accelerations(q, qd, forces),
                               rtol=1e-12, atol=1e-9)


# ------------------------------------------------------------------ runs
@pytest.fixture(scope="module")
def rigid_model() -> VehicleModel:
    return VehicleModel(load_vehicle(), rigid=True)


@pytest.fixture(scope="module")
def elastic_model() -> VehicleModel:
    return VehicleModel(load_vehicle())


def _irregularity(model: VehicleModel) -> Any:
    return parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                              span_length_m=model.guideway.span.length_m)


def test_standing_vehicle_rigid_guideway_carries_its_weight(rigid_model: VehicleModel) -> None:
    tr = rigid_model.train
    res = rigid_model.run(speed_m_per_s=0.0, duration_s=1.0)
    ds = res.dataset
    weight = tr.total_mass_kg * STANDARD_GRAVITY
    f_end = ds.force.isel(time=-1).values
    # sum of the magnet forces = weight (measured 1e-15 relative; bound 1e-9)
    assert abs(f_end.sum() / weight - 1) < 1e-9
    # frame loads: frame with magnets plus its share of the loaded car body (symmetric
    # train: equal air-spring forces, unloaded joints), from the masses alone
    share = (tr.frame_total_mass_kg + tr.loaded_car_body_mass_kg / tr.n_frames_per_section) \
        * STANDARD_GRAVITY
    frame_load = np.bincount(rigid_model.circuit_frame, weights=f_end)
    np.testing.assert_allclose(frame_load, share, rtol=1e-9)
    # gaps stay at nominal (measured 1e-16 m); currents at the trim
    assert np.abs(ds.gap.values - tr.nominal_gap_m).max() < 1e-9
    np.testing.assert_allclose(ds.current.isel(time=-1).values, rigid_model.trim_current_A,
                               rtol=1e-6)
    assert res.touchdown is None


def test_levitates_standing_on_elastic_guideway(elastic_model: VehicleModel) -> None:
    res = elastic_model.run(speed_m_per_s=0.0, duration_s=1.5)
    ds = res.dataset
    gaps = ds.gap.values
    # settling from the initial static fit: measured 9.90-10.2 mm: within 1 mm; settled:
    # over the last 0.3 s no gap moves by more than 2 um (no integrator wind-up), and the
    # remaining offsets are what a rigid frame cannot follow on the sagging girder
    # (measured <= 0.13 mm; bound 0.3 mm)
    assert np.abs(gaps - 0.010).max() < 1e-3
    assert np.ptp(gaps[-300:], axis=0).max() < 2e-6
    assert np.abs(gaps[-300:] - 0.010).max() < 3e-4
    w = ds.guideway_deflection.values[-1]
    assert 1e-3 < w.max() < 5e-3        # the girders sag under the train (static ~3 mm)


def test_levitates_at_500_kmh_elastic_with_irregularities(elastic_model: VehicleModel) -> None:
    res = elastic_model.run(speed_m_per_s=500 / 3.6, duration_s=1.0,
                            irregularity=_irregularity(elastic_model))
    ds = res.dataset
    assert res.touchdown is None
    gaps = ds.gap.values
    # measured 7.0-11.5 mm (1.0 s); stable levitation: well clear of the skids (2 mm)
    # and no growth: the second half's range is not larger than 1.5x the first half's
    assert gaps.min() > 5e-3 and gaps.max() < 14e-3
    half = gaps.shape[0] // 2
    dev1 = np.abs(gaps[:half] - 0.01).max()
    dev2 = np.abs(gaps[half:] - 0.01).max()
    assert dev2 < 1.5 * dev1
    # 2-quadrant chopper: U >= -R_ec I_L with I_L sampled at the step start, so the coil
    # current may undershoot 0 within a step by dI_L R_ec/(R_el + R_ec): measured -0.5 A
    assert ds.current.values.min() > -1.5
    assert np.abs(ds.voltage.values[:-1]).max() <= 440.0 + 1e-9
    # comfort figures are computed and finite
    assert res.comfort and all(np.isfinite(v["sperling_wz"]) for v in res.comfort.values())


def test_circuit_failure_at_400_kmh(elastic_model: VehicleModel) -> None:
    fail = Failure("s2m4/front", 0.3)
    res = elastic_model.run(speed_m_per_s=400 / 3.6, duration_s=1.5, failures=[fail],
                            irregularity=_irregularity(elastic_model))
    ds = res.dataset
    assert res.touchdown is None, res.report()
    i_f = ds.current.sel(circuit="s2m4/front").values
    u_f = ds.voltage.sel(circuit="s2m4/front").values
    t = ds.time.values
    assert np.all(u_f[(t >= 0.3) & (t < t[-1])] == 0.0)
    # the switched-off coil's current decays (L/R ~ 0.4 s): measured 2.8 A at 1.5 s
    assert i_f[-1] < 0.25 * i_f[t < 0.3].mean()
    # its neighbour on the same magnet takes load: its mean current after the failure
    # exceeds the mean before by > 20 % (measured ~ +60 %)
    i_n = ds.current.sel(circuit="s2m4/rear").values
    assert i_n[t > 0.8].mean() > 1.2 * i_n[t < 0.3].mean()
    # the total force still carries the train on average over the last 0.5 s (within 2 %)
    weight = elastic_model.train.total_mass_kg * STANDARD_GRAVITY
    assert abs(ds.force.values[t > 1.0].sum(axis=1).mean() / weight - 1) < 0.02
    assert "minimum gap" in res.report()


def test_touchdown_reported_and_run_stops(rigid_model: VehicleModel) -> None:
    """Every circuit of the first frame (bow magnet s1m1, standard magnet s1m2) switched
    off: the frame drops onto its skids; the report names the circuit and the kind."""
    fails = [Failure("s1m2/front", 0.05), Failure("s1m2/rear", 0.05)]
    fails += [Failure(f"s1m1/c{k}", 0.05) for k in (1, 2, 3)]
    res = rigid_model.run(speed_m_per_s=0.0, duration_s=2.0, failures=fails)
    assert res.touchdown is not None
    name, t, g, kind = res.touchdown
    assert name.split("/")[0] in ("s1m1", "s1m2") and 0.05 < t < 2.0
    assert kind == "landed" and g >= rigid_model.train.landing_gap_m
    assert float(res.dataset.time[-1]) == pytest.approx(t)
    assert "TOUCHDOWN" in res.report()


def test_guideway_in_the_loop_matches_guideway_step(elastic_model: VehicleModel) -> None:
    """Replay the recorded magnet forces through Guideway.step (the guideway module's own
    implementation): same deflections under the circuits (equal and opposite forces)."""
    v = 300 / 3.6
    res = elastic_model.run(speed_m_per_s=v, duration_s=0.3)
    ds = res.dataset
    gw = elastic_model.guideway
    ref = Guideway(gw.span, n_spans=gw.n_spans, origin_m=gw.origin_m)
    xi = elastic_model.circuit_xi_m
    x0 = float(ds.attrs["nose_position_at_t0_m"])
    dt = float(ds.attrs["dt_s"])
    f = ds.force.values
    st = ref.initial_state(first_span=int(ref.span_index(x0 - xi.max())))
    qs = gw.span.static_modal_displacement(ref.modal_forces(st, x0 - xi,
                                                            elastic_model.mechanics_trim_forces()))
    st = type(st)(0.0, st.first_span, qs, np.zeros_like(qs))
    worst = 0.0
    for k in range(ds.sizes["time"] - 1):
        x = x0 + v * k * dt - xi
        w = ref.deflection(st, x).deflection_m
        worst = max(worst, float(np.abs(w - ds.guideway_deflection.values[k]).max()))
        st = ref.step(st, dt, x + 0.5 * v * dt, 0.5 * (f[k] + f[k + 1]))
    # same arithmetic in another order: measured 1e-18 m; bound 1e-12 m (deflections ~3 mm)
    assert worst < 1e-12


@pytest.mark.slow
def test_fine_vs_coarse_force_distribution() -> None:
    """Detailed flux models with per-pole gaps and forces vs reduced models with one force
    per circuit, same short run (the paper's study [17]): the vehicle responses agree."""
    tr = load_vehicle()
    prof = parse_irregularity("sag:0.5e-3", span_length_m=24.768)
    runs = {}
    for kind in ("reduced", "detailed"):
        m = VehicleModel(tr, magnets=kind, rigid=True)
        runs[kind] = m.run(speed_m_per_s=100 / 3.6, duration_s=0.3, irregularity=prof).dataset
    c, d = runs["reduced"], runs["detailed"]
    for var in ("car_body_heave", "frame_heave"):
        a, b = c[var].values, d[var].values
        dev = np.abs(a - a[0]).max()
        diff = np.abs(a - b).max()
        print(f"{var}: response {dev:.3e} m, fine - coarse {diff:.3e} m")
        # the body motions coincide except minor deviations: within 20 % of the response
        assert diff < 0.2 * max(dev, 1e-5), var
    # gaps: measured 20 um apart on a +-87 um response (the detailed magnets' own dynamics,
    # eddy currents and circuit coupling, plus the per-pole gaps); bound 0.5 % of the
    # nominal gap (50 um)
    gdiff = np.abs(c.gap.values - d.gap.values).max()
    print(f"gap: fine - coarse {gdiff:.3e} m")
    assert gdiff < 0.005 * 0.010


# ------------------------------------------------------------------ parsing and CLI
def test_parse_failure_and_irregularity() -> None:
    assert parse_failure("s2m4/front@0.5") == Failure("s2m4/front", 0.5)
    for bad in ("s2m4/front", "@1", "x@-1", "x@nan", "x@abc"):
        with pytest.raises(InputError, match="CIRCUIT@T"):
            parse_failure(bad)
    assert parse_irregularity("none", span_length_m=24.768) is None
    prof = parse_irregularity("random:0.3e-3:2", span_length_m=24.768)
    assert np.sqrt(prof.variance_m2) == pytest.approx(0.3e-3, rel=1e-9)
    with pytest.raises(InputError, match="use sag:A"):
        parse_irregularity("bumps:1", span_length_m=24.768)


def test_model_rejects_bad_input(rigid_model: VehicleModel) -> None:
    with pytest.raises(InputError, match="no circuit 'nope'"):
        rigid_model.run(speed_m_per_s=0.0, duration_s=0.1, failures=[Failure("nope", 0.0)])
    with pytest.raises(InputError, match="speed_m_per_s must be >= 0"):
        rigid_model.run(speed_m_per_s=-1.0, duration_s=0.1)
    with pytest.raises(InputError, match="magnets"):
        VehicleModel(load_vehicle(), magnets="fancy")


@pytest.mark.slow   # 1-4 min; CLI / pool re-run of what fast tests cover (make test-all)
def test_cli_vehicle_run(tmp_path: Any) -> None:
    from maglevkit.cli import app

    runner = CliRunner()
    out = tmp_path / "run.nc"
    r = runner.invoke(app, ["vehicle", "run", "--speed-kmh", "0", "--duration", "0.2", "--rigid",
                            "-o", str(out), "--no-progress"])
    assert r.exit_code == 0, r.output
    assert "minimum gap 10.000 mm" in r.stdout
    import xarray as xr

    with xr.open_dataset(out) as ds:
        assert ds.gap.attrs["units"] == "m" and ds.sizes["circuit"] == 50
    for args, msg in ((["--failure", "s9m9/x@0.1"], "no circuit"),
                      (["--failure", "oops"], "CIRCUIT@T"),
                      (["--irregularity", "bumps:1"], "irregularity"),
                      (["--speed-kmh", "-5"], "--speed-kmh -5")):
        r = runner.invoke(app, ["vehicle", "run", "--duration", "0.1", "--rigid",
                                "--no-progress", *args])
        assert r.exit_code == 2, (args, r.output)
        assert msg in r.output and "Traceback" not in r.output
    r = runner.invoke(app, ["vehicle", "run", "missing.toml", "--no-progress"])
    assert r.exit_code == 2 and "does not exist" in r.output


def test_vehicle_guideway_default_window() -> None:
    gw = load_guideway().guideway(n_spans=1)
    assert gw.spans_needed(load_vehicle().length_m) == 5


@pytest.mark.slow   # 1-4 min; CLI / pool re-run of what fast tests cover (make test-all)
def test_guideway_file_on_the_api_and_the_cli(tmp_path: Any) -> None:
    # a user's guideway file (longer spans, stiffer girder) reaches the model's guideway;
    # the CLI's --guideway takes the same file and names a bad one (issue 27: the options
    # the messages recommend exist)
    from maglevkit.cli import app

    text = (Path(__file__).resolve().parents[1] / "src/maglevkit/data/vehicle/guideway.toml"
            ).read_text()
    text = text.replace("span_length = 24.768", "span_length = 30.96")
    text = text.replace("bending_stiffness = 4.0e10", "bending_stiffness = 8.0e10")
    path = tmp_path / "long-spans.toml"
    path.write_text(text)
    model = VehicleModel(load_vehicle(), guideway=load_guideway(path))
    assert model.guideway.span.length_m == pytest.approx(30.96, rel=1e-12)
    default = VehicleModel(load_vehicle())
    assert default.guideway.span.length_m == pytest.approx(24.768, rel=1e-12)
    # the moving window covers the train on the longer spans too (fewer spans needed)
    assert model.guideway.n_spans * 30.96 >= load_vehicle().length_m
    with pytest.raises(InputError, match="guideway"):
        VehicleModel(load_vehicle(), guideway="long-spans.toml")
    runner = CliRunner()
    r = runner.invoke(app, ["vehicle", "run", "--duration", "0.02", "--no-progress",
                            "--speed-kmh", "100", "--guideway", str(path)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["vehicle", "run", "--duration", "0.02", "--no-progress",
                            "--guideway", str(tmp_path / "missing.toml")])
    assert r.exit_code == 2 and "missing.toml" in r.output and "Traceback" not in r.output
