"""Reduced models against one detailed model on ``compare``'s standard scenarios, each
detailed run once: shared by ``measure_eddy_default`` and ``measure_guidance_switch``.

``compare_models`` simulates the detailed model afresh for every reduced model it is given;
these scripts compare several reduced models (eq. 8, eddy networks, ladders) against the
same detailed model, so the detailed runs are memoised by their inputs while the helper
runs (the same inputs give the same run).  The scripts put this folder on ``sys.path`` to
import it (as they do ``fem_common``).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np


def compare_reduced_models(magnet: Any, detailed: Any, reduced: dict[str, Any], *,
                           gap_m: float, current_A: float
                           ) -> tuple[dict[str, Any], dict[str, tuple[float, float]]]:
    """Largest errors per reduced model and scenario, and the detailed runs' CPU time.

    Parameters
    ----------
    magnet : maglevkit.Magnet
        The magnet whose standard scenarios are run.
    detailed : maglevkit.FluxModel
        Its detailed model (each of its runs is computed once).
    reduced : dict of str to maglevkit.CurrentModel
        The reduced models, by label.
    gap_m : float
        Operating gap [m].
    current_A : float
        Operating current [A].

    Returns
    -------
    rows : dict
        ``rows[label][scenario]`` with ``nrms_current``, ``nrms_force``, ``ac_current``,
        ``ac_force`` (largest over the circuits, fractions).
    detailed_cpu : dict
        ``scenario -> (CPU time of its detailed run [s], simulated duration [s])``.
    """
    import maglevkit.compare as cmp
    from maglevkit.compare import compare_models, standard_scenarios

    runs: dict[Any, Any] = {}
    cpu: list[float] = []
    sim, loop = cmp.simulate, cmp.closed_loop

    def shared(fn: Any, label: str) -> Any:
        def run(m: Any, *a: Any, **kw: Any) -> Any:
            if m is not detailed:
                return fn(m, *a, **kw)
            key = (label, repr(a), kw.get("dt_s"), kw.get("duration_s"), id(kw.get("gaps_m")),
                   id(kw.get("voltages_V")), id(kw.get("gap_reference_m")),
                   id(kw.get("external_force_N")))
            if key not in runs:
                t0 = time.process_time()
                runs[key] = fn(m, *a, **kw)
                cpu.append(time.process_time() - t0)
            return runs[key]
        return run

    cmp.simulate, cmp.closed_loop = shared(sim, "sim"), shared(loop, "loop")
    try:
        scen = standard_scenarios(magnet, gap_m=gap_m, current_A=current_A)
        rows: dict[str, Any] = {}
        for label, red in reduced.items():
            res = compare_models(detailed, red, scen, gap_m=gap_m, current_A=current_A,
                                 repeat=0)
            rows[label] = {r.scenario.name: {
                "nrms_current": float(np.max(r.current_error)),
                "nrms_force": float(np.max(r.force_error)),
                "ac_current": float(np.nanmax(r.current_error_ac)),
                "ac_force": float(np.nanmax(r.force_error_ac))} for r in res}
    finally:
        cmp.simulate, cmp.closed_loop = sim, loop
    return rows, {s.name: (c, s.duration_s) for s, c in zip(scen, cpu, strict=True)}
