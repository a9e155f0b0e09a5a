"""Reading netCDF files whole, and writing result files so that an interrupted or failed
write leaves no damaged file."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["read_netcdf", "write_netcdf_atomically"]


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


def read_netcdf(path: str | Path) -> Any:
    """An xarray Dataset read from the netCDF file ``path`` completely into memory (the file
    is closed again).

    Raises
    ------
    ParameterFileError
        The file cannot be read as netCDF (``"<path>: not a readable netCDF file: ..."``).
    """
    import xarray as xr

    from .errors import ParameterFileError

    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds.load()
    except (OSError, ValueError) as exc:
        raise ParameterFileError(f"{path}: not a readable netCDF file: {exc}") from None
    return ds
