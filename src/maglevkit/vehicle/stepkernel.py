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
    magnets   the bank's own step function (MagnetBank.step_function: RK4 of eq. 8)
    control   psi_hat += dt (U - R (I + I+)/2),   e_I += P (s - s0) dt
    mechanics x+ = Ad x + Bd (Q_g - B F_bar),     F_bar = sides (F + F+)/2
    guideway  X+ = X Ad^T + Q Bd^T,  Q[r] = sum over the loads on ring row r of
              sin(k_j xi_mid) F_bar  (mid-step positions)

Which ring rows the moving system boundary recycles at which step, and the check that the
loads stay on the integrated spans, are computed in Python before the loop (they change
once per span crossing); the rows come in as a per-step keep mask (1 keep, 0 reset to
rest).  The mode shapes' ring rows follow inside the function from the load positions
(``row = floor((x - x0)/L) mod N``, as the loop computes them).

Layout (:class:`StepLayout`): input ``S`` (state), ``P`` (per-step inputs: the load
positions at the step start, the irregularity and its slope there, the time, the keep
mask), ``C`` (per-run constants: speed and failure times); outputs ``S_next`` and ``R``
(the record of the step: gaps, rates, coil currents, forces and ``I_L`` at the step start,
deflections, the mechanical state, the midspan deflection per ring row, the voltages,
min/max gap and the bank's out-of-range count).  The block function chains the step
``block_steps`` times (``P`` and ``R`` one column per step).
"""

from __future__ import annotations

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
        ``"psi_hat"``, ``"integral"``, ``"current"``, ``"force"``).
    step_inputs : dict of str to slice
        Parts of the per-step input ``P`` (``"x"``, ``"r"``, ``"r_x"``, ``"t"``,
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


def _layout(n_dof: int, nc: int, n_sp: int, nm: int, held: bool = False) -> StepLayout:
    state = pack_slices([("x_mech", 2 * n_dof), ("guideway", n_sp * 2 * nm), ("I_L", nc),
                         ("psi_hat", nc), ("integral", nc), ("current", nc), ("force", nc)])
    extra = [("u_held", nc), ("q_g", n_dof)] if held else []
    step = pack_slices([("x", nc), ("r", nc), ("r_x", nc), ("t", 1), ("keep", n_sp), *extra])
    record = pack_slices([("gap", nc), ("gap_rate", nc), ("current", nc), ("force", nc), ("I_L", nc),
                          ("deflection", nc), ("q", n_dof), ("q_dot", n_dof), ("midspan_ring", n_sp),
                          ("voltage", nc), ("gap_min", 1), ("gap_max", 1), ("n_bad", 1)])
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
        ``"guideway_in"`` (deflection, rate at the loads; gaps), ``"controllers"``
        (voltages), ``"magnets"`` (the bank's step), ``"controller_update"``,
        ``"mechanics"``, ``"guideway_out"`` (modal update), composed by ``function``.
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


def build_vehicle_parts(*, dt: float, nominal_gap_m: float, span_length_m: float,
                        origin_m: float, wavenumbers: np.ndarray, guideway_ad: np.ndarray,
                        guideway_bd: np.ndarray, n_spans: int, mech_ad: np.ndarray,
                        mech_bd: np.ndarray, gravity_force: np.ndarray,
                        force_matrix: np.ndarray, gains: dict[str, np.ndarray],
                        flux_bias_Wb: np.ndarray, resistance_ohm: np.ndarray,
                        eddy_resistance_ohm: np.ndarray, voltage_limit_V: float,
                        integral_projection: np.ndarray, midspan_shape: np.ndarray,
                        chopper: str = "eq8") -> dict[str, Any]:
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

    Returns
    -------
    dict of str to casadi.Function
        ``"guideway_in"``, ``"cascade"`` (the flux cascade's command before limits),
        ``"voltage_limits"`` (clip, chopper, failures), ``"controllers"`` (the two
        composed), ``"controller_update"``, ``"mechanics_loaded"`` (with ``Q_g`` an
        input), ``"mechanics"`` (with the constant ``gravity_force``),
        ``"guideway_out"``; see the module docstring for the laws.
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

    def shapes(xs: Any) -> tuple[Any, Any, Any]:
        """Ring-row one-hot matrix (npt, N), sin(k_j xi) and cos(k_j xi) (npt, nm) at the
        positions ``xs``.  ``sin(j a)``, ``cos(j a)`` by the angle-addition recurrence from
        ``sin a``, ``cos a`` (two transcendental calls per point instead of 2 nm; the
        rounding differs from direct evaluation by a few ulp)."""
        ks = ca.floor((xs - origin_m) / span_length_m)
        rows = ks - n_sp * ca.floor(ks / n_sp)
        onehot = ca.horzcat(*[rows == j for j in range(n_sp)])
        a = (xs - (origin_m + ks * span_length_m)) * float(kk[0])
        s1, c1 = ca.sin(a), ca.cos(a)
        sins, coss = [s1], [c1]
        for _ in range(1, nm):
            sj, cj = sins[-1], coss[-1]
            sins.append(sj * c1 + cj * s1)
            coss.append(cj * c1 - sj * s1)
        return onehot, ca.horzcat(*sins), ca.horzcat(*coss)

    w: Any
    w_rate: Any
    mid: Any
    if nm:
        gx = ca.reshape(gx_flat, 2 * nm, n_sp).T            # (N, 2 nm), row-major as the loop
        onehot, phi, cosines = shapes(xp)
        dphi = cosines * ca.repmat(ca.DM(kk).T, npt, 1)
        qg = ca.mtimes(onehot, gx)
        w = ca.sum2(qg[:, :nm] * phi)
        w_rate = ca.sum2(qg[:, nm:] * phi) + v * ca.sum2(qg[:, :nm] * dphi)
        mid = ca.mtimes(gx[:, :nm], ca.DM(np.asarray(midspan_shape, dtype=float)))
    else:
        w = w_rate = ca.MX.zeros(npt)
        mid = ca.MX.zeros(0)
    gaps = s0 + ca.mtimes(bt, q) - w - r
    rates = ca.mtimes(bt, qd) - w_rate - v * rx
    f_in = ca.Function("vehicle_guideway_in", [x_m, gx_flat, xp, r, rx, v],
                       [gaps, rates, w, mid, ca.mtimes(bt, qd)],
                       ["x_mech", "guideway", "x", "r", "r_x", "v"],
                       ["gap", "gap_rate", "w", "midspan", "velocity"])

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
        half = 0.5 * v * dt
        onehot_m, sn_m, _ = shapes(xp + half)
        qmod = ca.mtimes(onehot_m.T, sn_m * ca.repmat(f_bar, 1, nm))
        gx_next = (ca.mtimes(gx, _sparse(np.asarray(guideway_ad).T))
                   + ca.mtimes(qmod, _sparse(np.asarray(guideway_bd).T)))
        gx_next_flat = ca.reshape(gx_next.T, n_sp * 2 * nm, 1)
    else:
        gx_next_flat = gx_flat
    f_out = ca.Function("vehicle_guideway_out", [gx_flat, xp, v, f_bar], [gx_next_flat],
                        ["guideway", "x", "v", "F_bar"], ["guideway_next"])
    return {"guideway_in": f_in, "cascade": f_cas, "voltage_limits": f_lim,
            "controllers": f_ctl, "controller_update": f_upd, "mechanics_loaded": f_mech_l,
            "mechanics": f_mech, "guideway_out": f_out}


def build_vehicle_step(*, bank_step: Any, dt: float, nominal_gap_m: float, sides: float,
                       span_length_m: float, origin_m: float, wavenumbers: np.ndarray,
                       guideway_ad: np.ndarray, guideway_bd: np.ndarray, n_spans: int,
                       mech_ad: np.ndarray, mech_bd: np.ndarray, gravity_force: np.ndarray,
                       force_matrix: np.ndarray, gains: dict[str, np.ndarray],
                       flux_bias_Wb: np.ndarray, resistance_ohm: np.ndarray,
                       eddy_resistance_ohm: np.ndarray, voltage_limit_V: float,
                       integral_projection: np.ndarray, midspan_shape: np.ndarray,
                       velocity_blend: float = 0.0,
                       block_steps: int = 10, name: str = "maglevkit_vehicle_step",
                       controller: str = "cascade") -> VehicleStepFunction:
    """Compose the vehicle step function (see the module docstring).

    Parameters are the run's constants, as the NumPy loop uses them: ``bank_step`` from
    :meth:`MagnetBank.step_function`, the guideway's and the mechanics' ZOH matrices, the
    mechanics' ``Q_g`` and ``B``, the controller gains and biases, the chopper data, the
    integral projection, the mode shapes at midspan.  ``wavenumbers`` may be empty (rigid
    guideway).  ``block_steps`` steps are chained in the block function (one call from
    Python per block: the per-call cost of binding buffers is ~1-2 us, a step ~40 us).

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
    velocity_blend : float, default 0.0
        Share [-] of the force points' absolute velocity ``B^T q'`` in the cascade's
        damping input (:func:`~maglevkit.control.damping_input`; 0: the gap rate).
    block_steps : int, default 10
        Steps chained in ``block_function``.
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
    lay = _layout(n_dof, nc, n_sp, nm, held)
    sym = ca.MX.sym
    parts = build_vehicle_parts(
        dt=dt, nominal_gap_m=nominal_gap_m, span_length_m=span_length_m, origin_m=origin_m,
        wavenumbers=kk, guideway_ad=guideway_ad, guideway_bd=guideway_bd, n_spans=n_spans,
        mech_ad=mech_ad, mech_bd=mech_bd, gravity_force=gravity_force, force_matrix=b_mat,
        gains=gains, flux_bias_Wb=flux_bias_Wb, resistance_ohm=resistance_ohm,
        eddy_resistance_ohm=eddy_resistance_ohm, voltage_limit_V=voltage_limit_V,
        integral_projection=integral_projection, midspan_shape=midspan_shape)
    f_in, f_ctl, f_upd, f_mech, f_out = (parts[k] for k in (
        "guideway_in", "controllers", "controller_update", "mechanics", "guideway_out"))

    # ---- the composed step
    S, P, C = sym("S", lay.n_state), sym("P", lay.n_step_inputs), sym("C", 1 + nc)
    st, sp = lay.state, lay.step_inputs
    s_xm, s_gx, s_il, s_psi, s_int, s_cur, s_f = (S[st[k]] for k in (
        "x_mech", "guideway", "I_L", "psi_hat", "integral", "current", "force"))
    p_x, p_r, p_rx, p_t, p_keep = (P[sp[k]] for k in ("x", "r", "r_x", "t", "keep"))
    c_v, c_fail = C[0], C[1:]
    if nm:    # spans recycled by the moving boundary at this step: rows reset to rest
        s_gx = ca.reshape(ca.reshape(s_gx, 2 * nm, n_sp) * ca.repmat(p_keep.T, 2 * nm, 1),
                          n_sp * 2 * nm, 1)
    gap_k, rate_k, w_k, mid_k, vel_k = f_in(s_xm, s_gx, p_x, p_r, p_rx, c_v)
    damp_k = rate_k if velocity_blend == 0.0 else damping_input(rate_k, vel_k,
                                                                float(velocity_blend))
    if held:
        u_k = parts["voltage_limits"](P[sp["u_held"]], s_il, s_cur, p_t, c_fail)
    else:
        u_k = f_ctl(gap_k, damp_k, s_il, s_cur, s_psi, s_int, p_t, c_fail)
    bout = bank_step.call({"I_L": s_il, "s": gap_k, "U": u_k, "sdot": rate_k, "h": ca.MX(dt)})
    il_next, cur_next, force_next, n_bad = (bout[k] for k in ("I_L_next", "I", "F", "n_bad"))
    psi_n, int_n = f_upd(s_psi, s_int, u_k, s_cur, cur_next, gap_k)
    fb = (0.5 * sides) * (s_f + force_next)
    xm_n = parts["mechanics_loaded"](s_xm, fb, P[sp["q_g"]]) if held else f_mech(s_xm, fb)
    gx_n = f_out(s_gx, p_x, c_v, fb)
    s_next = ca.vertcat(xm_n, gx_n, il_next, psi_n, int_n, cur_next, force_next)
    rec = ca.vertcat(gap_k, rate_k, s_cur, s_f, s_il, w_k, s_xm, mid_k, u_k, ca.mmin(gap_k),
                     ca.mmax(gap_k), n_bad)
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
