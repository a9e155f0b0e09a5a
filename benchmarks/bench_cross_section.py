"""Speed of the cross-section vehicle's time loop (issue 24): 1 kHz, reduced magnets, a
curve entry at 400 km/h; real-time factor of the time loop, compiled and NumPy."""

from __future__ import annotations

import math
import time

from maglevkit.vehicle.crossrun import CrossSectionModel, TransitionCurve

TITLE = "Cross-section vehicle (issue 24)"


def run() -> str:
    model = CrossSectionModel()
    curve = TransitionCurve(4000.0, math.radians(12.0), 300.0)
    lines = []
    for loop, duration in (("compiled", 10.0), ("python", 2.0)):
        model.run(speed_m_per_s=400 / 3.6, duration_s=0.1, curve=curve, loop=loop)  # warm-up
        best = math.inf
        whole = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            res = model.run(speed_m_per_s=400 / 3.6, duration_s=duration, curve=curve,
                            loop=loop)
            whole = min(whole, time.perf_counter() - t0)
            best = min(best, res.wall_time_s)
        steps = int(round(duration / 1e-3))
        lines.append(f"- {loop} loop: {best * 1e6 / steps:.1f} us per step, "
                     f"{duration / best:.0f}x real time in the time loop; whole run call "
                     f"{duration / whole:.0f}x")
    return ("4 magnets (8 circuits) through the bank, 4 cascade controllers, 6-DOF exact ZOH "
            "mechanics, 1 kHz, 400 km/h with a curve entry, best of 3 (wall time; aim: the "
            "time loop >= 100x real time):\n\n" + "\n".join(lines) + "\n")


if __name__ == "__main__":
    print(run())
