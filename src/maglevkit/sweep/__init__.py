"""Scenario sweeps: the Cartesian product of run parameters through an Executor.

A sweep file (TOML, SI units; :mod:`maglevkit.sweep.spec`) names a base job, a vehicle
run (:mod:`maglevkit.vehicle`) or a cross-section run (``job = "cross-section"``), and the
parameters to sweep: speeds, irregularity seeds, circuit failures, payloads, resistance
scales; for the cross-section curves and crosswind gusts.  :func:`run_sweep` runs every case through
a ``concurrent.futures.Executor`` (a local process pool by default, a
``dask.distributed`` client for a cluster), stores each case as it finishes (resumable),
records failing cases with their error, and returns one :class:`xarray.Dataset` with a
coordinate per swept parameter (``docs/sweep.md``).

Example::

    from maglevkit.sweep import load_sweep, run_sweep

    spec = load_sweep("vehicle-speeds")          # bundled example, or a path
    res = run_sweep(spec, workers=2, resume_dir="sweep.cases")
    res.dataset["min_gap"].sel(failure="none")
    res.to_netcdf("sweep.nc")
"""

from __future__ import annotations

from .cases import SUMMARY_UNITS, TIMING_VARIABLES, run_case
from .runner import SweepResult, assemble, case_path, run_sweep
from .spec import (
    CROSS_SECTION_PARAMETERS,
    PARAMETERS,
    SWEEP_FORMAT,
    CrossSectionJob,
    SweepParameter,
    SweepSpec,
    VehicleJob,
    bundled_sweeps,
    load_sweep,
    parse_sweep,
    scenario,
)

__all__ = [
    "CROSS_SECTION_PARAMETERS",
    "PARAMETERS",
    "SWEEP_FORMAT",
    "SUMMARY_UNITS",
    "TIMING_VARIABLES",
    "SweepParameter",
    "SweepSpec",
    "SweepResult",
    "VehicleJob",
    "CrossSectionJob",
    "assemble",
    "bundled_sweeps",
    "case_path",
    "load_sweep",
    "parse_sweep",
    "run_case",
    "run_sweep",
    "scenario",
]
