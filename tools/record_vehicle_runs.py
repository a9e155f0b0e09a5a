"""Record short runs of both vehicles before the vehicle framework rebuild (issue 23 item 1),
which ``tests/test_vehicle_recorded_runs.py`` reproduces to 1e-10 of each variable's
largest value.

Run from a checkout whose results must not change::

    PYTHONPATH=src python tools/record_vehicle_runs.py tests/data/vehicle_runs.npz [NAME ...] \
        [--rebuild-maps]

(with names: only those scenarios re-recorded, the others kept).  The runs are made on the
maps stored in ``tests/data/vehicle_run_maps`` (``--rebuild-maps``: built afresh, then
stored), so that they reproduce on any processor (:func:`maps_cache`).

Scenarios (``SCENARIOS``; the test runs the same functions): the heave-pitch train on a
rigid and on the elastic guideway with the bundled irregularity, the cascade in the
compiled and in the NumPy loop, a failed circuit, the offset-free NMPC, detailed
(per-pole) magnets for a few steps; the cross-section slice with a curve entry, a gust
and a failed guidance circuit.  Every ``every``-th time step of every variable is stored
(float64, compressed) with the run's summaries (minimum gaps, peak currents, comfort) as
JSON; the whole file stays well below 1 MB.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

KMH = 1 / 3.6


#: The characteristic maps the runs were recorded on, one netCDF file per magnet, named
#: ``<magnet name>-<network hash>.nc`` (the vehicle cache's name without its grid hash).
MAPS_DIR = Path(__file__).resolve().parents[1] / "tests" / "data" / "vehicle_run_maps"
_MAPS_CACHE: list[Path] = []


def maps_cache() -> Path:
    """A temporary vehicle-maps cache holding the recorded maps under this code's names.

    The runs are recorded and reproduced on the same maps: maps built on another processor
    agree with these only to about their solvers' tolerances (Newton solves and IDAS runs
    on linear algebra whose last bits depend on the processor's kernels; measured: the runs
    moved by up to 4.2e-6 of a variable's largest value between an AMD EPYC and an Intel
    Xeon with AVX-512), while the framework's own arithmetic is not sensitive (1e-13
    changes stay 1e-13).  A magnet whose network changed finds no
    stored file: its maps are built into this folder (and the runs must be re-recorded).
    """
    if not _MAPS_CACHE:
        import atexit
        import shutil
        import tempfile
        from types import SimpleNamespace

        from maglevkit.vehicle.mapcache import VEHICLE_MAP_CURRENTS_A, VEHICLE_MAP_GAPS_M, maps_path

        tmp = Path(tempfile.mkdtemp(prefix="maglevkit-recorded-maps-"))
        atexit.register(shutil.rmtree, tmp, True)
        # the grid hash of this code (it covers the law hash): the same for every magnet
        probe = SimpleNamespace(name="x", network=SimpleNamespace(branches=(), circuits=()))
        grid = maps_path(probe, VEHICLE_MAP_GAPS_M, VEHICLE_MAP_CURRENTS_A, tmp).stem
        grid = grid.rsplit("-", 1)[1]
        for f in sorted(MAPS_DIR.glob("*.nc")):
            shutil.copyfile(f, tmp / f"{f.stem}-{grid}.nc")
        _MAPS_CACHE.append(tmp)
    return _MAPS_CACHE[0]


def built_maps() -> list[str]:
    """Maps files of :func:`maps_cache` that were built in this process, not copied from
    :data:`MAPS_DIR` (a magnet whose network changed since the recording)."""
    if not _MAPS_CACHE:
        return []
    stored = {f.stem for f in MAPS_DIR.glob("*.nc")}
    return sorted(f.name for f in _MAPS_CACHE[0].glob("*.nc")
                  if f.stem.rsplit("-", 1)[0] not in stored)


def store_maps() -> None:
    """Keep the maps of this recording in :data:`MAPS_DIR` (added or replaced by name).

    Nothing is deleted: ``tools/record_vehicle_reference.py`` stores its own magnets' maps
    there too.  A file left by a magnet whose network has since changed is unused (its
    network hash is in its name); delete it by hand when re-recording.
    """
    import shutil

    MAPS_DIR.mkdir(parents=True, exist_ok=True)
    for f in sorted(maps_cache().glob("*.nc")):
        shutil.copyfile(f, MAPS_DIR / f"{f.stem.rsplit('-', 1)[0]}.nc")


def _train(**kw: Any) -> Any:
    from maglevkit.vehicle.simulation import VehicleModel

    return VehicleModel(_TRAIN(), maps_cache=maps_cache(), **kw)


def _TRAIN() -> Any:
    from maglevkit.vehicle.train import load_vehicle

    return load_vehicle()


def _irregularity(model: Any) -> Any:
    from maglevkit.vehicle.simulation import parse_irregularity

    return parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                              span_length_m=model.guideway.span.length_m)


_MODELS: dict[str, Any] = {}


def _cached(key: str, make: Callable[[], Any]) -> Any:
    if key not in _MODELS:
        _MODELS[key] = make()
    return _MODELS[key]


def hp_rigid_compiled() -> Any:
    m = _cached("rigid", lambda: _train(rigid=True))
    return m.run(speed_m_per_s=400 * KMH, duration_s=0.3, irregularity=_irregularity(m),
                 loop="compiled")


def _elastic(loop: str) -> Any:
    from maglevkit.vehicle.simulation import Failure

    m = _cached("elastic", lambda: _train())
    return m.run(speed_m_per_s=400 * KMH, duration_s=0.3, irregularity=_irregularity(m),
                 failures=[Failure("s2m4/front", 0.1)], loop=loop)


def hp_elastic_compiled() -> Any:
    return _elastic("compiled")


def hp_elastic_python() -> Any:
    return _elastic("python")


def hp_payload_python() -> Any:
    m = _cached("elastic", lambda: _train())
    return m.run(speed_m_per_s=300 * KMH, duration_s=0.2, payload_step_s=0.05, loop="python")


def hp_mpc() -> Any:
    m = _cached("mpc", lambda: _train(controller="mpc"))
    return m.run(speed_m_per_s=400 * KMH, duration_s=0.04, irregularity=_irregularity(m))


def hp_detailed() -> Any:
    m = _cached("detailed", lambda: _train(magnets="detailed", rigid=True))
    return m.run(speed_m_per_s=400 * KMH, duration_s=0.006, irregularity=_irregularity(m))


def _cross() -> Any:
    from maglevkit.vehicle.crossrun import CrossSectionModel

    return _cached("cross", lambda: CrossSectionModel(maps_cache=maps_cache()))


def cs_curve(loop: str = "compiled") -> Any:
    from maglevkit.vehicle.crossrun import TransitionCurve

    return _cross().run(speed_m_per_s=400 * KMH, duration_s=0.8, loop=loop,
                        curve=TransitionCurve(4000.0, math.radians(12.0), 50.0))


def cs_gust_python() -> Any:
    from maglevkit.vehicle.crossrun import Crosswind
    from maglevkit.vehicle.irregularities import HarmonicProfile

    return _cross().run(speed_m_per_s=400 * KMH, duration_s=0.8, loop="python",
                        crosswind=Crosswind(5e3, rise_s=0.2, hold_s=0.1, start_s=0.2),
                        lateral=HarmonicProfile(0.2e-3, 100.0))


def cs_gust_compiled() -> Any:
    from maglevkit.vehicle.crossrun import Crosswind
    from maglevkit.vehicle.irregularities import HarmonicProfile

    return _cross().run(speed_m_per_s=400 * KMH, duration_s=0.8, loop="compiled",
                        crosswind=Crosswind(5e3, rise_s=0.2, hold_s=0.1, start_s=0.2),
                        lateral=HarmonicProfile(0.2e-3, 100.0))


def cs_failure() -> Any:
    from maglevkit.vehicle.simulation import Failure

    return _cross().run(speed_m_per_s=400 * KMH, duration_s=0.8, loop="compiled",
                        failures=[Failure("guidance_left/front", 0.2),
                                  Failure("levitation_right/rear", 0.4)])


def cs_failure_python() -> Any:
    from maglevkit.vehicle.simulation import Failure

    return _cross().run(speed_m_per_s=400 * KMH, duration_s=0.8, loop="python",
                        failures=[Failure("guidance_left/front", 0.2),
                                  Failure("levitation_right/rear", 0.4)])


#: name -> (run function, every how many steps a row is stored)
SCENARIOS: dict[str, tuple[Callable[[], Any], int]] = {
    "hp_rigid_compiled": (hp_rigid_compiled, 20),
    "hp_elastic_compiled": (hp_elastic_compiled, 20),
    "hp_elastic_python": (hp_elastic_python, 20),
    "hp_payload_python": (hp_payload_python, 20),
    "hp_mpc": (hp_mpc, 4),
    "hp_detailed": (hp_detailed, 1),
    "cs_curve_compiled": (cs_curve, 40),
    "cs_curve_python": (lambda: cs_curve("python"), 40),
    "cs_gust_compiled": (cs_gust_compiled, 40),
    "cs_gust_python": (cs_gust_python, 40),
    "cs_failure_compiled": (cs_failure, 40),
    "cs_failure_python": (cs_failure_python, 40),
}


def summaries(run: Any) -> dict[str, Any]:
    """The run's summaries over every step (not only the stored rows)."""
    out: dict[str, Any] = {"min_gap_m": run.min_gap_m, "touchdown": run.touchdown}
    for key in ("peak_current_A", "comfort"):
        if hasattr(run, key):
            out[key] = getattr(run, key)
    return out


def arrays(run: Any, every: int) -> dict[str, np.ndarray]:
    """Every ``every``-th row of every numeric variable of the run's dataset, and the time."""
    ds = run.dataset.isel(time=slice(None, None, every))
    out = {"time": np.asarray(ds.time.values, dtype=float)}
    for name in ds.data_vars:
        val = np.asarray(ds[name].values)
        if val.dtype.kind in "fiu":
            out[str(name)] = val.astype(float)
    return out


def main(path: str, only: list[str], rebuild_maps: bool = False) -> None:
    """Record every scenario (``only`` empty) or re-record the named ones into ``path``.

    The runs use the stored maps (:func:`maps_cache`); ``rebuild_maps`` (``--rebuild-maps``)
    builds the runs' maps afresh (the stored files are not read).  The maps used are stored
    with the runs (:func:`store_maps`).
    """
    if rebuild_maps:
        for f in maps_cache().glob("*.nc"):
            f.unlink()
    data: dict[str, np.ndarray] = {}
    meta: dict[str, Any] = {}
    if only:
        with np.load(Path(path)) as old:
            data = {k: old[k] for k in old.files if k != "meta" and k.split("/")[0] not in only}
            meta = json.loads(str(old["meta"]))
    for name, (fun, every) in SCENARIOS.items():
        if only and name not in only:
            continue
        run = fun()
        for key, val in arrays(run, every).items():
            data[f"{name}/{key}"] = val
        meta[name] = summaries(run)
        print(name, "done", file=sys.stderr)
    commit = os.environ.get("RECORD_COMMIT", "")   # the code's commit, when run from a copy
    try:
        commit = commit or subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    meta["recorded_by" if not only else f"recorded_by ({', '.join(only)})"] = \
        f"tools/record_vehicle_runs.py at commit {commit}"
    data["meta"] = np.array(json.dumps(meta))
    np.savez_compressed(Path(path), **data)
    store_maps()


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--rebuild-maps"]
    main(args[0], args[1:], rebuild_maps="--rebuild-maps" in sys.argv[1:])
