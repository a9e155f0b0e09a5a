"""Checks shared by the tests of statics CSV files (``maglevkit statics --csv``) read back:
into maps (``maps_from_table``: test_tables_in, test_statics_csv_multi) and into
``calibrate`` (test_calibration, test_statics_csv_multi)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import tomllib
from typer.testing import CliRunner

import maglevkit as mk
from maglevkit.cli import app
from maglevkit.compare import ComparisonScenario, standard_scenarios
from maglevkit.control import closed_loop, design_gap_controller
from maglevkit.errors import DataWarning
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass


def replay_errors(ref: Any, model: Any, magnet: mk.Magnet, *, gap_m: float,
                  current_A: float) -> Iterator[tuple[ComparisonScenario, dict[str, float]]]:
    """``compare``'s standard scenarios at ``gap_m`` [m] / ``current_A`` [A] on two reduced
    models (built maps and imported ones): per scenario its largest relative differences.

    Closed loops (a heave mass holding the magnet's own force at the point, the gap
    controller designed on ``magnet``) give ``"gap"`` (of the reference's gap range) and
    ``"current"`` (of its peak); voltage-driven scenarios ``"current"`` and ``"force"`` (of
    the peaks).  The caller asserts its own bounds.
    """
    force0 = float(mk.solve_statics(magnet, gaps_m=gap_m, currents_A=current_A).force_N)
    heave = HeaveMass(force0 / STANDARD_GRAVITY)
    ctl = design_gap_controller(magnet.network, mass_kg=heave.mass_kg, gap_m=gap_m,
                                current_A=current_A)

    def rel(got: np.ndarray, want: np.ndarray, scale: float) -> float:
        return float(np.max(np.abs(got - want)) / scale)

    for sc in standard_scenarios(magnet, gap_m=gap_m, current_A=current_A):
        if sc.kind == "closed":
            a, b = (closed_loop(m, heave, ctl, duration_s=sc.duration_s, dt_s=sc.dt_s,
                                initial_gap_m=gap_m, initial_current_A=current_A,
                                gap_reference_m=sc.gap_reference_m,
                                external_force_N=lambda t, f=sc.external_force_fraction:
                                force0 * f(t))
                    for m in (ref, model))
            yield sc, {"gap": rel(b.gap_m, a.gap_m, float(np.ptp(a.gap_m))),
                       "current": rel(b.currents_A, a.currents_A,
                                      float(np.max(np.abs(a.currents_A))))}
            continue
        a, b = (mk.simulate(m, (0.0, sc.duration_s), dt_s=sc.dt_s, gaps_m=sc.gaps_m,
                            voltages_V=sc.voltages_V, initial_currents_A=sc.initial_current_A)
                for m in (ref, model))
        yield sc, {"current": rel(b.currents_A, a.currents_A,
                                  float(np.max(np.abs(a.currents_A)))),
                   "force": rel(b.circuit_force_N, a.circuit_force_N,
                                float(np.max(np.abs(a.circuit_force_N))))}


def calibrate_own_statics(magnet: str, gaps: str, currents: str, tmp_path: Path) -> Path:
    """Write ``magnet``'s own statics CSV (``maglevkit statics --csv`` on the CLI's
    ``gaps`` / ``currents`` ranges), read it back with ``maglevkit calibrate`` and check that
    the nominal factors come back; returns the CSV.

    ``calibrate`` warns that it does not read the derived column
    ``differential_inductance_H`` (a DataWarning naming it).  Bounds: the CSV's 9
    significant digits move the data by <= 5e-9 relative, so a factor by well under 1e-6
    (measured 2.2e-8) and the gap offset well under 1e-9 m.
    """
    runner = CliRunner()
    data, out = tmp_path / "s.csv", tmp_path / "c.toml"
    res = runner.invoke(app, ["statics", magnet, "--gaps", gaps, "--currents", currents,
                              "--csv", str(data)])
    assert res.exit_code == 0, res.output
    with pytest.warns(DataWarning, match=r"differential_inductance_H.*not read"):
        res = runner.invoke(app, ["calibrate", magnet, str(data), "-o", str(out)])
    assert res.exit_code == 0, res.output
    cal = tomllib.loads(out.read_text())["calibration"]
    for name in ("leakage_factor", "fringing_factor", "iron_field_scale"):
        assert abs(cal[name] - 1.0) < 1e-6, (name, cal[name])
    assert abs(cal["gap_offset_m"]) < 1e-9
    return data
