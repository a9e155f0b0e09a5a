"""Extended Kalman filter on the augmented magnet model ``z = [x; d]`` (docs/control.md).

Discrete model over one sample ``T`` (RK4 on the same CasADi right-hand side as the MPC)::

    x_k+1 = F_T(x_k, u_k, d_k) + w_x,     d_k+1 = d_k + w_d      (integrating disturbance)
    y_k   = h(x_k, u_k-1, d_k) + v        (the currents are measured with the voltage
                                           held over the previous interval)

One compiled call per sample does prediction (with the voltage applied since the last
sample) and correction (Joseph form); Jacobians by CasADi AD.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, SolverError
from .model import MagnetHeaveModel

__all__ = ["ExtendedKalmanFilter"]


class ExtendedKalmanFilter:
    """EKF for the state and disturbance of a :class:`MagnetHeaveModel`.

    Parameters
    ----------
    model : MagnetHeaveModel
        Prediction model with its disturbance model (the estimated state is
        ``[x; d]``).
    sample_time_s : float
        Sample time T [s], finite and > 0.
    process_std : array (n_x,), optional
        Standard deviation of the state noise per sample ``w_x`` (default: 0.05 A,
        1e-7 m, 1e-4 m/s).
    disturbance_std : array (n_d,), optional
        Standard deviation of the disturbance random walk per sample ``w_d`` (default:
        20 N, 0.5 V, 1e-5 m, 0.05 A per sample; sets how fast the estimates follow).
    measurement_std : array (n_y,), optional
        Measurement noise, > 0 (default: 1e-6 m gap, 0.01 A current).
    substeps : int
        RK4 steps per sample (default 1).

    Raises
    ------
    InputError
        ``sample_time_s`` not finite and > 0; standard deviations not finite and >= 0
        (measurement ones > 0).  Arrays of the wrong length raise numpy's ``ValueError``.
    """

    def __init__(self, model: MagnetHeaveModel, *, sample_time_s: float,
                 process_std: Any = None, disturbance_std: Any = None,
                 measurement_std: Any = None, substeps: int = 1) -> None:
        if not (math.isfinite(sample_time_s) and sample_time_s > 0):
            raise InputError(f"sample_time_s = {sample_time_s!r} must be a finite number > 0")
        self.model = model
        self.sample_time_s = float(sample_time_s)
        nx, nd, ny, nc = model.nx, model.nd, model.ny, model.n_circuits
        q = (np.r_[np.full(nc, 0.05), 1e-7, 1e-4, np.full(model.n_eddy, 0.05)]
             if process_std is None
             else np.asarray(process_std, dtype=float).reshape(nx))
        defaults = {"force": [20.0], "voltage": [0.5] * nc, "gap_sensor": [1e-5],
                    "current_sensor": [0.05] * nc}
        qd = (np.array([v for dname in model.disturbances for v in defaults[dname]])
              if disturbance_std is None else np.asarray(disturbance_std, dtype=float).reshape(nd))
        r = (np.r_[1e-6, np.full(nc, 0.01)] if measurement_std is None
             else np.asarray(measurement_std, dtype=float).reshape(ny))
        for name, arr in (("process_std", q), ("disturbance_std", qd), ("measurement_std", r)):
            if not (np.isfinite(arr).all() and (arr >= 0).all()):
                raise InputError(f"{name} must be finite and >= 0")
        if not (r > 0).all():
            raise InputError("measurement_std must be > 0")
        self.Q = np.diag(np.r_[q, qd] ** 2)
        self.R = np.diag(r ** 2)
        nz = nx + nd
        F = model.discrete(self.sample_time_s, substeps, jacobians=True)
        z, P = ca.MX.sym("z", nz), ca.MX.sym("P", nz, nz)
        u_prev, y = ca.MX.sym("u_prev", model.nu), ca.MX.sym("y", ny)
        T = ca.MX.sym("table", model.table.size)
        Qm, Rm = ca.DM(self.Q), ca.DM(self.R)
        x, d = z[:nx], z[nx:]
        xp, A, B, Bd, _, _, _, _ = F(x, u_prev, d, T)
        # the Kalman algebra, the measurement at the prediction included (its map reads no
        # table), as one function expanded to scalar code; only the RK4 map above reads
        # the maps
        ks = [ca.MX.sym(n, *v.shape) for n, v in (("xp", xp), ("A", A), ("Bd", Bd),
                                                   ("d", d), ("P", P), ("u", u_prev),
                                                   ("y", y))]
        P_in = P                     # the step's input; P below: the expanded part's
        k_xp, k_A, k_Bd, k_d, P, k_u, k_y = ks
        zp = ca.vertcat(k_xp, k_d)
        Az = ca.vertcat(ca.horzcat(k_A, k_Bd), ca.horzcat(ca.DM.zeros(nd, nx), ca.DM.eye(nd)))
        Pp = Az @ P @ Az.T + Qm
        yp = model.expressions(k_xp, k_u, k_d, T)[1]
        H = ca.horzcat(ca.jacobian(yp, k_xp), ca.jacobian(yp, k_d))
        S = H @ Pp @ H.T + Rm
        K = ca.solve(S, H @ Pp, "symbolicqr").T     # (n_y x n_y: QR in scalar code)
        zc = zp + K @ (k_y - yp)
        IKH = ca.DM.eye(nz) - K @ H
        Pc = IKH @ Pp @ IKH.T + K @ Rm @ K.T
        Pc = 0.5 * (Pc + Pc.T)
        kalman = ca.Function("mpc_ekf_update", ks, [zc, Pc, k_y - yp]).expand()
        zc, Pc, innov = kalman(xp, A, Bd, d, P_in, u_prev, y)
        f = ca.Function("mpc_ekf", [z, P_in, u_prev, y, T], [zc, Pc, innov],
                        ["z", "P", "u_prev", "y", "table"], ["z_next", "P_next", "innovation"])
        self.step_function = f          # symbolic, for controllers that embed the step
        self._step = model.compile(f)
        self.state = np.zeros(nz)
        self.covariance = np.eye(nz)
        self.innovation = np.zeros(ny)

    def reset(self, state: Any, disturbance: Any = None, *, covariance: Any = None) -> None:
        """Initial estimate: state ``x`` (n_x,), disturbance (n_d,, default 0), covariance
        (default: 1 A, 1 mm, 10 mm/s, and 10 % of the weight / 10 V / 1 mm / 1 A).

        Parameters
        ----------
        state : array_like (n_x,)
            Initial state: inductor currents [A], gap [m], gap rate [m/s].
        disturbance : array_like (n_d,), optional
            Initial disturbance estimate in the order of the model's
            ``disturbance_names`` (default zeros).
        covariance : array_like (n_x + n_d, n_x + n_d), optional
            Initial error covariance (SI units squared; keyword only).
        """
        m = self.model
        x = np.asarray(state, dtype=float).reshape(m.nx)
        d = np.zeros(m.nd) if disturbance is None else np.asarray(disturbance, dtype=float)
        self.state = np.r_[x, d.reshape(m.nd)]
        if covariance is None:
            nc = m.n_circuits
            big = {"force": [0.1 * m.mass_kg * m.gravity], "voltage": [10.0] * nc,
                   "gap_sensor": [1e-3], "current_sensor": [1.0] * nc}
            sd = np.r_[np.full(nc, 1.0), 1e-3, 1e-2, np.full(m.n_eddy, 1.0),
                       [v for dname in m.disturbances for v in big[dname]]]
            self.covariance = np.diag(sd ** 2)
        else:
            self.covariance = np.asarray(covariance, dtype=float).reshape(m.nx + m.nd,
                                                                          m.nx + m.nd)

    def update(self, measurement: np.ndarray, previous_voltages: np.ndarray) -> np.ndarray:
        """Predict over the last interval (voltages ``previous_voltages`` [V]) and correct
        with ``measurement = [gap, currents]``; returns the estimate ``[x; d]``.

        Parameters
        ----------
        measurement : array_like (n_y,)
            Measured gap [m], then the circuit currents [A].
        previous_voltages : array_like (n_u,)
            Voltages [V] held over the interval that just ended.

        Returns
        -------
        ndarray (n_x + n_d,)
            The corrected estimate (also kept as :attr:`state`).

        Raises
        ------
        SolverError
            If the estimate becomes non-finite (the filter diverged).
        """
        z, P, e = self._step(self.state, self.covariance, previous_voltages, measurement)
        if not np.isfinite(z).all():
            raise SolverError("the extended Kalman filter diverged",
                              state={"estimate": self.state, "measurement": measurement},
                              reason="non-finite estimate")
        self.state = z
        self.covariance = P
        self.innovation = e
        return z
