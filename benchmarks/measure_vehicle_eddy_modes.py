"""What flying the TR09 vehicle on the eddy network of the diffusing eddy ladder would
change (modesveh26; docs/decisions.md): today's bundled magnets (lumped eddy elements,
eq. 8) against magnet files with ``eddy_model = "ladder"`` flown with eq. 8 and with
``eddy_modes=2``.

1. Real-time factor of the heave-pitch compiled loop (3 sections, elastic guideway, 400
   km/h, sag + random irregularity, 1 s): simulated time over the process's CPU time,
   best of ``--rounds`` interleaved rounds, one process (pin it: ``taskset -c 0``).
2. Physics: circuit s2m4's gaps, gap rates and voltages under a 50 Hz guideway wave (0.05
   mm at 400 km/h, rigid guideway, 0.3 s, python loop) replayed through the detailed
   ``FluxModel`` of the ladder magnet (the model validated against the transient FEM);
   RMS coil-current error after 0.1 s and the 50 Hz phase error (as ladder3veh did).
3. The vehicle aims of tests/test_vehicle.py and test_vehicle_compiled.py: 500 km/h
   elastic run (gap range, lowest coil current), the circuit failure at 400 km/h
   (decay, neighbour, force), the range-error time of the 2 mm / 3 m harmonic.

Writes JSON (``--output``, default benchmarks/results/vehicle_eddy_modes.json).
Usage: ``PYTHONPATH=src taskset -c 0 python benchmarks/measure_vehicle_eddy_modes.py``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit.errors import OutOfRangeError
from maglevkit.vehicle.irregularities import HarmonicProfile
from maglevkit.vehicle.simulation import Failure, VehicleModel, parse_irregularity
from maglevkit.vehicle.train import load_vehicle

sys.path.insert(0, str(Path(__file__).resolve().parent))
from replay_common import fundamental_errors, replay_detailed  # noqa: E402

DATA = Path(mk.__file__).parent / "data"


def ladder_files(folder: Path) -> dict[str, str]:
    """The bundled TR09 levitation magnet files with ``eddy_model = "ladder"`` added to
    ``[magnet]`` (the one line eddydefault26 measured)."""
    out = {}
    for name in ("tr09-standard", "tr09-bow"):
        text = (DATA / f"{name}.toml").read_text()
        text = re.sub(r"(\[magnet\]\n)", r'\1eddy_model = "ladder"\n', text, count=1)
        path = folder / f"{name}-ladder.toml"
        path.write_text(text)
        out[name] = str(path)
    return out


def configs(files: dict[str, str]) -> dict[str, tuple[Any, dict[str, Any]]]:
    train = load_vehicle()
    ladder = dataclasses.replace(train, standard_magnet=files["tr09-standard"],
                                 bow_magnet=files["tr09-bow"])
    return {"lumped, eq. 8 (bundled)": (train, {}),
            "ladder, eq. 8": (ladder, {}),
            "ladder, eddy_modes=2": (ladder, {"eddy_modes": 2})}


def real_time(models: dict[str, VehicleModel], rounds: int) -> dict[str, Any]:
    out: dict[str, Any] = {k: [] for k in models}
    for _ in range(rounds):
        for name, m in models.items():
            prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                                      span_length_m=m.guideway.span.length_m)
            m.run(speed_m_per_s=400 / 3.6, duration_s=0.05, irregularity=prof)   # warm
            c0 = time.process_time()
            m.run(speed_m_per_s=400 / 3.6, duration_s=1.0, irregularity=prof,
                  loop="compiled")
            out[name].append(time.process_time() - c0)
    return {k: {"cpu_s": v, "real_time_factor": 1.0 / min(v),
                "us_per_step": 1e6 * min(v) / 1000} for k, v in out.items()}


def physics(train: Any, kw: dict[str, Any], reference: Any) -> dict[str, float]:
    v, f = 400 / 3.6, 50.0
    m = VehicleModel(train, rigid=True, **kw)
    calls: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    step = m.bank.step

    def spy(state: Any, dt: float, u: Any, gaps: Any, rates: Any, **k: Any) -> Any:
        calls.append((np.array(u, float), np.array(gaps, float), np.array(rates, float)))
        return step(state, dt, u, gaps, rates, **k)

    m.bank.step = spy  # type: ignore[method-assign]
    run = m.run(speed_m_per_s=v, duration_s=0.3, loop="python",
                irregularity=HarmonicProfile(0.05e-3, v / f))
    calls = calls[1:]
    ds = run.dataset
    names = list(ds.circuit.values)
    idx = [names.index("s2m4/front"), names.index("s2m4/rear")]
    ref = replay_detailed(reference, m.maps["standard"].pole_groups, calls, idx,
                          initial_gaps_m=ds.gap.values[0, idx],
                          initial_currents_A=m.trim_current_A[idx],
                          first_row_A=ds.current.values[0, idx])
    return fundamental_errors(ds.time.values, ds.current.values[:, idx], ref,
                              ds.gap.values[:, idx[0]], f)


def aims(m: VehicleModel) -> dict[str, Any]:
    prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                              span_length_m=m.guideway.span.length_m)
    out: dict[str, Any] = {}
    ds = m.run(speed_m_per_s=500 / 3.6, duration_s=1.0, irregularity=prof).dataset
    g = ds.gap.values
    half = g.shape[0] // 2
    out["500kmh"] = {"gap_min_mm": 1e3 * float(g.min()), "gap_max_mm": 1e3 * float(g.max()),
                     "growth": float(np.abs(g[half:] - 0.01).max()
                                     / np.abs(g[:half] - 0.01).max()),
                     "current_min_A": float(ds.current.values.min())}
    res = m.run(speed_m_per_s=400 / 3.6, duration_s=1.5, irregularity=prof,
                failures=[Failure("s2m4/front", 0.3)])
    ds = res.dataset
    t = ds.time.values
    i_f = ds.current.sel(circuit="s2m4/front").values
    i_n = ds.current.sel(circuit="s2m4/rear").values
    weight = m.train.total_mass_kg * 9.80665
    out["failure"] = {"touchdown": res.touchdown is not None,
                      "decay_ratio": float(i_f[-1] / i_f[t < 0.3].mean()),
                      "neighbour_ratio": float(i_n[t > 0.8].mean() / i_n[t < 0.3].mean()),
                      "force_error": float(ds.force.values[t > 1.0].sum(axis=1).mean()
                                           / weight - 1)}
    low = VehicleModel(dataclasses.replace(m.train, touchdown_gap_m=1e-3),
                       eddy_modes=m.eddy_modes)
    try:
        low.run(speed_m_per_s=400 / 3.6, duration_s=0.3,
                irregularity=HarmonicProfile(2e-3, 3.0))
        out["range_error"] = None
    except OutOfRangeError as exc:
        out["range_error"] = str(exc).split(":")[0]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--output", default="benchmarks/results/vehicle_eddy_modes.json")
    ap.add_argument("--skip", nargs="*", default=[], choices=["speed", "physics", "aims"])
    a = ap.parse_args()
    result: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        files = ladder_files(Path(tmp))
        cfg = configs(files)
        models = {k: VehicleModel(tr, **kw) for k, (tr, kw) in cfg.items()}
        result["max_step_s"] = {k: m.bank.max_step_s for k, m in models.items()}
        if "speed" not in a.skip:
            result["speed"] = real_time(models, a.rounds)
            print(json.dumps(result["speed"], indent=1), flush=True)
        if "physics" not in a.skip:
            ref = mk.load_magnet(files["tr09-standard"])
            result["physics"] = {k: physics(tr, kw, ref) for k, (tr, kw) in cfg.items()}
            lumped_ref = mk.load_magnet("tr09-standard")
            result["physics_own_detailed"] = {
                "lumped, eq. 8 (bundled)": physics(*cfg["lumped, eq. 8 (bundled)"], lumped_ref)}
            print(json.dumps(result["physics"], indent=1), flush=True)
        if "aims" not in a.skip:
            result["aims"] = {k: aims(m) for k, m in models.items()}
            print(json.dumps(result["aims"], indent=1), flush=True)
    out = Path(a.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
