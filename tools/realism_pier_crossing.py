"""Issue 23, item 4: the pier crossing before and after the realism changes (precamber,
damping from the magnet's absolute velocity, freewheeling diodes), measured against the
aims; the findings are in docs/decisions.md ("A realistic default run").

    PYTHONPATH=src python tools/realism_pier_crossing.py smooth [DURATION_S]
    PYTHONPATH=src python tools/realism_pier_crossing.py ablation [DURATION_S]
    PYTHONPATH=src python tools/realism_pier_crossing.py rough SEEDS [DURATION_S]
    PYTHONPATH=src python tools/realism_pier_crossing.py figure OUT.png

"before": the bundled train and guideway as of the diagnosis (no precamber, damping from
the gap rate, no diode in the plant); "after": the bundled files as they are.  Statistics
after the start transient (t >= 0.5 s).
"""

from __future__ import annotations

import dataclasses
import sys
import time
from typing import Any

import numpy as np

from maglevkit.vehicle import load_guideway, load_vehicle
from maglevkit.vehicle.simulation import Failure, VehicleModel, parse_irregularity

T0_S = 0.5
IRREGULARITY = "sag:0.5e-3+random:0.3e-3"
FAILED = "s1m7/front"


def model(which: str, *, loop_compiled: bool = True) -> VehicleModel:
    """The train ``"before"`` or ``"after"`` the realism changes, or ``"after"`` without
    one of them (``"no-precamber"``, ``"no-blend"``, ``"no-diode"``)."""
    train = load_vehicle()
    data = load_guideway()
    if which in ("before", "no-blend"):
        train = dataclasses.replace(train, control_velocity_blend=0.0)
    if which in ("before", "no-precamber"):
        data = dataclasses.replace(data, span=dataclasses.replace(data.span, precamber_m=0.0))
    gw0 = data.guideway(n_spans=1)
    gw = data.guideway(n_spans=gw0.spans_needed(train.length_m))
    return VehicleModel(train, guideway=gw, freewheel=which not in ("before", "no-diode"),
                        compiled="auto" if loop_compiled else "never")


def metrics(res: Any, m: VehicleModel) -> dict[str, float]:
    ds = res.dataset
    t = ds.time.values
    sel = t >= T0_S
    cur = ds.current.values[sel]
    dg = ds.gap.values[sel] - m.train.nominal_gap_m
    u = ds.voltage.values[sel]
    return {"I_min": float(cur.min()), "I_max": float(cur.max()),
            "I_std": float(cur.std(axis=0).mean()),
            "min_frac_of_mean": float((cur / cur.mean(axis=0)).min()),
            "below10": float((cur < 0.1 * cur.mean(axis=0)).mean()),
            "U_min": float(np.nanmin(u)), "U_max": float(np.nanmax(u)),
            "gap_lo_mm": 1e3 * float(dg.min()), "gap_hi_mm": 1e3 * float(dg.max()),
            "min_gap_mm": 1e3 * float(ds.gap.values.min()),
            "touchdown": str(res.touchdown)}


def smooth(duration: float, cases: tuple[str, ...] = ("before", "after")) -> None:
    for which in cases:
        m = model(which)
        for kmh in (400.0, 500.0):
            t0 = time.perf_counter()
            res = m.run(speed_m_per_s=kmh / 3.6, duration_s=duration)
            print(which, f"{kmh:.0f} km/h", f"{time.perf_counter() - t0:.1f}s",
                  {k: (round(v, 3) if isinstance(v, float) else v)
                   for k, v in metrics(res, m).items()}, flush=True)


def rough(seeds: list[int], duration: float) -> None:
    for which in ("before", "after"):
        m = model(which)
        for seed in seeds:
            prof = parse_irregularity(f"{IRREGULARITY}:{seed}",
                                      span_length_m=m.guideway.span.length_m)
            for fail in ((), (Failure(FAILED, 0.5),)):
                t0 = time.perf_counter()
                res = m.run(speed_m_per_s=500 / 3.6, duration_s=duration, irregularity=prof,
                            failures=fail)
                mm = metrics(res, m)
                print(which, seed, "failed" if fail else "intact",
                      f"{time.perf_counter() - t0:.1f}s", f"min gap {mm['min_gap_mm']:.2f} mm",
                      f"t_end {float(res.dataset.time[-1]):.2f} s", mm["touchdown"], flush=True)


def figure(out: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    span_t = 24.768 / (400 / 3.6)
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for which, colour in (("before", "tab:red"), ("after", "tab:blue")):
        m = model(which)
        res = m.run(speed_m_per_s=400 / 3.6, duration_s=1.5)
        ds = res.dataset
        t = ds.time.values
        sel = (t >= 1.0) & (t <= 1.0 + 2 * span_t)
        j = list(ds.circuit.values).index("s2m4/front")
        axes[0].plot(t[sel], ds.current.values[sel, j], color=colour, label=which)
        axes[1].plot(t[sel], 1e3 * ds.gap.values[sel, j], color=colour, label=which)
    axes[0].set_ylabel("coil current s2m4/front [A]")
    axes[0].axhline(0.0, color="k", lw=0.5)
    axes[1].set_ylabel("gap s2m4/front [mm]")
    axes[1].set_xlabel("time [s] (two spans at 400 km/h, smooth elastic guideway)")
    axes[0].legend(title="bundled train and guideway")
    axes[0].set_title("Pier crossing before / after precamber, velocity-blended damping, diodes")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "smooth":
        smooth(float(sys.argv[2]) if len(sys.argv) > 2 else 3.0)
    elif what == "ablation":
        smooth(float(sys.argv[2]) if len(sys.argv) > 2 else 3.0,
               ("no-precamber", "no-blend", "no-diode"))
    elif what == "rough":
        rough([int(s) for s in sys.argv[2].split(",")],
              float(sys.argv[3]) if len(sys.argv) > 3 else 12.0)
    else:
        figure(sys.argv[2])
