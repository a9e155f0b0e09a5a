"""Record the reference vehicle run that ``tests/test_vehicle_reference.py`` compares
against (the outputs of the implementation before the whole-run speed-up, commit a47fa63).

Run from a checkout of that commit (or any later one whose results must not change)::

    PYTHONPATH=src python tools/record_vehicle_reference.py tests/data/vehicle_run_reference.nc

The run: the bundled 3-section train at 400 km/h for 0.3 s on the elastic guideway with
the bundled irregularity ``sag:0.5e-3+random:0.3e-3:1`` and circuit ``s2m4/front`` off
from 0.1 s (compiled step).  Every 10th time step is stored (every variable in full
precision, compressed: ~120 kB instead of ~640 kB for all steps).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import maglevkit
from maglevkit.vehicle.simulation import Failure, VehicleModel, parse_irregularity
from maglevkit.vehicle.train import load_vehicle

SPEC = "sag:0.5e-3+random:0.3e-3:1"
SPEED_M_PER_S = 400 / 3.6
DURATION_S = 0.3
FAILURES = (Failure("s2m4/front", 0.1),)
EVERY = 10


def main(path: str) -> None:
    model = VehicleModel(load_vehicle())
    prof = parse_irregularity(SPEC, span_length_m=model.guideway.span.length_m)
    res = model.run(speed_m_per_s=SPEED_M_PER_S, duration_s=DURATION_S, irregularity=prof,
                    failures=FAILURES, loop="compiled")
    ds = res.dataset.isel(time=slice(None, None, EVERY))
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, check=True, cwd=Path(maglevkit.__file__).parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    # the run's summaries (from every step, not only the stored ones), as JSON
    ds.attrs["comfort"] = json.dumps(res.comfort)
    ds.attrs["min_gap_m"] = json.dumps(res.min_gap_m)
    ds.attrs["peak_current_A"] = json.dumps(res.peak_current_A)
    ds.attrs["recorded_by"] = f"tools/record_vehicle_reference.py at commit {commit}"
    enc = {v: {"zlib": True, "complevel": 9} for v in ds.data_vars}
    ds.to_netcdf(path, engine="netcdf4", encoding=enc)


if __name__ == "__main__":
    main(sys.argv[1])
