"""Issue 5 acceptance: reduced vs detailed model on the standard scenarios, <= 2 % NRMS."""

from __future__ import annotations

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.compare import compare_models, standard_scenarios

LIMIT = 0.02   # the bound on the normalised RMS error per circuit


def _run(name: str, s0: float, i0: float, gaps: tuple, currents: tuple, *, skip: tuple = (),
         **model_options: str) -> list:
    mag = mk.load_magnet(name)
    maps = mk.build_maps(mag, gaps=np.linspace(*gaps), currents=np.linspace(*currents))
    scenarios = [sc for sc in standard_scenarios(mag, gap_m=s0, current_A=i0)
                 if sc.name not in skip]
    return compare_models(mag, mk.CurrentModel(maps, **model_options), scenarios, gap_m=s0,
                          current_A=i0)


def _check(results: list) -> None:
    for r in results:
        if r.scenario.coupling:
            # neglected coupling, reported separately: the stepped circuit is within the
            # bound; the other circuit's response is what the reduced model cannot show
            assert r.current_error[0] < LIMIT and r.force_error[0] < LIMIT, r.scenario.name
            assert 0.0 < r.current_error[1] < 0.01, r.scenario.name
            continue
        assert np.all(r.current_error < LIMIT), (r.scenario.name, r.current_error)
        assert np.all(r.force_error < LIMIT), (r.scenario.name, r.force_error)


def test_u_magnet_with_eddy_currents_and_saturation() -> None:
    results = _run("u-magnet", 0.010, 20.0, (0.004, 0.020, 17), (0.0, 80.0, 33))
    assert {r.scenario.name for r in results} >= {"voltage step up", "gap sine 50 Hz",
                                                   "gap ramp", "closed loop"}
    _check(results)


def test_tr09_standard_magnet_fast_set() -> None:
    results = _run("tr09-standard", 0.010, 34.0, (0.005, 0.016, 12), (0.0, 80.0, 41),
                   skip=("gap sine 0.5 Hz",))
    _check(results)
    # the reduced model is much faster on every open-loop case (measured 100-250x; a
    # generous floor keeps the test robust on a loaded machine)
    assert all(r.speedup > 20 for r in results if r.scenario.kind == "open")


@pytest.mark.slow
def test_tr09_standard_magnet_full_set_both_eddy_resistances() -> None:
    for which in ("fit", "jump"):
        _check(_run("tr09-standard", 0.010, 34.0, (0.005, 0.016, 12), (0.0, 80.0, 41),
                    eddy_resistance=which))


@pytest.mark.slow
def test_u_magnet_with_transient_method_maps() -> None:
    """The paper's own identification (method="transient": voltage-step time constants and
    the virtual control law) instead of the statics sensitivities, on the standard set.
    A 9 x 9 grid (1 mm x 5 A, 81 points: 27 s for the maps on 2 cores, 30 s in all)
    covers the scenarios (gaps 9-12 mm, currents 13-30 A).  Measured largest NRMS 0.88 %
    (50 Hz gap sine, current); the 2 % bound is the issue's acceptance criterion."""
    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps=np.linspace(0.006, 0.014, 9), currents=np.linspace(0, 40, 9),
                         method="transient", progress=False)
    assert "transient" in maps.dataset.attrs["method"]
    scenarios = standard_scenarios(mag, gap_m=0.010, current_A=20.0)
    results = compare_models(mag, mk.CurrentModel(maps), scenarios, gap_m=0.010, current_A=20.0)
    assert {r.scenario.name for r in results} >= {"voltage step up", "gap sine 50 Hz",
                                                   "gap ramp", "closed loop"}
    _check(results)
