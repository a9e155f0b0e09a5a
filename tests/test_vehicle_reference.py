"""A whole vehicle run against the recorded outputs of the implementation before the
whole-run speed-up (``tests/data/vehicle_run_reference.nc``, recorded at commit a47fa63 by
``tools/record_vehicle_reference.py``; every 10th step of a 0.3 s run).

Since then the random irregularity is synthesised once along the track and interpolated
to the magnets (Hermite, remainder bound 1e-13 of its RMS; measured 5e-14 of the largest
elevation and 3e-13 of the largest slope against the direct sums), the run's other
arithmetic is unchanged.  Measured largest difference: 1.2e-13 of the largest voltage.

The recorded run has the parameters of its time: the realism changes of issue 23 item 4
(the girders' precamber, the damping input blended with the absolute velocity, the
choppers' diodes in the plant) are model and parameter changes that came after, so the
run here switches them off (``precamber_m = 0``, ``control_velocity_blend = 0``,
``freewheel=False``): with them off the step is the recorded one."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from maglevkit.vehicle.data import load_guideway
from maglevkit.vehicle.simulation import Failure, VehicleModel, parse_irregularity
from maglevkit.vehicle.train import load_vehicle

from .conftest import paper_tr09_vehicle

REFERENCE = Path(__file__).parent / "data" / "vehicle_run_reference.nc"

# the interpolated irregularity differs from the old per-point sums by <= 3e-13 of its
# largest value (slope), the compiled step's own rounding is ~1e-13 (test_vehicle_compiled)
# and a linear response carries such differences over unamplified: 1e-10 of each
# variable's largest value (the criterion) leaves a margin of > 100
RTOL = 1e-10


@pytest.fixture(scope="module")
def reference():                                     # type: ignore[no-untyped-def]
    xr = pytest.importorskip("xarray")
    with xr.open_dataset(REFERENCE, engine="netcdf4") as ds:
        return ds.load()


def test_whole_run_reproduces_the_recorded_run(reference, tmp_path) -> None:  # type: ignore[no-untyped-def]
    # recorded with the TR09 magnets' lumped "paper" network (the bundled files are split
    # since issue 26): loaded explicitly, so that the run is the recorded one
    train = dataclasses.replace(load_vehicle(paper_tr09_vehicle(tmp_path)),
                                control_velocity_blend=0.0)
    data = load_guideway()
    data = dataclasses.replace(data, span=dataclasses.replace(data.span, precamber_m=0.0))
    n_spans = data.guideway(n_spans=1).spans_needed(train.length_m)
    model = VehicleModel(train, guideway=data.guideway(n_spans=n_spans), freewheel=False)
    prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                              span_length_m=model.guideway.span.length_m)
    res = model.run(speed_m_per_s=400 / 3.6, duration_s=0.3, irregularity=prof,
                    failures=[Failure("s2m4/front", 0.1)], loop="compiled")
    ds = res.dataset.isel(time=slice(None, None, 10))
    assert set(ds.data_vars) == set(reference.data_vars)
    assert dict(ds.sizes) == dict(reference.sizes)
    np.testing.assert_array_equal(ds.time.values, reference.time.values)
    worst = {}
    for name in reference.data_vars:
        x = np.asarray(ds[name].values, dtype=float)
        y = np.asarray(reference[name].values, dtype=float)
        np.testing.assert_array_equal(np.isnan(x), np.isnan(y))
        ok = ~np.isnan(y)
        scale = float(np.abs(y[ok]).max())
        worst[name] = float(np.abs(x[ok] - y[ok]).max()) / scale if scale > 0 else 0.0
    assert max(worst.values()) < RTOL, worst
    # the summaries over every step: comfort (one FFT per record and Parseval now, an
    # inverse FFT per index before: rounding, measured 4e-15), minimum gaps, peak currents
    for key, recorded in (("comfort", res.comfort), ("min_gap_m", res.min_gap_m),
                          ("peak_current_A", res.peak_current_A)):
        ref = json.loads(reference.attrs[key])
        assert set(ref) == set(recorded)
        for k, v in ref.items():
            if isinstance(v, dict):
                for q, val in v.items():
                    assert recorded[k][q] == pytest.approx(val, rel=RTOL, abs=0.0)
            else:
                assert recorded[k] == pytest.approx(v, rel=RTOL, abs=0.0)
    # the reference run is not trivial: the gaps moved by more than a millimetre
    assert np.ptp(reference.gap.values) > 1e-3
