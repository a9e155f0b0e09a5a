"""Sweeps of the cross-section vehicle (issue 24): the ``cross-section`` job's file
checks name the key, and a tiny sweep through ``maglevkit sweep`` holds each case's
minimum gaps, equal to the same runs made directly with ``CrossSectionModel.run``."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from typer.testing import CliRunner

from maglevkit.cli import app
from maglevkit.errors import ParameterFileError
from maglevkit.sweep import CrossSectionJob, bundled_sweeps, load_sweep, scenario

runner = CliRunner()

# 0.1 s (100 steps: the comfort figures need >= 64 samples) of a curve entered at once
# (no transition: the lateral load steps in) with a 5 kN step gust at 0.02 s
SWEEP = """\
[sweep]
name = "tiny cross-section"
job = "cross-section"

[cross_section]
duration = 0.1
dt = 1e-3
curve_radius = 2000.0
curve_superelevation = 0.1
crosswind_force = 5000.0
crosswind_shape = "step"
crosswind_start = 0.02

[parameters]
speed = [40.0, 120.0]
"""


def _file(tmp: Path, text: str = SWEEP) -> Path:
    p = tmp / "xs.toml"
    p.write_text(text)
    return p


def test_tiny_sweep_through_the_cli_holds_the_minimum_gaps(tmp_path: Path) -> None:
    out = tmp_path / "xs.nc"
    res = runner.invoke(app, ["sweep", str(_file(tmp_path)), "-o", str(out), "--workers", "1",
                              "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "2 cases: 2 run" in res.stdout
    with xr.open_dataset(out) as back:
        ds = back.load()
    assert ds.attrs["job"] == "cross-section" and ds.attrs["swept"] == "speed"
    assert (ds["status"].values == "ok").all()
    assert ds["min_levitation_gap"].attrs["units"] == "m"
    assert ds.sizes["circuit"] == 8 and "comfort_point" not in ds.dims
    assert ds.attrs["fixed_curve_radius"] == 2000.0
    assert ds.attrs["fixed_crosswind_shape"] == "step"
    # the summary is the per-circuit minima's minimum, per kind
    lev = [c for c in ds["circuit"].values if str(c).startswith("levitation")]
    gui = [c for c in ds["circuit"].values if str(c).startswith("guidance")]
    np.testing.assert_array_equal(ds["min_levitation_gap"].values,
                                  ds["gap_min"].sel(circuit=lev).min("circuit").values)
    np.testing.assert_array_equal(ds["min_guidance_gap"].values,
                                  ds["gap_min"].sel(circuit=gui).min("circuit").values)
    np.testing.assert_array_equal(ds["min_gap"].values, ds["gap_min"].min("circuit").values)
    assert np.isfinite(ds["lateral_wd_rms"].values).all()
    # a second path: the same runs made directly (deterministic: equal to the last bit)
    from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind, TransitionCurve

    model = CrossSectionModel()
    for v in (40.0, 120.0):
        run = model.run(speed_m_per_s=v, duration_s=0.1, dt_s=1e-3,
                        curve=TransitionCurve(2000.0, 0.1, 0.0),
                        crosswind=Crosswind(5000.0, start_s=0.02, shape="step"))
        case = ds.sel(speed=v)
        assert float(case["min_levitation_gap"]) == run.min_gap_m["levitation"]
        assert float(case["min_guidance_gap"]) == run.min_gap_m["guidance"]
    # the two speeds differ (below / above the balancing speed sqrt(g R tan c) = 44.3 m/s)
    g = ds["min_guidance_gap"].values
    assert g[0] != g[1] and (g < 0.010).all() and (g > 0.002).all()


def test_bundled_example_spans_the_balancing_speed() -> None:
    assert "cross-section-curve" in bundled_sweeps()
    spec = load_sweep("cross-section-curve")
    assert isinstance(spec.job, CrossSectionJob) and spec.n_cases == 4
    r, c = spec.fixed["curve_radius"], spec.fixed["curve_superelevation"]
    v_bal = math.sqrt(9.80665 * r * math.tan(c))
    lo, hi = spec.swept["speed"]
    assert lo < v_bal < hi
    keys = {spec.case_key(case) for case in spec.cases()}
    assert len(keys) == 4
    # a straight track (infinite radius) is a valid, hashable case
    curve, wind = scenario({"curve_radius": math.inf})
    assert curve is None and wind is None


@pytest.mark.parametrize(("change", "needle"), [
    (("speed = [40.0, 120.0]", "sped = [40.0]"),
     "[parameters]: unknown key(s) ['sped']; allowed keys are: speed [m/s], curve_radius [m]"),
    (("duration = 0.1", "duratoin = 0.1"),
     "[cross_section]: unknown key(s) ['duratoin']; allowed keys are: file, duration"),
    (("curve_superelevation = 0.1", "curve_superelevation = 12.0"),
     "[cross_section] curve_superelevation: curve superelevation 687.549 deg "
     "(superelevation_rad = 12 rad): must be in"),
    (("curve_radius = 2000.0", "curve_radius = 0.5"),
     "[cross_section] curve_radius: curve radius_m = 0.5 m: expected |R| >= 1 m or inf"),
    (("curve_radius = 2000.0", 'curve_radius = "2 km"'),
     "[cross_section] curve_radius = '2 km': expected a number [m]"),
    (("speed = [40.0, 120.0]", "speed = [40.0]\ncurve_transition = [-1.0]"),
     "[parameters] curve_transition[0]: curve transition_m [m] = -1.0: must be >= 0"),
    (('crosswind_shape = "step"', 'crosswind_shape = "chinese"'),
     "[cross_section] crosswind_shape: crosswind shape = 'chinese'; allowed:"),
    (("crosswind_start = 0.02", "crosswind_rise = 0.0"),
     "[cross_section] crosswind_rise: crosswind rise_s"),
    (("speed = [40.0, 120.0]", 'speed = [40.0]\nfailure = ["guidance_left/c9@0.05"]'),
     "no circuit 'guidance_left/c9' in this vehicle"),
    (("speed = [40.0, 120.0]", 'speed = [40.0]\nfailure = ["guidance_left/front@0.5"]'),
     "failure time 0.5 s is not within the run"),
    (("speed = [40.0, 120.0]", "speed = [40.0]\nseed = [0, 1]"),
     "seed is swept but neither [cross_section] irregularity"),
    (("duration = 0.1", 'duration = 0.1\nlateral = "random:0.3e-3:4"'),
     "give random:RMS without a seed"),
    (("duration = 0.1", 'duration = 0.1\nlateral = "wavy:1"'), "[cross_section] lateral:"),
    (("duration = 0.1", 'duration = 0.1\nmagnets = "fast"'),
     "[cross_section] magnets = 'fast': use 'reduced' or 'detailed'"),
    (("duration = 0.1", 'duration = 0.1\nfile = "nope.toml"'),
     "[cross_section] file = 'nope.toml'"),
    (('job = "cross-section"', 'job = "vehicle"'),
     "a [cross_section] table belongs to job = 'cross-section'"),
    (("[parameters]", "[output]\ntime_series = [\"guidance_gap\"]\n[parameters]"),
     "[output] time_series = ['guidance_gap']: a list of distinct names from gap, current"),
    (("speed = [40.0, 120.0]", "speed = [40.0]\ncrosswind_hold = [1.0, 1.0]"),
     "repeated values"),
    # the job's own words in the checks shared with the vehicle job (sweep/spec.py)
    (("speed = [40.0, 120.0]", ""),
     "[parameters] is empty: give at least one list, e.g. speed = [55.6, 125.0] (m/s)"),
    (("curve_radius = 2000.0", "curve_radius = 2000.0\nspeed = 3.0"),
     "['speed'] given both in [cross_section] (fixed) and in [parameters] (swept)"),
    (("duration = 0.1", "duration = 0.001"),
     "[cross_section] duration = 0.001 s is less than two steps of dt = 0.001 s"),
    (("speed = [40.0, 120.0]", 'speed = [40.0]\nfailure = ["s1m1/front@0.05"]'),
     "(MAGNET_SIDE/front|rear, e.g. guidance_left/front)"),
])
def test_bad_cross_section_sweeps_name_the_key(change: tuple[str, str], needle: str,
                                               tmp_path: Path) -> None:
    assert change[0] in SWEEP
    with pytest.raises(ParameterFileError) as err:
        load_sweep(_file(tmp_path, SWEEP.replace(change[0], change[1])))
    assert needle in str(err.value), str(err.value)
    assert str(err.value).startswith(str(tmp_path / "xs.toml"))
