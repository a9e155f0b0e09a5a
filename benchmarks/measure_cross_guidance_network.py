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

    PYTHONPATH=src python benchmarks/measure_cross_guidance_network.py [out.json]
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


def main() -> None:
    t0 = time.time()
    refs = {"bundled (lumped)": mk.load_magnet("tr-guidance"),
            "ladder (8 layers)": mk.load_magnet("tr-guidance", eddy_model="ladder",
                                                eddy_layers=8)}
    out: dict[str, Any] = {}
    for name, modes in (("guidance eq. 8 (default)", None),
                        ("guidance network eddy_modes=2", {"guidance": 2})):
        model = CrossSectionModel(eddy_modes=modes)
        run, calls = record(model)
        out[name] = {"eddy_modes_of": model.eddy_modes_of}
        for rname, mag in refs.items():
            out[name][rname] = compare(run, replay(model, run, calls, mag))
        print(name, json.dumps(out[name], indent=1), flush=True)
    out["wall_s"] = time.time() - t0
    if len(sys.argv) > 1:
        with open(sys.argv[1], "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
