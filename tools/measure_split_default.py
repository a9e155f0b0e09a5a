"""Measure what making ``flux_paths = "split"`` the TR09 default would cost (issue 26, part 2).

Not part of the package: a measuring script for docs/decisions.md ("Switching the TR09
magnets to the split network: cost and consequences").  Run from the repository root with
``PYTHONPATH=src``; every part prints one line per measurement (CPU time of this process
and wall time).  The split magnet files are copies of the bundled ones with
``flux_paths = "split"`` added (written to ``--scratch``).

Examples::

    python tools/measure_split_default.py maps --magnet tr09-standard --variant split
    python tools/measure_split_default.py statics --magnet tr09-standard
    python tools/measure_split_default.py flux --magnet tr09-standard --variant split
    python tools/measure_split_default.py vehicle --variant split
"""
from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "src" / "maglevkit" / "data"


def magnet_file(name: str, variant: str, scratch: Path) -> str:
    """Bundled name (``"paper"``) or a copy with ``flux_paths = "split"``."""
    if variant == "paper":
        return name
    text = (DATA / f"{name}.toml").read_text()
    out = scratch / f"{name}-split.toml"
    out.write_text(text.replace("[magnet]\n", '[magnet]\nflux_paths = "split"\n', 1))
    return str(out)


def vehicle_file(variant: str, scratch: Path) -> str:
    """The bundled TR09 vehicle, or a copy whose magnets are the split copies."""
    if variant == "paper":
        return "tr09"
    text = (DATA / "vehicle" / "tr09.toml").read_text()
    for name, key in (("tr09-standard", "standard_magnet"), ("tr09-bow", "bow_magnet")):
        text = text.replace(f'{key} = "{name}"', f'{key} = "{magnet_file(name, variant, scratch)}"')
    out = scratch / "tr09-split.toml"
    out.write_text(text)
    return str(out)


def cpu_now() -> float:
    """CPU time [s] of this process and its finished children (the C compiler)."""
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ch.ru_utime + ch.ru_stime


class Clock:
    """CPU (this process and its children) and wall time of a block."""

    def __enter__(self) -> Clock:
        self.c0, self.w0 = cpu_now(), time.perf_counter()
        return self

    def __exit__(self, *exc: object) -> None:
        self.cpu = cpu_now() - self.c0
        self.wall = time.perf_counter() - self.w0


def load() -> str:
    return "load {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def part_maps(a: argparse.Namespace) -> None:
    from maglevkit.magnets import load_magnet
    from maglevkit.reduction.maps import build_maps
    from maglevkit.vehicle.mapcache import vehicle_maps

    mag = load_magnet(magnet_file(a.magnet, a.variant, a.scratch))
    d = a.scratch / f"maps-{a.variant}"      # empty it before timing: built, not read
    d.mkdir(exist_ok=True)
    print(load(), flush=True)
    with Clock() as t:
        vehicle_maps(mag, cache_dir=d)
    print(f"maps vehicle-grid 21x51 {a.magnet} {a.variant}: cpu {t.cpu:.1f} s "
          f"wall {t.wall:.1f} s; {load()}", flush=True)
    with Clock() as t:
        build_maps(mag, gaps_m=np.linspace(0.004, 0.020, 17), currents_A=np.linspace(0, 80, 33))
    print(f"maps cli-default 17x33 {a.magnet} {a.variant}: cpu {t.cpu:.1f} s "
          f"wall {t.wall:.1f} s; {load()}", flush=True)


def part_statics(a: argparse.Namespace) -> None:
    from maglevkit.magnets import load_magnet
    from maglevkit.models.statics import solve_statics

    for variant in ("paper", "split"):
        mag = load_magnet(magnet_file(a.magnet, variant, a.scratch))
        g = np.linspace(0.006, 0.020, 8)
        c = np.linspace(10.0, 100.0, 10)
        solve_statics(mag, gaps_m=0.01, currents_A=33.5)
        with Clock() as t:
            r = solve_statics(mag, gaps_m=g, currents_A=c, grid=True)
        n = g.size * c.size
        print(f"statics {a.magnet} {variant}: {1e3 * t.cpu / n:.2f} ms cpu / point "
              f"({1e3 * t.wall / n:.2f} ms wall), {n} points; {load()}", flush=True)
        del r


def part_flux(a: argparse.Namespace) -> None:
    from maglevkit.magnets import load_magnet
    from maglevkit.models.flux import FluxModel, simulate_flux
    from maglevkit.models.signals import Sine

    mag = load_magnet(magnet_file(a.magnet, a.variant, a.scratch))
    op = mag.parameters["operating"]
    s0, i0 = float(op["nominal_gap"]), float(op["nominal_current"])
    print(f"{a.magnet} {a.variant}: {len(mag.network.resistances)} circuits", flush=True)
    for compiled in a.compiled:
        with Clock() as t:
            fm = FluxModel(mag, compiled=compiled)
        print(f"FluxModel {a.magnet} {a.variant} compiled={compiled}: construct cpu "
              f"{t.cpu:.2f} s wall {t.wall:.2f} s", flush=True)
        t = np.linspace(0.0, 1.0, 1001)         # 1 s at 1 kHz, gap sine 5 Hz
        u0 = {c: float(r) * i0 for c, r in zip(mag.circuit_names, mag.network.resistances,
                                                 strict=True)}
        gaps = Sine(s0, 1e-3, 5.0)
        with Clock() as t1:
            simulate_flux(fm, t, gaps_m=gaps, voltages_V=u0)
        with Clock() as t2:
            simulate_flux(fm, t, gaps_m=gaps, voltages_V=u0)
        print(f"  1 s at 1 kHz (gap sine 5 Hz, constant voltage): first run cpu {t1.cpu:.2f} s "
              f"wall {t1.wall:.2f} s (incl. set-up/compile), second cpu {t2.cpu:.2f} s "
              f"wall {t2.wall:.2f} s; {load()}", flush=True)


def part_vehicle(a: argparse.Namespace) -> None:
    from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity
    from maglevkit.vehicle.train import load_vehicle

    train = load_vehicle(vehicle_file(a.variant, a.scratch))
    with Clock() as t:
        model = VehicleModel(train, maps_cache=a.scratch / f"maps-{a.variant}")
    print(f"vehicle {a.variant}: set-up cpu {t.cpu:.1f} s wall {t.wall:.1f} s", flush=True)
    for kind in ("standard", "bow"):
        sel = [j for j, k in enumerate(model.circuit_kind) if k == kind]
        j = sel[0]
        print(f"  {kind}: trim force {model.trim_force_N[sel].min():.1f} ... "
              f"{model.trim_force_N[sel].max():.1f} N per circuit, trim current "
              f"{model.trim_current_A[sel].min():.3f} ... {model.trim_current_A[sel].max():.3f} A, "
              f"psi0 {model.flux_bias_Wb[j]:.4f} Wb, R_ec {model.eddy_resistance_ohm[j]:.3f} ohm, "
              + ", ".join(f"{k} {v[j]:.4g}" for k, v in model.gains.items()), flush=True)
    prof = parse_irregularity(a.irregularity, span_length_m=model.guideway.span.length_m)
    res = model.run(speed_m_per_s=a.speed_kmh / 3.6, duration_s=a.duration, dt_s=1e-3,
                    irregularity=prof, progress=False)
    ds = res.dataset
    print(res.report())
    skip = ds.time >= 0.1
    cur, vol, gap = ds["current"], ds["voltage"], ds["gap"]
    print(f"  {a.irregularity}: gap {1e3 * float(gap.min()):.3f} ... {1e3 * float(gap.max()):.3f} mm, "
          f"current {float(cur.min()):.2f} ... {float(cur.max()):.2f} A (mean "
          f"{float(cur.mean()):.2f}), |U| max {float(abs(vol).max()):.1f} V, U rms "
          f"{float((vol.where(skip) ** 2).mean() ** 0.5):.1f} V", flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("part", choices=["maps", "statics", "flux", "vehicle"])
    p.add_argument("--magnet", default="tr09-standard")
    p.add_argument("--variant", default="split", choices=["paper", "split"])
    p.add_argument("--compiled", nargs="+", default=["auto"])
    p.add_argument("--cases", type=int, default=1)
    p.add_argument("--duration", type=float, default=2.0)
    p.add_argument("--speed-kmh", type=float, default=400.0)
    p.add_argument("--irregularity", default="none")
    p.add_argument("--scratch", type=Path, default=Path(tempfile.gettempdir()) / "split26")
    a = p.parse_args()
    a.scratch.mkdir(parents=True, exist_ok=True)
    {"maps": part_maps, "statics": part_statics, "flux": part_flux,
     "vehicle": part_vehicle}[a.part](a)


if __name__ == "__main__":
    main()
