"""Choosing the calibration's parameter set from the fitted gaps alone (issue 25 part 2):
leave-one-gap-out cross-validation (``select_parameters``), on seeded synthetic data and on
the U-magnet's 2-D FEM with its split network (fit 4-12 mm, held out 14-20 mm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.calibration import (
    StaticPoints,
    calibrate,
    calibrated_network,
    select_parameters,
)
from maglevkit.errors import InputError
from maglevkit.magnets import build_magnet
from maglevkit.parameter_files import read_parameter_file

ROOT = Path(__file__).resolve().parents[1]
FEM_2MM = ROOT / "benchmarks" / "results" / "u_magnet_fem_statics_2mm.csv"
HOLD_M = [0.014, 0.016, 0.018, 0.020]
TRUE = {"leakage_factor": 0.85, "iron_saturation_scale": 0.95}


def _points(model: object, values: dict[str, float], noise: float) -> StaticPoints:
    g, c = (a.ravel() for a in np.meshgrid(np.arange(4, 13, 2) * 1e-3,
                                           np.array([10.0, 40.0, 80.0]), indexing="ij"))
    sol = mk.solve_statics(calibrated_network(model, values), gaps_m=np.c_[g, g],
                           currents_A=c[:, None])
    f = np.asarray(sol.force_N, dtype=float).reshape(-1)
    p = np.asarray(sol.flux_linkage_Wb, dtype=float).reshape(-1)
    rng = np.random.default_rng(25)
    return StaticPoints(gap_m=g, current_A=c,
                        force_N=(f * (1 + noise * rng.standard_normal(f.size)))[:, None],
                        flux_linkage_Wb=(p * (1 + noise * rng.standard_normal(p.size)))[:, None],
                        circuits=("coil",), rows=np.arange(2, 2 + g.size))


def test_the_set_holding_the_perturbed_parameters_ranks_first() -> None:
    """Data made with leakage and saturation factors off nominal (0.3 % noise): the set of
    those two is ranked first, its left-out error at the noise level; a set missing one of
    them cannot follow the left-out gaps."""
    magnet = mk.load_magnet("u-magnet", eddy_currents=False)
    pts = _points(magnet, TRUE, 3e-3)
    ranked = select_parameters(magnet, pts, sets=[("leakage_factor",),
                                                  ("iron_saturation_scale",),
                                                  tuple(TRUE)])
    assert ranked[0].parameters == tuple(TRUE)
    # 3 sigma of 0.3 % noise is 0.9 %, plus the fitted values' own scatter: 1.5 %
    # (measured 0.69 %, rms 0.30 %)
    assert ranked[0].worst < 0.015
    assert set(ranked[0].per_gap) == {0.004, 0.006, 0.008, 0.010, 0.012}
    # a missing factor: measured worst left-out errors 5.9 % (saturation only) and 7.6 %
    # (leakage only)
    assert min(sc.worst for sc in ranked[1:]) > 2.0 * ranked[0].worst


def test_held_out_gaps_are_never_used_and_too_few_gaps_are_refused() -> None:
    magnet = mk.load_magnet("u-magnet", eddy_currents=False)
    pts = _points(magnet, TRUE, 0.0)
    ranked = select_parameters(magnet, pts, sets=[tuple(TRUE)], holdout_gaps_m=[0.012])
    assert set(ranked[0].per_gap) == {0.004, 0.006, 0.008, 0.010}
    # noise-free data of the same law: every left-out point to the solvers' tolerance
    # (measured 4.9e-14)
    assert ranked[0].worst < 1e-6
    with pytest.raises(InputError, match="at least 3 fitted gaps"):
        select_parameters(magnet, pts, sets=[tuple(TRUE)],
                          holdout_gaps_m=[0.006, 0.008, 0.010])
    with pytest.raises(InputError, match="documented set"):
        select_parameters(magnet, pts, sets=[("leakage",)])


@pytest.mark.slow
def test_fem_split_network_set_chosen_on_4_to_12_mm() -> None:
    """The U-magnet's split network on its 2-D FEM: the set chosen by cross-validation
    within 4-12 mm (all 31 subsets of the five static factors) and its error at the
    held-out 14-20 mm, which the choice never saw (docs/decisions.md, cal25)."""
    params, _ = read_parameter_file("u-magnet", what="magnet")
    split = build_magnet({**params, "magnet": {**params["magnet"], "flux_paths": "split"},
                          "provenance": {**params["provenance"],
                                         "magnet.flux_paths": "[E] test variant"}},
                         options=mk.ModelOptions(eddy_currents=False))
    ranked = select_parameters(split, FEM_2MM, holdout_gaps_m=HOLD_M)
    assert len(ranked) == 31
    best = ranked[0]
    # measured: leakage, fringing, gap offset and iron field scale, worst left-out error
    # 1.28 % (the default five second, 1.53 %)
    assert best.parameters == ("leakage_factor", "fringing_factor", "gap_offset_m",
                               "iron_field_scale")
    assert 0.010 < best.worst < 0.016
    res = calibrate(split, FEM_2MM, parameters=list(best.parameters), holdout_gaps_m=HOLD_M)
    # measured held out: force -0.04 ... +2.90 %, psi -0.87 ... +0.50 %; the force misses
    # the 2 % at 20 mm only (+2.07 ... +2.90 % at every current), growing with the
    # gap as with the default set (3.12 %): the window-limited inner fringe
    # (docs/magnets.md, "Why the force error grows with the gap")
    assert res.max_error("holdout", "force_N") == pytest.approx(0.0290, abs=0.002)
    assert res.max_error("holdout", "flux_linkage_Wb") < 0.011


def test_cli_select_params(tmp_path: Path) -> None:
    """``maglevkit calibrate --select-params``: the command line ranks the subsets of
    --params on the fitted gaps, fits the best one and writes it; the same choice as the
    Python function."""
    import tomllib
    from typer.testing import CliRunner

    from maglevkit.cli import app

    pool = ["leakage_factor", "iron_saturation_scale"]
    out = tmp_path / "calibrated.toml"
    res = CliRunner().invoke(app, ["calibrate", "u-magnet", str(FEM_2MM), "-o", str(out),
                                   "--params", ",".join(pool), "--select-params",
                                   "--holdout-gaps", ",".join(map(str, HOLD_M))])
    assert res.exit_code == 0, res.output
    ranked = select_parameters(mk.load_magnet("u-magnet"), FEM_2MM, candidates=pool,
                               holdout_gaps_m=HOLD_M)
    assert f"chosen: {', '.join(ranked[0].parameters)}" in res.stderr
    assert "cross-validation (leave one fitted gap out)" in res.stderr
    table = tomllib.loads(out.read_text())["calibration"]
    assert set(ranked[0].parameters) <= set(table) and set(pool) - set(
        ranked[0].parameters) == set(pool) - set(table)
