"""Writing result files so that an interrupted or failed write leaves no damaged file."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["write_netcdf_atomically"]


def write_netcdf_atomically(dataset: Any, path: str | Path, **to_netcdf: Any) -> Path:
    """Write ``dataset`` (xarray) to ``path`` as netCDF-4 through a temporary file in the
    same folder, renamed over ``path`` when complete (``os.replace``): a Ctrl-C or an error
    during the write leaves ``path`` as it was (and no temporary file).  Keyword arguments
    go to ``Dataset.to_netcdf``."""
    p = Path(path)
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        dataset.to_netcdf(tmp, engine="netcdf4", **to_netcdf)
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
    return p
