"""Issue 23, item 4: what makes the pier crossing at 400 km/h on a smooth guideway
unrealistic?  Short runs of the bundled train (NumPy loop, so that controller parameters
can change without compiling a step), statistics after the start transient; the findings
are in docs/decisions.md ("Realism of the pier crossing: diagnosis").

    PYTHONPATH=src python tools/diagnose_pier_crossing.py [base] [camber] [bw] [chopper]

Columns: coil current range [A], its standard deviation per circuit (mean over circuits)
[A], the share of samples below 10 % of the circuit's mean current, the voltage range [V],
the gap's deviation from nominal [mm], the largest one-step change of the differenced gap
rate [m/s] (the pier kink as the magnets see it) and the largest midspan deflection [mm].
Precamber is emulated by the camber irregularity ``sag:-A`` (zero at the piers, the
uniform-load line): in the gap ``s = s0 + u - w - r`` a built-in camber and an
irregularity are the same term.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Any

import numpy as np

from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity
from maglevkit.vehicle.train import TrainData, load_vehicle

T0_S = 0.5          # statistics from here on (after the start transient)
DURATION_S = 1.6


def metrics(name: str, res: Any, model: VehicleModel) -> str:
    ds = res.dataset
    t = ds.time.values
    sel = t >= T0_S
    if res.touchdown is not None or sel.sum() < 10:
        return f"{name:46s} TOUCHDOWN {res.touchdown} after {t[-1]:.3f} s"
    cur = ds.current.values[sel]
    u = ds.voltage.values[sel]
    dg = ds.gap.values[sel] - model.train.nominal_gap_m
    low = (cur < 0.1 * cur.mean(axis=0)).mean()
    rate = np.diff(ds.gap.values, axis=0) / float(ds.attrs["dt_s"])
    jump = np.abs(np.diff(rate, axis=0))[sel[2:]].max()
    mid = np.abs(ds.midspan_deflection.values[sel]).max()
    return (f"{name:46s} I {cur.min():6.2f}..{cur.max():6.1f} A  std "
            f"{cur.std(axis=0).mean():5.2f} A  <10% mean {100 * low:5.1f} %  U "
            f"{np.nanmin(u):5.0f}..{np.nanmax(u):4.0f} V  gap {1e3 * dg.min():+.2f}.."
            f"{1e3 * dg.max():+.2f} mm  rate jump {jump:.3f} m/s  midspan {1e3 * mid:.2f} mm")


def run(name: str, train: TrainData | None = None, *, rigid: bool = False,
        irregularity: str | None = None, kmh: float = 400.0, chopper: bool = True) -> str:
    model = VehicleModel(train or load_vehicle(), rigid=rigid)
    if not chopper:
        # the chopper bound U >= -R_ec I_L is the only use of R_ec in the controllers
        model.eddy_resistance_ohm = np.full_like(model.eddy_resistance_ohm, 1e12)
    prof = (parse_irregularity(irregularity, span_length_m=model.guideway.span.length_m)
            if irregularity else None)
    res = model.run(speed_m_per_s=kmh / 3.6, duration_s=DURATION_S, irregularity=prof,
                    loop="python")
    return metrics(name, res, model)


def main(which: list[str]) -> None:
    base = load_vehicle()
    every = not which
    if every or "base" in which:
        print(run("elastic, smooth, 400 km/h (as bundled)"))
        print(run("rigid, smooth, 400 km/h", rigid=True))
        for kmh in (200.0, 300.0, 500.0):
            print(run(f"elastic, smooth, {kmh:.0f} km/h", kmh=kmh))
    if every or "camber" in which:
        for a in (1.0e-3, 2.0e-3, 2.7e-3):
            print(run(f"precamber {a * 1e3:.1f} mm, 400 km/h", irregularity=f"sag:{-a}"))
    if every or "bw" in which:
        for bw in (8.0, 12.0):
            print(run(f"gap loop {bw:g} Hz, 400 km/h",
                      dataclasses.replace(base, control_bandwidth_Hz=bw)))
        print(run("gap-loop damping 1.0, 400 km/h",
                  dataclasses.replace(base, control_damping=1.0)))
    if every or "chopper" in which:
        print(run("no chopper limit (I may reverse), 400 km/h", chopper=False))


if __name__ == "__main__":
    main(sys.argv[1:])
