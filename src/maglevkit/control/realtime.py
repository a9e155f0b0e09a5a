"""Real-time iteration of the offset-free NMPC: condensed QP, compiled, dense active set.

:class:`RealTimeMPC` solves the same optimal control problem as
:class:`~maglevkit.control.mpc.OffsetFreeMPC` with ``solver="rti"`` (one Gauss-Newton QP
per sample at the shifted previous solution) and gives the same QP solution; it only
computes it faster (docs/control.md, "Real-time iteration"):

* one compiled function per sample (CasADi code generation, ``cc -O3``, disk cache) does
  the EKF step (the observer's own symbolic step), the target calculation (a fixed number
  of Newton steps, checked; the Python Newton of :meth:`MagnetHeaveModel.steady_state`
  takes over if they did not converge), the shifted previous solution and the QP data at
  that linearisation point, from the same CasADi expressions (``OffsetFreeMPC._problem``:
  eq. 8 + mechanics, RK4, the interval Jacobians by AD); only the RK4 maps read the
  maps' table, everything else is expanded to scalar code;
* the QP is *condensed* in that function: the linearised dynamics
  ``dx_k+1 = A_k dx_k + B_k du_k + c_k`` eliminate the state steps, ``dw = E z + e`` with
  ``z = [du_k, de_k]_k``, leaving a dense, strictly convex QP in ``N (n_u + 1)`` variables
  (Hessian ``E' H E``; general constraints: the soft state constraints and the maps'
  state bounds);
* the same compiled call solves that QP for the guessed active set "every slack at its
  lower bound, nothing else active" (a Cholesky factorisation of the input steps'
  Hessian) and checks the optimality conditions; where they hold, that point *is* the
  unique solution of the strictly convex QP, applied to the decision vector in the same
  call; otherwise the compiled QP data function gives that QP again and qpOASES (shipped
  in the casadi wheel, hot-started) solves it, called through preallocated buffers;
* two buffer sets alternate between samples (the outputs of one are bound as the inputs
  of the next), so that Python copies only the measurement in and the voltages out.

With ``linearization="target"`` the intervals after the first are linearised at the
steady-state target instead of the previous solution (two RK4 maps per sample instead of
``N``; the vehicle's default).

:class:`RealTimeMPCBatch` updates many such controllers (one per vehicle circuit) with one
compiled call per sample, evaluating each controller's own prepare function; a single
controller's :meth:`RealTimeMPC.update` is a batch of one.

The full Gauss-Newton SQP, the sparse reference RTI and the IPOPT peer stay in
:class:`OffsetFreeMPC` as the references (tests/test_mpc_realtime.py compares them).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import time
from collections.abc import Iterator, Mapping
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ParameterError, SolverError
from ..models.compiled import BoundCall
from .interface import Measurement
from .model import MagnetHeaveModel
from .mpc import MPCWeights, OffsetFreeMPC

__all__ = ["DENSE_QP_SOLVERS", "GUESS_TOLERANCE", "LINEARIZATIONS", "RealTimeMPC",
           "RealTimeMPCBatch", "vector_flags"]

#: where :class:`RealTimeMPC`'s QP linearises the prediction (every node of the previous
#: solution, or interval 0 at its node and the rest at the steady-state target)
LINEARIZATIONS = ("trajectory", "target")

#: conic solvers of the casadi wheel tried on the condensed QP (docs/decisions.md)
DENSE_QP_SOLVERS = ("qpoases", "daqp", "qrqp", "proxqp", "osqp")

#: tolerance [scaled units: 100 V, 10 A, 1 mm, 10 mm/s; slacks] of the optimality check of
#: the compiled active-set guess (its Cholesky solution is exact to rounding, ~1e-14;
#: 1e-9 x 100 V = 1e-7 V is below anything the chopper resolves)
GUESS_TOLERANCE = 1e-9

#: Newton steps of the compiled target calculation (from the previous target: measured
#: 2-3 steps to a step below 1e-10 A; 6 leave margin, each costs ~0.1 us)
_NEWTON_STEPS = 6

#: The compiled target counts as converged when its residual is below this fraction of the
#: target current (at least 1 A): 1e-10 relative, a few Newton steps past rounding
_TARGET_RESIDUAL = 1e-10

#: Relative slack on the voltage limit before a QP solution counts as violating it (the
#: QP solvers' tolerance; within it the voltage is clipped to the limit)
_LIMIT_SLACK = 1e-6


def vector_flags() -> tuple[str, ...]:
    """C compiler flags of the compiled controller batch and of the vehicles' compiled
    steps: the default optimised shared library, this machine's vector instructions (the
    bank's SIMD lanes' own target, :func:`maglevkit.reduced.lanes.lane_target`: AVX2 where
    the processor has it) and no contraction of products and sums into fused
    multiply-adds, so that the results are the same bits as without the vector flags (the
    compiler vectorises only where the order of every sum stays; measured on the
    3-section train's block: 10.5 -> 8.2 us per step, bit-identical).

    Returns
    -------
    tuple of str
        Flags for :func:`~maglevkit.models.compiled.compile_library` and
        :func:`~maglevkit.models.compiled.compile_linked` (part of their cache key).
    """
    from ..models.compiled import DEFAULT_FLAGS
    from ..reduced.lanes import lane_target

    return (*DEFAULT_FLAGS, "-ffp-contract=off", *lane_target()[2])


@contextlib.contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence the C-level standard output (file descriptor 1) for a moment."""
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:           # no file descriptor 1 (embedded interpreters)
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


class RealTimeMPC(OffsetFreeMPC):
    """The offset-free NMPC's real-time iteration, real-time capable (same QP solution as
    ``OffsetFreeMPC(solver="rti")``).

    Parameters
    ----------
    model, gap_ref_m, sample_time_s, horizon, interval_s, substeps
        As :class:`~maglevkit.control.mpc.OffsetFreeMPC` (model, reference [m], sample
        time [s], horizon, interval [s], RK4 steps per interval).
    voltage_limit_V, min_gap_m, max_current_A, weights, observer_options, initial_estimate
        As :class:`~maglevkit.control.mpc.OffsetFreeMPC` (voltage limit [V], soft
        constraints [m], [A], weights, EKF options, initial ``[x; d]``).
    qp_solver : str
        Dense QP solver of the condensed QP where the compiled active-set guess is not its
        solution, one of :data:`DENSE_QP_SOLVERS` (default qpOASES, hot-started; the
        others for comparison).
    linearization : {"trajectory", "target"}
        Where the QP linearises the prediction model.  ``"trajectory"`` (default): every
        interval at its node of the shifted previous solution (the real-time iteration;
        the QP of ``OffsetFreeMPC(solver="rti")``).  ``"target"``: the first interval at
        its node (the current estimate and the warm-started first voltage), the others
        at the steady-state target ``(x_t, u_t)`` (one Jacobian for intervals 1..N-1,
        affine predictions there): two RK4 evaluations per sample instead of ``N``
        (docs/control.md, "Real-time iteration").

    Notes
    -----
    The functions are compiled with the model's ``compiled`` mode (disk cache, see
    :func:`~maglevkit.models.compiled.compile_library`) when the controller is first
    reset (its batch of one) or batched; the first build of a new law takes a compile of
    a few seconds to a few minutes.
    """

    #: the prepare law's QP data, guess and step in one scalar-code function
    #: (:meth:`_solve_function`); False: the separate functions (for comparisons)
    _FUSED = True

    def __init__(self, model: MagnetHeaveModel, *, gap_ref_m: float, sample_time_s: float,
                 horizon: int = 20, interval_s: float | None = None, substeps: int = 1,
                 qp_solver: str = "qpoases", voltage_limit_V: float = 440.0,
                 min_gap_m: float | None = None, max_current_A: float | None = None,
                 weights: MPCWeights | None = None, observer_options: Mapping[str, Any] | None = None,
                 initial_estimate: Any = None, linearization: str = "trajectory") -> None:
        if qp_solver not in DENSE_QP_SOLVERS:
            raise ParameterError(f"qp_solver = {qp_solver!r}; the condensed QP takes one of "
                                 f"{list(DENSE_QP_SOLVERS)}")
        if linearization not in LINEARIZATIONS:
            raise ParameterError(f"linearization = {linearization!r}; use one of "
                                 f"{list(LINEARIZATIONS)}")
        self.linearization = linearization
        self._dense_solver = qp_solver
        super().__init__(model, gap_ref_m=gap_ref_m, sample_time_s=sample_time_s,
                         horizon=horizon, interval_s=interval_s, substeps=substeps,
                         solver="rti", qp_solver="qrqp", voltage_limit_V=voltage_limit_V,
                         min_gap_m=min_gap_m, max_current_A=max_current_A, weights=weights,
                         observer_options=observer_options, initial_estimate=initial_estimate)
        self.qp_solver = qp_solver
        self._finish_build()

    # ------------------------------------------------------------------ build
    def _build(self, substeps: int) -> None:
        """The condensed QP data function, the target function and the dense QP solver
        (replaces the sparse QP of :class:`OffsetFreeMPC`)."""
        m = self.model
        nx, nu, nd, N = m.nx, m.nu, m.nd, self.horizon
        xN, nw, blk = self._layout()
        self._np = 2 * nx + nd + nu
        self._lbw, self._ubw, self._lbg, self._ubg = self._bounds()
        nzs = nu + 1                                  # free variables per stage [U_k, e_k]
        nz = N * nzs
        w = ca.MX.sym("w", nw)
        p = ca.MX.sym("p", self._np)
        T = ca.MX.sym("table", m.table.size)
        Fd = m.discrete(self.interval_s, substeps, jacobians=True)
        # the intervals' (x_k+1, A_k, B_k) enter the QP data as symbols: everything below
        # is table-free and expanded to scalar code (straight-line C, every structural zero
        # skipped); _interval_blocks computes them from the maps
        def block(name: str) -> tuple[Any, Any, Any]:
            return (ca.MX.sym(f"xf{name}", nx), ca.MX.sym(f"A{name}", nx, nx),
                    ca.MX.sym(f"B{name}", nx, nu))

        if self.linearization == "trajectory":
            blocks = [block(str(k)) for k in range(N)]
            syms = [v for b in blocks for v in b]
        else:
            # interval 0 at its node; 1..N-1 affine about the target:
            # x_k+1 = xf_t + A_t (x_k - x_t) + B_t (u_k - u_t)
            first, (xf_t, a_t, b_t) = block("0"), block("t")
            Xs, Us, _ = self._unpack(w)
            sx_, su_ = ca.DM(self._sx), ca.DM(self._su)
            xt_, ut_ = p[nx + nd:2 * nx + nd], p[2 * nx + nd:]
            blocks = [first] + [(xf_t + a_t @ (Xs[k] * sx_ - xt_) + b_t @ (Us[k] * su_ - ut_),
                                 a_t, b_t) for k in range(1, N)]
            syms = [*first, xf_t, a_t, b_t]
        # the reference RTI's QP (OffsetFreeMPC._build): cost gradient, constraint values
        # and the Jacobian of the constraints linearised in dw
        J, g = self._problem(w, p, lambda k, x, u: blocks[k][0])
        grad = ca.gradient(J, w)
        dw = ca.MX.sym("dw", nw)
        _, g_lin = self._problem(dw, p, lambda k, x, u: blocks[k][1] @ x + blocks[k][2] @ u)
        Jg = ca.jacobian(g_lin, dw)
        H = ca.DM(ca.Function("H", [w, p], [ca.hessian(J, w)[0]])(np.zeros(nw),
                                                                   np.zeros(self._np)))
        # condensing: dX_0 = -g_0 (initial-state rows), dX_k+1 = Ab_k dX_k + Bb_k dU_k + c_k
        # (the defect rows, Ab = A scaled, Bb = B scaled), everything affine in z
        rows_per = self._rows_per_interval()
        Sx_inv = ca.DM(np.diag(1 / self._sx))
        Sx, Su = ca.DM(np.diag(self._sx)), ca.DM(np.diag(self._su))
        eye_z = ca.DM.eye(nz)
        # structurally zero start: M_k has nonzeros only in the columns of du_0..du_k-1,
        # so that the products below skip the upper (zero) triangle of E
        Mk: Any = ca.MX(nx, nz)
        mk: Any = -g[:nx]
        rows_E: list[Any] = []
        rows_e: list[Any] = []
        for k in range(N):
            rows_E += [Mk, eye_z[k * nzs:(k + 1) * nzs, :]]
            rows_e += [mk, ca.MX(nzs, 1)]
            Ab = Sx_inv @ blocks[k][1] @ Sx
            Bb = Sx_inv @ blocks[k][2] @ Su
            c = g[nx + k * rows_per:nx + k * rows_per + nx]
            Mk = Ab @ Mk + Bb @ eye_z[k * nzs:k * nzs + nu, :]
            mk = Ab @ mk + c
        rows_E.append(Mk)
        rows_e.append(mk)
        E = ca.vertcat(*rows_E)                       # dw = E z + e   (nw x nz)
        e = ca.vertcat(*rows_e)
        # general constraints of the condensed QP: the soft rows of the linearised
        # constraints, then the maps' bounds on the states x_1..x_N
        ineq = [nx + k * rows_per + nx + j for k in range(N) for j in range(rows_per - nx)]
        box = [k * blk + j for k in range(1, N + 1) for j in range(nx)
               if np.isfinite(self._lbw[k * blk + j]) or np.isfinite(self._ubw[k * blk + j])]
        zi = [k * blk + nx + j for k in range(N) for j in range(nzs)]
        Jin = Jg[ineq, :]
        lbw, ubw = ca.DM(self._lbw), ca.DM(self._ubw)
        Hm = ca.DM(H)
        Hc = E.T @ (Hm @ E)
        gc = E.T @ (Hm @ e + grad)
        Ac = ca.vertcat(Jin @ E, E[box, :])
        lbA = ca.vertcat(ca.DM(self._lbg[ineq]) - g[ineq] - Jin @ e,
                         lbw[box] - w[box] - e[box])
        ubA = ca.vertcat(ca.DM(self._ubg[ineq]) - g[ineq] - Jin @ e,
                         ubw[box] - w[box] - e[box])
        lbz, ubz = lbw[zi] - w[zi], ubw[zi] - w[zi]
        names = ["H", "g", "A", "lba", "uba", "lbx", "ubx", "E", "e"]
        condense = ca.Function("mpc_rti_condense", [w, p, *syms],
                               [ca.densify(v) for v in (Hc, gc, Ac, lbA, ubA, lbz, ubz, E, e)],
                               ["w", "p", *[v.name() for v in syms]], names).expand()
        ivals = [v for b in self._interval_blocks(w, p, T, Fd) for v in b]
        self._data_f = ca.Function("mpc_rti_condensed", [w, p, T],
                                   list(condense(w, p, *ivals)), ["w", "p", "table"], names)
        self._condense = condense
        self._ivals = (w, p, T, ivals)
        self._na = Ac.size1()
        self._nz = nz
        self._nw = nw
        self._blk = blk
        self._target_f = self._target_function()
        self._guess_f = self._guess_function()
        self._diag_raw: tuple[Any, ...] | None = None
        self._t_prep = self._t_qp = 0.0

    def _interval_blocks(self, w: Any, p: Any, T: Any, Fd: ca.Function) -> list[Any]:
        """The intervals' ``(x_k+1, A_k, B_k)`` of the QP at ``w`` (scaled decision vector),
        ``p`` (``[x_hat, d_hat, x_t, u_t]``), the map table ``T``: RK4 of eq. 8 + mechanics
        and its Jacobians by AD (``Fd``, :meth:`MagnetHeaveModel.discrete`) at every
        shooting node (the real-time iteration's Gauss-Newton linearisation); with
        ``linearization="target"`` only interval 0's and those at the target
        ``(x_t, u_t)``."""
        m = self.model
        nx, nd = m.nx, m.nd
        X, U, _ = self._unpack(w)
        sx, su = ca.DM(self._sx), ca.DM(self._su)
        d = p[nx:nx + nd]
        if self.linearization == "target":
            return [Fd(X[0] * sx, U[0] * su, d, T)[:3],
                    Fd(p[nx + nd:2 * nx + nd], p[2 * nx + nd:], d, T)[:3]]
        return [Fd(X[k] * sx, U[k] * su, d, T)[:3] for k in range(self.horizon)]

    def _target_function(self) -> ca.Function:
        """``(d_hat, s_ref, I_guess, table) -> (x_t, u_t, last Newton step)``: the target
        of :meth:`MagnetHeaveModel.steady_state` by a fixed number of Newton steps
        (clamped to the maps' current range like the Python Newton; the step is NaN where
        a slope <= 0 stopped the Python Newton)."""
        m = self.model
        nc, nd = m.n_circuits, m.nd
        dh, sref, ig = ca.MX.sym("d", nd), ca.MX.sym("s_ref"), ca.MX.sym("i_guess")
        T = ca.MX.sym("table", m.table.size)
        s = sref - m.disturbance(dh, "gap_sensor")
        load = m.mass_kg * m.gravity + m.disturbance(dh, "force")
        i_s = ca.MX.sym("i")
        x = ca.vertcat(ca.repmat(i_s, nc, 1), s, 0, ca.DM.zeros(m.n_eddy))
        # the force expression inlined (m.force is a Function: AD through a nested call
        # clears a 40 000-entry zero seed for the table, measured 28 us per target)
        F = m.expressions(x, ca.MX.zeros(m.nu), dh, T)[2]
        fs = ca.Function("mpc_rti_force", [i_s, dh, sref, T], [F, ca.jacobian(F, i_s)])
        i: Any = ig
        step: Any = ca.MX(0)
        bad: Any = ca.MX(0)
        lo, hi = m.current_range_A
        for _ in range(_NEWTON_STEPS):
            f, df = fs(i, dh, sref, T)
            bad = bad + (df <= 0)
            step = ca.if_else(df > 0, (f - load) / df, 0)
            i = ca.fmin(ca.fmax(i - step, lo), hi)
        step = ca.if_else(bad > 0, np.nan, step)
        xt = ca.vertcat(ca.repmat(i, nc, 1), s, 0, ca.DM.zeros(m.n_eddy))
        ut = ca.DM(m.resistance_ohm) * i - m.disturbance(dh, "voltage")
        return ca.Function("mpc_rti_target", [dh, sref, ig, T], [xt, ut, step])

    def _guess_function(self) -> ca.Function:
        """``(H, g, A, lba, uba, lbx, ubx) -> (z, ok)``: the condensed QP's solution for the
        guessed active set "every slack at its lower bound, nothing else" (the soft
        constraints inactive, the voltages inside their limit), by a dense Cholesky
        factorisation of the free variables' Hessian (unrolled, scalar code); ``ok`` is 1
        where that point satisfies the QP's optimality conditions (primal feasibility and
        non-negative bound multipliers of the slacks, within :data:`GUESS_TOLERANCE`), so
        that it *is* the unique solution of the strictly convex QP, else 0 (then the
        dense QP solver runs).  docs/control.md, "Real-time iteration"."""
        nu, N, nz, na = self.model.nu, self.horizon, self._nz, self._na
        nzs = nu + 1
        fixed = [k * nzs + nu for k in range(N)]
        free = [k * nzs + j for k in range(N) for j in range(nu)]
        H, A = ca.SX.sym("H", nz, nz), ca.SX.sym("A", na, nz)
        g, lbx, ubx = ca.SX.sym("g", nz), ca.SX.sym("lbx", nz), ca.SX.sym("ubx", nz)
        lba, uba = ca.SX.sym("lba", na), ca.SX.sym("uba", na)
        zf = lbx[fixed]
        rhs = -(g[free] + ca.mtimes(H[free, fixed], zf))
        n = len(free)
        Hf = H[free, free]
        # Cholesky Hf = L L' (lower triangle), forward and back substitution
        L = [[ca.SX(0)] * n for _ in range(n)]
        for j in range(n):
            d = Hf[j, j] - sum((L[j][q] * L[j][q] for q in range(j)), ca.SX(0))
            L[j][j] = ca.sqrt(d)
            for i in range(j + 1, n):
                L[i][j] = (Hf[i, j] - sum((L[i][q] * L[j][q] for q in range(j)),
                                          ca.SX(0))) / L[j][j]
        yv: list[Any] = []
        for i in range(n):
            yv.append((rhs[i] - sum((L[i][q] * yv[q] for q in range(i)), ca.SX(0))) / L[i][i])
        xv: list[Any] = [ca.SX(0)] * n
        for i in reversed(range(n)):
            xv[i] = (yv[i] - sum((L[q][i] * xv[q] for q in range(i + 1, n)), ca.SX(0))) / L[i][i]
        z = ca.SX.zeros(nz)
        for k, i in enumerate(free):
            z[i] = xv[k]
        for k, i in enumerate(fixed):
            z[i] = zf[k]
        az = ca.mtimes(A, z)
        mu = (ca.mtimes(H, z) + g)[fixed]
        tol = GUESS_TOLERANCE
        conds = ca.vertcat(z[free] - lbx[free] + tol, ubx[free] - z[free] + tol,
                           az - lba + tol, uba - az + tol, mu + tol)
        # NaN fails every comparison, so a failed factorisation is never ok
        ok = ca.SX(1)
        for q in range(conds.numel()):
            ok = ok * (conds[q] >= 0)
        return ca.Function("mpc_rti_guess", [H, g, A, lba, uba, lbx, ubx], [z, ok])

    def _finish_build(self) -> None:
        """The per-sample law ``prepare`` (uncompiled; :class:`RealTimeMPCBatch` compiles
        it, one generated copy per distinct law): the EKF step, the target, the shifted
        previous solution (or the cold start), the condensed QP data at that point and its
        solution for the guessed active set, applied (``w + E z + e``); the dense QP
        solver for the samples where the guess fails."""
        m = self.model
        nx, nu, nd, N = m.nx, m.nu, m.nd, self.horizon
        nz, nw, blk = self._nz, self._nw, self._blk
        nzz = nx + nd
        ekf = self.observer.step_function
        T = ca.MX.sym("table", m.table.size)
        z, P = ca.MX.sym("z", nzz), ca.MX.sym("P", nzz, nzz)
        u_prev, y = ca.MX.sym("u_prev", nu), ca.MX.sym("y", m.ny)
        sref, ig = ca.MX.sym("s_ref"), ca.MX.sym("i_guess")
        w_prev = ca.MX.sym("w_prev", nw)
        cold, given, use_given = ca.MX.sym("cold"), ca.MX.sym("target", nx + nu), \
            ca.MX.sym("use_given")
        zc, Pc, _ = ekf(z, P, u_prev, y, T)
        xt_n, ut_n, step = self._target_f(zc[nx:], sref, ig, T)
        # the table-free glue (target choice, warm or cold start) as one function expanded
        # to scalar code
        g_syms = [ca.MX.sym(n, *v.shape) for n, v in (
            ("zc", zc), ("xt_n", xt_n), ("ut_n", ut_n), ("given", given),
            ("use_given", use_given), ("w_prev", w_prev), ("cold", cold))]
        g_zc, g_xtn, g_utn, g_given, g_use, g_wp, g_cold = g_syms
        xt = ca.if_else(g_use, g_given[:nx], g_xtn)
        ut = ca.if_else(g_use, g_given[nx:], g_utn)
        w_warm = g_wp
        if math.isclose(self.interval_s, self.sample_time_s, rel_tol=1e-9):
            # OffsetFreeMPC._shift: advance by one interval, repeat the last block
            w_warm = ca.vertcat(w_warm[blk:N * blk], w_warm[N * blk:N * blk + nx],
                                w_warm[(N - 1) * blk + nx:N * blk], w_warm[N * blk:nw])
        sx, su = ca.DM(self._sx), ca.DM(self._su)
        w_cold = ca.vertcat(*[ca.vertcat(g_zc[:nx] / sx if k == 0 else xt / sx, ut / su,
                                         ca.MX(1, 1)) for k in range(N)], xt / sx)
        start = ca.Function("mpc_rti_start", g_syms,
                            [ca.if_else(g_cold, w_cold, w_warm), ca.vertcat(g_zc, xt, ut)]
                            ).expand()
        w, p = start(zc, xt_n, ut_n, given, use_given, w_prev, cold)
        # the guess applied: dw = E z + e (its U_0 row is z[:nu], exactly)
        ws, Es, es, zs = (ca.MX.sym("w", nw), ca.MX.sym("E", nw, nz), ca.MX.sym("e", nw),
                          ca.MX.sym("z", nz))
        apply = ca.Function("mpc_rti_apply", [ws, Es, es, zs],
                            [ws + ca.mtimes(Es, zs) + es]).expand()
        zg: Any
        ok: Any
        w_next: Any
        if self._FUSED:
            zg, ok, w_next = self._solve_function()(w, p, T)
        else:
            qp = self._data_f(w, p, T)
            zg, ok = self._guess_f(*qp[:7])
            w_next = apply(w, qp[7], qp[8], zg)
        status = ca.vertcat(step, ca.sum1(zc), ok)
        f = ca.Function("mpc_rti_prepare",
                        [z, P, u_prev, y, sref, ig, w_prev, cold, given, use_given, T],
                        [zc, Pc, w, p, status, w_next],
                        ["z", "P", "u_prev", "y", "s_ref", "i_guess", "w_prev", "cold",
                         "target", "use_given", "table"],
                        ["z_next", "P_next", "w", "p", "status", "w_next"])
        #: the prepare law (one sample of one controller, uncompiled), the function that
        #: :class:`RealTimeMPCBatch` calls per controller (inputs ``z, P, u_prev, y,
        #: s_ref, i_guess, w_prev, cold, target, use_given, table``; outputs ``z_next,
        #: P_next, w, p, status = [last Newton step, sum(z_next), guess ok], w_next``)
        self.prepare_function = f
        #: the QP data at ``(w, p)`` and its solver, for the samples whose guess fails
        self.apply_function = apply
        self._z = np.zeros(nz)
        qpdata = [np.zeros(self._data_f.nnz_out(j)) for j in range(7)]
        self._qpdata = qpdata
        with _quiet_stdout():        # qpOASES prints its licence banner per instance
            solver = self._qp_solver_function()
            names = ("h", "g", "a", "lba", "uba", "lbx", "ubx")
            self._qpb = BoundCall(solver, args={solver.index_in(n): qpdata[j]
                                                for j, n in enumerate(names)},
                                  res={solver.index_out("x"): self._z})
        self._one: RealTimeMPCBatch | None = None
        #: (batch, buffer class, row) whose buffers hold this controller's latest sample
        self._owner: tuple[RealTimeMPCBatch, int, int] | None = None

    def _solve_function(self) -> ca.Function:
        """``(w, p, table) -> (z, ok, w_next)``: the condensed QP data, its guessed
        active set's solution (:meth:`_guess_function`) and that step applied
        (``w + E z + e``) as ONE function of scalar code, composed from the same
        functions as :attr:`_data_f` and the guess: only the map-reading interval
        blocks stay outside.  Composed in scalar code, the guess and the step see the
        structural zeros of the condensed matrices (the upper triangle of ``E``, its
        identity rows, the zero blocks of the constraint matrix) and the constant
        entries, so their products with zeros and ones are not computed; every other
        operation and the order of every sum are those of the separate functions (the
        skipped terms are exact zeros, ``x + 0 = x``, ``1 z = z``), so the results are
        the same numbers (tests/test_mpc_realtime.py)."""
        cond = self._condense
        w, p, T, ivals = self._ivals
        ins = [ca.SX.sym(cond.name_in(i), cond.sparsity_in(i)) for i in range(cond.n_in())]
        qp = cond(*ins)
        zg, ok = self._guess_f(*qp[:7])
        w_next = ins[0] + ca.mtimes(qp[7], zg) + qp[8]
        fused = ca.Function("mpc_rti_solve", ins, [zg, ok, w_next],
                            [cond.name_in(i) for i in range(cond.n_in())],
                            ["z", "ok", "w_next"], {"cse": True})
        return ca.Function("mpc_rti_solved", [w, p, T], list(fused(w, p, *ivals)),
                           ["w", "p", "table"], ["z", "ok", "w_next"])

    def _table_array(self) -> np.ndarray:
        t = getattr(self, "_table_c", None)
        if t is None:
            t = self._table_c = np.ascontiguousarray(self.model.table, dtype=float)
        return t

    def _compile(self, f: ca.Function) -> tuple[ca.Function, bool]:
        from ..models.compiled import compile_function

        return compile_function(f, mode=self.model.compiled_mode)

    def _qp_solver_function(self) -> ca.Function:
        nz, na = self._nz, self._na
        name = self._dense_solver
        opts: dict[str, Any] = {"error_on_fail": False}
        if name == "qpoases":
            # dense SQProblem; casadi's interface hot-starts every solve after the first
            # from the previous working set
            opts.update(printLevel="none", sparse=False, schur=False)
        elif name == "qrqp":
            opts.update(print_iter=False, print_header=False, print_info=False)
        elif name == "osqp":
            opts["osqp"] = {"verbose": False, "eps_abs": 1e-10, "eps_rel": 1e-10,
                            "max_iter": 50000, "polish": True}
            opts["warm_start_primal"] = True
        elif name == "proxqp":
            opts["proxqp"] = {"backend": "dense", "eps_abs": 1e-10, "max_iter": 10000}
        return ca.conic("mpc_rti_dense_qp", name,
                        {"h": ca.Sparsity.dense(nz, nz), "a": ca.Sparsity.dense(na, nz)}, opts)

    # ------------------------------------------------------------------ interface
    def reset(self, measurement: Measurement, *, sample_time_s: float) -> None:
        """Start a run: observer at the initial estimate, cold start of the QP.

        Parameters
        ----------
        measurement : Measurement
            The first measurement (not used).
        sample_time_s : float
            The run's sample time [s]; must equal the controller's (keyword only).

        Raises
        ------
        InputError
            A sample time other than the one the controller was built for.
        """
        super().reset(measurement, sample_time_s=sample_time_s)
        if self._one is None:          # this controller alone, as a batch of one
            self._one = RealTimeMPCBatch([self])
        self._one._load()

    def update(self, measurement: Measurement) -> np.ndarray:
        """One sample: this controller as a batch of one (:class:`RealTimeMPCBatch`: one
        compiled call for the EKF step, target, QP data and the QP's solution for the
        guessed active set; the dense QP solver only where that guess fails its
        optimality check).

        The EKF step integrates the previous output, or the measurement's
        ``applied_voltages_V`` when given.

        The observer object's own ``state`` is not advanced (its step runs inside the
        compiled function); the estimates are in :meth:`diagnostics`.

        Parameters
        ----------
        measurement : Measurement
            Gap [m], currents [A] and gap reference [m] of this sample.

        Returns
        -------
        ndarray (n_u,)
            Voltages [V] to hold until the next sample, within ``+-voltage_limit_V``.

        Raises
        ------
        SolverError
            A diverged observer, no equilibrium for the reference, a failed QP, or a
            solution beyond the voltage limit.
        """
        if self._one is None:
            raise SolverError("RealTimeMPC.update before reset: call reset(measurement, "
                              "sample_time_s=...) first")
        one = self._one
        applied = measurement.applied_voltages_V
        u = one.update(np.array([measurement.gap_m]),
                       np.asarray(measurement.currents_A, dtype=float).reshape(1),
                       np.array([measurement.gap_ref_m]),
                       None if applied is None else np.asarray(applied, dtype=float)
                       .reshape(1), time_s=measurement.time_s, _single=True)
        self._u_prev = u
        return u

    def current_solution(self) -> np.ndarray:
        """The scaled decision vector after the last update (``w + E z + e``)."""
        if self._owner is None:
            return np.zeros(self._nw)
        batch, g, r = self._owner
        return batch._cdata[g]["alt"][batch._k][2][r].copy()

    def diagnostics(self) -> Mapping[str, float | np.ndarray]:
        """Estimates as :meth:`OffsetFreeMPC.diagnostics` after the last update of this
        controller (alone or in a :class:`RealTimeMPCBatch`); the times [s] of that
        update (of the whole batch's sample when batched): ``prepare_time_s`` (the
        compiled EKF step, target, QP data and active-set guess), ``qp_time_s`` (the
        dense QP solver where a guess was not the solution, and the checks),
        ``solve_time_s`` (the whole update) and ``update_cpu_time_s`` (its CPU time);
        ``qp_guess``: 1.0 where the compiled guess was the QP's solution, 0.0 where the
        dense solver ran."""
        if self._owner is None or not self._owner[0]._updated:
            return {}
        batch, g, r = self._owner
        gd = batch._cdata[g]
        m = self.model
        nc, nx = m.n_circuits, m.nx
        z = gd["alt"][batch._k][0][r]
        tp, tq, tu, cpu = batch._timing
        return {"gap_estimate_m": float(z[nc]), "gap_rate_estimate_m_per_s": float(z[nc + 1]),
                "inductor_current_estimate_A": z[:nc].copy(),
                "disturbance_estimate": z[nx:].copy(),
                "target_voltage_V": gd["out"][3][r, 2 * nx + m.nd:].copy(),
                "prepare_time_s": tp, "qp_time_s": tq, "solve_time_s": tu,
                "update_cpu_time_s": cpu, "iterations": 1.0,
                "qp_guess": float(gd["out"][4][r, 2] == 1.0)}

    # ------------------------------------------------------------------ OCP (tests)
    def solve(self, x_hat: np.ndarray, d_hat: np.ndarray, xt: np.ndarray,
              ut: np.ndarray) -> tuple[np.ndarray, dict[str, Any]]:
        """One condensed RTI QP from ``x_hat`` for the target ``(xt, ut)`` (for tests):
        the same QP data function and solver as :meth:`update`, without the observer.

        Parameters
        ----------
        x_hat : ndarray (n_x,)
            Estimated state: inductor currents [A], gap [m], gap rate [m/s].
        d_hat : ndarray (n_d,)
            Estimated disturbances.
        xt : ndarray (n_x,)
            Target steady state.
        ut : ndarray (n_u,)
            Target voltages [V].

        Returns
        -------
        (u, info) : ndarray (n_u,), dict
            First voltages [V] (clipped to the limit), ``{"iterations": 1, "solution"}``.

        Raises
        ------
        SolverError
            If the QP fails.
        """
        m = self.model
        nx = m.nx
        if self._w is None:
            w = self._initial_guess(x_hat, xt, ut)
        else:
            w = self._shift(self._w) if math.isclose(self.interval_s, self.sample_time_s,
                                                     rel_tol=1e-9) else self._w
        p = np.r_[x_hat, d_hat, xt, ut]
        out = self._data_f(w, p, self.model.table)
        qp = self._qpb.function
        r = qp(h=out[0], g=out[1], a=out[2], lba=out[3], uba=out[4], lbx=out[5], ubx=out[6])
        if not qp.stats()["success"]:
            raise SolverError("the MPC's condensed QP failed", state={"x_hat": x_hat},
                              reason=str(qp.stats().get("return_status", "unknown")))
        zs = np.asarray(r["x"], dtype=float).ravel()
        w = w + np.asarray(out[7]) @ zs + np.asarray(out[8]).ravel()
        self._w = w
        u = w[nx:nx + m.nu] * self._su
        return np.clip(u, -self._ulim, self._ulim), {"iterations": 1, "solution": w.copy()}


class RealTimeMPCBatch:
    """Many :class:`RealTimeMPC` controllers (e.g. one per vehicle circuit) updated by one
    compiled call per sample; a single controller's :meth:`RealTimeMPC.update` is a batch
    of one.

    The controllers' own prepare laws (:attr:`RealTimeMPC.prepare_function`: the EKF
    step, the target, the condensed QP data, the QP's solution for the guessed active set
    and that step applied) are called once per controller inside one function (one
    generated copy of each distinct law, its map table passed once), compiled together
    with each distinct law's QP data function; each sample then costs one call for every
    controller together.  Where a controller's guess fails its optimality check (an
    active voltage limit or soft constraint), the QP data function gives that
    controller's QP again and its own dense QP solver (qpOASES, hot-started) solves it.
    The batch's buffers hold every controller's state; each controller's
    :meth:`RealTimeMPC.diagnostics` and :meth:`RealTimeMPC.current_solution` read the
    batch that updated it last.

    Parameters
    ----------
    controllers : sequence of RealTimeMPC
        The controllers, in the order of the measurement and voltage vectors (one entry
        per controller, at least one), all with the same sample time [s], one input each
        and no two the same object.

    Raises
    ------
    ParameterError
        No controllers, not :class:`RealTimeMPC` objects, repeated objects, more than one
        input per controller, or different sample times.
    """

    # prepare inputs: alternating sets (z, P, w_prev) and the shared ones
    _ALT_IN, _SHARED_IN = (0, 1, 6), (2, 3, 4, 5, 7, 8, 9)
    # prepare outputs into the other set (z_next, P_next, w_next) and the once-only ones
    _ALT_OUT, _ONCE_OUT = (0, 1, 5), (2, 3, 4)

    def __init__(self, controllers: Any) -> None:
        ctls = list(controllers)
        if not ctls or not all(isinstance(c, RealTimeMPC) for c in ctls):
            raise ParameterError("RealTimeMPCBatch needs a non-empty sequence of RealTimeMPC "
                                 "controllers")
        if len({id(c) for c in ctls}) != len(ctls):
            raise ParameterError("RealTimeMPCBatch: a controller object appears twice (each "
                                 "has its own observer and QP state)")
        if any(c.model.nu != 1 for c in ctls):
            raise ParameterError("RealTimeMPCBatch takes controllers of one circuit each "
                                 "(model.nu = 1)")
        ts = {c.sample_time_s for c in ctls}
        if len(ts) != 1:
            raise ParameterError(f"RealTimeMPCBatch: the controllers' sample times differ "
                                 f"({sorted(ts)} s)")
        self.controllers = ctls
        self.sample_time_s = ctls[0].sample_time_s
        n = self.n = len(ctls)
        # groups of equal laws (the same serialised prepare function)
        keys: dict[str, int] = {}
        group = np.zeros(n, dtype=int)
        for j, c in enumerate(ctls):
            group[j] = keys.setdefault(c.prepare_function.serialize(), len(keys))
        self._groups = [np.flatnonzero(group == g) for g in range(len(keys))]
        self._build()

    def _build(self) -> None:
        from ..models.compiled import compile_library

        ctls = self.controllers
        ins: list[Any] = []
        outs: list[Any] = []
        self._gdata: list[dict[str, Any]] = []
        data_fs: list[ca.Function] = []
        for g, idx in enumerate(self._groups):
            c0 = ctls[int(idx[0])]
            f = c0.prepare_function
            ng = idx.size
            ti = f.n_in() - 1                       # the table, passed once per group
            # one call of the same law per controller (not Function.map: its shared-input
            # form repeats the 70 000-entry table per instance, measured 50 us a call);
            # per input one (numel, n_g) block, column r = controller r's (dense) input
            sy = [ca.MX.sym(f"g{g}_{f.name_in(i)}", f.numel_in(i) if i != ti else f.nnz_in(i),
                            ng if i != ti else 1) for i in range(f.n_in())]
            cols: list[list[Any]] = [[] for _ in range(f.n_out())]
            for r in range(ng):
                res = f(*[sy[i] if i == ti else ca.reshape(sy[i][:, r], f.size_in(i))
                          for i in range(f.n_in())])
                for q, o in enumerate(res):
                    cols[q].append(ca.densify(ca.vec(o)))
            ins += sy
            outs += [ca.horzcat(*c) for c in cols]
            d = c0._data_f
            sd = [ca.MX.sym(d.name_in(i), d.sparsity_in(i)) for i in range(d.n_in())]
            data_fs.append(ca.Function(f"mpc_rti_qp_data_g{g}", sd, d(*sd)))
            self._gdata.append({"f": f, "idx": idx, "c0": c0, "n_in": f.n_in(),
                                "n_out": f.n_out()})
        F = ca.Function("mpc_rti_prepare_batch", ins, outs)
        c0 = ctls[0]
        funcs, _ = compile_library("mpc_rti_batch", [F, *data_fs],
                                   mode=c0.model.compiled_mode, flags=vector_flags())
        compiled = funcs[0]
        self.function = F
        # buffers: (n rows, nnz of one controller) C-order arrays per input/output, one set
        # per class of groups with equal sizes (one class for a vehicle's circuits), each
        # group bound to its contiguous block of rows (the unrolled call stacks the
        # instances' nonzeros one after another), so that the checks after the call run
        # once per class, not once per group
        classes: dict[tuple[int, ...], list[int]] = {}
        for g, gd in enumerate(self._gdata):
            f = gd["f"]
            key = (*(f.numel_in(i) for i in range(f.n_in() - 1)),
                   *(f.numel_out(i) for i in range(f.n_out())), gd["c0"].model.nx)
            classes.setdefault(key, []).append(g)
        self._cdata: list[dict[str, Any]] = []
        for gs in classes.values():
            idx = np.concatenate([self._gdata[g]["idx"] for g in gs])
            nr = idx.size
            f, c0 = self._gdata[gs[0]]["f"], self._gdata[gs[0]]["c0"]

            def arr(nnz: int, nr: int = nr) -> np.ndarray:
                return np.zeros((nr, nnz))

            cd = {"idx": idx, "nx": c0.model.nx, "nd": c0.model.nd, "nz": c0._nz,
                  "nw": c0._nw, "alt": [[arr(f.numel_in(i)) for i in self._ALT_IN]
                                        for _ in range(2)],
                  "shared": {i: arr(f.numel_in(i)) for i in self._SHARED_IN},
                  "out": {i: arr(f.numel_out(i)) for i in self._ONCE_OUT},
                  "su": np.array([ctls[int(j)]._su[0] for j in idx]),
                  "ulim": np.array([ctls[int(j)].voltage_limit_V for j in idx]),
                  "group_of": np.concatenate([np.full(self._gdata[g]["idx"].size, g)
                                              for g in gs])}
            cd["shared"][7][:] = 1.0
            off = 0
            for g in gs:
                gd = self._gdata[g]
                ng = gd["idx"].size
                rows = slice(off, off + ng)
                gd.update(cls=len(self._cdata), rows=rows,
                          data=BoundCall(funcs[1 + g], args={2: gd["c0"]._table_array()}))
                off += ng
            self._cdata.append(cd)
        calls_args: list[dict[int, np.ndarray]] = [{}, {}]
        calls_res: list[dict[int, np.ndarray]] = [{}, {}]
        ia = oa = 0
        for gd in self._gdata:
            cd, rows = self._cdata[gd["cls"]], gd["rows"]
            for k in range(2):
                a, b = cd["alt"][k], cd["alt"][1 - k]
                args = {ia + i: v[rows] for i, v in cd["shared"].items()}
                args.update({ia + i: a[q][rows] for q, i in enumerate(self._ALT_IN)})
                args[ia + 10] = gd["c0"]._table_array()
                res = {oa + i: b[q][rows] for q, i in enumerate(self._ALT_OUT)}
                res.update({oa + i: v[rows] for i, v in cd["out"].items()})
                calls_args[k].update(args)
                calls_res[k].update(res)
            ia += gd["n_in"]
            oa += gd["n_out"]
        self._calls = [BoundCall(compiled, args=calls_args[k], res=calls_res[k])
                       for k in range(2)]
        self._k = 0
        self._u = np.zeros(self.n)
        self._updated = False
        self.last_fallbacks = 0
        self._timing: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    def _load(self) -> None:
        """The controllers' observer states and covariances, previous voltages and design
        currents into the buffers, cold start (after their own ``reset``); the batch
        becomes each controller's owner (its diagnostics read this batch)."""
        self._k = 0
        for ci, cd in enumerate(self._cdata):
            a = cd["alt"][0]
            sh = cd["shared"]
            for r, j in enumerate(cd["idx"].tolist()):
                c = self.controllers[j]
                a[0][r] = c.observer.state
                a[1][r] = np.ravel(c.observer.covariance, order="F")
                sh[2][r] = c._u_prev
                sh[5][r] = c.design_state[0]
                c._owner = (self, ci, r)
            sh[7][:] = 1.0
            sh[9][:] = 0.0
        self._updated = False
        self._timing = (0.0, 0.0, 0.0, 0.0)

    def reset(self, measurements: Any, *, sample_time_s: float) -> None:
        """Start a run: every controller's observer and cold start
        (:meth:`OffsetFreeMPC.reset`), copied into the batch's buffers.

        Parameters
        ----------
        measurements : sequence of Measurement
            One first measurement per controller (in order).
        sample_time_s : float
            The run's sample time [s]; must equal the controllers' (keyword only).

        Raises
        ------
        InputError
            A sample time other than the controllers', or not one measurement per
            controller.
        """
        from ..errors import InputError

        ms = list(measurements)
        if len(ms) != self.n:
            raise InputError(f"RealTimeMPCBatch.reset: {len(ms)} measurements for {self.n} "
                             "controllers")
        for c, meas in zip(self.controllers, ms, strict=True):
            OffsetFreeMPC.reset(c, meas, sample_time_s=sample_time_s)
        self._load()

    def update(self, gaps_m: np.ndarray, currents_A: np.ndarray, gap_refs_m: np.ndarray,
               applied_voltages_V: np.ndarray | None = None, *,
               time_s: float | None = None, _single: bool = False) -> np.ndarray:
        """One sample of every controller: one compiled call, the dense QP solver only
        where a controller's compiled guess is not its QP's solution.

        Parameters
        ----------
        gaps_m, currents_A, gap_refs_m : ndarray (n,)
            Measured gap [m], coil current [A] and gap reference [m] per controller.
        applied_voltages_V : ndarray (n,), optional
            The voltages [V] applied since the last sample (the EKF's input; default: the
            previous outputs).
        time_s : float, optional
            The sample's time [s] (for error messages).

        Returns
        -------
        ndarray (n,)
            Voltages [V] to hold until the next sample, within each controller's limit.

        Raises
        ------
        SolverError
            A diverged observer, no equilibrium for the reference, a failed QP or a
            solution beyond the voltage limit, naming the controller's index (not for a
            batch of one, :meth:`RealTimeMPC.update`).
        """
        t0 = time.perf_counter()
        c0 = time.thread_time()
        k = self._k
        for gd in self._cdata:
            idx, sh = gd["idx"], gd["shared"]
            if applied_voltages_V is not None:
                sh[2][:, 0] = applied_voltages_V[idx]
            sh[3][:, 0] = gaps_m[idx]
            sh[3][:, 1] = currents_A[idx]
            sh[4][:, 0] = gap_refs_m[idx]
        call = self._calls[k]
        call.eval()
        self._check_targets(call, gap_refs_m, time_s, _single)
        t1 = time.perf_counter()
        fallbacks = 0
        u = self._u
        for gd in self._cdata:
            idx, out, sh = gd["idx"], gd["out"], gd["shared"]
            b = gd["alt"][1 - k]
            st = out[4]
            if not np.isfinite(st[:, 1]).all():
                r = int(np.flatnonzero(~np.isfinite(st[:, 1]))[0])
                raise SolverError("the extended Kalman filter diverged", time_s=time_s,
                                  state=self._state(idx[r], _single, estimate=b[0][r].copy()),
                                  reason="non-finite estimate")
            nx = gd["nx"]
            guessed = st[:, 2] == 1.0
            if not guessed.all():
                for r in np.flatnonzero(~guessed).tolist():
                    self._dense_qp(gd, r, b[2][r], time_s, _single)
                    fallbacks += 1
            ug = b[2][:, nx] * gd["su"]
            lim = gd["ulim"]
            ok = np.abs(ug) <= lim * (1 + _LIMIT_SLACK)             # False for NaN
            if not ok.all():
                r = int(np.flatnonzero(~ok)[0])
                raise SolverError("the MPC solution violates the voltage limit", time_s=time_s,
                                  state=self._state(idx[r], _single, u=float(ug[r])),
                                  reason="QP tolerance too loose")
            np.clip(ug, -lim, lim, out=ug)
            sh[2][:, 0] = ug
            sh[5][:, 0] = out[3][:, nx + gd["nd"]]
            sh[7][:] = 0.0
            u[idx] = ug
        self._k = 1 - k
        self._updated = True
        self.last_fallbacks = fallbacks
        t2 = time.perf_counter()
        self._timing = (t1 - t0, t2 - t1, t2 - t0, time.thread_time() - c0)
        return u.copy()

    @staticmethod
    def _state(j: Any, single: bool, **kw: Any) -> dict[str, Any]:
        return kw if single else {"controller": int(j), **kw}

    def _check_targets(self, call: BoundCall, refs: np.ndarray, time_s: float | None,
                       single: bool) -> None:
        """Controllers whose compiled Newton did not converge: the Python Newton's target
        (or its SolverError), then the same call again with those targets given."""
        redo = False
        for gd in self._cdata:
            st, p, sh = gd["out"][4], gd["out"][3], gd["shared"]
            nx, nxd = gd["nx"], gd["nx"] + gd["nd"]
            lim = _TARGET_RESIDUAL * np.maximum(1.0, np.abs(p[:, nxd]))
            bad = ~(np.abs(st[:, 0]) < lim)                 # also for NaN
            if not bad.any():
                continue
            for r in np.flatnonzero(bad).tolist():
                j = int(gd["idx"][r])
                c = self.controllers[j]
                zc = gd["alt"][1 - self._k][0][r]
                guess = float(sh[5][r, 0])
                if not math.isfinite(guess):
                    guess = float(c.design_state[0])
                xs, us = c.model.steady_state(float(refs[j]), zc[nx:].copy(),
                                              current_guess_A=guess)
                sh[8][r, :nx] = xs
                sh[8][r, nx:] = us
                sh[9][r] = 1.0
                redo = True
        if redo:
            try:
                call.eval()        # the same inputs: the same EKF steps, the given targets
            finally:
                for gd in self._cdata:
                    gd["shared"][9][:] = 0.0

    def _dense_qp(self, gd: dict[str, Any], r: int, w_next: np.ndarray,
                  time_s: float | None, single: bool) -> None:
        """Row ``r`` of class ``gd``: its condensed QP at ``(w, p)`` again (its group's
        compiled QP data function), solved by the controller's own dense solver
        (hot-started), the step applied into ``w_next``."""
        j = int(gd["idx"][r])
        c = self.controllers[j]
        data = self._gdata[int(gd["group_of"][r])]["data"]
        data.args[0][:] = gd["out"][2][r]
        data.args[1][:] = gd["out"][3][r]
        data.eval()
        for q in range(7):
            c._qpdata[q][:] = data.res[q]
        qpb = c._qpb
        qpb.eval()
        z = c._z
        if qpb.buffer.ret() != 0 or not math.isfinite(z.sum()):
            m = c.model
            p = gd["out"][3][r]
            raise SolverError("the MPC's condensed QP failed", time_s=time_s,
                              state=self._state(j, single, x_hat=p[:m.nx].copy(),
                                                d_hat=p[m.nx:m.nx + m.nd].copy()),
                              reason=str(qpb.buffer.stats().get("return_status", "unknown")))
        nw, nz = gd["nw"], gd["nz"]
        w_next[:] = gd["out"][2][r] + data.res[7].reshape(nz, nw).T @ z + data.res[8]

    def timing(self) -> Mapping[str, float]:
        """Times of the last :meth:`update`: wall times [s] ``prepare_time_s`` (the one
        compiled call), ``qp_time_s`` (the dense QP solves where a guess failed, the
        checks and the voltages), ``solve_time_s`` (the whole update); its CPU time
        ``update_cpu_time_s`` [s]; ``fallbacks``: how many QPs went to the dense
        solver."""
        tp, tq, tu, cpu = self._timing
        return {"prepare_time_s": tp, "qp_time_s": tq, "solve_time_s": tu,
                "update_cpu_time_s": cpu, "fallbacks": float(self.last_fallbacks)}
