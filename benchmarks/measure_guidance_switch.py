"""The guidance magnet's eddy switch (guideswitch, issue 26): its reduced models against
the detailed model and against the transient FEM.

``compare FILE OUT.json [REF_CURRENT_A ...]``
    ``maglevkit.compare``'s standard scenarios at the file's nominal point (10 mm) on maps
    12 x 41 (5-16 mm x 0-80 A, the grid of ``compare``'s fast set): eq. 8 and the eddy
    network with 2 and 3 branches on the file's maps against the file's detailed model
    (each detailed run once, shared); with reference currents, the 2-branch network
    identified there too (``build_maps(eddy_reference=(0.010, I))``).  Then the gap sine
    of ``bench_gap_motion`` (10 +- 1 mm) at 5 / 50 / 200 Hz.  Run on the switched file
    and on the former one (``load_magnet(..., eddy_model="lumped")`` is not a file: give
    a copy of the file without its eddy lines).
``fem OUT.json``
    The bundled file's reduced models (the vehicle maps, 21 x 51) and the former ones
    (lumped elements, eq. 8) against the recorded voltage steps of the transient FEM
    (benchmarks/results/fem_guidance_transient.json), both sections stepped like the
    FEM's section; error in % of the step as ``fem_guidance_transient.metrics``.

    PYTHONPATH=src python benchmarks/measure_guidance_switch.py compare tr-guidance out.json 28 36
    PYTHONPATH=src python benchmarks/measure_guidance_switch.py fem out.json

Results of the session: benchmarks/results/guidance_switch.json; the decision:
docs/decisions.md ("guideswitch").
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk

sys.path.insert(0, str(Path(__file__).parent))

GRID = (np.linspace(0.005, 0.016, 12), np.linspace(0.0, 80.0, 41))
"""Maps of the ``compare`` runs (``compare``'s fast set, ``bench_gap_motion``)."""


def measure_compare(path: str, ref_currents: list[float]) -> dict[str, Any]:
    """Reduced models on the file's maps against its detailed model (module docstring)."""
    import bench_gap_motion as bgm
    from compare_common import compare_reduced_models

    mag = mk.load_magnet(path)
    fm = mk.FluxModel(mag)
    gap, i0 = 0.010, float(mag.nominal_current)
    maps = mk.build_maps(mag, gaps_m=GRID[0], currents_A=GRID[1], progress=False)
    reduced: dict[str, Any] = {"eq8": mk.CurrentModel(maps)}
    if mag.network.has_eddy_currents:
        reduced.update({f"modes{m}": mk.CurrentModel(maps, eddy_modes=m) for m in (2, 3)})
    for cur in ref_currents:
        other = mk.build_maps(mag, gaps_m=GRID[0], currents_A=GRID[1], progress=False,
                              eddy_reference=(gap, cur))
        reduced[f"modes2 at {cur:g} A"] = mk.CurrentModel(other, eddy_modes=2)
    rows, _ = compare_reduced_models(mag, fm, reduced, gap_m=gap, current_A=i0)
    sweep = bgm.sweep(fm, reduced, i0, frequencies=(5.0, 50.0, 200.0))
    gap_sine = {f"{r['f']:g} Hz": {label: {
        "ac_current": r[label][2], "ac_force": r[label][3],
        "phase_error_deg": float(np.degrees(np.angle(r[label][0] / r["detailed"][0])))}
        for label in reduced} for r in sweep}
    fits = {k: np.asarray(maps.dataset[k].values).tolist() for k in (
        "eddy_network_r0_ohm", "eddy_network_resistance_ohm", "eddy_network_inductance_H",
        "eddy_network_fit_rms") if k in maps.dataset}
    return {"file": path, "eddy_model": mag.options.eddy_model,
            "eddy_layers": mag.options.eddy_layers, "current_A": i0, "compare": rows,
            "gap_sine": gap_sine, "fits": fits}


def measure_fem() -> dict[str, Any]:
    """The bundled file's reduced models and the former ones against the FEM's steps."""
    import fem_guidance_transient as fgt

    from maglevkit.vehicle.mapcache import vehicle_maps

    bundled = mk.load_magnet("tr-guidance")
    lumped = mk.load_magnet("tr-guidance", eddy_model="lumped")
    ml, mb = vehicle_maps(lumped), vehicle_maps(bundled)
    models = {"lumped maps, eq. 8": mk.CurrentModel(ml), "ladder maps, eq. 8": mk.CurrentModel(mb),
              **{f"ladder maps, eddy_modes={m}": mk.CurrentModel(mb, eddy_modes=m)
                 for m in (2, 3)}}
    r_el = bundled.network.resistances
    out: dict[str, Any] = {"bundled": {"eddy_model": bundled.options.eddy_model,
                                       "eddy_layers": bundled.options.eddy_layers,
                                       "eddy_modes": bundled.default_eddy_modes}}
    for ref in fgt.load("cases"):
        for name, model in models.items():
            res = mk.simulate(model, np.asarray(ref["time_s"]), gaps_m=ref["gap_m"],
                              voltages_V=r_el * ref["i1_A"], initial_currents_A=ref["i0_A"])
            m = fgt.metrics(res.time_s, res.currents_A[:, 0], np.zeros_like(res.time_s), ref)
            out[f"{ref['label']} / {name}"] = {
                "err_1ms_pct": 100 * float(m["err_1ms"]), "err_max_pct": 100 * float(m["err_max"]),
                "t63_err_pct": 100 * float(m["t63_s"] / m["t63_fem_s"] - 1)}
            print(ref["label"], name, out[f"{ref['label']} / {name}"], flush=True)
    return out


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "compare":
        result = measure_compare(sys.argv[2], [float(c) for c in sys.argv[4:]])
        out_path = sys.argv[3]
    elif what == "fem":
        result = measure_fem()
        out_path = sys.argv[2]
    else:
        raise SystemExit("first argument: compare or fem")
    Path(out_path).write_text(json.dumps(result, indent=1))
