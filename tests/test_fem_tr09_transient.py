"""TR09 levitation magnets: voltage steps against the recorded transient 2-D FEM (issue 26).

The FEM (benchmarks/fem_tr09_transient.py: the longitudinal cut of fem_tr09 with solid
cores and pole back, eddy currents closing per core and back slice as the network's eddy
elements, laminated stator, circuits driven through their resistance) is recorded in
benchmarks/results/fem_tr09_transient.json; maglevkit's ``FluxModel`` on the same cut
(``end_effects = false``, split network) runs the same steps here.  Numbers and their
discussion: docs/validation_fem.md, "Voltage-step transient of the TR09 magnets".
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk

from .conftest import HAVE_SKFEM, SKIP_FEM_VAR, load_script

_DIR = Path(__file__).resolve().parents[1] / "benchmarks"
_RECORD = _DIR / "results" / "fem_tr09_transient.json"
needs_fem = pytest.mark.skipif(not HAVE_SKFEM, reason="scikit-fem not installed and "
                               f"{SKIP_FEM_VAR}=1: FEM validation skipped on request")


def _bench():  # type: ignore[no-untyped-def]
    return load_script(_DIR / "fem_tr09_transient.py")


def _record(magnet: str, label: str, kind: str = "slices") -> dict:
    return json.loads(_RECORD.read_text())[f"{magnet} | {label} | {kind} | o21.5"]


def _errors(bench, ref: dict, variant: str) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    """(largest current error for t >= 1 ms in % of the step, t63 error in %) per circuit."""
    e = bench.errors(ref, bench.simulate_network(ref, variant))
    t63 = np.asarray(e["t63_s"]) / np.asarray(e["t63_fem_s"]) - 1.0
    return 100 * np.asarray(e["err_max"]), 100 * t63


def test_recorded_fem_is_converged() -> None:
    """The FEM's own error, from its mesh (x 1.5 finer) and time-step (/2) runs."""
    data = json.loads(_RECORD.read_text())
    base = data["tr09-standard | 10 mm, 20 -> 40 A | slices | o21.5"]
    tb, ib = np.asarray(base["time_s"]), np.asarray(base["current_A"])[:, 0]
    late = tb >= 1e-3
    study = [r for k, r in data.items() if k.startswith("tr09-standard | 10 mm, 20 -> 40 A, ")]
    assert len(study) == 2
    for r in study:
        i = np.interp(tb, np.asarray(r["time_s"]), np.asarray(r["current_A"])[:, 0])
        # measured: mesh x 1.5 0.56 %, dt / 2 0.02 % of the step (t63 +0.44 / +0.05 %);
        # the model windows below are >= 1 pp wide
        assert np.max(np.abs(i - ib)[late]) / 20.0 < 0.01
    # energy balance of every run (rectangle rule on the BDF2 steps): measured <= 1e-3
    assert all(r["energy_residual"] < 2e-3 for r in data.values())


def test_ladder_statics_are_the_lumped_network_s() -> None:
    """The ladder splits each core and back segment into parallel tubes of one material
    and length: the statics are the lumped network's (round-off only)."""
    a = mk.load_magnet("tr09-standard", eddy_model="lumped")   # the file's: the ladder
    b = mk.load_magnet("tr09-standard", eddy_model="ladder", eddy_layers=4)
    assert len(b.network.branches) > len(a.network.branches)
    sa = mk.solve_statics(a, gaps_m=0.010, currents_A=[40.0, 40.0])
    sb = mk.solve_statics(b, gaps_m=0.010, currents_A=[40.0, 40.0])
    # Newton to ~1e-12 on both; measured 2e-12 (force) and 1e-12 (psi) relative
    assert float(np.ravel(sb.force_N)[0]) == pytest.approx(float(np.ravel(sa.force_N)[0]),
                                                             rel=1e-8)
    assert np.allclose(np.ravel(sb.flux_linkage_Wb), np.ravel(sa.flux_linkage_Wb), rtol=1e-8)


@needs_fem
@pytest.mark.slow
def test_lumped_network_jumps_and_the_ladder_follows_the_fem() -> None:
    bench = _bench()
    ref = _record("tr09-standard", "10 mm, 20 -> 40 A")
    lumped = bench.errors(ref, bench.simulate_network(ref, "cut"))
    # the lumped eddy elements are resistors for the coil at t = 0+: the current jumps
    # (measured +13.7 % of the step at 1 ms, t63 +15.1 %)
    assert lumped["err_1ms"][0] > 0.10
    assert lumped["t63_s"][0] / lumped["t63_fem_s"][0] - 1 > 0.10
    err, t63 = _errors(bench, ref, "cut, ladder n = 6")
    # measured 1.0 % of the step (largest, at 1 ms, where the FEM's own mesh error is
    # 0.56 %) and t63 +1.0 %; windows 1.5 / 2.5 pp around them, inside the aims (5 %)
    assert np.all(err < 2.5)
    assert np.all((t63 > -2.5) & (t63 < 3.5))


@needs_fem
@pytest.mark.slow
def test_ladder_vs_fem_all_steps() -> None:
    """Every recorded step of both magnets with the ladder (n = 6) on the cut."""
    bench = _bench()
    data = json.loads(_RECORD.read_text())
    labels = {c[0] for c in bench.CASES}
    seen = 0
    for key, ref in data.items():
        if ref["label"] not in labels or " | slices | o21.5" not in key:
            continue
        err, t63 = _errors(bench, ref, "cut, ladder n = 6")
        lo, hi = ALL_T63[ref["magnet"], ref["label"]]
        # signed windows around the measured values (docs/validation_fem.md)
        assert np.all(err < ALL_ERR[ref["magnet"], ref["label"]]), (key, err)
        assert np.all((t63 > lo) & (t63 < hi)), (key, t63)
        seen += 1
    assert seen == len(ALL_T63)


# Measured with the ladder n = 6 on the cut (docs/validation_fem.md): largest current error
# for t >= 1 ms [% of the step] and t63 error [%], per circuit the FEM holds (standard:
# rear; bow: middle c2 / end c3).  The model is deterministic (rtol 1e-7) and the record
# fixed; the windows (error: measured + 1 pp; t63: measured -/+ 1.5 pp) only leave room
# for round-off and integrator tolerance, and all lie inside the aims (5 % / 5 %).
_MEASURED = {
    ("tr09-standard", "10 mm, 20 -> 40 A"): ((1.0,), (+1.0,)),
    ("tr09-standard", "14 mm, 20 -> 40 A"): ((1.0,), (+0.1,)),
    ("tr09-standard", "10 mm, 30 -> 60 A"): ((1.1,), (-2.0,)),
    ("tr09-bow", "10 mm, 20 -> 40 A"): ((1.0, 1.1), (+1.2, +0.8)),
    ("tr09-bow", "14 mm, 20 -> 40 A"): ((1.0, 1.0), (+0.5, -0.1)),
    ("tr09-bow", "10 mm, 30 -> 60 A"): ((1.1, 1.1), (-0.9, -2.6)),
}
ALL_ERR = {k: max(e) + 1.0 for k, (e, _) in _MEASURED.items()}
ALL_T63 = {k: (min(t) - 1.5, max(t) + 1.5) for k, (_, t) in _MEASURED.items()}
