"""Characteristic numbers of a magnet from its statics: saturation knee and circuit coupling.

(In :mod:`maglevkit.models`, not :mod:`maglevkit.magnets`: they solve the statics, which
sit a layer above the magnets.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..magnets.base import Magnet
from ..validation import real_number, renamed_keywords, whole_number
from .statics import solve_statics

__all__ = ["saturation_knee", "coupling_ratios", "nominal_point", "force_exponent", "Coupling",
           "KNEE_EXPONENT"]

#: Force exponent ``d ln F / d ln I`` that defines the saturation knee I0: 2 for an
#: unsaturated magnet (F ~ I^2); at 1.8 the force grows 10 % slower than quadratically.
KNEE_EXPONENT = 1.8


def nominal_point(magnet: Magnet) -> tuple[float, float]:
    """``(nominal_gap [m], nominal_current [A])`` from the file's ``[operating]`` table.

    Parameters
    ----------
    magnet : Magnet
        A magnet loaded from a parameter file.

    Returns
    -------
    (gap_m, current_A) : tuple of float
        Nominal gap [m] and nominal current [A].

    Raises
    ------
    InputError
        If the magnet's parameter file has no ``[operating]`` table.
    """
    s0, i0 = magnet.nominal_gap, magnet.nominal_current
    if s0 is None or i0 is None:
        # issue 27: "give the gap and current explicitly" sent CLI users (figures) to
        # options that do not exist; the file's table is the remedy for every caller
        raise InputError(f"magnet {magnet.name!r} has no [operating] table: add one to its "
                         "parameter file (nominal_gap in m, nominal_current in A; see "
                         "'maglevkit template magnet levitation_magnet'), or in Python "
                         "pass the gap and current where the function takes them")
    return s0, i0


@renamed_keywords(gap="gap_m", currents="currents_A")
def force_exponent(magnet: Magnet, *, gap_m: float, currents_A: np.ndarray) -> np.ndarray:
    """Local exponent ``n = d ln F / d ln I = I (dF/dI) / F`` of the total force.

    Every circuit carries the same current; exact ``dF/dI`` from the statics.

    Old keyword names (``gap``, ``currents``) are deprecated aliases for one release.

    Parameters
    ----------
    magnet : Magnet
        The magnet (or network; anything :func:`~maglevkit.models.solve_statics` takes).
    gap_m : float
        Gap of every pole [m], > 0 (keyword only).
    currents_A : array_like (n,)
        Currents [A], each > 0, applied to every circuit at once (keyword only).

    Returns
    -------
    ndarray (n,)
        ``n`` [-] at each current: 2 for an unsaturated magnet, falling with saturation.

    Raises
    ------
    InputError
        A current <= 0, or a bad gap (from the statics).
    SolverError
        If the statics cannot be solved.
    """
    cur = np.asarray(currents_A, dtype=float)
    if np.any(cur <= 0.0):
        raise InputError("force_exponent needs currents > 0 A")
    sol = solve_statics(magnet, gaps_m=np.array([gap_m]), currents_A=cur, grid=True)
    dfdi = sol.dforce_dcurrent_N_per_A[0].sum(axis=(-2, -1))
    return np.asarray(cur * dfdi / sol.force_N[0])


@renamed_keywords(gap="gap_m", max_current="max_current_A")
def saturation_knee(magnet: Magnet, *, gap_m: float | None = None,
                    exponent: float = KNEE_EXPONENT, max_current_A: float | None = None,
                    points: int = 161) -> float:
    """Saturation knee I0 [A]: the current at which ``d ln F / d ln I`` falls to ``exponent``.

    Old keyword names (``gap``, ``max_current``) are deprecated aliases for one release.

    Parameters
    ----------
    magnet : Magnet
        The magnet (all circuits carry the same current).
    gap_m : float, optional
        Gap of every pole [m]; default the nominal gap.
    exponent : float
        Threshold in (0, 2); default :data:`KNEE_EXPONENT`.
    max_current_A : float, optional
        Upper end of the scan [A], finite and > 0; default 4 x the nominal current.
    points : int
        Scan resolution, a whole number >= 2 (currents ``max_current / points ...
        max_current``); the crossing is interpolated linearly.

    Returns
    -------
    float
        I0 [A].

    Raises
    ------
    InputError
        Bad arguments, or no knee within the scanned range.
    """
    if not 0.0 < real_number(exponent, "exponent") < 2.0:
        raise InputError(f"exponent = {exponent!r} must lie in (0, 2)")
    points = whole_number(points, "points", minimum=2)
    if max_current_A is not None:
        max_current_A = real_number(max_current_A, "max_current", "A", positive=True)
    scan = "max_current"
    if gap_m is None or max_current_A is None:
        s0, i0 = nominal_point(magnet)
        gap_m = s0 if gap_m is None else gap_m
        if max_current_A is None:
            max_current_A = 4.0 * i0
            scan = f"4 x the file's [operating] nominal_current = {i0:g} A"
    cur = np.linspace(max_current_A / points, max_current_A, points)
    n = force_exponent(magnet, gap_m=gap_m, currents_A=cur)
    below = np.nonzero(n < exponent)[0]
    # skip the low-current region (finite iron permeability rising with B)
    below = below[cur[below] > 0.05 * max_current_A]
    if below.size == 0:
        raise InputError(f"no saturation knee up to {max_current_A:g} A ({scan}) at gap "
                         f"{gap_m:g} m (d ln F/d ln I stays >= {exponent}): the magnet does "
                         "not saturate there; check the magnet file's [operating] "
                         "nominal_current and its dimensions for a unit slip"
                         + (", or raise max_current" if scan == "max_current" else ""))
    j = int(below[0])
    if j == 0:
        return float(cur[0])
    return float(np.interp(exponent, [n[j], n[j - 1]], [cur[j], cur[j - 1]]))


@dataclass(frozen=True)
class Coupling:
    """Differential inductance matrix and its coupling ratios at one operating point.

    Attributes
    ----------
    circuit_names : tuple of str
        The circuits, in the order of the matrix rows and columns.
    inductance_H : ndarray (n_circuits, n_circuits)
        ``dpsi_i / dI_j`` [H].
    ratio : ndarray (n_circuits, n_circuits)
        ``L_ij / sqrt(L_ii L_jj)`` (coupling coefficient; 1 on the diagonal).
    """

    circuit_names: tuple[str, ...]
    inductance_H: np.ndarray
    ratio: np.ndarray

    @property
    def max_ratio(self) -> float:
        """Largest ``|L_ij| / sqrt(L_ii L_jj)`` over ``i != j``."""
        r = np.abs(self.ratio.copy())
        np.fill_diagonal(r, 0.0)
        return float(r.max())


@renamed_keywords(gap="gap_m", current="current_A")
def coupling_ratios(magnet: Magnet, *, gap_m: float | None = None,
                    current_A: float | None = None) -> Coupling:
    """Mutual/self differential-inductance ratios of the circuits (statics, uniform gap).

    Defaults: nominal gap and current of the parameter file.

    Old keyword names (``gap``, ``current``) are deprecated aliases for one release.

    Parameters
    ----------
    magnet : Magnet
        The magnet.
    gap_m : float, optional
        Gap of every pole [m], > 0; default the nominal gap (keyword only).
    current_A : float, optional
        Current of every circuit [A]; default the nominal current (keyword only).

    Returns
    -------
    Coupling

    Raises
    ------
    InputError
        A default needed but no ``[operating]`` table in the magnet's file, or a bad gap
        or current (from the statics).
    SolverError
        If the statics cannot be solved.
    """
    if gap_m is None or current_A is None:
        s0, i0 = nominal_point(magnet)
        gap_m = s0 if gap_m is None else gap_m
        current_A = i0 if current_A is None else current_A
    sol = solve_statics(magnet, gaps_m=gap_m, currents_A=current_A)
    L = np.asarray(sol.differential_inductance_H)
    d = np.sqrt(np.diag(L))
    return Coupling(sol.circuit_names, L, L / np.outer(d, d))
