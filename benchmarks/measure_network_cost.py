"""Where the eddy network's cost per vehicle step went, and the two changes of netperf
(docs/decisions.md, "netperf"), before and after in one process.

1. ``MagnetBank.outputs`` (every vehicle run with eddy states calls it once for the
   initial currents and forces): the circuit function mapped over the circuits
   (``output_function``, the path before) against every circuit inlined into one graph
   (``_outputs_inlined``, now), on the TR09 vehicle's bank (50 circuits).
2. The SIMD lanes' loop with one block of lanes per iteration (before) against two
   interleaved blocks (``_LANE_INTERLEAVE = 2``, now): the bank's compiled step alone,
   100 TR09 circuits on the maps of the diffusing eddy ladder (12 x 41), eq. 8, the
   two-state ladder and the eddy network (``eddy_modes=2``), ns per circuit-step.
3. The heave-pitch vehicle (3 sections, elastic guideway, 400 km/h, sag + random, 1 s,
   compiled loop), magnet files with ``eddy_model = "ladder"`` (as
   ``measure_vehicle_eddy_modes.py``), eq. 8 and ``eddy_modes=2``, each with both changes
   off (before) and on (after): CPU time per step of the whole ``run`` and of the
   compiled block alone.

CPU time (``time.process_time``), best of ``--rounds`` interleaved rounds; results must
be equal bit for bit between before and after (checked, printed).  Pin it:
``PYTHONPATH=src taskset -c 0 python benchmarks/measure_network_cost.py``.  Writes JSON
(``--output``, default benchmarks/results/network_cost.json).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk
import maglevkit.reduced.bank as bank_module
from maglevkit.errors import ProvenanceWarning
from maglevkit.reduced.bank import MagnetBank

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing_common import bind_buffer, cpu_per_call, sibling_module  # noqa: E402

HERE = Path(__file__).parent
DT = 1e-3


def _mapped_outputs(bank: MagnetBank) -> Any:
    """The path before: ``output_function`` (the circuit function mapped), same inputs."""
    f = bank.output_function
    return lambda *args: f(*args[:-1])


def outputs_cost(model: Any, rounds: int) -> dict[str, Any]:
    bank = model.bank
    st = bank.initial_state(gaps_m=np.full(bank.n_gaps, 0.0101),
                            currents_A=model.trim_current_A)
    new = bank._outputs_inlined()
    old = _mapped_outputs(bank)
    args = [st.inductor_currents_A, bank.resistance_ohm * st.inductor_currents_A,
            bank.circuit_gaps(st.gaps_m)]
    if st.eddy_currents_A is not None:
        args.append(np.random.default_rng(0).normal(size=st.eddy_currents_A.shape))
    a, b = new(*args, bank._par), old(*args, bank._par)
    equal = all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(a, b, strict=True))
    t_old, t_new = [], []
    for _ in range(rounds):
        t_old.append(cpu_per_call(lambda: old(*args, bank._par), 5))
        t_new.append(cpu_per_call(lambda: new(*args, bank._par), 20))
    return {"circuits": bank.n_circuits, "table_size": int(bank.table.size),
            "mapped_ms": 1e3 * min(t_old), "inlined_ms": 1e3 * min(t_new),
            "ratio": min(t_old) / min(t_new), "bit_equal": bool(equal)}


def kernel_cost(maps: mk.CharacteristicMaps, cache: Path, rounds: int) -> dict[str, Any]:
    """The bank's compiled (lanes) step alone, interleave 1 and 2, 100 circuits."""
    rng = np.random.default_rng(3)
    out: dict[str, Any] = {}
    calls: dict[tuple[str, int], Callable[[], None]] = {}
    keep: list[Any] = []
    for label, opts in (("eq. 8", {}), ("two-state ladder", {"motion_eddy": True}),
                        ("eddy network (eddy_modes=2)", {"eddy_modes": 2})):
        members = {f"m{k}": maps for k in range(100 // len(maps.circuits))}
        bank = MagnetBank(members, compiled="always", cache_dir=cache, **opts)
        nc = bank.n_circuits
        n = bank._substeps(DT)
        args = [33.5 * (1 + 0.05 * rng.normal(size=nc)), 0.01 + 5e-4 * rng.normal(size=nc),
                bank.resistance_ohm * 33.5 + 30 * rng.normal(size=nc),
                0.02 * rng.normal(size=nc), np.array([DT])]
        if bank.n_eddy_states:
            args.append(0.3 * rng.normal(size=nc * bank.n_eddy_states))
        results = {}
        for il in (1, 2):
            bank_module._LANE_INTERLEAVE = il
            bank._lanes.clear()
            f = bank._lanes_kernel(n)
            assert f is not None
            ev, res, bound = bind_buffer(f, args)
            ev()
            results[il] = [r.copy() for r in res]
            keep.append((bound, res))
            calls[(label, il)] = ev
        bank_module._LANE_INTERLEAVE = 2
        out[label] = {"circuits": nc, "substeps": n, "bit_equal": all(
            np.array_equal(x, y, equal_nan=True) for x, y in zip(results[1], results[2],
                                                                 strict=True))}
    times: dict[tuple[str, int], list[float]] = {k: [] for k in calls}
    for _ in range(rounds):
        for k, ev in calls.items():
            times[k].append(cpu_per_call(ev, 2000))
    for (label, il), v in times.items():
        nc = out[label]["circuits"]
        out[label][f"interleave{il}_ns"] = 1e9 * min(v) / nc
    for d in out.values():
        d["ratio"] = d["interleave1_ns"] / d["interleave2_ns"]
    return out


def vehicle_cost(files: dict[str, str], rounds: int) -> dict[str, Any]:
    from maglevkit.vehicle import framework
    from maglevkit.vehicle import simulation as sim
    from maglevkit.vehicle.simulation import VehicleModel, parse_irregularity

    veh = sibling_module("measure_vehicle_eddy_modes")
    cfg = veh.configs(files)
    models: dict[tuple[str, str], Any] = {}
    captured: dict[str, Any] = {}
    orig = framework.run_blocks

    def spy(function: Any, **kw: Any) -> Any:
        captured.update(kw, function=function)
        return orig(function, **kw)

    sim.run_blocks = spy    # type: ignore[attr-defined]
    blocks: dict[tuple[str, str], Any] = {}
    records: dict[tuple[str, str], Any] = {}
    try:
        for key in ("ladder, eq. 8", "ladder, eddy_modes=2"):
            for when in ("before", "after"):
                tr, kw = cfg[key]
                m = VehicleModel(tr, **kw)
                if when == "before":
                    bank_module._LANE_INTERLEAVE = 1
                    m.bank._outputs_inlined = (   # type: ignore[method-assign]
                        lambda b=m.bank: _mapped_outputs(b))
                prof = parse_irregularity("sag:0.5e-3+random:0.3e-3:1",
                                          span_length_m=m.guideway.span.length_m)
                run = m.run(speed_m_per_s=400 / 3.6, duration_s=0.3, irregularity=prof,
                            loop="compiled")
                bank_module._LANE_INTERLEAVE = 2
                records[(key, when)] = run.dataset
                f, nb = captured["function"], captured["block_steps"]
                s = np.array(captured["state"], dtype=float)
                c = np.ascontiguousarray(captured["constants"], dtype=float)
                for b in range(2):      # a state away from the start
                    p = np.ascontiguousarray(captured["inputs"][b * nb:(b + 1) * nb])
                    s = np.asarray(f(s, p.T, c)[0]).ravel()
                p = np.ascontiguousarray(captured["inputs"][2 * nb:3 * nb])
                buf, ev = f.buffer()
                s_out = np.zeros_like(s)
                r = np.zeros(captured["n_record"] * nb)
                for i, a in enumerate((s, p, c)):
                    buf.set_arg(i, memoryview(a))
                buf.set_res(0, memoryview(s_out))
                buf.set_res(1, memoryview(r))
                blocks[(key, when)] = (ev, nb, buf, s, p, c, s_out, r)
                models[(key, when)] = (m, prof)
    finally:
        sim.run_blocks = orig   # type: ignore[attr-defined]
    out: dict[str, Any] = {}
    for key in ("ladder, eq. 8", "ladder, eddy_modes=2"):
        a, b = records[(key, "before")], records[(key, "after")]
        out[key] = {"bit_equal_0.3s_run": all(
            np.array_equal(a[v].values, b[v].values, equal_nan=True) for v in a.data_vars)}
    run_t: dict[tuple[str, str], list[float]] = {k: [] for k in models}
    block_t: dict[tuple[str, str], list[float]] = {k: [] for k in models}
    for _ in range(rounds):
        for k, (m, prof) in models.items():
            c0 = time.process_time()
            m.run(speed_m_per_s=400 / 3.6, duration_s=1.0, irregularity=prof, loop="compiled")
            run_t[k].append((time.process_time() - c0) / 1000)
            ev, nb = blocks[k][:2]
            block_t[k].append(cpu_per_call(ev, 100) / nb)
    for (key, when) in models:
        out[key][f"run_us_{when}"] = 1e6 * min(run_t[(key, when)])
        out[key][f"block_us_{when}"] = 1e6 * min(block_t[(key, when)])
        out[key][f"real_time_factor_{when}"] = 1e-3 / min(run_t[(key, when)])
    for key in out:
        d = out[key]
        d["run_ratio"] = d["run_us_before"] / d["run_us_after"]
        d["block_ratio"] = d["block_us_before"] / d["block_us_after"]
    net, eq8 = out["ladder, eddy_modes=2"], out["ladder, eq. 8"]
    out["network_over_eq8"] = {w: net[f"run_us_{w}"] / eq8[f"run_us_{w}"]
                               for w in ("before", "after")}
    out["network_over_eq8_block"] = {w: net[f"block_us_{w}"] / eq8[f"block_us_{w}"]
                                     for w in ("before", "after")}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--output", default=str(HERE / "results" / "network_cost.json"))
    a = ap.parse_args()
    warnings.simplefilter("ignore", ProvenanceWarning)
    result: dict[str, Any] = {"load_average_start": list(np.round(_load(), 2))}
    gm = sibling_module("bench_gap_motion")
    veh = sibling_module("measure_vehicle_eddy_modes")
    with tempfile.TemporaryDirectory() as tmp:
        files = veh.ladder_files(Path(tmp))
        ladder_maps = mk.build_maps(mk.load_magnet(files["tr09-standard"]),
                                    gaps_m=gm.GRID[0], currents_A=gm.GRID[1], progress=False)
        result["kernel"] = kernel_cost(ladder_maps, Path(tmp), a.rounds)
        print(json.dumps(result["kernel"], indent=1), flush=True)
        result["vehicle"] = vehicle_cost(files, a.rounds)
        print(json.dumps(result["vehicle"], indent=1), flush=True)
        from maglevkit.vehicle.simulation import VehicleModel
        tr, kw = veh.configs(files)["ladder, eddy_modes=2"]
        result["outputs"] = outputs_cost(VehicleModel(tr, **kw), a.rounds)
        print(json.dumps(result["outputs"], indent=1), flush=True)
    result["load_average_end"] = list(np.round(_load(), 2))
    out = Path(a.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))


def _load() -> tuple[float, float, float]:
    import os

    return os.getloadavg() if hasattr(os, "getloadavg") else (math.nan,) * 3


if __name__ == "__main__":
    main()
