"""Time loops of both vehicles for two source trees, interleaved (A B A B ...), one core.

    python tools/compare_vehicle_speed.py SRC_A SRC_B [ROUNDS]

Each round starts one fresh process per tree (``PYTHONPATH=SRC``, pinned with
``taskset -c 0``) that measures, best of 3 by process CPU time: the heave-pitch train
(3 sections, 50 circuits, elastic guideway, ``sag:0.5e-3+random:0.3e-3:1``, 400 km/h,
1 kHz) 3 s in the compiled loop and 1 s in the reference loop; the cross-section slice
(curve entry 4000 m / 12 deg / 300 m, 400 km/h) 10 s compiled and 2 s in the NumPy loop.
Prints the real-time factors of every round and their medians per tree: interleaving
spreads the shared machine's changing load over both trees.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys

CHILD = r"""
import json, math, time
from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity
from maglevkit.vehicle.train import load_vehicle
from maglevkit.vehicle.crossrun import CrossSectionModel, TransitionCurve
out = {}
m = VehicleModel(load_vehicle())
p = parse_irregularity("sag:0.5e-3+random:0.3e-3:1", span_length_m=m.guideway.span.length_m)
v = 400 / 3.6
for loop, dur in (("compiled", 3.0), ("python", 1.0)):
    m.run(speed_m_per_s=v, duration_s=0.05, irregularity=p, loop=loop)
    best = min(m.run(speed_m_per_s=v, duration_s=dur, irregularity=p, loop=loop).cpu_time_s
               for _ in range(3))
    out["heave-pitch " + loop] = dur / best
cs = CrossSectionModel()
curve = TransitionCurve(4000.0, math.radians(12.0), 300.0)
for loop, dur in (("compiled", 10.0), ("python", 2.0)):
    cs.run(speed_m_per_s=v, duration_s=0.1, curve=curve, loop=loop)
    best = math.inf
    for _ in range(3):
        c0 = time.process_time()
        cs.run(speed_m_per_s=v, duration_s=dur, curve=curve, loop=loop)
        best = min(best, time.process_time() - c0)
    out["cross-section " + loop + " (whole run)"] = dur / best
print(json.dumps(out))
"""


def main(a: str, b: str, rounds: int) -> None:
    res: dict[str, list[dict[str, float]]] = {a: [], b: []}
    for r in range(rounds):
        for src in (a, b):
            env = dict(os.environ, PYTHONPATH=src, OPENBLAS_NUM_THREADS="1",
                       OMP_NUM_THREADS="1")
            out = subprocess.run(["taskset", "-c", "0", sys.executable, "-c", CHILD], env=env,
                                 capture_output=True, text=True, check=True)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            res[src].append(row)
            print(r, src, {k: round(v, 1) for k, v in row.items()}, flush=True)
    for src, rows in res.items():
        print("median", src, {k: round(statistics.median(x[k] for x in rows), 1)
                              for k in rows[0]})


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 3)
