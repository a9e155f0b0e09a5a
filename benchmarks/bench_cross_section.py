"""Speed of the cross-section vehicle's time loop (issue 24): 1 kHz, reduced magnets, a
curve entry at 400 km/h; real-time factor of the loop (wall and process CPU time)."""

from __future__ import annotations

import math
import time

from maglevkit.vehicle.crossrun import CrossSectionModel, TransitionCurve

TITLE = "Cross-section vehicle (issue 24)"


def run() -> str:
    model = CrossSectionModel()
    curve = TransitionCurve(4000.0, math.radians(12.0), 300.0)
    model.run(speed_m_per_s=400 / 3.6, duration_s=0.1, curve=curve)      # warm-up
    best = math.inf
    cpu_best = math.inf
    duration = 3.0
    for _ in range(3):
        c0 = time.process_time()
        res = model.run(speed_m_per_s=400 / 3.6, duration_s=duration, curve=curve)
        cpu_best = min(cpu_best, time.process_time() - c0)
        best = min(best, res.wall_time_s)
    steps = int(round(duration / 1e-3))
    return (f"NumPy time loop, 4 magnets (8 circuits) through the bank's stepper, 4 cascade "
            f"controllers through the Controller interface, 6-DOF exact ZOH mechanics, "
            f"1 kHz, {duration:g} s at 400 km/h with a curve entry (best of 3):\n\n"
            f"- time loop: {best * 1e6 / steps:.0f} us per step, "
            f"{duration / best:.1f}x real time (aim: 100x; not met, see docs/decisions.md)\n"
            f"- whole run call by process CPU time: {duration / cpu_best:.1f}x real time\n")


if __name__ == "__main__":
    print(run())
