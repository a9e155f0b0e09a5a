"""The paper's validation figures, reproduced in kind from a magnet's models.

* :func:`figure_force_current` -- Fig. 6 analog: ``F/F0`` over ``I/I0`` at several gaps,
  full model vs the model without saturation (constant ``mu_r(0)``).
* :func:`figure_inductance` -- Fig. 7 analog at s = 9.5 mm: the full model's static
  differential inductance ``L~ = dpsi/dI`` and its *apparent* inductance ``tau R_el``
  from simulated small voltage steps of the detailed flux model (how fast the current
  follows a voltage step, what the paper measured), vs the model without saturation and
  eddy currents.  Statically ``L~`` does not depend on eddy currents (they carry no static
  MMF); in the step response they slow the current down, ``tau R_el ~ L~ (1 + R_el/R_ec)``.
* :func:`figure_coupling` -- time response of all circuits to a voltage step in the first
  one (detailed flux-based model, :func:`coupling_response`), with the coupling quantified.

Normalisation: ``I0`` is the saturation knee (:func:`~maglevkit.models.saturation_knee`
at the nominal gap ``s0``), ``F0 = F(s0, I0)`` of the full model.  The nominal current of
the parameter file is marked.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .magnets.base import Magnet
from .models.characteristics import KNEE_EXPONENT, nominal_point, saturation_knee
from .models.statics import solve_statics
from .plotting import place_legend, plt, save
from .validation import renamed_keywords

__all__ = ["Fig6Data", "Fig7Data", "CouplingResponse", "fig6_data", "fig7_data",
           "coupling_response", "figure_force_current", "figure_inductance", "figure_coupling",
           "write_figures"]


@dataclass(frozen=True)
class Fig6Data:
    """Normalised force-current characteristics (paper Fig. 6).

    ``force_full`` and ``force_linear`` have shape (n_gaps, n_currents) and are ``F/F0``;
    ``current`` is ``I/I0``; ``gaps_m`` the gaps [m].

    Attributes
    ----------
    gaps_m : ndarray (n_gaps,)
        Uniform gaps of the curves [m].
    current : ndarray (n_currents,)
        ``I/I0`` [-], every circuit at the same current.
    force_full, force_linear : ndarray (n_gaps, n_currents)
        Total force ``F/F0`` [-] of the full model and of the model without saturation
        and eddy currents.
    I0_A : float
        Saturation knee ``I0`` [A] at the nominal gap
        (:func:`~maglevkit.magnets.saturation_knee`).
    F0_N : float
        Force at the nominal gap and ``I0`` [N] (full model).
    nominal_gap_m, nominal_current_A : float
        The magnet's nominal operating point [m], [A].
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
    """Normalised inductance over current (paper Fig. 7).

    Attributes
    ----------
    gap_m : float
        Uniform gap of the curves [m].
    current : ndarray
        ``I/I0`` of the static curves.
    inductance_full, inductance_linear : ndarray
        Static ``L~/L0 = (dpsi/dI)/L0`` of the first circuit with every circuit at the
        same current; full model and model without saturation and eddy currents.
    step_current : ndarray
        ``I/I0`` of the simulated voltage steps (empty if none were simulated).
    step_inductance_full, step_inductance_linear : ndarray
        Apparent inductance ``tau R_el / L0`` from a small voltage step of the first
        circuit (:func:`~maglevkit.models.experiments.differential_inductance_from_step`,
        detailed flux model, other circuits at constant voltage).
    L0_H : float
        Static inductance of the model without saturation and eddy currents [H].
    I0_A : float
        Saturation knee ``I0`` [A] at the nominal gap.
    nominal_current_A : float
        The magnet's nominal current [A].
    """

    gap_m: float
    current: np.ndarray
    inductance_full: np.ndarray
    inductance_linear: np.ndarray
    I0_A: float
    L0_H: float
    nominal_current_A: float
    step_current: np.ndarray
    step_inductance_full: np.ndarray
    step_inductance_linear: np.ndarray


def fig6_data(magnet: Magnet, *, gap_factors: tuple[float, ...] = (0.8, 1.0, 1.2, 1.5),
              max_current: float = 2.2, points: int = 89) -> Fig6Data:
    """Data of the Fig. 6 analog; gaps ``gap_factors x s0``, currents ``0..max_current x I0``.

    Parameters
    ----------
    magnet : Magnet
        Magnet with an ``[operating]`` table (nominal gap ``s0`` and current).
    gap_factors : tuple of float
        Gaps as multiples of the nominal gap [-] (keyword only, like all that follow).
    max_current : float, default 2.2
        Largest current as a multiple of the knee ``I0`` [-].
    points : int, default 89
        Currents per curve.

    Returns
    -------
    Fig6Data

    Raises
    ------
    InputError
        A magnet without an ``[operating]`` table, no saturation knee, or bad gaps.
    """
    s0, i_nom = nominal_point(magnet)
    i0 = saturation_knee(magnet, gap_m=s0)
    gaps = s0 * np.asarray(gap_factors, dtype=float)
    cur = np.linspace(0.0, max_current, points)
    full = solve_statics(magnet, gaps_m=gaps, currents_A=cur * i0, grid=True).force_N
    lin_mag = magnet.with_options(saturation=False, eddy_currents=False)
    lin = solve_statics(lin_mag, gaps_m=gaps, currents_A=cur * i0, grid=True).force_N
    f0 = float(solve_statics(magnet, gaps_m=s0, currents_A=i0).force_N)
    return Fig6Data(gaps, cur, full / f0, lin / f0, i0, f0, s0, i_nom)


#: Settings of the Fig. 7 voltage steps: 25 samples per time constant (coarse, for speed)
#: at the integrator's default tolerances.  rtol 1e-6 was enough while IDAS restarted at
#: every sample; running through the hold intervals (one IDAS run per voltage level) it
#: left a 0.7 % error in ``tau R_el`` of the linear TR09 magnet (0.5559 vs 0.5522 H at
#: rtol 1e-11) and a 0.37 % spread over the step currents.
_STEP_SETTINGS: dict[str, Any] = {"samples_per_tau": 25, "n_tau": 4.0, "rtol": 1e-9,
                                  "atol": 1e-11}


@renamed_keywords(gap="gap_m")
def fig7_data(magnet: Magnet, *, gap_m: float = 0.0095, max_current: float = 2.2,
              points: int = 89, step_points: int = 12) -> Fig7Data:
    """Data of the Fig. 7 analog at ``gap_m`` [m] (the paper: 9.5 mm).

    Old keyword names (``gap``) are deprecated aliases for one release.

    Parameters
    ----------
    magnet : Magnet
        Magnet with an ``[operating]`` table.
    gap_m : float
        Uniform gap [m].
    max_current : float
        Largest current as a multiple of the knee ``I0``.
    points : int
        Currents of the static curves.
    step_points : int
        Currents ``0.1 .. max_current x I0`` at which a small voltage step of the first
        circuit is simulated with the detailed flux model, full and without saturation and
        eddy currents (0: none; each step costs ~0.3-1 s).

    Returns
    -------
    Fig7Data

    Raises
    ------
    InputError
        If ``step_points`` is negative or the magnet has no ``[operating]`` table.
    """
    from .errors import InputError
    from .models.experiments import differential_inductance_from_step

    if isinstance(step_points, bool) or not isinstance(step_points, int) or step_points < 0:
        raise InputError(f"step_points = {step_points!r} must be an integer >= 0")
    s0, i_nom = nominal_point(magnet)
    i0 = saturation_knee(magnet, gap_m=s0)
    cur = np.linspace(0.0, max_current, points)
    full = solve_statics(magnet, gaps_m=np.array([gap_m]), currents_A=cur * i0, grid=True)
    lin_mag = magnet.with_options(saturation=False, eddy_currents=False)
    lin = solve_statics(lin_mag, gaps_m=np.array([gap_m]), currents_A=cur * i0, grid=True)
    l_full = full.common_differential_inductance_H[0, :, 0]
    l_lin = lin.common_differential_inductance_H[0, :, 0]
    l0 = float(l_lin[0])
    x_step = np.linspace(0.1, max_current, step_points) if step_points else np.zeros(0)
    step_full = np.array([differential_inductance_from_step(
        magnet, gap_m=gap_m, current_A=float(x * i0), **_STEP_SETTINGS).apparent_inductance_H
        for x in x_step])
    step_lin = np.array([differential_inductance_from_step(    # lin_mag: compiled once
        lin_mag, gap_m=gap_m, current_A=float(x * i0), **_STEP_SETTINGS).apparent_inductance_H
        for x in x_step])
    return Fig7Data(gap_m, cur, l_full / l0, l_lin / l0, i0, l0, i_nom, x_step,
                    step_full / l0, step_lin / l0)


def _mark_currents(ax: Any, i_nom_rel: float) -> list[Any]:
    """Vertical lines at the knee (``I/I0 = 1``) and the nominal current, with labels.

    Each label sits on the outer side of its line (the left line's label to its left, the
    right line's to its right), so the two never collide whichever current is larger; a
    label that would leave the axes on the left goes inside, one row lower.  Returns the
    text artists.
    """
    ax.axvline(1.0, color="0.35", lw=0.9, ls=":")
    ax.axvline(i_nom_rel, color="tab:red", lw=0.9, ls=":")
    trans = ax.get_xaxis_transform()          # x in data, y in axes fraction
    marks = [(1.0, "knee I0", "0.35"), (i_nom_rel, "nominal", "tab:red")]
    if abs(i_nom_rel - 1.0) < 1e-9:
        return [ax.text(1.0, 0.98, " nominal = knee I0", transform=trans, va="top",
                        ha="left", fontsize=8, color="tab:red")]
    (x_l, lab_l, c_l), (x_r, lab_r, c_r) = sorted(marks, key=lambda m: m[0])
    x0, x1 = ax.get_xlim()
    left_inside = (x_l - x0) / (x1 - x0) < 0.12   # no room for the label left of the line
    texts = [ax.text(x_r, 0.98, f" {lab_r}", transform=trans, va="top", ha="left",
                     fontsize=8, color=c_r)]
    if left_inside:
        texts.append(ax.text(x_l, 0.91, f" {lab_l}", transform=trans, va="top", ha="left",
                             fontsize=8, color=c_l))
    else:
        texts.append(ax.text(x_l, 0.98, f"{lab_l} ", transform=trans, va="top", ha="right",
                             fontsize=8, color=c_l))
    return texts


def figure_force_current(magnet: Magnet, path: str | Path, *, data: Fig6Data | None = None
                         ) -> Path:
    """Write the Fig. 6 analog (PNG) and return its path.

    Parameters
    ----------
    magnet : Magnet
        Magnet with an ``[operating]`` table.
    path : str or Path
        The PNG file to write.
    data : Fig6Data, optional
        Precomputed data (default: :func:`fig6_data` of ``magnet``; keyword only).

    Returns
    -------
    Path
        The written file.
    """
    return save(_draw_force_current(magnet.name, data or fig6_data(magnet)), path)


def _draw_force_current(magnet_name: str, d: Fig6Data) -> Any:
    """The Fig. 6 analog as a matplotlib figure (not saved)."""
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
    ax.set_title(f"Fig. 6 analog: force-current characteristics\n{magnet_name}", fontsize=10)
    ax.grid(True, alpha=0.3)
    _mark_currents(ax, d.nominal_current_A / d.I0_A)
    place_legend(ax, fontsize=8)
    fig.text(0.01, -0.08, f"I0 = {d.I0_A:.1f} A (knee: d ln F/d ln I = {KNEE_EXPONENT} at "
             f"s0 = {d.nominal_gap_m * 1e3:.1f} mm),\nF0 = F(s0, I0) = {d.F0_N / 1e3:.1f} kN "
             f"(whole magnet); all circuits at the same current.", fontsize=7.5, color="0.3")
    return fig


def figure_inductance(magnet: Magnet, path: str | Path, *, data: Fig7Data | None = None) -> Path:
    """Write the Fig. 7 analog (PNG) and return its path.

    Static ``L~ = dpsi/dI`` and, where simulated, the apparent inductance ``tau R_el`` of
    small voltage steps (detailed flux model), for the full model and for the model without
    saturation and eddy currents.

    Parameters
    ----------
    magnet : Magnet
        Magnet with an ``[operating]`` table.
    path : str or Path
        The PNG file to write.
    data : Fig7Data, optional
        Precomputed data (default: :func:`fig7_data` of ``magnet``; keyword only).

    Returns
    -------
    Path
        The written file.
    """
    return save(_draw_inductance(magnet.name, data or fig7_data(magnet)), path)


def _draw_inductance(magnet_name: str, d: Fig7Data) -> Any:
    """The Fig. 7 analog as a matplotlib figure (not saved)."""
    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    has_steps = d.step_current.size > 0
    ax.plot(d.current, d.inductance_full, color="tab:blue", lw=2.0,
            label="full model: static L~ = dpsi/dI")
    if has_steps:
        ax.plot(d.step_current, d.step_inductance_full, color="tab:blue", lw=1.0, ls="-.",
                marker="o", ms=5, label="full model: step response tau R_el")
    ax.plot(d.current, d.inductance_linear, color="tab:orange", lw=1.5, ls="--",
            label="without saturation and eddy currents: static L~")
    if has_steps:
        ax.plot(d.step_current, d.step_inductance_linear, color="tab:orange", lw=0, marker="s",
                ms=5, mfc="none", label="without saturation and eddy currents: tau R_el")
    top = max(float(d.inductance_full.max()), 1.0,
              float(d.step_inductance_full.max()) if has_steps else 0.0)
    ax.set_xlim(0.0, 1.02 * d.current[-1])
    ax.set_ylim(0.0, 1.3 * top)
    ax.set_xlabel("normalised current I / I0")
    ax.set_ylabel("normalised inductance L / L0")
    ax.set_title(f"Fig. 7 analog: differential inductance at s = {d.gap_m * 1e3:.1f} mm\n"
                 f"{magnet_name}", fontsize=10)
    ax.grid(True, alpha=0.3)
    _mark_currents(ax, d.nominal_current_A / d.I0_A)
    place_legend(ax, fontsize=7.5, framealpha=0.9)
    note = (f"L~ = dpsi/dI of one circuit with all circuits at the same current; L0 = {d.L0_H:.3f} H "
            f"(model without saturation\nand eddy currents), I0 = {d.I0_A:.1f} A.  Statically L~ "
            "is independent of eddy currents.")
    if has_steps:
        below = d.step_current < 0.7
        ratio = (float(np.mean(d.step_inductance_full[below] / d.step_inductance_linear[below]))
                 if np.any(below) else float("nan"))
        note += ("  tau R_el: time constant of the current after a\nsmall voltage step of one "
                 "circuit (detailed flux model) times its resistance, the paper's measured "
                 "inductance.  With eddy\ncurrents the current follows more slowly, "
                 f"tau R_el ~ L~ (1 + R_el/R_ec): {ratio:.2f} x the model without saturation and "
                 "eddy currents\nbelow 0.7 I0, falling with saturation.  Without them "
                 f"tau R_el = L_11 = {float(np.mean(d.step_inductance_linear)):.3f} L0, constant "
                 "(one circuit stepped: the other's\nmutual share of L~ is missing).")
    fig.text(0.01, -0.02, note, fontsize=7.5, color="0.3", va="top")
    return fig


@dataclass(frozen=True)
class CouplingResponse:
    """Response of all circuits to a voltage step in the first one (flux-based model).

    Attributes
    ----------
    time_s : ndarray (n_t,)
        Sample times [s].
    circuit_names : tuple of str
        The circuits (columns of ``relative_current_change``).
    relative_current_change : ndarray (n_t, n_circuits)
        ``(I - I0) / I0`` [-].
    other_peak_ratio : float
        ``max |dI_other| / max |dI_stepped|`` [-].
    mutual_ratio : float
        ``max |L_ij| / sqrt(L_ii L_jj)``, ``i != j`` [-] (statics).
    """

    time_s: np.ndarray
    circuit_names: tuple[str, ...]
    relative_current_change: np.ndarray   # (n_t, n_circuits), (I - I0) / I0
    other_peak_ratio: float               # max |dI_other| / max |dI_stepped|
    mutual_ratio: float                   # max |L_ij| / sqrt(L_ii L_jj), i != j


def coupling_response(magnet: Magnet, *, step: float = 0.2) -> CouplingResponse:
    """Step the first circuit's voltage by ``step`` (relative) at the nominal point and
    simulate the detailed flux-based model for three time constants."""
    from .models.characteristics import coupling_ratios
    from .models.flux import simulate_flux as simulate

    s0, i0 = nominal_point(magnet)
    net = magnet.network
    r = net.resistances
    sol = solve_statics(magnet, gaps_m=s0, currents_A=i0)
    tau = float(sol.differential_inductance_H[0, 0] / r[0])
    u0 = r * i0
    bump = np.zeros(len(r))
    bump[0] = step
    dur = 3.0 * tau
    res = simulate(magnet, (0.0, dur), dt_s=dur / 600, gaps_m=s0,
                   voltages_V=lambda t: u0 * (1.0 + bump * (t >= 0.02 * dur)), initial_currents_A=i0)
    rel = (res.currents_A - i0) / i0
    peak = np.max(np.abs(rel), axis=0)
    ratios = coupling_ratios(magnet, gap_m=s0, current_A=i0).ratio
    off = np.abs(ratios - np.diag(np.diag(ratios)))
    return CouplingResponse(res.time_s, res.circuit_names, rel,
                            float(peak[1:].max() / peak[0]), float(off.max()))


def figure_coupling(magnet: Magnet, path: str | Path, *,
                    data: CouplingResponse | None = None) -> Path:
    """Currents of all circuits after a voltage step in the first circuit (paper Sec. IV-A).

    The stepped circuit is drawn against the left axis; the other circuits, whose response
    is below 1 % of it, against a magnified right axis with the same zero.

    Parameters
    ----------
    magnet : Magnet
        Magnet with an ``[operating]`` table and at least two circuits.
    path : str or Path
        The PNG file to write.
    data : CouplingResponse, optional
        Precomputed data (default: :func:`coupling_response` of ``magnet``; keyword only).

    Returns
    -------
    Path
        The written file.
    """
    return save(_draw_coupling(magnet.name, data or coupling_response(magnet)), path)


def _draw_coupling(magnet_name: str, d: CouplingResponse) -> Any:
    """The coupling figure as a matplotlib figure (not saved)."""
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    rel = 100.0 * d.relative_current_change
    t_ms = d.time_s * 1e3
    ax.plot(t_ms, rel[:, 0], color="tab:blue", lw=2.2,
            label=f"circuit {d.circuit_names[0]} (stepped, left axis)")
    m_step = float(np.max(np.abs(rel[:, 0])))
    others = rel[:, 1:]
    m_other = float(np.max(np.abs(others))) if others.size else 0.0
    negative = others.size > 0 and float(others.flat[np.argmax(np.abs(others))]) < 0.0
    lim = (-0.6 * m_step if negative else -0.1 * m_step, 1.1 * m_step)
    ax.set_ylim(*lim)
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("stepped circuit: (I - I0)/I0 [%]", color="tab:blue")
    ax.tick_params(axis="y", colors="tab:blue")
    ax.grid(True, alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    if others.size and m_other > 0.0:
        # magnify so that the other circuits' peak spans ~half the stepped circuit's range
        k = m_other / (0.5 * m_step)
        ax2 = ax.twinx()
        colors = ["tab:orange", "tab:green", "tab:red", "tab:purple"]
        for j, name in enumerate(d.circuit_names[1:]):
            ax2.plot(t_ms, rel[:, j + 1], color=colors[j % len(colors)], lw=1.6,
                     label=f"circuit {name} (right axis, magnified x{1.0 / k:.0f})")
        ax2.set_ylim(lim[0] * k, lim[1] * k)
        c2 = "tab:orange" if len(d.circuit_names) == 2 else "0.2"
        ax2.set_ylabel("other circuits: (I - I0)/I0 [%]", color=c2)
        ax2.tick_params(axis="y", colors=c2)
        h2, l2 = ax2.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    place_legend(ax, handles, labels, fontsize=8.5, framealpha=0.9)
    ax.set_title(f"Coupling of the circuits: +20 % voltage step on '{d.circuit_names[0]}'\n"
                 f"{magnet_name}", fontsize=10)
    fig.text(0.01, -0.02, f"Largest response of another circuit: {100 * d.other_peak_ratio:.2f} % "
             f"of the stepped circuit's; static mutual/self inductance ratio {d.mutual_ratio:.4f}.\n"
             "Detailed flux-based model with eddy currents, at the nominal gap and current; "
             "both y axes share the zero.", fontsize=8, color="0.3", va="top")
    return fig


def write_figures(magnet: Magnet, out: str | Path, *, step_points: int = 12) -> list[Path]:
    """Write the figures of ``magnet`` into folder ``out``: Figs. 6-7 analogs and, for
    magnets with several circuits, the coupling response (flux-based model).

    ``step_points`` is the number of simulated voltage steps of the Fig. 7 analog (see
    :func:`fig7_data`).

    Parameters
    ----------
    magnet : Magnet
        Magnet with an ``[operating]`` table; its file name gives the figures' names.
    out : str or Path
        Existing output folder.
    step_points : int, default 12
        Simulated voltage steps of the Fig. 7 analog (>= 0; keyword only).

    Returns
    -------
    list of Path
        ``<stem>-fig6-force-current.png``, ``<stem>-fig7-inductance.png`` and, with
        several circuits, ``<stem>-coupling.png``.
    """
    out = Path(out)
    stem = Path(magnet.source).stem or "magnet"
    paths = [figure_force_current(magnet, out / f"{stem}-fig6-force-current.png"),
             figure_inductance(magnet, out / f"{stem}-fig7-inductance.png",
                               data=fig7_data(magnet, step_points=step_points))]
    if len(magnet.network.circuits) > 1:
        paths.append(figure_coupling(magnet, out / f"{stem}-coupling.png"))
    return paths
