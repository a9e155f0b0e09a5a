"""Symbolic assembly of a :class:`~maglevkit.circuit.network.Network` into CasADi expressions.

Unknowns are the loop fluxes ``x`` (one per fundamental loop); branch fluxes are
``phi = C^T x``.  For gaps ``s`` and circuit currents ``I``:

* static loop law (Kirchhoff II with Ampere's law, paper eqs. 1-2)::

      r(x, s, I) = C (V_m(phi, s) - N I) = 0

* flux linkages ``psi = N^T phi`` (Faraday, paper eq. 3: ``U_ind = dpsi/dt``)
* gap energy ``W_gap(phi, s) = sum phi_e^2 / (2 G_e(s))`` over the gap-dependent
  (linear) elements, and the pole forces ``F_k = dW_gap/ds_k`` at constant flux,
  which equals ``-dW'/ds_k`` at constant currents (co-energy ``W'``) for any iron law
  because the iron parts do not depend on the gaps.  ``F > 0`` is attraction.

The Jacobian ``dr/dx = C diag(dV_m/dphi) C^T`` is symmetric positive definite for
monotone materials, so the static problem has a unique solution.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import TopologyError
from .elements import LinearElement
from .network import Network

__all__ = ["NetworkEquations", "assemble"]


@dataclass(frozen=True)
class NetworkEquations:
    """CasADi symbols, expressions and functions of one network.

    Attributes
    ----------
    network : Network
        The network the equations belong to.
    C : ndarray (n_loops, n_branches)
        Fundamental loop matrix (:attr:`Network.loop_matrix`).
    N : ndarray (n_branches, n_circuits)
        Signed turns matrix (:attr:`Network.turns_matrix`).
    x, s, I : casadi.SX
        Loop fluxes [Wb], gaps [m], circuit currents [A].
    phi : casadi.SX
        Branch fluxes ``C^T x`` [Wb].
    mmf_drop : casadi.SX
        Static branch drops ``V_m(phi, s)`` [A].
    residual : casadi.SX
        ``C (V_m - N I)`` [A].
    psi : casadi.SX
        Circuit flux linkages ``N^T phi`` [Wb].
    force : casadi.SX
        Pole forces, one per gap input [N] (attraction positive).
    gap_energy : casadi.SX
        Energy stored in the gap-dependent elements [J].
    """

    network: Network
    C: np.ndarray
    N: np.ndarray
    x: ca.SX
    s: ca.SX
    I: ca.SX
    phi: ca.SX
    mmf_drop: ca.SX
    residual: ca.SX
    psi: ca.SX
    force: ca.SX
    gap_energy: ca.SX

    @property
    def n_loops(self) -> int:
        return int(self.C.shape[0])

    @property
    def n_gaps(self) -> int:
        return int(self.s.numel())

    @property
    def n_circuits(self) -> int:
        return int(self.I.numel())


def assemble(network: Network) -> NetworkEquations:
    """Assemble (and cache on the network) the symbolic equations of ``network``.

    Parameters
    ----------
    network : Network
        The equivalent magnetic circuit.  The result is stored in ``network.cache`` under
        ``"equations"``: a second call on the same network returns the same object.

    Returns
    -------
    NetworkEquations

    Raises
    ------
    TopologyError
        The network has no air gap, or a gap-dependent element is not linear (its
        permeance must not depend on the flux).
    """
    cached = network.cache.get("equations")
    if cached is not None:
        return cached  # type: ignore[no-any-return]
    C = network.loop_matrix
    N = network.turns_matrix
    gaps = network.gap_names
    if not gaps:
        raise TopologyError(f"network {network.name!r} has no air gap; a magnet model needs at "
                            "least one gap-dependent element")
    x = ca.SX.sym("x", C.shape[0])
    s = ca.SX.sym("s", len(gaps))
    I = ca.SX.sym("I", N.shape[1])
    gap_index = {g: i for i, g in enumerate(gaps)}

    phi_b = ca.SX.sym("phi", len(network.branches))
    drops = []
    w_gap = ca.SX(0)
    for k, br in enumerate(network.branches):
        v = ca.SX(0)
        for el in br.elements:
            sk = s[gap_index[el.gap]] if el.gap is not None else None
            v = v + el.mmf_drop(phi_b[k], sk)
            if el.gap is not None:
                if not isinstance(el, LinearElement):
                    raise TopologyError(f"element {el.name!r} depends on a gap but is not linear; "
                                        "gap-dependent elements must have a flux-independent permeance")
                w_gap = w_gap + el.energy(phi_b[k], sk)
        drops.append(v)
    drop_b = ca.vertcat(*drops)
    force_b = ca.gradient(w_gap, s)

    phi = ca.mtimes(ca.DM(C.T), x)
    mmf = ca.substitute(drop_b, phi_b, phi)
    residual = ca.mtimes(ca.DM(C), mmf - ca.mtimes(ca.DM(N), I))
    psi = ca.mtimes(ca.DM(N.T), phi)
    force = ca.substitute(force_b, phi_b, phi)
    energy = ca.substitute(w_gap, phi_b, phi)
    eq = NetworkEquations(network, C, N, x, s, I, phi, mmf, residual, psi, force, energy)
    network.cache["equations"] = eq
    return eq
