"""Vehicle model: real-time factor of the 3-section train at 1 kHz on one core.

All 50 lumped circuits as reduced models in one magnet bank (one compiled call per step),
the 30-DOF heave-pitch mechanics (exact ZOH step), the elastic guideway (5 spans x 5 modes,
moving system boundary), 50 flux cascade controllers vectorised in NumPy, irregularities
(span sag + random profile, tabulated once per run).  The share of each part is measured
inside the loop with ``time.perf_counter`` around each part.
"""

from __future__ import annotations

import os
import time

from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity
from maglevkit.vehicle.train import load_vehicle

TITLE = "Vehicle model: 3-section train, reduced magnets, elastic guideway, 1 kHz"

DURATION_S = 3.0
SPEED_KMH = 400.0


def run() -> str:
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})   # one core
    except (AttributeError, OSError):
        pass
    t0 = time.perf_counter()
    model = VehicleModel(load_vehicle())
    setup = time.perf_counter() - t0
    prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                              span_length_m=model.guideway.span.length_m)
    model.run(speed_m_per_s=SPEED_KMH / 3.6, duration_s=0.05, irregularity=prof)   # compile
    rows = []
    for rigid in (False, True):
        m = model if not rigid else VehicleModel(load_vehicle(), rigid=True)
        if rigid:
            m.run(speed_m_per_s=0.0, duration_s=0.05)
        best = None
        for _ in range(2):
            res = m.run(speed_m_per_s=SPEED_KMH / 3.6, duration_s=DURATION_S,
                        irregularity=prof)
            if best is None or res.wall_time_s < best.wall_time_s:
                best = res
        assert best is not None
        rows.append(("rigid guideway" if rigid else "elastic guideway", best))
    lines = [f"{DURATION_S:g} s at {SPEED_KMH:g} km/h, dt = 1 ms, {model.bank.n_circuits} circuits "
             f"(bank compiled: {model.bank.compiled}), best of 2 runs; set-up (maps from the "
             f"cache, controllers, discretisation) {setup:.1f} s.", "",
             "| case | real-time factor | us per step | magnets | mechanics | guideway | "
             "controllers | other (gaps, records) |", "|---|---|---|---|---|---|---|---|"]
    for name, r in rows:
        steps = DURATION_S * 1000
        parts = r.timing_s
        tot = sum(parts.values())
        share = " | ".join(f"{100 * parts[k] / tot:.0f} %" for k in
                           ("magnets", "mechanics", "guideway", "controllers", "other"))
        lines.append(f"| {name} | {r.real_time_factor:.2f}x | {1e6 * r.wall_time_s / steps:.0f} "
                     f"| {share} |")
    lines += ["", "Shares are of the time measured inside the loop (the rest of the wall time, "
              "a few per cent, is loop overhead and the progress bookkeeping)."]
    return "\n".join(lines)
