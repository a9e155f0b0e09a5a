"""TR09 bow magnet against its recorded 2-D FEM, circuit by circuit (issue 26).

maglevkit parameterises the bow magnet pole by pole as the standard one; only the feeding
differs (three circuits of four poles).  benchmarks/fem_tr09_bow.py re-solves the standard
magnet's longitudinal cut (benchmarks/fem_tr09.py, unchanged) and records every pole's flux
linkage and its current derivative in benchmarks/results/fem_tr09_bow.json, so the
per-circuit statics of the end circuit (c3, poles 9-12; c1 mirrors it) and of the middle
circuit (c2, poles 5-8) can be held against the network (``end_effects = false``) without
rerunning the FEM.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .conftest import load_script

_BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _load(name: str):  # type: ignore[no-untyped-def]
    return load_script(_BENCH / f"{name}.py")


# (network - FEM)/FEM [%]: force, end circuit's psi and L, middle circuit's psi and L (all
# currents together).  Deterministic network, fixed record: 0.3 pp covers rounding only.
MARGIN = 0.3
# "split" as of fringe26 (the flank's conformal tubes up to window/pi; before: force +3.1
# ... +3.4 % at 20 mm, the middle circuit's L +1.9 % at 6 mm / 80 A, now +4.3 %), the
# network of test_fem_tr09.MEASURED: the force errors are those, to the digit; a change of
# the split network re-measures both tables with
# ``python benchmarks/fem_tr09_bow.py --compare``
SPLIT: dict[tuple[float, float], tuple[float, ...]] = {
    (6.0, 10.0): (+0.9, +0.5, +0.5, +0.9, +0.9),
    (6.0, 33.5): (+1.7, +0.7, -0.9, +1.4, +2.8),
    (6.0, 50.0): (-0.1, -0.2, -2.6, +0.9, -0.4),
    (6.0, 80.0): (+1.3, -0.2, -0.1, +1.3, +4.3),
    (6.0, 100.0): (+2.4, -0.3, -1.8, +1.5, +2.8),
    (10.0, 10.0): (+0.2, +0.5, +0.6, +1.1, +1.1),
    (10.0, 33.5): (+0.5, +0.7, +1.1, +1.1, +1.5),
    (10.0, 50.0): (+0.7, +0.6, -0.8, +1.6, +2.9),
    (10.0, 80.0): (-1.5, -0.2, -2.3, +1.1, +0.0),
    (10.0, 100.0): (-1.7, -0.4, -2.1, +1.1, +1.6),
    (20.0, 10.0): (+1.5, +0.5, +0.5, +1.3, +1.3),
    (20.0, 33.5): (+1.5, +0.6, +0.6, +1.3, +1.3),
    (20.0, 50.0): (+1.7, +0.6, +0.9, +1.3, +1.5),
    (20.0, 80.0): (+1.9, +0.6, -0.0, +1.7, +3.1),
    (20.0, 100.0): (+1.9, +0.5, -0.6, +1.9, +2.0),
}
# the lumped default ("paper")
PAPER: dict[tuple[float, float], tuple[float, ...]] = {
    (6.0, 10.0): (-7.7, -10.9, -10.8, -10.5, -10.5),
    (6.0, 33.5): (-7.0, -10.4, -12.7, -10.4, -13.0),
    (6.0, 50.0): (-14.7, -13.9, -35.0, -14.3, -35.9),
    (6.0, 80.0): (-22.1, -17.0, -21.3, -17.5, -21.6),
    (6.0, 100.0): (-23.2, -16.7, -4.4, -17.1, +4.0),
    (10.0, 10.0): (-9.6, -11.7, -11.6, -11.1, -11.1),
    (10.0, 33.5): (-9.3, -11.5, -10.8, -11.0, -10.7),
    (10.0, 50.0): (-9.0, -11.1, -13.1, -11.0, -14.1),
    (10.0, 80.0): (-19.4, -14.9, -29.4, -15.4, -29.4),
    (10.0, 100.0): (-23.1, -15.7, -17.2, -16.1, -15.6),
    (20.0, 10.0): (-9.3, -12.8, -12.8, -11.8, -11.8),
    (20.0, 33.5): (-9.3, -12.7, -12.7, -11.8, -11.7),
    (20.0, 50.0): (-9.1, -12.7, -12.3, -11.7, -11.5),
    (20.0, 80.0): (-7.9, -11.8, -7.9, -11.5, -10.9),
    (20.0, 100.0): (-9.0, -11.6, -15.5, -11.7, -15.9),
}


def _check(flux_paths: str, measured: dict[tuple[float, float], tuple[float, ...]]) -> dict:
    fem = _load("fem_tr09_bow")
    mag = fem.cut_magnet("tr09-bow", flux_paths)
    rows = {(r["s_mm"], r["I_A"]): r for r in fem.compare(mag, fem.load())}
    assert set(measured) <= set(rows)
    for k, want in measured.items():
        r = rows[k]
        got = (r["eF"], r["epsi_end"], r["eL_end"], r["epsi_mid"], r["eL_mid"])
        for name, g, w in zip(("F", "psi end", "L end", "psi mid", "L mid"), got, want,
                              strict=True):
            assert w - MARGIN <= g <= w + MARGIN, (k, name, g)
    return rows


@pytest.mark.slow
def test_split_network_per_circuit_against_recorded_fem() -> None:
    rows = _check("split", SPLIT)
    for k, r in rows.items():
        # every circuit's flux linkage within the 3 % aim, as the standard's half magnets
        assert abs(r["epsi_end"]) < 3.0 and abs(r["epsi_mid"]) < 3.0, k
        # the field's split between the circuits is followed to 2 pp: the network links
        # the middle circuit 0.4-1.7 pp more than the end circuit, relative to the FEM
        assert 0.0 < r["epsi_mid"] - r["epsi_end"] < 2.0, k


@pytest.mark.slow
def test_paper_network_per_circuit_against_recorded_fem() -> None:
    _check("paper", PAPER)


@pytest.mark.slow
def test_record_is_the_standard_magnets_field() -> None:
    """The bow record re-solves fem_tr09's cut: its force equals the standard magnet's
    recorded grid (same geometry, mesh and Newton tolerance; 1e-6 covers the sparse solves'
    round-off), and its six poles' linkages add up to fem_tr09's rear-circuit linkage
    (the same integral split by pole: 1e-9)."""
    bow = _load("fem_tr09_bow").load()
    std = json.loads((_BENCH / "results" / "fem_tr09_grid.json").read_text())
    common = sorted(set(bow) & set(std))
    assert len(common) >= 15
    for k in common:
        assert bow[k]["force_N"] == pytest.approx(std[k]["force_N"], rel=1e-6), k
    for k, p in bow.items():
        assert sum(p["psi_pole_Wb"].values()) == pytest.approx(p["psi_rear_Wb"], rel=1e-9), k
        assert sum(p["L_pole_H"].values()) == pytest.approx(p["L_rear_H"], rel=1e-9), k
