"""Dense vs sparse form of the flux DAE over network sizes (design25, SPARSE_FORM_SIZE).

For each network: its unknowns (loops + circuits, the rule's size), the non-zeros of the
DAE's Jacobian on each form, and the CPU time of one simulated second at 1 kHz hold
steps (a +20 % voltage step at 0.1 s, gaps 10 +- 1 mm at 5 Hz) on each form, on CasADi's
virtual machine (``compiled="never"``: compiling the dense form of the larger ladders
takes minutes, docs/decisions.md splitfast), best of ``--repeat``.  Run pinned:
``taskset -c 0 python benchmarks/form_size_survey.py``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings

import numpy as np

import maglevkit as mk
from maglevkit.models import flux
from maglevkit.models.signals import Sine

#: (label, bundled magnet, load_magnet options, nominal current [A])
CASES = [
    ("U-magnet lumped", "u-magnet", {}, 20.0),
    *[(f"U-magnet ladder n={n}", "u-magnet", {"eddy_model": "ladder", "eddy_layers": n}, 20.0)
      for n in (2, 3, 4)],
    ("TR09 lumped (paper)", "tr09-paper", {}, 34.0),
    ("TR09 split", "tr09-standard", {}, 34.0),
    ("guidance lumped", "tr-guidance", {}, None),
    *[(f"guidance ladder n={n}", "tr-guidance", {"eddy_model": "ladder", "eddy_layers": n}, None)
      for n in (4, 5, 6, 7, 8)],
]


def _magnet(name: str, opts: dict) -> mk.Magnet:
    if name == "tr09-paper":
        import copy

        from maglevkit.magnets.base import build_magnet
        params = copy.deepcopy(mk.load_magnet("tr09-standard").parameters)
        params["magnet"]["flux_paths"] = "paper"
        params["magnet"].pop("coil_segments", None)
        params["provenance"]["magnet.flux_paths"] = "[E] survey variant"
        return build_magnet(params, options=mk.ModelOptions(**opts))
    return mk.load_magnet(name, **opts)


def run(fm: mk.FluxModel, mag: mk.Magnet, i0: float) -> float:
    """CPU time [s] of one simulated second (bench_flux's scenario)."""
    u0 = mag.network.resistances * i0

    def volts(t: float) -> np.ndarray:
        return u0 * (1.2 if t >= 0.1 else 1.0)

    c = time.process_time()
    mk.simulate(fm, (0.0, 1.0), dt_s=1e-3, gaps_m=Sine(0.010, 1e-3, 5.0), voltages_V=volts,
                initial_currents_A=i0)
    return time.process_time() - c


def _children_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--only", default="", help="comma-separated label substrings")
    ap.add_argument("--compiled", action="store_true",
                    help="compiled C (compile time reported) instead of the virtual machine")
    a = ap.parse_args()
    print("network | unknowns | dense / sparse (setup incl. compile) | CPU s dense / sparse | ratio")
    for label, name, opts, i0 in CASES:
        if a.only and not any(o in label for o in a.only.split(",")):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mag = _magnet(name, opts)
            if i0 is None:
                op = mag.parameters.get("operating", {})
                i0 = float(op.get("nominal_current", 10.0))
            size = mag.network.n_loops + len(mag.network.circuits)
            out = {}
            for form, thr in (("dense", 10**9), ("sparse", 0)):
                flux.SPARSE_FORM_SIZE = thr
                c0 = time.process_time() + _children_cpu()
                fm = mk.FluxModel(mag, compiled="always" if a.compiled else "never",
                                  cache_dir=tempfile.mkdtemp() if a.compiled else None)
                run(fm, mag, i0)             # compiles (when compiled) before or in it
                c1 = time.process_time() + _children_cpu()
                best = min(run(fm, mag, i0) for _ in range(a.repeat))
                setup = c1 - c0 - best       # the first run's extra: setup and compile
                out[form] = (best, f"{fm.dae.form} setup {setup:.1f} s")
        print(f"{label} | {size} | {out['dense'][1]} / {out['sparse'][1]} | "
              f"{out['dense'][0]:.3f} / {out['sparse'][0]:.3f} | "
              f"{out['dense'][0] / out['sparse'][0]:.2f}", flush=True)


if __name__ == "__main__":
    main()
