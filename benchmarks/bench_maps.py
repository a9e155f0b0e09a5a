"""Map generation: statics vs the paper's transient identification, grid size and workers."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import maglevkit as mk
from maglevkit.reduction import build_maps

TITLE = "Characteristic maps: statics vs transient identification (U-magnet, TR09 standard)"


def _timed(fn):  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


_COLD_BUILD = """
import json, resource, sys, time
from concurrent.futures import ProcessPoolExecutor
w0, c0 = time.perf_counter(), time.process_time()
import numpy as np
import maglevkit as mk
from maglevkit.vehicle.mapcache import vehicle_maps
names, grid, workers = json.loads(sys.argv[1])
for name in names:
    mag = mk.load_magnet(name)
    if grid == "vehicle" and workers == 1:
        vehicle_maps(mag, cache_dir=sys.argv[2])        # as VehicleModel builds them
    else:
        if grid == "vehicle":
            from maglevkit.vehicle.mapcache import VEHICLE_MAP_CURRENTS_A as c
            from maglevkit.vehicle.mapcache import VEHICLE_MAP_GAPS_M as g
        else:
            g, c = np.linspace(*grid[0][:2], grid[0][2]), np.linspace(*grid[1][:2], grid[1][2])
        with ProcessPoolExecutor(workers) as ex:
            mk.build_maps(mag, gaps_m=g, currents_A=c, executor=ex if workers > 1 else None)
kids = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps([time.perf_counter() - w0, time.process_time() - c0,
                  kids.ru_utime + kids.ru_stime]))
"""


def _cold(names: tuple[str, ...], grid: object, workers: int) -> tuple[float, float]:
    """Wall and CPU time [s] (this process and its workers) of building maps in a fresh
    interpreter with an empty cache directory (``MAGLEVKIT_CACHE_DIR``: nothing compiled,
    no maps cached): what a first run on a new machine pays, import included.  ``grid``
    ``"vehicle"`` with one worker is ``vehicle_maps`` as ``VehicleModel`` calls it."""
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, MAGLEVKIT_CACHE_DIR=tmp)
        out = subprocess.run([sys.executable, "-c", _COLD_BUILD,
                              json.dumps([names, grid, workers]), tmp],
                             env=env, check=True, capture_output=True, text=True)
    wall, cpu, kids = json.loads(out.stdout.strip().splitlines()[-1])
    return wall, cpu + kids


def _grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.linspace(0.006, 0.014, n), np.linspace(0.0, 60.0, n)


def run() -> str:
    u = mk.load_magnet("u-magnet")
    tr = mk.load_magnet("tr09-standard")
    lines = ["| magnet | method | grid | workers | wall [s] | per point [ms] |",
             "|---|---|---|---|---|---|"]
    # Warm-up: compile the statics and transient functions once in this process.
    build_maps(u, gaps_m=_grid(4)[0], currents_A=_grid(4)[1], method="transient")
    for n in (10, 25, 50):
        g, c = _grid(n)
        t, _ = _timed(lambda g=g, c=c: build_maps(u, gaps_m=g, currents_A=c))
        lines.append(f"| U-magnet | statics | {n} x {n} | 1 | {t:.3f} | {t / n / n * 1e3:.2f} |")
    for n in (4, 6, 8):
        g, c = _grid(n)
        t, _ = _timed(lambda g=g, c=c: build_maps(u, gaps_m=g, currents_A=c, method="transient"))
        lines.append(f"| U-magnet | transient | {n} x {n} | 1 (serial) | {t:.2f} | "
                     f"{t / n / n * 1e3:.0f} |")
    g, c = _grid(8)
    for w in (1, 2):
        # a fresh pool each time: includes process start-up and per-process compilation
        def pooled(w: int = w):  # type: ignore[no-untyped-def]
            with ProcessPoolExecutor(w) as ex:
                return build_maps(u, gaps_m=g, currents_A=c, method="transient", executor=ex)
        t, _ = _timed(pooled)
        lines.append(f"| U-magnet | transient | 8 x 8 | {w} (process pool) | {t:.2f} | "
                     f"{t / 64 * 1e3:.0f} |")
    g, c = _grid(6)
    t, both = _timed(lambda: build_maps(u, gaps_m=g, currents_A=c, method="both"))
    dl = float(np.max(np.abs(both.dataset["inductance_relative_difference"].values)))
    dd = float(np.max(np.abs(both.dataset["dL_ds_relative_difference"].values)))
    build_maps(tr, gaps_m=np.linspace(0.006, 0.020, 4), currents_A=np.linspace(0.0, 68.0, 4))
    for n in (10, 25):
        gt, ct = np.linspace(0.006, 0.020, n), np.linspace(0.0, 68.0, n)
        t0, _ = _timed(lambda gt=gt, ct=ct: build_maps(tr, gaps_m=gt, currents_A=ct))
        lines.append(f"| TR09 standard (2 circuits) | statics | {n} x {n} | 1 | {t0:.2f} | "
                     f"{t0 / n / n * 1e3:.1f} |")
    gt, ct = np.linspace(0.009, 0.0105, 4), np.linspace(31.0, 37.0, 4)
    with ProcessPoolExecutor(2) as ex:
        t1, trb = _timed(lambda: build_maps(tr, gaps_m=gt, currents_A=ct, method="both", executor=ex))
    lines.append(f"| TR09 standard (2 circuits) | both | 4 x 4 near nominal | 2 (process pool) | "
                 f"{t1:.1f} | {t1 / 16 * 1e3:.0f} |")
    tdl = float(np.max(np.abs(trb.dataset["inductance_relative_difference"].values)))
    tdd = float(np.max(np.abs(trb.dataset["dL_ds_relative_difference"].values)))
    r_tr = trb.dataset["eddy_resistance_ohm"].values
    r_ec = both.dataset["eddy_resistance_ohm"].values
    cold = []
    tr09 = ("tr09-standard", "tr09-bow")
    for label, names, grid, workers in (
            ("vehicle TR09 set: tr09-standard + tr09-bow, 21 x 51 each (2-22 mm x 0-100 A, "
             "`vehicle_maps` as the heave-pitch vehicle builds them)", tr09, "vehicle", 1),
            ("the same, `build_maps` on a 2-process pool", tr09, "vehicle", 2),
            ("`maglevkit maps build tr09-standard` default grid 17 x 33 (4-20 mm x 0-80 A; "
             "the maps `compare` reads)", ("tr09-standard",),
             ((0.004, 0.020, 17), (0.0, 80.0, 33)), 1)):
        wall, cpu = _cold(names, grid, workers)
        cold.append(f"| {label} | {workers} | {wall:.1f} | {cpu:.1f} |")
    return ("Gaps 6-14 mm, currents 0-60 A on the U-magnet (with eddy currents and saturable "
            "iron); the transient method runs one voltage step and one flux-held gap ramp "
            "of the detailed model per grid point and circuit (IDAS, rtol 1e-9).  Pool runs "
            "include starting the processes and compiling in each.\n\n"
            + "\n".join(lines)
            + f"\n\nAgreement of the two methods on the 6 x 6 grid (`method=\"both\"`, {t:.1f} s): "
            f"max |L~ transient/statics - 1| = {dl:.2e}, max |dL/ds transient/statics - 1| = "
            f"{dd:.2e}.  TR09 standard near nominal (9-10.5 mm, 31-37 A): {tdl:.2e} and {tdd:.2e} "
            "(these include the neglected coupling: the other half magnet's voltage is held "
            "during the step and its flux during the ramp).  Analytic R_ec: U-magnet "
            f"{float(r_ec[0]):.3f} ohm, TR09 standard {r_tr[0]:.3f} / {r_tr[1]:.3f} ohm."
            "\n\nTR09 map sets from a cold start (issue 26 part 2: aim < 10 min for a TR09 "
            "map set on 2 cores): a fresh interpreter with an empty cache directory "
            "(nothing compiled, no maps cached; import included), the bundled files as "
            "shipped (eddy ladder, 6 layers; the identification of eq. 8's `R_ec`, the eddy "
            "networks and the ladders included); CPU = this process and its workers:\n\n"
            "| map set | workers | wall [s] | CPU [s] |\n|---|---|---|---|\n"
            + "\n".join(cold))
