"""Real-time factor of the flux-based dynamic model: compiled vs interpreted, compile cost."""

from __future__ import annotations

import copy
import resource
import tempfile
import time

import numpy as np

import maglevkit as mk
from maglevkit.magnets.base import build_magnet
from maglevkit.models.compiled import find_compiler
from maglevkit.models.signals import Sine

TITLE = "Flux model: real-time factor, compiled vs interpreted (1 s simulated, 1 kHz)"

DURATION = 1.0   # s simulated
DT = 1e-3        # s, hold / co-simulation step
#: (magnet, variant or None for the bundled file, nominal current [A], repetitions): the
#: bundled TR09 file is the split network since issue 26 (253 loops, short loops on the
#: sparse form) with the eddy ladder since switch26m; "lumped": the same network with the
#: lumped eddy elements (its default before switch26m); "paper": the lumped "paper" network
#: with lumped eddy elements, the default before the split network, for comparison
CASES = (("u-magnet", None, 20.0, 3), ("tr09-standard", None, 34.0, 3),
         ("tr09-standard", "lumped", 34.0, 3), ("tr09-standard", "paper", 34.0, 3))


def _magnet(name: str, variant: str | None) -> mk.Magnet:
    """The bundled magnet, or a variant: ``"lumped"`` (the file with the lumped eddy elements),
    ``"paper"`` (the ``"paper"`` network with lumped eddy elements and eq. 8's default)."""
    if variant is None:
        return mk.load_magnet(name)
    if variant == "lumped":
        return mk.load_magnet(name, eddy_model="lumped")
    params = copy.deepcopy(mk.load_magnet(name).parameters)
    params["magnet"]["flux_paths"] = variant
    params["magnet"].pop("coil_segments", None)         # a key of the split network only
    for key in ("eddy_model", "eddy_layers"):           # the file's ladder: the variant is lumped
        params["magnet"].pop(key, None)
        params["provenance"].pop(f"magnet.{key}", None)
    params.pop("reduced", None)
    params["provenance"].pop("reduced.eddy_modes", None)
    params["provenance"]["magnet.flux_paths"] = "[E] benchmark variant"
    return build_magnet(params)


def _cpu() -> float:
    return time.process_time()


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _scenario(mag: mk.Magnet, i0: float):  # type: ignore[no-untyped-def]
    """bench_reduced.py's standard scenario: gaps 10 +- 1 mm at 5 Hz, +20 % voltage at 0.1 s."""
    u0 = mag.network.resistances * i0

    def volts(t: float) -> np.ndarray:
        return u0 * (1.2 if t >= 0.1 else 1.0)

    return Sine(0.010, 1e-3, 5.0), volts


def _simulate(fm: mk.FluxModel, mag: mk.Magnet, i0: float) -> float:
    gaps, volts = _scenario(mag, i0)
    t0 = _cpu()
    mk.simulate(fm, (0.0, DURATION), dt_s=DT, gaps_m=gaps, voltages_V=volts, initial_currents_A=i0)
    return _cpu() - t0


def _stepping(fm: mk.FluxModel, mag: mk.Magnet, i0: float) -> float:
    gaps, volts = _scenario(mag, i0)
    n = int(round(DURATION / DT))
    t = np.arange(n + 1) * DT
    s = gaps(t)
    st = fm.initial_state(gaps_m=s[0], currents_A=i0)
    t0 = _cpu()
    for k in range(n):
        st, _out = fm.step(st, DT, volts(t[k]), gaps_m=s[k], gap_rates_m_per_s=(s[k + 1] - s[k]) / DT)
    return _cpu() - t0


def _live_counts(fm: mk.FluxModel, mag: mk.Magnet, i0: float) -> tuple[float, int, int]:
    """One untimed live run of the scenario: (IDAS steps per call, sparse and dense LU
    setups of the preconditioner); the live integrator's counters (steps since its last
    restart, setups since it was made)."""
    gaps, volts = _scenario(mag, i0)
    n = int(round(DURATION / DT))
    t = np.arange(n + 1) * DT
    s = gaps(t)
    st = fm.initial_state(gaps_m=s[0], currents_A=i0)
    first = fm.live_stats()
    assert first is not None
    steps, last, now = 0, first["steps"], first
    for k in range(n):
        st, _out = fm.step(st, DT, volts(t[k]), gaps_m=s[k], gap_rates_m_per_s=(s[k + 1] - s[k]) / DT)
        now = fm.live_stats()
        assert now is not None
        steps += now["steps"] - last if now["steps"] >= last else now["steps"]
        last = now["steps"]
    return (steps / n, now["sparse_setups"] - first["sparse_setups"],
            now["dense_setups"] - first["dense_setups"])


def run() -> str:
    rows, cost_rows = [], []
    modes = ("never", "always") if find_compiler() else ("never",)
    with tempfile.TemporaryDirectory(prefix="maglevkit-bench-flux-") as cache:
        for name, paths, i0, reps in CASES:
            label_m = name if paths is None else f"{name} ({paths})"
            for mode in modes:
                mag = _magnet(name, paths)
                c0, k0, w0 = _cpu(), _children_cpu(), time.perf_counter()
                fm = mk.FluxModel(mag, compiled=mode, cache_dir=cache)
                t_build = (_cpu() - c0, _children_cpu() - k0, time.perf_counter() - w0)
                if mode == "always":
                    c0, w0 = _cpu(), time.perf_counter()
                    mk.FluxModel(_magnet(name, paths), compiled=mode, cache_dir=cache)
                    t_load = (_cpu() - c0, time.perf_counter() - w0)
                    cost_rows.append(f"| {label_m} | {t_build[0]:.2f} | {t_build[1]:.2f} | "
                                     f"{t_build[2]:.1f} | {t_load[0]:.2f} | {t_load[1]:.2f} |")
                c0 = _cpu()
                _simulate(fm, mag, i0)                       # warm-up (builds the chunks)
                t_first = _cpu() - c0
                t_sim = min(_simulate(fm, mag, i0) for _ in range(reps))
                # step: CasADi's integrator restarted per call (before issue 22) and, where
                # compiled, the live integrator kept between calls; alternating, best of 3
                restart = fm.with_options(live_step=False)
                live = fm if fm.live_step else None
                t_restart, t_live = [], []
                for _ in range(reps):
                    t_restart.append(_stepping(restart, mag, i0))
                    if live is not None:
                        t_live.append(_stepping(live, mag, i0))
                t_step = min(t_live or t_restart)
                counts = _live_counts(live, mag, i0) if live is not None else None
                label = "compiled" if fm.compiled else "interpreted"
                rtf_live = f"{DURATION / min(t_live):.2f}" if t_live else "-"
                ratio = f"{min(t_restart) / min(t_live):.1f}x" if t_live else "-"
                rows.append(f"| {label_m} | {label} | {fm.dae.n_loops + fm.dae.n_circuits} | "
                            f"{fm.dae.form} | {len(fm.differential_state_names)} | "
                            f"{t_first:.2f} | {DURATION / t_sim:.2f} | {DURATION / min(t_restart):.2f} | "
                            f"{rtf_live} | {ratio} | {t_step / (DURATION / DT) * 1e6:.0f} | "
                            + (f"{counts[0]:.2f} | {counts[1]} / {counts[2]} |" if counts
                               else "- | - |"))
    return (
        f"Standard scenario of the reduced-model benchmark: {DURATION:g} s at a {DT * 1e3:g} ms "
        "hold, gaps 10 +- 1 mm at 5 Hz, voltage +20 % at 0.1 s, from the nominal point "
        "(U-magnet 20 A, TR09 34 A), eddy currents and saturable iron, IDAS rtol 1e-6.  "
        "Real-time factor = simulated seconds per CPU second of this process (best of 3; the "
        "machine is shared, CPU time is steadier than wall time).  *tr09-standard*: the bundled "
        "file, the split network since issue 26 (on the fundamental loops and the dense form it "
        "took 27.5 s CPU per simulated second interpreted and did not compile, "
        "docs/decisions.md, splitfast), with the eddy ladder (6 layers) since switch26m; "
        "*tr09-standard (lumped)*: the same with the lumped eddy elements, its default before "
        "switch26m; *tr09-standard (paper)*: the file with `flux_paths = \"paper\"` and the "
        "lumped eddy elements, the network that was the default before issue 26.  *unknowns*: loop "
        "fluxes and currents; *form*: the DAE form IDAS runs (dense up to 100 unknowns, "
        "sparse above, `SPARSE_FORM_SIZE`); *first simulate*: CPU time of the first run "
        "(it builds the integrators).  `simulate` runs IDAS "
        "through hold intervals of equal voltages (restart where they change, at most every "
        "128 intervals); `step` is one Python call per millisecond (a co-simulation): "
        "*restart* = CasADi's IDAS set up and restarted on every call (`live_step=False`, the "
        "only path before issue 22), *live* = one IDAS kept between calls, restarted only "
        "where an input jumps (models/flux_live.py; compiled models only), both measured "
        "alternately in this run, best of 3; *us per step call* is the faster.  *IDAS steps "
        "per live call*, *LU setups sparse / dense*: from one more (untimed) live run, the "
        "preconditioner's factorisations on the sparse LU's fixed pattern and in the dense "
        "LU (a fallback where a static pivot is tiny; livestep22).  *compiled*: "
        "residual, Jacobian, quadrature and output functions as one C library "
        "(`compiled='always'`, cc -O1; the live step's library -O3); *interpreted*: the same functions "
        "on CasADi's virtual machine.\n\n"
        "| magnet | functions | unknowns | form | differential states | first simulate CPU [s] "
        "| RTF simulate | RTF step (restart) | RTF step (live) | live / restart | "
        "us per step call | IDAS steps per live call | LU setups sparse / dense |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n" + "\n".join(rows)
        + "\n\nCompile and load cost (first model of a network: code generation in this "
        "process + the C compiler's CPU time in child processes, wall time; a second model "
        "finds the library in the on-disk cache):\n\n"
        "| magnet | build CPU [s] | compiler CPU [s] | build wall [s] | cached load CPU [s] | "
        "cached load wall [s] |\n|---|---|---|---|---|---|\n" + "\n".join(cost_rows))
