"""Offset-free NMPC: solve-time distribution over a closed-loop run at 1 ms sampling.

U-magnet on the reduced plant, +10 % load step.  Per horizon N: the reference RTI
(`OffsetFreeMPC(solver="rti")`: sparse QP, CasADi's qrqp, Python glue) and the real-time
RTI (`RealTimeMPC`: one compiled call for EKF step, target and condensed QP data, dense
qpOASES hot-started); the converged Gauss-Newton SQP; the IPOPT reference (exact Hessian,
B-spline maps) on the same OCPs for the ratio.  Wall time and CPU time (thread time) per
controller update: the machine is shared, so the wall-time tails include preemption.

Run alone: ``python benchmarks/bench_mpc.py`` (prints the section).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit.control import Measurement, closed_loop
from maglevkit.control.model import MagnetHeaveModel
from maglevkit.control.mpc import OffsetFreeMPC
from maglevkit.control.realtime import RealTimeMPC
from maglevkit.vehicle import STANDARD_GRAVITY, HeaveMass

TITLE = "Offset-free NMPC: solve times at 1 ms sampling (U-magnet, reduced plant)"

DT = 1e-3
S0 = 0.010
H = 2e-3                  # shooting interval [s]
DURATION = 0.2


class _Timed:
    """A controller whose updates are timed in CPU (thread) time as well."""

    def __init__(self, ctl: Any) -> None:
        self.ctl = ctl
        self.cpu_s: list[float] = []

    @property
    def gap_ref_m(self) -> float:
        return float(self.ctl.gap_ref_m)

    @property
    def voltage_limit_V(self) -> float:
        return float(self.ctl.voltage_limit_V)

    def reset(self, measurement: Measurement, *, sample_time_s: float) -> None:
        self.cpu_s = []
        self.ctl.reset(measurement, sample_time_s=sample_time_s)

    def update(self, measurement: Measurement) -> np.ndarray:
        c = time.thread_time()
        u = self.ctl.update(measurement)
        self.cpu_s.append(time.thread_time() - c)
        return np.asarray(u)

    def diagnostics(self) -> Mapping[str, float | np.ndarray]:
        return self.ctl.diagnostics()


def _stats(a: np.ndarray) -> tuple[float, float, float, float]:
    """(median, 99th percentile, max, min) [ms] without the first (cold) and last sample."""
    a = np.asarray(a)[1:-1] * 1e3
    return float(np.median(a)), float(np.percentile(a, 99)), float(a.max()), float(a.min())


def run() -> str:
    mag = mk.load_magnet("u-magnet")
    maps = mk.build_maps(mag, gaps_m=np.linspace(0.004, 0.02, 17),
                         currents_A=np.linspace(0, 80, 33), progress=False)
    f0 = float(mk.solve_statics(mag, gaps_m=S0, currents_A=20.0).force_N)
    veh = HeaveMass(f0 / STANDARD_GRAVITY)
    model = MagnetHeaveModel(maps, mass_kg=veh.mass_kg)
    plant = mk.CurrentModel(maps)

    def loop(ctl: Any) -> tuple[Any, _Timed]:
        timed = _Timed(ctl)
        r = closed_loop(plant, veh, timed, duration_s=DURATION, dt_s=DT, initial_gap_m=S0,
                        initial_current_A=ctl.design_state[0],
                        external_force_N=lambda t: 0.1 * f0 if t >= 0.02 else 0.0)
        return r, timed

    rows, sqp_rows, ratio_rows = [], [], []
    fast_median: dict[int, float] = {}
    ref_median: dict[int, float] = {}
    allowed = []
    for horizon in (5, 10, 20, 30):
        ref_r = None
        if horizon <= 20:
            ref = OffsetFreeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=horizon,
                                interval_s=H, solver="rti")
            ref_r, ref_t = loop(ref)
            st = _stats(ref_r.diagnostics["solve_time_s"])
            tot = _stats(ref_r.controller_time_s)
            cpu = _stats(np.array(ref_t.cpu_s))
            ref_median[horizon] = cpu[0]
            rows.append(f"| rti (reference: sparse QP, qrqp) | {horizon} | {st[0]:.3f} | "
                        f"{st[1]:.3f} | {st[2]:.3f} | {tot[0]:.3f} | {tot[1]:.3f} | "
                        f"{tot[2]:.3f} | {cpu[3]:.3f} | {cpu[0]:.3f} | {cpu[1]:.3f} | - "
                        "| - |")
        t0 = time.perf_counter()
        fast = RealTimeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=horizon,
                           interval_s=H)
        t_build = time.perf_counter() - t0
        r, timed = loop(fast)
        d = r.diagnostics
        prep, qp = _stats(d["prepare_time_s"]), _stats(d["qp_time_s"])
        tot = _stats(r.controller_time_s)
        cpu = _stats(np.array(timed.cpu_s))
        fast_median[horizon] = cpu[0]
        du = (f"{np.max(np.abs(r.voltages_V - ref_r.voltages_V)):.1e}"
              if ref_r is not None else "-")
        ratio = (f"{ref_median[horizon] / cpu[0]:.1f}" if horizon in ref_median else "-")
        if cpu[1] < 0.5:
            allowed.append(horizon)
        rows.append(f"| rti-fast (compiled, condensed, qpOASES; build {t_build:.0f} s) | "
                    f"{horizon} | {prep[0]:.3f} + {qp[0]:.3f} | {prep[1]:.3f} + {qp[1]:.3f} "
                    f"| - | {tot[0]:.3f} | {tot[1]:.3f} | {tot[2]:.3f} | {cpu[3]:.3f} | "
                    f"{cpu[0]:.3f} | {cpu[1]:.3f} | {ratio} | {du} |")
    for horizon in (10, 20):
        ctl = OffsetFreeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=horizon,
                            interval_s=H, solver="sqp")
        r, timed = loop(ctl)
        st, tot = _stats(r.diagnostics["solve_time_s"]), _stats(r.controller_time_s)
        sqp_rows.append(f"| sqp | {horizon} | {st[0]:.2f} | {st[1]:.2f} | {st[2]:.2f} | "
                        f"{tot[1]:.2f} |")
        ipo = OffsetFreeMPC(model, gap_ref_m=S0, sample_time_s=DT, horizon=horizon,
                            interval_s=H, solver="ipopt")
        x0 = np.r_[22.0, S0 + 5e-4, -0.01]
        t0 = time.thread_time()
        a = ipo.solve_ocp(x0, [30.0, 1.0])
        t_ipopt = time.thread_time() - t0
        t0 = time.thread_time()
        b = ctl.solve_ocp(x0, [30.0, 1.0])
        t_sqp = time.thread_time() - t0
        du = float(np.max(np.abs(a["inputs_V"] - b["inputs_V"])))
        ratio_rows.append(f"| {horizon} | {t_ipopt * 1e3:.1f} | {t_sqp * 1e3:.1f} | "
                          f"{t_ipopt / t_sqp:.1f} | {du:.2e} | {fast_median[horizon]:.3f} | "
                          f"{t_ipopt * 1e3 / fast_median[horizon]:.0f} |")
    return ("Closed loop of 0.2 s (+10 % load at 20 ms), intervals of 2 ms, sampling 1 ms "
            "[ms].  Reference RTI: *solve* = OCP only; rti-fast: *solve* = the compiled "
            "call (EKF step + target + condensed QP data) + the QP solver.  *update* = the "
            "whole controller update (observer, target, OCP, Python) in wall time and in "
            "CPU time (thread time: not counting the waits of a loaded machine, but still "
            "its cache evictions; the CPU minimum is the undisturbed cost); ratio = "
            "reference update CPU median / rti-fast update CPU median; du = largest "
            "voltage difference to the reference RTI over the run.\n\n"
            "| solver | N | solve median | solve p99 | solve max | update median | "
            "update p99 | update max | update CPU min | update CPU median | update CPU "
            "p99 | ratio | du [V] |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
            + "\n".join(rows)
            + f"\n\nHorizons with an update CPU-time p99 below 0.5 ms (50 % of the sample "
            f"time): {', '.join(f'N = {n}' for n in allowed) or 'none'}.\n\n"
            "Converged Gauss-Newton SQP (qrqp) in the same loop [ms]:\n\n"
            "| solver | N | solve median | solve p99 | solve max | total p99 |\n"
            "|---|---|---|---|---|---|\n" + "\n".join(sqp_rows)
            + "\n\nOne cold OCP solve from a disturbed state (CPU time), IPOPT reference "
            "against the converged Gauss-Newton SQP, and against one rti-fast update (CPU "
            "median above):\n\n"
            "| N | IPOPT [ms] | SQP [ms] | IPOPT / SQP | max input difference [V] | "
            "rti-fast update [ms] | IPOPT / rti-fast |\n|---|---|---|---|---|---|---|\n"
            + "\n".join(ratio_rows))


if __name__ == "__main__":
    t0 = time.perf_counter()
    print(f"## {TITLE}\n\n{run()}\n\n_(ran in {time.perf_counter() - t0:.1f} s)_")
