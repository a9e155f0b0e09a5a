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
from .inputs import gap_secants, sample_input, time_grid

__all__ = ["CurrentModel", "CurrentModelState", "CurrentOutputs", "ReducedSimulation"]


@dataclass(frozen=True)
class CurrentModelState:
    """State of the current-based model at one instant.

    Attributes
    ----------
    time_s : float
        Time [s].
    inductor_currents_A : ndarray (n_circuits,)
        The ODE states ``I_L`` [A].
    gaps_m : ndarray (n_gaps,)
        Pole gaps [m].
    """

    time_s: float
    inductor_currents_A: np.ndarray
    gaps_m: np.ndarray


@dataclass(frozen=True)
class CurrentOutputs:
    """Outputs of the current-based model at the end of a step.

    Attributes
    ----------
    time_s : float
    currents_A : ndarray (n_circuits,)
        Coil currents [A] (with the voltages of the step just taken).
    inductor_currents_A : ndarray (n_circuits,)
    circuit_force_N : ndarray (n_circuits,)
    pole_force_N : ndarray (n_gaps,)
        Circuit force shared equally by the circuit's poles [N].
    force_N : float
    """

    time_s: float
    currents_A: np.ndarray
    inductor_currents_A: np.ndarray
    circuit_force_N: np.ndarray
    pole_force_N: np.ndarray
    force_N: float


@dataclass(frozen=True)
class ReducedSimulation:
    """Time series of a current-based simulation (SI units; axis 0 is time).

    Same conventions as :class:`~maglevkit.models.flux.SimulationResult`: values at
    ``time_s[k]`` are left limits (before the inputs change at ``t_k``);
    ``voltages_V[k]`` and ``gap_rates_m_per_s[k]`` are the inputs held on
    ``[t_k, t_{k+1})`` (the last row repeats the previous one).

    Attributes
    ----------
    time_s : ndarray (n_t,)
    gaps_m, gap_rates_m_per_s : ndarray (n_t, n_gaps)
    voltages_V, currents_A, inductor_currents_A, circuit_force_N : ndarray (n_t, n_circuits)
    pole_force_N : ndarray (n_t, n_gaps)
    force_N : ndarray (n_t,)
    """

    time_s: np.ndarray
    gaps_m: np.ndarray
    gap_rates_m_per_s: np.ndarray
    voltages_V: np.ndarray
    currents_A: np.ndarray
    inductor_currents_A: np.ndarray
    circuit_force_N: np.ndarray
    pole_force_N: np.ndarray
    force_N: np.ndarray
    gap_names: tuple[str, ...]
    circuit_names: tuple[str, ...]
    final_state: CurrentModelState


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
        self.outputs_fun = ca.Function("current_model_out", [xm, Um, sm],
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

    def _integrate_stepwise(self, t: np.ndarray, x0: np.ndarray, uu: np.ndarray,
                            reason: str) -> np.ndarray:
        """Fallback after a failed one-pass run: integrate interval by interval.

        Returns the states if every interval succeeds; raises OutOfRangeError where the
        state leaves the maps, else SolverError with the failing time and state.
        """
        nc = self.n_circuits
        x = x0
        out = [x0]
        for k in range(t.size - 1):
            try:
                x = np.asarray(self._integrator((float(t[k + 1] - t[k]),))(
                    x0=x, u=uu[:, k])["xf"]).ravel()
            except RuntimeError as exc:
                # Retrace this interval in 64 sub-steps, checking the range after each.
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
            if not np.all(np.isfinite(x)):
                raise SolverError("current-model integration gave non-finite states",
                                  time=float(t[k + 1]), state={"I_L": out[-1][:nc]},
                                  reason=_last_line(reason))
            self._check_range(x[nc:][None, :], x[:nc][None, :], t[k + 1:k + 2])
            out.append(x)
        return np.array(out).T[:, 1:]

    # ------------------------------------------------------------------ stepping interface
    def initial_state(self, *, gaps: Any, currents: Any, time: float = 0.0) -> CurrentModelState:
        """The steady state at ``gaps`` [m] with coil currents ``currents`` [A] (``I_L = I``)."""
        g = _per_gap(gaps, self.gap_names, positive=True)
        i = _per_circuit(currents, self.circuit_names, "currents")
        if not math.isfinite(time):
            raise InputError(f"time = {time!r} must be finite")
        self._check_range(self.substitute_gaps(g)[None, :], i[None, :], np.array([time]))
        return CurrentModelState(float(time), i, g)

    def outputs(self, state: CurrentModelState, voltages: Any) -> CurrentOutputs:
        """Outputs at ``state`` with ``voltages`` [V] applied."""
        u = _per_circuit(voltages, self.circuit_names, "voltages")
        coil, fc, _ = (np.asarray(v).ravel() for v in self.outputs_fun(
            state.inductor_currents_A, u, self.substitute_gaps(state.gaps_m)))
        return CurrentOutputs(state.time_s, coil, state.inductor_currents_A.copy(), fc,
                              self._share @ fc, float(fc.sum()))

    def step(self, state: CurrentModelState, dt: float, voltages: Any, gaps: Any = None,
             gap_rates: Any = 0.0) -> tuple[CurrentModelState, CurrentOutputs]:
        """Advance by ``dt`` [s] with constant voltages [V] and linearly moving gaps.

        Same contract as :meth:`maglevkit.models.flux.FluxModel.step`: ``gaps`` [m] at the
        start of the step (None keeps the state's), ``gap_rates`` [m/s] over the step.
        """
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise InputError(f"dt = {dt!r} s must be a finite number > 0")
        u = _per_circuit(voltages, self.circuit_names, "voltages")
        g = state.gaps_m if gaps is None else _per_gap(gaps, self.gap_names, positive=True)
        gd = _per_gap(gap_rates, self.gap_names, positive=False)
        if np.any(g + gd * dt <= 0.0):
            raise InputError(f"gaps must stay > 0 m over the step: end {(g + gd * dt).tolist()} m")
        s0, sd = self.substitute_gaps(g), self.substitute_gaps(gd)
        t = np.array([state.time_s, state.time_s + dt])
        x = self._integrate(t, np.concatenate([state.inductor_currents_A, s0]),
                            np.concatenate([u, sd])[:, None])[-1]
        new = CurrentModelState(state.time_s + float(dt), x[:self.n_circuits], g + gd * dt)
        return new, self.outputs(new, u)

    def _integrate(self, t: np.ndarray, x0: np.ndarray, uu: np.ndarray) -> np.ndarray:
        """States (n_t, 2 n_c) on the grid ``t``; controls ``uu`` (2 n_c, n_t - 1)."""
        f = self._integrator(tuple(float(v) for v in (t[1:] - t[0])))
        try:
            xf = np.asarray(f(x0=x0, u=uu)["xf"])
        except RuntimeError as exc:
            xf = self._integrate_stepwise(t, x0, uu, str(exc))
        xs = np.concatenate([x0[:, None], xf], axis=1).T
        nc = self.n_circuits
        self._check_range(xs[:, nc:], xs[:, :nc], t)
        return xs

    def simulate(self, t: Any, *, gaps: Any, voltages: Any, gap_rates: Any = None,
                 dt: float | None = None, initial_currents: Any = None,
                 initial_state: CurrentModelState | None = None,
                 gap_rate_tolerance: float = 0.02) -> ReducedSimulation:
        """Simulate on a time grid; same inputs and conventions as :func:`maglevkit.simulate`.

        Gaps move linearly between samples, voltages are held from each sample to the
        next; the default initial state is the steady state ``I = U(t0) / R_el``.
        """
        times = time_grid(t, dt)
        g = sample_input(gaps, times, self.gap_names, "gaps", "m")
        if np.any(g <= 0.0):
            raise InputError("gaps must be > 0 m")
        u = sample_input(voltages, times, self.circuit_names, "voltages", "V")
        secant = gap_secants(times, g, gap_rates, self.gap_names, gap_rate_tolerance)
        if initial_state is not None:
            if initial_currents is not None:
                raise InputError("give initial_currents or initial_state, not both")
            if not isinstance(initial_state, CurrentModelState):
                raise InputError("initial_state must be a CurrentModelState")
            i0 = initial_state.inductor_currents_A
        else:
            i0 = _per_circuit(u[0] / self.resistance_ohm if initial_currents is None
                              else initial_currents, self.circuit_names, "initial_currents")
        s = self.substitute_gaps(g)
        self._check_range(s, np.broadcast_to(i0, s.shape), times)
        sd = self.substitute_gaps(secant)
        xs = self._integrate(times, np.concatenate([i0, s[0]]),
                             np.concatenate([u[:-1], sd], axis=1).T)
        nc = self.n_circuits
        il = xs[:, :nc]
        held = np.vstack((u[:1], u[:-1]))          # left limits: the voltage of [t_k-1, t_k)
        coil, fc, _ = self.outputs_fun.map(times.size)(il.T, held.T, xs[:, nc:].T)
        fc = np.asarray(fc).T
        final = CurrentModelState(float(times[-1]), il[-1].copy(), g[-1].copy())
        return ReducedSimulation(
            time_s=times, gaps_m=g, gap_rates_m_per_s=np.vstack((secant, secant[-1:])),
            voltages_V=np.vstack((u[:-1], u[-2:-1])), currents_A=np.asarray(coil).T,
            inductor_currents_A=il, circuit_force_N=fc, pole_force_N=fc @ self._share.T,
            force_N=fc.sum(axis=1), gap_names=self.gap_names, circuit_names=self.circuit_names,
            final_state=final)


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
