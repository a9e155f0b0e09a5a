"""Detailed flux-based dynamic model (paper Sec. II, eqs. 4-7) with eddy currents.

Unknowns are the loop fluxes ``x`` (branch fluxes ``phi = C^T x``) and the circuit
currents ``I``.  With the eddy conductances ``G_d = diag(G_ec)`` per branch::

    Kirchhoff II:  C G_d C^T x' = -C (V_m(C^T x, s) - N I)
    Faraday:       N^T C^T x'   = U - R I                    (psi = N^T C^T x)

i.e. ``M x' = h(x, I, s, U)`` with the singular ``M = [C G_d C^T; N^T C^T]`` (paper
eq. 4).  The model reduces it to a semi-explicit index-1 DAE (paper eq. 5): the rows of
``D`` are a maximal independent subset of the rows of ``[N^T C^T; E C^T]`` (``E`` picks
the eddy branches; flux-linkage rows first), so the differential states ``y = D x`` are
circuit flux linkages and eddy-branch fluxes.  ``M = K D`` with ``K = M D^+`` of full
column rank, hence::

    y' = K^+ h                  (differential: flux linkages, eddy-branch fluxes)
    0  = D x - y                (algebraic: loop fluxes x)
    0  = Q h                    (algebraic: currents, Q = left null space of K)
    s' = gap rate               (gaps as states: exactly piecewise linear)

Outputs: currents (eq. 7), pole forces from the network's gap energy at constant flux
(the exact co-energy force, which reduces to eq. 6 for a plain pole), flux linkages,
``eta`` = sum of the coil-core fluxes per circuit (eq. 5 coordinates), all branch fluxes,
eddy-branch fluxes and eddy MMFs ``G_ec phi'``.  Energy bookkeeping is integrated as
quadratures: ``E_in = int U.I``, ``E_ohm = int R I^2``, ``E_eddy = int sum G_ec phi'^2``,
``E_mech = int -F.s'``; ``E_in = E_ohm + E_eddy + Delta W + E_mech`` holds exactly.

Time is normalised per hold interval (``tau = k + (t - t_k) / h_k``, the interval length
an input), so one integrator serves every step size.  IDAS integrates a sparse form of the
DAE (the balance ``h`` as an algebraic unknown, the gaps explicit) and, in ``simulate``,
runs through hold intervals of equal voltages without a restart; its residual, Jacobian,
quadrature and output functions are compiled to C and cached on disk by default
(``compiled="auto"``).  See ``docs/flux_model.md``.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import threading
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from .._interrupt import check_interrupt
from ..circuit.assembly import assemble
from ..circuit.network import Network
from ..errors import CompilationWarning, InputError, SolverError, TopologyError
from ..magnets.base import PlausibleRange
from ..materials import MU0
from ..validation import flag, optional_flag, real_array, real_number, renamed_keywords, whole_number
from .compiled import COMPILE_MODES, compile_library
from .flux_live import LiveIntegrator, live_library
from .inputs import check_step, gap_secants, per_name_values, sample_input, time_grid
from .statics import (
    as_network,
    current_vector,
    gap_vector,
    magnetic_energy,
    plausible_range,
    solve_statics,
)

if TYPE_CHECKING:   # scipy is imported where it is used (~0.2 s of every import otherwise)
    import scipy.sparse as sp

__all__ = [
    "DEFAULT_RTOL",
    "DEFAULT_ATOL",
    "FluxModel",
    "FluxState",
    "FluxOutputs",
    "SimulationResult",
    "EnergyBalance",
    "FluxDAE",
    "flux_dae",
    "simulate_flux",
]

#: Default relative tolerance of the integrator (IDAS ``reltol``).
DEFAULT_RTOL = 1e-6
#: Default absolute tolerance, relative to each variable's nominal scale (see FluxModel).
DEFAULT_ATOL = 1e-8

_B_REF = 1.0        # T, nominal flux density for the tolerance scales
_GAP_REF = 5e-3     # m, nominal air gap for the current scale
_ENERGY_NAMES = ("electrical", "ohmic", "eddy", "mechanical")
#: Compiler flags of the flux model's library (docs/decisions.md "Flux model speed":
#: -O1 compiles in a fraction of the -O3 time and runs about as fast).
COMPILE_FLAGS = ("-O1", "-shared", "-fPIC")


def _power_flows(U: Any, I: Any, R: Any, g_e: Any, phidot_e: Any, force: Any, rate: Any) -> Any:
    """The energy balance's power flows [W] (integrated as quadratures): electric input
    ``U.I``, ohmic loss ``R I.I``, eddy loss ``sum G phi_e'^2`` and mechanical power
    ``-F.s'``."""
    return ca.vertcat(ca.dot(U, I), ca.dot(R * I, I), ca.dot(g_e * phidot_e, phidot_e),
                      -ca.dot(force, rate))


#: Networks with more loop and circuit unknowns than this run IDAS on the sparse form
#: (``K y' = h``, :meth:`FluxDAE._init_idas`); smaller ones on the dense form (``K^+``,
#: ``Q``), whose results and compiled libraries stay those of earlier versions.  Counted:
#: the bundled networks of 9-36 unknowns (U-magnet 18; guidance 33 on its split network
#: since guide26, 19 before; TR09 "paper" 36) and the U-magnet's ladder n = 2 (32) stay
#: dense; the ladders from n = 3 (U-magnet 46, guidance n = 4: 67, n = 6: 99, counted
#: before guide26), the grids and TR09's split networks (233) are sparse.  The
#: dense ``K^+`` and ``Q`` make the dense form's Jacobian a dense block.  Measured
#: (benchmarks/form_size_survey.py, compiled, 1 s at 1 kHz, docs/decisions.md design25):
#: the sparse form is faster at every size, by 1.2-1.7x up to 36 unknowns, 3.5x at 46, 7x
#: at 67 and 12x at 99 (whose dense form also compiled in 48 s instead of 2.5 s); the
#: bound sits between 36 and 46 so that the bundled magnets' default networks keep their
#: results and libraries (was 100: the guidance ladder n = 6, 99 unknowns, ran dense).
SPARSE_FORM_SIZE = 40

#: ``compiled="auto"`` compiles networks up to this many loop and circuit unknowns; larger
#: ones run on CasADi's virtual machine (``compiled="always"`` still compiles them).  What
#: the C compiler takes depends on the generated code, i.e. on the form and the loop basis
#: (:data:`SPARSE_FORM_SIZE`, :attr:`~maglevkit.circuit.network.Network.loop_matrix`):
#: measured with ``gcc -O1`` (docs/decisions.md, splitfast) the sparse form with short loops
#: compiles the U-magnet's ladder n = 8 (116 unknowns) in 8.6 s, the grid with Roters
#: tubes (111) in 12.5 s, the TR09 split network (255; bow 256) in 11 s, while the grid's
#: ladder n = 4 (507) still takes minutes.  So the bound is 300, between them (was 200:
#: the split network's dense form in the fundamental loops did not compile in 600 s).
AUTO_COMPILE_SIZE = 300


def _dm(a: Any, form: str) -> ca.DM:
    """A CasADi matrix of ``a``: sparse (structural zeros dropped) in the sparse form, dense
    (every entry, as earlier versions) in the dense form."""
    import scipy.sparse as sp

    if form == "dense":
        return ca.DM(np.asarray(a))
    return ca.DM(sp.csc_matrix(a))


def _independent_rows(A: np.ndarray, tol: float = 1e-9) -> list[int]:
    """Indices of the rows of ``A`` that are not in the span of the rows before them
    (greedy, in order), each row scaled to a largest entry of 1.

    Incremental Gram-Schmidt (twice, for orthogonality to rounding) instead of a rank
    (an SVD) per candidate row, which took minutes for the 1800 x 530 rows of the
    air-cell grid with the eddy ladder.  A row counts as independent when the part of it
    outside the span has a norm above ``tol`` (the scaled rows have norm >= 1; rows of
    loop and turns matrices are either in the span to rounding or clearly out of it).
    """
    basis = np.zeros((0, A.shape[1]))
    out: list[int] = []
    for k, row in enumerate(A):
        scale = float(np.abs(row).max())
        if scale == 0.0:
            continue
        v = row / scale
        for _ in range(2):
            v = v - basis.T @ (basis @ v)
        nv = float(np.linalg.norm(v))
        if nv > tol:
            basis = np.vstack((basis, v / nv))
            out.append(k)
    return out


def _sparse_condition(J: sp.spmatrix) -> tuple[bool, float]:
    """``(singular, condition estimate)`` of a square sparse matrix: a sparse LU (singular
    if it fails or a pivot is below 1e-12 of the largest) and the 1-norm condition
    estimate ``||J||_1 ||J^-1||_1`` (Hager-Higham)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    Jc = sp.csc_matrix(J)
    if Jc.shape[0] == 0:
        return False, 1.0
    try:
        lu = spla.splu(Jc)
    except RuntimeError:
        return True, math.inf
    piv = np.abs(lu.U.diagonal())
    if piv.min() < 1e-12 * piv.max():
        return True, math.inf
    n = Jc.shape[0]
    inv = spla.LinearOperator((n, n), matvec=lu.solve, rmatvec=lambda b: lu.solve(b, "T"),
                              dtype=float)
    return False, float(spla.norm(Jc, 1) * spla.onenormest(inv))


# ---------------------------------------------------------------------------- state / outputs
@dataclass(frozen=True)
class FluxState:
    """State of the flux model at one instant (returned by ``initial_state`` / ``step``).

    Attributes
    ----------
    time_s : float
        Time [s].
    differential_state : ndarray (n_diff,)
        ``y = D x``: circuit flux linkages [Wb] then eddy-branch fluxes [Wb].
    gaps_m : ndarray (n_gaps,)
        Gaps [m].
    loop_flux_Wb : ndarray (n_loops,)
        Loop fluxes [Wb] (algebraic; consistent with the inputs below).
    currents_A : ndarray (n_circuits,)
        Circuit currents [A] (algebraic).
    voltages_V, gap_rates_m_per_s : ndarray
        The inputs the algebraic part is consistent with (those of the last interval).
    energy_J : ndarray (4,)
        Cumulative electrical input, ohmic loss, eddy loss and mechanical work [J].
    """

    time_s: float
    differential_state: np.ndarray
    gaps_m: np.ndarray
    loop_flux_Wb: np.ndarray
    currents_A: np.ndarray
    voltages_V: np.ndarray
    gap_rates_m_per_s: np.ndarray
    energy_J: np.ndarray

    def _vector(self) -> np.ndarray:
        return np.concatenate((self.differential_state, self.gaps_m, self.loop_flux_Wb,
                               self.currents_A))


@dataclass(frozen=True)
class FluxOutputs:
    """Outputs of the flux model at one instant (left limit before an input change).

    Attributes
    ----------
    time_s : float
        Time [s].
    currents_A, flux_linkage_Wb, eta_Wb : ndarray (n_circuits,)
        Circuit currents [A], flux linkages [Wb], sums of coil-core fluxes [Wb].
    pole_force_N : ndarray (n_gaps,)
        Force per gap input [N], attraction positive.
    force_N : float
        Total force [N].
    branch_flux_Wb : ndarray (n_branches,)
        All branch fluxes [Wb].
    eddy_flux_Wb, eddy_mmf_A : ndarray (n_eddy,)
        Fluxes [Wb] and eddy-current MMFs ``G_ec dphi/dt`` [A] of the eddy branches.
    """

    time_s: float
    currents_A: np.ndarray
    flux_linkage_Wb: np.ndarray
    eta_Wb: np.ndarray
    pole_force_N: np.ndarray
    force_N: float
    branch_flux_Wb: np.ndarray
    eddy_flux_Wb: np.ndarray
    eddy_mmf_A: np.ndarray


@dataclass(frozen=True)
class EnergyBalance:
    """Energy bookkeeping of a simulation [J].

    ``electrical = ohmic + eddy + magnetic_change + mechanical + residual``.

    Attributes
    ----------
    electrical_J : float
        Electrical energy fed into the circuits, the integral of ``U I`` [J].
    ohmic_J : float
        Ohmic loss in the windings, the integral of ``R I^2`` [J].
    eddy_J : float
        Eddy-current loss in the eddy branches [J] (0 without eddy currents).
    magnetic_change_J : float
        Change of the stored magnetic energy (air gaps and iron) [J].
    mechanical_J : float
        Mechanical work done by the magnet's force on the moving gaps [J].
    residual_J : float
        What the other terms leave unexplained [J]: the integration error of the
        balance (small against the largest term, see :attr:`relative_residual`).
    """

    electrical_J: float
    ohmic_J: float
    eddy_J: float
    magnetic_change_J: float
    mechanical_J: float
    residual_J: float

    @property
    def relative_residual(self) -> float:
        """``|residual|`` over the largest term."""
        scale = max(abs(self.electrical_J), abs(self.ohmic_J), abs(self.eddy_J),
                    abs(self.magnetic_change_J), abs(self.mechanical_J), 1e-300)
        return abs(self.residual_J) / scale


# ---------------------------------------------------------------------------- DAE structure
class FluxDAE:
    """Matrices, symbolic DAE and compiled step functions of one network and solver setup.

    Built through :func:`flux_dae` (once per network and setup); the reduction
    (:mod:`maglevkit.reduction`) reads its matrices ``D``, ``K``, ``T``, ``Q`` and functions,
    and ``Kp`` = ``K^+`` (computed once here: an SVD of ~1.5 s on a ladder network's
    528 x 356 ``K``, which the reduction's step and frequency identifications reuse).

    ``form``: ``"dense"`` (IDAS on ``y' = K^+ v``, ``Q v = 0``, ``v = h``: dense ``K^+`` and
    ``Q``) or ``"sparse"`` (IDAS on ``K y' = h`` with a sparse ``K``, for large networks;
    both in :meth:`_init_idas`; ``method="radau"`` is always dense); ``"auto"`` takes the
    sparse form for IDAS on networks with more than :data:`SPARSE_FORM_SIZE` loop and
    circuit unknowns.
    """

    def __init__(self, network: Network, method: str, rtol: float, atol: float,
                 max_num_steps: int, radau_elements: int, radau_degree: int,
                 compiled: str = "never", cache_dir: str | None = None,
                 form: str = "auto") -> None:
        import scipy.linalg as sla
        import scipy.sparse as sp

        eq = assemble(network)
        self.network = network
        C, N = eq.C, eq.N
        G = network.eddy_conductances
        self.eddy_idx = np.nonzero(G > 0.0)[0]
        if form == "auto":
            form = ("sparse" if method == "idas" and C.shape[0] + N.shape[1] > SPARSE_FORM_SIZE
                    else "dense")
        if form not in ("dense", "sparse") or (form == "sparse" and method != "idas"):
            raise InputError(f"internal: flux-model form {form!r} with method {method!r}")
        self.form = form
        a_psi = N.T @ C.T
        a_eddy = C.T[self.eddy_idx]
        A = np.vstack((a_psi, a_eddy))
        names = [f"psi[{c}]" for c in network.circuit_names]
        names += [f"phi[{network.branch_names[b]}]" for b in self.eddy_idx]
        sel = _independent_rows(A)
        self.diff_names: list[str] = [names[k] for k in sel]
        D = A[sel].reshape(len(sel), C.shape[0])
        g_e = G[self.eddy_idx]
        Dp = np.linalg.pinv(D)
        if form == "dense":
            M = np.vstack((C @ np.diag(G) @ C.T, a_psi))
            K = M @ Dp
            T = a_eddy @ Dp                   # eddy-branch flux rates = T y'
        else:
            # A = S D (S: which combination of the states each candidate row is), so
            # K = M D^+ = [a_eddy^T G_e S_e; S_psi] and T = a_eddy D^+ = S_e, both sparse.
            # S's entries are those of node and loop laws (0, +-1, turns ratios): rounding
            # below 1e-12 of the largest is dropped and the product checked below.
            Cs = sp.csr_matrix(C)
            M = np.vstack(((Cs.multiply(G[None, :]) @ Cs.T).toarray(), a_psi))
            S = A @ Dp
            S[np.abs(S) < 1e-12 * max(1.0, float(np.abs(S).max()))] = 0.0
            S[sel] = np.eye(len(sel))
            nc_ = N.shape[1]
            self.K_sparse = sp.vstack((sp.csr_matrix(a_eddy.T * g_e[None, :]) @ sp.csr_matrix(
                S[nc_:]), sp.csr_matrix(S[:nc_]))).tocsc()
            K = self.K_sparse.toarray()
            T = S[nc_:]
        if not np.allclose(K @ D, M, rtol=0.0, atol=1e-9 * max(1.0, np.abs(M).max())):
            raise TopologyError("internal: the flux-model reduction M = K D failed")
        Kp = np.linalg.pinv(K)
        self.D, self.M, self.K, self.T = D, M, K, T
        self.Kp = Kp
        self._Q: np.ndarray | None = sla.null_space(K.T).T if form == "dense" else None
        nl, nc, ng, r = C.shape[0], N.shape[1], eq.n_gaps, D.shape[0]
        self.n_loops, self.n_circuits, self.n_gaps, self.n_diff = nl, nc, ng, r
        self.n_eddy = len(self.eddy_idx)
        self.n_branches = len(network.branches)
        self.nw = r + ng + nl + nc
        R = network.resistances

        y = ca.SX.sym("y", r)
        h = ca.SX.sym("h")
        U = ca.SX.sym("U", nc)
        rate = ca.SX.sym("rate", ng)
        x, s, I = eq.x, eq.s, eq.I
        hv = ca.vertcat(-eq.residual, U - R * I)
        ydot = ca.mtimes(ca.DM(Kp), hv)
        phidot_e = ca.mtimes(_dm(T, form), ydot)
        power = _power_flows(U, I, R, g_e, phidot_e, eq.force, rate)
        # eta (eq. 5): pole fluxes summed per circuit (coil-core fluxes; a pole winding
        # split over several branches counts with its turn-weighted mean flux)
        eta = ca.mtimes(ca.DM(network.pole_flux_matrix.T), eq.phi)
        out = ca.vertcat(eq.phi, eq.psi, eta, eq.force, g_e * phidot_e)
        self.n_out = int(out.numel())
        self.output_fun = ca.Function("flux_outputs", [ca.vertcat(y, s, x, I), U, rate], [out])

        if form == "dense":
            alg = ca.vertcat(ca.mtimes(ca.DM(D), x) - y, ca.mtimes(ca.DM(self.Q), hv))
            # Index-1 check: d(alg)/d(x, I) must be regular (at zero flux and a 5 mm gap).
            jac = ca.Function("jz", [x, I, s], [ca.jacobian(alg, ca.vertcat(x, I))])
            Jz = np.array(jac(np.zeros(nl), np.zeros(nc), np.full(ng, _GAP_REF)))
            sv = np.linalg.svd(Jz / np.maximum(np.abs(Jz).max(axis=1, keepdims=True), 1e-300),
                               compute_uv=False)
            singular = bool(sv.size and sv[-1] < 1e-12 * sv[0])
            self.index1_condition = float(sv[0] / sv[-1]) if sv.size and not singular else 1.0
        else:
            # the same check on the sparse form's Jacobian d(alg)/d(x, I, y') (regular
            # exactly when the dense form's is): a sparse LU and a 1-norm estimate of the
            # condition instead of an SVD of a matrix of several thousand rows
            yd = ca.SX.sym("yd", r)
            alg = ca.vertcat(ca.mtimes(_dm(D, form), x) - y,
                             ca.mtimes(_dm(self.K_sparse, form), yd) - hv)
            z = ca.vertcat(x, I, yd)
            jac = ca.Function("jz", [z, s, y, U], [ca.jacobian(alg, z)])
            Jz = jac(np.zeros(z.numel()), np.full(ng, _GAP_REF), np.zeros(r),
                     np.zeros(nc)).sparse().tocsr()
            row_max = np.maximum(abs(Jz).max(axis=1).toarray().ravel(), 1e-300)
            singular, self.index1_condition = _sparse_condition(
                sp.diags(1.0 / row_max) @ Jz)
        if singular:
            raise TopologyError(f"network {network.name!r}: the flux-model DAE is not index 1 "
                                "(d alg / d(x, I) is singular); check the circuit topology")

        # Nominal scales for the absolute tolerances.
        areas = network.branch_areas
        finite = areas[np.isfinite(areas)]
        phi_nom = _B_REF * (float(np.median(finite)) if finite.size else 1e-3)
        turns = np.maximum(np.abs(N).sum(axis=0), 1.0)
        i_nom = _B_REF * _GAP_REF / MU0 / turns
        nominal = np.concatenate((np.abs(D).sum(axis=1) * phi_nom, np.full(ng, 1e-2),
                                  np.full(nl, phi_nom), i_nom))
        self.nominal = nominal
        wm = ca.MX.sym("w", self.nw)
        pm = ca.MX.sym("p", 1 + nc + ng)
        nx = r + ng
        #: Whether the residual, Jacobian and output functions run as compiled C.
        self.compiled = False
        self._live_parts: tuple[Any, ...] | None = None
        self._live_lib: Any = False                  # False: not built yet; None: unavailable
        self._chunks: dict[int, ca.Function] = {}
        if method == "idas":
            self._init_idas(eq, Kp, hv, y, h, U, rate, g_e, nominal, rtol, atol, max_num_steps,
                            compiled, cache_dir)
        elif method == "radau":
            dae = {"x": ca.vertcat(y, s), "z": ca.vertcat(x, I), "p": ca.vertcat(h, U, rate),
                   "ode": h * ca.vertcat(ydot, rate), "alg": alg, "quad": h * power}
            integ = ca.integrator("flux_radau", "collocation", dae, 0.0, 1.0,
                                  {"number_of_finite_elements": radau_elements,
                                   "interpolation_order": radau_degree,
                                   # KINSOL (SUNDIALS Newton with line search): plain
                                   # Newton failed mid-run on stiff networks (12 eddy
                                   # states of the U-magnet at 1 ms steps)
                                   "collocation_scheme": "radau", "rootfinder": "kinsol",
                                   "rootfinder_options": {"error_on_fail": True}})
            res = integ(x0=wm[:nx], z0=wm[nx:], p=pm)
            wf = ca.vertcat(res["xf"], res["zf"])
            o = self.output_fun(wf, pm[1:1 + nc], pm[1 + nc:])
            self.step_fun = ca.Function("flux_step", [wm, pm], [wf, res["qf"], o])
        else:
            raise InputError(f"method = {method!r}; use 'idas' (error-controlled BDF) or "
                             "'radau' (fixed-step Radau IIA collocation)")
        self._accum: dict[int, ca.Function] = {}

    @property
    def Q(self) -> np.ndarray:
        """Left null space of ``K`` (rows): the balance combinations ``Q h = 0`` that fix
        the currents (dense; computed on first use in the sparse form)."""
        import scipy.linalg as sla

        if self._Q is None:
            self._Q = sla.null_space(self.K.T).T
        return self._Q

    def _init_idas(self, eq: Any, Kp: np.ndarray, hv: ca.SX, y: ca.SX, h: ca.SX, U: ca.SX,
                   rate: ca.SX, g_e: np.ndarray, nominal: np.ndarray, rtol: float, atol: float,
                   max_num_steps: int, compiled: str, cache_dir: str | None) -> None:
        """The IDAS form: sparse balance unknowns, explicit gaps, optionally compiled.

        * The balance vector ``v = h(x, I, s, U)`` is an algebraic unknown, so the dense
          ``K^+`` and ``Q`` multiply ``v`` linearly (constant Jacobian blocks) instead of
          entering every nonlinear Jacobian entry (TR09: IDAS's Jacobian function 73672 ->
          14377 SX instructions).  Eliminating ``v`` gives back the system of the class
          docstring, so it is index 1 exactly when that is.  ``v`` is fixed by ``y'``;
          its error weight is small (see ``v_scale``).
        * The gaps are explicit, ``s = s_k + h_k rate_k (tau - k)`` on interval ``k``
          (the hold inputs of each interval are IDAS controls ``u``), so one IDAS run
          crosses many hold intervals without a restart: a kink of the gap path is no
          jump of any unknown.  A run restarts (consistent re-initialisation) where the
          voltages change, since the eddy-current model's currents jump there.
        * The sparse form (``self.form``, large networks) takes ``y'`` itself as the
          algebraic unknown instead of ``v``: ``K y' = h`` with the sparse ``K``, no ``Q``
          and no ``K^+`` in IDAS's Jacobian (docs/flux_model.md).
        """
        D, T = self.D, self.T
        nl, nc, ng, r = self.n_loops, self.n_circuits, self.n_gaps, self.n_diff
        R = self.network.resistances
        x, s, I = eq.x, eq.s, eq.I
        s0 = ca.SX.sym("s0", ng)
        t_sym = ca.SX.sym("t")
        tau0 = ca.SX.sym("tau0")
        s_t = s0 + h * rate * (t_sym - tau0)
        # v's absolute tolerance: 1e3 x atol x its scale (MMF of 1 T over 5 mm of air per
        # loop, R x nominal current per circuit).  Measured on the U-magnet: x1 ran 4x
        # slower; v out of the error test (x1e300) left x and I consistent only to 2e-7
        # (psi = L I of a linear magnet) because IDAS's Newton test ignored v; x1e3:
        # as fast as x1e300, consistent to 5e-9.
        v_scale = 1e3 * atol * np.concatenate((np.full(nl, _B_REF * _GAP_REF / MU0),
                                                R * nominal[-nc:]))
        if self.form == "dense":
            v = ca.SX.sym("v", nl + nc)
            ydot_v = ca.mtimes(ca.DM(Kp), v)
            phidot_v = ca.mtimes(ca.DM(T), ydot_v)
            alg = ca.vertcat(ca.mtimes(ca.DM(D), x) - y, ca.mtimes(ca.DM(self.Q), v), v - hv)
            extra, extra_scale = v, v_scale
            balance_fun = ca.Function("flux_balance", [ca.vertcat(x, I), s, U], [hv])
        else:
            # K y' = h with y' an algebraic unknown: the sparse K (a few entries per row)
            # instead of the dense K^+ and Q (a Jacobian block of (n_loops + n_circuits)^2
            # entries, 2e6 on the air-cell grid).  Eliminating y' gives back y' = K^+ h,
            # Q h = 0 (K has full column rank).  y''s tolerance: that of the y' a v of
            # v's tolerance gives, |K^+| v_scale.
            ydot_v = ca.SX.sym("yd", r)
            phidot_v = ca.mtimes(_dm(T, "sparse"), ydot_v)
            alg = ca.vertcat(ca.mtimes(_dm(D, "sparse"), x) - y,
                             ca.mtimes(_dm(self.K_sparse, "sparse"), ydot_v) - hv)
            extra, extra_scale = ydot_v, np.abs(Kp) @ v_scale
            balance_fun = ca.Function("flux_balance", [ca.vertcat(x, I), s, U],
                                      [ca.mtimes(ca.DM(Kp), hv)])
        power_v = _power_flows(U, I, R, g_e, phidot_v, eq.force, rate)
        alg, quad = ca.substitute([alg, h * power_v], [s], [s_t])
        self.n_u = 2 + 2 * ng                         # per interval: h, s_k, rate_k, tau_k
        dae_fun = ca.Function(
            "flux_dae", [t_sym, y, ca.vertcat(x, I, extra), U, ca.vertcat(h, s0, rate, tau0)],
            [h * ydot_v, alg, quad, ca.SX(0, 1)],
            ["t", "x", "z", "p", "u"], ["ode", "alg", "quad", "zero"])
        keep = np.r_[0:r, r + ng:r + ng + nl + nc]     # no gap states
        opts: dict[str, Any] = {"reltol": rtol,
                                "abstolv": list(atol * nominal[keep]) + list(extra_scale),
                                "max_num_steps": max_num_steps,
                                "disable_internal_warnings": True}
        oracle: Any = dae_fun
        output_fun = output_sx = self.output_fun
        if compiled != "never":
            # One C file: the DAE, the residual/Jacobian/quadrature functions IDAS asks its
            # DAE for (casadi.external finds them by name in the DAE's library), the
            # balance and the outputs.  Taken from an interpreted integrator, so both paths
            # evaluate the same expressions in the same order.
            vm_integ = ca.integrator("flux_idas", "idas", dae_fun, 0.0, 1.0, opts)
            daeF, jacF, quadF = (vm_integ.get_function(k) for k in ("daeF", "jacF", "quadF"))
            # the library's DAE calls daeF and quadF (their code is generated once)
            args = [ca.MX.sym(dae_fun.name_in(i), dae_fun.sparsity_in(i)) for i in range(5)]
            ode_alg = daeF(*args)
            lib_dae = ca.Function("flux_dae", args, [*ode_alg, quadF(*args), ca.MX(0, 1)],
                                  dae_fun.name_in(), dae_fun.name_out())
            lib = [lib_dae, daeF, jacF, quadF, balance_fun, output_fun]
            loaded, self.compiled = compile_library("maglevkit_flux", lib, mode=compiled,
                                                    cache_dir=cache_dir, flags=COMPILE_FLAGS,
                                                    stacklevel=7)
            if self.compiled:
                oracle, balance_fun, output_fun = loaded[0], loaded[4], loaded[5]
                self.output_fun = output_fun
                force_fun = ca.Function(
                    "flux_force_quad", [t_sym, y, ca.vertcat(x, I, extra), U,
                                        ca.vertcat(h, s0, rate, tau0)],
                    [ca.substitute(h * eq.force, s, s_t)])
                # -O3 (DEFAULT_FLAGS): -O1 saved a quarter of the compile time but
                # the live step ran 1.6x slower (docs/decisions.md)
                self._live_parts = (daeF, jacF, quadF, force_fun, output_sx, cache_dir)
        self._oracle, self._idas_opts, self._balance = oracle, opts, balance_fun
        # one hold interval, (w, p = (h, U, rate)) -> (w, q, outputs) as for radau
        wm = ca.MX.sym("w", self.nw)
        pm = ca.MX.sym("p", 1 + nc + ng)
        P1 = ca.vertcat(pm[0], wm[r:r + ng], pm[1 + nc:], 0.0)
        W, Qi, O = self.chunk(1)(wm, pm[1:1 + nc], P1)
        self.step_fun = ca.Function("flux_step", [wm, pm], [W, Qi, O])

    def live_integrator(self) -> LiveIntegrator | None:
        """A new IDAS integrator kept alive between :meth:`FluxModel.step` calls
        (:mod:`maglevkit.models.flux_live`), or None: interpreted functions,
        ``method="radau"``, or no IDAS library to link against."""
        if self._live_parts is None:
            return None
        try:
            if self._live_lib is False:
                self._live_lib = live_library(*self._live_parts)
            if self._live_lib is None:
                return None
            opts = self._idas_opts
            nz = len(opts["abstolv"]) - self.n_diff        # loop fluxes, currents, balance
            return LiveIntegrator(self._live_lib, self.n_diff, nz, self.n_circuits, self.n_u,
                                  4 + self.n_gaps, self.n_gaps, self.n_loops + self.n_circuits,
                                  self.n_out,
                                  opts["reltol"], np.asarray(opts["abstolv"]),
                                  opts["max_num_steps"])
        except (OSError, RuntimeError, AttributeError, subprocess.SubprocessError) as exc:
            # a library that does not load (a missing symbol), lacks an entry point or
            # cannot set IDAS up: the restarting step works without it
            self._live_lib = None
            warnings.warn(f"the live IDAS step is unavailable ({type(exc).__name__}: "
                          f"{str(exc).strip()[:200]}); FluxModel.step restarts IDAS every call",
                          CompilationWarning, stacklevel=3)
            return None

    def chunk(self, n: int) -> ca.Function:
        """IDAS over ``n`` hold intervals without restart: ``(w0, U, P) -> (W, Q, O)``.

        ``P`` (n_u, n): per interval ``h``, start gaps, gap rates, interval index;
        ``W`` (nw, n) states, ``Q`` (4, n) energy increments, ``O`` (n_out, n) outputs at
        the interval ends.  IDAS only.
        """
        f = self._chunks.get(n)
        if f is not None:
            return f
        nl, nc, ng, r = self.n_loops, self.n_circuits, self.n_gaps, self.n_diff
        integ = ca.integrator(f"flux_idas_{n}", "idas", self._oracle, 0.0,
                              [float(k) for k in range(1, n + 1)], self._idas_opts)
        w0 = ca.MX.sym("w", self.nw)
        Um = ca.MX.sym("U", nc)
        P = ca.MX.sym("P", self.n_u, n)
        nx = r + ng
        v0 = self._balance(w0[nx:], P[1:1 + ng, 0], Um)
        res = integ(x0=w0[:r], z0=ca.vertcat(w0[nx:], v0), p=Um, u=P)
        rates = P[1 + ng:1 + 2 * ng, :]
        s_end = P[1:1 + ng, :] + rates * ca.repmat(P[0, :], ng, 1)
        W = ca.vertcat(res["xf"], s_end, res["zf"][:nl + nc, :])
        qf = res["qf"]                                   # cumulative from the chunk start
        Qi = qf if n == 1 else ca.horzcat(qf[:, 0], qf[:, 1:] - qf[:, :-1])
        O = self.output_fun.map(n)(W, ca.repmat(Um, 1, n), rates)
        f = ca.Function(f"flux_chunk_{n}", [w0, Um, P], [W, Qi, O])
        self._chunks[n] = f
        return f

    def accum(self, n: int) -> ca.Function:
        f = self._accum.get(n)
        if f is None:
            f = self.step_fun.mapaccum("flux_steps", n)
            if len(self._accum) > 8:
                self._accum.clear()
            self._accum[n] = f
        return f


def flux_dae(network: Network, method: str, rtol: float, atol: float, max_num_steps: int,
             radau_elements: int, radau_degree: int, compiled: str = "never",
             cache_dir: str | None = None) -> FluxDAE:
    """The :class:`FluxDAE` of ``network`` for one solver setup, built once and kept in
    ``network.cache``.

    Parameters
    ----------
    network : Network
        The equivalent magnetic circuit.
    method : {"idas", "radau"}
        Integrator.
    rtol, atol : float
        Relative and (nominal-scaled) absolute tolerance.
    max_num_steps : int
        IDAS step limit per run.
    radau_elements, radau_degree : int
        Radau collocation: elements per call and their degree.
    compiled : {"auto", "always", "never"}
        Whether the IDAS functions run as compiled C (see :class:`FluxModel`).
    cache_dir : str or None
        Where compiled libraries are cached.
    """
    if method != "idas":
        compiled, cache_dir = "never", None   # only the IDAS functions are compiled
    size = network.n_loops + len(network.circuits)
    if compiled == "auto" and size > AUTO_COMPILE_SIZE:
        compiled = "never"                    # compiling would take many minutes
    form = "sparse" if method == "idas" and size > SPARSE_FORM_SIZE else "dense"
    key = ("flux_dae", method, rtol, atol, max_num_steps, radau_elements, radau_degree,
           compiled, cache_dir, form)
    dae = network.cache.get(key)
    if dae is None:
        dae = FluxDAE(network, method, rtol, atol, max_num_steps, radau_elements, radau_degree,
                       compiled, cache_dir, form)
        network.cache[key] = dae
    return dae  # type: ignore[no-any-return]


def _resolve_network(model: Any, saturation: bool | None, eddy_currents: bool | None) -> Network:
    saturation = optional_flag(saturation, "saturation")
    eddy_currents = optional_flag(eddy_currents, "eddy_currents")
    if isinstance(model, FluxModel):
        model = model.network
    options = getattr(model, "options", None)
    if not isinstance(model, Network) and options is not None and hasattr(model, "with_options"):
        changes = {}
        if saturation is not None and saturation != options.saturation:
            changes["saturation"] = saturation
        if eddy_currents is not None and eddy_currents != options.eddy_currents:
            changes["eddy_currents"] = eddy_currents
        if changes:
            model = model.with_options(**changes)
        return as_network(model)
    net = as_network(model)
    if saturation is False or eddy_currents is False:
        net = net.with_options(saturation=saturation is not False,
                               eddy_currents=eddy_currents is not False)
    return net


#: Largest jump of the gaps between a step's end and the next step's start, relative to the
#: largest gap, that :meth:`FluxModel.step` integrates on across without restarting IDAS
#: (rounding of ``s_k + rate dt``; a larger jump moves the currents: restart).
LIVE_GAP_TOLERANCE = 1e-9

#: Longest IDAS run without restart in ``simulate`` [hold intervals].
MAX_RUN = 128

#: Keyword options of :class:`FluxModel` (also accepted by ``simulate`` and ``with_options``).
FLUX_MODEL_OPTIONS = ("saturation", "eddy_currents", "method", "rtol", "atol", "max_num_steps",
                      "radau_elements", "radau_degree", "compiled", "cache_dir", "live_step")


def check_options(options: Mapping[str, Any], where: str) -> None:
    """InputError for keyword options that :class:`FluxModel` does not have."""
    unknown = sorted(set(options) - set(FLUX_MODEL_OPTIONS))
    if unknown:
        raise InputError(f"{where}: unknown option(s) {unknown}; the FluxModel options are "
                         f"{', '.join(FLUX_MODEL_OPTIONS)}")


def _physical_time(exc: Exception, t_restart: float, dt: float) -> RuntimeError:
    """The live integrator's IDAS message with its normalised times ``t``, ``tstop``,
    ``tout`` (intervals of ``dt`` since the restart at ``t_restart``) and step ``h`` in
    seconds."""
    def sec(m: re.Match[str]) -> str:
        v = float(m.group(2))
        phys = v * dt if m.group(1) == "h" else t_restart + v * dt
        return f"{m.group(1)} = {phys:.9g} s"

    num = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
    return RuntimeError(re.sub(r"\b(tstop|tout|t|h)\s*=\s*" + num, sec, str(exc)))


# ---------------------------------------------------------------------------- the model
class FluxModel:
    """Flux-based dynamic magnet model (index-1 DAE, paper eqs. 4-7).

    Parameters
    ----------
    model : Network, Magnet or FluxModel
        The equivalent magnetic circuit (a magnet built with eddy-current elements
        gives the eddy-current model).
    saturation, eddy_currents : bool or None
        Physics switches (None: as the model is built).  A Magnet is rebuilt with the
        changed option; a bare Network can only have effects switched off.
    method : {"idas", "radau"}
        ``"idas"`` (default): SUNDIALS IDAS, variable-order BDF with error control and
        exact Jacobians (via CasADi).  ``"radau"``: fixed-step Radau IIA collocation
        (``radau_elements`` elements of degree ``radau_degree`` per call) - faster for
        co-simulation at small fixed steps, without error control.
    rtol : float
        Relative tolerance (IDAS), default :data:`DEFAULT_RTOL` = 1e-6.
    atol : float
        Absolute tolerance relative to nominal scales (flux 1 T x median branch area,
        flux linkage the same times the turns, current = MMF of 1 T over 5 mm of air
        divided by the circuit turns, gap 10 mm), default :data:`DEFAULT_ATOL` = 1e-8.
    max_num_steps : int
        IDAS step limit per run (one hold interval in :meth:`step`, up to :data:`MAX_RUN`
        intervals in ``simulate``; failure raises :class:`SolverError`).
    compiled : {"auto", "always", "never"}
        IDAS only: ``"auto"`` (default) generates the DAE's residual, Jacobian, quadrature
        and output functions as one C file, compiles it with the system C compiler and
        caches the library on disk (a second model of the same network only loads it);
        without a working compiler it warns (:class:`~maglevkit.errors.CompilationWarning`)
        and runs on CasADi's virtual machine.  Networks with more than
        :data:`AUTO_COMPILE_SIZE` loop and circuit unknowns (the cell networks of
        ``discretisation="grid"`` with eddy ladders) are interpreted under ``"auto"``: the
        C compiler would take many minutes there.  ``"always"`` compiles every network and
        raises :class:`~maglevkit.errors.SolverError` where that fails; ``"never"`` always
        interprets.
        Both paths evaluate the same expressions: the trajectories agree to rounding.
        ``method="radau"`` is always interpreted.
    cache_dir : str or None
        Where compiled libraries are cached (default
        :func:`maglevkit.models.compiled.cache_directory`).
    live_step : bool
        :meth:`step` keeps its IDAS integrator alive between calls (default True): it
        integrates on where nothing jumped since the last call (same state, ``dt`` and
        voltages, continuous gaps) and restarts only where something did
        (:mod:`maglevkit.models.flux_live`; compiled IDAS, else ignored).
        False restarts CasADi's integrator on every call (the behaviour before).

    Other Parameters
    ----------------
    radau_elements : int, default 2
        ``method="radau"`` only: collocation elements per integrator call (per hold
        interval), a whole number >= 1.
    radau_degree : int, default 3
        ``method="radau"`` only: degree of the Radau IIA collocation polynomial, 1..9.

    Raises
    ------
    InputError
        ``rtol`` or ``atol`` outside (0, 1), a step limit, element count or degree that is
        not a whole number in range, an unknown ``method`` or ``compiled``, a ``cache_dir``
        that is not a path, or switches that are neither bool nor None.  (A bare
        Network ignores ``True`` switches: it can only have effects switched off.)

    Attributes
    ----------
    compiled : bool
        Whether this model runs compiled code.
    """

    def __init__(self, model: Any, *, saturation: bool | None = None,
                 eddy_currents: bool | None = None, method: str = "idas",
                 rtol: float = DEFAULT_RTOL, atol: float = DEFAULT_ATOL,
                 max_num_steps: int = 20000, radau_elements: int = 2,
                 radau_degree: int = 3, compiled: str = "auto",
                 cache_dir: Any = None, live_step: bool = True) -> None:
        for name, v in (("rtol", rtol), ("atol", atol)):
            if not 0.0 < real_number(v, name) < 1.0:
                raise InputError(f"{name} = {v!r} must lie in (0, 1)")
        max_num_steps = whole_number(max_num_steps, "max_num_steps", minimum=1)
        radau_elements = whole_number(radau_elements, "radau_elements", minimum=1)
        radau_degree = whole_number(radau_degree, "radau_degree", minimum=1)
        if radau_degree > 9:
            raise InputError(f"radau_degree = {radau_degree!r} must lie in 1..9")
        if not isinstance(method, str) or method not in ("idas", "radau"):
            raise InputError(f"method = {method!r}; use 'idas' (error-controlled BDF) or "
                             "'radau' (fixed-step Radau IIA collocation)")
        if not isinstance(compiled, str) or compiled not in COMPILE_MODES:
            raise InputError(f"compiled = {compiled!r}; use one of {list(COMPILE_MODES)} "
                             "('auto': compiled C where a compiler exists)")
        if cache_dir is not None and not isinstance(cache_dir, (str, os.PathLike)):
            raise InputError(f"cache_dir = {cache_dir!r} must be a path (str or Path) or None")
        cache_dir = None if cache_dir is None else os.fspath(cache_dir)
        self.network = _resolve_network(model, saturation, eddy_currents)
        # the network's names, derived once (step reads them on every call)
        self._gap_names = self.network.gap_names
        self._circuit_names = self.network.circuit_names
        #: Gaps and currents beyond which inputs warn (from a Magnet; None for a Network).
        self.plausible_range: PlausibleRange | None = plausible_range(model)
        self.method = method
        self.rtol = float(rtol)
        self.atol = float(atol)
        self._dae = flux_dae(self.network, method, self.rtol, self.atol, max_num_steps,
                             radau_elements, radau_degree, compiled, cache_dir)
        self.compiled = self._dae.compiled
        d = self._dae
        self._state_shapes = (("differential_state", d.n_diff), ("gaps_m", d.n_gaps),
                              ("loop_flux_Wb", d.n_loops), ("currents_A", d.n_circuits),
                              ("voltages_V", d.n_circuits), ("gap_rates_m_per_s", d.n_gaps),
                              ("energy_J", 4))
        # step's live integrator (None: not made yet, False: none for this model), the last
        # state it returned with (dt, voltages, interval index, quadratures)
        self._live: LiveIntegrator | None | bool = None if flag(live_step, "live_step") else False
        self._live_last: tuple[Any, ...] | None = None
        self._live_next: tuple[Any, ...] | None = None
        # one IDAS memory per model: threads stepping the model take turns
        self._live_lock = threading.Lock()
        self._options = {"method": method, "rtol": self.rtol, "atol": self.atol,
                         "max_num_steps": max_num_steps, "radau_elements": radau_elements,
                         "radau_degree": radau_degree, "compiled": compiled,
                         "cache_dir": cache_dir, "live_step": bool(live_step)}

    # ------------------------------------------------------------------ description
    @property
    def gap_names(self) -> tuple[str, ...]:
        return self._gap_names

    @property
    def circuit_names(self) -> tuple[str, ...]:
        return self._circuit_names

    @property
    def branch_names(self) -> tuple[str, ...]:
        return self.network.branch_names

    @property
    def eddy_branch_names(self) -> tuple[str, ...]:
        return tuple(self.network.branch_names[i] for i in self._dae.eddy_idx)

    @property
    def differential_state_names(self) -> tuple[str, ...]:
        """Names of the differential states ``y = D x`` (flux linkages, eddy-branch fluxes)."""
        return tuple(self._dae.diff_names)

    @property
    def has_eddy_currents(self) -> bool:
        return self._dae.n_eddy > 0

    @property
    def resistances(self) -> np.ndarray:
        """Circuit resistances R_el [ohm]."""
        return self.network.resistances

    @property
    def live_step(self) -> bool:
        """Whether :meth:`step` keeps an IDAS integrator alive between calls (the option,
        where this model supports it; builds the integrator's library on first use)."""
        if self._live is None:
            with self._live_lock:            # threads' first steps make one integrator
                if self._live is None:
                    self._live = self._dae.live_integrator() or False
        return self._live is not False

    @property
    def dae(self) -> FluxDAE:
        """The model's DAE: matrices, symbolic functions and integrators (shared by every
        model of the same network and solver setup)."""
        return self._dae

    @property
    def options(self) -> dict[str, Any]:
        """The solver options this model was built with (a copy; see :meth:`with_options`)."""
        return dict(self._options)

    def __getstate__(self) -> dict[str, Any]:
        # the live integrator (C memory) stays behind; a copy makes its own on first step
        state = {**self.__dict__, "_live": None, "_live_last": None, "_live_next": None}
        state.pop("_live_lock", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._live_lock = threading.Lock()

    def with_options(self, **changes: Any) -> FluxModel:
        """A model of the same network with other solver options (method, rtol, atol, ...)."""
        check_options(changes, "FluxModel.with_options")
        return FluxModel(self, **{**self._options, **changes})

    def __repr__(self) -> str:
        return (f"FluxModel({self.network.name!r}, method={self.method!r}, rtol={self.rtol:g}, "
                f"atol={self.atol:g}, compiled={self.compiled}, "
                f"states={list(self.differential_state_names)})")

    # ------------------------------------------------------------------ states
    @renamed_keywords(gaps="gaps_m", currents="currents_A", time="time_s")
    def initial_state(self, *, gaps_m: Any, currents_A: Any, time_s: float = 0.0) -> FluxState:
        """Consistent steady state at ``gaps`` [m] and circuit ``currents`` [A].

        The fluxes come from :func:`solve_statics`; the state is at rest (no eddy
        currents), consistent with the voltages ``U = R I`` and zero gap rates.

        The old keyword names ``gaps``, ``currents``, ``time`` still work as deprecated aliases (a
        ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        gaps_m : float, array_like (n_gaps,) or mapping
            Gaps [m], each > 0: one value for all, one per gap input (:attr:`gap_names`),
            or ``{gap name: value}`` with every name.  One operating point only.
        currents_A : float, array_like (n_circuits,) or mapping
            Circuit currents [A], same forms per circuit (:attr:`circuit_names`).
        time_s : float, default 0.0
            Time of the state [s], a finite real number.

        Returns
        -------
        FluxState

        Raises
        ------
        InputError
            Bad gaps or currents (wrong count or names, not finite, a gap <= 0, more than
            one operating point) or a bad ``time``.

        Warns
        -----
        PlausibilityWarning
            Gaps or currents beyond the magnet's plausible range (models built from a
            Magnet).
        """
        gaps, currents, time = gaps_m, currents_A, time_s
        return self._initial_state(gaps, currents, time, where="FluxModel.initial_state")

    def _initial_state(self, gaps: Any, currents: Any, time: Any, *,
                       where: str | None) -> FluxState:
        """:meth:`initial_state`; ``where=None``: the caller has checked plausibility."""
        net = self.network
        s = gap_vector(net, gaps)
        i = current_vector(net, currents)
        if s.shape != (len(net.gap_names),) or i.shape != (len(net.circuit_names),):
            raise InputError("initial_state takes one operating point (one value per gap and "
                             "circuit)")
        time = real_number(time, "time", "s")
        if self.plausible_range is not None and where is not None:
            self.plausible_range.check(gaps_m=s, currents_A=i, where=where)
        sol = solve_statics(net, gaps_m=s, currents_A=i)
        x = np.asarray(sol.loop_flux_Wb, dtype=float).ravel()
        return FluxState(float(time), self._dae.D @ x, s.copy(), x, i.copy(),
                         self.resistances * i, np.zeros_like(s), np.zeros(4))

    def _check_state(self, state: Any) -> None:
        """InputError unless ``state`` is a finite FluxState with this model's array shapes."""
        if not isinstance(state, FluxState):
            raise InputError(f"state must be a FluxState (from FluxModel.initial_state or "
                             f"step), got {type(state).__name__}")
        for name, n in self._state_shapes:
            got = np.shape(getattr(state, name))
            if got != (n,):
                raise InputError(
                    f"state.{name} has shape {got}, but this model "
                    f"({self.network.name!r}, differential states "
                    f"{list(self.differential_state_names)}) expects ({n},); the state "
                    "belongs to a different model (e.g. other eddy_currents setting) - make "
                    "it with this model's initial_state")
        if not (math.isfinite(state.time_s) and np.isfinite(state._vector()).all()
                and np.isfinite(state.voltages_V).all()
                and np.isfinite(state.gap_rates_m_per_s).all()):
            raise InputError(f"state is not finite (time {state.time_s!r} s, differential "
                             f"state {np.asarray(state.differential_state).tolist()}, "
                             f"currents {np.asarray(state.currents_A).tolist()})")

    def outputs(self, state: FluxState) -> FluxOutputs:
        """Outputs at ``state`` (with the inputs stored in the state).

        Parameters
        ----------
        state : FluxState
            A finite state of this model (from :meth:`initial_state` or :meth:`step`); its
            ``voltages_V`` [V] and ``gap_rates_m_per_s`` [m/s] are the inputs used.

        Returns
        -------
        FluxOutputs

        Raises
        ------
        InputError
            ``state`` not a FluxState, of another model's shapes, or not finite.
        """
        self._check_state(state)
        o = np.asarray(self._dae.output_fun(state._vector(), state.voltages_V,
                                            state.gap_rates_m_per_s)).ravel()
        return self._unpack_outputs(state.time_s, state.currents_A, o)

    def _unpack_outputs(self, t: float, currents: np.ndarray, o: np.ndarray) -> FluxOutputs:
        d = self._dae
        nb, nc, ng = d.n_branches, d.n_circuits, d.n_gaps
        phi = o[:nb]
        pole = o[nb + 2 * nc:nb + 2 * nc + ng]
        return FluxOutputs(t, currents, o[nb:nb + nc], o[nb + nc:nb + 2 * nc], pole,
                           float(pole.sum()), phi, phi[d.eddy_idx], o[nb + 2 * nc + ng:])

    def _unpack_state(self, t: float, w: np.ndarray, U: np.ndarray, rate: np.ndarray,
                      energy: np.ndarray) -> FluxState:
        d = self._dae
        a, b, c = d.n_diff, d.n_diff + d.n_gaps, d.n_diff + d.n_gaps + d.n_loops
        return FluxState(t, w[:a], w[a:b], w[b:c], w[c:], U, rate, energy)

    def _fail(self, exc: Exception, t: float, w: np.ndarray, U: np.ndarray,
              rate: np.ndarray, dt: float) -> SolverError:
        d = self._dae
        st: dict[str, Any] = {}
        for name, v in zip(d.diff_names, w[:d.n_diff], strict=True):
            st[name] = float(v)
        st["gaps_m"] = w[d.n_diff:d.n_diff + d.n_gaps]
        st["currents_A"] = w[d.nw - d.n_circuits:]
        st["voltages_V"] = U
        st["gap_rates_m_per_s"] = rate
        msg = str(exc).strip().splitlines()
        reason = next((ln.strip() for ln in reversed(msg) if ln.strip()), type(exc).__name__)
        return SolverError(f"flux model ({self.method}) failed on the step of {dt:.6g} s",
                           time_s=t, state=st, reason=reason[:400])

    @renamed_keywords(dt="dt_s", voltages="voltages_V", gaps="gaps_m", gap_rates="gap_rates_m_per_s")
    def step(self, state: FluxState, dt_s: float, voltages_V: Any, gaps_m: Any = None,
             gap_rates_m_per_s: Any = 0.0) -> tuple[FluxState, FluxOutputs]:
        """Advance ``state`` by ``dt`` [s] with constant voltages and gap rates.

        The old keyword names ``dt``, ``voltages``, ``gaps``, ``gap_rates`` still work as
        deprecated aliases (a ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        state : FluxState
            From :meth:`initial_state` or a previous :meth:`step`.
        dt_s : float
            Step length [s] (> 0).
        voltages_V : float, sequence or mapping
            Circuit voltages [V], held constant over the step (zero-order hold).
        gaps_m : float, sequence, mapping or None
            Gaps [m] at the start of the step (e.g. from a mechanical model); None keeps
            the state's gaps.  Flux linkages are continuous; currents adapt.
        gap_rates_m_per_s : float, sequence or mapping
            Gap rates [m/s] over the step (gaps move linearly).

        Returns
        -------
        (FluxState, FluxOutputs)
            The state and the outputs at ``state.time_s + dt``.

        Raises
        ------
        InputError
            A state of another model (array shapes differ from this model's), bad shapes,
            non-finite values or bools, ``dt`` not a real number > 0, gaps that are or
            become <= 0.
        SolverError
            The integrator failed (with time, state and the solver's reason).

        Notes
        -----
        With :attr:`live_step` the IDAS integrator stays alive between calls: stepping the
        state the last call returned, with the same ``dt`` and voltages and the gaps where
        that step ended, integrates on (as ``simulate`` does across hold intervals); any
        other call restarts IDAS from ``state`` with consistent algebraic variables.  Both
        agree with a restart per call to the integrator's accuracy.  Threads stepping one
        model take turns on its integrator (a per-model lock); a live library that does not
        load falls back to the restarting step with a ``CompilationWarning``.
        """
        dt, voltages, gaps, gap_rates = dt_s, voltages_V, gaps_m, gap_rates_m_per_s
        d = self._dae
        self._check_state(state)
        dt = check_step(dt)
        U = per_name_values(voltages, self.circuit_names, "voltages", "V")
        rate = per_name_values(gap_rates, self.gap_names, "gap_rates", "m/s", kind="gap")
        w = state._vector()
        if gaps is not None:
            s0 = per_name_values(gaps, self.gap_names, "gaps", "m", kind="gap")
            w[d.n_diff:d.n_diff + d.n_gaps] = s0
        else:
            s0 = state.gaps_m
        if np.any(s0 <= 0.0) or np.any(s0 + rate * dt <= 0.0):
            raise InputError(f"gaps must stay > 0 m over the step: start {s0.tolist()} m, end "
                             f"{(s0 + rate * dt).tolist()} m")
        if self.plausible_range is not None and gaps is not None:
            self.plausible_range.check(gaps_m=(s0, s0 + rate * dt), where="FluxModel.step")
        if self.live_step:
            with self._live_lock:
                return self._step_live_locked(state, dt, U, rate, s0, w)
        try:
            wf, q, o = d.step_fun(w, np.concatenate(((dt,), U, rate)))
        except RuntimeError as exc:
            raise self._fail(exc, state.time_s, w, U, rate, dt) from None
        return self._finish_step(state, dt, U, rate, w, wf, q, o)

    def live_stats(self) -> dict[str, int] | None:
        """Counters of the live integrator (:meth:`~maglevkit.models.flux_live.LiveIntegrator.stats`:
        sparse and dense LU setups, preconditioner solves, IDAS steps and iterations since
        its last restart), or None where :meth:`step` restarts IDAS on every call."""
        if not self.live_step:
            return None
        with self._live_lock:
            assert isinstance(self._live, LiveIntegrator)
            return self._live.stats()

    def _step_live_locked(self, state: FluxState, dt: float, U: np.ndarray, rate: np.ndarray,
                          s0: np.ndarray, w: np.ndarray) -> tuple[FluxState, FluxOutputs]:
        assert isinstance(self._live, LiveIntegrator)
        wf, q, o = self._step_live(self._live, state, dt, U, rate, s0, w)
        return self._finish_step(state, dt, U, rate, w, wf, q, o)

    def _finish_step(self, state: FluxState, dt: float, U: np.ndarray, rate: np.ndarray,
                     w: np.ndarray, wf: Any, q: Any, o: Any) -> tuple[FluxState, FluxOutputs]:
        wf = np.asarray(wf).ravel()
        o = np.asarray(o).ravel()
        if not (np.isfinite(wf).all() and np.isfinite(o).all()):
            self._live_next = None
            raise self._fail(RuntimeError("non-finite solution"), state.time_s, w, U, rate, dt)
        t1 = state.time_s + dt
        new = self._unpack_state(t1, wf, U, rate, state.energy_J + np.asarray(q).ravel())
        if self._live_next is not None:
            self._live_last, self._live_next = (new, *self._live_next), None
        return new, self._unpack_outputs(t1, new.currents_A, o)

    def _step_live(self, live: LiveIntegrator, state: FluxState, dt: float, U: np.ndarray,
                   rate: np.ndarray, s0: np.ndarray, w: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One :meth:`step` on the live integrator: integrate on from the last step where
        nothing jumped (``state`` is the one it returned, same ``dt`` and voltages, gaps
        continuous to :data:`LIVE_GAP_TOLERANCE`), else restart IDAS from ``state``."""
        d = self._dae
        r, nx = d.n_diff, d.n_diff + d.n_gaps
        last = self._live_last
        self._live_last = None
        if not (last is not None and state is last[0] and dt == last[1]
                and (U == last[2]).all()
                and (np.abs(s0 - state.gaps_m) <= LIVE_GAP_TOLERANCE * np.abs(s0).max()).all()):
            last = (None, dt, U, 0, np.zeros(4 + d.n_gaps))
            v0 = np.asarray(d._balance(w[nx:], s0, U)).ravel()
            try:
                live.reinit(0.0, w[:r], np.concatenate((w[nx:], v0)), U,
                            np.concatenate(((dt,), s0, rate, (0.0,))))
            except RuntimeError as exc:
                raise self._fail(_physical_time(exc, state.time_s, dt), state.time_s, w, U,
                                 rate, dt) from None
        k = last[3]
        try:
            wf, q, o = live.step(k + 1.0, np.concatenate(((dt,), s0, rate, (float(k),))))
        except RuntimeError as exc:
            raise self._fail(_physical_time(exc, state.time_s - k * dt, dt), state.time_s,
                             w, U, rate, dt) from None
        self._live_next = (dt, U.copy(), k + 1, q)
        dq = q - last[4]
        # the mechanical work from the integrated pole forces (-rate . int F dt, exact for
        # the constant rate), not from -F.rate (whose integrand jumps at every step)
        return wf, np.concatenate((dq[:3], (-rate @ dq[4:],))), o

    # ------------------------------------------------------------------ batch
    def _run_idas(self, state: FluxState, h: np.ndarray, U: np.ndarray, rate: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """IDAS runs without restart over intervals of equal voltages (at most
        :data:`MAX_RUN` intervals each, split into power-of-two chunks)."""
        d = self._dae
        n, ng = h.size, d.n_gaps
        W = np.empty((n, d.nw))
        Qd = np.empty((n, 4))
        O = np.empty((n, d.n_out))
        s_start = state.gaps_m + np.vstack((np.zeros((1, ng)),
                                            np.cumsum(h[:-1, None] * rate[:-1], axis=0)))
        P = np.vstack((h[None, :], s_start.T, rate.T, np.zeros((1, n))))
        change = np.nonzero(np.any(U[1:] != U[:-1], axis=1))[0] + 1
        bounds = [0, *change.tolist(), n]
        w = state._vector()
        for a, b in zip(bounds[:-1], bounds[1:], strict=True):
            k = a
            while k < b:
                m = min(MAX_RUN, 1 << ((b - k).bit_length() - 1))
                Pc = P[:, k:k + m].copy()
                Pc[-1] = np.arange(m)
                try:
                    Wc, Qc, Oc = d.chunk(m)(w, U[k], Pc)
                except RuntimeError:
                    self._locate_failure(state, w, h, U, rate, k, m)
                W[k:k + m] = np.asarray(Wc).T
                Qd[k:k + m] = np.asarray(Qc).T
                O[k:k + m] = np.asarray(Oc).T
                w = W[k + m - 1]
                k += m
                check_interrupt()  # a deferred Ctrl-C (CLI): between chunks, not in CasADi
        self._check_finite(state, W, O, h, U, rate)
        return W, Qd, O

    def _locate_failure(self, state: FluxState, w: np.ndarray, h: np.ndarray, U: np.ndarray,
                        rate: np.ndarray, k: int, m: int) -> None:
        """Repeat intervals ``k..k+m-1`` one by one and raise the informative SolverError."""
        t = state.time_s + float(h[:k].sum())
        for j in range(k, k + m):
            p = np.concatenate(((h[j],), U[j], rate[j]))
            try:
                wf, _, _ = self._dae.step_fun(w, p)
            except RuntimeError as exc:
                raise self._fail(exc, t, w, U[j], rate[j], float(h[j])) from None
            w = np.asarray(wf).ravel()
            t += float(h[j])
        raise SolverError("flux model failed over several hold intervals but not interval by "
                          "interval", time_s=t) from None

    def _check_finite(self, state: FluxState, W: np.ndarray, O: np.ndarray, h: np.ndarray,
                      U: np.ndarray, rate: np.ndarray) -> None:
        bad = ~(np.all(np.isfinite(W), axis=1) & np.all(np.isfinite(O), axis=1))
        if np.any(bad):
            j = int(np.argmax(bad))
            t = state.time_s + float(h[:j].sum())
            w0 = state._vector() if j == 0 else W[j - 1]
            raise self._fail(RuntimeError("non-finite solution"), t, w0, U[j], rate[j],
                             float(h[j]))

    def _run(self, state: FluxState, h: np.ndarray, U: np.ndarray, rate: np.ndarray,
             chunk: int = 200) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Integrate intervals ``h`` (n,) with inputs U (n, nc), rate (n, ng) in C++ chunks."""
        if self.method == "idas":
            return self._run_idas(state, h, U, rate)
        d = self._dae
        n = h.size
        W = np.empty((n, d.nw))
        Qd = np.empty((n, 4))
        O = np.empty((n, d.n_out))
        w = state._vector()
        k = 0
        while k < n:
            m = min(chunk, n - k)
            P = np.vstack((h[None, k:k + m], U[k:k + m].T, rate[k:k + m].T))
            try:
                Wc, Qc, Oc = d.accum(m)(w, P)
            except RuntimeError:
                # locate the failing interval step by step for an informative error
                self._locate_failure(state, w, h, U, rate, k, m)
            W[k:k + m] = np.asarray(Wc).T
            Qd[k:k + m] = np.asarray(Qc).T
            O[k:k + m] = np.asarray(Oc).T
            w = W[k + m - 1]
            k += m
            check_interrupt()      # a deferred Ctrl-C (CLI): between chunks, not in CasADi
        self._check_finite(state, W, O, h, U, rate)
        return W, Qd, O


# ---------------------------------------------------------------------------- simulate
@dataclass(frozen=True)
class SimulationResult:
    """Time series of a flux-model simulation (SI units; axis 0 is time).

    Values at ``time_s[k]`` are left limits (before the inputs change at ``t_k``);
    ``voltages_V[k]`` and ``gap_rates_m_per_s[k]`` are the inputs held on
    ``[t_k, t_{k+1})`` (the last row repeats the previous one).

    Attributes
    ----------
    time_s : ndarray (n_t,)
        Sample times [s].
    gaps_m : ndarray (n_t, n_gaps)
        Gap inputs [m].
    gap_rates_m_per_s : ndarray (n_t, n_gaps)
        Gap rates [m/s] held on each interval.
    voltages_V : ndarray (n_t, n_circuits)
        Circuit voltages [V] held on each interval.
    currents_A : ndarray (n_t, n_circuits)
        Circuit currents [A].
    flux_linkage_Wb : ndarray (n_t, n_circuits)
        Circuit flux linkages [Wb].
    eta_Wb : ndarray (n_t, n_circuits)
        Sums of the coil-core fluxes of each circuit [Wb].
    pole_force_N : ndarray (n_t, n_gaps)
        Force per gap input [N], attraction positive.
    force_N : ndarray (n_t,)
        Total force [N].
    branch_flux_Wb : ndarray (n_t, n_branches)
        All branch fluxes [Wb] (:attr:`branch_names`).
    eddy_flux_Wb : ndarray (n_t, n_eddy)
        Fluxes of the eddy branches [Wb] (no columns without eddy currents).
    eddy_mmf_A : ndarray (n_t, n_eddy)
        Eddy-current MMFs ``G_ec dphi/dt`` of the eddy branches [A].
    differential_state : ndarray (n_t, n_diff)
        The DAE's differential states ``y = D x``: flux linkages, then eddy fluxes [Wb].
    electrical_energy_J : ndarray (n_t,)
        Electrical energy fed in since ``time_s[0]`` [J] (cumulative).
    ohmic_loss_J : ndarray (n_t,)
        Cumulative ohmic loss [J].
    eddy_loss_J : ndarray (n_t,)
        Cumulative eddy-current loss [J].
    mechanical_work_J : ndarray (n_t,)
        Cumulative mechanical work of the magnet's force on the moving gaps [J].
    gap_names : tuple of str
        Column order of the gap arrays.
    circuit_names : tuple of str
        Column order of the circuit arrays.
    branch_names : tuple of str
        Column order of ``branch_flux_Wb``.
    eddy_branch_names : tuple of str
        Column order of the eddy arrays.
    final_state : FluxState
        State at ``time_s[-1]``, to continue with :meth:`FluxModel.step` or as
        ``initial_state`` of another simulation.
    network : Network
        The simulated equivalent circuit (for the magnetic energy; not in ``repr`` or
        comparisons).
    """

    time_s: np.ndarray
    gaps_m: np.ndarray
    gap_rates_m_per_s: np.ndarray
    voltages_V: np.ndarray
    currents_A: np.ndarray
    flux_linkage_Wb: np.ndarray
    eta_Wb: np.ndarray
    pole_force_N: np.ndarray
    force_N: np.ndarray
    branch_flux_Wb: np.ndarray
    eddy_flux_Wb: np.ndarray
    eddy_mmf_A: np.ndarray
    differential_state: np.ndarray
    electrical_energy_J: np.ndarray
    ohmic_loss_J: np.ndarray
    eddy_loss_J: np.ndarray
    mechanical_work_J: np.ndarray
    gap_names: tuple[str, ...]
    circuit_names: tuple[str, ...]
    branch_names: tuple[str, ...]
    eddy_branch_names: tuple[str, ...]
    final_state: FluxState
    network: Network = field(repr=False, compare=False)

    def magnetic_energy_J(self, index: int = -1) -> float:
        """Stored magnetic energy [J] at sample ``index`` (iron by quadrature).

        Parameters
        ----------
        index : int, default -1
            Sample index into the time axis (NumPy indexing: negative counts from the end;
            out of range raises ``IndexError``).

        Returns
        -------
        float
            Energy stored in the air gaps and the iron [J].
        """
        return magnetic_energy(self.network, self.branch_flux_Wb[index], self.gaps_m[index])

    def energy_balance(self, start: int = 0, stop: int = -1) -> EnergyBalance:
        """Energy balance between samples ``start`` and ``stop``.

        Parameters
        ----------
        start : int, default 0
            Sample index where the balance starts.
        stop : int, default -1
            Sample index where it ends (NumPy indexing; default the last sample).  Each
            term is the value at ``stop`` minus that at ``start``, so ``stop`` before
            ``start`` gives the negated balance.

        Returns
        -------
        EnergyBalance
        """
        def d(a: np.ndarray) -> float:
            return float(a[stop] - a[start])

        dw = self.magnetic_energy_J(stop) - self.magnetic_energy_J(start)
        e_in, e_ohm = d(self.electrical_energy_J), d(self.ohmic_loss_J)
        e_ed, e_me = d(self.eddy_loss_J), d(self.mechanical_work_J)
        return EnergyBalance(e_in, e_ohm, e_ed, dw, e_me, e_in - e_ohm - e_ed - dw - e_me)

    def columns(self) -> dict[str, np.ndarray]:
        """Flat named columns (for CSV): one per scalar series, names with units."""
        cols: dict[str, np.ndarray] = {"time_s": self.time_s}

        def add(base: str, unit: str, arr: np.ndarray, names: tuple[str, ...]) -> None:
            for j, nm in enumerate(names):
                cols[f"{base}[{nm}]_{unit}"] = arr[:, j]

        add("gap", "m", self.gaps_m, self.gap_names)
        add("gap_rate", "m_per_s", self.gap_rates_m_per_s, self.gap_names)
        add("voltage", "V", self.voltages_V, self.circuit_names)
        add("current", "A", self.currents_A, self.circuit_names)
        add("flux_linkage", "Wb", self.flux_linkage_Wb, self.circuit_names)
        add("eta", "Wb", self.eta_Wb, self.circuit_names)
        add("pole_force", "N", self.pole_force_N, self.gap_names)
        cols["force_N"] = self.force_N
        add("eddy_flux", "Wb", self.eddy_flux_Wb, self.eddy_branch_names)
        add("eddy_mmf", "A", self.eddy_mmf_A, self.eddy_branch_names)
        cols["electrical_energy_J"] = self.electrical_energy_J
        cols["ohmic_loss_J"] = self.ohmic_loss_J
        cols["eddy_loss_J"] = self.eddy_loss_J
        cols["mechanical_work_J"] = self.mechanical_work_J
        return cols


@renamed_keywords(t="times_s", gaps="gaps_m", voltages="voltages_V",
                  gap_rates="gap_rates_m_per_s", dt="dt_s", initial_currents="initial_currents_A")
def simulate_flux(model: Any, times_s: Any, *, gaps_m: Any, voltages_V: Any,
                  gap_rates_m_per_s: Any = None, dt_s: float | None = None, initial_currents_A: Any = None,
                  initial_state: Any = None, gap_rate_tolerance: float = 0.02,
                  **options: Any) -> SimulationResult:
    """Simulate the flux model on a time grid (the flux-model branch of
    :func:`maglevkit.simulate`, which also runs the reduced models).

    The old keyword names ``t``, ``gaps``, ``voltages``, ``gap_rates``, ``dt``, ``initial_currents`` still
    work as deprecated aliases (a ``DeprecationWarning`` names the new one).

    Parameters
    ----------
    model : FluxModel, Magnet or Network
        The model; ``options`` (``saturation``, ``eddy_currents``, ``method``, ``rtol``,
        ``atol``, ...) build a :class:`FluxModel` (or change a given one).
    times_s : (t0, tf), [t0, tf] or array
        A time span [s]: a tuple or list of exactly two numbers gives the grid
        ``t0 + k dt`` ending exactly at ``tf``.  A numpy array (any length >= 2) or a
        sequence of three or more times is an explicit increasing grid [s] (then no
        ``dt``; a two-point grid is ``np.array([t0, t1])``).  Inputs are sampled on the
        grid.
    gaps_m : float, sequence, mapping, Signal, callable or array
        Gaps [m]: constant (scalar or one value per gap), a Signal or ``f(t)`` (scalar
        or per-gap values), a mapping per gap name of any of these, or samples of shape
        ``(n_t, n_gaps)`` (``(n_t,)`` for one gap).  Between samples the gap moves
        linearly (rate = secant).
    voltages_V : same forms
        Circuit voltages [V]; zero-order hold: ``U(t_k)`` on ``[t_k, t_{k+1})``.
    gap_rates_m_per_s : same forms, optional
        Gap rates [m/s].  If given, they must agree with the gaps: the trapezoidal mean
        of the rates over each interval may differ from the secant by at most
        ``gap_rate_tolerance`` times the largest rate (plus 1 um/s); otherwise InputError.
    dt_s : float, optional
        Grid step [s] with a time span (default 1e-4 s); a real number > 0 (numpy scalars
        allowed, bools rejected).
    initial_currents_A : float, sequence or mapping, optional
        Start at the static operating point with these currents [A]; default the
        steady state ``U(t0) / R``.
    initial_state : FluxState, optional
        Start from this state instead (its gaps are replaced by ``gaps(t0)``).
    gap_rate_tolerance : float, optional
        Allowed mismatch between given gap rates and the gaps' secants, as a fraction of
        the largest rate [-] (default 0.02); see ``gap_rates``.

    Returns
    -------
    SimulationResult

    Raises
    ------
    InputError
        Invalid inputs (shapes, NaN, gaps <= 0, inconsistent gap rates).
    SolverError
        The integrator failed (time, state and reason in the exception).
    """
    gaps, voltages, gap_rates, dt = gaps_m, voltages_V, gap_rates_m_per_s, dt_s
    initial_currents = initial_currents_A
    if initial_currents is not None:
        real_array(initial_currents if not isinstance(initial_currents, Mapping)
                   else list(initial_currents.values()), "initial_currents", "A")
    check_options(options, "simulate")
    if isinstance(model, FluxModel):
        fm = model.with_options(**options) if options else model
    else:
        fm = FluxModel(model, **options)
    net = fm.network
    times = time_grid(times_s, dt)
    s = sample_input(gaps, times, net.gap_names, "gaps", "m")
    gap_vector(net, s)  # checks > 0
    U = sample_input(voltages, times, net.circuit_names, "voltages", "V")
    rng = fm.plausible_range
    if rng is not None:
        rng.check(gaps_m=s, currents_A=initial_currents, where="simulate")
    h = np.diff(times)
    secant = gap_secants(times, s, gap_rates, net.gap_names, gap_rate_tolerance)
    if initial_state is not None:
        if initial_currents is not None:
            raise InputError("give initial_currents or initial_state, not both")
        fm._check_state(initial_state)
        st0 = FluxState(float(times[0]), initial_state.differential_state, s[0].copy(),
                        initial_state.loop_flux_Wb, initial_state.currents_A,
                        initial_state.voltages_V, initial_state.gap_rates_m_per_s,
                        np.zeros(4))
    else:
        i0 = U[0] / net.resistances if initial_currents is None else initial_currents
        st0 = fm._initial_state(s[0], i0, float(times[0]), where=None)
    W, Qd, O = fm._run(st0, h, U[:-1], secant)
    d = fm._dae
    o0 = np.asarray(d.output_fun(st0._vector(), st0.voltages_V,
                                 st0.gap_rates_m_per_s)).ravel()
    O = np.vstack((o0, O))
    W = np.vstack((st0._vector(), W))
    E = np.vstack((np.zeros(4), np.cumsum(Qd, axis=0)))
    nb, nc, ng = d.n_branches, d.n_circuits, d.n_gaps
    rates = np.vstack((secant, secant[-1:]))
    held_U = np.vstack((U[:-1], U[-2:-1]))
    final = fm._unpack_state(float(times[-1]), W[-1], U[-2], secant[-1], E[-1])
    if rng is not None:
        # voltages may drive currents no coil carries (e.g. U typed in mV)
        rng.check(currents_A=W[:, d.nw - nc:], where="simulate (the currents the voltages drive)")
    return SimulationResult(
        time_s=times, gaps_m=W[:, d.n_diff:d.n_diff + ng], gap_rates_m_per_s=rates,
        voltages_V=held_U, currents_A=W[:, d.nw - nc:],
        flux_linkage_Wb=O[:, nb:nb + nc], eta_Wb=O[:, nb + nc:nb + 2 * nc],
        pole_force_N=O[:, nb + 2 * nc:nb + 2 * nc + ng],
        force_N=O[:, nb + 2 * nc:nb + 2 * nc + ng].sum(axis=1),
        branch_flux_Wb=O[:, :nb], eddy_flux_Wb=O[:, :nb][:, d.eddy_idx],
        eddy_mmf_A=O[:, nb + 2 * nc + ng:], differential_state=W[:, :d.n_diff],
        electrical_energy_J=E[:, 0], ohmic_loss_J=E[:, 1], eddy_loss_J=E[:, 2],
        mechanical_work_J=E[:, 3], gap_names=net.gap_names, circuit_names=net.circuit_names,
        branch_names=net.branch_names, eddy_branch_names=fm.eddy_branch_names,
        final_state=final, network=net,
    )

