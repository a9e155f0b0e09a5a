"""Statics on a 50 x 50 (gap x current) grid for the U-magnet."""

from __future__ import annotations

import time

import numpy as np

import maglevkit as mk

TITLE = "Statics: U-magnet, 50 x 50 gap-current grid"


def _best(fn, repeat: int = 5) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def run() -> str:
    gaps = np.linspace(0.004, 0.020, 50)
    currents = np.linspace(0.0, 80.0, 50)
    rows = []
    for label, kw in (("saturable iron", {}), ("linear iron", {"saturation": False})):
        mag = mk.load_magnet("u-magnet", eddy_currents=False, **kw)
        t0 = time.perf_counter()
        mk.solve_statics(mag, gaps_m=gaps, currents_A=currents, grid=True)
        first = time.perf_counter() - t0
        t = _best(lambda mag=mag: mk.solve_statics(mag, gaps_m=gaps, currents_A=currents, grid=True))
        rows.append(f"| {label} | {first * 1e3:.1f} | {t * 1e3:.1f} | {t / 2500 * 1e6:.1f} |")
    return ("Gaps 4-20 mm, currents 0-80 A (into deep saturation); each point returns fluxes, "
            "forces, flux linkage, differential inductance and dpsi/ds (exact sensitivities).\n\n"
            "| model | first call incl. set-up [ms] | grid, best of 5 [ms] | per point [us] |\n"
            "|---|---|---|---|\n" + "\n".join(rows))
