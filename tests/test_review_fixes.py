"""Regression tests of the defects an independent review left open (fix2 branch)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest


def test_python_dash_m_runs_the_cli() -> None:
    """``python -m maglevkit --help`` exits 0 and names the program ``maglevkit``."""
    env = dict(os.environ)
    src = str(Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-m", "maglevkit", "--help"], env=env,
                         capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    assert "Usage: maglevkit" in out.stdout


# ---------------------------------------------------------------- CLI output paths
from typer.testing import CliRunner  # noqa: E402

from maglevkit.cli import app  # noqa: E402

runner = CliRunner()


def test_output_may_not_be_the_input_even_with_force(tmp_path: Path) -> None:
    """``design spec.toml -o spec.toml --force`` refuses (before reading), input unchanged."""
    spec = tmp_path / "spec.toml"
    spec.write_text("# a design spec\n")
    res = runner.invoke(app, ["design", str(spec), "-o", str(spec), "--force"])
    assert res.exit_code == 2
    assert "input file" in res.output and "--output" in res.output
    assert spec.read_text() == "# a design spec\n"
    # the same file through another spelling of the path
    other = tmp_path / "sub" / ".." / "spec.toml"
    (tmp_path / "sub").mkdir()
    res = runner.invoke(app, ["statics", str(spec), "--csv", str(other), "--force"])
    assert res.exit_code == 2 and "input file" in res.output


def test_plot_folder_is_not_created_by_a_failed_run(tmp_path: Path) -> None:
    """``--plot DIR`` is checked before the run but created only when figures are written."""
    folder = tmp_path / "figs"
    res = runner.invoke(app, ["vehicle", "run", "tr09", "--duration", "0.001", "--dt", "0.001",
                              "--plot", str(folder)])
    assert res.exit_code == 2 and "--duration" in res.output
    assert not folder.exists()
    # a file in its place is still refused before the run
    folder.write_text("x")
    res = runner.invoke(app, ["vehicle", "run", "tr09", "--plot", str(folder)])
    assert res.exit_code == 2 and "not a folder" in res.output


# ---------------------------------------------------------------- design_sensitivities
def test_design_sensitivities_warns_on_gap_in_mm() -> None:
    """``gap_m=10`` (mm typed as m) warns as solve_statics does; a negative gap is refused."""
    from maglevkit.design import design_sensitivities, read_design_spec
    from maglevkit.errors import InputError, PlausibilityWarning
    from tests.test_design import example_doc

    spec = read_design_spec(example_doc())
    values = {"pole_width": 0.027, "coil_height": 0.045, "coil_thickness": 0.014,
              "leg_height": 0.068}
    with pytest.warns(PlausibilityWarning, match="design_sensitivities: gap 10 m"):
        design_sensitivities(spec, values, gap_m=10, current_A=14.0)
    with pytest.raises(InputError, match="gap_m"):
        design_sensitivities(spec, values, gap_m=-0.008, current_A=14.0)


# ---------------------------------------------------------------- run options
def test_speed_in_kmh_typed_as_m_per_s_warns() -> None:
    """400 m/s (1440 km/h, above the 160 m/s = 576 km/h bound) warns naming km/h; 111 m/s
    (400 km/h) and 0 do not.  The check is the one both run methods call."""
    import warnings

    from maglevkit.errors import PlausibilityWarning
    from maglevkit.vehicle.simulation import check_run_speed

    with pytest.warns(PlausibilityWarning, match=r"speed_m_per_s = 400(\.0)? m/s.*km/h"):
        check_run_speed(400.0, "VehicleModel.run")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_run_speed(400 / 3.6, "VehicleModel.run")
        check_run_speed(0.0, "VehicleModel.run")


def test_run_methods_warn_on_speed_before_running() -> None:
    """Both ``run`` methods call the speed check before any work: with warnings as errors
    the warning itself stops them (no simulation is started)."""
    import warnings

    from maglevkit.errors import PlausibilityWarning
    from maglevkit.vehicle import crossrun, simulation

    for cls in (simulation.VehicleModel, crossrun.CrossSectionModel):
        obj = cls.__new__(cls)   # the check comes first: no model needs to be built
        with warnings.catch_warnings():
            warnings.simplefilter("error", PlausibilityWarning)
            with pytest.raises(PlausibilityWarning, match="speed_m_per_s = 400"):
                obj.run(speed_m_per_s=400.0, duration_s=0.01, dt_s=1e-3)


def test_irregularity_amplitude_in_mm_warns_naming_the_option() -> None:
    """``random:0.3`` (0.3 mm typed as metres) warns naming --irregularity; 0.3e-3 does not."""
    import warnings

    from maglevkit.errors import PlausibilityWarning
    from maglevkit.vehicle.simulation import parse_irregularity

    with pytest.warns(PlausibilityWarning, match=r"--irregularity.*random = 0.3 m"):
        parse_irregularity("random:0.3", span_length_m=24.8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parse_irregularity("sag:0.5e-3+random:0.3e-3:7+joints:1e-4", span_length_m=24.8)


def test_irregularity_closing_the_gap_is_refused_naming_the_option() -> None:
    """``--irregularity random:0.3`` on the train: one warning naming the option, then a
    clear error naming the irregularity (not a circuit's "gaps must be > 0")."""
    import warnings

    from maglevkit.errors import PlausibilityWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = runner.invoke(app, ["vehicle", "run", "tr09", "--duration", "0.004",
                                  "--irregularity", "random:0.3", "--no-progress"])
    assert res.exit_code == 2
    named = [w for w in caught if issubclass(w.category, PlausibilityWarning)
             and "(--irregularity): [irregularity] random = 0.3 m" in str(w.message)]
    assert len(named) == 1
    assert "irregularity: the guideway profile closes the gap at t = 0" in res.output
    assert "circuit" not in res.output


# ---------------------------------------------------------------- BeamSpan = the guideway file
def test_beamspan_precamber_checked_as_the_file() -> None:
    """A negative precamber is refused (the file's ``nonnegative``), 2.7 (mm as m) warns
    (the file's plausible range 0.1 mm ... 50 mm); 2.7e-3 and 0 pass silently."""
    import warnings

    from maglevkit.errors import ParameterError, PlausibilityWarning
    from maglevkit.vehicle.guideway import BeamSpan

    with pytest.raises(ParameterError, match="precamber_m"):
        BeamSpan(24.768, 4e10, 7500.0, precamber_m=-2.7e-3)
    with pytest.warns(PlausibilityWarning, match=r"precamber_m = 2.7 m.*typed in mm"):
        BeamSpan(24.768, 4e10, 7500.0, precamber_m=2.7)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        BeamSpan(24.768, 4e10, 7500.0, precamber_m=2.7e-3)
        BeamSpan(24.768, 4e10, 7500.0)


# ---------------------------------------------------------------- crosswind step
def test_crosswind_step_with_ignored_rise_hold_warns_naming_the_option() -> None:
    """``5000:0.5:1:step``: RISE/HOLD without START do nothing for a step -> a warning naming
    --crosswind; ``5000:0.5:3:0.2:step`` (a hold for a step) too; the documented
    ``5000:0.5:0:0.2:step`` and ``5000:step`` are silent and keep their meaning."""
    import warnings

    from maglevkit.errors import MaglevkitWarning
    from maglevkit.vehicle.crossrun import parse_crosswind

    with pytest.warns(MaglevkitWarning, match=r"--crosswind = '5000:0.5:1:step'.*RISE_S and "
                                              r"HOLD_S 0.5:1 s are ignored"):
        cw = parse_crosswind("5000:0.5:1:step")
    assert cw.shape == "step" and cw.start_s == 0.5      # the default start, unchanged
    with pytest.warns(MaglevkitWarning, match=r"HOLD_S = 3 s is ignored"):
        parse_crosswind("5000:0.5:3:0.2:step")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert parse_crosswind("5000:0.5:0:0.2:step").start_s == 0.2
        assert parse_crosswind("5000:step").peak_force_N == 5000.0
        parse_crosswind("8000:0.5:1:0.5")


# ---------------------------------------------------------------- cross-section dt
def _bare_cross_section_model():  # type: ignore[no-untyped-def]
    """A CrossSectionModel shell (the checks below run before any model data is used)."""
    from maglevkit.vehicle.crossrun import CrossSectionModel

    obj = CrossSectionModel.__new__(CrossSectionModel)
    obj.flux_bandwidth_Hz = 30.0
    obj._compiled_cache = {}
    return obj


def test_coarse_dt_warns_with_the_flux_loop_reasoning() -> None:
    """dt = 50 ms (the review's --dt 0.05, touched down at 0.3 s) warns before the run;
    the bound is 0.06 / 30 Hz = 2 ms, where the hold's lag pi f dt is 0.06 pi = 10.8 deg;
    at 50 ms it is pi * 30 * 0.05 = 270 deg (closed form)."""
    import warnings

    from maglevkit.errors import MaglevkitWarning

    obj = _bare_cross_section_model()
    with warnings.catch_warnings():
        warnings.simplefilter("error", MaglevkitWarning)
        with pytest.raises(MaglevkitWarning, match=r"dt_s = 0.05 s is coarse for the 30 Hz "
                                                   r"flux loop.*270 deg.*dt_s <= 0.002 s"):
            obj.run(speed_m_per_s=100.0, duration_s=1.0, dt_s=0.05)
        # 2 ms itself passes the check (then fails later on the shell: no model data)
        with pytest.raises(AttributeError):
            obj.run(speed_m_per_s=100.0, duration_s=1.0, dt_s=0.002)


def test_compile_note_once_per_dt(capsys: pytest.CaptureFixture[str]) -> None:
    """The note names dt and is written only while that dt is not compiled yet."""
    obj = _bare_cross_section_model()
    obj._note_compiling(0.002)
    err = capsys.readouterr().err
    assert err.startswith("compiling the cross-section step for dt = 0.002 s (once per dt")
    assert err.count("\n") == 1
    obj._compiled_cache[0.002] = {}
    obj._note_compiling(0.002)
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------- touchdown within a step
def test_limit_crossing_on_the_linear_path() -> None:
    """Closed form: gap 2.299 mm closing at 0.63 m/s over dt = 1 ms ends at 1.669 mm (the
    review's numbers); it crosses 2 mm at (2.299 - 2) / 630 s = 0.4746 ms, reported there
    with the gap 2 mm (not the extrapolated 1.669 mm below every recorded gap)."""
    from maglevkit.vehicle.simulation import limit_crossing

    gaps = np.array([10e-3, 2.299e-3, 9e-3])
    rates = np.array([0.0, -0.63, 1.0])
    hit = limit_crossing(gaps, rates, dt_s=1e-3, start_s=0.3, touchdown_gap_m=2e-3,
                         landing_gap_m=20e-3)
    assert hit is not None
    j, when, gap, closed = hit
    assert (j, closed) == (1, True)
    assert when == pytest.approx(0.3 + 0.299e-3 / 0.63, abs=1e-15)
    assert gap == 2e-3
    # the first of two crossings wins (the opening one here: 19.9 mm at +1 m/s, 0.1 ms)
    hit = limit_crossing(np.array([2.299e-3, 19.9e-3]), np.array([-0.63, 1.0]), dt_s=1e-3,
                         start_s=0.0, touchdown_gap_m=2e-3, landing_gap_m=20e-3)
    assert hit is not None and hit[0] == 1 and not hit[3]
    assert hit[1] == pytest.approx(1e-4, abs=1e-15) and hit[2] == 20e-3
    # no gap ends the step beyond a limit: None
    assert limit_crossing(gaps, np.zeros(3), dt_s=1e-3, start_s=0.0, touchdown_gap_m=2e-3,
                          landing_gap_m=20e-3) is None
