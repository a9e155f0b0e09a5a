"""The pieces the heave-pitch and cross-section runs share: the report's touchdown line
and the atomic netCDF write (``vehicle.simulation``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from maglevkit.errors import InputError
from maglevkit.vehicle.simulation import touchdown_report_line, write_run_netcdf


def _dataset() -> xr.Dataset:
    return xr.Dataset({"gap": ("time", np.array([0.01, 0.0099]))},
                      coords={"time": [0.0, 0.001]},
                      attrs={"touchdown_gap_m": 0.002, "landing_gap_m": 0.020})


def test_touchdown_line_words() -> None:
    ds = _dataset()
    assert touchdown_report_line(ds, None) == "  no touchdown (gaps stayed within 2 ... 20 mm)"
    td = ("s1m1/c1", 0.012345, 0.0021, "closed")
    # the kind itself by default (the cross-section run's report)
    assert touchdown_report_line(ds, td) == ("  TOUCHDOWN (closed): circuit s1m1/c1 at "
                                             "t = 0.0123 s (gap 2.100 mm); the run stopped "
                                             "there")
    # the heave-pitch run's words
    line = touchdown_report_line(ds, (*td[:3], "landed"),
                                 what={"landed": "frame down on its skids"})
    assert line.startswith("  TOUCHDOWN (frame down on its skids): circuit s1m1/c1")


def test_netcdf_round_trip_and_missing_folder(tmp_path: Path) -> None:
    ds = _dataset()
    p = write_run_netcdf(ds, tmp_path / "run.nc")
    assert xr.load_dataset(p).identical(ds)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["run.nc"]   # no temporary left
    with pytest.raises(InputError, match="does not exist"):
        write_run_netcdf(ds, tmp_path / "typo" / "run.nc")
