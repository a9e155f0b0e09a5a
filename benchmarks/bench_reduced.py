"""Reduced (current-based) vs detailed (flux-based) model: speed-up on the same scenario.

Each magnet is compared as its file builds it and names it: the detailed model of the
file's eddy model (the bundled TR09 files: the diffusing ``"ladder"``, since switch26m)
against the reduced model the maps name, ``CurrentModel(maps,
eddy_modes=default_eddy_modes(maps))`` (TR09: the 2-branch eddy network; the U-magnet:
eq. 8), as compare, demo, the FMU and the vehicles take it.  Where that is not eq. 8, eq. 8
on the same maps (``CurrentModel(maps)``, the library's building-block default and the
paper's form) is a labelled second row.
Every time is CPU time (``time.process_time``) of a warm call, the best of ``REPEAT``
(one untimed call first: compilation, caches), and every ratio is taken between times
measured in this one run, so that a loaded machine shifts both sides alike.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit.models.signals import Sine, Step
from maglevkit.reduction import default_eddy_modes

TITLE = "Reduced vs detailed model: speed-up and real-time factors (1 s simulated, 1 kHz)"

DURATION, DT = 1.0, 1e-3
REPEAT = 5


def _best(fn: Callable[[], Any], repeat: int = REPEAT) -> float:
    """CPU time [s] of ``fn()``: the best of ``repeat`` calls after one untimed call."""
    fn()
    out = []
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        out.append(time.process_time() - c0)
    return min(out)


def _case(mag: mk.Magnet, s0: float, i0: float) -> tuple[Any, dict, Callable[[float], Any]]:
    """Gaps 10 +- 1 mm at 5 Hz; voltage +20 % at 0.1 s, as Signals (sampled as arrays) and
    as a Python callable of t (sampled one call per time)."""
    u0 = mag.network.resistances * i0
    signals = {c: Step(float(u0[j]), 1.2 * float(u0[j]), 0.1)
               for j, c in enumerate(mag.network.circuit_names)}

    def volts(t: float) -> np.ndarray:
        return u0 * (1.2 if t >= 0.1 else 1.0)

    return Sine(s0, 1e-3, 5.0), signals, volts


def _stepping(model: Any, mag: mk.Magnet, s0: float, i0: float) -> Callable[[], None]:
    gaps, _, volts = _case(mag, s0, i0)
    n = int(round(DURATION / DT))
    t = np.arange(n + 1) * DT
    s = np.repeat(gaps(t)[:, None], len(mag.network.gap_names), axis=1)
    u = np.array([volts(float(x)) for x in t])
    rates = np.diff(s, axis=0) / DT

    def run() -> None:
        st = model.initial_state(gaps_m=s[0], currents_A=i0)
        for k in range(n):
            st, _ = model.step(st, DT, u[k], gaps_m=s[k], gap_rates_m_per_s=rates[k])
    return run


def _bank_stepping(maps: mk.CharacteristicMaps, mag: mk.Magnet, s0: float,
                   i0: float, eddy_modes: int = 0) -> Callable[[], None]:
    bank = mk.MagnetBank({"m": maps}, eddy_modes=eddy_modes)
    gaps, _, volts = _case(mag, s0, i0)
    n = int(round(DURATION / DT))
    t = np.arange(n + 1) * DT
    g = np.repeat(gaps(t)[:, None], bank.n_gaps, axis=1)
    u = np.array([volts(float(x)) for x in t])
    rates = np.diff(g, axis=0) / DT

    def run() -> None:
        stepper = bank.stepper(bank.initial_state(gaps_m=g[0], currents_A=i0), DT)
        for k in range(n):
            stepper.advance(u[k], g[k], rates[k])
    return run


def _compiled_loop(maps: mk.CharacteristicMaps, red: Any) -> Callable[[], None]:
    """The compiled time loop of a reduced ``simulate`` (eq. 8) alone:
    ``MagnetBank.run_steps`` on the run's sampled inputs (substitute gaps, held voltages,
    gap rates; step 0 of length 0 as ``simulate`` runs it)."""
    bank = mk.MagnetBank({"m": maps})
    avg = np.zeros((bank.n_circuits, len(red.gap_names)))
    for j, c in enumerate(red.circuit_names):
        for g in maps.pole_groups[c]:
            avg[j, red.gap_names.index(g)] = 1.0 / len(maps.pole_groups[c])
    s = red.gaps_m @ avg.T
    sd = red.gap_rates_m_per_s @ avg.T
    h = np.concatenate([[0.0], np.diff(red.time_s)])
    s_k = np.vstack((s[:1], s[:-1]))
    u_k = np.vstack((red.voltages_V[:1], red.voltages_V[:-1]))
    sd_k = np.vstack((np.zeros((1, bank.n_circuits)), sd[:-1]))
    i0 = red.inductor_currents_A[0]

    def run() -> None:
        bank.run_steps(i0, s_k, u_k, sd_k, h)
    return run


def run() -> str:
    rows, step_rows, aims, configs = [], [], [], []
    std_rows: list[str] = []
    for name, s0, i0, grid in (("u-magnet", 0.010, 20.0, (0.004, 0.020, 17, 80.0, 33)),
                               ("tr09-standard", 0.010, 34.0, (0.005, 0.016, 12, 80.0, 41))):
        mag = mk.load_magnet(name)
        maps = mk.build_maps(mag, gaps_m=np.linspace(grid[0], grid[1], grid[2]),
                             currents_A=np.linspace(0.0, grid[3], grid[4]), progress=False)
        m = default_eddy_modes(maps)
        red_label = f"eddy network m = {m}" if m else "eq. 8"
        opts = mag.options
        det_label = opts.eddy_model + (f" ({opts.eddy_layers} layers)"
                                       if opts.eddy_model.startswith("ladder") else "")
        configs.append(f"{name}: detailed eddy model {det_label!r}, "
                       f"{len(mag.network.branches)} branches; reduced default {red_label}")
        fm = mk.FluxModel(mag)
        gaps, signals, volts = _case(mag, s0, i0)

        def sim(model: Any, voltages: Any, gaps: Any = gaps, i0: float = i0) -> Any:
            return mk.simulate(model, (0, DURATION), dt_s=DT, gaps_m=gaps, voltages_V=voltages,
                               initial_currents_A=i0)

        det = sim(fm, signals)
        t_det = _best(lambda fm=fm, signals=signals: sim(fm, signals), repeat=3)
        dm = {"eddy_modes": m}
        variants: list[tuple[str, dict, Any]] = [
            (f"{red_label}: RK4 on the compiled tables (default), Signal inputs", dm, signals),
            (f"{red_label}: RK4 on the compiled tables (default), Python callable", dm, volts),
            (f"{red_label}: RK4 on B-splines (lookup='bspline')", dm | {"lookup": "bspline"},
             signals),
            (f"{red_label}: CVODES (method='cvodes')", dm | {"method": "cvodes"}, signals)]
        if m:
            variants.append(("eq. 8 (paper's form, `eddy_modes=0`): RK4 on the compiled "
                             "tables, Signal inputs", {}, signals))
        for label, kw, voltages in variants:
            cm = mk.CurrentModel(maps, **kw)
            red = sim(cm, voltages)
            t_red = _best(lambda cm=cm, voltages=voltages: sim(cm, voltages))
            err_i = np.sqrt(np.mean((red.currents_A - det.currents_A) ** 2)) / np.sqrt(
                np.mean(det.currents_A ** 2))
            err_f = np.sqrt(np.mean((red.force_N - det.force_N) ** 2)) / np.sqrt(
                np.mean(det.force_N ** 2))
            rows.append(f"| {name} | {label} | {t_det * 1e3:.0f} | {t_red * 1e3:.3f} | "
                        f"**{t_det / t_red:.0f}** | {DURATION / t_det:.2f} | "
                        f"{DURATION / t_red:.0f} | {100 * err_i:.2f} | {100 * err_f:.2f} |")
            if name == "tr09-standard" and kw == dm and voltages is signals:
                aims.append(f"reduced `simulate` / detailed `simulate` ({red_label} / "
                            f"{det_label}): **{t_det / t_red:.0f}x** (aim >= 1000x)")
            if name == "tr09-standard" and not kw and voltages is signals:
                t_loop = _best(_compiled_loop(maps, red))
                aims.append(f"eq. 8 on the same maps / detailed: {t_det / t_red:.0f}x (of its "
                            f"{t_red * 1e6:.0f} us the compiled time loop alone, "
                            f"`MagnetBank.run_steps` on the same sampled inputs, takes "
                            f"{t_loop * 1e6:.0f} us)")
        t_sd = _best(_stepping(fm, mag, s0, i0), repeat=2)
        n = DURATION / DT
        steppers = [(f"{red_label}: tables (default)", mk.CurrentModel(maps, eddy_modes=m)),
                    (f"{red_label}: B-splines", mk.CurrentModel(maps, eddy_modes=m,
                                                                 lookup="bspline"))]
        if m:
            steppers.append(("eq. 8: tables", mk.CurrentModel(maps)))
        for label, model in steppers:
            t_sr = _best(_stepping(model, mag, s0, i0), repeat=3)
            step_rows.append(f"| {name} | {label} | {t_sd / n * 1e6:.0f} | {t_sr / n * 1e6:.2f} | "
                             f"{t_sd / t_sr:.0f} | {DURATION / t_sd:.2f} | {DURATION / t_sr:.0f} |")
            if name == "tr09-standard" and "tables" in label:
                aims.append(f"`CurrentModel.step` ({label.split(':')[0]}): "
                            f"**{t_sr / n * 1e6:.1f} us** per call (aim <= 5 us)")
        t_bank = _best(_bank_stepping(maps, mag, s0, i0, m), repeat=3)
        step_rows.append(f"| {name} | {red_label}: bank stepper (`MagnetBank.stepper`) | "
                         f"{t_sd / n * 1e6:.0f} "
                         f"| {t_bank / n * 1e6:.2f} | {t_sd / t_bank:.0f} | "
                         f"{DURATION / t_sd:.2f} | {DURATION / t_bank:.0f} |")
        if name == "tr09-standard":
            std_rows, median = _standard_set(mag, maps, s0, i0, m)
            aims.append(f"`compare` standard set ({red_label}), open-loop median (coupling "
                        f"case excluded, as `make demo`): **{median:.0f}x** (aim >= 300x)")
    return (
        "Same inputs for both models: gaps 10 +- 1 mm at 5 Hz, voltage +20 % at 0.1 s, "
        f"{DURATION:g} s at a {DT * 1e3:g} ms output/hold step, started at the nominal point "
        "(U-magnet 20 A, TR09 34 A). Times are CPU times (process_time) of warm calls, the "
        f"best of {REPEAT} (detailed: 3) after one untimed call, all measured in this one run; "
        "the detailed model is IDAS (rtol 1e-6), the reduced model RK4 with 1 ms sub-steps "
        "(the eddy network: at most its stable step) on the compiled per-cell tables "
        "(default: one compiled loop over all steps, `MagnetBank.run_steps` for eq. 8, the "
        "bank's compiled step in a compiled CasADi loop for the network), on CasADi "
        "B-splines per interval, or CVODES (rtol 1e-8, "
        "restarted at every input change). Inputs as `Signal`s are sampled as arrays; a "
        "Python callable of t is called once per sample (its cost is in the row). NRMS "
        "errors: RMS of the difference over RMS of the detailed signal; both magnets with "
        "eddy currents and saturable iron, each as its file builds it and with the reduced "
        "model its maps name (`default_eddy_modes(maps)`; eq. 8 with the step-fitted "
        "`R_ec` as a second row where that is not eq. 8): " + "; ".join(configs) + ".\n\n"
        "Issue 22's aims (TR09): " + "; ".join(aims) + ".\n\n"
        "| magnet | reduced model | detailed [ms] | reduced [ms] | speed-up | "
        "RTF detailed | RTF reduced | current NRMS [%] | force NRMS [%] |\n"
        "|---|---|---|---|---|---|---|---|---|\n" + "\n".join(rows)
        + "\n\nStepping interface (one Python call per millisecond, as in a co-simulation; "
        "CPU time per call):\n\n"
        "| magnet | reduced model | detailed [us/step] | reduced [us/step] | speed-up | "
        "RTF detailed | RTF reduced |\n|---|---|---|---|---|---|---|\n" + "\n".join(step_rows)
        + "\n\nThe standard comparison set of `maglevkit compare` on TR09 (as the CLI and "
        "`make demo` time it: CPU time, best of 3 warm runs per model; the maps' default "
        "reduced model, as `compare` takes it; "
        "the closed loop is a Python co-simulation loop of model `step`, heave mass and "
        "controller at 1 kHz, so its ratio is bounded by the loop's own overhead):\n\n"
        "| scenario | simulated [s] | detailed [ms] | reduced [ms] | speed-up | "
        "current NRMS [%] | force NRMS [%] |\n|---|---|---|---|---|---|---|\n"
        + "\n".join(std_rows))


def _standard_set(mag: mk.Magnet, maps: mk.CharacteristicMaps, s0: float,
                  i0: float, eddy_modes: int) -> tuple[list[str], float]:
    from maglevkit.compare import compare_models, standard_scenarios

    results = compare_models(mk.FluxModel(mag), mk.CurrentModel(maps, eddy_modes=eddy_modes),
                             standard_scenarios(mag, gap_m=s0, current_A=i0),
                             gap_m=s0, current_A=i0, repeat=3)
    rows = []
    for r in results:
        rows.append(f"| {r.scenario.name} | {r.scenario.duration_s:.3g} | "
                    f"{r.detailed_cpu_s * 1e3:.0f} | {r.reduced_cpu_s * 1e3:.2f} | "
                    f"**{r.speedup:.0f}** | {100 * float(np.max(r.current_error)):.3f} | "
                    f"{100 * float(np.max(r.force_error)):.3f} |")
    # as make demo reports it: the open-loop cases without the coupling case
    median = float(np.median([r.speedup for r in results
                              if r.scenario.kind == "open" and not r.scenario.coupling]))
    return rows, median
