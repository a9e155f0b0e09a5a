"""Speed of the cross-section vehicle's time loop (issue 24): 1 kHz, reduced magnets, a
curve entry at 400 km/h; real-time factor of the time loop, compiled and NumPy.

The magnets fly their files' default reduced model (since issue 26's switch: the
levitation magnets the 2-branch eddy network, the guidance magnets their own file's
default); eq. 8 on every magnet (``eddy_modes=0``, the default before) is measured in the
same process, and the default's time per step given as a ratio to it.  Process CPU time
of the whole ``run`` call, which holds the time loop (the cross-section run reports its
loop's wall time only; the machine is shared), and the loop's wall time beside it.
"""

from __future__ import annotations

import math
import time

from maglevkit.vehicle.crossrun import CrossSectionModel, TransitionCurve
from maglevkit.vehicle.stepkernel import eddy_modes_label

TITLE = "Cross-section vehicle (issue 24)"


def _times(model: CrossSectionModel, loop: str, duration: float, curve: TransitionCurve
           ) -> tuple[float, float]:
    """(least CPU time of a whole run call, least wall time of its loop) [s], best of 3."""
    model.run(speed_m_per_s=400 / 3.6, duration_s=0.1, curve=curve, loop=loop)  # warm-up
    cpu = wall = math.inf
    for _ in range(3):
        c0 = time.process_time()
        res = model.run(speed_m_per_s=400 / 3.6, duration_s=duration, curve=curve, loop=loop)
        cpu = min(cpu, time.process_time() - c0)
        wall = min(wall, res.wall_time_s)
    return cpu, wall


def run() -> str:
    try:
        import os
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})   # one core
    except (AttributeError, OSError):
        pass
    curve = TransitionCurve(4000.0, math.radians(12.0), 300.0)
    default, eq8 = CrossSectionModel(), CrossSectionModel(eddy_modes=0)
    lines = []
    per_step: dict[tuple[str, str], float] = {}
    for name, model in (("default", default), ("eq. 8", eq8)):
        for loop, duration in (("compiled", 10.0), ("python", 2.0)):
            cpu, wall = _times(model, loop, duration, curve)
            steps = int(round(duration / 1e-3))
            per_step[name, loop] = cpu / steps
            label = (f"default ({eddy_modes_label(model.eddy_modes_of)})"
                     if name == "default" else "eq. 8 (eddy_modes=0)")
            lines.append(f"- {label}, {loop} loop: {cpu * 1e6 / steps:.1f} us per step "
                         f"(whole run call, CPU), {duration / cpu:.0f}x real time; time "
                         f"loop by wall time {duration / wall:.0f}x")
    ratio = [per_step["default", lp] / per_step["eq. 8", lp] for lp in ("compiled", "python")]
    lines.append(f"- the default against eq. 8, CPU time per step: x{ratio[0]:.2f} compiled, "
                 f"x{ratio[1]:.2f} NumPy loop")
    return ("4 magnets (8 circuits) through the bank, 4 cascade controllers, 6-DOF exact ZOH "
            "mechanics, 1 kHz, 400 km/h with a curve entry, best of 3, one core (aim: the "
            "time loop >= 100x real time):\n\n" + "\n".join(lines) + "\n")


if __name__ == "__main__":
    print(run())
