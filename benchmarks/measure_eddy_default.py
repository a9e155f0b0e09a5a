"""Lumped eddy elements vs the diffusing eddy ladder on the bundled Transrapid magnets.

Issue 26 item 2 (eddydefault26): which eddy model the bundled ``tr09-standard``,
``tr09-bow`` and ``tr-guidance`` files should use.  Two measurements, each per magnet and
per ``eddy_model`` (``"lumped"``, ``"ladder"`` with 6 layers on the levitation magnets
and 8 on the guidance magnet; ``end_effects`` as bundled, i.e. true):

``maps``
    The cost of a map set: ``build_maps`` on the vehicle grid (``vehicle.mapcache``,
    21 x 51) and, for the levitation magnets, on the 12 x 41 grid of ``maglevkit demo``
    and ``compare``; one fresh process per set with an empty ``MAGLEVKIT_CACHE_DIR``
    (cold cache); CPU time of the process and its children, wall time.  Also the fits
    stored in the maps (``R_ec`` from the step, the shielded-gap ladders' residuals).
``accuracy``
    The reduced model on maps of each eddy model against the detailed model of the same
    eddy model: ``maglevkit.compare``'s standard scenarios (NRMS and AC-normalised errors
    of current and force) for eq. 8, the two-state ladder (``motion_eddy=True``) and the
    three-state ladder (``eddy_branches=2``); the gap sine of ``bench_gap_motion`` at 5 /
    50 / 200 Hz on ``tr09-standard``; eq. 8 with ``eddy_modes`` 2 and 3 (the RL eddy network
    fitted to the voltage step); the detailed model's CPU time per simulated second
    in each scenario (each detailed run done once and shared by the reduced models).

``bar``
    The physical check of the 3-D question (no FEM): a solid bar of the TR09 core's, the
    TR09 pole back's and a guidance yoke's section in a uniform tangential field, linear
    iron: its exact diffusion in the section (eddy currents closing round all four sides)
    against the slab of the 2-D cut, the slab ladder with the Saint-Venant factor and the
    lumped element (:func:`bar_check`).

``python benchmarks/measure_eddy_default.py maps NAME MODEL GRID OUT.json`` (one set per
process, for the cold cache; GRID ``vehicle`` or ``demo``) and ``... accuracy NAME MODEL
OUT.json [MAPS_MODEL]`` (MAPS_MODEL: the reduced models on the maps of the other eddy
model, against this detailed model) and ``... bar OUT.json``.  Results of the
session: benchmarks/results/eddy_default.json; the decision: docs/decisions.md
("eddydefault26").
"""

from __future__ import annotations

import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

LAYERS = {"tr09-standard": 6, "tr09-bow": 6, "tr-guidance": 8}
"""Ladder layers per bundled magnet: those of its transient FEM comparison
(docs/validation_fem.md: n = 6 for TR09 within 1.1 % of the step, n = 8 for guidance)."""
ACCURACY_GRID = (np.linspace(0.005, 0.016, 12), np.linspace(0.0, 80.0, 41))
"""Maps of the accuracy runs: the grid of ``compare``'s fast set and ``bench_gap_motion``."""


def load(name: str, model: str) -> Any:
    """The bundled magnet ``name`` with ``eddy_model = model``."""
    import maglevkit as mk

    if model == "lumped":   # explicit: the TR09 files name the ladder since switch26m
        return mk.load_magnet(name, eddy_model="lumped")
    return mk.load_magnet(name, eddy_model=model, eddy_layers=LAYERS[name])


def _cpu() -> float:
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _fits(ds: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in ("eddy_resistance_fit_ohm", "eddy_resistance_ohm", "motion_eddy_fit_rms",
                "motion_eddy_jump_resistance_ohm", "motion_eddy_unshielded_inductance_H",
                "motion_eddy_shielding_resistance_ohm", "motion_eddy3_fit_rms"):
        if key in ds:
            out[key] = [float(v) for v in np.ravel(ds[key].values)]
    return out


def measure_maps(name: str, model: str, grid: str) -> dict[str, Any]:
    """Build one map set in this process (cold cache) and time it."""
    from maglevkit.reduction.maps import build_maps
    from maglevkit.vehicle.mapcache import VEHICLE_MAP_CURRENTS_A, VEHICLE_MAP_GAPS_M

    g, c = ((VEHICLE_MAP_GAPS_M, VEHICLE_MAP_CURRENTS_A) if grid == "vehicle"
            else ACCURACY_GRID)
    c0, w0 = _cpu(), time.perf_counter()
    mag = load(name, model)
    maps = build_maps(mag, gaps_m=g, currents_A=c, progress=False)
    cpu, wall = _cpu() - c0, time.perf_counter() - w0
    return {"magnet": name, "eddy_model": model, "grid": f"{g.size} x {c.size}",
            "branches": len(mag.network.branches), "cpu_s": cpu, "wall_s": wall,
            **_fits(maps.dataset)}


def measure_accuracy(name: str, model: str, maps_model: str | None = None) -> dict[str, Any]:
    """The reduced models on the maps of ``maps_model`` (default: ``model``) against the
    detailed model of eddy model ``model`` (the statics of both are the same: the ladder's
    tubes carry one flux density, so the maps differ only in their eddy fits)."""
    from compare_common import compare_reduced_models

    import maglevkit as mk

    mag = load(name, model)
    fm = mk.FluxModel(mag)
    gap, i0 = 0.010, float(mag.nominal_current)
    c0 = time.process_time()
    maps = mk.build_maps(mag if maps_model in (None, model) else load(name, maps_model),
                         gaps_m=ACCURACY_GRID[0], currents_A=ACCURACY_GRID[1], progress=False)
    maps_cpu = time.process_time() - c0
    reduced = {"eq8": mk.CurrentModel(maps),
               "ladder": mk.CurrentModel(maps, motion_eddy=True)}
    try:
        reduced["ladder3"] = mk.CurrentModel(maps, motion_eddy=True, eddy_branches=2)
    except mk.MaglevkitError as exc:   # no three-state fit in these maps: say so
        print(f"no three-state ladder: {exc}", file=sys.stderr)
    for m in (2, 3):   # eq. 8 with the RL eddy network fitted to the voltage step
        reduced[f"modes{m}"] = mk.CurrentModel(maps, eddy_modes=m)
    # every detailed run once (compare_common)
    rows, det_cpu = compare_reduced_models(mag, fm, reduced, gap_m=gap, current_A=i0)
    out: dict[str, Any] = {"magnet": name, "eddy_model": model,
                           "maps_eddy_model": maps_model or model, "current_A": i0,
                           "maps_cpu_s": maps_cpu, "compare": rows,
                           "detailed_cpu_s_per_scenario": det_cpu, **_fits(maps.dataset)}
    if name in ("tr09-standard", "tr-guidance"):
        sys.path.insert(0, str(Path(__file__).parent))
        import bench_gap_motion as bgm

        t0 = time.process_time()
        sweep = bgm.sweep(fm, reduced, i0, frequencies=(5.0, 50.0, 200.0))
        out["gap_sine_cpu_s"] = time.process_time() - t0
        out["gap_sine"] = {f"{r['f']:g} Hz": {
            label: {"ac_current": r[label][2], "ac_force": r[label][3],
                    "phase_error_deg": float(np.degrees(np.angle(r[label][0] / r["detailed"][0])))}
            for label in reduced} for r in sweep}
    return out


def _ladder_admittance(s: np.ndarray, layers: int, factor: float) -> np.ndarray:
    """``Phi / (MMF P_0)`` of the ``layers``-tube slab ladder with every conductance times
    ``factor``, ``s`` in units of ``1/tau`` (``tau = mu sigma b^2``): the Cauer form of
    ``circuit.ladder`` with ``P_k = a_k P_0``, ``G_k P_0 = factor w_k tau`` (``layers =
    1``: the lumped element, ``G P_0 = factor tau/3``)."""
    from maglevkit.circuit.ladder import LADDER_COEFFICIENTS

    a, w = LADDER_COEFFICIENTS[layers]
    y = a[-1] + 0.0 * s           # admittance of tube n and everything inside it
    for k in range(layers - 2, -1, -1):
        y = a[k] + 1.0 / (s * factor * w[k + 1] + 1.0 / y)
    return 1.0 / (s * factor * w[0] + 1.0 / y)


def _talbot_step(fn: Any, t: float, m: int = 32) -> float:
    """Inverse Laplace transform of ``fn(s)/s`` at ``t`` (fixed Talbot, Abate-Valko)."""
    r = 2.0 * m / (5.0 * t)
    theta = np.arange(1, m) * np.pi / m
    cot = 1.0 / np.tan(theta)
    sk = r * theta * (cot + 1j)
    sig = theta + (theta * cot - 1.0) * cot
    head = 0.5 * np.exp(r * t) * fn(np.array([r + 0j]))[0] / r
    tail = np.sum((np.exp(t * sk) * fn(sk) / sk * (1.0 + 1j * sig)).real)
    return float((r / m) * (head.real + tail))


def bar_check(thickness_m: float, depth_m: float, layers: int) -> dict[str, Any]:
    """A solid bar of ``thickness x depth`` section in a uniform tangential field (a core
    inside its coil, linear iron): its exact diffusion in the section (the 3-D bar, eddy
    currents closing round all four sides; double Fourier series) against the 2-D cut's
    slab, the slab ladder with the Saint-Venant factor (``eddy_model = "ladder"`` with
    ``end_effects``) and the lumped element (``EddyCurrent.solid_rectangular``, the
    one-tube ladder with the same factor).  Returns the largest relative error of
    ``Phi/(MMF P_0)`` against the bar's over ``omega tau`` in 1e-3 ... 1e3 and the flux's
    response to an MMF step (share of its final value) at ``t/tau`` = 1e-4 ... 1, ``tau =
    mu sigma (t/2)^2`` (12 s for a TR09 core at mu_r 400)."""
    from maglevkit.circuit.ladder import saint_venant_factor

    f = saint_venant_factor(thickness_m, depth_m)
    r = depth_m / thickness_m
    odd = np.arange(1, 600, 2, dtype=float)
    m, n = np.meshgrid(odd, odd, indexing="ij")
    coef = 64.0 / (np.pi ** 4 * m ** 2 * n ** 2)
    coef /= coef.sum()            # the truncated series' static value exactly 1
    lam = (np.pi ** 2 / 4.0) * (m ** 2 + n ** 2 / r ** 2)   # in 1/tau (b = t/2)
    models = {
        "bar": lambda s: np.array([np.sum(coef * lam / (lam + sk)) for sk in s]),
        "2-D slab": lambda s: np.tanh(np.sqrt(s)) / np.sqrt(s),
        f"ladder n = {layers}": lambda s: _ladder_admittance(s, layers, f),
        "lumped": lambda s: _ladder_admittance(s, 1, f)}
    w = np.geomspace(1e-3, 1e3, 61)
    ref = models["bar"](1j * w)
    times = [1e-4, 1e-3, 1e-2, 1e-1, 1.0]
    out: dict[str, Any] = {"saint_venant_factor": f, "depth_over_thickness": r,
                           "step_times_t_over_tau": times}
    for label, fn in models.items():
        out[label] = {"max_rel_error_vs_bar": float(np.max(np.abs(fn(1j * w) / ref - 1.0))),
                      "low_frequency_slope": float(((1.0 / fn(np.array([1e-6 + 0j]))[0]
                                                     - 1.0) / 1e-6).real),
                      "step": [_talbot_step(fn, t) for t in times]}
    return out


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "maps":
        name, model, grid, path = sys.argv[2:6]
        with tempfile.TemporaryDirectory() as cache:
            os.environ["MAGLEVKIT_CACHE_DIR"] = cache
            result = measure_maps(name, model, grid)
    elif what == "bar":   # TR09 core 0.12 m (diffusion, along the track) x 0.17 m, back
        # 0.08 x 0.17 m; a guidance yoke block 0.07 m (t_y) x 0.30 m (bundled files)
        path = sys.argv[2]
        result = {"core": bar_check(0.12, 0.17, 6), "back": bar_check(0.08, 0.17, 6),
                  "guidance yoke": bar_check(0.07, 0.30, 8)}
    elif what == "accuracy":
        name, model, path = sys.argv[2:5]
        result = measure_accuracy(name, model, *sys.argv[5:6])
    else:
        raise SystemExit("first argument: maps or accuracy")
    Path(path).write_text(json.dumps(result, indent=1))
    print(json.dumps(result, indent=1))
