"""Simplified current-based magnet model (paper Sec. IV, eq. 8 and Fig. 8).

One ODE per electric circuit ``j`` in the current ``I_L`` through the inductance of the
equivalent circuit of Fig. 8 (``R_el`` in series with ``R_ec || L(s, I_L)``)::

    a      = 1 + R_el / R_ec
    dI_L/dt = [ (U - R_el I_L) / a  -  dL/ds(s, I_L) I_L ds/dt ] / L~(s, I_L)       (8)

with the characteristic maps ``L~ = dL/dI I + L``, ``dL/ds`` and ``F(s, I)``.  Outputs:

* coil current ``I = (U - U_L) / R_el`` with ``U_L = (U - R_el I_L) / a`` (equals ``I_L`` in
  steady state, jumps by ``dU / (R_el + R_ec)`` on a voltage step);
* circuit force ``F_j(s_j, I_L)`` read from the force map (the map is computed from the
  network co-energy, so it satisfies eq. 9 up to the neglected inter-circuit coupling);
* per-pole forces: the circuit force shared equally by the circuit's poles (the paper's
  concentrated force per circuit).

The substitute gap of a circuit is the mean of its poles' gaps.  Maps are B-spline
interpolants (CasADi), so the same model gives exact Jacobians for linearisation and MPC.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, OutOfRangeError, SolverError

__all__ = ["CurrentModel", "CurrentModelState", "ReducedSimulation"]


@dataclass(frozen=True)
class CurrentModelState:
    """State of the current-based model: time [s] and inductor currents I_L [A]."""

    time_s: float
    inductor_currents_A: np.ndarray


@dataclass(frozen=True)
class ReducedSimulation:
    """Time series of a current-based simulation (rows: time samples).

    Attributes
    ----------
    time_s : ndarray (n_t,)
    gaps_m : ndarray (n_t, n_gaps)
        Pole gaps (inputs).
    voltages_V : ndarray (n_t, n_circuits)
        Voltages (zero-order hold: the value applied from this sample on).
    currents_A : ndarray (n_t, n_circuits)
        Coil currents.
    inductor_currents_A : ndarray (n_t, n_circuits)
        States ``I_L``.
    circuit_force_N : ndarray (n_t, n_circuits)
    pole_force_N : ndarray (n_t, n_gaps)
    force_N : ndarray (n_t,)
    """

    circuit_names: tuple[str, ...]
    gap_names: tuple[str, ...]
    time_s: np.ndarray
    gaps_m: np.ndarray
    voltages_V: np.ndarray
    currents_A: np.ndarray
    inductor_currents_A: np.ndarray
    circuit_force_N: np.ndarray
    pole_force_N: np.ndarray
    force_N: np.ndarray


class CurrentModel:
    """The current-based model of a magnet, built from its characteristic maps.

    Parameters
    ----------
    maps : CharacteristicMaps
        From :func:`maglevkit.reduction.build_maps` or :func:`~maglevkit.reduction.load_maps`.
    extrapolate : bool
        Leaving the maps' gap or current range raises :class:`OutOfRangeError` (default);
        with ``True`` the maps are continued linearly from their edge (value and slope)
        and a warning is issued.
    rtol, atol : float
        CVODES tolerances (defaults 1e-8 relative, 1e-10 A absolute).
    """

    def __init__(self, maps: Any, *, extrapolate: bool = False, rtol: float = 1e-8,
                 atol: float = 1e-10) -> None:
        self.maps = maps
        self.extrapolate = extrapolate
        self.rtol, self.atol = rtol, atol
        self.circuit_names: tuple[str, ...] = maps.circuits
        groups = maps.pole_groups
        self.gap_names: tuple[str, ...] = tuple(
            maps.dataset.attrs.get("gap_names", "").split(",")) if maps.dataset.attrs.get(
            "gap_names") else tuple(g for c in self.circuit_names for g in groups[c])
        gi = {g: k for k, g in enumerate(self.gap_names)}
        nc, ng = len(self.circuit_names), len(self.gap_names)
        # averaging matrix: substitute gap per circuit = mean of its poles' gaps
        self._avg = np.zeros((nc, ng))
        for j, c in enumerate(self.circuit_names):
            for g in groups[c]:
                self._avg[j, gi[g]] = 1.0 / len(groups[c])
        self._share = (self._avg > 0).T / np.maximum((self._avg > 0).sum(axis=1), 1)  # (ng, nc)
        self.gap_range = (float(maps.gaps_m[0]), float(maps.gaps_m[-1]))
        self.current_range = (float(maps.currents_A[0]), float(maps.currents_A[-1]))
        r_el = np.asarray(maps.dataset["resistance_ohm"].values, dtype=float)
        r_ec = np.asarray(maps.dataset["eddy_resistance_ohm"].values, dtype=float)
        self.resistance_ohm = r_el
        self.eddy_resistance_ohm = r_ec
        a = 1.0 + np.where(np.isinf(r_ec), 0.0, r_el / np.where(np.isinf(r_ec), 1.0, r_ec))

        grid = [maps.gaps_m, maps.currents_A]

        def spline(var: str, j: int) -> ca.Function:
            values = maps.variable(var, self.circuit_names[j])
            if not np.all(np.isfinite(values)):
                raise InputError(f"map {var!r} of circuit {self.circuit_names[j]!r} has non-finite "
                                 "values; rebuild the maps")
            return ca.interpolant(f"{var}_{j}", "bspline", grid, values.ravel(order="F"))

        x = ca.SX.sym("I_L", nc)
        U = ca.SX.sym("U", nc)
        s = ca.SX.sym("s", nc)
        sd = ca.SX.sym("sdot", nc)
        mx_rhs, forces, ltil = [], [], []
        xm, Um, sm, sdm = (ca.MX.sym(n, nc) for n in ("I_L", "U", "s", "sdot"))
        lo = ca.DM([self.gap_range[0], self.current_range[0]])
        hi = ca.DM([self.gap_range[1], self.current_range[1]])

        def extended(fun: ca.Function, arg: ca.MX) -> ca.MX:
            # CasADi's B-spline is 0 outside its grid; continue it linearly (C1) instead,
            # so that the integrator stays well-defined. Leaving the range is still
            # reported (or warned about) by the range checks on every returned sample.
            a0 = ca.MX.sym("a", 2)
            lin = ca.Function("lin", [a0], [fun(a0), ca.jacobian(fun(a0), a0)])
            clamped = ca.fmin(ca.fmax(arg, lo), hi)
            val, grad = lin(clamped)
            return val + ca.mtimes(grad, arg - clamped)

        for j in range(nc):
            arg = ca.vertcat(sm[j], xm[j])
            lt = extended(spline("inductance_H", j), arg)
            dl = extended(spline("dL_ds_H_per_m", j), arg)
            f = extended(spline("force_N", j), arg)
            rhs = ((Um[j] - r_el[j] * xm[j]) / a[j] - dl * xm[j] * sdm[j]) / lt
            mx_rhs.append(rhs)
            forces.append(f)
            ltil.append(lt)
        del x, U, s, sd
        u_L = (Um - ca.DM(r_el) * xm) / ca.DM(a)
        coil = (Um - u_L) / ca.DM(r_el)
        self.ode = ca.Function("current_model_ode", [xm, Um, sm, sdm], [ca.vertcat(*mx_rhs)],
                               ["I_L", "U", "s", "sdot"], ["dI_L"])
        self.outputs = ca.Function("current_model_out", [xm, Um, sm],
                                   [coil, ca.vertcat(*forces), ca.vertcat(*ltil)],
                                   ["I_L", "U", "s"], ["I", "F", "Ltilde"])
        # Integrator: states [I_L; s], controls [U; sdot] piecewise constant.
        X = ca.MX.sym("X", 2 * nc)
        Uc = ca.MX.sym("u", 2 * nc)
        dae = {"x": X, "u": Uc,
               "ode": ca.vertcat(self.ode(X[:nc], Uc[:nc], X[nc:], Uc[nc:]), Uc[nc:])}
        self._dae = dae
        self._integrators: dict[Any, ca.Function] = {}

    # ------------------------------------------------------------------ helpers
    @property
    def n_circuits(self) -> int:
        return len(self.circuit_names)

    def substitute_gaps(self, gaps: np.ndarray) -> np.ndarray:
        """Mean gap per circuit [m] from pole gaps (..., n_gaps)."""
        return np.asarray(gaps) @ self._avg.T

    def _check_range(self, s: np.ndarray, i_l: np.ndarray, t: np.ndarray | None = None) -> None:
        lo_s, hi_s = self.gap_range
        lo_i, hi_i = self.current_range
        tol_s = 1e-12 * hi_s
        tol_i = 1e-9 * max(1.0, hi_i)
        bad_s = (s < lo_s - tol_s) | (s > hi_s + tol_s)
        bad_i = (i_l < lo_i - tol_i) | (i_l > hi_i + tol_i)
        bad = bad_s | bad_i
        if not np.any(bad):
            return
        idx = np.argwhere(bad)[0]
        k = int(idx[0]) if bad.ndim > 1 else 0
        j = int(idx[-1])
        where = f" at t = {t[k]:.6g} s" if t is not None else ""
        msg = (f"circuit {self.circuit_names[j]!r}{where}: substitute gap "
               f"{np.atleast_2d(s)[k if bad.ndim > 1 else 0, j]:.6g} m and current "
               f"{np.atleast_2d(i_l)[k if bad.ndim > 1 else 0, j]:.6g} A; the maps cover gaps "
               f"{lo_s:g}..{hi_s:g} m and currents {lo_i:g}..{hi_i:g} A")
        if self.extrapolate:
            warnings.warn("extrapolating the characteristic maps: " + msg, stacklevel=3)
            return
        raise OutOfRangeError("outside the characteristic maps: " + msg
                              + " (rebuild the maps on a larger grid, or pass extrapolate=True)")

    def _integrator(self, grid: tuple[float, ...]) -> ca.Function:
        key = grid
        f = self._integrators.get(key)
        if f is None:
            opts = {"abstol": self.atol, "reltol": self.rtol, "max_num_steps": 100000}
            f = ca.integrator("current_model", "cvodes", self._dae, 0.0, list(grid), opts)
            if len(self._integrators) > 32:
                self._integrators.clear()
            self._integrators[key] = f
        return f

    # ------------------------------------------------------------------ stepping interface
    def initial_state(self, *, currents: Any, time_s: float = 0.0) -> CurrentModelState:
        """A steady state with the given coil currents [A] (``I_L = I``)."""
        i = _per_circuit(currents, self.circuit_names, "currents")
        return CurrentModelState(float(time_s), i)

    def step(self, state: CurrentModelState, dt: float, *, voltages: Any, gaps: Any,
             gap_rates: Any = 0.0) -> tuple[CurrentModelState, dict[str, np.ndarray]]:
        """Advance by ``dt`` [s] with constant voltages [V] and linearly moving gaps.

        ``gaps`` [m] are the pole gaps at the start of the step, ``gap_rates`` [m/s] their
        (constant) rates.  Returns the new state and the outputs at its end.
        """
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise InputError(f"dt = {dt!r} s must be a finite number > 0")
        u = _per_circuit(voltages, self.circuit_names, "voltages")
        g = _per_gap(gaps, self.gap_names, positive=True)
        gd = _per_gap(gap_rates, self.gap_names, positive=False)
        s0, sd = self.substitute_gaps(g), self.substitute_gaps(gd)
        self._check_range(s0, state.inductor_currents_A)
        self._check_range(s0 + sd * dt, state.inductor_currents_A)
        f = self._integrator((float(dt),))
        try:
            res = f(x0=np.concatenate([state.inductor_currents_A, s0]),
                    u=np.concatenate([u, sd]))
        except RuntimeError as exc:
            raise SolverError("current-model integration failed", time=state.time_s,
                              state={"I_L": state.inductor_currents_A, "s": s0},
                              reason=_last_line(str(exc))) from None
        x = np.asarray(res["xf"]).ravel()
        nc = self.n_circuits
        self._check_range(x[nc:], x[:nc])
        new = CurrentModelState(state.time_s + float(dt), x[:nc])
        coil, fc, _ = (np.asarray(v).ravel() for v in self.outputs(x[:nc], u, x[nc:]))
        return new, {"currents_A": coil, "circuit_force_N": fc,
                     "pole_force_N": self._share @ fc, "force_N": np.array(fc.sum())}

    def _locate_failure(self, t: np.ndarray, x0: np.ndarray, uu: np.ndarray, reason: str) -> None:
        """After a failed run: step interval by interval to say where and why it failed."""
        nc = self.n_circuits
        x = x0
        for k in range(t.size - 1):
            self._check_range(x[nc:][None, :], x[:nc][None, :], t[k:k + 1])
            try:
                x = np.asarray(self._integrator((float(t[k + 1] - t[k]),))(
                    x0=x, u=uu[:, k])["xf"]).ravel()
            except RuntimeError as exc:
                # The state left the maps inside this interval, or the solver failed:
                # retrace the interval in 64 sub-steps and check the range after each.
                h = float(t[k + 1] - t[k]) / 64
                sub = self._integrator((h,))
                xs = x
                for m in range(64):
                    try:
                        xs = np.asarray(sub(x0=xs, u=uu[:, k])["xf"]).ravel()
                    except RuntimeError:
                        break
                    if not np.all(np.isfinite(xs)):
                        break
                    self._check_range(xs[nc:][None, :], xs[:nc][None, :],
                                      np.array([t[k] + (m + 1) * h]))
                raise SolverError("current-model integration failed", time=float(t[k]),
                                  state={"I_L": x[:nc], "s": x[nc:]},
                                  reason=_last_line(str(exc))) from None
            if np.any(~np.isfinite(x)):
                break
            self._check_range(x[nc:][None, :], x[:nc][None, :], t[k + 1:k + 2])
        raise SolverError("current-model integration failed", time=float(t[0]),
                          state={"I_L": x0[:nc], "s": x0[nc:]}, reason=_last_line(reason))

    # ------------------------------------------------------------------ batch simulation
    def simulate_sampled(self, time_s: np.ndarray, *, gaps: np.ndarray, voltages: np.ndarray,
                         initial_currents: Any) -> ReducedSimulation:
        """Simulate on a time grid with sampled inputs.

        ``gaps`` (n_t, n_gaps) are linear between samples; ``voltages`` (n_t, n_circuits) are
        held constant from each sample to the next.
        """
        t = np.asarray(time_s, dtype=float)
        if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
            raise InputError("time grid must be 1-D, finite, strictly increasing, >= 2 samples")
        g = np.asarray(gaps, dtype=float)
        u = np.asarray(voltages, dtype=float)
        if g.shape != (t.size, len(self.gap_names)) or u.shape != (t.size, self.n_circuits):
            raise InputError(f"gaps must be ({t.size}, {len(self.gap_names)}) and voltages "
                             f"({t.size}, {self.n_circuits}); got {g.shape} and {u.shape}")
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(u))):
            raise InputError("gaps and voltages must be finite")
        if np.any(g <= 0):
            raise InputError("gaps must be > 0 m")
        s = self.substitute_gaps(g)
        i0 = _per_circuit(initial_currents, self.circuit_names, "initial_currents")
        self._check_range(s, np.broadcast_to(i0, s.shape), t)
        sd = np.diff(s, axis=0) / np.diff(t)[:, None]
        rel = tuple(float(v) for v in (t[1:] - t[0]))
        f = self._integrator(rel)
        uu = np.concatenate([u[:-1], sd], axis=1).T
        x0 = np.concatenate([i0, s[0]])
        try:
            res = f(x0=x0, u=uu)
        except RuntimeError as exc:
            self._locate_failure(t, x0, uu, str(exc))
        xs = np.concatenate([x0[:, None], np.asarray(res["xf"])], axis=1).T
        nc = self.n_circuits
        il = xs[:, :nc]
        self._check_range(xs[:, nc:], il, t)
        coil, fc, _ = self.outputs.map(t.size)(il.T, u.T, xs[:, nc:].T)
        fc = np.asarray(fc).T
        return ReducedSimulation(
            circuit_names=self.circuit_names, gap_names=self.gap_names, time_s=t, gaps_m=g,
            voltages_V=u, currents_A=np.asarray(coil).T, inductor_currents_A=il,
            circuit_force_N=fc, pole_force_N=fc @ self._share.T, force_N=fc.sum(axis=1))


def _last_line(text: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    return lines[-1] if lines else text


def _per_circuit(value: Any, names: tuple[str, ...], what: str) -> np.ndarray:
    if isinstance(value, dict):
        missing = [n for n in names if n not in value]
        unknown = sorted(set(value) - set(names))
        if missing or unknown:
            raise InputError(f"{what}: give one value per circuit {list(names)} "
                             f"(missing {missing}, unknown {unknown})")
        arr = np.array([float(value[n]) for n in names])
    else:
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 0:
            arr = np.full(len(names), float(arr))
        if arr.shape != (len(names),):
            raise InputError(f"{what}: expected {len(names)} values (circuits {list(names)}), "
                             f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what} must be finite, got {arr}")
    return arr


def _per_gap(value: Any, names: tuple[str, ...], *, positive: bool) -> np.ndarray:
    arr = _per_circuit(value, names, "gaps" if positive else "gap_rates")
    if positive and np.any(arr <= 0):
        raise InputError(f"gaps must be > 0 m, got {arr}")
    return arr
