"""Regression tests of the defects an independent review left open (fix2 branch)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


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
    import pytest

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
