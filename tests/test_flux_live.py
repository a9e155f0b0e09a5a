"""FluxModel.step on a live IDAS integrator (issue 22, item 4): it integrates on between calls
where nothing jumped and restarts where something did; its results equal those of the
restart-every-call path (``live_step=False``) to the integrator's accuracy.

The bundled U-magnet with eddy currents (eddy states, saturable iron), compiled once into a
temporary cache for this module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import maglevkit as mk
from maglevkit.models import compiled as compiled_mod
from maglevkit.models.signals import Sine

pytestmark = pytest.mark.skipif(compiled_mod.find_compiler() is None,
                                reason="no C compiler on this machine")

DT = 1e-3
N = 60                      # steps; the voltage jumps +20 % at step 20
I0 = 20.0                   # A


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("maglevkit-flux-live")


@pytest.fixture(scope="module")
def models(u_magnet: mk.Magnet, cache: Path) -> dict[str, mk.FluxModel]:
    return {"live": mk.FluxModel(u_magnet, compiled="always", cache_dir=cache),
            "restart": mk.FluxModel(u_magnet, compiled="always", cache_dir=cache,
                                    live_step=False),
            "reference": mk.FluxModel(u_magnet, compiled="always", cache_dir=cache,
                                      rtol=1e-10, live_step=False)}


def _run(fm: mk.FluxModel) -> np.ndarray:
    """Co-simulation: 1 ms calls, gaps 10 +- 1 mm at 20 Hz, +20 % voltage at step 20.
    Rows: currents [A], force [N], differential state, energies [J]."""
    t = np.arange(N + 1) * DT
    s = np.asarray(Sine(0.010, 1e-3, 20.0)(t), dtype=float)
    u0 = float(fm.resistances[0]) * I0
    st = fm.initial_state(gaps=s[0], currents=I0)
    rows = []
    for k in range(N):
        st, out = fm.step(st, DT, u0 * (1.2 if k >= 20 else 1.0), gaps=s[k],
                          gap_rates=(s[k + 1] - s[k]) / DT)
        rows.append(np.concatenate((st.currents_A, [out.force_N], st.differential_state,
                                    st.energy_J)))
    return np.array(rows)


def test_live_step_is_used_where_compiled(models: dict[str, mk.FluxModel]) -> None:
    assert models["live"].live_step and not models["restart"].live_step
    assert not mk.FluxModel(models["live"], compiled="never").live_step


def test_live_step_equals_the_restarting_step_to_the_integrator_accuracy(
        models: dict[str, mk.FluxModel]) -> None:
    """Against a run at rtol 1e-10 the live integrator's error is at most that of the
    restart-every-call path (times 3, plus 1e-7 of the signal's range), column by column;
    and the two differ by less than 1e-4 of each signal's largest value (energies 1e-3)."""
    live, restart, ref = (_run(models[k]) for k in ("live", "restart", "reference"))
    scale = np.abs(ref).max(axis=0)
    err_live = (np.abs(live - ref) / scale).max(axis=0)
    err_restart = (np.abs(restart - ref) / scale).max(axis=0)
    assert np.all(err_live <= 3.0 * err_restart + 1e-7), (err_live, err_restart)
    diff = (np.abs(live - restart) / scale).max(axis=0)
    assert diff[:-4].max() < 1e-4 and diff[-4:].max() < 1e-3, diff


def test_a_state_other_than_the_last_restarts(models: dict[str, mk.FluxModel],
                                              u_magnet: mk.Magnet, cache: Path) -> None:
    """Stepping an older state (or the same state twice) restarts IDAS from it: the result
    is bit-identical to a fresh model's first step from that state."""
    fm = models["live"]
    u = float(fm.resistances[0]) * I0
    st0 = fm.initial_state(gaps=0.010, currents=I0)
    st1, _ = fm.step(st0, DT, 1.1 * u)
    on, _ = fm.step(st1, DT, 1.1 * u)          # integrates on from st1
    again, _ = fm.step(st1, DT, 1.1 * u)       # st1 is no longer the last state: restart
    fresh, _ = mk.FluxModel(u_magnet, compiled="always", cache_dir=cache).step(st1, DT, 1.1 * u)
    np.testing.assert_array_equal(again.currents_A, fresh.currents_A)
    np.testing.assert_array_equal(again.differential_state, fresh.differential_state)
    np.testing.assert_allclose(on.currents_A, again.currents_A, rtol=1e-5)


def test_a_voltage_or_gap_jump_restarts_with_consistent_currents(
        models: dict[str, mk.FluxModel]) -> None:
    """A jump of the voltages or the gaps between calls restarts: the live step then equals
    the restarting step to the integrator's accuracy, not the continuation's."""
    live, restart = models["live"], models["restart"]
    u = float(live.resistances[0]) * I0
    for kwargs in ({"voltages": 1.5 * u}, {"voltages": u, "gaps": 0.011}):
        a = live.initial_state(gaps=0.010, currents=I0)
        a, _ = live.step(a, DT, u)
        b, _ = live.step(a, DT, **kwargs)
        c, _ = restart.step(a, DT, **kwargs)
        np.testing.assert_allclose(b.currents_A, c.currents_A, rtol=1e-5)
        # quadratures are outside the error test in both paths (as in CasADi)
        np.testing.assert_allclose(b.energy_J, c.energy_J, rtol=1e-3)


def test_live_step_option_is_checked(u_magnet: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match="live_step"):
        mk.FluxModel(u_magnet, compiled="never", live_step="yes")
