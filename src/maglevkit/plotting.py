"""Figures (matplotlib, Agg backend): force-current-gap curves, inductances, time responses."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["plot_force_current", "plot_simulation", "save"]


def save(fig: Any, path: str | Path) -> Path:
    """Save a figure as PNG (creating the folder) and close it."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(p, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return p


def plot_force_current(sol: Any, path: str | Path, *, title: str = "") -> Path:
    """Total force over current, one curve per gap, from a ``grid=True`` StaticSolution."""
    gaps = sol.gaps_m[:, 0, 0]
    currents = sol.currents_A[0, :, 0]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    cmap = plt.get_cmap("viridis")
    for i, s in enumerate(gaps):
        color = cmap(i / max(1, len(gaps) - 1))
        ax1.plot(currents, sol.force_N[i] / 1e3, color=color, label=f"s = {s * 1e3:.1f} mm")
        ax2.plot(currents, sol.common_differential_inductance_H[i].sum(axis=-1) * 1e3,
                 color=color)
    ax1.set_xlabel("current I [A]")
    ax1.set_ylabel("total force F [kN]")
    ax1.set_title("force-current-gap characteristics")
    ax1.grid(True, alpha=0.3)
    ax1.legend(fontsize=8, ncol=2)
    ax2.set_xlabel("current I [A]")
    ax2.set_ylabel("differential inductance dpsi/dI [mH]")
    ax2.set_title("differential inductance (sum over circuits)")
    ax2.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    return save(fig, path)


def currents_grid_note(values: np.ndarray) -> str:
    return f"{values.min():g} .. {values.max():g} A ({values.size} points)"


def plot_maps(maps: Any, folder: str | Path) -> list[Path]:
    """The paper's Fig. 9 analog: F, L~ and dL/ds over gap and current, one PNG per circuit."""
    out = []
    s_mm = maps.gaps_m * 1e3
    cur = maps.currents_A
    panels = [("force_N", "force F [kN]", 1e-3, "viridis"),
              ("inductance_H", "differential inductance L~ [mH]", 1e3, "magma"),
              ("dL_ds_H_per_m", "dL/ds [H/m]", 1.0, "cividis")]
    for circuit in maps.circuits:
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.3))
        for ax, (var, label, scale, cmap) in zip(axes, panels, strict=True):
            z = maps.variable(var, circuit).T * scale   # (current, gap)
            cs = ax.contourf(s_mm, cur, z, levels=20, cmap=cmap)
            ax.contour(s_mm, cur, z, levels=10, colors="k", linewidths=0.4, alpha=0.6)
            fig.colorbar(cs, ax=ax, label=label)
            ax.set_xlabel("gap s [mm]")
            ax.set_ylabel("current I [A]")
            ax.set_title(label.split(" [")[0])
        fig.suptitle(f"characteristic maps of circuit '{circuit}' "
                     f"({maps.dataset.attrs.get('magnet_name', '')})")
        fig.tight_layout()
        out.append(save(fig, Path(folder) / f"maps_{circuit}.png"))
    return out


def plot_simulation(res: Any, path: str | Path, *, title: str = "") -> Path:
    """Time response of a flux-model simulation: inputs, currents, forces, eddy MMFs."""
    t = res.time_s * 1e3
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    ax = axes[0, 0]
    for j, nm in enumerate(res.circuit_names):
        ax.step(t, res.voltages_V[:, j], where="post", label=f"U [{nm}]")
    ax.set_ylabel("voltage [V]")
    ax2 = ax.twinx()
    for j, nm in enumerate(res.gap_names):
        ax2.plot(t, res.gaps_m[:, j] * 1e3, "--", label=f"s [{nm}]")
    ax2.set_ylabel("gap [mm] (dashed)")
    ax.legend(loc="center left", fontsize=8)
    ax2.legend(loc="center right", fontsize=8)
    ax.set_title("inputs")
    ax = axes[0, 1]
    for j, nm in enumerate(res.circuit_names):
        ax.plot(t, res.currents_A[:, j], label=nm)
    ax.set_ylabel("current [A]")
    ax.set_title("circuit currents")
    ax.legend(fontsize=8)
    ax = axes[1, 0]
    for j, nm in enumerate(res.gap_names):
        ax.plot(t, res.pole_force_N[:, j] / 1e3, label=f"pole {nm}")
    ax.plot(t, res.force_N / 1e3, "k", lw=1.5, label="total")
    ax.set_ylabel("force [kN]")
    ax.set_xlabel("time [ms]")
    ax.set_title("magnet forces (attraction > 0)")
    ax.legend(fontsize=8)
    ax = axes[1, 1]
    for j, nm in enumerate(res.eddy_branch_names):
        ax.plot(t, res.eddy_mmf_A[:, j], label=nm)
    ax.set_ylabel("eddy-current MMF [A]")
    ax.set_xlabel("time [ms]")
    ax.set_title("eddy currents" if res.eddy_branch_names else "eddy currents (switched off)")
    if res.eddy_branch_names:
        ax.legend(fontsize=8)
    for a in axes.ravel():
        a.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return save(fig, path)


def plot_comparison(result: Any, path: str | Path, *, title: str = "") -> Path:
    """Detailed vs reduced time responses of one comparison scenario (current and force)."""
    t = result.time_s * 1e3
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    for j, name in enumerate(result.circuit_names):
        line, = a1.plot(t, result.detailed_currents_A[:, j], lw=2.0, label=f"{name}: detailed")
        a1.plot(t, result.reduced_currents_A[:, j], "--", color="k", lw=1.0,
                label=f"{name}: reduced")
        a2.plot(t, result.detailed_forces_N[:, j] / 1e3, lw=2.0, color=line.get_color())
        a2.plot(t, result.reduced_forces_N[:, j] / 1e3, "--", color="k", lw=1.0)
    a1.set_ylabel("coil current [A]")
    a2.set_ylabel("circuit force [kN]")
    a2.set_xlabel("time [ms]")
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
    a1.legend(fontsize=8, ncol=2)
    errs = ", ".join(f"{n}: I {100 * ci:.2f} %, F {100 * fi:.2f} %" for n, ci, fi in
                     zip(result.circuit_names, result.current_error, result.force_error,
                         strict=True))
    a1.set_title((title + "\n" if title else "") + f"{result.scenario.name}: "
                 f"{result.scenario.description}")
    fig.text(0.01, 0.0, f"normalised RMS error {errs}; wall time detailed "
             f"{result.detailed_wall_s * 1e3:.0f} ms, reduced {result.reduced_wall_s * 1e3:.1f} ms "
             f"(x{result.speedup:.0f})", fontsize=8, color="0.3")
    return save(fig, path)
