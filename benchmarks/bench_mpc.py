"""Offset-free NMPC: solve-time distribution over a closed-loop run at 1 ms sampling.

U-magnet on the reduced plant, +10 % load step; RTI (one Gauss-Newton QP per sample) and
the converged Gauss-Newton SQP, both with CasADi's qrqp; the IPOPT reference (exact
Hessian, B-spline maps) on the same OCPs for the ratio.
"""

from __future__ import annotations

import numpy as np

import maglevkit as mk
from maglevkit.control import closed_loop
from maglevkit.control.model import MagnetHeaveModel
from maglevkit.control.mpc import OffsetFreeMPC
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

TITLE = "Offset-free NMPC: solve times at 1 ms sampling (U-magnet, reduced plant)"

DT = 1e-3
S0 = 0.010


def run() -> str:
    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps=np.linspace(0.004, 0.02, 17),
                         currents=np.linspace(0, 80, 33), progress=False)
    f0 = float(mk.solve_statics(mag, gaps=S0, currents=20.0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    model = MagnetHeaveModel(maps, mass_kg=veh.mass_kg)
    plant = mk.CurrentModel(maps)
    rows = []
    ratio_rows = []
    for solver, horizon in (("rti", 5), ("rti", 10), ("rti", 20), ("sqp", 10), ("sqp", 20)):
        ctl = OffsetFreeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=horizon,
                            interval_s=2e-3, solver=solver)
        r = closed_loop(plant, veh, ctl, duration_s=0.2, dt_s=DT, initial_gap_m=S0,
                        initial_current_A=ctl.design_state[0],
                        external_force=lambda t: 0.1 * f0 if t >= 0.02 else 0.0)
        st = r.diagnostics["solve_time_s"][1:-1] * 1e3
        tot = r.controller_time_s[1:-1] * 1e3
        rows.append(f"| {solver} | {horizon} | {np.median(st):.2f} | {np.percentile(st, 99):.2f} "
                    f"| {st.max():.2f} | {np.percentile(tot, 99):.2f} | "
                    f"{'yes' if np.percentile(tot, 99) < 0.5 else 'no'} |")
        if solver == "sqp":
            ref = OffsetFreeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=horizon,
                                interval_s=2e-3, solver="ipopt")
            x0 = np.r_[22.0, S0 + 5e-4, -0.01]
            import time
            t0 = time.perf_counter()
            a = ref.solve_ocp(x0, [30.0, 1.0])
            t_ipopt = time.perf_counter() - t0
            t0 = time.perf_counter()
            b = ctl.solve_ocp(x0, [30.0, 1.0])
            t_sqp = time.perf_counter() - t0
            du = float(np.max(np.abs(a["inputs_V"] - b["inputs_V"])))
            ratio_rows.append(f"| {horizon} | {t_ipopt * 1e3:.1f} | {t_sqp * 1e3:.1f} | "
                              f"{t_ipopt / t_sqp:.1f} | {du:.2e} |")
    return ("Closed loop of 0.2 s (+10 % load at 20 ms), intervals of 2 ms; solve = OCP "
            "only, total = observer + target + OCP per sample [ms].\n\n"
            "| solver | N | solve median | solve p99 | solve max | total p99 | "
            "p99 < 0.5 ms |\n|---|---|---|---|---|---|---|\n" + "\n".join(rows)
            + "\n\nOne cold OCP solve from a disturbed state, IPOPT reference against the "
            "converged Gauss-Newton SQP:\n\n| N | IPOPT [ms] | SQP [ms] | ratio | "
            "max input difference [V] |\n|---|---|---|---|---|\n" + "\n".join(ratio_rows))
