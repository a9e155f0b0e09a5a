"""The paper's validation figures, reproduced in kind from a magnet's statics.

* :func:`figure_force_current` -- Fig. 6 analog: ``F/F0`` over ``I/I0`` at several gaps,
  full model vs the model without saturation (constant ``mu_r(0)``).
* :func:`figure_inductance` -- Fig. 7 analog: normalised differential inductance
  ``L~ = dpsi/dI`` over ``I/I0`` at s = 9.5 mm, full model vs the model without saturation
  and eddy currents.  Statically ``L~`` does not depend on eddy currents (they carry no
  static MMF); they matter only for the dynamic identification of the paper's Sec. IV-B.

Normalisation: ``I0`` is the saturation knee (:func:`~maglevkit.magnets.saturation_knee`
at the nominal gap ``s0``), ``F0 = F(s0, I0)`` of the full model.  The nominal current of
the parameter file is marked.  The time response of the coupled circuits needs the
flux-based dynamic model and is not produced here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .magnets.base import Magnet
from .magnets.characteristics import KNEE_EXPONENT, nominal_point, saturation_knee
from .models.statics import solve_statics
from .plotting import plt, save

__all__ = ["Fig6Data", "Fig7Data", "fig6_data", "fig7_data", "figure_force_current",
           "figure_inductance", "write_figures"]


@dataclass(frozen=True)
class Fig6Data:
    """Normalised force-current characteristics (paper Fig. 6).

    ``force_full`` and ``force_linear`` have shape (n_gaps, n_currents) and are ``F/F0``;
    ``current`` is ``I/I0``; ``gaps_m`` the gaps [m].
    """

    gaps_m: np.ndarray
    current: np.ndarray
    force_full: np.ndarray
    force_linear: np.ndarray
    I0_A: float
    F0_N: float
    nominal_gap_m: float
    nominal_current_A: float


@dataclass(frozen=True)
class Fig7Data:
    """Normalised differential inductance over current (paper Fig. 7).

    ``inductance_*`` are ``L~/L0`` with ``L0`` the model without saturation (constant),
    for the first circuit with every circuit at the same current.
    """

    gap_m: float
    current: np.ndarray
    inductance_full: np.ndarray
    inductance_linear: np.ndarray
    I0_A: float
    L0_H: float
    nominal_current_A: float


def fig6_data(magnet: Magnet, *, gap_factors: tuple[float, ...] = (0.8, 1.0, 1.2, 1.5),
              max_current: float = 2.2, points: int = 89) -> Fig6Data:
    """Data of the Fig. 6 analog; gaps ``gap_factors x s0``, currents ``0..max_current x I0``."""
    s0, i_nom = nominal_point(magnet)
    i0 = saturation_knee(magnet, gap=s0)
    gaps = s0 * np.asarray(gap_factors, dtype=float)
    cur = np.linspace(0.0, max_current, points)
    full = solve_statics(magnet, gaps=gaps, currents=cur * i0, grid=True).force_N
    lin_mag = magnet.with_options(saturation=False, eddy_currents=False)
    lin = solve_statics(lin_mag, gaps=gaps, currents=cur * i0, grid=True).force_N
    f0 = float(solve_statics(magnet, gaps=s0, currents=i0).force_N)
    return Fig6Data(gaps, cur, full / f0, lin / f0, i0, f0, s0, i_nom)


def fig7_data(magnet: Magnet, *, gap: float = 0.0095, max_current: float = 2.2,
              points: int = 89) -> Fig7Data:
    """Data of the Fig. 7 analog at ``gap`` [m] (the paper: 9.5 mm)."""
    s0, i_nom = nominal_point(magnet)
    i0 = saturation_knee(magnet, gap=s0)
    cur = np.linspace(0.0, max_current, points)
    full = solve_statics(magnet, gaps=np.array([gap]), currents=cur * i0, grid=True)
    lin_mag = magnet.with_options(saturation=False, eddy_currents=False)
    lin = solve_statics(lin_mag, gaps=np.array([gap]), currents=cur * i0, grid=True)
    l_full = full.common_differential_inductance_H[0, :, 0]
    l_lin = lin.common_differential_inductance_H[0, :, 0]
    l0 = float(l_lin[0])
    return Fig7Data(gap, cur, l_full / l0, l_lin / l0, i0, l0, i_nom)


def _mark_currents(ax: object, i_nom_rel: float) -> None:
    ax.axvline(1.0, color="0.35", lw=0.9, ls=":")  # type: ignore[attr-defined]
    ax.axvline(i_nom_rel, color="tab:red", lw=0.9, ls=":")  # type: ignore[attr-defined]
    ymax = ax.get_ylim()[1]  # type: ignore[attr-defined]
    ax.text(1.0, 0.97 * ymax, " knee I0", va="top", fontsize=8, color="0.35")  # type: ignore[attr-defined]
    ax.text(i_nom_rel, 0.97 * ymax, "nominal ", va="top", ha="right", fontsize=8,  # type: ignore[attr-defined]
            color="tab:red")


def figure_force_current(magnet: Magnet, path: str | Path, *, data: Fig6Data | None = None
                         ) -> Path:
    """Write the Fig. 6 analog (PNG) and return its path."""
    d = data or fig6_data(magnet)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    cmap = plt.get_cmap("viridis")
    n = len(d.gaps_m)
    for k, s in enumerate(d.gaps_m):
        c = cmap(0.85 * k / max(1, n - 1))
        ax.plot(d.current, d.force_full[k], color=c, lw=2.0,
                label=f"s = {s * 1e3:.1f} mm (s/s0 = {s / d.nominal_gap_m:.2g})")
        ax.plot(d.current, d.force_linear[k], color=c, lw=1.2, ls="--")
    ax.plot([], [], color="k", lw=2.0, label="full model")
    ax.plot([], [], color="k", lw=1.2, ls="--", label="without saturation")
    ax.set_xlim(0.0, d.current[-1])
    ax.set_ylim(0.0, min(float(d.force_linear.max()), 3.5) * 1.02)
    ax.set_xlabel("normalised current I / I0")
    ax.set_ylabel("normalised force F / F0")
    ax.set_title(f"Fig. 6 analog: force-current characteristics\n{magnet.name}", fontsize=10)
    ax.grid(True, alpha=0.3)
    _mark_currents(ax, d.nominal_current_A / d.I0_A)
    ax.legend(fontsize=8, loc="lower right")
    fig.text(0.01, -0.08, f"I0 = {d.I0_A:.1f} A (knee: d ln F/d ln I = {KNEE_EXPONENT} at "
             f"s0 = {d.nominal_gap_m * 1e3:.1f} mm),\nF0 = F(s0, I0) = {d.F0_N / 1e3:.1f} kN "
             f"(whole magnet); all circuits at the same current.", fontsize=7.5, color="0.3")
    return save(fig, path)


def figure_inductance(magnet: Magnet, path: str | Path, *, data: Fig7Data | None = None) -> Path:
    """Write the Fig. 7 analog (PNG) and return its path."""
    d = data or fig7_data(magnet)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    ax.plot(d.current, d.inductance_full, color="tab:blue", lw=2.0, label="full model")
    ax.plot(d.current, d.inductance_linear, color="tab:orange", lw=1.5, ls="--",
            label="without saturation and eddy currents")
    ax.set_xlim(0.0, d.current[-1])
    ax.set_ylim(0.0, 1.15 * max(float(d.inductance_full.max()), 1.0))
    ax.set_xlabel("normalised current I / I0")
    ax.set_ylabel("normalised differential inductance L~ / L0")
    ax.set_title(f"Fig. 7 analog: differential inductance at s = {d.gap_m * 1e3:.1f} mm\n"
                 f"{magnet.name}", fontsize=10)
    ax.grid(True, alpha=0.3)
    _mark_currents(ax, d.nominal_current_A / d.I0_A)
    ax.legend(fontsize=8, loc="lower left")
    fig.text(0.01, -0.08, f"L~ = dpsi/dI of one circuit with all circuits at the same current; "
             f"L0 = {d.L0_H:.3f} H\n(model without saturation), I0 = {d.I0_A:.1f} A. "
             "Statically L~ is independent of eddy currents.", fontsize=7.5, color="0.3")
    return save(fig, path)


@dataclass(frozen=True)
class CouplingResponse:
    """Response of all circuits to a voltage step in the first one (flux-based model)."""

    time_s: np.ndarray
    circuit_names: tuple[str, ...]
    relative_current_change: np.ndarray   # (n_t, n_circuits), (I - I0) / I0
    other_peak_ratio: float               # max |dI_other| / max |dI_stepped|
    mutual_ratio: float                   # max |L_ij| / sqrt(L_ii L_jj), i != j


def coupling_response(magnet: Magnet, *, step: float = 0.2) -> CouplingResponse:
    """Step the first circuit's voltage by ``step`` (relative) at the nominal point and
    simulate the detailed flux-based model for three time constants."""
    from .magnets.characteristics import coupling_ratios
    from .models.flux import simulate

    s0, i0 = nominal_point(magnet)
    net = magnet.network
    r = net.resistances
    sol = solve_statics(magnet, gaps=s0, currents=i0)
    tau = float(sol.differential_inductance_H[0, 0] / r[0])
    u0 = r * i0
    bump = np.zeros(len(r))
    bump[0] = step
    dur = 3.0 * tau
    res = simulate(magnet, (0.0, dur), dt=dur / 600, gaps=s0,
                   voltages=lambda t: u0 * (1.0 + bump * (t >= 0.02 * dur)), initial_currents=i0)
    rel = (res.currents_A - i0) / i0
    peak = np.max(np.abs(rel), axis=0)
    ratios = coupling_ratios(magnet, gap=s0, current=i0).ratio
    off = np.abs(ratios - np.diag(np.diag(ratios)))
    return CouplingResponse(res.time_s, res.circuit_names, rel,
                            float(peak[1:].max() / peak[0]), float(off.max()))


def figure_coupling(magnet: Magnet, path: str | Path, *,
                    data: CouplingResponse | None = None) -> Path:
    """Currents of all circuits after a voltage step in the first circuit (paper Sec. IV-A)."""
    d = data or coupling_response(magnet)
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    for j, name in enumerate(d.circuit_names):
        ax.plot(d.time_s * 1e3, 100 * d.relative_current_change[:, j],
                lw=2.2 if j == 0 else 1.6, label=f"circuit {name}" + (" (stepped)" if j == 0 else ""))
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("current change (I - I0)/I0 [%]")
    ax.set_title(f"Coupling of the circuits: +20 % voltage step on '{d.circuit_names[0]}'\n"
                 f"{magnet.name}")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.text(0.01, -0.04, f"largest response of another circuit: {100 * d.other_peak_ratio:.2f} % "
             f"of the stepped one; static mutual/self inductance ratio {d.mutual_ratio:.4f} "
             "(flux-based model, nominal point)", fontsize=8, color="0.3")
    return save(fig, path)


def write_figures(magnet: Magnet, out: str | Path) -> list[Path]:
    """Write the figures of ``magnet`` into folder ``out``: Figs. 6-7 analogs and, for
    magnets with several circuits, the coupling response (flux-based model)."""
    out = Path(out)
    stem = Path(magnet.source).stem or "magnet"
    paths = [figure_force_current(magnet, out / f"{stem}-fig6-force-current.png"),
             figure_inductance(magnet, out / f"{stem}-fig7-inductance.png")]
    if len(magnet.network.circuits) > 1:
        paths.append(figure_coupling(magnet, out / f"{stem}-coupling.png"))
    return paths
