"""The cross-section's guidance magnets on the eddy network against their detailed model
(issue 26, switch26v; the check modesveh26 made for the TR09 levitation magnets).

The cross-section at 400 km/h on a 50 Hz guidance-rail wave (0.05 mm), NumPy loop, 0.3 s,
with the guidance magnets on eq. 8 (their file's default) and on the 2-branch eddy
network (``eddy_modes={"guidance": 2}``), the levitation magnets on their default (the
network) in both.  The left guidance magnet's two circuits: the voltages, gaps and gap
rates the bank received at every step, replayed through the guidance magnet's detailed
model (``FluxModel``, per pole the circuit's gap) of (a) the bundled file (lumped eddy
elements: the model the vehicle maps come from) and (b) the file on the eddy ladder
(``eddy_model = "ladder"``, 8 layers: the one checked against the transient FEM,
docs/validation_fem.md).  After 0.1 s: RMS of the coil-current error, the reference's RMS
variation, and gain and phase of the current's 50 Hz component per metre of gap.

    PYTHONPATH=src python benchmarks/measure_cross_guidance_network.py [--guidance FILE] [out.json]

``--guidance FILE`` flies that guidance magnet file (e.g. the bundled one on the eddy
ladder, guideswitch) on eq. 8 and the network with 2 and 3 branches and replays each run
through the file's own detailed model.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import maglevkit as mk
from maglevkit.vehicle.crossrun import CrossSectionModel
from maglevkit.vehicle.irregularities import HarmonicProfile

sys.path.insert(0, str(Path(__file__).resolve().parent))
from replay_common import fundamental_errors, replay_detailed  # noqa: E402

V = 400 / 3.6
F_HZ = 50.0
AMPLITUDE_M = 0.05e-3
DURATION_S = 0.3
MEMBER = "guidance_left"


def record(model: CrossSectionModel) -> tuple[Any, list[tuple[np.ndarray, ...]]]:
    """A run and the (voltages, gaps, rates) of every step the bank took."""
    calls: list[tuple[np.ndarray, ...]] = []
    make = model.bank.stepper

    class Spy:
        """The bank's stepper, its inputs recorded at every advance."""

        def __init__(self, st: Any) -> None:
            self._st = st

        def __getattr__(self, name: str) -> Any:
            return getattr(self._st, name)

        def advance(self, *, voltages_V: Any, gaps_m: Any, gap_rates_m_per_s: Any) -> Any:
            calls.append((np.array(voltages_V, float), np.array(gaps_m, float),
                          np.array(gap_rates_m_per_s, float)))
            return self._st.advance(voltages_V=voltages_V, gaps_m=gaps_m,
                                    gap_rates_m_per_s=gap_rates_m_per_s)

    def stepper(*a: Any, **k: Any) -> Any:
        return Spy(make(*a, **k))

    model.bank.stepper = stepper  # type: ignore[method-assign]
    run = model.run(speed_m_per_s=V, duration_s=DURATION_S, loop="python",
                    lateral=HarmonicProfile(AMPLITUDE_M, V / F_HZ))
    return run, calls


def replay(model: CrossSectionModel, run: Any, calls: list[tuple[np.ndarray, ...]],
           magnet: Any) -> np.ndarray:
    """The detailed model's coil currents of MEMBER's circuits under the recorded inputs."""
    idx = list(range(*model.bank.circuit_slices[MEMBER].indices(model.bank.n_circuits)))
    ds = run.dataset
    i0 = ds.guidance_current.values[0, :2]
    return replay_detailed(magnet, model.maps["guidance"].pole_groups, calls, idx,
                           initial_gaps_m=calls[0][1][idx], initial_currents_A=i0)


def compare(run: Any, ref: np.ndarray) -> dict[str, float]:
    ds = run.dataset     # guidance_left's circuits
    return fundamental_errors(ds.time.values, ds.guidance_current.values[:, :2], ref,
                              ds.guidance_gap.values[:, 0], F_HZ)


def configurations(argv: list[str]) -> tuple[dict[str, Any], list[tuple[str, str, Any]]]:
    """The detailed references and the (label, guidance file, eddy modes) runs to make.

    Without arguments: switch26v's comparison (the bundled guidance file on eq. 8 and on
    the network, against the bundled and the 8-layer ladder detailed models).  With
    ``--guidance FILE`` (a guidance magnet file, e.g. a copy of ``tr-guidance`` on the
    ladder): that file flown on eq. 8 and on the network with 2 and 3 branches, against
    its own detailed model (and the 8-layer ladder of the bundled file).
    """
    if "--guidance" not in argv:
        refs = {"bundled (lumped)": mk.load_magnet("tr-guidance"),
                "ladder (8 layers)": mk.load_magnet("tr-guidance", eddy_model="ladder",
                                                    eddy_layers=8)}
        return refs, [("guidance eq. 8 (default)", "tr-guidance", None),
                      ("guidance network eddy_modes=2", "tr-guidance", {"guidance": 2})]
    path = argv[argv.index("--guidance") + 1]
    refs = {"its file": mk.load_magnet(path),
            "ladder (8 layers)": mk.load_magnet("tr-guidance", eddy_model="ladder",
                                                eddy_layers=8)}
    return refs, [(f"{path}, guidance eddy_modes={m}", path, {"guidance": m})
                  for m in (0, 2, 3)]


def main() -> None:
    t0 = time.time()
    argv = sys.argv[1:]
    refs, runs = configurations(argv)
    out: dict[str, Any] = {}
    for name, guidance, modes in runs:
        model = CrossSectionModel(guidance_magnet=guidance, eddy_modes=modes)
        c0 = time.process_time()
        run, calls = record(model)
        out[name] = {"eddy_modes_of": model.eddy_modes_of,
                     "run_cpu_s": time.process_time() - c0,
                     "min_guidance_gap_mm": 1e3 * float(run.dataset.guidance_gap.min()),
                     "max_guidance_current_A": float(run.dataset.guidance_current.max())}
        for rname, mag in refs.items():
            out[name][rname] = compare(run, replay(model, run, calls, mag))
        print(name, json.dumps(out[name], indent=1), flush=True)
    out["wall_s"] = time.time() - t0
    paths = [a for a in argv if a.endswith(".json")]
    if paths:
        with open(paths[0], "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
