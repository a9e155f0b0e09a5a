"""Record the reference vehicle run that ``tests/test_vehicle_reference.py`` compares against.

The run (:func:`reference_run`; the test runs the same function): the bundled 3-section
train with its TR09 magnets on the lumped ``"paper"`` network, the realism changes of issue
23 item 4 switched off (no precamber, no velocity blend in the damping input, no freewheel
diodes), at 400 km/h for 0.3 s on the elastic guideway with the bundled irregularity
``sag:0.5e-3+random:0.3e-3:1`` and circuit ``s2m4/front`` off from 0.1 s (compiled step),
on the stored maps of ``tests/data/vehicle_run_maps`` (see
``record_vehicle_runs.maps_cache``).  Every 10th time step is stored (every variable in
full precision, compressed)::

    PYTHONPATH=src python tools/record_vehicle_reference.py tests/data/vehicle_run_reference.nc

History: first recorded at commit a47fa63 (the implementation before the whole-run
speed-up, which reproduced it to 1e-10); re-recorded on 2026-12-03 on stored maps, because
maps built on another processor differ at the integrator's tolerance (docs/decisions.md).
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SPEC = "sag:0.5e-3+random:0.3e-3:1"
SPEED_M_PER_S = 400 / 3.6
DURATION_S = 0.3
EVERY = 10


# the runs' recorder beside this file (its maps cache and store); the same module object
# as the tests' when they loaded it first (registered under its file name)
sys.path.insert(0, str(ROOT / "tools"))
import record_vehicle_runs as RUNS  # noqa: E402


def reference_run(work_dir: str | Path) -> Any:
    """The reference run (``work_dir``: where the ``"paper"`` vehicle file is written)."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from tests.conftest import paper_tr09_vehicle

    from maglevkit.vehicle.data import load_guideway
    from maglevkit.vehicle.simulation import Failure, VehicleModel, parse_irregularity
    from maglevkit.vehicle.train import load_vehicle

    train = dataclasses.replace(load_vehicle(paper_tr09_vehicle(work_dir)),
                                control_velocity_blend=0.0)
    data = load_guideway()
    data = dataclasses.replace(data, span=dataclasses.replace(data.span, precamber_m=0.0))
    n_spans = data.guideway(n_spans=1).spans_needed(train.length_m)
    model = VehicleModel(train, guideway=data.guideway(n_spans=n_spans), freewheel=False,
                         maps_cache=RUNS.maps_cache())
    prof = parse_irregularity(SPEC, span_length_m=model.guideway.span.length_m)
    return model.run(speed_m_per_s=SPEED_M_PER_S, duration_s=DURATION_S, irregularity=prof,
                     failures=[Failure("s2m4/front", 0.1)], loop="compiled")


def main(path: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        res = reference_run(tmp)
    ds = res.dataset.isel(time=slice(None, None, EVERY))
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, check=True, cwd=ROOT).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    # the run's summaries (from every step, not only the stored ones), as JSON
    ds.attrs["comfort"] = json.dumps(res.comfort)
    ds.attrs["min_gap_m"] = json.dumps(res.min_gap_m)
    ds.attrs["peak_current_A"] = json.dumps(res.peak_current_A)
    ds.attrs["recorded_by"] = f"tools/record_vehicle_reference.py at commit {commit}"
    enc = {v: {"zlib": True, "complevel": 9} for v in ds.data_vars}
    ds.to_netcdf(path, engine="netcdf4", encoding=enc)
    RUNS.store_maps()


if __name__ == "__main__":
    main(sys.argv[1])
