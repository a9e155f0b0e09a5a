"""Figures of docs/cross_section.md: curve entry and crosswind gust at 400 km/h, failure of
one guidance circuit (the cross-section model, reduced magnets).

Run: ``PYTHONPATH=src python tools/cross_section_figures.py [OUTDIR]`` (default
docs/figures); prints the minimum gaps it reports in the docs.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from maglevkit.vehicle.crossplots import plot_cross_section_run
from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind, TransitionCurve
from maglevkit.vehicle.simulation import Failure


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/figures")
    model = CrossSectionModel()
    v = 400 / 3.6
    cases = {
        "cross-section-curve-400": ("curve entry R 4000 m, 12 deg, 300 m transition",
                                    {"curve": TransitionCurve(4000.0, math.radians(12.0),
                                                              300.0, start_m=50.0)}, 6.0),
        "cross-section-gust-400": ("1-cosine gust 10 kN (0.5 s rise, 1 s hold)",
                                   {"crosswind": Crosswind(1.0e4, rise_s=0.5, hold_s=1.0,
                                                           start_s=0.3)}, 5.0),
        "cross-section-guidance-failure": ("guidance circuit left/front off at 0.2 s",
                                           {"failures": [Failure("guidance_left/front",
                                                                 0.2)]}, 2.0),
    }
    for name, (label, kw, dur) in cases.items():
        run = model.run(speed_m_per_s=v, duration_s=dur, **kw)   # type: ignore[arg-type]
        run.dataset.attrs["scenario"] = label
        for p in plot_cross_section_run(run.dataset, out, name=name):
            print("wrote", p)
        ds = run.dataset
        print(f"{name}: min levitation gap {float(ds.levitation_gap.min()) * 1e3:.3f} mm, "
              f"max {float(ds.levitation_gap.max()) * 1e3:.3f} mm; min guidance gap "
              f"{float(ds.guidance_gap.min()) * 1e3:.3f} mm, max "
              f"{float(ds.guidance_gap.max()) * 1e3:.3f} mm; peak |a_y| "
              f"{float(abs(ds.car_body_lateral_acceleration).max()):.3f} m/s^2; "
              f"comfort {run.comfort}; touchdown {run.touchdown}; "
              f"{run.real_time_factor:.1f}x real time")


if __name__ == "__main__":
    main()
