"""Prediction model of the MPC and its observer: one magnet's reduced circuits + heave mass,
augmented by a disturbance model (docs/control.md).

State ``x = [I_L,1..n_c, s, s']`` (inductor currents [A], gap [m], gap rate [m/s]), input
``u = U`` (circuit voltages [V]), disturbance ``d`` (constant in the model)::

    I_L,j' = eq. 8 of circuit j (MagnetBank expressions) at the voltage U_j + d_U,j
    s''    = g + (F_ext + d_F - sum_j F_j(s, I_L,j)) / m
    y      = [s + d_s,  I_j(I_L, U + d_U, s) + d_I,j]          (measured gap and currents)

The disturbance model is any subset of ``"force"`` (``d_F`` [N], an unknown load on the
mass), ``"voltage"`` (``d_U`` [V] per circuit, a voltage offset / resistance error),
``"gap_sensor"`` (``d_s`` [m]) and ``"current_sensor"`` (``d_I`` [A] per circuit).

The eq. 8 expressions and map tables are the :class:`~maglevkit.reduced.bank.MagnetBank`'s
(its per-cell polynomial tables); here the table is an *input* of the compiled functions,
passed by pointer, so that a call does not copy the ~40 000 table coefficients as an
embedded constant would (measured: 28 ms against 0.03 ms for 20 intervals with Jacobians).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from ..errors import InputError, ParameterError
from ..models.compiled import BoundCall, compile_function
from ..plant import STANDARD_GRAVITY
from ..reduced.bank import MagnetBank
from ..reduced.core import rk4_substep, substep_count
from ..validation import real_number

if TYPE_CHECKING:
    from ..reduction.maps import CharacteristicMaps

__all__ = ["DISTURBANCES", "MagnetHeaveModel"]

DISTURBANCES = ("force", "voltage", "gap_sensor", "current_sensor")


class MagnetHeaveModel:
    """One magnet (all its circuits at one gap) on a heave mass, with a disturbance model.

    Parameters
    ----------
    maps : CharacteristicMaps or MagnetBank
        The magnet's characteristic maps (or a bank of exactly this one magnet, all
        members reduced; a bank with the shielded-gap ladder or the eddy network adds its
        eddy states to the state: :attr:`eddy_states` per circuit, two with
        ``eddy_branches=2``, ``m`` with ``eddy_modes=m``).
    mass_kg : float
        The mass the magnet carries [kg], finite and > 0.
    gravity : float
        Gravitational acceleration [m/s^2], finite and >= 0 (default 9.80665; 0 for a
        guidance magnet).
    disturbances : sequence of str
        The disturbance model, a subset of :data:`DISTURBANCES` (may be empty).
    compiled : {"auto", "always", "never"}
        How the model functions are evaluated (:func:`~maglevkit.models.compiled.
        compile_function`).

    Raises
    ------
    ParameterError
        ``mass_kg`` or ``gravity`` out of range, unknown or repeated disturbance names
        (or a single string), or maps that are not those of exactly one reduced magnet.
    """

    def __init__(self, maps: CharacteristicMaps | MagnetBank, *, mass_kg: float,
                 gravity: float = STANDARD_GRAVITY,
                 disturbances: Sequence[str] = ("force", "voltage"),
                 compiled: str = "auto") -> None:
        mass_kg = real_number(mass_kg, "mass_kg", "kg", positive=True, error=ParameterError)
        gravity = real_number(gravity, "gravity", "m/s^2", nonnegative=True,
                              error=ParameterError)
        if isinstance(disturbances, str):
            raise ParameterError("disturbances must be a sequence of names, e.g. ('force',)")
        dist = tuple(disturbances)
        bad = [d for d in dist if d not in DISTURBANCES]
        if bad or len(set(dist)) != len(dist):
            raise ParameterError(f"disturbances = {dist!r}; use distinct names from "
                                 f"{list(DISTURBANCES)}")
        bank = maps if isinstance(maps, MagnetBank) else MagnetBank({"magnet": maps},
                                                                     compiled="never")
        if len(bank.member_names) != 1 or bank.members[0][1] != "reduced":
            raise ParameterError("the prediction model needs the maps of exactly one magnet "
                                 "(a bank of one reduced member)")
        self.bank = bank
        self.mass_kg = float(mass_kg)
        self.gravity = float(gravity)
        self.disturbances = dist
        self.compiled_mode = compiled
        nc = self.n_circuits = bank.n_circuits
        self.circuit_names = bank.circuit_names
        #: eddy states per circuit (:attr:`MagnetBank.n_eddy_states`): 0 (eq. 8), 1 (the
        #: two-state shielded-gap ladder, ``I_e``), 2 (the three-state ladder, ``I_e1``,
        #: ``I_e2``) or ``m`` (the eddy network, ``eddy_modes=m``: branch currents ``I_k``)
        self.eddy_states = int(bank.n_eddy_states)
        #: the eddy states in the state (a magnet with the shielded-gap ladder,
        #: ``motion_eddy``, or the eddy network, ``eddy_modes``): ``n_c`` times
        #: :attr:`eddy_states`, after ``[I_L, s, s']``, the bank's column-major order
        #: (every circuit's first eddy state, then the second, ...)
        self.n_eddy = nc * self.eddy_states
        self.nx = nc + 2 + self.n_eddy
        self.nu = nc
        self.ny = nc + 1
        sizes = {"force": 1, "voltage": nc, "gap_sensor": 1, "current_sensor": nc}
        self.nd = sum(sizes[d] for d in dist)
        self.disturbance_names: tuple[str, ...] = tuple(
            n for dn in dist for n in ((f"{dn}_N",) if dn == "force" else (f"{dn}_m",)
                                       if dn == "gap_sensor" else
                                       tuple(f"{dn}_{'V' if dn == 'voltage' else 'A'}[{c}]"
                                             for c in bank.circuit_names)))
        self._dslices: dict[str, slice] = {}
        k = 0
        for dname in dist:
            self._dslices[dname] = slice(k, k + sizes[dname])
            k += sizes[dname]
        self.resistance_ohm = np.asarray(bank.resistance_ohm, dtype=float)
        b = bank.map_ranges
        self.gap_range_m = (float(b[0].max()), float(b[1].min()))
        self.current_range_A = (float(b[2].max()), float(b[3].min()))
        self.table = np.asarray(bank.table, dtype=float)
        self._T = ca.MX.sym("table", self.table.size)
        x, u, d = ca.MX.sym("x", self.nx), ca.MX.sym("u", self.nu), ca.MX.sym("d", self.nd)
        xdot, y, force = self.expressions(x, u, d, self._T)
        self.rhs = ca.Function("mpc_rhs", [x, u, d, self._T], [xdot], ["x", "u", "d", "table"],
                               ["xdot"])
        self.measurement = ca.Function("mpc_meas", [x, u, d, self._T], [y],
                                       ["x", "u", "d", "table"], ["y"])
        self.force = ca.Function("mpc_force", [x, self._T], [force])
        self._compiled: dict[Any, _TableCall] = {}

    # ------------------------------------------------------------------ expressions
    def disturbance(self, d: Any, name: str) -> Any:
        """The part ``name`` (``"voltage"`` [V] per circuit, ``"force"`` [N],
        ``"gap_sensor"`` [m], ``"current_sensor"`` [A] per circuit) of the disturbance vector
        ``d``; zeros where the model has no such disturbance."""
        sl = self._dslices.get(name)
        n = 1 if name in ("force", "gap_sensor") else self.n_circuits
        return d[sl] if sl is not None else ca.DM.zeros(n)

    def coil_currents(self, x: Any, u: Any, d: Any) -> Any:
        """Symbolic coil currents ``I_j`` [A] at state ``x`` and voltages ``u`` [V] under the
        disturbances ``d``: the measurement's current part (eq. 8's Fig. 8 circuit, no
        sensor offset), which the two-quadrant chopper keeps >= 0 (the MPC's constraint).

        Parameters
        ----------
        x : casadi.MX
            State ``[I_L, s, s' (, I_e)]`` ([A], [m], [m/s], [A]).
        u : casadi.MX
            Circuit voltages [V].
        d : casadi.MX
            Disturbances (:attr:`disturbance_names`).

        Returns
        -------
        casadi.MX
            ``(n_c,)`` coil currents [A] (the maps' table is not needed).
        """
        f = getattr(self, "_coil_f", None)
        if f is None:        # built once (the expressions build every map lookup first)
            xs, us, ds = (ca.MX.sym("x", self.nx), ca.MX.sym("u", self.nu),
                          ca.MX.sym("d", self.nd))
            y = self.expressions(xs, us, ds, self._T)[1]
            f = self._coil_f = ca.Function("mpc_coil_currents", [xs, us, ds],
                                           [y[1:] - self.disturbance(ds, "current_sensor")])
        # inlined (a call node's Jacobian would keep the point symbolic): the function's
        # graph holds only the coil-current nodes, not the map lookups
        return f.call([x, u, d], True, False)[0]

    def expressions(self, x: Any, u: Any, d: Any, table: Any) -> tuple[Any, Any, Any]:
        """Symbolic ``(xdot, y, force)`` at state ``x``, voltages ``u`` [V], disturbances
        ``d`` and the bank's cell table ``table``: the state derivative, the measurements
        (gap [m], coil currents [A]) and the total magnet force [N]."""
        nc = self.n_circuits
        s, v = x[nc], x[nc + 1]
        ueff = u + self.disturbance(d, "voltage")
        rhs, coil, force, eddy = [], [], 0, []
        ne = self.eddy_states
        for j in range(nc):
            if ne:          # the ladder's or the network's I_e after [I_L, s, s']
                ie = (x[nc + 2 + j] if ne == 1 else
                      ca.vertcat(*(x[nc + 2 + m * nc + j] for m in range(ne))))
                r, e, c, f, _ = self.bank.ladder_expressions(j, x[j], ie, s, ueff[j], v,
                                                             table)
                eddy.append(e)
            else:
                r, c, f, _ = self.bank.circuit_expressions(j, x[j], s, ueff[j], v, table)
            rhs.append(r)
            coil.append(c)
            force = force + f
        acc = self.gravity + (self.disturbance(d, "force") - force) / self.mass_kg
        if ne > 1:         # column-major as the state: every circuit's dI_e1, then dI_e2, ...
            eddy = [e[m] for m in range(ne) for e in eddy]
        xdot = ca.vertcat(*rhs, v, acc, *eddy)
        y = ca.vertcat(s + self.disturbance(d, "gap_sensor"), ca.vertcat(*coil)
                       + self.disturbance(d, "current_sensor"))
        return xdot, y, force

    def rk4_substeps(self, h: float, substeps: int) -> int:
        """RK4 steps over an interval of ``h`` [s]: ``substeps``, and with eddy states
        (``n_eddy > 0``: the shielded-gap ladder or the eddy network) at least the count
        the eddy law's own stable step needs, ``ceil(h / bank.eddy_step_s)``
        (:attr:`~maglevkit.reduced.bank.MagnetBank.eddy_step_s`).

        The one rule of every MPC path (:meth:`discrete`, so the batched and real-time
        MPCs and the observer, and the ipopt interval).  Not the bank's ``max_step_s``:
        that is the simulation's accuracy cap (1 ms), which the prediction need not meet
        -- a model without eddy states predicts with ``substeps`` (default 1) whatever the
        interval, and with the eddy network on the TR09 maps one RK4 step per 2 ms
        interval predicts the horizon within 1.3 nm of gap and 33 uA of coil current of
        a 32-step reference (docs/control.md, "RK4 sub-steps of the prediction").

        Parameters
        ----------
        h : float
            Interval [s], > 0.
        substeps : int
            The requested count, >= 1.

        Returns
        -------
        int
            The count used.
        """
        if not self.n_eddy:
            return substeps
        return max(substeps, substep_count(h, self.bank.eddy_step_s))

    def discrete(self, h: float, substeps: int, *, jacobians: bool = False) -> ca.Function:
        """RK4 over ``h`` [s] in ``substeps`` steps: ``(x, u, d, table) -> x+`` and, with
        ``jacobians``, also ``dx+/dx, dx+/du, dx+/dd, y(x, u, d), dy/dx, dy/du, dy/dd``.

        The stages are inlined expressions (no nested function calls), so that CasADi's
        AD does not create derivative seeds for the 40 000-entry table input (which the
        generated code would copy at every call: measured 120 ms instead of 0.1 ms).

        Parameters
        ----------
        h : float
            Interval [s], > 0 (not checked).
        substeps : int
            Number of RK4 steps in the interval, >= 1 (not checked; raised to the ladder's
            stable count with ``n_eddy > 0``, :meth:`rk4_substeps`).
        jacobians : bool, default False
            Also return the Jacobians and the measurement (keyword only).

        Returns
        -------
        casadi.Function
            Inputs ``x`` (n_x: [A]..., [m], [m/s]), ``u`` (n_u) [V], ``d`` (n_d), ``table``;
            outputs ``xf`` (and ``A, B, Bd, y, C, D, Cd`` with ``jacobians``).
        """
        x, u, d = ca.MX.sym("x", self.nx), ca.MX.sym("u", self.nu), ca.MX.sym("d", self.nd)
        T = ca.MX.sym("table", self.table.size)
        substeps = self.rk4_substeps(h, substeps)
        hs = h / substeps

        def f(xx: Any) -> Any:
            return self.expressions(xx, u, d, T)[0]

        xk: Any = x
        for _ in range(substeps):
            xk = rk4_substep(xk, hs, f)
        if not jacobians:
            return ca.Function("mpc_rk4", [x, u, d, T], [xk], ["x", "u", "d", "table"], ["xf"])
        y = self.expressions(x, u, d, T)[1]
        return ca.Function("mpc_rk4_jac", [x, u, d, T],
                           [xk, ca.jacobian(xk, x), ca.jacobian(xk, u), ca.jacobian(xk, d),
                            y, ca.jacobian(y, x), ca.jacobian(y, u), ca.jacobian(y, d)],
                           ["x", "u", "d", "table"],
                           ["xf", "A", "B", "Bd", "y", "C", "D", "Cd"])

    def compile(self, f: ca.Function) -> _TableCall:
        """``f`` (last input: the table) compiled (cached on disk per source, see
        :func:`compile_function`) and bound to the table: a callable of the other inputs
        returning NumPy arrays (dense outputs; sparse ones as their nonzeros).

        Parameters
        ----------
        f : casadi.Function
            A function whose last input is the map table (e.g. from :meth:`discrete`).

        Returns
        -------
        callable
            ``call(*inputs_but_table) -> list of ndarray``; compiled or interpreted as the
            model's ``compiled`` mode says.
        """
        out, _ = compile_function(f, mode=self.compiled_mode)
        return _TableCall(out, self.table)

    # ------------------------------------------------------------------ steady states
    def steady_state(self, gap_m: float, disturbance: Any = None, *,
                     current_guess_A: float = 20.0) -> tuple[np.ndarray, np.ndarray]:
        """Equilibrium ``(x_s, u_s)`` with the *measured* gap at ``gap_m`` [m] under the
        disturbance ``d`` (every circuit at the same inductor current; Newton on the
        force balance ``sum_j F_j(s, I) = m g + d_F``).

        Parameters
        ----------
        gap_m : float
            Measured gap [m] (the true gap is ``gap_m - d_s`` with a gap-sensor
            disturbance); should lie within the maps' gap range.
        disturbance : array_like (n_d,), optional
            Disturbance estimate in the order of :attr:`disturbance_names` (default zeros).
        current_guess_A : float, default 20.0
            Start of the Newton iteration [A] (keyword only); iterates are clipped to the
            maps' current range.

        Returns
        -------
        (x_s, u_s) : ndarray (n_x,), ndarray (n_u,)
            Steady state (inductor currents [A], gap [m], gap rate 0) and voltages [V]
            ``R I - d_U``.

        Raises
        ------
        SolverError
            No equilibrium within the maps' current range (load too large).
        """
        from ..errors import SolverError

        d = np.zeros(self.nd) if disturbance is None else np.asarray(disturbance, dtype=float)
        dd = {k: d[sl] for k, sl in self._dslices.items()}
        s = gap_m - float(dd.get("gap_sensor", np.zeros(1))[0])
        load = self.mass_kg * self.gravity + float(dd.get("force", np.zeros(1))[0])
        nc = self.n_circuits
        i = float(current_guess_A)
        fun = self._force_and_slope()
        for _ in range(50):
            f, df = (float(v[0]) for v in fun(s, i))
            step = (f - load) / df if df > 0 else math.nan
            if not math.isfinite(step):
                break
            i -= step
            i = min(max(i, self.current_range_A[0]), self.current_range_A[1])
            if abs(step) < 1e-10 * max(1.0, abs(i)):
                # (the ladder's steady state has I_e = 0)
                x = np.concatenate([np.full(nc, i), [s, 0.0], np.zeros(self.n_eddy)])
                u = self.resistance_ohm * i - dd.get("voltage", np.zeros(nc))
                return x, u
        raise SolverError("no equilibrium current for the gap reference within the maps",
                          state={"gap_m": s, "load_N": load, "current_A": i},
                          reason=f"the maps cover {self.current_range_A[0]:g}.."
                                 f"{self.current_range_A[1]:g} A")

    def _force_and_slope(self) -> _TableCall:
        f = self._compiled.get("force")
        if f is None:
            s, i = ca.MX.sym("s"), ca.MX.sym("i")
            T = ca.MX.sym("table", self.table.size)
            x = ca.vertcat(ca.repmat(i, self.n_circuits, 1), s, 0, ca.DM.zeros(self.n_eddy))
            F = self.force(x, T)
            f = self.compile(ca.Function("mpc_force_slope", [s, i, T],
                                         [F, ca.jacobian(F, i)]))
            self._compiled["force"] = f
        return f

    # ------------------------------------------------------------------ linearisation
    def linearize(self, x: np.ndarray, u: np.ndarray, d: Any = None, *, h: float,
                  substeps: int = 1) -> dict[str, np.ndarray]:
        """Discrete-time linearisation over ``h`` [s] (RK4): ``A, B, Bd`` and ``C, D, Cd``.

        Parameters
        ----------
        x : array_like (n_x,)
            State: inductor currents [A], gap [m], gap rate [m/s].
        u : array_like (n_u,)
            Circuit voltages [V].
        d : array_like (n_d,), optional
            Disturbances (default zeros).
        h : float
            Interval [s] (keyword only).
        substeps : int, default 1
            RK4 steps in the interval (keyword only).

        Returns
        -------
        dict of str to ndarray
            ``A`` (n_x, n_x), ``B`` (n_x, n_u), ``Bd`` (n_x, n_d), ``C`` (n_y, n_x),
            ``D`` (n_y, n_u), ``Cd`` (n_y, n_d).
        """
        dv = np.zeros(self.nd) if d is None else np.asarray(d, dtype=float)
        F = self.discrete(h, substeps, jacobians=True)
        out = F(x, u, dv, self.table)
        res = [np.array(out[k], dtype=float).reshape(out[k].shape) for k in (1, 2, 3, 5, 6, 7)]
        return dict(zip(("A", "B", "Bd", "C", "D", "Cd"), res, strict=True))

    def check_detectability(self, x: np.ndarray, u: np.ndarray, *, h: float) -> None:
        """Raise :class:`ParameterError` unless the augmented system (x, d) is detectable
        at ``(x, u)``: ``n_d <= n_y``, ``(A, C)`` detectable and the rank condition
        ``rank [[A - I, Bd], [C, Cd]] = n_x + n_d`` (Pannocchia & Rawlings 2003).

        Parameters
        ----------
        x : array_like (n_x,)
            Operating state: inductor currents [A], gap [m], gap rate [m/s].
        u : array_like (n_u,)
            Operating voltages [V].
        h : float
            Sample time of the linearisation [s] (keyword only).

        Raises
        ------
        ParameterError
            More disturbances than measurements, an undetectable unstable mode, or a
            disturbance model whose steady-state effects on the measurements coincide.
        """
        nx, nd, ny = self.nx, self.nd, self.ny
        if nd > ny:
            raise ParameterError(f"disturbance model {self.disturbances!r} has {nd} "
                                 f"disturbances but only {ny} measurements (gap and "
                                 f"{self.n_circuits} current(s)); at most n_y = {ny} can be "
                                 "detectable")
        lin = self.linearize(x, u, h=h)
        A, C = lin["A"], lin["C"]
        # PBH test of (A, C) at every eigenvalue on or outside the unit circle
        for lam in np.linalg.eigvals(A):
            if abs(lam) >= 1.0 - 1e-9:
                M = np.vstack([lam * np.eye(nx) - A, C])
                if np.linalg.matrix_rank(M, tol=1e-9 * np.linalg.norm(M)) < nx:
                    raise ParameterError(f"the magnet model is not detectable from gap and "
                                         f"current (mode {lam:.4g})")
        if nd == 0:
            return
        M = np.block([[A - np.eye(nx), lin["Bd"]], [C, lin["Cd"]]])
        # scale rows and columns so that the rank tolerance is unit-independent
        M = M / np.maximum(np.abs(M).max(axis=1, keepdims=True), 1e-300)
        M = M / np.maximum(np.abs(M).max(axis=0, keepdims=True), 1e-300)
        sv = np.linalg.svd(M, compute_uv=False)
        rank = int(np.sum(sv > 1e-8 * sv[0]))
        if rank < nx + nd:
            raise ParameterError(
                f"disturbance model {self.disturbances!r} is not detectable: "
                f"rank [[A - I, Bd], [C, Cd]] = {rank} < n_x + n_d = {nx + nd} (two "
                "disturbances act on the measurements alike in steady state, e.g. a load "
                "force and a gap-sensor offset); choose disturbances that the gap and "
                "current measurements can tell apart, e.g. ('force', 'voltage')")

    def check_inputs(self, x: np.ndarray) -> None:
        """Check a state vector.

        Parameters
        ----------
        x : ndarray (n_x,)
            State: inductor currents [A], gap [m], gap rate [m/s].

        Raises
        ------
        InputError
            Wrong shape or non-finite values.
        """
        if x.shape != (self.nx,) or not np.isfinite(x).all():
            raise InputError(f"state must be {self.nx} finite values [I_L..., s, s'"
                             + (", I_e...]" if self.n_eddy else "]"))

    def spline_rhs(self) -> tuple[ca.Function, ca.Function]:
        """The same model with the single :class:`~maglevkit.reduced.current.CurrentModel`'s
        B-spline maps instead of the bank's cell tables (equal to rounding for the default
        bicubic tables): ``(x, u, d) -> xdot`` and ``(x, u, d) -> y`` (MX, no table input),
        for the IPOPT reference formulation."""
        from ..reduced.current import CurrentModel

        ne = self.eddy_states
        m = self.bank.eddy_modes
        cm = (CurrentModel(self.bank.members[0][2], eddy_modes=m) if m else
              CurrentModel(self.bank.members[0][2], motion_eddy=bool(ne),
                           eddy_branches=max(ne, 1)))
        nc = self.n_circuits
        x, u, d = ca.MX.sym("x", self.nx), ca.MX.sym("u", self.nu), ca.MX.sym("d", self.nd)
        s, v = x[nc], x[nc + 1]
        ueff = u + self.disturbance(d, "voltage")
        sv = ca.repmat(s, nc, 1)
        if ne:
            # CurrentModel's eddy states run circuit by circuit (I_e1, I_e2 of circuit 0,
            # ...), the state's column-major: the (n_c, n_e) block transposed
            ie = ca.vec(ca.reshape(x[nc + 2:], nc, ne).T)
            didt, dedt = cm.ode(x[:nc], ueff, sv, ca.repmat(v, nc, 1), ie)
            coil, force, _ = cm.outputs_fun(x[:nc], ueff, sv, ie)
            tail = [ca.vec(ca.reshape(dedt, ne, nc).T)]
        else:
            didt = cm.ode(x[:nc], ueff, sv, ca.repmat(v, nc, 1))
            coil, force, _ = cm.outputs_fun(x[:nc], ueff, sv)
            tail = []
        acc = self.gravity + (self.disturbance(d, "force") - ca.sum1(force)) / self.mass_kg
        y = ca.vertcat(s + self.disturbance(d, "gap_sensor"), coil + self.disturbance(d, "current_sensor"))
        return (ca.Function("spline_rhs", [x, u, d], [ca.vertcat(didt, v, acc, *tail)]),
                ca.Function("spline_meas", [x, u, d], [y]))


class _TableCall:
    """Call a CasADi function through bound NumPy buffers; its last input, the table, is
    bound once by pointer (a per-call conversion of the 40 000 coefficients costs 1-20 ms)."""

    def __init__(self, f: ca.Function, table: np.ndarray) -> None:
        self.function = f
        n = f.n_in()
        self._table = np.ascontiguousarray(table, dtype=float)
        self._bound = BoundCall(f, args={n - 1: self._table})
        self._eval = self._bound.eval
        self._args = self._bound.args[:n - 1]
        self._res = self._bound.res
        self.sparsity_out = [f.sparsity_out(i) for i in range(f.n_out())]

    def __call__(self, *args: Any) -> list[np.ndarray]:
        for a, v in zip(self._args, args, strict=True):
            a[:] = np.ravel(np.asarray(v, dtype=float), order="F")
        self._eval()
        out = []
        for r, sp in zip(self._res, self.sparsity_out, strict=True):
            if sp.is_dense():
                out.append(r.reshape(sp.size2(), sp.size1()).T.copy() if sp.size2() > 1
                           else r.copy())
            else:
                out.append(r.copy())
        return out
