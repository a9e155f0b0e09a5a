"""One compiled function per vehicle time step (reduced magnets, coarse force distribution).

The step of :meth:`maglevkit.vehicle.VehicleModel.run` written as one CasADi function and
compiled to machine code (:func:`maglevkit.models.compiled.compile_function`, disk cache),
so that a time step is one call instead of some fifty NumPy operations on small arrays.
Each law of the step is written once, as a CasADi function of
:func:`build_vehicle_parts`; :func:`build_vehicle_step` composes them with the bank's step,
and the reference loop of ``simulation.py`` (``loop="python"``: detailed magnets, other
controllers, payload steps) and the cross-section model evaluate the same functions.  Per
step, in this order::

    gaps      s = s0 + B^T q - w(x) - r,   s' = B^T q' - (w_t + v w_x)(x) - v r_x
    control   U = clip(R I + k_psi (psi0 (1 + rho) - psi_hat)), U >= -R_ec I_L, failures
              (rho's damping input blends s' with the points' velocity B^T q')
    magnets   the bank's own step function (MagnetBank.step_function: RK4 of eq. 8, or of
              the shielded-gap ladder with its I_e in the state: motion_eddy)
    control   psi_hat += dt (U - R (I + I+)/2),   e_I += P (s - s0) dt
    mechanics x+ = Ad x + Bd (Q_g - B F_bar),     F_bar = sides (F + F+)/2
    guideway  X+ = X Ad^T + Q Bd^T,  Q[r] = sum over the loads on ring row r of
              sin(k_j xi_mid) F_bar  (mid-step positions)

Which ring rows the moving system boundary recycles at which step, and the check that the
loads stay on the integrated spans, are computed in Python before the loop (they change
once per span crossing); the rows come in as a per-step keep mask (1 keep, 0 reset to
rest).  The loads' geometry follows inside the function from the train's reference
position ``x_ref`` (the points ride at ``x_ref - xi_p``): the ring rows
(``row = floor((x - x0)/L) mod N``, as the loop computes them) and the first mode's phase
at every point by angle addition from the reference point's phase (four transcendental
calls per step); each point then reads its own span's modal state (a gather by ring row)
and the modal forces are a scatter-add (:func:`_elastic_guideway`).

Layout (:class:`StepLayout`): input ``S`` (state), ``P`` (per-step inputs: the reference
position at the step start, the irregularity and its slope at the points there, the time,
the keep mask), ``C`` (per-run constants: speed and failure times); outputs ``S_next`` and
``R`` (the record of the step: gaps, rates, coil currents, forces and ``I_L`` at the step
start, deflections, the mechanical state, the midspan deflection per ring row, the
voltages, min/max gap, the bank's count of flagged circuits and, per circuit, the bank
kernel's reason code (:class:`~maglevkit.reduced.StepFlag` bits) and the extremes of
``I_L`` over the RK4 sub-steps, from which :meth:`MagnetBank.raise_step_flags` gives a
flagged step's message without stepping again).  The block function chains the
step ``block_steps`` times (``P`` and ``R`` one column per step).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..control import damping_input
from ..errors import InputError
from ..plant import chopper_floor

__all__ = ["StepLayout", "VehicleStepFunction", "build_vehicle_parts", "build_vehicle_step",
           "pack_slices"]


@dataclass(frozen=True)
class StepLayout:
    """Offsets of the packed vectors of the vehicle step function.

    ``state`` and ``record`` map a name to a slice of ``S`` and ``R``; ``n_state``,
    ``n_step_inputs``, ``n_record`` are their sizes.

    Attributes
    ----------
    n_dof : int
        Degrees of freedom of the mechanics (heave and pitch of every body).
    n_circuits : int
        Circuits of the magnet bank (one force point each).
    n_spans : int
        Guideway spans in the ring buffer (0 for a rigid guideway).
    n_modes : int
        Sine modes per span (0 for a rigid guideway).
    state : dict of str to slice
        Parts of the state vector ``S`` (``"x_mech"``, ``"guideway"``, ``"I_L"``,
        ``"psi_hat"``, ``"integral"``, ``"current"``, ``"force"``; ``"I_e"`` last with
        shielded-gap ladder magnets).
    step_inputs : dict of str to slice
        Parts of the per-step input ``P`` (``"x_ref"``, ``"r"``, ``"r_x"``, ``"t"``,
        ``"keep"``).
    record : dict of str to slice
        Parts of the record ``R`` of a step.
    """

    n_dof: int
    n_circuits: int
    n_spans: int
    n_modes: int
    state: dict[str, slice]
    step_inputs: dict[str, slice]
    record: dict[str, slice]

    @property
    def n_state(self) -> int:
        return max(s.stop for s in self.state.values())

    @property
    def n_step_inputs(self) -> int:
        return max(s.stop for s in self.step_inputs.values())

    @property
    def n_record(self) -> int:
        return max(s.stop for s in self.record.values())


def pack_slices(items: list[tuple[str, int]]) -> dict[str, slice]:
    """Consecutive slices of a flat vector, one per named block, in the given order.

    Parameters
    ----------
    items : list of (str, int)
        Block names and sizes (number of entries, no unit).

    Returns
    -------
    dict
        Name -> ``slice`` into the vector; the last block's ``stop`` is its length.
    """
    out, k = {}, 0
    for name, n in items:
        out[name] = slice(k, k + n)
        k += n
    return out


def _layout(n_dof: int, nc: int, n_sp: int, nm: int, held: bool = False,
            motion_eddy: bool = False, eddy_states: int = 1) -> StepLayout:
    # the ladder's I_e after every other block: without it the layout is the one before;
    # with the three-state ladder 2 n_c entries (every circuit's I_e1, then I_e2)
    eddy = [("I_e", nc * eddy_states)] if motion_eddy else []
    state = pack_slices([("x_mech", 2 * n_dof), ("guideway", n_sp * 2 * nm), ("I_L", nc),
                         ("psi_hat", nc), ("integral", nc), ("current", nc), ("force", nc),
                         *eddy])
    extra = [("u_held", nc), ("q_g", n_dof)] if held else []
    step = pack_slices([("x_ref", 1), ("r", nc), ("r_x", nc), ("t", 1), ("keep", n_sp), *extra])
    record = pack_slices([("gap", nc), ("gap_rate", nc), ("current", nc), ("force", nc), ("I_L", nc),
                          ("deflection", nc), ("q", n_dof), ("q_dot", n_dof), ("midspan_ring", n_sp),
                          ("voltage", nc), ("gap_min", 1), ("gap_max", 1), ("n_bad", 1),
                          ("flags", nc), ("I_L_min", nc), ("I_L_max", nc), *eddy])
    return StepLayout(n_dof, nc, n_sp, nm, state, step, record)


@dataclass(frozen=True)
class VehicleStepFunction:
    """The vehicle step as a CasADi function plus its parts (for profiling).

    Attributes
    ----------
    function : casadi.Function
        One step: ``(S, P, C) -> (S_next, R)``.
    block_function : casadi.Function
        ``block_steps`` steps in one call: ``(S, P, C) -> (S_next, R)`` with ``P`` and
        ``R`` one column per step (the rows of C-ordered ``(steps, n)`` arrays).
    block_steps : int
        Steps per call of ``block_function``.
    layout : StepLayout
        Where each quantity sits in the state, step-input and record vectors.
    parts : dict of casadi.Function
        The parts :func:`build_vehicle_parts` gives (the reference loop evaluates
        ``"guideway_in"`` and ``"guideway_out"``; ``function`` composes the elastic
        guideway from ``"guideway_train_loads"``, ``"guideway_deflection"``, ``"gaps"``
        and ``"guideway_update"``), with ``"magnets"`` (the bank's step).
    measure : casadi.Function
        ``(S, P, C) -> (gap, gap_rate)``: the circuits' gaps [m] and rates [m/s] at the
        step's start, as the step computes and records them (what a sampled controller
        measures before the step).
    """

    function: Any
    block_function: Any
    block_steps: int
    layout: StepLayout
    parts: dict[str, Any]
    measure: Any = None


def _sparse(a: np.ndarray) -> ca.DM:
    return ca.sparsify(ca.DM(np.asarray(a, dtype=float)))


def _scatter_add(values: Any, index: Any, n: int) -> Any:
    """``z = zeros(n); z[index[i]] += values[i]`` for i in order (CasADi MX, ``index``
    an MX of whole numbers in ``0 ... n - 1``; entries outside are dropped): the
    transpose of the gather ``g[index]``, which is how CasADi writes it."""
    g = ca.MX.sym("g", n)
    return ca.jtimes(g[index], g, values, True)


def _elastic_guideway(*, npt: int, wavenumbers: np.ndarray, n_spans: int, origin_m: float,
                      span_length_m: float, dt: float, guideway_ad: np.ndarray,
                      guideway_bd: np.ndarray, midspan_shape: np.ndarray,
                      point_offsets_m: np.ndarray | None = None) -> dict[str, Any]:
    """The elastic guideway's laws at ``npt`` point loads, as CasADi functions.

    ``"guideway_loads"`` ``(x, v) -> (rows, sin_a, cos_a, rows_mid, sin_a_mid,
    cos_a_mid)``: the ring row of every point's span, ``row = floor((x - x0)/L) mod N``,
    and the first mode's phase ``a = k_1 xi`` there (``xi = x - x0 - floor(..) L``), at the
    step's start and at the mid-step positions ``x + v dt/2`` (the modal update's load
    positions), evaluated directly (``sin``, ``cos`` per point).  With
    ``point_offsets_m`` (points rigidly attached to a train, ``x_p = x_ref - xi_p``) also
    ``"guideway_train_loads"`` ``(x_ref, v) -> (the same)``: since
    ``a_p = (a_ref - k_1 xi_p) + (k_ref - k_p) pi``, ``sin a_p = (-1)^(k_ref - k_p)
    (sin a_ref cos k_1 xi_p - cos a_ref sin k_1 xi_p)`` and ``cos a_p`` likewise, with
    ``cos k_1 xi_p``, ``sin k_1 xi_p`` constants: four transcendental calls per step
    instead of four per point (the rounding differs from direct evaluation by a few ulp).

    ``"guideway_deflection"`` ``(guideway, rows, sin_a, cos_a, v) -> (w, w_rate,
    midspan)``: ``w = sum_j q_j sin(k_j xi)``, ``w_rate = w_t + v w_x = sum_j (q_j' sin(k_j
    xi) + v q_j k_j cos(k_j xi))`` at the points, each point reading its own span's
    modal state (a gather by ring row), and the midspan deflection per ring row.

    ``"guideway_update"`` ``(guideway, rows_mid, sin_a_mid, cos_a_mid, F_bar) ->
    guideway_next``: ``X+ = X Ad^T + Q Bd^T``, ``Q[r, j] = sum of sin(k_j xi_p) F_p`` over
    the points on ring row ``r`` (a scatter-add, points in ascending order).

    ``sin(j a)``, ``cos(j a)`` come from ``sin a``, ``cos a`` by the angle-addition
    recurrence (the rounding differs from direct evaluation by a few ulp).  The state
    ``guideway`` is the ring buffer row-major: row ``r`` holds ``[q_1..q_n, q_1'..q_n']``.
    """
    kk = np.asarray(wavenumbers, dtype=float).ravel()
    nm, n_sp = kk.size, int(n_spans)
    k1 = float(kk[0])
    sym = ca.MX.sym
    xp, v = sym("x", npt), sym("v")

    def span_rows(xs: Any) -> tuple[Any, Any]:
        ks = ca.floor((xs - origin_m) / span_length_m)
        return ks, ks - n_sp * ca.floor(ks / n_sp)

    def phases(xs: Any) -> tuple[Any, Any, Any]:
        """Ring rows, ``sin a``, ``cos a`` at the positions ``xs`` (direct evaluation)."""
        ks, rows = span_rows(xs)
        a = (xs - (origin_m + ks * span_length_m)) * k1
        return rows, ca.sin(a), ca.cos(a)

    half = 0.5 * v * dt
    names_out = ["rows", "sin_a", "cos_a", "rows_mid", "sin_a_mid", "cos_a_mid"]
    f_loads = ca.Function("vehicle_guideway_loads", [xp, v],
                          [*phases(xp), *phases(xp + half)], ["x", "v"], names_out)
    out: dict[str, Any] = {"guideway_loads": f_loads}
    if point_offsets_m is not None:
        # points rigidly attached to the train, x_p = x_ref - xi_p: with
        # a_p = k_1 (x_p - x0 - k_p L) = (a_ref - k_1 xi_p) + (k_ref - k_p) pi,
        # sin a_p = (-1)^(k_ref - k_p) (sin a_ref cos k_1 xi_p - cos a_ref sin k_1 xi_p),
        # cos a_p likewise: four transcendental calls per step instead of four per point
        offs = np.asarray(point_offsets_m, dtype=float).ravel()
        c_off, s_off = ca.DM(np.cos(k1 * offs)), ca.DM(np.sin(k1 * offs))
        x_ref = sym("x_ref")

        def train_phases(xr: Any, xs: Any) -> tuple[Any, Any, Any]:
            ks_r = ca.floor((xr - origin_m) / span_length_m)
            a_r = (xr - (origin_m + ks_r * span_length_m)) * k1
            s_r, c_r = ca.sin(a_r), ca.cos(a_r)
            ks, rows = span_rows(xs)
            d = ks_r - ks
            sign = 1.0 - 2.0 * (d - 2.0 * ca.floor(0.5 * d))
            return rows, sign * (s_r * c_off - c_r * s_off), sign * (c_r * c_off + s_r * s_off)

        x_pts = x_ref - ca.DM(offs)          # as the run's positions x_ref + v t - xi
        out["guideway_train_loads"] = ca.Function(
            "vehicle_guideway_train_loads", [x_ref, v],
            [*train_phases(x_ref, x_pts), *train_phases(x_ref + half, x_pts + half)],
            ["x_ref", "v"], names_out)

    def modes(s_1: Any, c_1: Any) -> tuple[list[Any], list[Any]]:
        sins, coss = [s_1], [c_1]
        for _ in range(1, nm):
            sj, cj = sins[-1], coss[-1]
            sins.append(sj * c_1 + cj * s_1)
            coss.append(cj * c_1 - sj * s_1)
        return sins, coss

    gx_flat = sym("guideway", n_sp * 2 * nm)
    gx = ca.reshape(gx_flat, 2 * nm, n_sp).T            # (N, 2 nm), row-major as the loop
    r_in, s_in, c_in = sym("rows", npt), sym("sin_a", npt), sym("cos_a", npt)
    phi, cosines = modes(s_in, c_in)
    # each point reads its own span's [q | q'] (gx_flat[row 2 nm : (row + 1) 2 nm]): a
    # gather instead of a one-hot (npt, N) matrix times the (N, 2 nm) state; the same
    # numbers (the one-hot's zero products added nothing) with ~1/10 of the arithmetic
    base = r_in * float(2 * nm)
    qs = [gx_flat[base + float(j)] for j in range(nm)]
    qds = [gx_flat[base + float(nm + j)] for j in range(nm)]
    w = qs[0] * phi[0]
    w_t = qds[0] * phi[0]
    w_x = qs[0] * (cosines[0] * k1)
    for j in range(1, nm):
        w = w + qs[j] * phi[j]
        w_t = w_t + qds[j] * phi[j]
        w_x = w_x + qs[j] * (cosines[j] * float(kk[j]))
    mid = ca.mtimes(gx[:, :nm], ca.DM(np.asarray(midspan_shape, dtype=float)))
    f_defl = ca.Function("vehicle_guideway_deflection", [gx_flat, r_in, s_in, c_in, v],
                         [w, w_t + v * w_x, mid],
                         ["guideway", "rows", "sin_a", "cos_a", "v"],
                         ["w", "w_rate", "midspan"])

    f_bar = sym("F_bar", npt)
    sn_m, _ = modes(s_in, c_in)
    # Q[r, j] = sum of sin(k_j xi_p) F_p over the points p on ring row r: a scatter-add
    # (points in ascending order, as the one-hot product summed them) into the
    # column-major (N, nm) matrix
    at = ca.vertcat(*[r_in + float(j * n_sp) for j in range(nm)])
    loads = ca.vertcat(*[sn_m[j] * f_bar for j in range(nm)])
    qmod = ca.reshape(_scatter_add(loads, at, n_sp * nm), n_sp, nm)
    gx_next = (ca.mtimes(gx, _sparse(np.asarray(guideway_ad).T))
               + ca.mtimes(qmod, _sparse(np.asarray(guideway_bd).T)))
    f_upd = ca.Function("vehicle_guideway_update", [gx_flat, r_in, s_in, c_in, f_bar],
                        [ca.reshape(gx_next.T, n_sp * 2 * nm, 1)],
                        ["guideway", "rows_mid", "sin_a_mid", "cos_a_mid", "F_bar"],
                        ["guideway_next"])
    return {**out, "guideway_deflection": f_defl, "guideway_update": f_upd}


def bank_step_outputs(bank_step: Any, *, il: Any, ie: Any, gaps: Any, voltages: Any,
                      rates: Any, dt: float) -> tuple[Any, ...]:
    """One call of the bank's step function inside a vehicle's compiled step: inputs
    ``I_L``, gaps [m], voltages [V], gap rates [m/s], the step ``dt`` [s] and, with the
    shielded-gap ladder (``ie`` not None), ``I_e`` [A] (``n`` or, three-state, ``2 n``
    entries, column-major).  Returns ``I_L_next``, the coil
    current ``I``, the force ``F``, ``n_bad``, the reason ``flags``, ``I_L_min``,
    ``I_L_max`` and ``I_e_next`` (None without the ladder); used by the heave-pitch and the
    cross-section steps."""
    b_in = {"I_L": il, "s": gaps, "U": voltages, "sdot": rates, "h": ca.MX(dt)}
    ie_next = None
    if ie is not None:
        # the three-state ladder's (n, 2) block comes and goes as the vehicle state's flat
        # 2n entries, column-major (every circuit's I_e1, then I_e2); (n, 1): unchanged
        shape = bank_step.sparsity_in("I_e").shape
        b_in["I_e"] = ie if shape[1] == 1 else ca.reshape(ie, *shape)
    bout = bank_step.call(b_in)
    if ie is not None:
        ie_next = bout["I_e_next"]
        if ie_next.shape[1] != 1:
            ie_next = ca.vec(ie_next)
    return (*(bout[k] for k in ("I_L_next", "I", "F", "n_bad", "flags", "I_L_min",
                                "I_L_max")), ie_next)


def terminal_current(il: Any, ie: Any, n_circuits: int) -> Any:
    """The ladder's terminal current ``I_L + I_e`` (two-state, ``ie`` of ``n_circuits``
    entries) or ``I_L + I_e1 + I_e2`` (three-state, ``ie`` of ``2 n_circuits``, every
    circuit's ``I_e1`` first, or a NumPy ``(n_circuits, 2)`` array as the bank's state);
    the eddy network's ``I_L + sum_k I_k`` alike (``ie`` of ``n_e n_circuits`` or
    ``(n_circuits, n_e)``):
    the chopper's current, whose floor is ``U >= -R_a`` times it (the coil current
    ``(U/R_a + I_u)/a`` stays >= 0); ``il`` itself when ``ie`` is None (eq. 8).  CasADi
    or NumPy [A], summed in the bank kernel's order."""
    if ie is None:
        return il
    out = il
    if len(ie.shape) == 2 and ie.shape[1] > 1:      # the bank's (n_c, n_e) state
        for k in range(ie.shape[1]):
            out = out + ie[:, k]
        return out
    for k in range(ie.shape[0] // n_circuits):      # column-major: I_e1 block, I_e2, ...
        out = out + ie[k * n_circuits:(k + 1) * n_circuits]
    return out


def eddy_block_as_state(block: np.ndarray, n_circuits: int) -> np.ndarray:
    """A compiled step's recorded eddy-state block ``(n_t, n_e n_circuits)`` (column-major:
    every circuit's ``I_e1``, then ``I_e2``, ...) in the bank's state shape: ``(n_t,
    n_circuits)`` for one eddy state per circuit, ``(n_t, n_circuits, n_e)`` for more (as
    :attr:`BankState.eddy_currents_A` with time in front)."""
    n_t = block.shape[0]
    out = block.reshape(n_t, -1, n_circuits).transpose(0, 2, 1)
    return out[:, :, 0] if out.shape[2] == 1 else out


def eddy_modes_label(modes: Mapping[str, int]) -> str:
    """The eddy-network branch counts of a vehicle's magnet kinds as written in its records
    (``modes``: magnet kind -> ``eddy_modes``, 0 for eq. 8): ``"eddy_modes = 2"`` when
    every kind flies the same network, ``"eddy_modes = levitation 2, guidance 0"``
    otherwise; ``""`` when no kind flies one."""
    values = set(modes.values())
    if values <= {0}:
        return ""
    if len(values) == 1:
        return f"eddy_modes = {values.pop()}"
    return "eddy_modes = " + ", ".join(f"{k} {m}" for k, m in modes.items())


def eddy_record(record: np.ndarray, *, modes: Mapping[str, int], scope: str = ""
                ) -> tuple[tuple[str, ...], dict[str, list[str]], str]:
    """How a vehicle run's dataset records its eddy states (the bank-shaped record
    ``(n_t, n_circuits)`` or ``(n_t, n_circuits, n_e)``, as :func:`eddy_block_as_state`
    gives it): the dimensions after ``("time", <circuit>)`` (``("eddy_state",)`` for more
    than one state per circuit), the coordinates they need (``eddy_state``: ``I_e1 ..
    I_en``) and the ``long_name``.  ``modes``: magnet kind -> ``eddy_modes`` of the eddy
    network (all 0: the shielded-gap ladder, ``motion_eddy``); ``scope`` a note on what a
    circuit is (e.g. ``"one side's circuit"``).  Written once for the heave-pitch and the
    cross-section records."""
    n_e = record.shape[2] if record.ndim == 3 else 1
    dims: tuple[str, ...] = ("eddy_state",) if n_e > 1 else ()
    coords = {"eddy_state": [f"I_e{k + 1}" for k in range(n_e)]} if n_e > 1 else {}
    label = eddy_modes_label(modes)
    notes = [scope] if scope else []
    if label:
        text = "branch currents I_k of the eddy network"
        notes.append(label + ("; a kind's absent branches 0" if len(set(modes.values())) > 1
                              else ""))
        if n_e > 1:
            notes.append(f"eddy_state I_e1..I_e{n_e}: the branches I_1..I_{n_e}")
    else:
        text = "shielding eddy current I_e of the shielded-gap ladder"
        notes.append("motion_eddy")
        if n_e > 1:
            notes.append("eddy_state I_e1 (inner shield R_3), I_e2 (outer shield R_2)")
    return dims, coords, f"{text} ({'; '.join(notes)})"


def build_vehicle_parts(*, dt: float, nominal_gap_m: float, span_length_m: float,
                        origin_m: float, wavenumbers: np.ndarray, guideway_ad: np.ndarray,
                        guideway_bd: np.ndarray, n_spans: int, mech_ad: np.ndarray,
                        mech_bd: np.ndarray, gravity_force: np.ndarray,
                        force_matrix: np.ndarray, gains: dict[str, np.ndarray],
                        flux_bias_Wb: np.ndarray, resistance_ohm: np.ndarray,
                        eddy_resistance_ohm: np.ndarray, voltage_limit_V: float,
                        integral_projection: np.ndarray, midspan_shape: np.ndarray,
                        chopper: str = "eq8", point_offsets_m: np.ndarray | None = None
                        ) -> dict[str, Any]:
    """The parts of the vehicle step, each law written once as a CasADi function.

    The compiled step (:func:`build_vehicle_step`) composes them with the bank's step; the
    NumPy reference loop of :meth:`VehicleModel.run` (``loop="python"``, also the loop of
    detailed magnets and of controllers other than the cascade) evaluates the same
    functions on CasADi's virtual machine.  The guideway and mechanics parts work on the
    force points (``force_matrix.shape[1]``: circuits of reduced magnets, poles of
    detailed ones), the controller parts on the circuits (the gains' length).

    Parameters
    ----------
    dt : float
        Time step [s].
    nominal_gap_m : float
        Nominal gap ``s0`` [m].
    span_length_m, origin_m : float
        Span length L [m] and position of pier 0 [m].
    wavenumbers : ndarray (n_modes,)
        ``k_j = j pi / L`` [rad/m] (empty: rigid guideway).
    guideway_ad, guideway_bd : ndarray
        Span ZOH matrices (:meth:`BeamSpan.discretize`).
    n_spans : int
        Spans in the ring buffer.
    mech_ad, mech_bd : ndarray
        Mechanics ZOH matrices (:meth:`VehicleMechanics.discretize`).
    gravity_force : ndarray (n_dof,)
        Generalised gravity ``Q_g`` [N, N m] of the ``"mechanics"`` part.
    force_matrix : ndarray (n_dof, n_points)
        ``B`` of the force points [1, m].
    gains : dict of str to ndarray (n_circuits,)
        ``kp_per_m`` [1/m], ``kd_s_per_m`` [s/m], ``ki_per_m_s`` [1/(m s)],
        ``kflux_per_s`` [1/s].
    flux_bias_Wb : ndarray (n_circuits,)
        Bias flux linkage ``psi_0`` [Wb].
    resistance_ohm, eddy_resistance_ohm : ndarray (n_circuits,)
        ``R_el`` and ``R_ec`` [ohm].
    voltage_limit_V : float
        ``|U| <= U_max`` [V].
    integral_projection : ndarray (n_circuits, n_circuits)
        Maps the gap errors [m] to the integrators' inputs [1].
    midspan_shape : ndarray (n_modes,)
        Mode shapes at midspan [1].
    chopper : {"eq8", "coil_current"}, default "eq8"
        The two-quadrant chopper's bound: ``"eq8"`` the reduced circuit's
        ``U >= -R_ec I_L`` (:func:`~maglevkit.plant.chopper_floor`); ``"coil_current"``
        (detailed magnets, no ``I_L``): no negative voltage while the coil current is
        below 1 A.
    point_offsets_m : ndarray (n_points,), optional
        Distances ``xi_p`` [m] of the force points behind the train's reference point
        (they ride at ``x_ref - xi_p``); with an elastic guideway this adds the part
        ``"guideway_train_loads"``, the compiled step's geometry of the loads.

    Returns
    -------
    dict of str to casadi.Function
        ``"guideway_in"``, ``"cascade"`` (the flux cascade's command before limits),
        ``"voltage_limits"`` (clip, chopper, failures), ``"controllers"`` (the two
        composed), ``"controller_update"``, ``"mechanics_loaded"`` (with ``Q_g`` an
        input), ``"mechanics"`` (with the constant ``gravity_force``),
        ``"guideway_out"``; see the module docstring for the laws.  ``"gaps"``: the
        gaps and rates with the deflection at the points given.  With an elastic
        guideway also the guideway's own parts (:func:`_elastic_guideway`):
        ``"guideway_loads"`` (``"guideway_train_loads"``), ``"guideway_deflection"``,
        ``"guideway_update"``, of which ``"guideway_in"`` and ``"guideway_out"`` are
        composed.
    """
    if chopper not in ("eq8", "coil_current"):
        raise InputError(f"chopper = {chopper!r}; use 'eq8' or 'coil_current'")
    kk = np.asarray(wavenumbers, dtype=float).ravel()
    nm = kk.size
    b_mat = np.asarray(force_matrix, dtype=float)
    n_dof, npt = b_mat.shape
    nc = np.asarray(gains["kp_per_m"]).size
    n_sp = int(n_spans) if nm else 0
    s0 = float(nominal_gap_m)
    sym = ca.MX.sym

    # ---- guideway at the loads, gaps and rates
    x_m, gx_flat, xp, r, rx, v = (sym("x_mech", 2 * n_dof), sym("guideway", n_sp * 2 * nm),
                                  sym("x", npt), sym("r", npt), sym("r_x", npt), sym("v"))
    bt = _sparse(b_mat.T)
    q, qd = x_m[:n_dof], x_m[n_dof:]

    velocity = ca.mtimes(bt, qd)

    def gaps_rates(w: Any, w_rate: Any) -> tuple[Any, Any]:
        """``s = s0 + B^T q - w - r``, ``s' = B^T q' - w_rate - v r_x``."""
        return s0 + ca.mtimes(bt, q) - w - r, velocity - w_rate - v * rx

    elastic: dict[str, Any] = {}
    if nm:
        elastic = _elastic_guideway(
            npt=npt, wavenumbers=kk, n_spans=n_sp, origin_m=origin_m,
            span_length_m=span_length_m, dt=dt, guideway_ad=guideway_ad,
            guideway_bd=guideway_bd, midspan_shape=midspan_shape,
            point_offsets_m=point_offsets_m)
        rows, s1, c1, _, _, _ = elastic["guideway_loads"](xp, v)
        w, w_rate, mid = elastic["guideway_deflection"](gx_flat, rows, s1, c1, v)
    else:
        w = w_rate = ca.MX.zeros(npt)
        mid = ca.MX.zeros(0)
    f_in = ca.Function("vehicle_guideway_in", [x_m, gx_flat, xp, r, rx, v],
                       [*gaps_rates(w, w_rate), w, mid, velocity],
                       ["x_mech", "guideway", "x", "r", "r_x", "v"],
                       ["gap", "gap_rate", "w", "midspan", "velocity"])
    # the same with the deflection given (the compiled step: the loads' geometry once
    # per step, shared with the modal update)
    w_in, wr_in = sym("w", npt), sym("w_rate", npt)
    f_in_w = ca.Function("vehicle_gaps", [x_m, w_in, wr_in, r, rx, v],
                         [*gaps_rates(w_in, wr_in), velocity],
                         ["x_mech", "w", "w_rate", "r", "r_x", "v"],
                         ["gap", "gap_rate", "velocity"])

    # ---- controllers: flux cascade of every circuit, then chopper and failures
    g_s, g_r, i_l, cur, psi, integ, t, fail_t = (
        sym("gap", nc), sym("gap_rate", nc), sym("I_L", nc), sym("current", nc),
        sym("psi_hat", nc), sym("integral", nc), sym("t"), sym("fail_t", nc))
    kp, kd, ki, kf = (ca.DM(np.asarray(gains[k], dtype=float)) for k in
                      ("kp_per_m", "kd_s_per_m", "ki_per_m_s", "kflux_per_s"))
    res, psi0 = ca.DM(np.asarray(resistance_ohm, float)), ca.DM(np.asarray(flux_bias_Wb, float))
    r_ec = ca.DM(np.asarray(eddy_resistance_ohm, float))
    umax = float(voltage_limit_V)
    rho = kp * (g_s - s0) + kd * g_r + ki * integ
    u_cmd = res * cur + kf * (psi0 * (1.0 + rho) - psi)
    f_cas = ca.Function("vehicle_cascade", [g_s, g_r, cur, psi, integ], [u_cmd],
                        ["gap", "damping_input", "current", "psi_hat", "integral"], ["U_cmd"])
    u_c = sym("U_cmd", nc)
    # limits by comparisons, not fmin/fmax, so that NaN stays NaN (as numpy's clip and
    # maximum): the bank then names the same culprit on every path
    u = ca.if_else(u_c < -umax, -umax, ca.if_else(u_c > umax, umax, u_c))
    if chopper == "eq8":
        # 2-quadrant chopper: the reduced model's coil current (U + R_ec I_L)/(R_el + R_ec) >= 0
        u = chopper_floor(u, i_l, r_ec)
    else:
        u = ca.if_else((cur < 1.0) * (u < 0.0), 0.0, u)
    u = ca.if_else(fail_t <= t, 0.0, u)
    f_lim = ca.Function("vehicle_voltage_limits", [u_c, i_l, cur, t, fail_t], [u],
                        ["U_cmd", "I_L", "current", "t", "fail_t"], ["U"])
    u_k = f_lim(f_cas(g_s, g_r, cur, psi, integ), i_l, cur, t, fail_t)
    f_ctl = ca.Function("vehicle_controllers", [g_s, g_r, i_l, cur, psi, integ, t, fail_t], [u_k],
                        ["gap", "gap_rate", "I_L", "current", "psi_hat", "integral", "t",
                         "fail_t"], ["U"])
    u_in, new_cur = sym("U", nc), sym("current_next", nc)
    proj = _sparse(integral_projection)
    psi_next = psi + dt * (u_in - res * 0.5 * (cur + new_cur))
    integ_next = integ + ca.mtimes(proj, (g_s - s0) * dt)
    f_upd = ca.Function("vehicle_controller_update", [psi, integ, u_in, cur, new_cur, g_s],
                        [psi_next, integ_next],
                        ["psi_hat", "integral", "U", "current", "current_next", "gap"],
                        ["psi_hat_next", "integral_next"])

    # ---- mechanics (exact ZOH)
    f_bar, q_g = sym("F_bar", npt), sym("Q_g", n_dof)
    x_next = (ca.mtimes(_sparse(mech_ad), x_m)
              + ca.mtimes(_sparse(mech_bd), q_g - ca.mtimes(_sparse(b_mat), f_bar)))
    f_mech_l = ca.Function("vehicle_mechanics_loaded_step", [x_m, f_bar, q_g], [x_next],
                           ["x_mech", "F_bar", "Q_g"], ["x_mech_next"])
    f_mech = ca.Function("vehicle_mechanics_step", [x_m, f_bar],
                         [f_mech_l(x_m, f_bar, ca.DM(np.asarray(gravity_force, float)))],
                         ["x_mech", "F_bar"], ["x_mech_next"])

    # ---- guideway modal update (loads at the mid-step positions)
    if nm:
        _, _, _, rows_m, s1_m, c1_m = elastic["guideway_loads"](xp, v)
        gx_next_flat = elastic["guideway_update"](gx_flat, rows_m, s1_m, c1_m, f_bar)
    else:
        gx_next_flat = gx_flat
    f_out = ca.Function("vehicle_guideway_out", [gx_flat, xp, v, f_bar], [gx_next_flat],
                        ["guideway", "x", "v", "F_bar"], ["guideway_next"])
    return {"guideway_in": f_in, "cascade": f_cas, "voltage_limits": f_lim,
            "controllers": f_ctl, "controller_update": f_upd, "mechanics_loaded": f_mech_l,
            "mechanics": f_mech, "guideway_out": f_out, "gaps": f_in_w, **elastic}


def build_vehicle_step(*, bank_step: Any, dt: float, nominal_gap_m: float, sides: float,
                       span_length_m: float, origin_m: float, wavenumbers: np.ndarray,
                       guideway_ad: np.ndarray, guideway_bd: np.ndarray, n_spans: int,
                       mech_ad: np.ndarray, mech_bd: np.ndarray, gravity_force: np.ndarray,
                       force_matrix: np.ndarray, gains: dict[str, np.ndarray],
                       flux_bias_Wb: np.ndarray, resistance_ohm: np.ndarray,
                       eddy_resistance_ohm: np.ndarray, voltage_limit_V: float,
                       integral_projection: np.ndarray, midspan_shape: np.ndarray,
                       point_offsets_m: np.ndarray, velocity_blend: float = 0.0,
                       block_steps: int = 50, name: str = "maglevkit_vehicle_step",
                       controller: str = "cascade", motion_eddy: bool = False,
                       eddy_states: int = 1) -> VehicleStepFunction:
    """Compose the vehicle step function (see the module docstring).

    Parameters are the run's constants, as the NumPy loop uses them: ``bank_step`` from
    :meth:`MagnetBank.step_function`, the guideway's and the mechanics' ZOH matrices, the
    mechanics' ``Q_g`` and ``B``, the controller gains and biases, the chopper data, the
    integral projection, the mode shapes at midspan.  ``wavenumbers`` may be empty (rigid
    guideway).  ``block_steps`` steps are chained in the block function (one call from
    Python per block, and the per-block look for events: ~10-20 us of Python against
    ~10 us per step).

    Parameters
    ----------
    bank_step : casadi.Function
        The bank's step (:meth:`MagnetBank.step_function`): inputs ``I_L``, ``s``, ``U``,
        ``sdot``, ``h``; outputs ``I_L_next``, ``I``, ``F``, ``n_bad``.
    dt : float
        Time step [s].
    nominal_gap_m : float
        Nominal gap ``s0`` [m] (gap at zero displacement; the controllers' reference).
    sides : float
        Magnets per lumped position (the bank's force times ``sides`` acts on the frame).
    span_length_m, origin_m : float
        Span length L [m] and position of pier 0 [m].
    wavenumbers : ndarray (n_modes,)
        ``k_j = j pi / L`` [rad/m] (empty: rigid guideway).
    guideway_ad, guideway_bd : ndarray
        Span ZOH matrices (:meth:`BeamSpan.discretize`), (2 n_modes, 2 n_modes) and
        (2 n_modes, n_modes).
    n_spans : int
        Spans in the ring buffer.
    mech_ad, mech_bd : ndarray
        Mechanics ZOH matrices (:meth:`VehicleMechanics.discretize`).
    gravity_force : ndarray (n_dof,)
        Generalised gravity ``Q_g`` [N, N m].
    force_matrix : ndarray (n_dof, n_circuits)
        ``B`` of the force points (its transpose maps ``q`` to the gap changes [m]).
    gains : dict of str to ndarray (n_circuits,)
        Gap-controller gains ``kp_per_m``, ``kd_s_per_m``, ``ki_per_m_s``,
        ``kflux_per_s`` (see :class:`~maglevkit.control.GapController`).
    flux_bias_Wb : ndarray (n_circuits,)
        Bias flux linkage ``psi_0`` [Wb].
    resistance_ohm, eddy_resistance_ohm : ndarray (n_circuits,)
        ``R_el`` and ``R_ec`` [ohm] (the chopper keeps ``U >= -R_ec I_L``).
    voltage_limit_V : float
        ``|U| <= U_max`` [V].
    integral_projection : ndarray (n_circuits, n_circuits)
        Maps the gap errors [m] to the integrators' inputs.
    midspan_shape : ndarray (n_modes,)
        Mode shapes at midspan (for the recorded midspan deflection).
    point_offsets_m : ndarray (n_circuits,)
        Distances ``xi_p`` [m] of the force points behind the reference point whose
        position ``x_ref`` is the step input ``"x_ref"`` (the points ride at
        ``x_ref - xi_p``).
    velocity_blend : float, default 0.0
        Share [-] of the force points' absolute velocity ``B^T q'`` in the cascade's
        damping input (:func:`~maglevkit.control.damping_input`; 0: the gap rate).
    block_steps : int, default 50
        Steps chained in ``block_function`` (one call from Python per block).
    name : str, default "maglevkit_vehicle_step"
        Name of the CasADi function (and of its compiled library).
    controller : {"cascade", "held"}, default "cascade"
        ``"cascade"``: the flux cascade computes every circuit's voltage in the step.
        ``"held"``: the voltages come in per step (``P``'s ``"u_held"``, e.g. an NMPC's
        outputs held over its sample; :class:`StepLayout`), through the same
        ``"voltage_limits"`` part, and so does the generalised gravity (``"q_g"``
        [N, N m]: payload steps; the ``"mechanics_loaded"`` part); the cascade's flux
        estimate and integrator are still updated (the integrator is the NMPC's
        reference correction).
    motion_eddy : bool, default False
        The bank has shielded-gap ladder members (:attr:`MagnetBank.motion_eddy`): its
        step takes and returns the eddy currents ``I_e``, which the state carries (block
        ``"I_e"`` after the others) and the record holds at the step start (``"I_e"``,
        last); the chopper floor is the ladder's, ``U >= -R_a (I_L + I_e)``
        (``eddy_resistance_ohm`` then holds the bank's ``R_a`` in ladder circuits).
        False: the layout and the function are the ones without the ladder.
    eddy_states : {1, 2}, default 1
        Eddy states per circuit with ``motion_eddy`` (:attr:`MagnetBank.n_eddy_states`):
        2 for the three-state ladder, whose ``I_e`` block then holds ``2 n_c`` entries
        (every circuit's ``I_e1``, then ``I_e2``) and whose chopper floor is ``U >= -R_a
        (I_L + I_e1 + I_e2)``.

    Returns
    -------
    VehicleStepFunction
        Not compiled here (the caller compiles it).  Inputs are not checked.
    """
    kk = np.asarray(wavenumbers, dtype=float).ravel()
    nm = kk.size
    b_mat = np.asarray(force_matrix, dtype=float)
    n_dof, nc = b_mat.shape
    n_sp = int(n_spans) if nm else 0
    if controller not in ("cascade", "held"):
        raise InputError(f"controller = {controller!r}; use 'cascade' or 'held'")
    held = controller == "held"
    lay = _layout(n_dof, nc, n_sp, nm, held, motion_eddy, eddy_states)
    sym = ca.MX.sym
    parts = build_vehicle_parts(
        dt=dt, nominal_gap_m=nominal_gap_m, span_length_m=span_length_m, origin_m=origin_m,
        wavenumbers=kk, guideway_ad=guideway_ad, guideway_bd=guideway_bd, n_spans=n_spans,
        mech_ad=mech_ad, mech_bd=mech_bd, gravity_force=gravity_force, force_matrix=b_mat,
        gains=gains, flux_bias_Wb=flux_bias_Wb, resistance_ohm=resistance_ohm,
        eddy_resistance_ohm=eddy_resistance_ohm, voltage_limit_V=voltage_limit_V,
        integral_projection=integral_projection, midspan_shape=midspan_shape,
        point_offsets_m=point_offsets_m)
    # the matrix parts without data-dependent indexing expanded to scalar code: in the
    # generated C straight-line products instead of CasADi's sparse-product loops, the
    # same operations in the same order (bit-identical; the 3-section train's block 8.1 ->
    # 7.5 us per step); the element-wise controller parts stay as they are (expanded,
    # CasADi reorders their arithmetic: ~1e-14 relative)
    expanded = {k: parts[k].expand() for k in ("mechanics", "mechanics_loaded", "gaps")}
    if not nm:
        expanded["guideway_in"] = parts["guideway_in"].expand()
    f_in, f_ctl, f_upd, f_mech = ({**parts, **expanded}[k] for k in (
        "guideway_in", "controllers", "controller_update", "mechanics"))

    # ---- the composed step
    S, P, C = sym("S", lay.n_state), sym("P", lay.n_step_inputs), sym("C", 1 + nc)
    st, sp = lay.state, lay.step_inputs
    s_xm, s_gx, s_il, s_psi, s_int, s_cur, s_f = (S[st[k]] for k in (
        "x_mech", "guideway", "I_L", "psi_hat", "integral", "current", "force"))
    p_x, p_r, p_rx, p_t, p_keep = (P[sp[k]] for k in ("x_ref", "r", "r_x", "t", "keep"))
    c_v, c_fail = C[0], C[1:]
    if nm:    # spans recycled by the moving boundary at this step: rows reset to rest
        s_gx = ca.reshape(ca.reshape(s_gx, 2 * nm, n_sp) * ca.repmat(p_keep.T, 2 * nm, 1),
                          n_sp * 2 * nm, 1)
    if nm:    # the loads' geometry once per step, for the deflection and the update
        rows_k, sa_k, ca_k, rows_mk, sa_mk, ca_mk = parts["guideway_train_loads"](p_x, c_v)
        w_k, wr_k, mid_k = parts["guideway_deflection"](s_gx, rows_k, sa_k, ca_k, c_v)
        gap_k, rate_k, vel_k = expanded["gaps"](s_xm, w_k, wr_k, p_r, p_rx, c_v)
    else:
        gap_k, rate_k, w_k, mid_k, vel_k = f_in(s_xm, s_gx, ca.MX.zeros(nc), p_r, p_rx, c_v)
    damp_k = rate_k if velocity_blend == 0.0 else damping_input(rate_k, vel_k,
                                                                float(velocity_blend))
    # the chopper's current: I_L (eq. 8), I_L + I_e (the ladder: I = (U/R_a + I_L +
    # I_e)/a, so I >= 0 is U >= -R_a (I_L + I_e), the same floor; three states: I_L +
    # I_e1 + I_e2)
    s_ie = S[st["I_e"]] if motion_eddy else None
    i_chop = terminal_current(s_il, s_ie, nc)
    if held:
        u_k = parts["voltage_limits"](P[sp["u_held"]], i_chop, s_cur, p_t, c_fail)
    else:
        u_k = f_ctl(gap_k, damp_k, i_chop, s_cur, s_psi, s_int, p_t, c_fail)
    il_next, cur_next, force_next, n_bad, flags, il_lo, il_hi, ie_next = bank_step_outputs(
        bank_step, il=s_il, ie=s_ie, gaps=gap_k, voltages=u_k, rates=rate_k, dt=dt)
    eddy_next = [] if ie_next is None else [ie_next]
    eddy_rec = [] if s_ie is None else [s_ie]
    psi_n, int_n = f_upd(s_psi, s_int, u_k, s_cur, cur_next, gap_k)
    fb = (0.5 * sides) * (s_f + force_next)
    xm_n = expanded["mechanics_loaded"](s_xm, fb, P[sp["q_g"]]) if held else f_mech(s_xm, fb)
    gx_n = parts["guideway_update"](s_gx, rows_mk, sa_mk, ca_mk, fb) if nm else s_gx
    s_next = ca.vertcat(xm_n, gx_n, il_next, psi_n, int_n, cur_next, force_next, *eddy_next)
    rec = ca.vertcat(gap_k, rate_k, s_cur, s_f, s_il, w_k, s_xm, mid_k, u_k, ca.mmin(gap_k),
                     ca.mmax(gap_k), n_bad, flags, il_lo, il_hi, *eddy_rec)
    assert rec.shape[0] == lay.n_record and s_next.shape[0] == lay.n_state
    fun = ca.Function(name, [S, P, C], [s_next, rec], ["S", "P", "C"], ["S_next", "R"])
    measure = ca.Function(f"{name}_measure", [S, P, C], [gap_k, rate_k], ["S", "P", "C"],
                          ["gap", "gap_rate"])
    nb = int(block_steps)
    Sb, Pb = sym("S", lay.n_state), sym("P", lay.n_step_inputs, nb)
    s_b: Any = Sb
    recs = []
    for j in range(nb):
        s_b, r_j = fun(s_b, Pb[:, j], C)
        recs.append(r_j)
    block = ca.Function(f"{name}s{nb}", [Sb, Pb, C], [s_b, ca.horzcat(*recs)],
                        ["S", "P", "C"], ["S_next", "R"])
    return VehicleStepFunction(fun, block, nb, lay, {**parts, "magnets": bank_step}, measure)
