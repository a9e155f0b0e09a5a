"""Circuit parameters of the current-based model derived analytically (paper Sec. IV-B).

``R_el`` is the circuit resistance.  The eddy-current resistance ``R_ec`` follows from the
detailed flux-based DAE (``models/flux.py``)::

    y' = K^+ h,   0 = alg(y, z, U) = [D x - y;  Q h],   h = [-r(x, s, I);  U - R I]

with differential states ``y`` (flux linkages, eddy-branch fluxes), algebraic states
``z = (x, I)`` (loop fluxes, currents) and ``r = C (V_m(C^T x, s) - N I)``.  The differential
states cannot jump, so a voltage step ``dU`` changes the currents instantly by
``dI = Y dU`` with (implicit function theorem on ``alg = 0`` at fixed ``y``)::

    dz/dU = -(d alg/dz)^-1 d alg/dU,     Y = dI/dU (the current rows)
    d alg/dz = [[D, 0], [Q [-dr/dx, -dr/dI; 0, -diag(R)]]],   d alg/dU = [0; Q [0; 1]]

In the equivalent circuit of the paper's Fig. 8 (``R_el`` in series with ``L || R_ec``)
the inductor current cannot jump either, so the jump is ``dU / (R_el + R_ec)`` and::

    R_ec,j = 1 / Y_jj - R_el,j        (inf if Y_jj = 0: no eddy currents)

For one coil of ``n`` turns on one loop with one eddy element of conductance ``G`` this
is ``n^2 / G`` exactly (docs/sources.md sec. 5).  ``Y`` depends on the operating point through
the iron's differential reluctances (saturation moves flux between main and leakage
paths, which changes how much of the eddy conductance the coil sees).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..circuit.assembly import assemble
from ..circuit.network import Network
from ..errors import InputError, SolverError
from ..models.flux import DEFAULT_ATOL, DEFAULT_RTOL, flux_dae
from ..models.statics import as_network, solve_statics
from ..validation import renamed_keywords

__all__ = ["current_jump_admittance", "eddy_resistance"]

JUMP_ADMITTANCE_ZERO = 1e-12
"""``|Y_jj| <= JUMP_ADMITTANCE_ZERO / R_el`` counts as no current jump (``R_ec = inf``)."""


def _jacobians(net: Network) -> ca.Function:
    """``(x, s, I) -> (dr/dx, dr/dI)`` of the static loop law (cached on the network)."""
    f = net.cache.get("reduction_jacobians")
    if f is None:
        eq = assemble(net)
        f = ca.Function("r_jac", [eq.x, eq.s, eq.I],
                        [ca.jacobian(eq.residual, eq.x), ca.jacobian(eq.residual, eq.I)])
        net.cache["reduction_jacobians"] = f
    return f  # type: ignore[no-any-return]


def _structure(net: Network) -> Any:
    # The flux model's DAE matrices D, Q (same setup as FluxModel's defaults, so cached).
    return flux_dae(net, "idas", DEFAULT_RTOL, DEFAULT_ATOL, 20000, 2, 3)


@renamed_keywords(gap="gap_m", current="current_A")
def current_jump_admittance(model: Any, *, gap_m: Any, current_A: Any) -> np.ndarray:
    """``Y = dI/dU`` [S] at fixed flux linkages and eddy fluxes (instantaneous current jump).

    Old keyword names (``gap``, ``current``) are deprecated aliases for one release.

    Parameters
    ----------
    model : Magnet, Network or FluxModel
        The detailed model (with eddy-current elements for a non-zero result).
    gap_m : float, sequence or mapping
        Gap(s) [m] of one operating point (scalar: all gaps equal).
    current_A : float, sequence or mapping
        Circuit current(s) [A] of the operating point (scalar: every circuit).

    Returns
    -------
    ndarray (n_circuits, n_circuits)
        ``Y[i, j] = dI_i / dU_j`` at the static operating point (at rest); zeros without
        eddy-current elements.

    Raises
    ------
    InputError
        Bad inputs, or more than one operating point.
    SolverError
        If the statics cannot be solved.
    """
    net = as_network(model)
    sol = solve_statics(net, gaps_m=gap_m, currents_A=current_A)
    if sol.shape != ():
        raise InputError("current_jump_admittance takes one operating point (scalar or one "
                         "value per gap / circuit)")
    d = _structure(net)
    if d.n_eddy == 0:
        return np.zeros((d.n_circuits, d.n_circuits))
    drdx, drdi = (np.asarray(a) for a in _jacobians(net)(sol.loop_flux_Wb, sol.gaps_m,
                                                           sol.currents_A))
    nl, nc = d.n_loops, d.n_circuits
    dh_dz = np.block([[-drdx, -drdi], [np.zeros((nc, nl)), -np.diag(net.resistances)]])
    jz = np.vstack((np.hstack((d.D, np.zeros((d.D.shape[0], nc)))), d.Q @ dh_dz))
    ju = np.vstack((np.zeros((d.D.shape[0], nc)), d.Q @ np.vstack((np.zeros((nl, nc)),
                                                                    np.eye(nc)))))
    dz_du = -np.linalg.solve(jz, ju)
    return np.asarray(dz_du[nl:, :])


@renamed_keywords(gap="gap_m", current="current_A")
def eddy_resistance(model: Any, *, gap_m: Any, current_A: Any) -> np.ndarray:
    """Eddy-current resistance ``R_ec`` [ohm] per circuit at one operating point.

    ``R_ec,j = 1 / Y_jj - R_el,j`` with ``Y`` from :func:`current_jump_admittance`: the
    resistance that, in series with ``R_el`` (paper Fig. 8), gives the detailed model's
    instantaneous current jump under a voltage step of circuit ``j`` (other voltages
    held).  ``inf`` where the circuit sees no eddy currents (``Y_jj = 0``).

    Old keyword names (``gap``, ``current``) are deprecated aliases for one release.

    Parameters
    ----------
    model : Magnet, Network or FluxModel
        The detailed model (with eddy-current elements for a finite result).
    gap_m : float, sequence or mapping
        Gap(s) [m] of one operating point, > 0 (scalar: all gaps equal; keyword only).
    current_A : float, sequence or mapping
        Circuit current(s) [A] of the operating point (scalar: every circuit; keyword
        only).

    Returns
    -------
    ndarray (n_circuits,)
        ``R_ec`` [ohm] per circuit (``inf`` without eddy currents).

    Raises
    ------
    InputError
        Bad inputs, more than one operating point, or a non-positive or non-finite
        ``Y_jj`` (a network that is not passive).
    SolverError
        If the statics cannot be solved, or ``Y_jj > 1 / R_el`` (a negative ``R_ec``).
    """
    net = as_network(model)
    y = current_jump_admittance(net, gap_m=gap_m, current_A=current_A)
    out = np.empty(y.shape[0])
    for j in range(y.shape[0]):
        yjj = float(y[j, j])
        # a coil whose every flux path is shielded by eddy elements (an eddy ladder) cannot
        # jump: Y_jj is then zero up to the solve's rounding (measured +-1e-33 .. 1e-20 S on
        # the guidance ladder, against 1/R_el ~ 0.7 S); |Y_jj| below 1e-12 of 1/R_el (the
        # largest admittance a passive circuit can show) is that zero, not a sign of a
        # non-passive network
        if abs(yjj) <= JUMP_ADMITTANCE_ZERO * (1.0 / float(net.resistances[j])):
            out[j] = math.inf
        elif yjj < 0.0 or not math.isfinite(yjj):
            raise InputError(f"circuit {net.circuit_names[j]!r}: current-jump admittance "
                             f"{yjj!r} S is not a positive number; the network is not passive")
        else:
            r_el = float(net.resistances[j])
            out[j] = 1.0 / yjj - r_el
            if out[j] < 0.0:
                # Y_jj > 1/R_el: a current jump larger than the coil resistance alone allows
                raise SolverError(
                    f"eddy_resistance: negative R_ec = {out[j]:.6g} ohm for circuit "
                    f"{net.circuit_names[j]!r}",
                    state={"gap_m": gap_m, "current_A": current_A},
                    reason=f"current-jump admittance Y_jj = {yjj:.9g} S exceeds 1/R_el = "
                           f"{1.0 / r_el:.9g} S (R_el = {r_el:g} ohm); R_ec must be >= 0 "
                           "for a passive network (rounding or a non-passive model)")
    return out
