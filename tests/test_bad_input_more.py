"""Bad input (issue 10) found in review: CurrentModel, maps, CLI warnings, vehicle CLI."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError, OutOfRangeError


@pytest.fixture(scope="module")
def model(u_magnet: mk.Magnet) -> mk.CurrentModel:
    maps = mk.build_maps(u_magnet, gaps_m=np.linspace(0.008, 0.012, 5),
                         currents_A=np.linspace(0.0, 40.0, 9), progress=False)
    return mk.CurrentModel(maps)


def test_far_outside_the_maps_is_out_of_range_not_a_solver_error(model) -> None:
    state = model.initial_state(gaps_m=0.010, currents_A=20.0)
    # 20 mm on 8-12 mm maps: refused before integrating (the spline would be evaluated
    # far beyond its extension and the state would become non-finite)
    with pytest.raises(OutOfRangeError, match=r"over the step t = 0\.\.0\.001 s: substitute gap "
                                              r"0\.02 m.*0\.008\.\.0\.012"):
        model.step(state, 1e-3, 20.0, gaps_m=0.02)
    with pytest.raises(OutOfRangeError, match=r"over the step.*gap 1\.01 m"):
        model.step(state, 1e-3, 20.0, gap_rates_m_per_s=1e3)


def test_a_path_instead_of_maps_is_an_input_error() -> None:
    with pytest.raises(InputError, match=r"needs CharacteristicMaps.*load_maps"):
        mk.CurrentModel("maps.nc")
    with pytest.raises(InputError, match=r"needs CharacteristicMaps.*got NoneType"):
        mk.CurrentModel(None)


def test_bools_and_strings_are_refused_by_the_current_model(model) -> None:
    state = model.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(InputError, match="voltages.*bool"):
        model.step(state, 1e-3, True)
    with pytest.raises(InputError, match="voltages.*string"):
        model.step(state, 1e-3, "1")
    with pytest.raises(InputError, match="initial_currents.*bool"):
        model.simulate((0.0, 0.01), dt_s=1e-3, gaps_m=0.01, voltages_V=20.0, initial_currents_A=True)


def test_maps_entry_points_refuse_wrong_types() -> None:
    with pytest.raises(InputError, match="load_maps needs the path.*NoneType"):
        mk.load_maps(None)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="wraps an xarray.Dataset"):
        mk.CharacteristicMaps("x")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="gap grid.*string"):
        mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=["0.01"] * 4, currents_A=[0, 1, 2, 3])
    with pytest.raises(InputError, match="current grid.*bool"):
        mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=[0.01, 0.02, 0.03, 0.04],
                      currents_A=[True, 1, 2, 3])


def test_cli_prints_warnings_as_one_line(tmp_path) -> None:
    """A plausibility warning on the CLI is one 'warning: ...' line on stderr."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", "from maglevkit.cli import main; main()",
                          "statics", "u-magnet", "--gaps", "10", "--currents", "20"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=300)
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    warn = [ln for ln in lines if ln.startswith("warning: ")]
    assert warn and "gap" in warn[0]
    assert not any("warnings.warn" in ln or ".py:" in ln for ln in lines)


def test_vehicle_cli_refuses_a_missing_output_folder_before_running(tmp_path) -> None:
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", "from maglevkit.cli import main; main()",
                          "vehicle", "run", "--speed-kmh", "100", "--duration", "0.01",
                          "-o", str(tmp_path / "missing" / "x.nc")],
                         capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert out.returncode == 2
    assert out.stderr.strip().startswith("error: -o") and "does not exist" in out.stderr
    assert "setting up" not in out.stderr            # refused before any work
    assert not (tmp_path / "missing").exists()
    bad = subprocess.run([sys.executable, "-c", "from maglevkit.cli import main; main()",
                          "vehicle", "run", "--speed-kmh", "-5", "--duration", "0.01"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert bad.returncode == 2 and bad.stderr.startswith("error: --speed-kmh -5")
    assert "[bold" not in bad.stderr                  # no raw markup
