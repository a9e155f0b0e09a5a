"""Calibration of a magnet's uncertain network factors to measured statics (issue 25,
part 2): exact parameter derivatives, recovery from synthetic data, the FEM as
measurement, identifiability, the calibrated TOML and the command line."""

from __future__ import annotations

import csv
import hashlib
from pathlib import Path

import numpy as np
import pytest
import tomllib
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.calibration import (
    PARAMETERS,
    StaticPoints,
    calibrate,
    calibrated_network,
    load_calibrated_magnet,
    parameter_sensitivities,
    read_points,
    write_calibrated_toml,
)
from maglevkit.cli import app
from maglevkit.errors import DataError

from .statics_csv_checks import calibrate_own_statics

ROOT = Path(__file__).resolve().parents[1]
FEM = ROOT / "benchmarks" / "results" / "u_magnet_fem_statics.csv"
FEM_2MM = ROOT / "benchmarks" / "results" / "u_magnet_fem_statics_2mm.csv"
TRUE = {"leakage_factor": 1.15, "fringing_factor": 0.85, "gap_offset_m": 3e-4,
        "iron_field_scale": 1.3, "iron_saturation_scale": 0.97}


@pytest.fixture(scope="module")
def magnet() -> mk.Magnet:
    return mk.load_magnet("u-magnet", eddy_currents=False)


def _statics(model: object, gaps: np.ndarray, currents: np.ndarray) -> tuple[np.ndarray, ...]:
    sol = mk.solve_statics(model, gaps_m=np.c_[gaps, gaps], currents_A=currents[:, None])
    return (np.asarray(sol.force_N, dtype=float).reshape(-1),
            np.asarray(sol.flux_linkage_Wb, dtype=float).reshape(-1))


def test_nominal_factors_leave_the_statics_unchanged(magnet: mk.Magnet) -> None:
    g, c = np.array([0.004, 0.008, 0.020]), np.array([5.0, 40.0, 80.0])
    f0, p0 = _statics(magnet, g, c)
    f1, p1 = _statics(calibrated_network(magnet, {}), g, c)
    np.testing.assert_array_equal(f0, f1)     # the same law, bit for bit
    np.testing.assert_array_equal(p0, p1)


@pytest.mark.parametrize(("gap", "current"), [(0.008, 40.0), (0.004, 80.0), (0.020, 5.0)])
def test_parameter_derivatives_match_central_differences(magnet: mk.Magnet, gap: float,
                                                         current: float) -> None:
    d = parameter_sensitivities(magnet, TRUE, gap_m=gap, current_A=current)
    f, p = _statics(calibrated_network(magnet, TRUE), np.array([gap]), np.array([current]))
    assert d["force_N"][0] == pytest.approx(f[0], rel=1e-12)
    assert d["flux_linkage_Wb"][0] == pytest.approx(p[0], rel=1e-12)
    for k, name in enumerate(TRUE):
        # central differences of the independent Newton solver (solve_statics) on the
        # numeric calibrated network; h = 1e-4 of the parameter's scale: truncation
        # ~h^2 ~ 1e-8, rounding ~1e-15/1e-4 ~ 1e-11 (measured agreement ~3e-9)
        h = 1e-4 * PARAMETERS[name].scale
        out = [_statics(calibrated_network(magnet, {**TRUE, name: TRUE[name] + sign * h}),
                        np.array([gap]), np.array([current])) for sign in (1, -1)]
        fd_f = (out[0][0][0] - out[1][0][0]) / (2 * h)
        fd_p = (out[0][1][0] - out[1][1][0]) / (2 * h)
        assert d["dforce_dp"][0, k] == pytest.approx(fd_f, rel=1e-6), name
        assert d["dpsi_dp"][0, k] == pytest.approx(fd_p, rel=1e-6), name


def test_recovers_known_parameters_within_their_confidence_intervals(
        magnet: mk.Magnet) -> None:
    g, c = (a.ravel() for a in np.meshgrid(np.arange(4, 21, 2) * 1e-3,
                                           np.array([5.0, 10, 20, 40, 60, 80]), indexing="ij"))
    f, p = _statics(calibrated_network(magnet, TRUE), g, c)
    rng = np.random.default_rng(25)
    inside, estimates = [], []
    for _ in range(20):
        # 0.3 % relative Gaussian noise on every force and flux linkage
        pts = StaticPoints(gap_m=g, current_A=c,
                           force_N=(f * (1 + 3e-3 * rng.standard_normal(f.size)))[:, None],
                           flux_linkage_Wb=(p * (1 + 3e-3 * rng.standard_normal(p.size)))[:, None],
                           circuits=("coil",), rows=np.zeros(g.size, dtype=int))
        res = calibrate(magnet, pts)
        assert res.undetermined == () and res.bounds_active == ()
        inside += [abs(res.values[k] - TRUE[k]) <= res.confidence_95[k] for k in TRUE]
        estimates.append([res.values[k] for k in TRUE])
    # 95 % intervals: of 100 (parameter, run) pairs ~95 contain the truth (measured 97.5 %
    # on 8 runs); P(fewer than 88 | p = 0.95) ~ 0.3 %
    assert np.mean(inside) >= 0.88, np.mean(inside)
    # and the ensemble mean is unbiased to well within one interval
    mean = np.mean(estimates, axis=0)
    half = np.array([res.confidence_95[k] for k in TRUE])
    assert np.all(np.abs(mean - np.array(list(TRUE.values()))) < half / 2)


def test_fem_as_measurement_fit_4_to_12_mm_held_out_16_and_20_mm(magnet: mk.Magnet) -> None:
    res = calibrate(magnet, FEM, holdout_gaps_m=[0.016, 0.020])
    assert {r["gap_m"] for r in res.points} == {0.004, 0.008, 0.012}
    assert {r["gap_m"] for r in res.holdout} == {0.016, 0.020}
    assert len(res.holdout) == 16 and all(r["row"] > 0 for r in res.holdout)
    # the fit removes most of the lumped network's error on the fitted gaps (nominal: force
    # 7.6 %, psi 7.3 %; calibrated 2.3 %, 2.6 %, measured) ...
    assert res.max_error("points") < 0.5 * max(abs(r["relative_error"])
                                               for r in res.nominal_points)
    # ... and carries to the held-out gaps for the flux linkage (7.9 % -> 3.4 %), not for
    # the force at 20 mm (6.0 % -> 6.2 %: the lumped fringe law's gap dependence; the
    # issue's 2 % aim is not met by the lumped network, docs/magnets.md "Calibration")
    nominal_psi = max(abs(r["relative_error"]) for r in res.nominal_holdout
                      if r["quantity"] == "flux_linkage_Wb")
    assert res.max_error("holdout", "flux_linkage_Wb") < 0.6 * nominal_psi
    # 12 points cannot pin the iron's initial permeability: named, interval wider than it
    assert "iron_field_scale" in res.undetermined
    assert res.confidence_95["iron_field_scale"] > PARAMETERS["iron_field_scale"].scale


def test_fem_every_2_mm_fit_4_to_12_mm_held_out_14_to_20_mm(magnet: mk.Magnet) -> None:
    """The issue's held-out split on the FEM solved every 2 mm
    (benchmarks/fem_u_magnet_calibration.py): the lumped network's best documented set
    (leakage and the iron's B axis) carries to 14-20 mm, but not to 2 %."""
    res = calibrate(magnet, FEM_2MM, parameters=["leakage_factor", "iron_saturation_scale"],
                    holdout_gaps_m=[0.014, 0.016, 0.018, 0.020])
    assert {round(r["gap_m"] * 1e3) for r in res.holdout} == {14, 16, 18, 20}
    assert len(res.points) == 40 and len(res.holdout) == 32
    assert res.undetermined == () and res.bounds_active == ()
    nominal = {q: max(abs(r["relative_error"]) for r in res.nominal_holdout
                      if r["quantity"] == q) for q in ("force_N", "flux_linkage_Wb")}
    # measured: nominal held out 6.9 % / 7.9 %, calibrated 4.35 % / 3.61 % (force at
    # 20 mm: the lumped fringe law's gap dependence; psi at 80 A: the saturation shape);
    # bounds with ~0.2 pp margin for solver rounding across platforms
    assert res.max_error("holdout", "force_N") < 4.6e-2 < nominal["force_N"]
    assert res.max_error("holdout", "flux_linkage_Wb") < 3.8e-2 < nominal["flux_linkage_Wb"]
    # the held-out force error grows with the gap at 5 A (+0.6 % at 14 mm, +4.0 % at 20 mm):
    # a structural error of the lumped tubes, not noise
    low = {round(r["gap_m"] * 1e3): r["relative_error"] for r in res.holdout
           if r["quantity"] == "force_N" and r["current_A"] == 5.0}
    assert low[14] < low[16] < low[18] < low[20]


@pytest.mark.slow
def test_fem_held_out_14_to_20_mm_within_2_percent_on_the_cell_network() -> None:
    """The issue's aim met on the U-magnet's cell network (discretisation = "grid",
    air_model = "cells") as calibration base: ~4-7 min (2812 branches, exact Jacobians)."""
    from maglevkit.magnets import build_magnet
    from maglevkit.parameter_files import read_parameter_file

    params, _ = read_parameter_file("u-magnet", what="magnet")
    params = {**params, "magnet": {**params["magnet"], "discretisation": "grid",
                                   "air_model": "cells"}}
    mag = build_magnet(params, options=mk.ModelOptions(eddy_currents=False))
    res = calibrate(mag, FEM_2MM, parameters=["leakage_factor", "iron_saturation_scale"],
                    holdout_gaps_m=[0.014, 0.016, 0.018, 0.020])
    assert res.undetermined == () and res.bounds_active == ()
    # measured: leakage_factor 1.079 +- 0.011 (the air cells outside the gap), k_B
    # 0.998 +- 0.002; held out max 1.24 % force, 0.62 % psi (nominal 2.72 / 2.44 %)
    assert res.max_error("holdout", "force_N") < 0.02
    assert res.max_error("holdout", "flux_linkage_Wb") < 0.02
    assert res.max_error("holdout") < max(abs(r["relative_error"])
                                          for r in res.nominal_holdout)


def test_a_parameter_the_data_cannot_see_is_named(magnet: mk.Magnet) -> None:
    # flux linkage at one gap in the linear range: the gap offset and the fringing factor
    # both only change the gap permeance there -- one direction, two parameters
    c = np.array([2.0, 4.0, 6.0, 8.0])
    g = np.full(c.size, 0.010)
    _, p = _statics(magnet, g, c)
    pts = StaticPoints(gap_m=g, current_A=c, force_N=None, flux_linkage_Wb=p[:, None],
                       circuits=("coil",), rows=np.arange(2, 6))
    res = calibrate(magnet, pts, parameters=["fringing_factor", "gap_offset_m"])
    assert set(res.undetermined) & {"fringing_factor", "gap_offset_m"}
    assert res.singular_values[-1] < 1e-3 * res.singular_values[0]


def test_calibrated_toml_round_trip(magnet: mk.Magnet, tmp_path: Path) -> None:
    """calibrate on synthetic data -> write -> load_magnet: the loaded magnet is the
    calibrated one (statics), with its provenance and the data's hash visible."""
    g, c = (a.ravel() for a in np.meshgrid([0.004, 0.008, 0.012, 0.016], [10.0, 40.0, 80.0],
                                           indexing="ij"))
    true = {k: TRUE[k] for k in ("leakage_factor", "fringing_factor", "iron_saturation_scale")}
    f, p = _statics(calibrated_network(magnet, true), g, c)
    data = tmp_path / "synthetic.csv"
    with data.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["gap_m", "current_A", "force_N", "flux_linkage_Wb"])
        rng = np.random.default_rng(7)     # 0.2 % noise: the fit is not the truth
        w.writerows([gk, ck, fk * (1 + 2e-3 * rng.standard_normal()),
                     pk * (1 + 2e-3 * rng.standard_normal())]
                    for gk, ck, fk, pk in zip(g, c, f, p, strict=True))
    res = calibrate(magnet, data, parameters=list(true))
    out = write_calibrated_toml(magnet, res, tmp_path / "cal.toml", data_source=str(data))
    doc = tomllib.loads(out.read_text())
    sha = hashlib.sha256(data.read_bytes()).hexdigest()
    assert doc["calibration"]["data_sha256"] == sha
    loaded = mk.load_magnet(out, eddy_currents=False)
    assert loaded.calibration == res.values
    assert loaded.name.endswith("(calibrated)")
    assert loaded.provenance["calibration.data_sha256"] == sha
    for name in true:
        tag = loaded.provenance[f"calibration.{name}"]
        assert tag.startswith("calibrated") and sha in tag and "synthetic.csv" in tag, name
    assert loaded.parameter_hash != magnet.parameter_hash     # maps are not shared
    gt, ct = np.array([0.006, 0.014, 0.020]), np.array([10.0, 60.0, 25.0])
    # the loaded file's statics equal the fitted model's: the same law, bit for bit up to
    # the value's repr round trip through TOML (exact for floats)
    np.testing.assert_allclose(_statics(loaded, gt, ct),
                               _statics(calibrated_network(magnet, res.values), gt, ct),
                               rtol=1e-12)
    # ... and differ from the uncalibrated magnet's by the calibration (>= 1 %)
    assert np.max(np.abs(_statics(loaded, gt, ct)[0] / _statics(magnet, gt, ct)[0] - 1)) > 0.01
    # rebuilt with other switches, the factors stay (with_options re-reads the table);
    # without saturation the iron wrapper is linearised like an IronPath
    lin = loaded.with_options(saturation=False)
    assert lin.calibration == res.values
    np.testing.assert_allclose(
        _statics(lin, gt, ct),
        _statics(calibrated_network(magnet.with_options(saturation=False), res.values), gt,
                 ct), rtol=1e-12)
    # Network.with_options linearises the wrapped iron like a plain IronPath
    np.testing.assert_allclose(
        _statics(calibrated_network(magnet, res.values).with_options(saturation=False), gt,
                 ct), _statics(lin, gt, ct), rtol=1e-12)
    assert load_calibrated_magnet(out, eddy_currents=False).calibration == res.values
    # the command line reads it too (the command `calibrate` suggests next)
    cli = CliRunner().invoke(app, ["statics", str(out), "--gaps", "0.01", "--currents", "20"])
    assert cli.exit_code == 0 and "(calibrated)" in cli.output, cli.output
    # factors do not compose: calibrating the calibrated magnet is refused
    with pytest.raises(mk.InputError, match="already carries calibration factors"):
        calibrate(loaded, data, parameters=list(true))
    # the design rebuilds the network from the geometry: a calibrated base is refused
    from importlib import resources

    from maglevkit.design import DesignSpecError, read_design_spec
    from maglevkit.parameter_files import toml_text

    spec = tomllib.loads((resources.files("maglevkit") / "data" / "designs"
                          / "u-magnet-design.toml").read_text())
    spec["design"]["magnet"] = str(out)
    (tmp_path / "spec.toml").write_text(toml_text(spec))
    with pytest.raises(DesignSpecError, match=r"is calibrated .*give the uncalibrated file"):
        read_design_spec(tmp_path / "spec.toml")


@pytest.mark.parametrize(("edit", "match"), [
    ("leakage_factor = 1.05\nleak = 2.0", r"\[calibration\]: unknown key\(s\) \['leak'\]"),
    ("leakage_factor = 9.0", r"leakage_factor = 9\.0: expected a number in \[0\.2, 5\]"),
    ("leakage_factor = 'x'", r"leakage_factor = 'x'"),
    ("leakage_factor = 1.05\n[calibration.provenance]\nleakage_factor = '[E] guess'",
     r"\['leakage_factor'\] lack a 'calibrated \.\.\.' tag"),
    ("leakage_factor = 1.05\n[calibration.provenance]\nleakage_factor = 'calibrated'\n"
     "gap_offset_m = 'calibrated'", r"\['gap_offset_m'\] name no factor"),
])
def test_a_bad_calibration_table_is_refused_naming_the_key(tmp_path: Path, edit: str,
                                                            match: str) -> None:
    src = (ROOT / "src" / "maglevkit" / "data" / "u-magnet.toml").read_text()
    path = tmp_path / "bad.toml"
    path.write_text(src + "\n[calibration]\n" + edit + "\n")
    with pytest.raises(mk.ParameterFileError, match=match):
        mk.load_magnet(path)


def test_bad_calibration_input(magnet: mk.Magnet, tmp_path: Path) -> None:
    with pytest.raises(mk.InputError, match="unknown.*'leak'"):
        calibrate(magnet, FEM, parameters=["leak"])
    with pytest.raises(mk.InputError, match=r"holdout gap 0\.005 m: no data point"):
        calibrate(magnet, FEM, holdout_gaps_m=[0.005])
    bad = tmp_path / "z.csv"
    with bad.open("w", newline="") as fh:
        csv.writer(fh).writerows([["gap_m", "current_A", "force_N"], [0.01, 0, 0.0],
                                  [0.01, 10, 100.0]])
    with pytest.raises(DataError, match=r"row 2: current_A = 0; calibration points need I > 0"):
        read_points(bad)


def _fem_rows() -> tuple[list[str], list[list[str]]]:
    lines = [ln for ln in FEM.read_text().splitlines() if not ln.startswith("#")]
    return lines[0].split(","), [ln.split(",") for ln in lines[1:]]


def _fem_edit(tmp_path: Path, edit=None, header=None) -> Path:  # type: ignore[no-untyped-def]
    head, rows = _fem_rows()
    rows = edit(rows) if edit is not None else rows
    path = tmp_path / "bad.csv"
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows([header or head, *rows])
    return path


def _scale_column(rows, col, factor):  # type: ignore[no-untyped-def]
    return [[*r[:col], repr(float(r[col]) * factor), *r[col + 1:]] for r in rows]


@pytest.mark.parametrize(("edit", "header", "message"), [
    # the CSV rows are file lines: the header is line 1, the first point line 2
    (lambda r: [*r[:4], [r[4][0], r[4][1], "nan", r[4][3]], *r[5:]], None,
     r"row 6, column force_N: 'nan' is not a finite number"),
    (None, ["gap_m", "current_A", "force_N", "psi"], r"unknown column 'psi' \(column 4\)"),
    # force in kN: the nominal magnet's force is ~1000x the data
    (lambda r: _scale_column(r, 2, 1e-3), None,
     r"force_N is 0\.00\d+ x the nominal magnet's \(median over its 20 points, first at "
     r"row 2\).*unit slip"),
    # flux linkage in mWb
    (lambda r: _scale_column(r, 3, 1e3), None, r"flux_linkage_Wb is 1\.0\de\+03 x"),
])
def test_bad_calibration_data_name_the_row(magnet: mk.Magnet, tmp_path: Path, edit, header,
                                           message) -> None:  # type: ignore[no-untyped-def]
    path = _fem_edit(tmp_path, edit, header)
    with pytest.raises(DataError, match=message):
        calibrate(magnet, path, parameters=["leakage_factor", "iron_saturation_scale"])


def test_gap_in_mm_and_a_repeated_point_in_calibration_data(magnet: mk.Magnet,
                                                            tmp_path: Path) -> None:
    # gaps in mm: warned naming the row, then refused as a unit slip (no force at 4 m)
    path = _fem_edit(tmp_path, lambda r: _scale_column(r, 0, 1e3))
    with pytest.warns(mk.PlausibilityWarning, match=r"row 2: gap_m = 4 m .* in mm"), \
            pytest.raises(DataError, match=r"force_N is .* x the nominal magnet's"):
        calibrate(magnet, path, parameters=["leakage_factor"])
    # a point given twice: warned naming both rows, both fitted (scattered points need no
    # grid, so there is no "non-rectangular" case for calibration data)
    path = _fem_edit(tmp_path, lambda r: [*r, r[2]])
    with pytest.warns(mk.DataWarning, match=r"row 22 repeats the point gap 0\.004 m, current "
                                            r"40 A of row 4"):
        pts = read_points(path)
    assert pts.gap_m.size == 21


def test_cli_calibrate(tmp_path: Path) -> None:
    runner = CliRunner()
    out = tmp_path / "c.toml"
    res = runner.invoke(app, ["calibrate", "u-magnet", str(FEM), "-o", str(out), "--params",
                              "leakage_factor,fringing_factor,iron_saturation_scale",
                              "--holdout-gaps", "0.016,0.020"])
    assert res.exit_code == 0, res.output
    assert "fringing_factor = " in res.output and "held out: max" in res.output
    assert f"next: maglevkit statics {out}" in res.stderr
    assert "calibration" in tomllib.loads(out.read_text())
    res = runner.invoke(app, ["calibrate", "u-magnet", str(FEM), "-o", str(out), "--params",
                              "nonsense", "--force"])
    assert res.exit_code == 2 and "Traceback" not in res.output and "nonsense" in res.output


def test_voltage_step_response_and_its_parameter_derivatives() -> None:
    from maglevkit.calibration import step_response_sensitivities

    mag = mk.load_magnet("u-magnet")                 # with eddy currents: a current jump
    vals = {"leakage_factor": 1.1, "iron_saturation_scale": 0.97}
    times = np.linspace(0.002, 0.2, 12)
    kw = {"gap_m": 0.01, "current_A": 20.0, "voltage_step_V": 8.0, "times_s": times}
    d = step_response_sensitivities(mag, vals, **kw)
    ref = mk.voltage_step_response(calibrated_network(mag, vals), gap_m=0.01, voltage_V=48.0,
                                   initial_current_A=20.0, duration_s=0.2, dt_s=0.002, rtol=1e-10,
                                   atol=1e-12)
    idx = np.rint(times / 0.002).astype(int)
    # the collocation run against the adaptive IDAS one: measured 3.4e-10
    np.testing.assert_allclose(d["current_A"], ref.currents_A[idx, 0], rtol=1e-8)
    for k, name in enumerate(vals):
        h = 1e-4 * PARAMETERS[name].scale
        out = [step_response_sensitivities(mag, {**vals, name: vals[name] + sg * h},
                                           **kw)["current_A"] for sg in (1, -1)]
        fd = (out[0] - out[1]) / (2 * h)
        err = np.max(np.abs(d["dcurrent_dp"][:, k] - fd)) / np.max(np.abs(fd))
        # max over the samples relative to the largest derivative.  Central differences
        # of the same discrete scheme: truncation ~ (h/1e-3)^2 x 5.9e-7 (measured at
        # h = 1e-3) ~ 6e-9, the rootfinders' residual 1e-11 of the scaled unknowns makes
        # the noise; measured 6.9e-9 / 1.4e-8 with 10 Radau steps per interval (1.8e-8 /
        # 2.2e-8 with 40; before the scaling, 3-6e-6 for every h:
        # the unscaled Newton's 1e-9 was ~1e-6 of the eddy fluxes)
        assert err < 1e-6, (name, err)


def test_two_circuit_magnet_from_a_suffixed_csv(tmp_path: Path) -> None:
    """TR09 half magnets: per-circuit columns, forces summed over each circuit's poles."""
    mag = mk.load_magnet("tr09-standard", eddy_currents=False)
    true = {"leakage_factor": 1.2, "iron_saturation_scale": 0.95}
    net = calibrated_network(mag, true)
    g, c = (a.ravel() for a in np.meshgrid([0.008, 0.010, 0.012], [10.0, 25.0, 40.0],
                                           indexing="ij"))
    groups = mk.reduction.circuit_pole_groups(mag, gap_m=0.01, current_A=10.0)
    gi = {n: k for k, n in enumerate(net.gap_names)}
    sol = mk.solve_statics(net, gaps_m=np.repeat(g[:, None], len(gi), axis=1),
                           currents_A=np.repeat(c[:, None], 2, axis=1))
    path = tmp_path / "tr09.csv"
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["gap_m", "current_A", "force_N_rear", "force_N_front",
                    "flux_linkage_Wb_rear", "flux_linkage_Wb_front"])
        for k in range(g.size):
            f = {cn: sol.pole_force_N[k, [gi[p] for p in groups[cn]]].sum()
                 for cn in ("front", "rear")}
            j = {cn: net.circuit_names.index(cn) for cn in ("front", "rear")}
            w.writerow([g[k], c[k], f["rear"], f["front"], sol.flux_linkage_Wb[k, j["rear"]],
                        sol.flux_linkage_Wb[k, j["front"]]])
    res = calibrate(mag, path, parameters=list(true))
    # noise-free data of the model itself: the fit returns the truth to the solver's
    # precision (measured 2e-14, residual rms 1e-14)
    for name, value in true.items():
        assert res.values[name] == pytest.approx(value, rel=1e-6), name
    assert res.residual_rms < 1e-8
    assert {r["circuit"] for r in res.points} == {"front", "rear"}


def test_only_the_parameters_spanning_the_null_direction_are_undetermined(
        magnet: mk.Magnet, monkeypatch: pytest.MonkeyPatch) -> None:
    # flux linkage at one gap, into saturation: gap offset and fringing share one null
    # direction (gap permeance), the iron's saturation scale is seen by the high currents
    c = np.array([2.0, 4.0, 6.0, 8.0, 20.0, 40.0, 60.0, 80.0])
    g = np.full(c.size, 0.010)
    _, p = _statics(magnet, g, c)
    pts = StaticPoints(gap_m=g, current_A=c, force_N=None, flux_linkage_Wb=p[:, None],
                       circuits=("coil",), rows=np.arange(2, 2 + c.size))
    names = ["fringing_factor", "gap_offset_m", "iron_saturation_scale"]
    res = calibrate(magnet, pts, parameters=names)
    assert set(res.undetermined) == {"fringing_factor", "gap_offset_m"}
    # measured shares 0.09 / 0.91 / 8e-34
    assert res.null_shares["gap_offset_m"] > 0.5 > res.null_shares["fringing_factor"] > 0.05
    assert res.null_shares["iron_saturation_scale"] < 1e-6
    assert np.isfinite(res.confidence_95["iron_saturation_scale"])
    assert res.converged
    import scipy.optimize

    real = scipy.optimize.least_squares
    monkeypatch.setattr(scipy.optimize, "least_squares",
                        lambda *a, **k: real(*a, **{**k, "max_nfev": 1}))
    with pytest.warns(mk.MaglevkitWarning, match="did not converge"):
        res = calibrate(magnet, pts, parameters=names, initial={"iron_saturation_scale": 1.2})
    assert not res.converged


def test_the_statics_csv_reads_back_into_calibrate(tmp_path: Path) -> None:
    """A new user's first try: `maglevkit statics --csv` writes the magnet's own statics, with
    two derived columns (differential inductance, dpsi/ds) besides force and flux linkage;
    `calibrate` reads that file (a DataWarning names the derived columns it does not read) and,
    the data being the nominal model's own, returns the nominal factors.  Bound: the CSV's
    9 significant digits move the data by <= 5e-9 relative, so a factor by well under 1e-6."""
    data = calibrate_own_statics("u-magnet", "0.004:0.012:5", "5:40:4", tmp_path)
    assert "differential_inductance_H" in data.read_text().splitlines()[0]
