"""Characteristic maps of the vehicle's magnets, built once per magnet kind and cached.

The maps cover the gaps and currents a vehicle run can reach, including failure cases (a
neighbour of a failed circuit carries up to about twice its share; a closing gap reaches
the skids): gaps 2-22 mm in 1 mm steps, currents 0-100 A in 2 A steps.  They are written
to netCDF under ``<cache>/vehicle-maps/`` (``<cache>`` = ``$MAGLEVKIT_CACHE_DIR``, else
``$XDG_CACHE_HOME/maglevkit`` or ``~/.cache/maglevkit``) or a directory you give, named
by the magnet's network hash and the grid (values and shapes), and checked against the
magnet and the grid when read (a file on another grid is rebuilt).
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import real_array, renamed_keywords

__all__ = ["VEHICLE_MAP_GAPS_M", "VEHICLE_MAP_CURRENTS_A", "vehicle_maps", "maps_path"]

VEHICLE_MAP_GAPS_M = np.linspace(0.002, 0.022, 21)
"""Gap grid of the vehicle maps [m]."""
VEHICLE_MAP_CURRENTS_A = np.linspace(0.0, 100.0, 51)
"""Current grid of the vehicle maps [A]."""


def maps_path(magnet: Any, gaps: np.ndarray, currents: np.ndarray,
              cache_dir: str | Path | None = None) -> Path:
    """Where the maps of ``magnet`` on this grid are cached.

    Parameters
    ----------
    magnet : Magnet
        The magnet (its name and network hash name the file).
    gaps : ndarray
        Gap grid [m] (its values and shape are hashed).
    currents : ndarray
        Current grid [A] (its values and shape are hashed, separately from the gaps).
    cache_dir : str or Path, optional
        Directory of the cached files (default: ``<cache>/vehicle-maps``, see the module
        docstring).  Not created here.

    Returns
    -------
    Path
        ``<dir>/<magnet name>-<network hash>-<grid hash>.nc``; the grid hash also covers
        :func:`~maglevkit.reduction.maps.law_hash` (the code that builds maps).
    """
    from ..models.compiled import cache_directory
    from ..reduction.maps import law_hash, network_hash

    h = hashlib.sha256()
    # the code of the laws too: maps cached by an older maglevkit are not taken for current
    h.update(law_hash().encode())
    for label, arr in (("gaps", gaps), ("currents", currents)):
        a = np.ascontiguousarray(arr, dtype=np.float64)
        # name and shape first: [g1, g2] + [c1, c2, c3] and [g1, g2, c1] + [c2, c3] differ
        h.update(f"{label}{a.shape};".encode())
        h.update(a.tobytes())
    grid = h.hexdigest()[:10]
    base = Path(cache_dir) if cache_dir is not None else cache_directory() / "vehicle-maps"
    name = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in magnet.name)[:40]
    return base / f"{name}-{network_hash(magnet.network)[:16]}-{grid}.nc"


def _check_cache_dir(base: Path) -> None:
    """A given maps cache folder: an existing folder, or a new one in an existing folder."""
    if base.exists() and not base.is_dir():
        raise InputError(f"maps cache (cache_dir, --maps-cache) {str(base)!r} is a file, not "
                         "a folder")
    if not base.exists() and not base.parent.is_dir():
        raise InputError(f"maps cache (cache_dir, --maps-cache) {str(base)!r}: the directory "
                         f"{str(base.parent)!r} does not exist; create it first (only the last "
                         "folder is created)")


@renamed_keywords(gaps="gaps_m", currents="currents_A")
def vehicle_maps(magnet: Any, *, cache_dir: str | Path | None = None,
                 gaps_m: Any = None, currents_A: Any = None, progress: bool = False) -> Any:
    """The characteristic maps of ``magnet`` on the vehicle grid, from the cache or built.

    Old keyword names (``gaps``, ``currents``) are deprecated aliases for one release.

    Parameters
    ----------
    magnet : Magnet
        The magnet whose maps are wanted.
    cache_dir : path, optional
        Directory of the cached netCDF files (default: the user's cache, see module doc).
    gaps_m, currents_A : array_like, optional
        Grids [m], [A] (default :data:`VEHICLE_MAP_GAPS_M`, :data:`VEHICLE_MAP_CURRENTS_A`).
    progress : bool
        Show the build's progress bar.

    Returns
    -------
    CharacteristicMaps
        Read from the cache (checked against the magnet and the grid), or built and
        then written there (atomically, creating the directory).  A cached file on
        another grid (a stale file under this name) is rebuilt and replaced.
    """
    from ..reduction.maps import build_maps, load_maps

    g = VEHICLE_MAP_GAPS_M if gaps_m is None else real_array(gaps_m, "gaps", "m")
    c = VEHICLE_MAP_CURRENTS_A if currents_A is None else real_array(currents_A, "currents", "A")
    if cache_dir is not None:
        _check_cache_dir(Path(cache_dir))
    path = maps_path(magnet, g, c, cache_dir)
    if path.is_file():
        cached = load_maps(path, magnet=magnet)
        if (cached.gaps_m.shape == g.shape and cached.currents_A.shape == c.shape
                and np.array_equal(cached.gaps_m, g) and np.array_equal(cached.currents_A, c)):
            return cached
    maps = build_maps(magnet, gaps_m=g, currents_A=c, progress=progress)
    # the user's cache may be created with its parents; a folder given (cache_dir,
    # --maps-cache) only as its last level, as every other output folder
    path.parent.mkdir(parents=cache_dir is None, exist_ok=True)
    tmp = path.with_suffix(f".tmp{np.random.default_rng().integers(1 << 30)}.nc")
    maps.to_netcdf(tmp)
    tmp.replace(path)
    return maps
