"""Statics of the TR09-type standard levitation magnet (12 poles, 2 circuits)."""

from __future__ import annotations

import time

import numpy as np

import maglevkit as mk

TITLE = "Statics: TR09 standard levitation magnet, 40 x 40 gap-current grid and single points"


def _best(fn, repeat: int = 5) -> float:  # type: ignore[no-untyped-def]
    """CPU time [s] of ``fn()``, the best of ``repeat`` calls (CPU time: the machine may be
    shared; bench26)."""
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return min(times)


def run() -> str:
    gaps = np.linspace(0.006, 0.020, 40)
    currents = np.linspace(0.0, 90.0, 40)
    rows = []
    for label, kw in (("saturable iron", {}), ("linear iron", {"saturation": False})):
        mag = mk.load_magnet("tr09-standard", eddy_currents=False, **kw)
        net = mag.network
        t0 = time.process_time()
        mk.solve_statics(mag, gaps_m=gaps, currents_A=currents, grid=True)
        first = time.process_time() - t0
        t = _best(lambda mag=mag: mk.solve_statics(mag, gaps_m=gaps, currents_A=currents, grid=True))
        one = _best(lambda mag=mag: mk.solve_statics(mag, gaps_m=0.010, currents_A=34.0), repeat=50)
        uneven = np.linspace(0.008, 0.012, 12)
        one_u = _best(lambda mag=mag, uneven=uneven: mk.solve_statics(
            mag, gaps_m=uneven, currents_A=[34.0, 30.0]), repeat=50)
        rows.append(f"| {label} | {len(net.branches)} / {net.n_loops} | {first * 1e3:.0f} | "
                    f"{t * 1e3:.1f} | {t / gaps.size / currents.size * 1e6:.0f} | "
                    f"{one * 1e3:.2f} | {one_u * 1e3:.2f} |")
    return ("12 gap inputs (one per pole), 2 circuits; gaps 6-20 mm, currents 0-90 A (to ~2 x the "
            "saturation knee); every point returns pole forces, fluxes, flux linkages, the 2 x 2 "
            "differential inductance and dpsi/ds, dF/dI, dF/ds (exact sensitivities); CPU times "
            "(process_time); the bundled network (split, since issue 26; the eddy ladder "
            "does not enter the statics).\n\n"
            "| model | branches / loops | first call incl. set-up [ms] | grid, best of 5 [ms] | "
            "grid per point [us] | single point [ms] | single point, uneven gaps [ms] |\n"
            "|---|---|---|---|---|---|---|\n" + "\n".join(rows))
