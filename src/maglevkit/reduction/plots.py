"""Figures of the maps' cross-check: transient vs statics method per grid point."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["DIFFERENCE_VARIABLES", "has_method_differences", "plot_method_differences"]

DIFFERENCE_VARIABLES = (("inductance_relative_difference", "L~ transient / statics - 1"),
                        ("dL_ds_relative_difference", "dL/ds transient / statics - 1"))
"""The per-point relative differences that ``build_maps(method="both")`` stores."""


def has_method_differences(maps: Any) -> bool:
    """True if the maps carry the relative differences of the two methods.

    Parameters
    ----------
    maps : CharacteristicMaps
        Maps built with both the statics and the transient method.

    Returns
    -------
    bool
    """
    return all(name in maps.dataset.data_vars for name, _ in DIFFERENCE_VARIABLES)


def plot_method_differences(maps: Any, folder: str | Path) -> list[Path]:
    """Relative difference of the transient and statics maps over gap and current.

    One PNG per circuit (``maps_difference_<circuit>.png``) with the ``L~`` and ``dL/ds``
    differences in percent, on a colour scale symmetric about zero.

    Parameters
    ----------
    maps : CharacteristicMaps
        Maps built with ``method="both"``.
    folder : str or Path
        Output folder (created).

    Returns
    -------
    list of Path

    Raises
    ------
    InputError
        If the maps have no relative differences (built without ``method="both"``).
    """
    import numpy as np

    from ..errors import InputError
    from ..plotting import plt, save

    if not has_method_differences(maps):
        raise InputError("these maps have no transient-vs-statics differences; build them "
                         "with method='both' (maglevkit maps build --method both)")
    s_mm = maps.gaps_m * 1e3
    cur = maps.currents_A
    out = []
    for circuit in maps.circuits:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.3))
        for ax, (var, label) in zip(axes, DIFFERENCE_VARIABLES, strict=True):
            z = maps.variable(var, circuit).T * 100.0   # (current, gap) in %
            lim = float(np.nanmax(np.abs(z))) or 1e-12
            mesh = ax.pcolormesh(s_mm, cur, z, cmap="RdBu_r", vmin=-lim, vmax=lim,
                                 shading="nearest")
            fig.colorbar(mesh, ax=ax, label=f"{label} [%]")
            ax.set_xlabel("gap s [mm]")
            ax.set_ylabel("current I [A]")
            ax.set_title(f"{label} (max |.| {lim:.3g} %)")
        fig.suptitle(f"transient vs statics maps, circuit '{circuit}' "
                     f"({maps.dataset.attrs.get('magnet_name', '')})")
        fig.tight_layout()
        out.append(save(fig, Path(folder) / f"maps_difference_{circuit}.png"))
    return out
