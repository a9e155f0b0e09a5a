"""Figures of a vehicle run (PNG): gaps and currents per magnet, car-body acceleration,
guideway deflection along the train."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["plot_vehicle_run"]


def plot_vehicle_run(dataset: Any, directory: str | Path) -> list[Path]:
    """Write ``gaps_currents.png``, ``car_body_acceleration.png`` and
    ``guideway_deflection.png`` into ``directory``; returns the paths.

    Parameters
    ----------
    dataset : xarray.Dataset
        The dataset of a vehicle run (``VehicleRun.dataset``).
    directory : str or Path
        Output folder; created if missing (its parent must exist).

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
    title = (f"{ds.attrs['vehicle']}\n{float(ds.attrs['speed_m_per_s']) * 3.6:.0f} km/h, "
             f"{ds.attrs['magnets']}" + (f", failure {ds.attrs['failures']}"
                                         if ds.attrs.get("failures") else ""))
    paths = []
    # gaps and currents, one line per circuit, coloured by position along the train
    fig, ax = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    pos = ds.circuit_position.values
    cmap = plt.get_cmap("viridis")
    failed = {f.split("@")[0] for f in str(ds.attrs.get("failures", "")).split(", ") if f}
    for j, c in enumerate(ds.circuit.values):
        col = "red" if c in failed else cmap(pos[j] / max(pos.max(), 1e-9))
        lw = 1.6 if c in failed else 0.6
        ax[0].plot(t, ds.gap.values[:, j] * 1e3, color=col, lw=lw)
        ax[1].plot(t, ds.current.values[:, j], color=col, lw=lw)
    ax[0].axhline(float(ds.attrs["touchdown_gap_m"]) * 1e3, color="k", ls="--", lw=0.8)
    ax[0].axhline(float(ds.attrs["landing_gap_m"]) * 1e3, color="k", ls=":", lw=0.8)
    ax[0].set_ylabel("gap [mm]")
    ax[1].set_ylabel("coil current [A]")
    ax[1].set_xlabel("time [s]")
    ax[0].set_title(title, fontsize=9)
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, float(pos.max())))
    fig.colorbar(sm, ax=ax, label="circuit position behind the nose [m] (red: failed)")
    for a in ax:
        a.grid(alpha=0.3)
    p = out / "gaps_currents.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    # car-body vertical acceleration at the floor points
    fig, ax = plt.subplots(ds.sizes["section"], 1, figsize=(10, 2.2 * ds.sizes["section"] + 1),
                           sharex=True, squeeze=False)
    for s in range(ds.sizes["section"]):
        for k, fp in enumerate(ds.floor_point.values):
            ax[s, 0].plot(t, ds.car_body_acceleration.values[:, s, k], lw=0.7,
                          label=f"{fp:+.2f} L")
        ax[s, 0].set_ylabel(f"car {s + 1}\n[m/s^2]")
        ax[s, 0].grid(alpha=0.3)
    ax[0, 0].legend(fontsize=7, ncol=3, title="floor point from centre", title_fontsize=7)
    ax[0, 0].set_title("car-body vertical acceleration (down positive)\n" + title, fontsize=9)
    ax[-1, 0].set_xlabel("time [s]")
    p = out / "car_body_acceleration.png"
    fig.tight_layout()
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    # guideway deflection under the circuits along the train, a few instants; midspans
    fig, ax = plt.subplots(2, 1, figsize=(10, 7))
    idx = np.unique(np.linspace(0, t.size - 1, 5).astype(int))
    for i in idx:
        ax[0].plot(pos, ds.guideway_deflection.values[i] * 1e3, marker=".", lw=0.8,
                   label=f"t = {t[i]:.2f} s")
    ax[0].invert_yaxis()
    ax[0].set_xlabel("position behind the nose [m]")
    ax[0].set_ylabel("deflection under the magnets [mm]\n(down)")
    ax[0].legend(fontsize=7)
    ax[0].set_title("guideway deflection along the train\n" + title, fontsize=9)
    mids = ds.midspan_deflection.values * 1e3
    spans = ds.span_index.values
    for k in np.unique(spans):
        sel = spans == k
        tt = np.broadcast_to(t[:, None], spans.shape)[sel]
        order = np.argsort(tt)
        ax[1].plot(tt[order], mids[sel][order], lw=0.8)
    ax[1].invert_yaxis()
    ax[1].set_xlabel("time [s]")
    ax[1].set_ylabel("midspan deflection [mm]\n(each integrated span)")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    p = out / "guideway_deflection.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths
