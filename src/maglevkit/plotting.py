"""Figures (matplotlib, Agg backend): force-current-gap curves, inductances, time responses."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["covers_data", "figure_directory", "place_legend", "plot_comparison",
           "plot_force_current", "plot_simulation", "save", "sequence_colors"]


def save(fig: Any, path: str | Path) -> Path:
    """Save a figure (creating the folder) and close it; the format follows the suffix
    (PNG for ``.png``, ...; the command line checks it first, ``plot_file``)

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards).
    path : str or Path
        Target file; missing folders are created.

    Returns
    -------
    Path
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(p, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return p


def figure_directory(directory: str | Path) -> Path:
    """The folder figures are written into, created if missing; only its last level is
    created (a mistyped parent is refused rather than built).

    Parameters
    ----------
    directory : str or Path
        Output folder (no unit); its parent must exist if it does not exist itself.

    Returns
    -------
    Path
        ``directory``, now an existing folder.

    Raises
    ------
    InputError
        The parent of a missing ``directory`` does not exist.
    """
    out = Path(directory)
    if not out.is_dir():
        if not out.parent.is_dir():
            from .errors import InputError

            raise InputError(f"cannot write figures into {str(out)!r}: the directory "
                             f"{str(out.parent)!r} does not exist")
        out.mkdir()
    return out


#: Inside positions tried, in this order, before a legend goes outside the axes.
_LEGEND_INSIDE = ("upper right", "upper left", "lower right", "lower left", "center right",
                  "center left", "upper center", "lower center")


def _artists_in(ax: Any) -> list[Any]:
    """Lines and texts of ``ax`` and of the axes sharing its place (twin axes)."""
    fig = ax.figure
    pos = ax.get_position().bounds
    axes = [a for a in fig.axes if a is ax or a.get_position().bounds == pos]
    return [art for a in axes for art in (*a.lines, *a.texts)]


def covers_data(legend: Any, ax: Any) -> bool:
    """True if ``legend``'s box overlaps a line (any segment, also between samples) or a
    text of ``ax`` or of its twin axes, in display coordinates of the drawn figure.

    Parameters
    ----------
    legend : matplotlib.legend.Legend
        A drawn legend.
    ax : matplotlib.axes.Axes
        Its axes.

    Returns
    -------
    bool
    """
    from matplotlib.lines import Line2D

    renderer = ax.figure.canvas.get_renderer()
    box = legend.get_window_extent(renderer)
    for art in _artists_in(ax):
        if not art.get_visible():
            continue
        if isinstance(art, Line2D):
            if np.asarray(art.get_xydata()).size == 0:
                continue
            path = art.get_transform().transform_path(art.get_path())
            if path.intersects_bbox(box, filled=False):
                return True
        elif art.get_text().strip() and box.overlaps(art.get_window_extent(renderer)):
            return True
    return False


def place_legend(ax: Any, handles: list[Any] | None = None, labels: list[str] | None = None,
                 *, outside: bool = False, **kwargs: Any) -> Any:
    """A legend where it covers no data: the first free inside position, else outside.

    Inside positions are tried in the order of ``_LEGEND_INSIDE`` (each checked with
    :func:`covers_data` on the drawn figure); if none is free, or with ``outside=True``,
    the legend goes to the right of the axes.  Call it after the axes' limits are final.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    handles, labels : list, optional
        Legend entries (default: the axes' own).
    outside : bool, default False
        Put the legend outside at once (keyword only).
    **kwargs
        Passed to ``ax.legend``.

    Returns
    -------
    matplotlib.legend.Legend
    """
    if handles is None or labels is None:
        handles, labels = ax.get_legend_handles_labels()
    fig = ax.figure
    if not outside:
        fig.canvas.draw()
        for loc in _LEGEND_INSIDE:
            leg = ax.legend(handles, labels, loc=loc, **kwargs)
            if not covers_data(leg, ax):
                return leg
            leg.remove()
    # outside: to the right of the axes (and of a twin axis' tick labels)
    return ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.12 if _has_twin(ax)
                     else 1.01, 1.0), borderaxespad=0.0, **kwargs)


def _has_twin(ax: Any) -> bool:
    pos = ax.get_position().bounds
    return any(a is not ax and a.get_position().bounds == pos for a in ax.figure.axes)


def sequence_colors(n: int, cmap: str = "viridis") -> list[Any]:
    """``n`` distinct colours along a colormap (for traces ordered along the magnet).

    Parameters
    ----------
    n : int
        Number of colours.
    cmap : str, default "viridis"
        Matplotlib colormap name.

    Returns
    -------
    list of RGBA tuples
        From the start to 90 % of the colormap.
    """
    cm = plt.get_cmap(cmap)
    return [cm(0.9 * k / max(1, n - 1)) for k in range(n)]


def plot_force_current(sol: Any, path: str | Path, *, title: str = "") -> Path:
    """Total force over current, one curve per gap, from a ``grid=True`` StaticSolution.

    Parameters
    ----------
    sol : StaticSolution
        From :func:`~maglevkit.models.solve_statics` with ``grid=True``.
    path : str or Path
        The PNG file to write.
    title : str, optional
        Figure title (keyword only).

    Returns
    -------
    Path
    """
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
    ax2.set_xlabel("current I [A]")
    ax2.set_ylabel("differential inductance dpsi/dI [mH]")
    ax2.set_title("differential inductance (sum over circuits)")
    ax2.grid(True, alpha=0.3)
    # one legend for both panels (same colours), right of the second: it covers no curve
    h, lab = ax1.get_legend_handles_labels()
    place_legend(ax2, h, lab, outside=True, fontsize=8, ncol=1 + len(lab) // 16)
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


#: Sequential colormaps for groups of traces (one per group, light -> dark along it).
_GROUP_CMAPS = ("Blues", "Oranges", "Greens", "Purples", "Reds", "Greys")
_GROUP_STYLES = ("-", "--", "-.", ":")


def group_styles(names: tuple[str, ...] | list[str]) -> list[tuple[Any, str]]:
    """Colour and line style per trace, grouped by the name without its index suffix.

    ``core_p01 .. core_p12`` form the group ``core``, ``leg_left_0 ..`` the group
    ``leg_left``: each group of several traces gets its own sequential colormap (light =
    first) and line style, a single trace a colour of its own.  So 14-24 eddy elements stay
    distinguishable, and which element sits where along the magnet is visible.
    """
    keys = [re.sub(r"([_-]?[A-Za-z]?\d+)+$", "", nm) or nm for nm in names]
    order = list(dict.fromkeys(keys))
    members = {k: [i for i, kk in enumerate(keys) if kk == k] for k in order}
    multi = [k for k in order if len(members[k]) > 1]
    out: list[tuple[Any, str]] = [("k", "-")] * len(names)
    single = 0
    for k in order:
        idx = members[k]
        if k in multi:
            g = multi.index(k)
            cm = plt.get_cmap(_GROUP_CMAPS[g % len(_GROUP_CMAPS)])
            for n, i in enumerate(idx):
                out[i] = (cm(0.45 + 0.5 * n / max(1, len(idx) - 1)),
                          _GROUP_STYLES[g % len(_GROUP_STYLES)])
        else:
            out[idx[0]] = (f"C{(3 + single) % 10}", "-")
            single += 1
    return out


def _distinct_columns(y: np.ndarray, names: tuple[str, ...] | list[str]
                      ) -> list[tuple[int, str]]:
    """Columns of ``y`` (n_t, n) to draw, with labels: columns that coincide with an
    earlier one (``COINCIDE_FRACTION`` of the range) are merged into its label."""
    rng = float(np.ptp(y)) or max(float(np.max(np.abs(y))) if y.size else 0.0, 1e-300)
    kept: list[tuple[int, list[str]]] = []
    for j, nm in enumerate(names):
        for k, labels in kept:
            if float(np.max(np.abs(y[:, j] - y[:, k]))) < COINCIDE_FRACTION * rng:
                labels.append(nm)
                break
        else:
            kept.append((j, [nm]))
    return [(k, ", ".join(labels) if len(labels) < 4 else
             f"{labels[0]} .. {labels[-1]} ({len(labels)}, equal)") for k, labels in kept]


def plot_simulation(res: Any, path: str | Path, *, title: str = "") -> Path:
    """Time response of a flux-model simulation: inputs, currents, forces, eddy MMFs.

    One column of four panels with the legends to the right of the axes (they never cover
    a trace).  Equal inputs and currents (e.g. the same gap at all 12 poles) are drawn once
    with a merged label; pole forces take their colours from a colormap along the magnet,
    eddy elements one colormap and line style per group (:func:`group_styles`).

    Parameters
    ----------
    res : SimulationResult
        A flux-model simulation result.
    path : str or Path
        The PNG file to write.
    title : str, optional
        Figure title (keyword only).

    Returns
    -------
    Path
    """
    t = res.time_s * 1e3
    n_pole = len(res.gap_names)
    n_eddy = len(res.eddy_branch_names)
    fig, axes = plt.subplots(4, 1, figsize=(10.5, 12), sharex=True)
    ax = axes[0]
    for j, label in _distinct_columns(res.voltages_V, res.circuit_names):
        ax.step(t, res.voltages_V[:, j], where="post", color=f"C{j % 10}", lw=1.6,
                label=f"U [{label}]")
    ax.set_ylabel("voltage [V] (solid)")
    ax2 = ax.twinx()
    gaps = _distinct_columns(res.gaps_m, res.gap_names)
    gap_colors = sequence_colors(len(gaps), "cividis")
    for (j, label), c in zip(gaps, gap_colors, strict=True):
        ax2.plot(t, res.gaps_m[:, j] * 1e3, "--", color=c, lw=1.2, label=f"s [{label}]")
    ax2.set_ylabel("gap [mm] (dashed)")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    place_legend(ax, h1 + h2, l1 + l2, outside=True, fontsize=7.5,
                 ncol=1 + (len(l1) + len(l2)) // 14)
    ax.set_title("inputs")
    ax = axes[1]
    for j, label in _distinct_columns(res.currents_A, res.circuit_names):
        ax.plot(t, res.currents_A[:, j], color=f"C{j % 10}", lw=1.6, label=label)
    ax.set_ylabel("current [A]")
    ax.set_title("circuit currents")
    place_legend(ax, outside=True, fontsize=8)
    ax = axes[2]
    for j, (nm, c) in enumerate(zip(res.gap_names, sequence_colors(n_pole), strict=True)):
        ax.plot(t, res.pole_force_N[:, j] / 1e3, color=c, lw=1.1, label=f"pole {nm}")
    ax.plot(t, res.force_N / 1e3, "k", lw=1.8, label="total")
    ax.set_ylabel("force [kN]")
    ax.set_title("magnet forces (attraction > 0)")
    place_legend(ax, outside=True, fontsize=7.5, ncol=1 + n_pole // 14)
    ax = axes[3]
    for j, (nm, (c, ls)) in enumerate(zip(res.eddy_branch_names,
                                          group_styles(res.eddy_branch_names), strict=True)):
        ax.plot(t, res.eddy_mmf_A[:, j], color=c, ls=ls, lw=1.2, label=nm)
    ax.set_ylabel("eddy-current MMF [A]")
    ax.set_xlabel("time [ms]")
    ax.set_title(f"eddy currents ({n_eddy} eddy elements)" if n_eddy
                 else "eddy currents (switched off)")
    if n_eddy:
        place_legend(ax, outside=True, fontsize=7.5, ncol=1 + n_eddy // 14)
    for a in axes:
        a.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return save(fig, path)


#: Two traces "coincide" when they differ by less than this fraction of the panel's range:
#: at the saved size a panel is ~400 px high, so 1e-3 of its range is < 0.5 px, invisible.
COINCIDE_FRACTION = 1e-3

#: Markers of the reduced model's traces, one per circuit, so that dashes of different
#: circuits stay apart where they overlap.
_MARKERS = ("o", "s", "^", "D", "v", "P")


def _coinciding(series: list[np.ndarray]) -> tuple[bool, float]:
    """Whether all columns of every (n_t, n_circuits) array equal the first column within
    ``COINCIDE_FRACTION`` of the array's range, and the largest such relative difference."""
    worst = 0.0
    for y in series:
        rng = float(np.ptp(y)) or max(float(np.max(np.abs(y))), 1e-300)
        worst = max(worst, float(np.max(np.abs(y - y[:, :1]))) / rng)
    return worst < COINCIDE_FRACTION, worst


def plot_comparison(result: Any, path: str | Path, *, title: str = "") -> Path:
    """Detailed vs reduced time responses of one comparison scenario.

    Panels: the gap (closed loop: both models and the reference; open loop: the common gap
    input, drawn if it moves), the coil currents and the circuit forces.  Each circuit has
    its colour; the detailed model is a solid line, the reduced model a dashed line of a
    darker shade with the circuit's marker.  Circuits whose traces coincide (symmetric
    magnet and inputs, within ``COINCIDE_FRACTION`` of the range) are drawn once and named
    together.  The legend sits to the right of the axes.

    Parameters
    ----------
    result : ComparisonResult
        One scenario of :func:`~maglevkit.compare.compare_models`.
    path : str or Path
        The PNG file to write.
    title : str, optional
        Figure title (keyword only).

    Returns
    -------
    Path
    """
    from matplotlib.colors import to_rgb

    t = result.time_s * 1e3
    names = list(result.circuit_names)
    nc = len(names)
    closed = result.scenario.kind == "closed"
    gd = getattr(result, "detailed_gap_m", None)
    gr = getattr(result, "reduced_gap_m", None)
    gref = getattr(result, "reference_gap_m", None)
    # open loop: the gap panel only if the input moves by more than rounding (1e-6 of it;
    # the mean over the gap inputs of a constant gap varies by ~1e-18 m)
    show_gap = gd is not None and (closed or float(np.ptp(gd)) > 1e-6 * float(np.mean(gd)))
    same, worst = (_coinciding([result.detailed_currents_A, result.reduced_currents_A,
                                result.detailed_forces_N, result.reduced_forces_N])
                   if nc > 1 else (False, 0.0))
    shown = [0] if same else list(range(nc))
    rows = 3 if show_gap else 2
    fig, axes = plt.subplots(rows, 1, figsize=(10, 2.6 * rows + 1.2), sharex=True)
    a_gap = axes[0] if show_gap else None
    a1, a2 = axes[-2], axes[-1]
    every = max(1, t.size // 14)
    for j in shown:
        label = " = ".join(names) if same else names[j]
        color = f"C{j % 10}"
        dark = tuple(0.55 * c for c in to_rgb(color))
        mk = _MARKERS[j % len(_MARKERS)]
        for ax, yd, yr, scale in ((a1, result.detailed_currents_A, result.reduced_currents_A, 1.0),
                                  (a2, result.detailed_forces_N, result.reduced_forces_N, 1e-3)):
            ax.plot(t, yd[:, j] * scale, lw=2.4, color=color, alpha=0.8,
                    label=f"{label}: detailed")
            ax.plot(t, yr[:, j] * scale, "--", lw=1.1, color=dark, marker=mk, ms=4.5,
                    mfc="none", markevery=(every * j // max(1, nc), every),
                    label=f"{label}: reduced")
    if a_gap is not None and gd is not None:
        if closed and gr is not None:
            if gref is not None:
                a_gap.plot(t, gref * 1e3, color="0.5", lw=1.0, ls=":", label="gap reference")
            a_gap.plot(t, gd * 1e3, lw=2.4, color="tab:purple", alpha=0.8,
                       label="gap: detailed")
            a_gap.plot(t, gr * 1e3, "--", lw=1.1, color="indigo", marker="x", ms=4.5,
                       markevery=every, label="gap: reduced")
            a_gap.set_title("gap (controlled variable)", fontsize=9)
        else:
            a_gap.plot(t, gd * 1e3, lw=1.6, color="tab:purple",
                       label="gap input (both models)")
            a_gap.set_title("gap (input)", fontsize=9)
        a_gap.set_ylabel("gap [mm]")
    a1.set_ylabel("coil current [A]")
    a2.set_ylabel("circuit force [kN]")
    a2.set_xlabel("time [ms]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        place_legend(ax, outside=True, fontsize=8)
    a1.set_title("coil currents" + (f" ({' and '.join(names)} coincide)" if same else ""),
                 fontsize=9)
    a2.set_title("circuit forces", fontsize=9)
    errs = ", ".join(f"{n}: I {100 * ci:.2f} %, F {100 * fi:.2f} %" for n, ci, fi in
                     zip(result.circuit_names, result.current_error, result.force_error,
                         strict=True))
    fig.suptitle((title + "\n" if title else "") + f"{result.scenario.name}: "
                 f"{result.scenario.description}", fontsize=10)
    note = (f"normalised RMS error {errs}; CPU time (best warm run) detailed "
            f"{result.detailed_cpu_s * 1e3:.0f} ms, reduced {result.reduced_cpu_s * 1e3:.2f} ms "
            f"(x{result.speedup:.0f})")
    if same:
        note += (f".\nCircuits {', '.join(names)} coincide (largest difference "
                 f"{100 * worst:.1g} % of the signal range): drawn once.")
    if closed and result.extra.get("gap_error") is not None:
        note += (f"\ngap: RMS(reduced - detailed) = {100 * result.extra['gap_error']:.2f} % of "
                 "the detailed gap's range")
    fig.tight_layout()
    fig.text(0.01, -0.01, note, fontsize=8, color="0.3", va="top")
    return save(fig, path)
