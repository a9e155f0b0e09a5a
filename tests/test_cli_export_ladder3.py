"""``maglevkit export fmu --motion-eddy --eddy-branches 2``: the three-state ladder in the
FMU from the command line (the API's ``export_fmu(..., eddy_branches=2)``, tested against
the bank in tests/test_bank_ladder3.py).

The command's FMU is compared with the API's by GUID, a hash of the FMU's content (model
description, generated C, start values): equal GUIDs mean the same FMU, and the GUID of
the two-state ladder's FMU differs, so the option is not dropped on the way.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app

pytest.importorskip("fmpy")
from fmpy import read_model_description  # noqa: E402

from maglevkit.export import export_fmu  # noqa: E402

GAPS = np.linspace(0.006, 0.014, 5)
CURRENTS = np.linspace(0.0, 40.0, 9)
runner = CliRunner()


@pytest.fixture(scope="module")
def u_maps() -> mk.CharacteristicMaps:
    return mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=GAPS, currents_A=CURRENTS,
                         progress=False)


@pytest.fixture(scope="module")
def maps_file(u_maps: mk.CharacteristicMaps, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return u_maps.to_netcdf(tmp_path_factory.mktemp("maps") / "u.nc")


def _cli(maps_file: Path, target: Path, *extra: str) -> Any:
    return runner.invoke(app, ["export", "fmu", "u-magnet", str(maps_file), "-o", str(target),
                               "--gap", "0.010", "--current", "20", *extra])


def _one_line_error(res: Any, needle: str) -> None:
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.output
    assert needle in lines[0], res.output


def test_cli_writes_the_three_state_fmu_of_the_api(u_maps: mk.CharacteristicMaps,
                                                   maps_file: Path, tmp_path: Path) -> None:
    target = tmp_path / "ladder3.fmu"
    res = _cli(maps_file, target, "--motion-eddy", "--eddy-branches", "2")
    assert res.exit_code == 0, res.output
    api = export_fmu(u_maps, tmp_path / "api3.fmu", start_gaps_m=0.010,
                     initial_currents_A=20.0, motion_eddy=True, eddy_branches=2)
    two = export_fmu(u_maps, tmp_path / "api2.fmu", start_gaps_m=0.010,
                     initial_currents_A=20.0, motion_eddy=True)
    guid = read_model_description(str(target)).guid
    assert guid == api.guid
    assert guid != two.guid
    # the default stays the two-state ladder
    res = _cli(maps_file, tmp_path / "ladder2.fmu", "--motion-eddy")
    assert res.exit_code == 0, res.output
    assert read_model_description(str(tmp_path / "ladder2.fmu")).guid == two.guid


def test_cli_eddy_branches_errors_exit_2(u_maps: mk.CharacteristicMaps, maps_file: Path,
                                        tmp_path: Path) -> None:
    target = tmp_path / "m.fmu"
    _one_line_error(_cli(maps_file, target, "--motion-eddy", "--eddy-branches", "3"),
                    "--eddy-branches 3: allowed are 1")
    _one_line_error(_cli(maps_file, target, "--eddy-branches", "2"),
                    "--eddy-branches 2 needs --motion-eddy")
    # maps built before the three-state ladder (no motion_eddy3_* variables)
    old = mk.CharacteristicMaps(u_maps.dataset.drop_vars(
        [v for v in u_maps.dataset.data_vars if str(v).startswith("motion_eddy3_")]))
    old_file = old.to_netcdf(tmp_path / "old.nc")
    _one_line_error(_cli(old_file, target, "--motion-eddy", "--eddy-branches", "2"),
                    "no three-state ladder")
    assert not target.exists()
