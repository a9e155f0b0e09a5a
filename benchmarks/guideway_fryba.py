"""Guideway span under a moving constant force: modal integration vs Fryba's closed form.

``python benchmarks/guideway_fryba.py [--out docs/figures]`` draws

* the midspan deflection history at three speed parameters (integration of the bundled
  girder's modes with the exact ZOH step, and the converged closed-form series), and
* the maximum midspan dynamic amplification over alpha = v / (2 f_1 L) = 0.05 ... 1.2
  (dense closed form, undamped; integration points at alpha = 0.1 ... 1.0),

and writes ``guideway-fryba.png``.  The closed form is the undamped series of Fryba,
Vibration of solids and structures under moving loads (1999), eq. (1.29), continued by
free vibration after the force has left the span.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from maglevkit.vehicle import BeamSpan, Guideway, load_guideway  # noqa: E402

FORCE = 1.0e5


def series_midspan(alpha: float, tau: np.ndarray, n_terms: int = 201) -> np.ndarray:
    """Undamped midspan deflection / (F L^3 / 48 EI) at times tau = t v / L."""
    out = np.zeros_like(tau)
    for j in range(1, n_terms + 1, 2):
        a, b = j * math.pi, j * j * math.pi / alpha     # j omega T, omega_j T

        def forced(tt: np.ndarray, j: int = j, a: float = a, b: float = b
                   ) -> tuple[np.ndarray, np.ndarray]:
            if abs(j - alpha) < 1e-12:                   # resonance: the limit
                return (0.5 * (np.sin(b * tt) - b * tt * np.cos(b * tt)) / j ** 4,
                        0.5 * b * b * tt * np.sin(b * tt) / j ** 4)
            c = 1.0 / (j * j * (j * j - alpha * alpha))
            return c * (np.sin(a * tt) - alpha / j * np.sin(b * tt)), c * a * (np.cos(a * tt)
                                                                               - np.cos(b * tt))

        q, _ = forced(np.minimum(tau, 1.0))
        q1, v1 = forced(np.array(1.0))
        free = q1 * np.cos(b * (tau - 1.0)) + v1 / b * np.sin(b * (tau - 1.0))
        out += np.where(tau <= 1.0, q, free) * math.sin(j * math.pi / 2)
    return out * 96.0 / math.pi ** 4


def integrate_midspan(span: BeamSpan, alpha: float, steps: int = 1000, duration: float = 1.5
                      ) -> tuple[np.ndarray, np.ndarray]:
    gw = Guideway(span, n_spans=1, moving_boundary=False)
    length = span.length_m
    v = alpha * 2 * float(span.natural_frequencies_Hz[0]) * length
    dt = length / v / steps
    st = gw.initial_state()
    w = [0.0]
    for k in range(int(round(duration * steps))):
        x = v * (k + 0.5) * dt
        st = gw.step(st, dt, [x], [FORCE]) if x < length else gw.step(st, dt)
        w.append(float(gw.deflection(st, [length / 2]).deflection_m[0]))
    tau = np.arange(len(w)) / steps
    return tau, np.array(w) / span.static_midspan_deflection_m(FORCE)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/figures")
    args = ap.parse_args()
    data = load_guideway()
    span = BeamSpan(data.span.length_m, data.span.bending_stiffness_N_m2,
                    data.span.mass_per_length_kg_per_m, n_modes=8, damping_ratio=0.0)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for alpha, color in ((0.1, "C0"), (0.5, "C1"), (1.0, "C2")):
        tau, w = integrate_midspan(span, alpha)
        ax1.plot(tau, w, color=color, lw=2.2, alpha=0.5, label=f"8 modes, alpha = {alpha}")
        ax1.plot(tau, series_midspan(alpha, tau), color=color, lw=0.9, ls="--")
    ax1.axvline(1.0, color="0.5", lw=0.6)
    ax1.set_xlabel("t v / L  (force leaves the span at 1)")
    ax1.set_ylabel("midspan deflection / (F L^3 / 48 EI)")
    ax1.set_title("deflection history (dashed: closed form, 201 terms)")
    ax1.legend(fontsize=8)
    alphas = np.linspace(0.05, 1.2, 231)
    dense = [series_midspan(a, np.linspace(0, 3.0, 12001)).max() for a in alphas]
    ax2.plot(alphas, dense, "k-", lw=1, label="closed form (undamped series)")
    pts = np.round(np.arange(0.1, 1.01, 0.1), 2)
    ax2.plot(pts, [integrate_midspan(span, a)[1].max() for a in pts], "o", color="C3",
             label="modal integration (8 modes, exact ZOH step)")
    ax2.set_xlabel("speed parameter alpha = v / (2 f1 L)")
    ax2.set_ylabel("max midspan deflection / static")
    v500 = span.speed_parameter(500 / 3.6)
    ax2.axvline(v500, color="0.5", lw=0.6)
    ax2.text(v500 - 0.01, 1.25, "500 km/h on the\nbundled girder ", fontsize=8, color="0.3",
             ha="right")
    ax2.set_title("maximum dynamic amplification")
    ax2.legend(fontsize=8, loc="lower right")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out / "guideway-fryba.png", dpi=130)
    print(out / "guideway-fryba.png")


if __name__ == "__main__":
    main()
