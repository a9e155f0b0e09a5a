"""Static solution of the equivalent magnetic circuit (paper Sec. III, eq. 5 with eta' = 0).

Given gaps ``s`` and circuit currents ``I`` the loop law ``C (V_m(C^T x, s) - N I) = 0``
is solved for the loop fluxes ``x`` by Newton's method (CasADi rootfinder with line
search), starting from the solution of the same network with unsaturated iron; points
that do not converge are retried by continuation in the current from zero.

Derived quantities are exact (implicit function theorem, no finite differences)::

    J      = dr/dx = C diag(dV_m/dphi) C^T
    dx/dI  = J^-1 C N            dx/ds = -J^-1 dr/ds
    psi    = N^T C^T x           dpsi/dI = N^T C^T dx/dI (differential inductance)
    F_k    = dW_gap/ds_k |phi    (= -dW'/ds_k |I, co-energy force; attraction > 0)
    dF/dI  = dF/dx dx/dI         (reciprocity: dF_k/dI_j = -dpsi_j/ds_k)
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..circuit.assembly import assemble
from ..circuit.network import Network
from ..errors import InputError, SolverError
from ..magnets.base import PlausibleRange
from ..materials import MU0
from ..validation import describe, flag, real_array, real_number, renamed_keywords
from .inputs import per_name_values

__all__ = [
    "StaticSolution",
    "circuit_pole_groups",
    "pole_groups_from_sensitivities",
    "solve_statics",
    "magnetic_energy",
    "coenergy",
    "pole_force_eq6",
    "as_network",
    "plausible_range",
    "gap_vector",
    "current_vector",
]

# Convergence test on the scaled loop residual max|r| / (1 + sum|N I|): Newton reaches
# ~1e-15 in double precision; 1e-9 leaves room for ill-conditioned deep saturation.
_RESIDUAL_TOL = 1e-9


def as_network(model: Any) -> Network:
    """The :class:`Network` of a model (a Network, or anything with a ``network`` attribute).

    Parameters
    ----------
    model : Network, Magnet, FluxModel or CurrentModel
        The model.

    Returns
    -------
    Network

    Raises
    ------
    InputError
        ``model`` is a name or path (load it with ``load_magnet`` first) or another
        object without an equivalent circuit.
    """
    if isinstance(model, Network):
        return model
    net = getattr(model, "network", None)
    if isinstance(net, Network):
        return net
    if isinstance(model, (str, os.PathLike)):
        raise InputError(f"model = {str(model)!r} is a name or path, not a magnet; load it "
                         f"first: magnet = maglevkit.load_magnet({str(model)!r})")
    raise InputError(f"model = {describe(model)}: expected a Magnet (maglevkit.load_magnet), "
                     "a FluxModel or a Network")


def plausible_range(model: Any) -> PlausibleRange | None:
    """The model's :class:`~maglevkit.magnets.base.PlausibleRange` (None if it has none).

    A Magnet has one from its geometry, a FluxModel keeps that of the magnet it was
    built from; a bare Network has none.

    Parameters
    ----------
    model : object
        A Magnet, model or Network.

    Returns
    -------
    PlausibleRange or None
    """
    rng = getattr(model, "plausible_range", None)
    return rng if isinstance(rng, PlausibleRange) else None


def gap_vector(network: Network, gaps: Any) -> np.ndarray:
    """Validated gaps [m] as an array (..., n_gaps); scalar means all gaps equal.

    Parameters
    ----------
    network : Network
        Gives the gap names.
    gaps : float, mapping or array_like
        Gaps [m], > 0: a scalar, ``{gap name: value}`` with every name, or an array
        whose last axis has one entry per gap input.

    Returns
    -------
    ndarray (..., n_gaps)

    Raises
    ------
    InputError
        Non-numbers, non-finite values, gaps <= 0, wrong shapes, unknown or missing
        names.
    """
    arr = per_name_values(gaps, tuple(network.gap_names), "gaps", "m", kind="gap",
                          leading=True)
    if np.any(arr <= 0.0):
        bad = float(arr[arr <= 0.0].ravel()[0])
        raise InputError(f"gap = {bad!r} m is not allowed; gaps must be > 0 m "
                         "(the magnet would touch or penetrate the rail)")
    return arr


def current_vector(network: Network, currents: Any) -> np.ndarray:
    """Validated circuit currents [A] as an array (..., n_circuits).

    Parameters
    ----------
    network : Network
        Gives the circuit names.
    currents : float, mapping or array_like
        Currents [A]: a scalar (every circuit), ``{circuit name: value}`` with every
        name, or an array whose last axis has one entry per circuit.

    Returns
    -------
    ndarray (..., n_circuits)

    Raises
    ------
    InputError
        Non-numbers, non-finite values, wrong shapes, unknown or missing names.
    """
    return per_name_values(currents, tuple(network.circuit_names), "circuit currents", "A",
                           leading=True)


@dataclass(frozen=True)
class StaticSolution:
    """Static operating point(s) of a magnet.

    All arrays have a leading batch shape ``shape`` (``()`` for a single point,
    ``(n_gaps, n_currents)`` for ``grid=True``), then the named axis given in the
    field's description.

    Attributes
    ----------
    gap_names : tuple of str
        Names of the gap inputs (last axis of ``gaps_m``, ``pole_force_N``).
    circuit_names : tuple of str
        Names of the circuits (last axis of ``currents_A``, ``flux_linkage_Wb``).
    branch_names : tuple of str
        Names of the network branches (last axis of ``branch_flux_Wb``).
    gaps_m : ndarray (..., n_gaps)
        Gap inputs [m].
    currents_A : ndarray (..., n_circuits)
        Circuit currents [A].
    loop_flux_Wb : ndarray (..., n_loops)
        Loop fluxes [Wb] (the solver's unknowns).
    branch_flux_Wb, branch_flux_density_T : ndarray (..., n_branches)
        Branch fluxes [Wb] and flux densities [T] (NaN where a branch has no area).
    pole_force_N : ndarray (..., n_gaps)
        Force per gap input [N], attraction positive, from the network co-energy.
    force_N : ndarray (...)
        Total force [N].
    flux_linkage_Wb : ndarray (..., n_circuits)
        ``psi = N^T phi`` [Wb].
    apparent_inductance_H : ndarray (..., n_circuits)
        ``psi / I`` [H] (NaN where the circuit current is 0).
    differential_inductance_H : ndarray (..., n_circuits, n_circuits)
        ``dpsi_i / dI_j`` [H] (symmetric).
    dpsi_dgap_Wb_per_m : ndarray (..., n_circuits, n_gaps)
        ``dpsi_i / ds_k`` [Wb/m].
    dforce_dcurrent_N_per_A : ndarray (..., n_gaps, n_circuits)
        ``dF_k / dI_j`` [N/A]; reciprocity gives ``-dpsi_j/ds_k``.
    dforce_dgap_N_per_m : ndarray (..., n_gaps, n_gaps)
        ``dF_k / ds_l`` at constant currents [N/m].
    """

    gap_names: tuple[str, ...]
    circuit_names: tuple[str, ...]
    branch_names: tuple[str, ...]
    gaps_m: np.ndarray
    currents_A: np.ndarray
    loop_flux_Wb: np.ndarray
    branch_flux_Wb: np.ndarray
    branch_flux_density_T: np.ndarray
    pole_force_N: np.ndarray
    force_N: np.ndarray
    flux_linkage_Wb: np.ndarray
    apparent_inductance_H: np.ndarray
    differential_inductance_H: np.ndarray
    dpsi_dgap_Wb_per_m: np.ndarray
    dforce_dcurrent_N_per_A: np.ndarray
    dforce_dgap_N_per_m: np.ndarray

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.force_N.shape)

    # Quantities along the "same current in every circuit, same gap at every pole" ray.
    @property
    def common_differential_inductance_H(self) -> np.ndarray:
        """``dpsi_i/dI`` [H] when all circuits carry the same current (..., n_circuits)."""
        return self.differential_inductance_H.sum(axis=-1)

    @property
    def common_dpsi_dgap_Wb_per_m(self) -> np.ndarray:
        """``dpsi_i/ds`` [Wb/m] when all gaps move together (..., n_circuits)."""
        return self.dpsi_dgap_Wb_per_m.sum(axis=-1)

    def branch_flux(self, name: str) -> np.ndarray:
        """Flux [Wb] of the named branch (batch shape).

        Parameters
        ----------
        name : str
            Branch name, one of :attr:`branch_names`.

        Returns
        -------
        ndarray (...)
            Branch flux [Wb], of batch shape :attr:`shape`.

        Raises
        ------
        InputError
            ``name`` is not one of :attr:`branch_names`.
        """
        names = list(self.branch_names)
        if not isinstance(name, str) or name not in names:
            raise InputError(f"branch_flux: name = {name!r} is no branch of this network; "
                             f"allowed: {', '.join(names)}")
        return self.branch_flux_Wb[..., names.index(name)]


class _StaticSolver:
    """Compiled CasADi functions for the statics of one network (cached on it)."""

    def __init__(self, network: Network) -> None:
        eq = assemble(network)
        self.network = network
        self.eq = eq
        x, s, I = eq.x, eq.s, eq.I
        nl = eq.n_loops
        scale = 1.0 + ca.sum1(ca.fabs(ca.mtimes(ca.DM(eq.N), I)))
        p = ca.vertcat(s, I)
        resid_fun = ca.Function("r", [x, p], [eq.residual / scale])
        self.rootfinder = ca.rootfinder(
            "statics_newton", "newton", resid_fun,
            {"abstol": 1e-13, "abstolStep": 1e-16, "max_iter": 80, "error_on_fail": False,
             "line_search": True, "show_eval_warnings": False},
        )
        self.residual_fun = resid_fun

        # Initial guess: the same network with unsaturated iron (linear in x).
        lin = assemble(network.with_options(saturation=False, eddy_currents=False))
        r_lin = ca.Function("rlin", [lin.x, lin.s, lin.I], [lin.residual])
        jac_lin = ca.Function("jlin", [lin.x, lin.s, lin.I], [ca.jacobian(lin.residual, lin.x)])
        xm, sm, Im = ca.MX.sym("x", nl), ca.MX.sym("s", eq.n_gaps), ca.MX.sym("I", eq.n_circuits)
        zero = ca.MX.zeros(nl)
        x_lin = -ca.solve(jac_lin(zero, sm, Im), r_lin(zero, sm, Im))
        self.initial_guess = ca.Function("x_lin", [sm, Im], [x_lin])

        # Exact derived quantities at a solution x (implicit function theorem).
        J = ca.jacobian(eq.residual, x)
        dr_dI = ca.jacobian(eq.residual, I)
        dr_ds = ca.jacobian(eq.residual, s)
        post_in = ca.Function("post_in", [x, s, I],
                              [J, dr_dI, dr_ds, eq.phi, eq.psi, eq.force,
                               ca.jacobian(eq.force, x), ca.jacobian(eq.force, s)])
        Jm, dIm, dsm, phim, psim, fm, dfdx, dfds = post_in(xm, sm, Im)
        dx_dI = -ca.solve(Jm, dIm)
        dx_ds = -ca.solve(Jm, dsm)
        NC = ca.DM(eq.N.T @ eq.C.T)
        post = [phim, psim, fm, ca.mtimes(NC, dx_dI), ca.mtimes(NC, dx_ds),
                ca.mtimes(dfdx, dx_dI), dfds + ca.mtimes(dfdx, dx_ds)]
        self.post = ca.Function("statics_post", [xm, sm, Im], post)
        pm = ca.vertcat(sm, Im)
        xs = self.rootfinder(self.initial_guess(sm, Im), pm)
        res = ca.mmax(ca.fabs(resid_fun(xs, pm)))
        self.point = ca.Function("statics_point", [sm, Im], [xs, res, *self.post(xs, sm, Im)])
        xg = ca.MX.sym("xg", nl)
        xw = self.rootfinder(xg, pm)
        self.point_from = ca.Function("statics_from", [xg, sm, Im],
                                      [xw, ca.mmax(ca.fabs(resid_fun(xw, pm)))])
        self._maps: dict[int, ca.Function] = {}

    def batch(self, s: np.ndarray, I: np.ndarray) -> list[np.ndarray]:
        """Solve m points: ``s`` (n_gaps, m), ``I`` (n_c, m)."""
        m = s.shape[1]
        f = self._maps.get(m)
        if f is None:
            f = self.point.map(m, "thread", 2) if m > 1 else self.point
            if len(self._maps) > 16:
                self._maps.clear()
            self._maps[m] = f
        try:
            out = [np.asarray(v) for v in f(s, I)]
        except RuntimeError as exc:
            raise self._evaluation_error(exc, s, I) from None
        res = out[1].ravel()
        # a NaN state can come with a residual of -inf (which is <= the tolerance)
        bad = np.nonzero(~(np.abs(res) <= _RESIDUAL_TOL)
                         | ~np.isfinite(out[0]).all(axis=0))[0]
        for j in (int(v) for v in bad):
            xj = self._continuation(s[:, j], I[:, j])
            outs = self.post(xj, s[:, j], I[:, j])
            out[0][:, j] = np.asarray(xj).ravel()
            out[1][..., j] = 0.0
            for k, v in enumerate(outs):
                arr = np.asarray(v)
                _assign_column(out[2 + k], arr, j, m)
        finite = np.ones(m, dtype=bool)
        for v in out[2:]:   # the results (flux, force, derivatives) of every point
            finite &= np.isfinite(v.reshape(v.shape[0], m, -1)).all(axis=(0, 2))
        if not finite.all():
            j = int(np.argmin(finite))
            raise SolverError(
                f"the network equations of {self.network.name!r} gave a non-finite result "
                "(NaN or inf); check the magnet's dimensions and the operating point for "
                "absurd values", state=self._point_state(s[:, j], I[:, j]),
                reason="non-finite flux, force or derivative")
        return out

    def _point_state(self, s: np.ndarray, I: np.ndarray) -> dict[str, float]:
        state = dict(zip((f"gap[{g}]" for g in self.network.gap_names), s, strict=True))
        state.update(zip((f"I[{c}]" for c in self.network.circuit_names), I, strict=True))
        return state

    def _evaluation_error(self, exc: RuntimeError, s: np.ndarray, I: np.ndarray) -> SolverError:
        """SolverError for a failed evaluation of the compiled network equations.

        CasADi stops with "Evaluation failed" when the equations produce non-finite
        numbers (e.g. iron paths or permeances of absurd size); the first point that
        fails on its own is reported.
        """
        point = 0
        for j in range(s.shape[1]):
            try:
                self.point(s[:, j], I[:, j])
            except RuntimeError:
                point = j
                break
        state = dict(zip((f"gap[{g}]" for g in self.network.gap_names), s[:, point],
                         strict=True))
        state.update(zip((f"I[{c}]" for c in self.network.circuit_names), I[:, point],
                         strict=True))
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        reason = lines[-1] if lines else type(exc).__name__
        return SolverError(
            f"the network equations of {self.network.name!r} could not be evaluated (non-finite "
            "numbers); check the magnet's dimensions and materials for absurd values",
            state=state, reason=reason[:300])

    def _continuation(self, s: np.ndarray, I: np.ndarray) -> np.ndarray:
        """Newton continuation in the current from 0 to I; raises SolverError on failure."""
        lam, step = 0.0, 0.1
        x = np.zeros(self.eq.n_loops)
        reason = "step size fell below 1e-6 of the target current"
        while lam < 1.0:
            target = min(1.0, lam + step)
            xn, res = self.point_from(x, s, target * I)
            if float(res) <= _RESIDUAL_TOL:
                x, lam = np.asarray(xn).ravel(), target
                step = min(step * 2.0, 0.5)
            else:
                step *= 0.5
                if step < 1e-6:
                    break
        else:
            return x
        state = dict(zip((f"gap[{g}]" for g in self.network.gap_names), s, strict=True))
        state.update(zip((f"I[{c}]" for c in self.network.circuit_names), I, strict=True))
        raise SolverError("static network solution did not converge", state=state,
                          reason=f"{reason} (reached {lam:.3g} of the current)")


def _assign_column(dst: np.ndarray, src: np.ndarray, j: int, m: int) -> None:
    # CasADi maps return horizontally concatenated blocks: (rows, m * cols).
    cols = src.shape[1] if src.ndim == 2 else 1
    dst[:, j * cols:(j + 1) * cols] = src.reshape(dst.shape[0], cols)


#: Statics solvers of the networks built last in this process, by the network's name, repr
#: (its every element, material and parameter) and loop matrix (the basis its unknowns are
#: in): an equal network loaded again (a magnet file read twice, each CLI command in one
#: session) reuses the solver instead of building it anew (TR09 split: ~2.5 s of CasADi per
#: build).  Networks holding CasADi symbols are not shared (equal reprs, other symbols).
_SHARED_SOLVERS: dict[tuple[str, str, str], _StaticSolver] = {}
_SHARED_SOLVERS_MAX = 8


def _solver(network: Network) -> _StaticSolver:
    solver = network.cache.get("statics")
    if solver is None:
        import hashlib

        text = repr((network.branches, network.circuits))
        loops = np.ascontiguousarray(network.loop_matrix, dtype=float)
        key = (network.name, text,
               f"{loops.shape}" + hashlib.sha256(loops.tobytes()).hexdigest())
        shared = "SX(" not in text and "MX(" not in text
        solver = _SHARED_SOLVERS.pop(key, None) if shared else None
        if solver is None:
            solver = _StaticSolver(network)
        if shared:
            _SHARED_SOLVERS[key] = solver          # the most recent last
            while len(_SHARED_SOLVERS) > _SHARED_SOLVERS_MAX:
                del _SHARED_SOLVERS[next(iter(_SHARED_SOLVERS))]
        network.cache["statics"] = solver
    return solver


@renamed_keywords(gaps="gaps_m", currents="currents_A")
def solve_statics(model: Any, *, gaps_m: Any, currents_A: Any,
                  grid: bool = False) -> StaticSolution:
    """Solve the magnet's statics at given gaps and circuit currents.

    Parameters
    ----------
    model : Network or magnet
        The equivalent magnetic circuit (or an object with a ``network``).
    gaps_m : float, mapping or array_like
        Gaps [m]: a scalar (all gap inputs equal), a mapping ``{gap name: value}``, or
        an array whose last axis runs over the gap inputs.  With ``grid=True``: a 1-D
        array of uniform gaps.  (Deprecated alias: ``gaps``.)
    currents_A : float, mapping or array_like
        Circuit currents [A], in the same forms (per circuit).  With ``grid=True``: a
        1-D array of currents applied to every circuit.  (Deprecated alias: ``currents``.)
    grid : bool
        Solve on the outer product ``gaps_m x currents_A`` (batch shape ``(n_s, n_I)``).

    Returns
    -------
    StaticSolution

    Raises
    ------
    InputError
        Inputs that are not real finite numbers (bools and strings included), gaps
        <= 0, wrong shapes or names, ``grid`` not True/False, or a ``model`` that is not
        a magnet or network (e.g. a name: load it with ``load_magnet``).
    SolverError
        If Newton's method and the continuation fallback both fail, or the network
        equations cannot be evaluated (non-finite numbers).

    Warns
    -----
    PlausibilityWarning
        With a Magnet (or a FluxModel of one): gaps or currents far outside the
        magnet's physical range (:class:`~maglevkit.magnets.base.PlausibleRange`).
    """
    net = as_network(model)
    ng, nc = len(net.gap_names), len(net.circuit_names)
    if flag(grid, "grid"):
        g1 = real_array(gaps_m, "gaps", "m")
        c1 = real_array(currents_A, "currents", "A")
        if g1.ndim != 1 or c1.ndim != 1:
            raise InputError("with grid=True, gaps and currents must be 1-D arrays "
                             f"(got shapes {g1.shape} and {c1.shape})")
        sv = gap_vector(net, np.repeat(g1[:, None], ng, axis=1))
        iv = current_vector(net, np.repeat(c1[:, None], nc, axis=1))
        sv = np.broadcast_to(sv[:, None, :], (g1.size, c1.size, ng))
        iv = np.broadcast_to(iv[None, :, :], (g1.size, c1.size, nc))
    else:
        sv = gap_vector(net, gaps_m)
        iv = current_vector(net, currents_A)
        shape = np.broadcast_shapes(sv.shape[:-1], iv.shape[:-1])
        sv = np.broadcast_to(sv, (*shape, ng))
        iv = np.broadcast_to(iv, (*shape, nc))
    batch = sv.shape[:-1]
    m = int(np.prod(batch)) if batch else 1
    s2 = np.ascontiguousarray(sv.reshape(m, ng).T)
    i2 = np.ascontiguousarray(iv.reshape(m, nc).T)
    if m == 0:
        raise InputError("empty set of operating points")
    rng = plausible_range(model)
    if rng is not None:
        rng.check(gaps_m=sv, currents_A=iv, where="solve_statics")
    solver = _solver(net)
    x, _res, phi, psi, f, dpsi_di, dpsi_ds, df_di, df_ds = solver.batch(s2, i2)
    nb = len(net.branches)

    def per_point(a: np.ndarray, rows: int, cols: int | None = None) -> np.ndarray:
        if cols is None:
            return a.reshape(rows, m).T.reshape(*batch, rows)
        return a.reshape(rows, m, cols).transpose(1, 0, 2).reshape(*batch, rows, cols)

    phi_b = per_point(phi, nb)
    psi_c = per_point(psi, nc)
    pole = per_point(f, ng)
    with np.errstate(divide="ignore", invalid="ignore"):
        app = np.where(iv != 0.0, psi_c / np.where(iv != 0.0, iv, 1.0), np.nan)
    return StaticSolution(
        gap_names=net.gap_names,
        circuit_names=net.circuit_names,
        branch_names=net.branch_names,
        gaps_m=np.array(sv),
        currents_A=np.array(iv),
        loop_flux_Wb=per_point(x, solver.eq.n_loops),
        branch_flux_Wb=phi_b,
        branch_flux_density_T=phi_b / net.branch_areas,
        pole_force_N=pole,
        force_N=pole.sum(axis=-1),
        flux_linkage_Wb=psi_c,
        apparent_inductance_H=app,
        differential_inductance_H=per_point(dpsi_di, nc, nc),
        dpsi_dgap_Wb_per_m=per_point(dpsi_ds, nc, ng),
        dforce_dcurrent_N_per_A=per_point(df_di, ng, nc),
        dforce_dgap_N_per_m=per_point(df_ds, ng, ng),
    )


@renamed_keywords(branch_flux="branch_flux_Wb", gaps="gaps_m")
def magnetic_energy(model: Any, branch_flux_Wb: Any, gaps_m: Any) -> float:
    """Stored magnetic energy ``W = sum_elements integral_0^phi V_m dphi`` [J] at one point.

    Iron energies are integrated numerically from the material law (relative accuracy
    ~1e-13); air and leakage parts are exact.

    Parameters
    ----------
    model : Magnet, FluxModel or Network
        The equivalent magnetic circuit (or a model with a ``network``).
    branch_flux_Wb : array_like (n_branches,)
        Flux of every branch [Wb], in :attr:`Network.branch_names` order (e.g.
        ``StaticSolution.branch_flux_Wb`` of a single point; deprecated alias
        ``branch_flux``).
    gaps_m : float, mapping or array_like (n_gaps,)
        Gaps [m], > 0: a scalar (all equal), ``{gap name: value}`` or one per gap input
        (deprecated alias ``gaps``).

    Returns
    -------
    float
        W [J].

    Raises
    ------
    InputError
        A model without a network, non-finite fluxes or a wrong number of them, gaps
        <= 0 or of the wrong shape or names.
    """
    net = as_network(model)
    phi = real_array(branch_flux_Wb, "branch_flux", "Wb").ravel()
    if phi.size != len(net.branches):
        raise InputError(f"branch_flux must have {len(net.branches)} entries, got {phi.size}")
    s = gap_vector(net, gaps_m)
    gidx = {g: i for i, g in enumerate(net.gap_names)}
    total = 0.0
    for k, br in enumerate(net.branches):
        for el in br.elements:
            gap = None if el.gap is None else float(s[gidx[el.gap]])
            total += float(el.energy(phi[k], gap))
    return total


@renamed_keywords(gaps="gaps_m", currents="currents_A")
def coenergy(model: Any, *, gaps_m: Any, currents_A: Any) -> float:
    """Magnetic co-energy ``W' = I^T psi - W`` [J] at one operating point.

    Parameters
    ----------
    model : Magnet, FluxModel or Network
        The equivalent magnetic circuit (or a model with a ``network``).
    gaps_m : float, mapping or array_like (n_gaps,)
        Gaps [m], > 0 (keyword only; forms as in :func:`solve_statics`; deprecated
        alias ``gaps``).
    currents_A : float, mapping or array_like (n_circuits,)
        Circuit currents [A] (keyword only; deprecated alias ``currents``).

    Returns
    -------
    float
        W' [J].

    Raises
    ------
    InputError
        Bad inputs (see :func:`solve_statics`), or more than one operating point.
    SolverError
        If the statics cannot be solved.
    """
    sol = solve_statics(model, gaps_m=gaps_m, currents_A=currents_A)
    if sol.shape != ():
        raise InputError("coenergy takes a single operating point")
    w = magnetic_energy(model, sol.branch_flux_Wb, sol.gaps_m)
    return float(sol.currents_A @ sol.flux_linkage_Wb) - w


@renamed_keywords(flux="flux_Wb", area="area_m2")
def pole_force_eq6(flux_Wb: Any, area_m2: float, mu_r: float = math.inf) -> Any:
    """The paper's pole force, eq. 6: ``F = (mu_r - 1) / (2 mu_r mu0 A) phi_F^2`` [N].

    Parameters
    ----------
    flux_Wb : float or ndarray
        Flux through the pole face contributing to the force, ``phi_F`` [Wb] (deprecated
        alias ``flux``).
    area_m2 : float
        Pole face area ``A`` [m^2] (deprecated alias ``area``).
    mu_r : float
        Relative permeability of the iron (``inf``: ``phi^2 / (2 mu0 A)``), dimensionless.

    Returns
    -------
    float or ndarray
        Pole force [N].
    """
    phi = real_array(flux_Wb, "flux", "Wb")
    a = real_number(area_m2, "area", "m^2", positive=True)
    if isinstance(mu_r, (int, float)) and not isinstance(mu_r, bool) and math.isinf(mu_r) \
            and mu_r > 0:
        factor = 1.0
    else:
        mu = real_number(mu_r, "mu_r")
        if mu < 1.0:
            raise InputError(f"mu_r = {mu_r!r}: a relative permeability must be >= 1 (or inf)")
        factor = (mu - 1.0) / mu
    return factor * phi ** 2 / (2.0 * MU0 * a)


@renamed_keywords(gap="gap_m", current="current_A")
def circuit_pole_groups(model: Any, *, gap_m: float,
                        current_A: float) -> dict[str, tuple[str, ...]]:
    """Assign each gap input (pole) to the circuit whose flux linkage depends most on it.

    Parameters
    ----------
    model : Magnet, FluxModel or Network
        The equivalent magnetic circuit (or a model with a ``network``).
    gap_m : float
        Gap of every pole [m], > 0, at which ``dpsi/ds`` is evaluated (keyword only;
        deprecated alias ``gap``).
    current_A : float
        Current of every circuit [A] (keyword only; deprecated alias ``current``).

    Returns
    -------
    dict of str to tuple of str
        Circuit name -> the gap inputs it drives.  With one circuit: every gap, without
        solving the statics.

    Raises
    ------
    InputError
        A circuit that drives no pole of its own (the current-based model needs one
        substitute gap per circuit), or bad inputs.
    SolverError
        If the statics cannot be solved.
    """
    net = as_network(model)
    if len(net.circuits) == 1:
        return {net.circuit_names[0]: net.gap_names}
    sol = solve_statics(net, gaps_m=gap_m, currents_A=current_A)
    return pole_groups_from_sensitivities(sol.dpsi_dgap_Wb_per_m, net.circuit_names,
                                          net.gap_names)


def pole_groups_from_sensitivities(dpsi_dgap_Wb_per_m: np.ndarray, circuit_names: Sequence[str],
                                   gap_names: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """The rule of :func:`circuit_pole_groups` on given sensitivities: each pole (gap input)
    belongs to the circuit ``argmax_j |dpsi_j/ds_k|``.

    Parameters
    ----------
    dpsi_dgap_Wb_per_m : ndarray (n_circuits, n_gaps)
        ``dpsi_j/ds_k`` [Wb/m] at one operating point.
    circuit_names, gap_names : sequence of str

    Raises
    ------
    InputError
        A circuit that drives no pole of its own.
    """
    owner = np.argmax(np.abs(np.asarray(dpsi_dgap_Wb_per_m)), axis=0)   # (n_gaps,)
    groups = {c: tuple(g for g, o in zip(gap_names, owner, strict=True) if o == j)
              for j, c in enumerate(circuit_names)}
    empty = [c for c, g in groups.items() if not g]
    if empty:
        raise InputError(f"circuit(s) {empty} drive no pole of their own; the current-based model "
                         "needs one substitute gap per circuit")
    return groups
