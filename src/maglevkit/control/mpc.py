"""Offset-free nonlinear MPC of one magnet's gap on the reduced model (docs/control.md).

Per sample: the EKF (:mod:`~maglevkit.control.observers`) estimates ``x`` and ``d``; the
target calculation gives the equilibrium ``(x_t, u_t)`` whose measured gap is the
reference under ``d``; the optimal control problem (multiple shooting, RK4 intervals of
length ``h``, ``N`` intervals, scaled variables)::

    min  sum_k=0..N-1 [ q_s (s_k - s_t)^2 + q_v s'_k^2 + q_I |I_k - I_t|^2 + r |U_k - U_t|^2 ]
         + (x_N - x_t)' P (x_N - x_t) + sum_k=1..N (rho_1 e_k + rho_2 e_k^2)
    s.t. x_0 = x_hat,  x_k+1 = F_h(x_k, U_k, d_hat),  |U_k| <= U_max,
         s_k >= s_min - e_k,  I_L,k <= I_max + e_k,  e_k >= 0,  I_k >= 0,
         x_k within the maps

(``I_L``: the inductor currents, the maps' current axis; ``I_k``: the coil currents at the
start of interval ``k`` under ``U_k``, kept >= 0 by the two-quadrant chopper, a hard
constraint, linear in ``(I_L, U)``)

with ``P`` from the discrete Riccati equation of the linearisation at the design point
(the infinite-horizon LQR cost beyond the horizon).  Solvers:

* ``"sqp"``: Gauss-Newton SQP (the cost is quadratic, so its Hessian is exact and the
  constraint curvature is dropped), full steps, warm-started from the previous solution,
  QPs by a CasADi conic solver shipped in the casadi wheel (``qrqp`` default, ``osqp``,
  ``hpipm``, ``qpoases``, ``daqp``), iterated to a step below ``tol``;
* ``"rti"``: the real-time iteration (Diehl et al. 2005): one such QP per sample;
* ``"ipopt"``: the same OCP as an NLP for IPOPT (exact Hessian), with the single
  :class:`~maglevkit.reduced.current.CurrentModel`'s B-spline maps, as the reference.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg

from ..errors import InputError, ParameterError, SolverError
from ..reduced.core import rk4_substep
from .interface import Measurement
from .model import MagnetHeaveModel
from .observers import ExtendedKalmanFilter

__all__ = ["MPCWeights", "OffsetFreeMPC", "SOLVERS"]

SOLVERS = ("rti", "sqp", "ipopt")
QP_SOLVERS = ("qrqp", "osqp", "hpipm", "qpoases", "daqp")


@dataclass(frozen=True)
class MPCWeights:
    """Cost weights as the deviation that costs 1 per interval (Bryson's rule).

    Attributes
    ----------
    gap_m : float
        Gap error [m].
    gap_rate_m_per_s : float
        Gap rate [m/s] (comfort).
    current_A : float
        Current deviation from the target [A] (weak regularisation).
    voltage_V : float
        Voltage deviation from the target [V] (input effort).
    soft_constraint : float
        Penalty ``rho_1`` per unit violation of the (scaled) soft constraints; ``rho_2``
        is the same (exact penalty).
    """

    gap_m: float = 2e-4
    gap_rate_m_per_s: float = 2e-2
    current_A: float = 20.0
    voltage_V: float = 100.0
    soft_constraint: float = 1e4

    def __post_init__(self) -> None:
        for k in ("gap_m", "gap_rate_m_per_s", "current_A", "voltage_V", "soft_constraint"):
            v = getattr(self, k)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v)
                                           and v > 0):
                raise ParameterError(f"MPCWeights.{k} = {v!r} must be a finite number > 0")


class OffsetFreeMPC:
    """Offset-free NMPC gap controller (implements :class:`~maglevkit.control.interface.
    Controller`).

    Parameters
    ----------
    model : MagnetHeaveModel
        Prediction and observer model (its disturbance model makes the controller
        offset-free; an empty one gives plain NMPC).
    gap_ref_m : float
        Default reference and design point [m], > 0, inside the maps' gap range.
    sample_time_s : float
        Controller sample time [s], > 0.
    horizon : int
        Number of shooting intervals ``N`` (>= 1, default 20).
    interval_s : float, optional
        Interval length ``h`` [s], > 0 (default: the sample time).
    substeps : int
        RK4 steps per interval (>= 1, default 1).
    solver : {"rti", "sqp", "ipopt"}
        "rti": one QP per sample (real-time iteration); "sqp": full SQP; "ipopt": the
        NLP solver (reference).
    qp_solver : str
        Conic solver of "rti"/"sqp" (see :data:`QP_SOLVERS`; default "qrqp").
    voltage_limit_V : float
        ``|U| <= U_max`` [V] (chopper limit), > 0.
    min_gap_m, max_current_A : float
        Soft state constraints [m], [A] (default: the maps' lowest gap and highest
        current; the maps' range is a hard bound).  ``min_gap_m < gap_ref_m``.
    weights : MPCWeights
        Cost weights (default :class:`MPCWeights()`).
    max_iter, tol : int, float
        SQP iterations and step tolerance (scaled variables) of "sqp".
    observer_options : mapping, optional
        Keyword arguments of :class:`ExtendedKalmanFilter`.
    initial_estimate : array (n_x + n_d,), optional
        The observer's initial ``[x; d]`` (default: the design equilibrium, d = 0).

    Raises
    ------
    ParameterError
        Bad options, or a disturbance model that is not detectable (rank condition).
    """

    def __init__(self, model: MagnetHeaveModel, *, gap_ref_m: float, sample_time_s: float,
                 horizon: int = 20, interval_s: float | None = None, substeps: int = 1,
                 solver: str = "rti", qp_solver: str = "qrqp", voltage_limit_V: float = 440.0,
                 min_gap_m: float | None = None, max_current_A: float | None = None,
                 weights: MPCWeights | None = None, max_iter: int = 20, tol: float = 1e-8,
                 observer_options: Mapping[str, Any] | None = None,
                 initial_estimate: Any = None) -> None:
        if solver not in SOLVERS:
            raise ParameterError(f"solver = {solver!r}; use one of {list(SOLVERS)}")
        if qp_solver not in QP_SOLVERS:
            raise ParameterError(f"qp_solver = {qp_solver!r}; use one of {list(QP_SOLVERS)}")
        # bools are ints to Python, not horizons (True would be a horizon of 1)
        if isinstance(horizon, bool) or not (isinstance(horizon, int) and horizon >= 1):
            raise ParameterError(f"horizon = {horizon!r} must be an integer >= 1")
        if isinstance(substeps, bool) or not (isinstance(substeps, int) and substeps >= 1):
            raise ParameterError(f"substeps = {substeps!r} must be an integer >= 1")
        for name, v in (("sample_time_s", sample_time_s), ("voltage_limit_V", voltage_limit_V),
                        ("gap_ref_m", gap_ref_m)):
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v)
                                           and v > 0):
                raise ParameterError(f"{name} = {v!r} must be a finite number > 0")
        self.model = model
        self.solver = solver
        self.qp_solver = qp_solver
        self.sample_time_s = float(sample_time_s)
        self.interval_s = float(interval_s) if interval_s is not None else self.sample_time_s
        if not (math.isfinite(self.interval_s) and self.interval_s > 0):
            raise ParameterError(f"interval_s = {interval_s!r} must be a finite number > 0")
        self.horizon = horizon
        self._gap_ref = float(gap_ref_m)
        self._ulim = float(voltage_limit_V)
        lo_s, hi_s = model.gap_range_m
        lo_i, hi_i = model.current_range_A
        self.min_gap_m = float(lo_s if min_gap_m is None else min_gap_m)
        self.max_current_A = float(hi_i if max_current_A is None else max_current_A)
        if not lo_s <= self.min_gap_m < self._gap_ref < hi_s:
            raise ParameterError(f"need maps' lowest gap {lo_s:g} m <= min_gap_m = "
                                 f"{self.min_gap_m:g} m < gap_ref_m = {self._gap_ref:g} m < "
                                 f"{hi_s:g} m")
        if not lo_i < self.max_current_A <= hi_i:
            raise ParameterError(f"max_current_A = {self.max_current_A:g} A must lie in the "
                                 f"maps' range {lo_i:g}..{hi_i:g} A")
        self.weights = weights or MPCWeights()
        self.max_iter = 1 if solver == "rti" else int(max_iter)
        self.tol = float(tol)
        nx, nu, nc = model.nx, model.nu, model.n_circuits
        ne = model.n_eddy                   # the ladder's I_e (motion_eddy), after [I_L, s, s']
        self._sx = np.r_[np.full(nc, 10.0), 1e-3, 1e-2, np.full(ne, 1.0)]
        self._su = np.full(nu, 100.0)
        # design point, detectability, terminal cost
        self.design_state, self.design_input = model.steady_state(self._gap_ref)
        model.check_detectability(self.design_state, self.design_input, h=self.sample_time_s)
        w = self.weights
        self._Q = np.diag(np.r_[np.full(nc, 1 / w.current_A**2), 1 / w.gap_m**2,
                                1 / w.gap_rate_m_per_s**2, np.full(ne, 1 / w.current_A**2)])
        self._R = np.eye(nu) / w.voltage_V**2
        lin = model.linearize(self.design_state, self.design_input, h=self.interval_s,
                              substeps=substeps)
        try:
            self._P = scipy.linalg.solve_discrete_are(lin["A"], lin["B"], self._Q, self._R)
        except (np.linalg.LinAlgError, ValueError) as exc:
            raise ParameterError(f"no terminal cost: the Riccati equation failed ({exc})") from None
        self._build(substeps)
        self.observer = ExtendedKalmanFilter(model, sample_time_s=self.sample_time_s,
                                             **dict(observer_options or {}))
        self._initial_estimate = (None if initial_estimate is None
                                  else np.asarray(initial_estimate, dtype=float)
                                  .reshape(nx + model.nd))
        self._w: np.ndarray | None = None
        self._lam: tuple[np.ndarray, np.ndarray] | None = None
        self._u_prev = self.design_input.copy()
        self._target = (self.design_state, self.design_input)
        self._diag: dict[str, Any] = {}

    # ------------------------------------------------------------------ interface
    @property
    def gap_ref_m(self) -> float:
        return self._gap_ref

    @property
    def voltage_limit_V(self) -> float:
        return self._ulim

    def reset(self, measurement: Measurement, *, sample_time_s: float) -> None:
        """Start a run: observer at the initial estimate, cold start of the OCP.

        Parameters
        ----------
        measurement : Measurement
            The first measurement (not used: the estimate starts at ``initial_estimate``
            or the design equilibrium).
        sample_time_s : float
            The run's sample time [s]; must equal the controller's ``sample_time_s``
            (keyword only).

        Raises
        ------
        InputError
            A sample time other than the one the controller was built for.
        """
        if not math.isclose(sample_time_s, self.sample_time_s, rel_tol=1e-9):
            raise InputError(f"this MPC was built for a sample time of {self.sample_time_s:g} s, "
                             f"the run uses {sample_time_s:g} s")
        m = self.model
        if self._initial_estimate is None:
            self.observer.reset(self.design_state)
        else:
            self.observer.reset(self._initial_estimate[:m.nx], self._initial_estimate[m.nx:])
        self._u_prev = self.design_input.copy()
        self._w = None
        self._lam = None
        self._target = (self.design_state, self.design_input)

    def update(self, measurement: Measurement) -> np.ndarray:
        """One sample: observer step, steady-state target for the reference, OCP solve.

        The observer step integrates the previous output, or the measurement's
        ``applied_voltages_V`` when given.

        Parameters
        ----------
        measurement : Measurement
            Gap [m], currents [A] and gap reference [m] of this sample (the gap rate is
            not used: the observer estimates it).

        Returns
        -------
        ndarray (n_u,)
            Voltages [V] to hold until the next sample, within ``+-voltage_limit_V``.

        Raises
        ------
        SolverError
            A diverged observer, no equilibrium for the reference, or a failed solver.
        """
        m = self.model
        y = np.r_[measurement.gap_m, np.asarray(measurement.currents_A, dtype=float)]
        t0 = time.perf_counter()
        applied = measurement.applied_voltages_V
        z = self.observer.update(y, self._u_prev if applied is None
                                 else np.asarray(applied, dtype=float).reshape(m.nu))
        t1 = time.perf_counter()
        x_hat, d_hat = z[:m.nx], z[m.nx:]
        xt, ut = m.steady_state(measurement.gap_ref_m, d_hat,
                                current_guess_A=float(self._target[0][0]))
        self._target = (xt, ut)
        t2 = time.perf_counter()
        u, info = self.solve(x_hat, d_hat, xt, ut)
        t3 = time.perf_counter()
        self._u_prev = u
        self._diag = {"gap_estimate_m": x_hat[m.n_circuits],
                      "gap_rate_estimate_m_per_s": x_hat[m.n_circuits + 1],
                      "inductor_current_estimate_A": x_hat[:m.n_circuits].copy(),
                      "disturbance_estimate": d_hat.copy(),
                      "target_voltage_V": ut.copy(),
                      "observer_time_s": t1 - t0, "target_time_s": t2 - t1,
                      "solve_time_s": t3 - t2, "iterations": float(info["iterations"])}
        return u

    def diagnostics(self) -> Mapping[str, float | np.ndarray]:
        return dict(self._diag)

    # ------------------------------------------------------------------ OCP
    def _layout(self) -> tuple[int, int, int]:
        """``(index of x_N, n_w, block length)``: blocks ``[x_k, U_k, e_k+1]`` for
        ``k < N``, then ``x_N`` (interleaved, so that the KKT matrix stays banded)."""
        nx, nu, N = self.model.nx, self.model.nu, self.horizon
        blk = nx + nu + 1
        return N * blk, N * blk + nx, blk

    def _unpack(self, w: Any) -> tuple[list[Any], list[Any], list[Any]]:
        nx, nu, N = self.model.nx, self.model.nu, self.horizon
        _, _, blk = self._layout()
        X = [w[k * blk:k * blk + nx] for k in range(N + 1)]
        U = [w[k * blk + nx:k * blk + nx + nu] for k in range(N)]
        E = [w[k * blk + nx + nu] for k in range(N)]
        return X, U, E

    def _problem(self, w: Any, p: Any, interval: Any) -> tuple[Any, Any]:
        """Cost and constraints of the OCP in the scaled variables ``w`` (symbolic);
        ``interval(k, x, u)`` is the state after interval ``k`` (physical units).  Rows:
        ``x_0``, then per interval its dynamics and the soft constraints at its end."""
        m, N = self.model, self.horizon
        nx, nd, nc = m.nx, m.nd, m.n_circuits
        sx, su = ca.DM(self._sx), ca.DM(self._su)
        x0, xt, ut = p[:nx], p[nx + nd:2 * nx + nd], p[2 * nx + nd:]
        X, U, E = self._unpack(w)
        Q, R, P = ca.DM(self._Q), ca.DM(self._R), ca.DM(self._P)
        rho = self.weights.soft_constraint
        J: Any = 0
        g = [X[0] - x0 / sx]
        for k in range(N):
            ex, eu = X[k] * sx - xt, U[k] * su - ut
            J += ca.bilin(Q, ex, ex) + ca.bilin(R, eu, eu) + rho * (E[k] + E[k] ** 2)
            g.append(interval(k, X[k] * sx, U[k] * su) / sx - X[k + 1])
            g.append((X[k + 1][nc] * sx[nc] - self.min_gap_m) / sx[nc] + E[k])
            g.append((self.max_current_A - X[k + 1][:nc] * sx[:nc]) / sx[:nc] + E[k])
            # the two-quadrant chopper: the coil currents under U_k >= 0 (hard; scaled)
            g.append(m.coil_currents(X[k] * sx, U[k] * su, p[nx:nx + nd]) / sx[:nc])
        ex = X[N] * sx - xt
        J += ca.bilin(P, ex, ex)
        return J, ca.vertcat(*g)

    def _rows_per_interval(self) -> int:
        """Constraint rows per interval in :meth:`_problem`: the dynamics (n_x), then the
        inequalities: the soft gap (1), the soft current bound (n_c), the chopper's
        ``I >= 0`` (n_c), all ``>= 0``."""
        return self.model.nx + 1 + 2 * self.model.n_circuits

    def _bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        m, N = self.model, self.horizon
        nx, nu, nc = m.nx, m.nu, m.n_circuits
        _, nw, blk = self._layout()
        lbw, ubw = np.full(nw, -np.inf), np.full(nw, np.inf)
        ne = m.n_eddy
        xlo = np.r_[np.full(nc, m.current_range_A[0]), m.gap_range_m[0], -np.inf,
                    np.full(ne, -np.inf)] / self._sx
        xhi = np.r_[np.full(nc, m.current_range_A[1]), m.gap_range_m[1], np.inf,
                    np.full(ne, np.inf)] / self._sx
        for k in range(N + 1):
            if k >= 1:
                lbw[k * blk:k * blk + nx], ubw[k * blk:k * blk + nx] = xlo, xhi
            if k < N:
                lbw[k * blk + nx:k * blk + nx + nu] = -self._ulim / self._su
                ubw[k * blk + nx:k * blk + nx + nu] = self._ulim / self._su
                lbw[k * blk + nx + nu] = 0.0
        rows = self._rows_per_interval()
        ng = nx + N * rows
        lbg, ubg = np.zeros(ng), np.zeros(ng)
        for k in range(N):
            lbg[nx + k * rows + nx:nx + (k + 1) * rows] = 0.0
            ubg[nx + k * rows + nx:nx + (k + 1) * rows] = np.inf
        return lbw, ubw, lbg, ubg

    def _build(self, substeps: int) -> None:
        m = self.model
        nx, nd = m.nx, m.nd
        _, nw, _ = self._layout()
        self._np = 2 * nx + nd + m.nu
        self._lbw, self._ubw, self._lbg, self._ubg = self._bounds()
        p = ca.MX.sym("p", self._np)
        w = ca.MX.sym("w", nw)
        if self.solver == "ipopt":
            rhs, _ = m.spline_rhs()
            xs, us, ds = ca.MX.sym("x", nx), ca.MX.sym("u", m.nu), ca.MX.sym("d", nd)
            substeps = m.rk4_substeps(self.interval_s, substeps)
            hs = self.interval_s / substeps
            xk: Any = xs
            for _ in range(substeps):
                xk = rk4_substep(xk, hs, lambda v: rhs(v, us, ds))
            F = ca.Function("interval", [xs, us, ds], [xk])
            dv = p[nx:nx + nd]
            J, g = self._problem(w, p, lambda k, x, u: F(x, u, dv))
            self._nlp = ca.nlpsol("mpc_ipopt", "ipopt", {"x": w, "p": p, "f": J, "g": g},
                                  {"print_time": False, "ipopt.print_level": 0,
                                   "ipopt.sb": "yes", "ipopt.tol": 1e-10,
                                   "ipopt.warm_start_init_point": "yes"})
            return
        T = ca.MX.sym("table", m.table.size)
        Fd = m.discrete(self.interval_s, substeps, jacobians=True)
        # Gauss-Newton QP data at w: the interval Jacobians come from Fd's own (inlined)
        # AD; the constraint Jacobian is that of the linearised constraints in dw
        X, U, _ = self._unpack(w)
        sx, su = ca.DM(self._sx), ca.DM(self._su)
        d = p[nx:nx + nd]
        blocks = [Fd(X[k] * sx, U[k] * su, d, T)[:3] for k in range(self.horizon)]
        J, g = self._problem(w, p, lambda k, x, u: blocks[k][0])
        # the constraints linearised in a step dw: the interval maps replaced by their
        # Jacobians (A dx + B du), the rest is linear already
        dw = ca.MX.sym("dw", nw)
        _, g_lin = self._problem(dw, p, lambda k, x, u: blocks[k][1] @ x + blocks[k][2] @ u)
        Jg = ca.jacobian(g_lin, dw)
        H, grad = ca.hessian(J, w)
        data = ca.Function("mpc_qp_data", [w, p, T], [grad, g, Jg])
        self._qp_data = m.compile(data)
        self._A_sparsity = Jg.sparsity()
        Hf = ca.Function("H", [w, p], [H])
        self._H = ca.DM(Hf(np.zeros(nw), np.zeros(self._np)))
        opts: dict[str, Any] = {"error_on_fail": False}
        if self.qp_solver == "qrqp":
            opts.update(print_iter=False, print_header=False, print_info=False)
        elif self.qp_solver == "osqp":
            opts["osqp"] = {"verbose": False, "eps_abs": 1e-9, "eps_rel": 1e-9,
                            "max_iter": 20000, "polish": True}
            opts["warm_start_primal"] = True
        elif self.qp_solver == "qpoases":
            opts.update(printLevel="none", sparse=True)
        self._qp = ca.conic("mpc_qp", self.qp_solver,
                            {"h": self._H.sparsity(), "a": Jg.sparsity()}, opts)

    def _initial_guess(self, x_hat: np.ndarray, xt: np.ndarray, ut: np.ndarray) -> np.ndarray:
        nx, nu, N = self.model.nx, self.model.nu, self.horizon
        _, nw, blk = self._layout()
        w = np.zeros(nw)
        for k in range(N + 1):
            w[k * blk:k * blk + nx] = (x_hat if k == 0 else xt) / self._sx
            if k < N:
                w[k * blk + nx:k * blk + nx + nu] = ut / self._su
        return w

    def solve(self, x_hat: np.ndarray, d_hat: np.ndarray, xt: np.ndarray,
              ut: np.ndarray) -> tuple[np.ndarray, dict[str, Any]]:
        """Solve the OCP (warm-started from the previous solution); returns the first
        voltages [V] and ``{"iterations", "solution"}`` (the scaled decision vector).

        Parameters
        ----------
        x_hat : ndarray (n_x,)
            Estimated state: inductor currents [A], gap [m], gap rate [m/s].
        d_hat : ndarray (n_d,)
            Estimated disturbances.
        xt : ndarray (n_x,)
            Target steady state (from :meth:`MagnetHeaveModel.steady_state`).
        ut : ndarray (n_u,)
            Target voltages [V].

        Returns
        -------
        (u, info) : ndarray (n_u,), dict
            First voltages [V], and the iteration count and scaled solution.

        Raises
        ------
        SolverError
            A failed QP or IPOPT solve, or a solution beyond the voltage limit.
        """
        m = self.model
        nx = m.nx
        p = np.r_[x_hat, d_hat, xt, ut]
        w = self._w if self._w is not None else self._initial_guess(x_hat, xt, ut)
        if self._w is not None and math.isclose(self.interval_s, self.sample_time_s,
                                                rel_tol=1e-9):
            w = self._shift(w)
        it = 0
        if self.solver == "ipopt":
            kw: dict[str, Any] = {}
            if self._lam is not None:
                kw = {"lam_x0": self._lam[0], "lam_g0": self._lam[1]}
            r = self._nlp(x0=w, p=p, lbx=self._lbw, ubx=self._ubw, lbg=self._lbg,
                          ubg=self._ubg, **kw)
            st = self._nlp.stats()
            if not st["success"]:
                raise SolverError("IPOPT failed on the MPC problem",
                                  state={"x_hat": x_hat, "d_hat": d_hat},
                                  reason=str(st["return_status"]))
            w = np.asarray(r["x"], dtype=float).ravel()
            self._lam = (np.asarray(r["lam_x"]).ravel(), np.asarray(r["lam_g"]).ravel())
            it = int(st["iter_count"])
        else:
            for k in range(1, self.max_iter + 1):
                it = k
                grad, g, a_nz = self._qp_data(w, p)
                A = ca.DM(self._A_sparsity, a_nz)
                # cold QPs: starting qrqp from the previous multipliers (lam_x0, lam_a0)
                # took 1 iteration instead of ~20 but returned non-optimal steps that
                # let the gap run away (measured), so the QP is not warm-started
                r = self._qp(h=self._H, g=grad, a=A, lba=self._lbg - g, uba=self._ubg - g,
                             lbx=self._lbw - w, ubx=self._ubw - w)
                st = self._qp.stats()
                dw = np.asarray(r["x"], dtype=float).ravel()
                if not (st.get("success", False) and np.isfinite(dw).all()):
                    raise SolverError("the MPC's QP failed", state={"x_hat": x_hat,
                                                                    "d_hat": d_hat},
                                      reason=str(st.get("return_status", "unknown")))
                w = w + dw
                if float(np.max(np.abs(dw))) < self.tol:
                    break
        self._w = w
        u = w[nx:nx + m.nu] * self._su
        # the QP keeps |u| <= U_max up to its tolerance; remove that rounding only
        if np.any(np.abs(u) > self._ulim * (1 + 1e-6)):
            raise SolverError("the MPC solution violates the voltage limit",
                              state={"u": u}, reason="QP tolerance too loose")
        return np.clip(u, -self._ulim, self._ulim), {"iterations": it, "solution": w.copy()}

    def _shift(self, w: np.ndarray) -> np.ndarray:
        """The previous solution advanced by one interval (last block repeated)."""
        nx, N = self.model.nx, self.horizon
        _, nw, blk = self._layout()
        out = w.copy()
        out[:(N - 1) * blk] = w[blk:N * blk]
        out[(N - 1) * blk:(N - 1) * blk + nx] = w[N * blk:N * blk + nx]
        return out

    def solve_ocp(self, x_hat: Any, d_hat: Any = None, *, gap_ref_m: float | None = None,
                  cold: bool = True) -> dict[str, np.ndarray]:
        """One OCP solve from ``x_hat`` (for tests and comparisons): the target for
        ``gap_ref_m`` and the disturbance, the optimal inputs (N, n_u) [V] and states
        (N+1, n_x).

        Parameters
        ----------
        x_hat : array_like (n_x,)
            Initial state: inductor currents [A], gap [m], gap rate [m/s].
        d_hat : array_like (n_d,), optional
            Disturbances (default zeros).
        gap_ref_m : float, optional
            Gap reference [m] (default: the controller's; keyword only).
        cold : bool, default True
            Forget the previous solution (no warm start; keyword only).

        Returns
        -------
        dict of str to ndarray
            ``states`` (N+1, n_x), ``inputs_V`` (N, n_u), ``target_state``,
            ``target_input_V``, ``iterations``.
        """
        m = self.model
        x = np.asarray(x_hat, dtype=float).reshape(m.nx)
        d = np.zeros(m.nd) if d_hat is None else np.asarray(d_hat, dtype=float).reshape(m.nd)
        xt, ut = m.steady_state(self._gap_ref if gap_ref_m is None else gap_ref_m, d)
        if cold:
            self._w, self._lam = None, None
        _, info = self.solve(x, d, xt, ut)
        X, U, _ = self._unpack(info["solution"])
        return {"states": np.array([np.asarray(v).ravel() * self._sx for v in X]),
                "inputs_V": np.array([np.asarray(v).ravel() * self._su for v in U]),
                "target_state": xt, "target_input_V": ut,
                "iterations": np.array(info["iterations"])}

