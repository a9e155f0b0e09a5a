"""Reduced (current-based) vs detailed (flux-based) model: speed-up on the same scenario."""

from __future__ import annotations

import shutil
import time

import numpy as np

import maglevkit as mk
from maglevkit.models.signals import Sine

TITLE = "Reduced vs detailed model: speed-up and real-time factors (1 s simulated, 1 kHz)"

DURATION, DT = 1.0, 1e-3


def _best(fn, repeat: int = 5) -> float:  # type: ignore[no-untyped-def]
    fn()   # warm-up: compiles the batch functions of this grid
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def _case(mag: mk.Magnet, s0: float, i0: float):  # type: ignore[no-untyped-def]
    u0 = mag.network.resistances * i0
    gaps = Sine(s0, 1e-3, 5.0)

    def volts(t: float) -> np.ndarray:
        return u0 * (1.2 if t >= 0.1 else 1.0)

    return gaps, volts


def _stepping(model, mag: mk.Magnet, s0: float, i0: float) -> float:  # type: ignore[no-untyped-def]
    gaps, volts = _case(mag, s0, i0)
    n = int(round(DURATION / DT))
    t = np.arange(n + 1) * DT
    s = gaps(t)
    st = model.initial_state(gaps=s[0], currents=i0)
    t0 = time.perf_counter()
    for k in range(n):
        st, _ = model.step(st, DT, volts(t[k]), gaps=s[k], gap_rates=(s[k + 1] - s[k]) / DT)
    return time.perf_counter() - t0


def run() -> str:
    rows, step_rows = [], []
    for name, s0, i0, grid in (("u-magnet", 0.010, 20.0, (0.004, 0.020, 17, 80.0, 33)),
                               ("tr09-standard", 0.010, 34.0, (0.005, 0.016, 12, 80.0, 41))):
        mag = mk.load_magnet(name)
        t0 = time.perf_counter()
        maps = mk.build_maps(mag, gaps=np.linspace(grid[0], grid[1], grid[2]),
                             currents=np.linspace(0.0, grid[3], grid[4]))
        t_maps = time.perf_counter() - t0
        fm = mk.FluxModel(mag)
        gaps, volts = _case(mag, s0, i0)
        det = mk.simulate(fm, (0, DURATION), dt=DT, gaps=gaps, voltages=volts, initial_currents=i0)
        t_det = _best(lambda fm=fm, gaps=gaps, volts=volts, i0=i0: mk.simulate(
            fm, (0, DURATION), dt=DT, gaps=gaps, voltages=volts, initial_currents=i0))
        variants = [("rk4", {}), ("cvodes", {"method": "cvodes"})]
        if shutil.which("gcc") or shutil.which("cc"):
            variants.insert(1, ("rk4, jit=True", {"jit": True}))
        for method, opts in variants:
            cm = mk.CurrentModel(maps, **opts)
            red = mk.simulate(cm, (0, DURATION), dt=DT, gaps=gaps, voltages=volts,
                              initial_currents=i0)
            t_red = _best(lambda cm=cm, gaps=gaps, volts=volts, i0=i0: mk.simulate(
                cm, (0, DURATION), dt=DT, gaps=gaps, voltages=volts, initial_currents=i0))
            err_i = np.sqrt(np.mean((red.currents_A - det.currents_A) ** 2)) / np.sqrt(
                np.mean(det.currents_A ** 2))
            err_f = np.sqrt(np.mean((red.force_N - det.force_N) ** 2)) / np.sqrt(
                np.mean(det.force_N ** 2))
            rows.append(f"| {name} | {method} | {t_det * 1e3:.0f} | {t_red * 1e3:.2f} | "
                        f"**{t_det / t_red:.0f}** | {DURATION / t_det:.2f} | "
                        f"{DURATION / t_red:.0f} | {100 * err_i:.2f} | {100 * err_f:.2f} |")
        cm = mk.CurrentModel(maps)
        t_sd = min(_stepping(fm, mag, s0, i0) for _ in range(2))
        t_sr = min(_stepping(cm, mag, s0, i0) for _ in range(3))
        step_rows.append(f"| {name} | {t_sd / DURATION * 1e3:.0f} | {t_sr / DURATION * 1e3:.0f} | "
                         f"{t_sd / t_sr:.0f} | {DURATION / t_sd:.2f} | {DURATION / t_sr:.1f} |")
        rows_maps = f"maps of {name}: {t_maps:.2f} s"
        step_rows.append(f"<!-- {rows_maps} -->")
        if name == "tr09-standard":
            std_rows = _standard_set(mag, maps, s0, i0)
    return (
        f"Same inputs for both models: gaps {10} +- 1 mm at 5 Hz, voltage +20 % at 0.1 s, "
        f"{DURATION:g} s at a {DT * 1e3:g} ms output/hold step, started at the nominal point "
        "(U-magnet 20 A, TR09 34 A). Wall times are the best of 5 warm runs; the detailed "
        "model is IDAS (rtol 1e-6), the reduced model RK4 with 1 ms sub-steps (default) or "
        "CVODES (rtol 1e-8, restarted at every input change), or RK4 compiled to machine "
        "code by CasADi's JIT (opt-in, needs a C compiler). NRMS errors: RMS of the "
        "difference over RMS of the detailed signal; both magnets with eddy currents and "
        "saturable iron, maps with the step-fitted `R_ec` (docs/reduction.md).  Map "
        "generation time is in the maps section.\n\n"
        "| magnet | reduced integrator | detailed [ms] | reduced [ms] | speed-up | "
        "RTF detailed | RTF reduced | current NRMS [%] | force NRMS [%] |\n"
        "|---|---|---|---|---|---|---|---|---|\n" + "\n".join(rows)
        + "\n\nStepping interface (one Python call per millisecond, as in a co-simulation):\n\n"
        "| magnet | detailed [us/step] | reduced [us/step] | speed-up | RTF detailed | "
        "RTF reduced |\n|---|---|---|---|---|---|\n"
        + "\n".join(r for r in step_rows if not r.startswith("<!--"))
        + "\n\nThe standard comparison set of `maglevkit compare` on TR09 (each scenario run "
        "once per model, cold, as the CLI and `make demo` do; default reduced model, "
        "interpreted RK4; the closed loop is a Python co-simulation loop of model `step`, "
        "heave mass and controller at 1 kHz, so its ratio is bounded by the loop's own "
        "overhead):\n\n"
        "| scenario | simulated [s] | detailed [ms] | reduced [ms] | speed-up | "
        "current NRMS [%] | force NRMS [%] |\n|---|---|---|---|---|---|---|\n"
        + "\n".join(std_rows))


def _standard_set(mag: mk.Magnet, maps, s0: float, i0: float) -> list[str]:  # type: ignore[no-untyped-def]
    from maglevkit.compare import compare_models, standard_scenarios

    results = compare_models(mk.FluxModel(mag), mk.CurrentModel(maps),
                             standard_scenarios(mag, gap_m=s0, current_A=i0),
                             gap_m=s0, current_A=i0)
    rows = []
    for r in results:
        rows.append(f"| {r.scenario.name} | {r.scenario.duration_s:.3g} | "
                    f"{r.detailed_wall_s * 1e3:.0f} | {r.reduced_wall_s * 1e3:.1f} | "
                    f"**{r.speedup:.0f}** | {100 * float(np.max(r.current_error)):.3f} | "
                    f"{100 * float(np.max(r.force_error)):.3f} |")
    return rows
