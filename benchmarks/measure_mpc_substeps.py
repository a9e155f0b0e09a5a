"""The NMPC prediction's RK4 sub-steps with the eddy network (docs/decisions.md, "nmpcnet"),
before and after in one process.

1. Accuracy: the vehicle's prediction model of the first circuit (TR09 heave-pitch train,
   the magnet file's default ``eddy_modes = 2``, as ``VehicleModel(controller="mpc")``
   builds it) predicts the MPC's horizon (N = 10 intervals of 2 ms) from the trim with a
   gap rate and a voltage sequence that swings over the chopper's range, with 1 and 2 RK4
   sub-steps per interval, against a 32-sub-step reference; the same for eq. 8's
   prediction model (``eddy_modes=0``), whose 1 sub-step per interval is what the NMPC
   has predicted with all along.  Largest errors over the horizon: gap [m], coil current
   [A], branch currents [A].
2. Speed: the NMPC train (``bench_vehicle.mpc_lines``: 3 sections, 50 circuits, N = 10,
   2 ms sample, 0.5 s at 400 km/h, best of ``MPC_REPEATS``) with the rule before
   (``ceil(h / bank.max_step_s)``, the bank's 1 ms accuracy cap: 2 sub-steps) and after
   (``ceil(h / bank.eddy_step_s)``, the network's stable step: 1), and eq. 8.

CPU time.  Pin it: ``PYTHONPATH=src taskset -c 0 python benchmarks/measure_mpc_substeps.py``.
Writes JSON (``--output``, default benchmarks/results/mpc_substeps.json).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from maglevkit.control.model import MagnetHeaveModel
from maglevkit.reduced.core import substep_count
from maglevkit.vehicle import load_vehicle
from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing_common import sibling_module  # noqa: E402

HERE = Path(__file__).parent
HORIZON = 10
INTERVAL_S = 2e-3
REFERENCE_SUBSTEPS = 32


def _old_rule(self: MagnetHeaveModel, h: float, substeps: int) -> int:
    """The rule before nmpcnet: the bank's simulation cap ``max_step_s``."""
    if not self.n_eddy:
        return substeps
    return max(substeps, substep_count(h, self.bank.max_step_s))


def accuracy(eddy_modes: int | None) -> dict[str, Any]:
    """Largest horizon errors of 1 and 2 sub-steps against the reference."""
    model = VehicleModel(load_vehicle(), eddy_modes=eddy_modes)
    m = model._circuit_mpc(0, INTERVAL_S, {}, {}).model
    xs, us = m.steady_state(model.train.nominal_gap_m)
    nc, ulim = m.n_circuits, model.train.voltage_limit_V
    rng = np.random.default_rng(7)
    # voltages over the chopper's range (0..U_max), held per interval, as an MPC that
    # fights a disturbance commands them; a gap rate of 50 mm/s at the start
    u_seq = rng.uniform(0.0, ulim, size=(HORIZON, nc))
    x0 = np.asarray(xs, dtype=float).copy()
    x0[nc + 1] = 0.05
    d = np.zeros(m.nd)
    out: dict[str, Any] = {"nx": m.nx, "eddy_step_s": float(getattr(m.bank, "eddy_step_s",
                                                                    float("inf"))),
                           "max_step_s": float(m.bank.max_step_s)}
    trajs = {}
    for n in (1, 2, REFERENCE_SUBSTEPS):
        f = m.discrete(INTERVAL_S, n)
        xk, traj = x0.copy(), []
        for k in range(HORIZON):
            xk = np.asarray(f(xk, u_seq[k], d, m.table)).ravel()
            traj.append(xk)
        trajs[n] = np.array(traj)
    ref = trajs[REFERENCE_SUBSTEPS]
    ycur = m.discrete(INTERVAL_S, 1, jacobians=True)
    for n in (1, 2):
        e = np.abs(trajs[n] - ref)
        # coil currents: the measurement y[1:] at each predicted state and the next voltage
        cur = [np.asarray(ycur(trajs[n][k], u_seq[min(k + 1, HORIZON - 1)], d,
                                m.table)[4]).ravel()[1:] -
               np.asarray(ycur(ref[k], u_seq[min(k + 1, HORIZON - 1)], d,
                               m.table)[4]).ravel()[1:] for k in range(HORIZON)]
        out[f"substeps_{n}"] = {
            "gap_m": float(e[:, nc].max()),
            "gap_rate_m_per_s": float(e[:, nc + 1].max()),
            "inductor_current_A": float(e[:, :nc].max()),
            "coil_current_A": float(np.abs(cur).max()),
            "eddy_current_A": float(e[:, nc + 2:].max()) if m.n_eddy else 0.0}
    out["gap_span_m"] = float(np.ptp(ref[:, nc]))
    out["current_span_A"] = float(np.ptp(ref[:, :nc]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--output", default=str(HERE / "results" / "mpc_substeps.json"))
    ap.add_argument("--skip-speed", action="store_true")
    args = ap.parse_args()
    res: dict[str, Any] = {"load_start": os.getloadavg()[0]}
    res["accuracy_network"] = accuracy(None)
    res["accuracy_eq8"] = accuracy(0)
    print(json.dumps(res, indent=1))
    if not args.skip_speed:
        bench = sibling_module("bench_vehicle")
        v = bench.SPEED_KMH / 3.6
        span = VehicleModel(load_vehicle()).guideway.span.length_m
        prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1", span_length_m=span)
        new_rule = MagnetHeaveModel.rk4_substeps
        for label, rule, modes in (("network_before", _old_rule, None),
                                   ("network_after", new_rule, None),
                                   ("eq8", new_rule, 0)):
            MagnetHeaveModel.rk4_substeps = rule       # type: ignore[method-assign]
            t0 = time.process_time()
            res[label] = bench.mpc_lines(v, prof, eddy_modes=modes)[0]
            res[label + "_cpu_s"] = time.process_time() - t0
            print(label, res[label])
        MagnetHeaveModel.rk4_substeps = new_rule        # type: ignore[method-assign]
    res["load_end"] = os.getloadavg()[0]
    Path(args.output).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
