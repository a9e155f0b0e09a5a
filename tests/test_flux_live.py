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
from maglevkit.errors import CompilationWarning
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
    st = fm.initial_state(gaps_m=s[0], currents_A=I0)
    rows = []
    for k in range(N):
        st, out = fm.step(st, DT, u0 * (1.2 if k >= 20 else 1.0), gaps_m=s[k],
                          gap_rates_m_per_s=(s[k + 1] - s[k]) / DT)
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
    _check_live(*(_run(models[k]) for k in ("live", "restart", "reference")))


def _check_live(live: np.ndarray, restart: np.ndarray, ref: np.ndarray) -> None:
    """The bounds of the test above on runs of :func:`_run` (live, restart, rtol 1e-10)."""
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
    st0 = fm.initial_state(gaps_m=0.010, currents_A=I0)
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
    for kwargs in ({"voltages_V": 1.5 * u}, {"voltages_V": u, "gaps_m": 0.011}):
        a = live.initial_state(gaps_m=0.010, currents_A=I0)
        a, _ = live.step(a, DT, u)
        b, _ = live.step(a, DT, **kwargs)
        c, _ = restart.step(a, DT, **kwargs)
        np.testing.assert_allclose(b.currents_A, c.currents_A, rtol=1e-5)
        # quadratures are outside the error test in both paths (as in CasADi)
        np.testing.assert_allclose(b.energy_J, c.energy_J, rtol=1e-3)


def test_live_step_option_is_checked(u_magnet: mk.Magnet) -> None:
    with pytest.raises(mk.InputError, match="live_step"):
        mk.FluxModel(u_magnet, compiled="never", live_step="yes")


def test_a_live_library_that_does_not_load_falls_back_with_a_warning(
        u_magnet: mk.Magnet, cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A missing IDAS symbol (OSError from the loader) gives the restarting step and a
    CompilationWarning, not a failure of the first step (own rtol: an own DAE)."""
    from maglevkit.models import flux as flux_mod

    def broken(*args: object, **kwargs: object) -> None:
        raise OSError("undefined symbol: IDASetStopTime")

    monkeypatch.setattr(flux_mod, "LiveIntegrator", broken)
    fm = mk.FluxModel(u_magnet, compiled="always", cache_dir=cache, rtol=3.3e-7)
    st = fm.initial_state(gaps_m=0.010, currents_A=I0)
    with pytest.warns(CompilationWarning, match="undefined symbol.*restarts IDAS"):
        st1, _ = fm.step(st, DT, float(fm.resistances[0]) * I0)
    assert not fm.live_step and st1.time_s == pytest.approx(DT)


def test_two_threads_stepping_one_model(models: dict[str, mk.FluxModel]) -> None:
    """Threads take turns on the model's one IDAS memory: each thread's run equals the same
    run alone (restarts where the other thread stepped in between)."""
    import threading

    fm, restart = models["live"], models["restart"]
    u = float(fm.resistances[0]) * I0
    results: dict[int, np.ndarray] = {}
    errors: list[BaseException] = []

    def run(j: int) -> None:
        try:
            st = fm.initial_state(gaps_m=0.009 + 0.002 * j, currents_A=I0)
            for _ in range(150):
                st, _ = fm.step(st, DT, (1.1 + 0.1 * j) * u)
            results[j] = st.currents_A
        except BaseException as exc:            # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(j,)) for j in range(3)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors, errors
    for j in range(3):
        st = restart.initial_state(gaps_m=0.009 + 0.002 * j, currents_A=I0)
        for _ in range(150):
            st, _ = restart.step(st, DT, (1.1 + 0.1 * j) * u)
        np.testing.assert_allclose(results[j], st.currents_A, rtol=1e-4)


def test_the_live_reason_quotes_physical_time() -> None:
    from maglevkit.models.flux import _physical_time

    msg = str(_physical_time(RuntimeError("At t = 3.5 and h = 1.2e-05, the corrector "
                                          "convergence failed repeatedly"), 0.01, 1e-3))
    assert msg.startswith("At t = 0.0135 s and h = 1.2e-08 s, the corrector")
    msg = str(_physical_time(RuntimeError("The value tstop = 53 is behind current t = 57.5"),
                             0.0, 1e-3))
    assert msg == "The value tstop = 0.053 s is behind current t = 0.0575 s"


def test_build_source_part_files_are_unique_per_call(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    import subprocess

    outs: list[str] = []

    def fake(cmd: list[str], **kwargs: object) -> subprocess.CompletedProcess[str]:
        outs.append(cmd[cmd.index("-o") + 1])
        return subprocess.CompletedProcess(cmd, 1, "", "error: boom")

    monkeypatch.setattr(compiled_mod, "run_compiler", fake)
    for _ in range(2):
        with pytest.raises(RuntimeError, match="boom"):
            compiled_mod.build_source("x", b"int x;", cache=tmp_path)
    assert len(set(outs)) == 2 and not list(tmp_path.iterdir())


def test_live_step_on_the_sparse_form(u_magnet: mk.Magnet, tmp_path: Path,
                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """The sparse form (``K y' = h``, the split network's) on the live integrator: the same
    bounds as the dense form's test above against a run at rtol 1e-10."""
    from maglevkit.models import flux

    monkeypatch.setattr(flux, "SPARSE_FORM_SIZE", 0)     # the DAE's cache key holds the form
    live = mk.FluxModel(u_magnet, compiled="always", cache_dir=tmp_path)
    restart = mk.FluxModel(u_magnet, compiled="always", cache_dir=tmp_path, live_step=False)
    ref = mk.FluxModel(u_magnet, compiled="always", cache_dir=tmp_path, rtol=1e-10,
                       live_step=False)
    assert live.dae.form == "sparse" and live.live_step
    _check_live(_run(live), _run(restart), _run(ref))
