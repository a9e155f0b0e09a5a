"""Calibration's voltage steps: one step evaluation (response and exact parameter
derivatives) and a step fit, the SX Radau steps against CasADi's collocation integrator
(the scheme before, ``calibration._STEP_SCHEME = "casadi"``), in the same run."""

from __future__ import annotations

import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit import calibration
from maglevkit.calibration import DEFAULT_PARAMETERS, PARAMETERS, calibrate

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem_u_magnet_calibration import STEP_HOLDOUT, fem_steps  # noqa: E402

TITLE = "Calibration: voltage-step evaluation and fit (U-magnet, transient FEM steps)"

#: the five static factors and the eddy conductance scale (cal25's joint fit's set)
NAMES = (*DEFAULT_PARAMETERS, "eddy_conductance_scale")


def _cpu(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """Best CPU time [s] of ``repeat`` calls, and the last result."""
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def _magnet(layers: int) -> mk.Magnet:
    return (mk.load_magnet("u-magnet") if layers == 0 else
            mk.load_magnet("u-magnet", eddy_model="ladder", eddy_layers=layers))


def _evaluation_rows() -> list[str]:
    """One step (the FEM's 10 mm, 10 -> 20 A, 17 thinned samples) with six parameters,
    off nominal: build and one evaluation per scheme, and their differences."""
    step = fem_steps().steps[0]
    values = np.array([PARAMETERS[n].nominal for n in NAMES]) + 0.02 * np.array(
        [PARAMETERS[n].scale for n in NAMES])
    rows = []
    for layers in (0, 2, 6):
        net = _magnet(layers).network
        res: dict[str, tuple[float, float, np.ndarray, np.ndarray]] = {}
        for scheme in ("casadi", "radau"):
            t = time.process_time()
            model = calibration._ParametricStep(
                net, NAMES, gap_m=step.gap_m, current_A=step.initial_current_A,
                times_s=step.time_s, circuit=0, voltage_V=step.voltage_V, scheme=scheme)
            build = time.process_time() - t
            repeat = 1 if (layers == 6 and scheme == "casadi") else 2
            cpu, (cur, jac) = _cpu(lambda model=model: model.evaluate(values), repeat)
            res[scheme] = (build, cpu, cur, jac)
        (b0, c0, cur0, jac0), (b1, c1, cur1, jac1) = res["casadi"], res["radau"]
        change = float(np.max(np.abs(cur0 - step.initial_current_A)))
        rows.append(
            f"| {'lumped' if layers == 0 else f'ladder, {layers} layers'} | {b0:.2f} / {b1:.2f} "
            f"| {c0:.2f} | {c1:.2f} | {c0 / c1:.1f} "
            f"| {np.max(np.abs(cur1 - cur0)) / change:.1e} "
            f"| {np.max(np.abs(jac1 - jac0)) / np.max(np.abs(jac0)):.1e} |")
    return rows


def _fit_rows() -> list[str]:
    """``k_e`` on three FEM steps (the fourth held out) with the 2-layer ladder."""
    data = fem_steps()
    mag = _magnet(2)
    out: dict[str, tuple[float, Any]] = {}
    old = calibration._STEP_SCHEME
    try:
        for scheme in ("casadi", "radau"):
            calibration._STEP_SCHEME = scheme
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out[scheme] = _cpu(lambda: calibrate(
                    mag, None, steps=data, parameters=["eddy_conductance_scale"],
                    holdout_steps=[STEP_HOLDOUT]), 1)
    finally:
        calibration._STEP_SCHEME = old
    (c0, r0), (c1, r1) = out["casadi"], out["radau"]
    k0, k1 = (r.values["eddy_conductance_scale"] for r in (r0, r1))
    return [f"| ladder, 2 layers, `k_e` | {c0:.1f} | {c1:.1f} | {c0 / c1:.1f} | {k0:.6f} / "
            f"{k1:.6f} ({abs(k1 - k0):.1e}) | {100 * r0.max_error('step_holdout'):.3f} / "
            f"{100 * r1.max_error('step_holdout'):.3f} |"]


def run() -> str:
    ev = _evaluation_rows()
    fit = _fit_rows()
    return (
        "The step model of `calibrate(..., steps=)`: the flux DAE in Radau IIA collocation "
        "(3 points, fixed steps), its exact parameter derivatives by the implicit function "
        "theorem.  *Before*: CasADi's `collocation` integrator on the explicit DAE `y' = T "
        "pinv(K) h` (its step equations in MX, the Newton's Jacobian by forward directional "
        "derivatives through the DAE at every iteration; `d(pinv(K) h)/d(y, z)` 41 % dense "
        "on the 6-layer ladder; the nominal run integrated twice, for the values and inside "
        "the forward sensitivities).  *After*: the same collocation on the sparse form `K y' = "
        "h` in SX, one Newton rootfinder per step unrolled in MX (values and derivatives "
        "from one run).  CPU seconds, best of 2 (the 6-layer before: 1 run).\n\n"
        "One evaluation: step 1 of the FEM (10 mm, 10 -> 20 A, 17 thinned samples, 253 "
        "Radau steps), six parameters (five static factors and `k_e`) 2 % of their scale "
        "off nominal.\n\n"
        "| eddy model | build before / after [s] | evaluation before [s] | after [s] | "
        "speed-up | current difference / change | Jacobian difference (relative) |\n"
        "|---|---|---|---|---|---|---|\n" + "\n".join(ev) + "\n\n"
        "A fit: `k_e` on three FEM steps, 6 mm 20 -> 50 A held out (`calibrate`, builds "
        "included).\n\n"
        "| network | fit before [s] | after [s] | speed-up | `k_e` before / after "
        "(difference) | held-out error before / after [%] |\n"
        "|---|---|---|---|---|---|\n" + "\n".join(fit))
