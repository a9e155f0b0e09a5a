"""The bank with shielded-gap ladder members (``motion_eddy``): cost and accuracy.

Cost: the in-place stepper at 100 circuits (50 TR09 standard magnets) at 1 ms, eq. 8
against the two-state and the three-state ladder (``eddy_branches=2``), and on the maps of
the diffusing eddy ladder (``eddy_model = "ladder"``) eq. 8 against the eddy network
(``eddy_modes=2``), each through the SIMD lanes (the default) and CasADi's generated C, in
ns per circuit-step (CPU time, best of 5, all in one run; run pinned, ``taskset -c 0``).

Accuracy: the gap-sine sweep of ``bench_gap_motion`` (TR09 standard, 10 +- 1 mm, constant
voltage of the nominal current) through a bank of one ladder member (two- and
three-state), against the detailed model and against the ``CurrentModel`` on its own.
"""

from __future__ import annotations

import math
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit.reduced.bank import MagnetBank

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing_common import cpu_per_call, sibling_module  # noqa: E402

TITLE = "Bank with shielded-gap ladder members: cost per circuit-step and gap-sine accuracy"

DT = 1e-3
N_CIRCUITS = 100
SWEEP = (5.0, 50.0, 200.0)


def cost(maps: mk.CharacteristicMaps, cache: Path,
         ladder_maps: mk.CharacteristicMaps | None = None) -> list[str]:
    """Table rows: stepper ns per circuit-step at :data:`N_CIRCUITS` circuits; with
    ``ladder_maps`` (the diffusing eddy ladder's maps) eq. 8 and the eddy network
    (``eddy_modes=2``) on them too."""
    rows = []
    cases: list[tuple[str, mk.CharacteristicMaps, dict[str, Any]]] = [
        (label, maps, opts) for label, opts in (("eq. 8, lanes (default)", {}),
                        ("eq. 8, CasADi C", {"codegen": "casadi"}),
                        ("ladder (motion_eddy), lanes (default)", {"motion_eddy": True}),
                        ("ladder (motion_eddy), CasADi C", {"motion_eddy": True,
                                                           "codegen": "casadi"}),
                        ("three-state ladder (eddy_branches=2), lanes (default)",
                         {"motion_eddy": True, "eddy_branches": 2}),
                        ("three-state ladder (eddy_branches=2), CasADi C",
                         {"motion_eddy": True, "eddy_branches": 2, "codegen": "casadi"}))]
    if ladder_maps is not None:
        cases += [("ladder maps: eq. 8, lanes (default)", ladder_maps, {}),
                  ("ladder maps: eddy network (eddy_modes=2), lanes (default)", ladder_maps,
                   {"eddy_modes": 2}),
                  ("ladder maps: eddy network (eddy_modes=2), CasADi C", ladder_maps,
                   {"eddy_modes": 2, "codegen": "casadi"})]
    for label, source, opts in cases:
        members = {f"m{k}": source for k in range(N_CIRCUITS // len(source.circuits))}
        bank = MagnetBank(members, compiled="always", cache_dir=cache, **opts)
        st = bank.initial_state(gaps_m=0.010, currents_A=33.5)
        nc = bank.n_circuits
        u = bank.resistance_ohm * 33.5 * 1.05
        stepper = bank.stepper(st, DT)
        g, sd = np.full(nc, 0.010), np.zeros(nc)

        def step(stepper: Any = stepper, u: np.ndarray = u, g: np.ndarray = g,
                 sd: np.ndarray = sd) -> None:
            stepper.advance(voltages_V=u, gaps_m=g, gap_rates_m_per_s=sd)

        t = cpu_per_call(step, 2000, repeats=5, warm=True)
        sub = max(1, math.ceil(DT / bank.max_step_s * (1 - 1e-12)))
        rows.append(f"| {label} | {nc} | {sub} | {bank.max_step_s * 1e6:.0f} | "
                    f"{t / nc * 1e9:.0f} | {t / nc / sub * 1e9:.0f} |")
    return rows


def _sine_rows(gm: Any, fm: Any, u0: Any, members: list[tuple[str, Any]]) -> list[str]:
    """Table rows: per frequency of SWEEP, the gap sine through the detailed model ``fm``
    at the voltages ``u0`` [V], and through a bank of one member and the single model of
    each (label, CurrentModel) in ``members``, against the detailed model."""
    rows = []
    for f in SWEEP:
        dur, dt = max(2.0 / f, 0.1), min(1.0 / (100 * f), 1e-3)

        def gaps(t: Any, f: float = f) -> Any:
            return gm.GAP + gm.AMPLITUDE * np.sin(2 * np.pi * f * t)

        det = mk.simulate(fm, (0.0, dur), dt_s=dt, gaps_m=gaps, voltages_V=u0)
        t = det.time_s
        g = gaps(t)
        cd, fd = det.currents_A[:, 0], det.pole_force_N.sum(axis=1)
        last = t >= t[-1] - 1.0 / f * max(1, math.floor(f * dur / 2))
        zd = gm._fundamental(t[last], cd[last], f)
        for label, model in members:
            bank = MagnetBank({"m": model}, compiled="auto")
            single = mk.simulate(model, (0.0, dur), dt_s=dt, gaps_m=gaps, voltages_V=u0)
            res = bank.simulate(t, gaps_m=np.repeat(g[:, None], bank.n_gaps, axis=1),
                                voltages_V=u0)
            cb, fb = res.currents_A[:, 0], res.member_force_N[:, 0]
            zb = gm._fundamental(t[last], cb[last], f)
            phase = math.degrees(math.atan2(zb.imag, zb.real) - math.atan2(zd.imag, zd.real))
            diff = float(np.max(np.abs(cb - single.currents_A[:, 0])))
            rows.append(f"| {f:g} Hz | {label} | {100 * gm._ac_error(cd, cb):.1f} % | "
                        f"{100 * gm._ac_error(cd, single.currents_A[:, 0]):.1f} % | "
                        f"{phase:+.1f} deg | {100 * gm._ac_error(fd, fb):.1f} % | "
                        f"{100 * gm._ac_error(fd, single.force_N):.1f} % | {diff:.1e} A |")
    return rows


def sweep(gm: Any, maps: mk.CharacteristicMaps) -> list[str]:
    """Table rows: the gap-sine sweep through banks of one two-state and one three-state
    ladder member on ``maps`` (the lumped eddy elements' maps: the ladders' fits need
    their current jump), against that magnet's detailed model and the single ladder
    model."""
    mag = mk.load_magnet(gm.MAGNET, eddy_model="lumped")
    fm = mk.FluxModel(mag)
    ladder = mk.CurrentModel(maps, motion_eddy=True)
    ladder3 = mk.CurrentModel(maps, motion_eddy=True, eddy_branches=2)
    u0 = fm.resistances * gm.nominal_current(mag)
    return _sine_rows(gm, fm, u0, [("two-state", ladder), ("three-state", ladder3)])


def network_sweep(gm: Any, ladder_maps: mk.CharacteristicMaps) -> list[str]:
    """Table rows: the gap-sine sweep through a bank of one eddy-network member
    (``eddy_modes=2``) on the maps of the diffusing eddy ladder, against the detailed
    model of that ladder (``eddy_model = "ladder"``) and the single ``CurrentModel``."""
    mag = mk.load_magnet(gm.MAGNET, eddy_model="ladder")
    fm = mk.FluxModel(mag)
    model = mk.CurrentModel(ladder_maps, eddy_modes=2)
    u0 = fm.resistances * gm.nominal_current(mag)
    return _sine_rows(gm, fm, u0, [("eddy network (eddy_modes=2), ladder maps", model)])


def run() -> str:
    if shutil.which("cc") is None:
        return "No C compiler on this machine: the compiled bank needs one."
    gm = sibling_module("bench_gap_motion")
    # the shielded-gap ladders (motion_eddy) are fitted to a current jump, which the lumped
    # eddy elements have and the bundled file's diffusing eddy ladder has not
    maps = mk.build_maps(mk.load_magnet(gm.MAGNET, eddy_model="lumped"), gaps_m=gm.GRID[0],
                         currents_A=gm.GRID[1], progress=False)
    ladder_maps = mk.build_maps(mk.load_magnet(gm.MAGNET, eddy_model="ladder"),
                                gaps_m=gm.GRID[0], currents_A=gm.GRID[1], progress=False)
    cache = Path(tempfile.mkdtemp(prefix="maglevkit-bench-cache-"))
    try:
        cost_rows = cost(maps, cache, ladder_maps)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    out = [f"Stepper at {DT * 1e3:g} ms, TR09 standard maps {gm.GRID[0].size} x "
           f"{gm.GRID[1].size}, CPU time per step (best of 5) / circuits; the ladder limits "
           "the RK4 sub-step to its stable step.", "",
           "| bank | circuits | RK4 sub-steps | sub-step [us] | ns / circuit-step | "
           "ns / circuit-sub-step |", "|---|---|---|---|---|---|", *cost_rows, "",
           "Gap sine through a bank of one ladder member, two-state (`motion_eddy=True`) and "
           "three-state (`eddy_branches=2`) (error = RMS(bank - detailed) / RMS(detailed - "
           "mean) of circuit 0's current and of the magnet force; phase of the current's "
           "fundamental against the detailed one; last column: largest difference of the "
           "coil current bank - CurrentModel(maps, motion_eddy=True, eddy_branches=...) "
           "over the run):", "",
           "| f | ladder | bank current error | CurrentModel current error | bank phase "
           "error | bank force error | CurrentModel force error | bank - CurrentModel |",
           "|---|---|---|---|---|---|---|---|", *sweep(gm, maps), *network_sweep(gm, ladder_maps),
           "", "(The eddy-network rows: a bank of `CurrentModel(maps, eddy_modes=2)` on the "
           "maps of the diffusing eddy ladder against the detailed model of that ladder, "
           "`eddy_model = \"ladder\"`.)"]
    return "\n".join(out)


if __name__ == "__main__":
    print(run())
