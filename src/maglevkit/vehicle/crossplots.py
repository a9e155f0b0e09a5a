"""Figures of a cross-section run (PNG): gaps, forces and currents of the levitation and
guidance circuits, and the car body's motion and accelerations."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["plot_cross_section_run"]


def plot_cross_section_run(dataset: Any, directory: str | Path, *,
                           name: str = "cross_section") -> list[Path]:
    """Write ``<name>_magnets.png`` and ``<name>_car_body.png`` into ``directory``.

    Parameters
    ----------
    dataset : xarray.Dataset
        The dataset of a cross-section run (``CrossSectionRun.dataset``).
    directory : str or Path
        Output folder; created if missing (its parent must exist).
    name : str, default "cross_section"
        File name prefix (keyword only).

    Returns
    -------
    list of Path
        The written figures.

    Raises
    ------
    InputError
        The parent of a missing ``directory`` does not exist.
    """
    from ..plotting import figure_directory  # imported first: it sets the Agg backend

    out = figure_directory(directory)
    import matplotlib.pyplot as plt

    ds = dataset
    t = ds.time.values
    title = (f"{ds.attrs['vehicle']}, {float(ds.attrs['speed_m_per_s']) * 3.6:.0f} km/h"
             + (f" - {ds.attrs['scenario']}" if ds.attrs.get("scenario") else ""))
    lo, hi = float(ds.attrs["touchdown_gap_m"]) * 1e3, float(ds.attrs["landing_gap_m"]) * 1e3
    paths = []
    fig, ax = plt.subplots(3, 2, figsize=(11, 8), sharex=True)
    styles = {"left/front": ("C0", "-"), "left/rear": ("C0", "--"),
              "right/front": ("C3", "-"), "right/rear": ("C3", "--")}
    for col, kind in enumerate(("levitation", "guidance")):
        circ = ds[f"{kind}_circuit"].values
        for var, row, scale, unit in ((f"{kind}_gap", 0, 1e3, "mm"),
                                      (f"{kind}_force", 1, 1e-3, "kN"),
                                      (f"{kind}_current", 2, 1.0, "A")):
            a = ax[row, col]
            for j, c in enumerate(circ):
                colour, ls = styles.get(str(c), ("k", "-"))
                a.plot(t, ds[var].values[:, j] * scale, color=colour, ls=ls, lw=1.0,
                       label=str(c))
            a.set_ylabel(f"{kind} {var.split('_')[1]} [{unit}]")
            a.ticklabel_format(axis="y", useOffset=False)
            a.grid(alpha=0.3)
        g = ds[f"{kind}_gap"].values * 1e3
        ax[0, col].set_title(f"{kind}: minimum gap {g.min():.2f} mm (limits {lo:g} / {hi:g} "
                             "mm)", fontsize=10)
        ax[2, col].set_xlabel("time [s]")
    ax[0, 0].legend(fontsize=8, ncol=2, loc="best")
    paths.append(_write(fig, title, out / f"{name}_magnets.png"))
    fig, ax = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    ax[0].plot(t, ds.car_body_y.values * 1e3, label="car body y")
    ax[0].plot(t, ds.chassis_y.values * 1e3, label="chassis y")
    ax[0].plot(t, ds.car_body_phi.values * 1e3, label="car body roll [mrad]")
    ax[0].set_ylabel("displacement [mm]")
    ax[0].legend(fontsize=8)
    ax[1].plot(t, ds.car_body_lateral_acceleration.values, label="lateral (track plane)")
    ax[1].plot(t, ds.car_body_vertical_acceleration.values, label="vertical")
    ax[1].set_ylabel("car body acc. [m/s$^2$]")
    ax[1].legend(fontsize=8)
    ax[2].plot(t, ds.field_a_y.values, label="track field a_y [m/s$^2$]")
    ax[2].plot(t, ds.crosswind_force.values * 1e-4, label="crosswind force [10 kN]")
    ax[2].set_ylabel("excitation")
    ax[2].set_xlabel("time [s]")
    ax[2].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    paths.append(_write(fig, title, out / f"{name}_car_body.png"))
    return paths


def _write(fig: Any, title: str, path: Path) -> Path:
    """Title, lay out, save (PNG, 110 dpi) and close ``fig``; returns ``path``."""
    import matplotlib.pyplot as plt

    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
