"""Issue 5 acceptance: reduced vs detailed model on the standard scenarios, <= 2 % NRMS."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.compare import compare_models, standard_scenarios

LIMIT = 0.02   # the bound on the normalised RMS error per circuit


def _run(name: str, s0: float, i0: float, gaps: tuple, currents: tuple, *, skip: tuple = (),
         repeat: int = 0, magnet_options: dict | None = None, **model_options: Any) -> list:
    """The standard scenarios of the bundled magnet ``name`` (``magnet_options`` for
    ``load_magnet``) against its reduced model: the magnet file's default
    (``[reduced] eddy_modes``, as ``maglevkit compare``) unless ``model_options`` say."""
    mag = mk.load_magnet(name, **(magnet_options or {}))
    maps = mk.build_maps(mag, gaps_m=np.linspace(*gaps), currents_A=np.linspace(*currents))
    assert maps.default_eddy_modes == mag.default_eddy_modes
    options: dict = {"eddy_modes": maps.default_eddy_modes, **model_options}
    scenarios = [sc for sc in standard_scenarios(mag, gap_m=s0, current_A=i0)
                 if sc.name not in skip]
    return compare_models(mag, mk.CurrentModel(maps, **options), scenarios, gap_m=s0,
                          current_A=i0, repeat=repeat)


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


# Regression bounds on the AC-normalised errors (RMS error over the RMS of the detailed
# signal's AC part), which -- unlike the NRMS acceptance metric, dominated by the steady
# level -- see the dynamics: measured (current, force) on the U-magnet, default maps and
# R_ec.  Bound: measured x AC_MARGIN.  Both models are deterministic (same inputs, fixed
# tolerances: reruns agree to ~1e-6 relative), so the margin only absorbs legitimate small
# changes of the numerics (integrator sub-steps, tolerances); a change of the reduced or
# detailed model that moves an error by more must re-measure these numbers.  What they
# catch: dL/ds x1.05 in eq. 8 raises the current error of the 0.5 Hz sine 0.77 -> 5.3 %,
# of the gap ramp 3.4 -> 10.7 %, of the 5 Hz sine 3.4 -> 8.4 %; R_ec x1.05 raises the
# voltage-step errors 4.3 -> 5.1 % and 5.6 -> 6.6 % (measured).
AC_MARGIN = 1.15
U_MAGNET_AC_MEASURED = {
    "voltage step up": (0.04322, 0.03668),
    "voltage step down": (0.05584, 0.04863),
    "gap sine 0.5 Hz": (0.00772, 0.00447),
    "gap sine 5 Hz": (0.03378, 0.01210),
    "gap sine 50 Hz": (0.02783, 0.13910),
    "gap ramp": (0.03351, 0.01447),
    "closed loop": (0.01454, 0.00559),
}


# TR09 standard magnet (fast set), both half magnets (equal by symmetry); the coupling
# scenario: its stepped circuit only (the other one's response is the neglected coupling).
# Measured on the bundled file as shipped since switch26m: the diffusing eddy ladder (6
# layers) against its reduced model, the 2-branch eddy network ([reduced] eddy_modes = 2);
# in the comments the former default's values (the split network's lumped eddy elements
# against eq. 8 with one R_ec, tr09switch), which the ladder's network beats in every
# dynamic case (gap sine 50 Hz: 26.5 -> 1.3 %, closed loop 8.2 -> 2.6 % in current).
TR09_AC_MEASURED = {
    "voltage step up": (0.00919, 0.01183),      # lumped + eq. 8: 0.02068, 0.00607
    "voltage step down": (0.01119, 0.00507),    # 0.01995, 0.00523
    "gap sine 5 Hz": (0.00489, 0.00463),        # 0.02274, 0.03677
    "gap sine 50 Hz": (0.01331, 0.01417),       # 0.26542, 0.26739
    "gap ramp": (0.00867, 0.00116),             # 0.02866, 0.01301
    "closed loop": (0.02630, 0.00402),          # 0.08155, 0.00865
    "coupling": (0.00927, 0.02816),             # 0.01487, 0.01194
}


def _check_ac(results: list, measured: dict[str, tuple[float, float]]) -> None:
    assert {r.scenario.name for r in results} == set(measured)
    for r in results:
        cur, force = measured[r.scenario.name]
        if r.scenario.coupling:
            assert r.current_error_ac[0] <= AC_MARGIN * cur, (r.scenario.name, cur)
            assert r.force_error_ac[0] <= AC_MARGIN * force, (r.scenario.name, force)
            continue
        assert np.all(r.current_error_ac <= AC_MARGIN * cur), (r.scenario.name,
                                                                r.current_error_ac, cur)
        assert np.all(r.force_error_ac <= AC_MARGIN * force), (r.scenario.name,
                                                               r.force_error_ac, force)


def test_u_magnet_with_eddy_currents_and_saturation() -> None:
    """Acceptance (NRMS <= 2 %) and regression (AC-normalised errors near their measured
    values) on the U-magnet's standard scenarios."""
    results = _run("u-magnet", 0.010, 20.0, (0.004, 0.020, 17), (0.0, 80.0, 33))
    assert {r.scenario.name for r in results} >= {"voltage step up", "gap sine 50 Hz",
                                                   "gap ramp", "closed loop"}
    _check(results)
    _check_ac(results, U_MAGNET_AC_MEASURED)


def test_tr09_standard_magnet_fast_set() -> None:
    results = _run("tr09-standard", 0.010, 34.0, (0.005, 0.016, 12), (0.0, 80.0, 41),
                   skip=("gap sine 0.5 Hz",), repeat=1)
    _check(results)
    _check_ac(results, TR09_AC_MEASURED)
    # the reduced model is faster on every open-loop case (CPU time of a warm run: measured
    # 100-1000x on the table kernel with eq. 8, 74-364x with the eddy network on the
    # B-splines (switch26m, loaded machine); floor 3 against a loaded machine)
    speedups = {r.scenario.name: round(r.speedup, 1) for r in results
                if r.scenario.kind == "open"}
    assert all(v > 3 for v in speedups.values()), speedups


@pytest.mark.slow
def test_tr09_standard_magnet_full_set_both_eddy_resistances() -> None:
    # eq. 8's two R_ec on the magnet whose eddy elements it represents: the lumped ones
    # (the bundled file's ladder has no current jump; its reduced model is the network)
    for which in ("fit", "jump"):
        _check(_run("tr09-standard", 0.010, 34.0, (0.005, 0.016, 12), (0.0, 80.0, 41),
                    magnet_options={"eddy_model": "lumped"}, eddy_modes=0,
                    eddy_resistance=which))


@pytest.mark.slow
def test_u_magnet_with_transient_method_maps() -> None:
    """The paper's own identification (method="transient": voltage-step time constants and
    the virtual control law) instead of the statics sensitivities, on the standard set.
    A 9 x 9 grid (1 mm x 5 A, 81 points: 27 s for the maps on 2 cores, 30 s in all)
    covers the scenarios (gaps 9-12 mm, currents 13-30 A).  Measured largest NRMS 0.88 %
    (50 Hz gap sine, current); the 2 % bound is the issue's acceptance criterion."""
    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.006, 0.014, 9), currents_A=np.linspace(0, 40, 9),
                         method="transient", progress=False)
    assert "transient" in maps.dataset.attrs["method"]
    scenarios = standard_scenarios(mag, gap_m=0.010, current_A=20.0)
    results = compare_models(mag, mk.CurrentModel(maps), scenarios, gap_m=0.010, current_A=20.0,
                             repeat=0)
    assert {r.scenario.name for r in results} >= {"voltage step up", "gap sine 50 Hz",
                                                   "gap ramp", "closed loop"}
    _check(results)


def test_timing_is_warm_cpu_best_of_repeat() -> None:
    from maglevkit.errors import InputError

    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.006, 0.016, 6),
                         currents_A=np.linspace(0.0, 60.0, 7), progress=False)
    step = [sc for sc in standard_scenarios(mag, gap_m=0.010, current_A=20.0)
            if sc.name == "voltage step up"]
    model = mk.CurrentModel(maps)
    for bad in (-1, 1.5, True):
        with pytest.raises(InputError, match=r"repeat = .*whole number >= 0"):
            compare_models(mag, model, step, gap_m=0.010, current_A=20.0, repeat=bad)
    untimed = compare_models(mag, model, step, gap_m=0.010, current_A=20.0, repeat=0)[0]
    assert untimed.timing_runs == 0
    assert np.isnan(untimed.detailed_cpu_s) and np.isnan(untimed.speedup)
    timed = compare_models(mag, model, step, gap_m=0.010, current_A=20.0, repeat=2)[0]
    assert timed.timing_runs == 2
    assert 0.0 < timed.reduced_cpu_s < math.inf and 0.0 < timed.detailed_cpu_s < math.inf
    # the warm-up run's results are those compared: equal to the untimed comparison
    assert np.array_equal(timed.reduced_currents_A, untimed.reduced_currents_A)
    assert np.array_equal(timed.current_error, untimed.current_error)


def test_cli_compare_has_the_extrapolate_option_its_message_recommends() -> None:
    # the out-of-range message names --extrapolate for command-line users (issue 27)
    from typer.testing import CliRunner

    from maglevkit.cli import app

    r = CliRunner().invoke(app, ["compare", "--help"])
    assert r.exit_code == 0 and "--extrapolate" in r.output
    import numpy as np

    import maglevkit as mk

    maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.004, 0.02, 5),
                         currents_A=np.linspace(0.0, 80.0, 5), progress=False)
    model = mk.CurrentModel(maps)
    state = model.initial_state(gaps_m=0.010, currents_A=20.0)
    with pytest.raises(mk.OutOfRangeError, match="--extrapolate"):
        model.step(state, 1e-3, 40.0, gaps_m=0.05, gap_rates_m_per_s=0.0)   # 50 mm: far outside
