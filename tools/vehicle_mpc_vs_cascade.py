"""The heave-pitch train flown by the offset-free NMPC and by the cascade, side by side.

400 km/h over the bundled irregularity (``sag:0.5e-3+random:0.3e-3``, seed 0) on the
elastic guideway, a +10 % payload step (every car body 10 % heavier) at ``--step`` s; the
same run with ``controller="cascade"`` and ``controller="mpc"`` (the cascade in the NumPy
loop, as its payload step needs it; the NMPC between compiled blocks of its sample's
steps).  Prints the numbers recorded in docs/vehicle.md and docs/decisions.md and writes
the figure ``docs/figures/vehicle-mpc-vs-cascade.png``.

Usage::

    PYTHONPATH=src python tools/vehicle_mpc_vs_cascade.py [--sections 3] [--duration 7]
        [--step 1.0] [--settle 2.0] [--figure docs/figures/vehicle-mpc-vs-cascade.png]
        [--linearization target|trajectory] [--only mpc]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity
from maglevkit.vehicle.train import load_vehicle


def metrics(run, step_s: float, settle_s: float, model) -> dict[str, float]:
    ds = run.dataset
    # the inductor currents I_L (the maps' current axis) at the records from eq. 8's
    # coil current I = (U + R_ec I_L) / (R_el + R_ec), U the voltage held before the record
    r_el = np.asarray(model.bank.resistance_ohm, dtype=float)
    r_ec = model.eddy_resistance_ohm
    u_held = ds.voltage.values[:-1]
    i_l = ((r_el + r_ec) * ds.current.values[1:] - u_held) / r_ec
    t = ds.time.values
    g = ds.gap.values - float(ds.attrs["nominal_gap_m"])
    u = ds.voltage.values
    late = t >= step_s + settle_s
    ride = t >= 0.3                                   # after the start transient
    cf = run.comfort
    return {
        "gap_rms_um": float(np.sqrt(np.mean(g[ride] ** 2)) * 1e6),
        "gap_min_mm": float((g.min() + float(ds.attrs["nominal_gap_m"])) * 1e3),
        "mean_gap_error_after_step_um": float(g[late].mean() * 1e6),
        "worst_circuit_mean_error_after_step_um": float(np.abs(g[late].mean(axis=0)).max() * 1e6),
        "mean_gap_error_before_step_um": float(g[ride & (t < step_s)].mean() * 1e6),
        "peak_current_A": float(ds.current.values.max()),
        "min_current_A": float(ds.current.values[ride].min()),
        "peak_inductor_current_A": float(np.nanmax(i_l)),
        "max_abs_voltage_V": float(np.nanmax(np.abs(u))),
        "wk_rms_max_m_per_s2": max(v["wk_rms_m_per_s2"] for v in cf.values()),
        "sperling_wz_max": max(v["sperling_wz"] for v in cf.values()),
        "real_time_factor": run.real_time_factor,
        # all circuits' NMPC updates of one sample (one call), CPU time
        "update_p50_us": float(np.percentile(run.controller_update_cpu_time_s, 50) * 1e6)
        if run.controller_update_time_s.size else float("nan"),
        "update_p90_us": float(np.percentile(run.controller_update_cpu_time_s, 90) * 1e6)
        if run.controller_update_time_s.size else float("nan"),
        "update_p99_us": float(np.percentile(run.controller_update_cpu_time_s, 99) * 1e6)
        if run.controller_update_time_s.size else float("nan"),
        "cpu_real_time_factor": float(ds.time.values[-1]) / run.cpu_time_s,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sections", type=int, default=3)
    ap.add_argument("--duration", type=float, default=7.0)
    ap.add_argument("--step", type=float, default=1.0)
    ap.add_argument("--settle", type=float, default=2.0, help="transient after the step [s]")
    ap.add_argument("--figure", default="docs/figures/vehicle-mpc-vs-cascade.png")
    ap.add_argument("--json", default=None)
    ap.add_argument("--linearization", default=None,
                    help="the NMPC's linearization (default: the vehicle's)")
    ap.add_argument("--only", default=None, choices=("cascade", "mpc"))
    a = ap.parse_args()
    train = dataclasses.replace(load_vehicle(), n_sections=a.sections)
    runs, out = {}, {}
    for ctl in ("cascade", "mpc"):
        if a.only is not None and ctl != a.only:
            continue
        t0 = time.perf_counter()
        opts = ({"linearization": a.linearization}
                if ctl == "mpc" and a.linearization is not None else None)
        model = VehicleModel(train, controller=ctl, mpc_options=opts)
        build = time.perf_counter() - t0
        prof = parse_irregularity("sag:0.5e-3+random:0.3e-3",
                                  span_length_m=model.guideway.span.length_m)
        run = model.run(speed_m_per_s=400 / 3.6, duration_s=a.duration, irregularity=prof,
                        payload_step_s=a.step, payload_fraction=0.1)
        runs[ctl] = run
        out[ctl] = {"build_s": build, **metrics(run, a.step, a.settle, model)}
        print(run.report())
    print(json.dumps(out, indent=1))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    if len(runs) < 2:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(4, 1, figsize=(9, 10), sharex=True)
    col = {"cascade": "tab:blue", "mpc": "tab:red"}
    lab = {"cascade": "flux cascade", "mpc": "offset-free NMPC (RTI)"}
    for ctl, run in runs.items():
        ds = run.dataset
        t = ds.time.values
        g = (ds.gap.values - float(ds.attrs["nominal_gap_m"])) * 1e3
        # mean over circuits, averaged over 0.2 s (the offset), and one circuit raw
        k = 200
        gm = np.convolve(g.mean(axis=1), np.ones(k) / k, mode="valid")
        ax[0].plot(t[k // 2:k // 2 + gm.size], gm * 1e3, color=col[ctl],
                   label=f"{lab[ctl]}: mean over circuits, 0.2 s average")
        j = list(ds.circuit.values).index("s1m4/front")
        ax[1].plot(t, g[:, j], color=col[ctl], lw=0.7, label=f"{lab[ctl]}: s1m4/front")
        ax[2].plot(t, ds.current.values[:, j], color=col[ctl], lw=0.7, label=lab[ctl])
        ax[3].plot(t, ds.voltage.values[:, j], color=col[ctl], lw=0.5, label=lab[ctl])
    ax[0].set_ylabel("gap error [um]")
    ax[0].axhspan(-10, 10, color="green", alpha=0.15, lw=0)
    ax[1].set_ylabel("gap error [mm]")
    ax[2].set_ylabel("current s1m4/front [A]")
    ax[3].set_ylabel("voltage s1m4/front [V]")
    ax[3].axhline(440, color="k", ls=":", lw=0.8)
    ax[3].axhline(-440, color="k", ls=":", lw=0.8)
    ax[3].set_xlabel("time [s]")
    for x in ax:
        x.axvline(a.step, color="grey", ls="--", lw=0.8)
        x.legend(loc="upper right", fontsize=7)
        x.grid(alpha=0.3)
    c, m = out["cascade"], out["mpc"]
    ax[0].set_title(f"TR09-type train, {a.sections} sections, 400 km/h, sag 0.5 mm + random "
                    f"0.3 mm, +10 % payload at {a.step:g} s\n"
                    f"gap RMS {c['gap_rms_um']:.0f} / {m['gap_rms_um']:.0f} um, peak current "
                    f"{c['peak_current_A']:.0f} / {m['peak_current_A']:.0f} A, Wk a_w "
                    f"{c['wk_rms_max_m_per_s2']:.3f} / {m['wk_rms_max_m_per_s2']:.3f} m/s^2 "
                    "(cascade / NMPC)", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.figure, dpi=110)
    print("wrote", a.figure)


if __name__ == "__main__":
    main()
