"""Issue 26's frequency sweep on the bundled default (its "Must show": the reduced model's
frequency sweep as a test, 5 / 50 / 200 Hz bounds).

The pair is what ``tr09-standard`` builds and names since switch26m: the detailed model on
the diffusing eddy ladder (``eddy_model = "ladder"``, 6 layers) against the reduced model
its maps name, ``CurrentModel(maps, eddy_modes=default_eddy_modes(maps))`` (the 2-branch
eddy network, ``[reduced] eddy_modes = 2``), as compare, demo, the FMU and the vehicles
take it.  The network is fitted to a voltage step of the detailed model at fixed gap
(docs/reduction.md, "More eddy modes"); the gap sine checks it on an input it was not
fitted to.  Aims (issue 26 part 3): the coil current's error relative to its variation <=
5 / 10 / 20 % at 5 / 50 / 200 Hz, its phase within 5 deg up to 100 Hz.

The default suite checks the law on the linearised models (the detailed DAE linearised by
AD against ``CurrentModel.linearize``, seconds); the simulated +-1 mm sweep of ``make
bench`` (benchmarks/bench_gap_motion.py) is the slow test.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.reduction import default_eddy_modes
from maglevkit.reduction.motion_eddy import detailed_frequency_response

from .conftest import load_script

AIMS = {5.0: 0.05, 50.0: 0.10, 200.0: 0.20}
"""Issue 26's bounds on the current error relative to its variation, per frequency [Hz]."""
PHASE_AIM_DEG, PHASE_UP_TO_HZ = 5.0, 100.0
"""Issue 26's phase bound [deg], up to this frequency [Hz]."""


def _bench() -> Any:
    """benchmarks/bench_gap_motion.py (its sweep, grid and linearised response: the same
    code as the ``make bench`` section, not a copy)."""
    return load_script(Path(__file__).resolve().parents[1] / "benchmarks" / "bench_gap_motion.py")


def _phase_error_deg(reduced: complex, detailed: complex) -> float:
    return float(np.degrees(np.angle(reduced / detailed)))


def test_linearised_sweep_of_the_default_pair() -> None:
    """Small-signal version of the sweep: gap -> coil current ('front', every pole moving)
    at 10 mm / 31.7 A and constant voltage, detailed DAE (linearised by AD, 1011
    branches) vs the maps' default reduced model (``linearize``).  For a sine the AC error
    of the simulated run is ``|H_red - H_det| / |H_det|`` up to start-up and harmonics.

    Measured (maps 5 x 6, 8-12 mm x 20-45 A, identified at their centre 10 mm / 32.5 A):
    network 0.61 / 1.23 / 1.29 / 1.48 / 1.99 % at 5 / 20 / 50 / 100 / 200 Hz, phase
    +0.03 / +0.59 / +0.42 / +0.51 / +0.79 deg; eq. 8 on the same maps 22.4 / 23.6 / 24.0 /
    24.0 / 23.9 % (its one R_ec, fitted to a step that has no current jump, gives the
    motion-induced current too small at every frequency: 1.45 vs 1.85-1.90 A/mm).  The
    bounds are the issue's; eq. 8 is held above 15 % so that the test tells the two apart
    (the simulated sweep of the slow test: 21.6-23.6 %)."""
    bench = _bench()
    mag = mk.load_magnet("tr09-standard")
    assert mag.options.eddy_model == "ladder"           # the file's detailed model
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.008, 0.012, 5),
                         currents_A=np.linspace(20.0, 45.0, 6), progress=False)
    m = default_eddy_modes(maps)
    assert m == 2                                        # the file's [reduced] eddy_modes
    f = np.array([5.0, 20.0, 50.0, 100.0, 200.0])
    i0 = mag.nominal_current
    everything = {c: tuple(mag.network.gap_names) for c in mag.network.circuit_names}
    det = detailed_frequency_response(mag.network, gap=bench.GAP, current=i0,
                                      frequencies_Hz=f, groups=everything)[0]
    h_det = det.gap_to_current_A_per_m
    net, _ = bench.frequency_response(mk.CurrentModel(maps, eddy_modes=m), i0, f)
    eq8, _ = bench.frequency_response(mk.CurrentModel(maps), i0, f)
    for k, fk in enumerate(f):
        err = abs(net[k] - h_det[k]) / abs(h_det[k])
        if fk in AIMS:
            assert err <= AIMS[fk], (fk, err)
        if fk <= PHASE_UP_TO_HZ:
            assert abs(_phase_error_deg(net[k], h_det[k])) <= PHASE_AIM_DEG, fk
        assert abs(eq8[k] - h_det[k]) / abs(h_det[k]) > 0.15, fk


@pytest.mark.slow
def test_simulated_sweep_of_the_default_pair() -> None:
    """The sweep of ``make bench`` (bench_gap_motion: maps 12 x 41, 5-16 mm x 0-80 A; gap
    sine 10 +- 1 mm, constant voltage of 31.7 A, all poles; error over the whole run
    including the start, phase of the fundamental over its last half).  Measured: current
    error 0.50 / 1.32 / 2.05 % at 5 / 50 / 200 Hz (switch26m: 0.5 / 1.3 / 2.0 %), phase
    within 1 deg; eq. 8 on the same maps 21.6 / 23.6 / 23.5 %.  Bounds: the issue's."""
    bench = _bench()
    mag = bench.magnet()
    assert mag.options.eddy_model == "ladder"
    maps = mk.build_maps(mag, gaps_m=bench.GRID[0], currents_A=bench.GRID[1], progress=False)
    assert default_eddy_modes(maps) == 2
    models = {"net": bench.default_reduced(maps), "eq8": mk.CurrentModel(maps)}
    rows = bench.sweep(mk.FluxModel(mag), models, bench.nominal_current(mag),
                       (5.0, 50.0, 100.0, 200.0))
    for row in rows:
        f, (cd, _) = row["f"], row["detailed"]
        if f in AIMS:
            assert row["net"][2] <= AIMS[f], (f, row["net"][2])
        if f <= PHASE_UP_TO_HZ:
            assert abs(_phase_error_deg(row["net"][0], cd)) <= PHASE_AIM_DEG, f
        assert row["eq8"][2] > 0.15, f
