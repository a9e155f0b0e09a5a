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

``CurrentModel(maps, eddy_modes=m)`` replaces ``R_ec`` by an RL eddy network
``1/R_0 + sum_k 1/(R_k + p L_k)`` with one state ``I_k`` per branch (for detailed models
whose eddy currents diffuse; :mod:`maglevkit.reduction.eddy_network`, docs/reduction.md)::

    U_L = (U - R_el (I_L + sum_k I_k)) / (1 + R_el/R_0)
    L~ dI_L/dt = U_L - dL/ds I_L ds/dt,     L_k L~/L~_ref dI_k/dt = U_L - R_k I_k
    I = (U - U_L)/R_el

``CurrentModel(maps, motion_eddy=True)`` makes the motion-induced term pass through eddy
dynamics (our extension of Fig. 8 for gap motion; :mod:`maglevkit.reduction.motion_eddy`):
the ladder ``R_el`` -- shunt ``R_a`` -- series ``L_u`` -- shunt ``R_2 || L(s, I_L)``, two
states per circuit (``I_L`` and the shielding eddy current ``I_e``)::

    V_A = (U - R_el (I_L + I_e))/(1 + R_el/R_a),   V_m = R_2 I_e
    (L~ - L_u) dI_L/dt = V_m - dL/ds I_L ds/dt,     L_u dI_e/dt = V_A - V_m - L_u dI_L/dt
    I = (U - V_A)/R_el
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import casadi as ca
import numpy as np

from ..errors import InputError, OutOfRangeError, SolverError
from ..models.compiled import COMPILE_MODES, DEFAULT_FLAGS, BoundCall, compile_linked
from ..models.inputs import check_initial_choice, check_step, per_name_values, simulation_inputs
from ..reduction.motion_eddy import ladder3_force_current
from ..validation import external_stacklevel, flag, real_array, renamed_keywords
from .core import (
    EXTRA_CELLS,
    STEP_FLAG_MESSAGES,
    MotionEddyLadder,
    ReducedCore,
    StepFlag,
    diagnose_flags,
    eq8_a,
    extend_values,
    rk4_substep,
    substep_count,
    substep_counts,
)

if TYPE_CHECKING:
    from ..reduction.maps import CharacteristicMaps

__all__ = ["CurrentModel", "CurrentModelLinearization", "CurrentModelState", "CurrentOutputs",
           "ReducedSimulation", "check_network_freewheel", "eddy_network_coil_current",
           "eddy_network_freewheel_voltage", "eddy_network_parameters", "eddy_network_rhs",
           "eq8_coil_current", "eq8_eddy_branch_rhs", "eq8_freewheel_voltage", "eq8_rhs",
           "eq8_shielded_gap_rhs", "shielded_gap_force_current", "shielded_gap_freewheel_voltage"]


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
    eddy_currents_A : ndarray (n_circuits, m), (n_circuits,) or None
        Currents ``I_k`` [A] of the eddy network's RL branches (``CurrentModel(maps,
        eddy_modes=m)``); ``(n_circuits,)``: the shielding eddy current ``I_e`` of the gap
        section (``motion_eddy=True``; ``(n_circuits, 1)`` is still read, deprecated);
        ``(n_circuits, 2)``: ``(I_e1, I_e2)`` of the three-state ladder
        (``eddy_branches=2``); None for eq. 8's single ``R_ec`` (the default).
    """

    time_s: float
    inductor_currents_A: np.ndarray
    gaps_m: np.ndarray
    eddy_currents_A: np.ndarray | None = None


@dataclass(frozen=True)
class CurrentOutputs:
    """Outputs of the current-based model at the end of a step.

    Attributes
    ----------
    time_s : float
        Time [s].
    currents_A : ndarray (n_circuits,)
        Coil currents [A] (with the voltages of the step just taken).
    inductor_currents_A : ndarray (n_circuits,)
        Currents ``I_L`` through the inductors ``L~`` [A] (the ODE states, a copy).
    circuit_force_N : ndarray (n_circuits,)
        Force of each circuit's poles [N], attraction positive.
    pole_force_N : ndarray (n_gaps,)
        Circuit force shared equally by the circuit's poles [N].
    force_N : float
        Total force of the magnet [N].
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
        Sample times [s].
    gaps_m, gap_rates_m_per_s : ndarray (n_t, n_gaps)
        Pole gaps [m] and the gap rates [m/s] held on each interval (the gaps' secants).
    voltages_V, currents_A, inductor_currents_A, circuit_force_N : ndarray (n_t, n_circuits)
        Circuit voltages [V], coil currents [A], inductor currents ``I_L`` [A] and circuit
        forces [N].
    pole_force_N : ndarray (n_t, n_gaps)
        Circuit forces shared equally by each circuit's poles [N].
    force_N : ndarray (n_t,)
        Total force [N].
    gap_names : tuple of str
        Names of the pole gaps, the order of the ``n_gaps`` columns.
    circuit_names : tuple of str
        Names of the circuits, the order of the ``n_circuits`` columns.
    final_state : CurrentModelState
        State at ``time_s[-1]``, to continue with :meth:`CurrentModel.step` or as
        ``initial_state`` of another :meth:`CurrentModel.simulate`.
    eddy_currents_A : ndarray (n_t, n_circuits, m), (n_t, n_circuits) or None
        Eddy-branch currents ``I_k`` [A] with ``eddy_modes = m > 0``, the shielding eddy
        current ``I_e`` (``(n_t, n_circuits)``) with ``motion_eddy=True``, ``(I_e1, I_e2)``
        (``(n_t, n_circuits, 2)``) with ``eddy_branches=2``, else None.
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
    eddy_currents_A: np.ndarray | None = None


@dataclass(frozen=True)
class CurrentModelLinearization:
    """Linearisation of the current-based model at one operating point (CasADi AD).

    With deviations ``x = dI_L`` (state), ``u = dU`` (voltages), ``g = ds`` (pole gaps)
    and ``r = d(ds/dt)`` (pole gap rates)::

        dx/dt = A x + B u + E_gap g + E_gap_rate r
        dF    = C_force x + D_force_gap g                 (circuit forces)
        dI    = C_current x + D_current u                 (coil currents)

    With ``eddy_modes = m > 0`` the state is ``x = (dI_L, dI_ec)``: the ``n_c`` inductor
    currents, then the ``n_c m`` eddy-branch currents (circuit by circuit, branch ``k``
    of circuit ``j`` at ``n_c + j m + k``); the rows and columns below that say
    ``n_circuits`` for the state have ``n_c (1 + m)`` entries then.  With
    ``motion_eddy=True`` likewise with ``m = 1`` (``dI_e``, the shielding eddy current).

    Attributes
    ----------
    gaps_m : ndarray (n_gaps,)
        Pole gaps of the operating point [m].
    inductor_currents_A : ndarray (n_circuits,)
        ``I_L`` of the operating point [A].
    voltages_V : ndarray (n_circuits,)
        Voltages of the operating point [V].
    gap_rates_m_per_s : ndarray (n_gaps,)
        Pole gap rates of the operating point [m/s].
    state_derivative_A_per_s : ndarray (n_circuits,)
        ``dI_L/dt`` at the operating point [A/s] (0 at a steady state).
    A_per_s : ndarray (n_circuits, n_circuits)
        ``d(dI_L/dt)/dI_L`` [1/s].
    B_A_per_V_s : ndarray (n_circuits, n_circuits)
        ``d(dI_L/dt)/dU`` [A/(V s)].
    E_gap_A_per_m_s : ndarray (n_circuits, n_gaps)
        ``d(dI_L/dt)/ds_k`` per pole gap [A/(m s)].
    E_gap_rate_A_per_m : ndarray (n_circuits, n_gaps)
        ``d(dI_L/dt)/d(ds_k/dt)`` per pole gap rate [A/m].
    C_force_N_per_A : ndarray (n_circuits, n_circuits)
        ``dF_j/dI_L`` [N/A].
    D_force_gap_N_per_m : ndarray (n_circuits, n_gaps)
        ``dF_j/ds_k`` [N/m] (the force does not depend on the voltage).
    C_current : ndarray (n_circuits, n_circuits)
        ``dI/dI_L`` [A/A].
    D_current_A_per_V : ndarray (n_circuits, n_circuits)
        ``dI/dU`` [A/V] (the current jump ``1/(R_el + R_ec)`` of a voltage step).
    circuit_names, gap_names : tuple of str
    """

    gaps_m: np.ndarray
    inductor_currents_A: np.ndarray
    voltages_V: np.ndarray
    gap_rates_m_per_s: np.ndarray
    state_derivative_A_per_s: np.ndarray
    A_per_s: np.ndarray
    B_A_per_V_s: np.ndarray
    E_gap_A_per_m_s: np.ndarray
    E_gap_rate_A_per_m: np.ndarray
    C_force_N_per_A: np.ndarray
    D_force_gap_N_per_m: np.ndarray
    C_current: np.ndarray
    D_current_A_per_V: np.ndarray
    circuit_names: tuple[str, ...]
    gap_names: tuple[str, ...]


class CurrentModel:
    """The current-based model of a magnet, built from its characteristic maps.

    Parameters
    ----------
    maps : CharacteristicMaps
        From :func:`maglevkit.reduction.build_maps` or :func:`~maglevkit.reduction.load_maps`.
    extrapolate : bool
        Leaving the maps' gap or current range raises :class:`OutOfRangeError` (default);
        with ``True`` the maps are continued linearly from their edge slope for up to
        three grid cells and a warning is issued (beyond that it raises as well).
    method : {"rk4", "cvodes"}
        ``"rk4"`` (default): classical Runge-Kutta with sub-steps of at most
        ``max_step_s``, compiled in CasADi (SX); ``"cvodes"``: SUNDIALS CVODES, adaptive
        BDF with error control.  Eq. 8 is not stiff (time constants >= 4 ms even in deep
        saturation); RK4 at 1 ms sub-steps stays within 3e-6 of CVODES at rtol 1e-11 on a
        saturating voltage step and a 50 Hz gap sine, and costs ~4 us per interval instead
        of a ~150 us CVODES restart at every input change (docs/decisions.md).
    rtol, atol : float
        CVODES tolerances (defaults 1e-8 relative, 1e-10 absolute).
    max_step_s : float
        Largest RK4 sub-step [s] (default 1e-3 s).  With ``eddy_modes > 0`` or
        ``motion_eddy`` the sub-step is also limited to ``1.5/lambda`` with ``lambda`` a
        bound (Gershgorin) of the fastest eddy branch's rate over the maps (RK4 is
        stable up to 2.78/lambda): the fast branches are stiff for the explicit
        integrator (attribute ``max_step_s`` holds the step used).
    eddy_resistance : {"fit", "jump"} or None
        Which ``R_ec`` of the maps to use: ``"fit"`` (default; None means ``"fit"``) the
        value the step-response time constant implies (the paper's procedure; eq. 8 then
        has the detailed model's dominant time constant), or ``"jump"`` the exact
        instantaneous current jump of the detailed model.  Measured on the standard
        scenarios the fit value gives the smaller errors (docs/decisions.md).  Not with
        ``eddy_modes > 0`` (the network's ``R_0`` takes ``R_ec``'s place there).
    eddy_modes : int
        ``0`` (default): eq. 8 with one eddy resistor ``R_ec`` (Fig. 8).  ``m`` in
        :data:`~maglevkit.reduction.eddy_network.EDDY_NETWORK_MODES` (1, 2, 3): the eddy branch is
        the RL network ``1/R_0 + sum_k 1/(R_k + p L_k)`` with ``m`` branches fitted to the
        detailed model's voltage step at the maps' reference point or at
        ``build_maps(eddy_reference=...)`` (maps variables ``eddy_network_*``; identify
        at the operating point if it is known), one extra state ``I_k`` per branch and circuit; ``L_k`` scales
        with ``L~(s, I_L)`` (docs/reduction.md, "More eddy modes").  For detailed models
        whose eddy currents diffuse (``eddy_model="ladder"`` or ``"ladder_split"``).  The
        magnet file's choice for these maps is ``maps.default_eddy_modes`` (``[reduced]
        eddy_modes``; 2 for the bundled TR09 magnets); the option's default stays 0
        (docs/reduction.md, "Which `m` by default").
    motion_eddy : bool
        ``False`` (default): eq. 8.  ``True``: the shielded-gap ladder (our extension of
        Fig. 8 for gap motion; :mod:`maglevkit.reduction.motion_eddy`, docs/reduction.md,
        "Gap motion"): ``R_el``, a shunt ``R_a``, a series ``L_u`` and the gap section
        ``L(s, I_L)`` shunted by its eddy resistance ``R_2``, so that the motion-induced
        current passes through eddy dynamics; ``R_a``, ``L_u``, ``R_2`` are fitted by
        ``build_maps`` to the detailed model's small-signal gap and voltage responses
        (maps variables ``motion_eddy_*``).  Two states per circuit: ``I_L`` and the
        shielding eddy current ``I_e`` (``eddy_currents_A``, shape ``(n_circuits,)``, as in
        :class:`MagnetBank`).
        Not with ``eddy_modes > 0`` or ``eddy_resistance``.
    eddy_branches : int
        With ``motion_eddy=True``: ``1`` (default) the two-state ladder above; ``2`` the
        three-state ladder with a second shielded section (two eddy time scales,
        :func:`eq8_shielded_gap3_rhs`, maps variables ``motion_eddy3_*``; docs/equations.md
        section 8): states ``I_L`` and ``eddy_currents_A`` of shape ``(n_circuits, 2)``,
        ``(I_e1, I_e2)`` = ``(I_2 - I_L, I_u - I_2)``, the force
        ``F(s, I_L + c_1 I_e1 + c_2 I_e2)``.  B-spline path only (with or without
        ``linearize``); with ``freewheel`` the diodes act on the terminal current ``I_L +
        I_e1 + I_e2``; a :class:`MagnetBank` member (its kernel, stepper and the FMU carry
        it).
    freewheel : bool
        ``False`` (default): eq. 8 with the applied voltage as given.  ``True``: behind a
        two-quadrant chopper with freewheeling diodes, the coil current cannot go below
        zero within a step (:func:`eq8_freewheel_voltage` in every RK4 stage and in the
        coil current; the same law as ``MagnetBank(freewheel=True)``).  With
        ``motion_eddy`` the diodes act on the ladder's coil current
        ``(U/R_a + I_L + I_e)/a`` (:func:`shielded_gap_freewheel_voltage`, the bank's law).
        With ``eddy_modes > 0`` on the network's terminal current ``I_L + sum_k I_k``
        (:func:`eddy_network_freewheel_voltage`, the bank's law); a network whose fitted
        ``R_0`` is inf is refused (:func:`check_network_freewheel`).
    jit : bool
        Compile the B-spline RK4 interval (``lookup="bspline"``) to machine code with
        CasADi's JIT (needs a C compiler on the ``PATH``; ~0.3 s once per sub-step count).
        :class:`SolverError` if compilation fails.  Implies ``lookup="bspline"``.
    lookup : {"tables", "bspline"}
        How RK4 (``method="rk4"``; eq. 8 or the eddy network) reads the maps in :meth:`step` and
        :meth:`simulate`.  ``"tables"`` (default): the compiled per-cell tables of
        :class:`~maglevkit.reduced.bank.MagnetBank` (the same bicubic function as the
        B-spline, equal to it within 1e-12 relative on the standard scenarios,
        docs/decisions.md), one compiled call per step and the whole time loop of
        :meth:`simulate` in C.  ``"bspline"``: CasADi's B-spline interpolants evaluated
        per interval.  A step the table kernel flags (it leaves the maps, an input is not
        finite) raises from the kernel's reason codes with the messages of every reduced
        model (:data:`~maglevkit.reduced.core.STEP_FLAG_MESSAGES`); with ``extrapolate``,
        a non-finite result, a pole gap <= 0 or a run that starts outside the maps the call
        is redone on the B-spline path (the continuation beyond the maps is the
        B-spline's), which raises or warns; maps on a grid that is not regular (or has
        fewer than 4 points) stay on the B-splines.  :meth:`linearize`, :attr:`ode` and
        :attr:`outputs_fun` (AD, MPC), ``method="cvodes"`` and ``motion_eddy=True``
        always use the B-splines; ``eddy_modes > 0`` runs on the tables too (the bank's
        eddy-network member; docs/reduction.md, "The compiled tables").
    compiled : {"auto", "always", "never"}
        How the tables are compiled (as :class:`~maglevkit.reduced.bank.MagnetBank`):
        ``"auto"`` (default) by the system C compiler, cached on disk, falling back to
        CasADi's virtual machine with a warning; ``"never"`` the virtual machine;
        ``"always"`` a :class:`SolverError` if compiling fails.
    """

    def __init__(self, maps: CharacteristicMaps, *, extrapolate: bool = False, method: str = "rk4",
                 rtol: float = 1e-8, atol: float = 1e-10, max_step_s: float = 1e-3,
                 eddy_resistance: str | None = None, jit: bool = False,
                 eddy_modes: int = 0, motion_eddy: bool = False, lookup: str = "tables",
                 compiled: str = "auto", freewheel: bool = False,
                 eddy_branches: int = 1) -> None:
        if not (hasattr(maps, "dataset") and hasattr(maps, "variable")):
            hint = (" (load a maps file with maglevkit.load_maps first)"
                    if isinstance(maps, (str, bytes)) or hasattr(maps, "__fspath__") else "")
            raise InputError("CurrentModel needs CharacteristicMaps (from build_maps or load_maps), "
                             f"got {type(maps).__name__}{hint}")
        if method not in ("cvodes", "rk4"):
            raise InputError(f"method = {method!r}; use 'cvodes' (adaptive) or 'rk4' (fixed step)")
        if not (math.isfinite(max_step_s) and max_step_s > 0):
            raise InputError(f"max_step_s = {max_step_s!r} must be a finite number > 0")
        self.maps = maps
        # one flag check everywhere: "no" would be truthy (MagnetBank, load_magnet refuse it)
        self.extrapolate = flag(extrapolate, "extrapolate")
        self.method = method
        self.rtol, self.atol = rtol, atol
        self.max_step_s = float(max_step_s)
        self.jit = flag(jit, "jit")
        if lookup not in ("tables", "bspline"):
            raise InputError(f"lookup = {lookup!r}; use 'tables' (compiled cell tables) or "
                             "'bspline' (CasADi interpolants)")
        if compiled not in COMPILE_MODES:
            raise InputError(f"compiled = {compiled!r}; use one of {list(COMPILE_MODES)}")
        self.lookup = lookup
        self.compiled = compiled
        m = check_eddy_modes(eddy_modes)
        # the facts of the maps, derived once (names, pole groups, averaging and share
        # matrices, R_el, eq. 8's R_ec and a, grids, ranges and their allowances); the eddy
        # extensions replace R_ec below
        eq8 = not m and not motion_eddy
        core = ReducedCore.from_maps(maps, eddy_resistance=eddy_resistance if eq8 else "fit")
        #: the reduced circuits' core (:class:`~maglevkit.reduced.core.ReducedCore`)
        self.core = core
        self.circuit_names: tuple[str, ...] = core.circuit_names
        self.gap_names: tuple[str, ...] = core.gap_names
        nc = core.n_circuits
        self._avg = core.averaging           # pole gaps -> substitute gap per circuit
        self._share = core.share             # circuit force -> pole forces, (ng, nc)
        one = np.count_nonzero(self._share, axis=1) == 1
        self._pole_share = ((np.argmax(self._share != 0, axis=1),
                             self._share[np.arange(self._share.shape[0]),
                                         np.argmax(self._share != 0, axis=1)])
                            if one.all() else None)
        self.gap_range = core.gap_range_m
        self.current_range = core.current_range_A
        # rounding allowances of every range check, and the bounds of the state [I_L; s]
        # they give (sub-step check)
        self._tol_s = core.gap_tolerance_m
        self._tol_i = core.current_tolerance_A
        self._lower, self._upper = core.state_bounds()
        r_el = core.resistance_ohm
        self.eddy_modes = m
        if not isinstance(motion_eddy, (bool, np.bool_)):
            raise InputError(f"motion_eddy = {motion_eddy!r}; use False (eq. 8, the default) "
                             "or True (the shielded-gap ladder)")
        #: whether the shielded-gap ladder replaces eq. 8 (:mod:`~maglevkit.reduction.motion_eddy`)
        self.motion_eddy = bool(motion_eddy)
        self.freewheel = flag(freewheel, "freewheel")
        if isinstance(eddy_branches, bool) or eddy_branches not in (1, 2):
            raise InputError(f"eddy_branches = {eddy_branches!r}; use 1 (the two-state ladder) "
                             "or 2 (the three-state ladder), with motion_eddy=True")
        if eddy_branches == 2 and not self.motion_eddy:
            raise InputError("eddy_branches = 2 needs motion_eddy=True (it is the shielded-gap "
                             "ladder's second shielded section)")
        #: shielded sections of the ladder (1: two states per circuit, 2: three)
        self.eddy_branches = int(eddy_branches)
        if self.motion_eddy:
            if m:
                raise InputError(f"motion_eddy=True with eddy_modes={m}: these are two "
                                 "different eddy extensions of eq. 8; use one of them")
            if eddy_resistance is not None:
                raise InputError(f"eddy_resistance = {eddy_resistance!r} chooses eq. 8's single "
                                 "R_ec; with motion_eddy=True the ladder's fitted R_a and R_2 "
                                 "take its place: leave eddy_resistance out")
            ladder = MotionEddyLadder.from_maps(maps, resistance_ohm=r_el)
            r_ec = ladder.jump_resistance_ohm
            r_2, l_u = ladder.shielding_resistance_ohm, ladder.unshielded_inductance_H
            beta = ladder.unshielded_share
            gamma = ladder.force_share
            shares: tuple[np.ndarray, ...] = (gamma,)
            if self.eddy_branches == 2:
                ladder3, ladder3_step = motion_eddy3_parameters(maps, r_el)
                r_ec = ladder3["r_a"]
                shares = (ladder3["c_1"], ladder3["c_2"])
            # the force current's shares, where one is not 0 (then it is range-checked
            # like I_L: the force map is read there)
            self._force_shares = shares if any(np.any(c != 0.0) for c in shares) else None
        elif m:
            if eddy_resistance is not None:
                raise InputError(f"eddy_resistance = {eddy_resistance!r} chooses eq. 8's single "
                                 "R_ec; with eddy_modes > 0 the eddy network's R_0 takes its "
                                 "place: leave eddy_resistance out")
            net, net_step = eddy_network_parameters(maps, m, r_el)
            if self.freewheel:
                check_network_freewheel(net["r_0"], core.circuit_names, f"eddy_modes={m}: ")
            r_ec, r_k, l_k, l_ref = net["r_0"], net["r_k"], net["l_k"], net["l_ref"]
        else:
            r_ec = core.eddy_resistance_ohm
        if not self.motion_eddy:
            self._force_shares = None
        self.resistance_ohm = r_el
        #: ``R_ec`` of eq. 8, the eddy network's ``R_0`` with ``eddy_modes > 0``, the
        #: ladder's shunt ``R_a`` with ``motion_eddy``
        self.eddy_resistance_ohm = r_ec
        a = core.a if eq8 else eq8_a(r_el, r_ec)
        # extra (eddy) states per circuit: the m branch currents, or the ladder's I_e
        n_e = m if m else (self.eddy_branches if self.motion_eddy else 0)
        self._n_e = n_e
        # state [I_L; s; I_ec]: the gap slice and the bounds of the sub-step check
        # (eddy-branch currents are not range-checked)
        self._n_x = (2 + n_e) * nc
        self._sl = slice(nc, 2 * nc)
        if self.motion_eddy:
            self._lower = np.concatenate([self._lower, np.full(nc * n_e, -np.inf)])
            self._upper = np.concatenate([self._upper, np.full(nc * n_e, np.inf)])
            # RK4 stability (MotionEddyLadder.max_step_s, motion_eddy3_parameters)
            self.max_step_s = min(self.max_step_s, ladder.max_step_s
                                  if self.eddy_branches == 1 else ladder3_step)
        if m:
            self._lower = np.concatenate([self._lower, np.full(nc * m, -np.inf)])
            self._upper = np.concatenate([self._upper, np.full(nc * m, np.inf)])
            # RK4 stability (eddy_network_parameters)
            self.max_step_s = min(self.max_step_s, net_step)

        # CasADi's B-spline is 0 outside its grid. The map data are therefore continued
        # linearly (edge slope) by EXTRA_CELLS grid cells on every side before the spline
        # is fitted: the integrator stays well-defined just outside the range, while the
        # range checks on every returned sample still raise (or warn with extrapolate).
        grid_s = core.extended_gaps_m
        grid_i = core.extended_currents_A
        self._spline_range = ((float(grid_s[0]), float(grid_s[-1])),
                              (float(grid_i[0]), float(grid_i[-1])))

        def spline(j: int) -> ca.Function:
            # One spline with three outputs (L~, dL/ds, F) per circuit: the knot search
            # and the basis functions are shared, ~2x cheaper than three splines.
            data = []
            for var in ("inductance_H", "dL_ds_H_per_m", "force_N"):
                values = maps.variable(var, self.circuit_names[j])
                if not np.all(np.isfinite(values)):
                    raise InputError(f"map {var!r} of circuit {self.circuit_names[j]!r} has "
                                     "non-finite values; rebuild the maps")
                data.append(extend_values(extend_values(values, axis=0), axis=1)
                            .ravel(order="F"))
            return ca.interpolant(f"maps_{j}", "bspline", [grid_s, grid_i],
                                  np.stack(data, axis=1).ravel())

        mx_rhs, forces, ltil = [], [], []
        xm, Um, sm, sdm = (ca.MX.sym(n, nc) for n in ("I_L", "U", "s", "sdot"))
        em = ca.MX.sym("I_ec", nc * n_e)
        eddy_rhs, coils = [], []
        for j in range(nc):
            sp = spline(j)
            vals = sp(ca.vertcat(sm[j], xm[j]))
            lt, dl, f = vals[0], vals[1], vals[2]
            if self.motion_eddy and self.eddy_branches == 2:
                # the three-state ladder (eq8_shielded_gap3_rhs); eddy states (I_e1, I_e2)
                e1, e2 = em[2 * j], em[2 * j + 1]
                p3 = {k: float(v[j]) for k, v in ladder3.items()}
                # behind the chopper's diodes with freewheel: eq. 8's diode law of the
                # terminal current I_u = I_L + I_e1 + I_e2 (shielded_gap_freewheel_voltage)
                u_j = (shielded_gap_freewheel_voltage(xm[j] + e1, e2, Um[j], r_el[j], p3["a"])
                       if self.freewheel else Um[j])
                d_il, d_e1, d_e2 = eq8_shielded_gap3_rhs(
                    xm[j], e1, e2, u_j, sdm[j], lt, dl, r_el[j], p3["a"], p3["r_2"],
                    p3["l_u"], p3["r_3"], p3["l_2"], p3["beta"], p3["beta_2"])
                mx_rhs.append(d_il)
                eddy_rhs.append(ca.vertcat(d_e1, d_e2))
                coils.append(eq8_coil_current(xm[j] + e1 + e2, u_j, r_el[j], p3["a"]))
                f = sp(ca.vertcat(sm[j], ladder3_force_current(
                    xm[j] + e1 + e2, xm[j] + e1, xm[j], (p3["c_1"], p3["c_2"]))))[2]
            elif self.motion_eddy:
                # the shielded-gap ladder (module docstring, reduction.motion_eddy), behind
                # the chopper's diodes with freewheel (the bank's law, every RK4 stage)
                u_j = (shielded_gap_freewheel_voltage(xm[j], em[j], Um[j], r_el[j], a[j])
                       if self.freewheel else Um[j])
                d_il, d_ie = eq8_shielded_gap_rhs(xm[j], em[j], u_j, sdm[j], lt, dl, r_el[j],
                                                  a[j], r_2[j], l_u[j], beta[j])
                mx_rhs.append(d_il)
                eddy_rhs.append(d_ie)
                coils.append(eq8_coil_current(xm[j] + em[j], u_j, r_el[j], a[j]))
                if gamma[j] != 0.0:
                    # the force at the force current I_L + gamma I_e (maps without gamma,
                    # or gamma = 0: F(s, I_L) from the lookup above)
                    f = sp(ca.vertcat(sm[j], shielded_gap_force_current(
                        xm[j], em[j], float(gamma[j]))))[2]
            elif m:
                # the eddy network (eddy_network_rhs, eddy_network_coil_current: the law
                # the bank's kernel evaluates too)
                ik = [em[j * m + k] for k in range(m)]
                # behind the chopper's diodes with freewheel: eq. 8's diode law of the
                # terminal current I_L + sum_k I_k (eddy_network_freewheel_voltage)
                u_j = (eddy_network_freewheel_voltage(xm[j], ik, Um[j], r_el[j], a[j])
                       if self.freewheel else Um[j])
                d_il, d_ik = eddy_network_rhs(xm[j], ik, u_j, sdm[j], lt, dl, r_el[j], a[j],
                                              r_k[j], l_k[j], l_ref[j])
                mx_rhs.append(d_il)
                eddy_rhs.append(ca.vertcat(*d_ik))
                coils.append(eddy_network_coil_current(xm[j], ik, u_j, r_el[j], a[j]))
            else:
                u_j = (eq8_freewheel_voltage(xm[j], Um[j], r_el[j], a[j]) if self.freewheel
                       else Um[j])
                mx_rhs.append(eq8_rhs(xm[j], u_j, sdm[j], lt, dl, r_el[j], a[j]))
                coils.append(eq8_coil_current(xm[j], u_j, r_el[j], a[j]))
            forces.append(f)
            ltil.append(lt)
        if n_e:
            self.ode = ca.Function("current_model_ode", [xm, Um, sm, sdm, em],
                                   [ca.vertcat(*mx_rhs), ca.vertcat(*eddy_rhs)],
                                   ["I_L", "U", "s", "sdot", "I_ec"], ["dI_L", "dI_ec"])
            self.outputs_fun = ca.Function("current_model_out", [xm, Um, sm, em],
                                           [ca.vertcat(*coils), ca.vertcat(*forces),
                                            ca.vertcat(*ltil)],
                                           ["I_L", "U", "s", "I_ec"],
                                           ["I", "F", "Ltilde"]).expand()
        else:
            coil = (ca.vertcat(*coils) if self.freewheel
                    else eq8_coil_current(xm, Um, ca.DM(r_el), ca.DM(a)))
            self.ode = ca.Function("current_model_ode", [xm, Um, sm, sdm],
                                   [ca.vertcat(*mx_rhs)], ["I_L", "U", "s", "sdot"], ["dI_L"])
            self.outputs_fun = ca.Function("current_model_out", [xm, Um, sm],
                                           [coil, ca.vertcat(*forces), ca.vertcat(*ltil)],
                                           ["I_L", "U", "s"], ["I", "F", "Ltilde"]).expand()
        # Integrator: states [I_L; s] (and I_ec with eddy modes), controls [U; sdot]
        # piecewise constant.
        X = ca.MX.sym("X", self._n_x)
        Uc = ca.MX.sym("u", 2 * nc)
        if n_e:
            di, de = self.ode(X[:nc], Uc[:nc], X[self._sl], Uc[nc:], X[2 * nc:])
            rhs = ca.vertcat(di, Uc[nc:], de)
        else:
            rhs = ca.vertcat(self.ode(X[:nc], Uc[:nc], X[nc:], Uc[nc:]), Uc[nc:])
        self._rhs = ca.Function("rhs", [X, Uc], [rhs])
        self._dae = {"x": X, "u": Uc, "ode": rhs}
        # One interval of length h in normalised time (CVODES), no cache per step length.
        h = ca.MX.sym("h")
        norm = ca.integrator("current_model_step", "cvodes",
                             {"x": X, "p": ca.vertcat(Uc, h), "ode": h * rhs}, 0.0, 1.0,
                             {"abstol": atol, "reltol": rtol, "max_num_steps": 100000,
                              "show_eval_warnings": False})
        self._cvodes_interval = ca.Function(
            "cvodes_interval", [X, Uc, h], [norm(x0=X, p=ca.vertcat(Uc, h))["xf"]])
        self._integrators: dict[Any, ca.Function] = {}
        self._rk4: dict[tuple[int, int], ca.Function] = {}
        self._fused: dict[int, ca.Function] = {}
        self._step_calls: dict[int, Any] = {}
        self._lin_fun: ca.Function | None = None
        # the table kernel (eq. 8 or the eddy network, RK4): a bank of this one magnet, built
        # on first use
        self._use_tables = (lookup == "tables" and method == "rk4" and not self.jit
                            and not self.motion_eddy)
        #: the shape of the eddy-network state (n_c, m) the table step takes as it is
        self._eddy_dims = (nc, m)
        self._bank: Any = None
        self._table_steps: dict[float, _TableStep] = {}
        self._network_runs: dict[tuple[int, int], _NetworkRun] = {}
        self._input_shapes = ((self.n_circuits,), (len(self.gap_names),))

    # ------------------------------------------------------------------ helpers
    @property
    def n_circuits(self) -> int:
        return len(self.circuit_names)

    @renamed_keywords(gaps="gaps_m")
    def substitute_gaps(self, gaps_m: np.ndarray) -> np.ndarray:
        """Mean gap per circuit [m] from pole gaps (..., n_gaps).

        Old keyword names (``gaps``) are deprecated aliases for one release.

        Parameters
        ----------
        gaps_m : array_like (..., n_gaps)
            Pole gaps [m] in the order of ``gap_names``; leading axes (e.g. time) are kept.
            Not checked (no range or sign check).

        Returns
        -------
        ndarray (..., n_circuits)
            Substitute gap ``s`` of every circuit [m]: the mean of its poles' gaps.
        """
        return np.asarray(gaps_m) @ self._avg.T

    def _pole_forces(self, fc: np.ndarray) -> np.ndarray:
        """Pole forces [N] (n_t, n_gaps) from circuit forces ``fc`` [N] (n_t, n_circuits):
        ``fc @ share.T``, taken as each pole's circuit force times its share (the share
        matrix has one entry per row, so the product adds only exact zeros: the same
        numbers for finite forces, a zero's sign aside, without a BLAS call per run)."""
        if self._pole_share is None:
            return fc @ self._share.T
        col, w = self._pole_share
        return fc[:, col] * w

    def _outs(self, x: Any, u: Any) -> Any:
        """``outputs_fun`` on a full state ``x = [I_L; s(; I_ec)]`` with voltages ``u``."""
        nc = self.n_circuits
        if self._n_e:
            return self.outputs_fun(x[:nc], u, x[self._sl], x[2 * nc:])
        return self.outputs_fun(x[:nc], u, x[nc:])

    def _eddy_shape(self) -> tuple[int, ...]:
        """Shape of ``CurrentModelState.eddy_currents_A``: ``(n_circuits,)`` for the
        two-state ladder (one eddy state per circuit, as ``MagnetBank``), else
        ``(n_circuits, m)`` (the eddy network's ``m`` branches, the three-state ladder's
        ``(I_e1, I_e2)``)."""
        nc = self.n_circuits
        return (nc,) if self.motion_eddy and self._n_e == 1 else (nc, self._n_e)

    def _eddy_state(self, state: CurrentModelState) -> np.ndarray:
        """The eddy-branch currents of ``state`` as a flat vector (empty for eq. 8)."""
        m = self._n_e
        e = state.eddy_currents_A
        if not m:
            if e is not None and np.size(e):
                raise InputError("this state has eddy-branch currents (eddy_currents_A) but "
                                 "the model has eddy_modes=0 and motion_eddy=False; use a "
                                 "state of this model")
            return np.zeros(0)
        if e is None:
            raise InputError(f"the model has {m} eddy state(s) per circuit (eddy_modes="
                             f"{self.eddy_modes}, motion_eddy={self.motion_eddy}) but the "
                             "state has no eddy_currents_A; make it with this model's "
                             "initial_state")
        arr = real_array(e, "eddy_currents_A")
        shape = self._eddy_shape()
        if len(shape) == 1 and arr.shape == (self.n_circuits, 1):
            warnings.warn("eddy_currents_A of shape (n_circuits, 1) for the two-state ladder "
                          "is deprecated: it has shape (n_circuits,), as in MagnetBank "
                          "(docs/reduction.md, \"Gap motion\")", DeprecationWarning,
                          stacklevel=external_stacklevel())
            return arr.ravel()
        if arr.shape != shape:
            raise InputError(f"eddy_currents_A: expected shape {shape} "
                             f"(circuits{'' if len(shape) == 1 else ' x eddy states'}), "
                             f"got {arr.shape}")
        return arr.ravel()

    def _eddy_of(self, x: np.ndarray) -> np.ndarray | None:
        """The eddy-branch currents of a full state vector (:meth:`_eddy_shape`), None for
        eq. 8."""
        if not self._n_e:
            return None
        return np.array(x[2 * self.n_circuits:]).reshape(self._eddy_shape())

    def _check_force_current(self, xs: np.ndarray, t: np.ndarray) -> None:
        """Range check of the ladder's force current (``I_L + gamma I_e``, three states
        ``I_L + c_1 I_e1 + c_2 I_e2``) of the states ``xs`` (n_t, n_x) at the times ``t``:
        the force map is read there, so it must lie in the maps as ``I_L`` does (the same
        error or extrapolation warning, naming the force current).  Nothing to check
        where every share is 0 (the force current is ``I_L``)."""
        if self._force_shares is None:
            return
        nc, ne = self.n_circuits, self._n_e
        il, e = xs[:, :nc], xs[:, 2 * nc:].reshape(-1, nc, ne)
        i_f = (shielded_gap_force_current(il, e[..., 0], self._force_shares[0]) if ne == 1
               else ladder3_force_current(il + e[..., 0] + e[..., 1], il + e[..., 0], il,
                                          self._force_shares))
        self._check_range(xs[:, self._sl], i_f, t, what=STEP_FLAG_MESSAGES["force_current"])

    def _check_range(self, s: np.ndarray, i_l: np.ndarray, t: np.ndarray | None = None, *,
                     where: str | None = None, what: str = "") -> None:
        lo_s, hi_s = self.gap_range
        lo_i, hi_i = self.current_range
        tol_s, tol_i = self._tol_s, self._tol_i
        bad_s = (s < lo_s - tol_s) | (s > hi_s + tol_s)
        bad_i = (i_l < lo_i - tol_i) | (i_l > hi_i + tol_i)
        bad = bad_s | bad_i
        if not bad.any():
            return
        idx = np.argwhere(bad)[0]
        k = int(idx[0]) if bad.ndim > 1 else 0
        j = int(idx[-1])
        if where is None:
            where = STEP_FLAG_MESSAGES["time"] % t[k] if t is not None else ""
        where += what
        row = k if bad.ndim > 1 else 0
        self._out_of_maps(j, float(np.atleast_2d(s)[row, j]), float(np.atleast_2d(i_l)[row, j]),
                          where, inside_extension=bool(np.all(
                              (s >= self._spline_range[0][0]) & (s <= self._spline_range[0][1])
                              & (i_l >= self._spline_range[1][0])
                              & (i_l <= self._spline_range[1][1]))))

    def _out_of_maps(self, j: int, gap_m: float, current_A: float, where: str, *,
                     inside_extension: bool = False) -> None:
        """Circuit ``j`` outside its maps, in the words of every reduced model
        (:data:`~maglevkit.reduced.core.STEP_FLAG_MESSAGES`): an :class:`OutOfRangeError`,
        or with ``extrapolate`` and the point within the maps' linear continuation
        (``inside_extension``) a warning."""
        text = STEP_FLAG_MESSAGES
        (lo_s, hi_s), (lo_i, hi_i) = self.gap_range, self.current_range
        msg = text["out_of_maps"] % (f"circuit {self.circuit_names[j]!r}", where, gap_m,
                                     current_A, lo_s, hi_s, lo_i, hi_i)
        if self.extrapolate:
            if inside_extension:
                warnings.warn("extrapolating the characteristic maps: "
                              + msg.removeprefix("outside the characteristic maps: "),
                              stacklevel=external_stacklevel())
                return
            msg += (f"; linear extrapolation reaches only {EXTRA_CELLS} grid cells beyond the "
                    "maps")
            raise OutOfRangeError(msg + text["advice_extrapolating"])
        raise OutOfRangeError(msg + text["advice_cli"])

    def _check_substeps(self, lo: np.ndarray, hi: np.ndarray, t0: float, t1: float) -> None:
        """Range check of the RK4 sub-step states of one interval from their extremes.

        ``lo``/``hi`` are the element-wise minima/maxima (``[I_L; s]``) over the sub-step
        end states.  The fast path is two vector comparisons (the step is a hot path);
        only a violation builds the message (and warns or raises like the end check).
        """
        if not ((lo < self._lower).any() or (hi > self._upper).any()):
            return
        nc = self.n_circuits
        pts = np.stack([lo, hi])
        # report the extreme sub-step state (gap and current extremes may come from
        # different sub-steps of the interval)
        self._check_range(pts[:, self._sl], pts[:, :nc], np.array([t0, t0]),
                          where=STEP_FLAG_MESSAGES["substep"] % (t0, t1))

    def _integrator(self, grid: tuple[float, ...]) -> ca.Function:
        """CVODES over a relative output grid (one run, no restarts), cached per grid."""
        key = tuple(round(v, 12) for v in grid)
        f = self._integrators.get(key)
        if f is None:
            opts = {"abstol": self.atol, "reltol": self.rtol, "max_num_steps": 100000,
                    "show_eval_warnings": False}
            f = ca.integrator("current_model", "cvodes", self._dae, 0.0, list(grid), opts)
            if len(self._integrators) > 32:
                self._integrators.clear()
            self._integrators[key] = f
        return f

    def _rk4_function(self, substeps: int, intervals: int) -> ca.Function:
        """``intervals`` RK4 intervals (each ``substeps`` sub-steps), compiled, cached.

        ``(x0, u, h) -> (x_end, coil currents, circuit forces, x_min, x_max)`` per
        interval; the outputs are those at the end of each interval with that interval's
        (held) voltages, ``x_min``/``x_max`` the element-wise extremes of the states at
        the ends of its sub-steps (for the range check).
        ``intervals`` is 1 or a power of two (see :meth:`_rk4_run`).
        """
        key = (substeps, intervals)
        f = self._rk4.get(key)
        if f is None:
            if intervals == 1:
                nc = self.n_circuits
                x, u, h = ca.MX.sym("x", self._n_x), ca.MX.sym("u", 2 * nc), ca.MX.sym("h")
                hs = h / substeps
                xk = x
                lo: Any = None
                hi: Any = None
                def rhs(v: Any) -> Any:
                    return self._rhs(v, u)

                for _ in range(substeps):
                    xk = rk4_substep(xk, hs, rhs)
                    # element-wise extremes of the sub-step end states (incl. the last):
                    # the range check covers every RK4 sub-step, not only interval ends
                    lo = xk if lo is None else ca.fmin(lo, xk)
                    hi = xk if hi is None else ca.fmax(hi, xk)
                coil, force, _ = self._outs(xk, u[:nc])
                outs: list[Any] = [xk, coil, force, lo, hi]
                f = ca.Function("rk4_interval", [x, u, h], outs).expand()  # SX: ~2x
                if self.jit:
                    f = _jit_compile(f)
            else:
                f = self._rk4_function(substeps, 1).mapaccum(f"rk4_{intervals}", intervals)
            self._rk4[key] = f
        return f

    def _rk4_run(self, substeps: int, x0: np.ndarray, uu: np.ndarray, h: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """RK4 over ``h.size`` intervals in power-of-two chunks (each chunk one compiled
        call; at most ~log2(n) distinct chunk functions are ever built, so a new run
        length costs no new compilation)."""
        n = h.size
        xs, cs, fs, los, his = [], [], [], [], []
        x, k = x0, 0
        while k < n:
            m = 1 << min((n - k).bit_length() - 1, 12)     # chunks of <= 4096 intervals
            xr, coil, force, lo, hi = self._rk4_function(substeps, m)(
                x, uu[:, k:k + m], h[k:k + m][None, :])
            xr = np.asarray(xr)
            xs.append(xr)
            cs.append(np.asarray(coil))
            fs.append(np.asarray(force))
            los.append(np.asarray(lo))
            his.append(np.asarray(hi))
            x = xr[:, -1]
            k += m
        return np.hstack(xs), np.hstack(cs), np.hstack(fs), np.hstack(los), np.hstack(his)

    def _interval(self, x0: np.ndarray, u: np.ndarray, h: float) -> np.ndarray:
        """Integrate one interval of length ``h`` with held controls ``u``."""
        if self.method == "rk4":
            n = substep_count(h, self.max_step_s)
            return np.asarray(self._rk4_function(n, 1)(x0, u, h)[0]).ravel()
        return np.asarray(self._cvodes_interval(x0, u, h)).ravel()

    def _fused_step(self, h: float) -> ca.Function:
        """One compiled call per step: ``(x0, u, h) -> (x1, coil currents, circuit forces)``."""
        n = substep_count(h, self.max_step_s) if self.method == "rk4" else 0
        if n:
            return self._rk4_function(n, 1)
        f = self._fused.get(n)
        if f is None:
            nc = self.n_circuits
            x, u, hh = ca.MX.sym("x", self._n_x), ca.MX.sym("u", 2 * nc), ca.MX.sym("h")
            xn = self._cvodes_interval(x, u, hh)
            coil, force, _ = self._outs(xn, u[:nc])
            f = ca.Function("current_model_fused_step", [x, u, hh], [xn, coil, force])
            self._fused[n] = f
        return f

    def _step_call(self, h: float) -> Any:
        """The fused step as a low-overhead call (CasADi buffer: ~5 us instead of ~50 us)."""
        key = substep_count(h, self.max_step_s) if self.method == "rk4" else 0
        call = self._step_calls.get(key)
        if call is None:
            call = BoundCall(self._fused_step(h)) if key else _PlainCall(self._fused_step(h))
            self._step_calls[key] = call
        return call

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
                xn = self._interval(x, uu[:, k], float(t[k + 1] - t[k]))
                if not np.all(np.isfinite(xn)):
                    raise RuntimeError("non-finite state")
                x = xn
            except RuntimeError as exc:
                # Retrace this interval in 64 sub-steps, checking the range after each.
                h = float(t[k + 1] - t[k]) / 64
                xs = x
                for m in range(64):
                    try:
                        xs = self._interval(xs, uu[:, k], h)
                    except RuntimeError:
                        break
                    if not np.all(np.isfinite(xs)):
                        break
                    self._check_range(xs[self._sl][None, :], xs[:nc][None, :],
                                      np.array([t[k] + (m + 1) * h]))
                raise SolverError("current-model integration failed", time_s=float(t[k]),
                                  state={"I_L": x[:nc], "s": x[self._sl]},
                                  reason=_last_line(str(exc))) from None
            self._check_range(x[self._sl][None, :], x[:nc][None, :], t[k + 1:k + 2])
            out.append(x)
        return np.array(out).T[:, 1:]

    # ------------------------------------------------------------------ stepping interface
    @renamed_keywords(gaps="gaps_m", currents="currents_A", time="time_s")
    def initial_state(self, *, gaps_m: Any, currents_A: Any, time_s: float = 0.0) -> CurrentModelState:
        """The steady state at ``gaps`` [m] with coil currents ``currents`` [A] (``I_L = I``;
        with eddy modes ``I_k = 0``).

        The old keyword names ``gaps``, ``currents``, ``time`` still work as deprecated aliases (a
        ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        gaps_m : float, array_like (n_gaps,) or mapping
            Pole gaps [m], each > 0: one value for all, one per gap in the order of
            ``gap_names``, or a mapping gap name -> value naming every gap exactly once.
        currents_A : float, array_like (n_circuits,) or mapping
            Coil currents [A], same forms per circuit (``circuit_names``).
        time_s : float, default 0.0
            Time of the state [s], finite.

        Returns
        -------
        CurrentModelState

        Raises
        ------
        InputError
            Wrong count, unknown or missing names, non-finite values, a gap <= 0 or a
            non-finite ``time``.
        OutOfRangeError
            Substitute gaps or currents outside the maps (with ``extrapolate=True`` only
            beyond the extrapolation band; inside it a warning).
        """
        gaps, currents, time = gaps_m, currents_A, time_s
        g = _per_gap(gaps, self.gap_names, positive=True)
        i = per_name_values(currents, self.circuit_names, "currents", "A")
        if not math.isfinite(time):
            raise InputError(f"time = {time!r} must be finite")
        self._check_range(self.substitute_gaps(g)[None, :], i[None, :], np.array([time]))
        if self._n_e:
            # steady state: U_L = 0, so every eddy branch has decayed (I_k = 0)
            return CurrentModelState(float(time), i, g, np.zeros(self._eddy_shape()))
        return CurrentModelState(float(time), i, g)

    @renamed_keywords(voltages="voltages_V")
    def outputs(self, state: CurrentModelState, voltages_V: Any = None) -> CurrentOutputs:
        """Outputs at ``state`` with ``voltages`` [V] applied (default: the steady-state
        voltages ``R_el I_L``, as in :meth:`initial_state`).

        Old keyword names (``voltages``) are deprecated aliases for one release.

        Parameters
        ----------
        state : CurrentModelState
            State of this model (from :meth:`initial_state`, :meth:`step` or a
            simulation's ``final_state``); not range-checked here.
        voltages_V : float, array_like (n_circuits,), mapping or None, default None
            Circuit voltages [V] (one for all, one per circuit, or circuit name -> value);
            they set the coil current ``I = (U - U_L) / R_el``. None: ``R_el I_L``.

        Returns
        -------
        CurrentOutputs
            Coil currents, circuit, pole and total forces at ``state.time_s``.

        Raises
        ------
        InputError
            Voltages of the wrong count or names, or not finite.
        """
        u = (self.resistance_ohm * state.inductor_currents_A if voltages_V is None
             else per_name_values(voltages_V, self.circuit_names, "voltages", "V"))
        x = np.concatenate([state.inductor_currents_A, self.substitute_gaps(state.gaps_m),
                            self._eddy_state(state)])
        coil, fc, _ = (np.asarray(v).ravel() for v in self._outs(x, u))
        return CurrentOutputs(state.time_s, coil, state.inductor_currents_A.copy(), fc,
                              self._share @ fc, float(fc.sum()))

    def linearize(self, *, gap_m: Any, current_A: Any, voltage_V: Any = None,
                  gap_rate_m_per_s: Any = 0.0) -> CurrentModelLinearization:
        """State-space matrices of eq. 8 at an operating point, by CasADi AD (exact).

        Parameters
        ----------
        gap_m : float, sequence or mapping
            Pole gaps [m] (a scalar for all poles).
        current_A : float, sequence or mapping
            Inductor currents ``I_L`` [A] per circuit.
        voltage_V : float, sequence, mapping or None
            Voltages [V]; None (default): the steady-state voltages ``R_el I_L``, which
            make the operating point an equilibrium at zero gap rate.
        gap_rate_m_per_s : float, sequence or mapping
            Pole gap rates [m/s] (default 0).

        Returns
        -------
        CurrentModelLinearization
            ``A``, ``B``, ``E`` (gap and gap-rate inputs per pole) and ``C``/``D`` of the
            circuit forces and coil currents.

        Raises
        ------
        OutOfRangeError
            If the operating point lies outside the maps (or warns with ``extrapolate``).
        """
        g = _per_gap(gap_m, self.gap_names, positive=True)
        il = per_name_values(current_A, self.circuit_names, "current_A", "A")
        u = (self.resistance_ohm * il if voltage_V is None
             else per_name_values(voltage_V, self.circuit_names, "voltage_V", "V"))
        gd = _per_gap(gap_rate_m_per_s, self.gap_names, positive=False)
        s, sd = self.substitute_gaps(g), self.substitute_gaps(gd)
        self._check_range(s[None, :], il[None, :], None)
        f = self._linearization_function()
        args = [il, u, s, sd]
        if self._n_e:
            # the operating point's eddy-branch currents are 0 (they decay at any steady
            # state; away from one the linearisation is about the same I_ec = 0 point)
            args.append(np.zeros(self.n_circuits * self._n_e))
        f_x, a, b, e_s, e_sd, c_f, d_f, c_i, d_i = (np.asarray(v, dtype=float)
                                                    for v in f(*args))
        # substitute gap of circuit j = mean of its poles' gaps: chain rule through _avg
        return CurrentModelLinearization(
            gaps_m=g, inductor_currents_A=il, voltages_V=u, gap_rates_m_per_s=gd,
            state_derivative_A_per_s=f_x.ravel(), A_per_s=a, B_A_per_V_s=b,
            E_gap_A_per_m_s=e_s @ self._avg, E_gap_rate_A_per_m=e_sd @ self._avg,
            C_force_N_per_A=c_f, D_force_gap_N_per_m=d_f @ self._avg, C_current=c_i,
            D_current_A_per_V=d_i, circuit_names=self.circuit_names, gap_names=self.gap_names)

    def _linearization_function(self) -> ca.Function:
        f = self._lin_fun
        if f is None:
            nc = self.n_circuits
            x, u, s, sd = (ca.MX.sym(n, nc) for n in ("I_L", "U", "s", "sdot"))
            ins = [x, u, s, sd]
            if self._n_e:
                e = ca.MX.sym("I_ec", nc * self._n_e)
                ins.append(e)
                di, de = self.ode(x, u, s, sd, e)
                rhs = ca.vertcat(di, de)
                coil, force, _ = self.outputs_fun(x, u, s, e)
                x = ca.vertcat(x, e)     # the state the Jacobians are taken with respect to
            else:
                rhs = self.ode(x, u, s, sd)
                coil, force, _ = self.outputs_fun(x, u, s)
            f = ca.Function("current_model_linearization", ins,
                            [rhs, ca.jacobian(rhs, x), ca.jacobian(rhs, u), ca.jacobian(rhs, s),
                             ca.jacobian(rhs, sd), ca.jacobian(force, x), ca.jacobian(force, s),
                             ca.jacobian(coil, x), ca.jacobian(coil, u)])
            self._lin_fun = f
        return f

    @renamed_keywords(dt="dt_s", voltages="voltages_V", gaps="gaps_m", gap_rates="gap_rates_m_per_s")
    def step(self, state: CurrentModelState, dt_s: float, voltages_V: Any, gaps_m: Any = None,
             gap_rates_m_per_s: Any = 0.0) -> tuple[CurrentModelState, CurrentOutputs]:
        """Advance by ``dt`` [s] with constant voltages [V] and linearly moving gaps.

        Same contract as :meth:`maglevkit.models.flux.FluxModel.step`: ``gaps`` [m] at the
        start of the step (None keeps the state's), ``gap_rates`` [m/s] over the step.

        The old keyword names ``dt``, ``voltages``, ``gaps``, ``gap_rates`` still work as
        deprecated aliases (a ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        state : CurrentModelState
            State at the start of the step.
        dt_s : float
            Step length [s], finite and > 0.
        voltages_V : float, array_like (n_circuits,) or mapping
            Circuit voltages [V], held over the step: one for all, one per circuit in the
            order of ``circuit_names``, or circuit name -> value.
        gaps_m : float, array_like (n_gaps,), mapping or None, default None
            Pole gaps [m] at the start of the step, each > 0 (same forms per gap); None
            keeps ``state.gaps_m``.
        gap_rates_m_per_s : float, array_like (n_gaps,) or mapping, default 0.0
            Gap rates [m/s], constant over the step; the gaps at the end,
            ``gaps + gap_rates * dt``, must stay > 0.

        Returns
        -------
        (CurrentModelState, CurrentOutputs)
            State and outputs at ``state.time_s + dt``.

        Raises
        ------
        InputError
            A bad ``dt``, inputs of the wrong count or names, non-finite values, or gaps
            that are or become <= 0.
        OutOfRangeError
            The substitute gap path or the currents (including RK4 sub-step states) leave
            the maps (see ``extrapolate``).
        """
        if not isinstance(state, CurrentModelState):
            raise InputError(f"state must be a CurrentModelState (from CurrentModel."
                             f"initial_state or step), got {type(state).__name__}")
        if self._use_tables:
            done = self._step_tables(state, dt_s, voltages_V, gaps_m, gap_rates_m_per_s)
            if done is not None:
                return done
        dt, voltages, gaps, gap_rates = dt_s, voltages_V, gaps_m, gap_rates_m_per_s
        dt = check_step(dt)
        u = per_name_values(voltages, self.circuit_names, "voltages", "V")
        g = state.gaps_m if gaps is None else _per_gap(gaps, self.gap_names, positive=True)
        gd = _per_gap(gap_rates, self.gap_names, positive=False)
        if (g + gd * dt <= 0.0).any():
            raise InputError(f"gaps must stay > 0 m over the step: end {(g + gd * dt).tolist()} m")
        s0, sd = self.substitute_gaps(g), self.substitute_gaps(gd)
        # the gap moves linearly: its whole path is known before integrating, so a step
        # far outside the maps is refused here (not as a non-finite integration later)
        s1 = s0 + sd * dt
        i_now = state.inductor_currents_A
        over = STEP_FLAG_MESSAGES["step"] % (state.time_s, state.time_s + dt)
        self._check_range(np.minimum(s0, s1)[None, :], i_now[None, :], None, where=over)
        self._check_range(np.maximum(s0, s1)[None, :], i_now[None, :], None, where=over)
        x0 = (np.concatenate([i_now, s0, self._eddy_state(state)]) if self._n_e
              else np.concatenate([i_now, s0]))
        uu = np.concatenate([u, sd])
        nc = self.n_circuits
        extremes = None
        try:
            res = self._step_call(float(dt))(x0, uu, float(dt))
            x, coil, fc = res[0], res[1], res[2]
            if len(res) == 5:
                extremes = (res[3], res[4])
            if not np.isfinite(x).all():
                raise RuntimeError("non-finite state")
        except RuntimeError as exc:
            x = self._integrate_stepwise(np.array([state.time_s, state.time_s + dt]), x0,
                                         uu[:, None], str(exc))[:, -1]
            coil, fc, _ = (np.asarray(v).ravel() for v in self._outs(x, u))
        t1 = state.time_s + float(dt)
        if extremes is not None:
            # the sub-step extremes include the end state: one check covers both
            self._check_substeps(extremes[0], extremes[1], state.time_s, t1)
        else:
            self._check_range(x[self._sl][None, :], x[:nc][None, :], np.array([t1]))
        self._check_force_current(x[None, :], np.array([t1]))
        new = CurrentModelState(t1, x[:nc], g + gd * dt, self._eddy_of(x))   # None for eq. 8
        return new, CurrentOutputs(t1, coil, x[:nc].copy(), fc, self._share @ fc, float(fc.sum()))

    # ------------------------------------------------------------------ table kernel
    def _table_bank(self) -> Any:
        """The bank of this one magnet whose compiled step and time loop the table path
        runs (built on first use; its tables hold the same bicubic maps)."""
        if self._bank is None:
            from .bank import MagnetBank  # the bank builds on this module

            try:
                self._bank = MagnetBank({"magnet": self}, compiled=self.compiled,
                                        max_step_s=self.max_step_s, freewheel=self.freewheel)
            except InputError:
                # maps the cell tables cannot hold (a grid that is not regular, or shorter
                # than 4 points): the B-splines take them, as before
                self._use_tables = False
                return None
        return self._bank

    def _run_tables(self, times: np.ndarray, s: np.ndarray, u: np.ndarray, sd: np.ndarray,
                    i0: np.ndarray, e0: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None] | None:
        """``I_L``, coil currents and circuit forces (n_t, n_c) and the eddy-network branch
        currents (n_t, n_c, m; None for eq. 8) on the grid from the compiled time loop; a
        flagged step raises from its reason codes (:meth:`_raise_from_codes`), or where
        that leaves it to the B-spline path (and for a flagged step 0, the start itself)
        None: then the B-spline path runs.

        Step 0 has length 0: it gives the outputs at ``t_0`` with ``u[0]``; step ``k``
        runs from ``t_k-1`` with the substitute gap ``s[k-1]``, its rate and ``u[k-1]``.
        ``e0``: the branch currents at the start, row-major (n_c, m) flattened.
        """
        bank = self._table_bank()
        if bank is None:
            return None
        n = times.size
        h = np.empty(n)
        h[0] = 0.0
        np.subtract(times[1:], times[:-1], out=h[1:])
        # the step inputs: step 0 (length 0) with the first sample, step k with sample k - 1
        s_k, u_k, sd_k = np.empty(s.shape), np.empty(u.shape), np.empty(s.shape)
        s_k[0], s_k[1:] = s[0], s[:-1]
        u_k[0], u_k[1:] = u[0], u[:-1]
        sd_k[0], sd_k[1:] = 0.0, sd
        if self._n_e:
            if int(np.max(substep_counts(h, self.max_step_s))) > _NETWORK_MAX_SUBSTEPS:
                # the network's loop unrolls its sub-steps in C: steps of many sub-steps
                # would compile for minutes (500 sub-steps: a 32 MB source); the B-splines
                # take them
                return None
            il, coil, fc, eddy, n_good = self._run_network(i0, e0, s_k, u_k, sd_k, h)
        else:
            run = bank.run_steps(i0, s_k, u_k, sd_k, h, time_s=float(times[0]),
                                 stop_at_flag=True)
            il, coil, fc, eddy, n_good = (run.inductor_currents_A, run.currents_A,
                                          run.circuit_force_N, None, run.n_good)
        if n_good < times.size:
            j = n_good
            if j > 0 and not self.extrapolate:
                # the flagged step's reason codes from the same compiled step (step j from
                # t_j-1 with the state the loop reached), read as step() reads them; step 0
                # (the start itself) and what they leave to it go to the B-spline path
                ins = {"I_L": il[j - 1], "s": s_k[j], "U": u_k[j], "sdot": sd_k[j],
                       "h": float(h[j])}
                kernel = bank.step_kernel(float(h[j]))
                if eddy is not None:          # (n_c, m), or its column-major vec
                    ins["I_e"] = np.reshape(eddy[j - 1], kernel.size_in("I_e"), order="F")
                res = kernel.call(ins)
                lo, hi = (np.asarray(res[k], dtype=float).ravel() for k in ("I_L_min", "I_L_max"))
                self._raise_from_codes(np.asarray(res["flags"]).ravel(), s_k[j], sd_k[j],
                                       il[j - 1], u_k[j], lo, hi,
                                       float(times[j - 1]), float(times[j]))
            return None
        return il, coil, fc, eddy

    def _run_network(self, i0: np.ndarray, e0: np.ndarray, s: np.ndarray, u: np.ndarray,
                     sd: np.ndarray, h: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
        """The time loop of the table path with eddy-network branches (the bank's
        ``run_steps`` carries ``I_L`` only): the bank's compiled step in a CasADi
        ``mapaccum`` over up to :data:`~maglevkit.reduced.bank.RUN_CHUNK` steps of one RK4
        sub-step count, compiled as C linked against the lane library where there is one.

        Inputs as ``run_steps`` (``e0`` the branch currents, row-major (n_c, m)); returns
        ``I_L``, coil currents, circuit forces (n_steps, n_c), branch currents
        (n_steps, n_c, m) and the count of steps before the first flagged one (the rows
        from there on are not meaningful).
        """
        from .bank import RUN_CHUNK  # the bank builds on this module

        nc, m = self.n_circuits, self._n_e
        n = h.size
        il, coil, fc = (np.full((n, nc), np.nan) for _ in range(3))
        eddy = np.full((n, nc, m), np.nan)
        per = substep_counts(h, self.max_step_s)
        if n > 1 and h[0] == 0.0:
            # a step of 0 s changes nothing with any sub-step count: the next one's keeps
            # it in the same loop (:meth:`_run_tables`' step 0)
            per[0] = per[1]
        # the loop's state: I_L, then the branch currents column-major ((n_c, m) as CasADi)
        x = np.concatenate([i0, e0.reshape(nc, m).T.ravel()])
        k = 0
        while k < n:
            other = np.flatnonzero(per[k:k + RUN_CHUNK] != per[k])
            c = int(other[0]) if other.size else min(RUN_CHUNK, n - k)
            # two loop lengths (short runs and the rest), padded with steps of 0 s at the
            # end gap (they change nothing)
            chunk = _NETWORK_SHORT if c <= _NETWORK_SHORT else RUN_CHUNK
            run = self._network_runs.get((int(per[k]), chunk))
            if run is None:
                run = self._network_run(int(per[k]), chunk)
            run.x0[:] = x
            run.s[:c], run.u[:c], run.sd[:c], run.h[:c] = (s[k:k + c], u[k:k + c],
                                                            sd[k:k + c], h[k:k + c])
            if c < chunk:
                run.s[c:] = s[k + c - 1] + sd[k + c - 1] * h[k + c - 1]
                run.u[c:] = u[k + c - 1]
                run.sd[c:] = 0.0
                run.h[c:] = 0.0
            run.eval()
            bad = np.flatnonzero(run.bad[:c])
            done = int(bad[0]) if bad.size else c
            xs = run.x[:c]
            il[k:k + done] = xs[:done, :nc]
            eddy[k:k + done] = xs[:done, nc:].reshape(done, m, nc).transpose(0, 2, 1)
            coil[k:k + done] = run.coil[:done]
            fc[k:k + done] = run.force[:done]
            if done < c:
                return il, coil, fc, eddy, k + done
            k += c
            x = xs[c - 1].copy()
        return il, coil, fc, eddy, n

    def _network_run(self, substeps: int, chunk: int) -> _NetworkRun:
        """The loop of ``chunk`` steps of :meth:`_run_network` for steps of ``substeps`` RK4
        sub-steps (built, compiled and kept on first use)."""
        bank = self._table_bank()
        nc, m = self.n_circuits, self._n_e
        dt = self.max_step_s * substeps              # a step of this sub-step count
        lanes = bank.compiled_step_library(dt)
        kernel = bank.step_kernel(dt) if lanes is None else lanes[0]
        x = ca.MX.sym("x", nc * (1 + m))
        sk, uk, sdk = (ca.MX.sym(v, nc) for v in ("s", "U", "sdot"))
        hk = ca.MX.sym("h")
        res = kernel.call({"I_L": x[:nc], "s": sk, "U": uk, "sdot": sdk, "h": hk,
                           "I_e": ca.reshape(x[nc:], kernel.size_in("I_e"))})
        step = ca.Function(f"maglevkit_cm_net_{kernel.name()}", [x, sk, uk, sdk, hk],
                           [ca.vertcat(res["I_L_next"], ca.vec(res["I_e_next"])), res["I"],
                            res["F"], res["n_bad"]])
        run = step.mapaccum(f"maglevkit_cm_netrun{chunk}_{kernel.name()}", chunk)
        if lanes is not None:
            # the same operations as generated C, no contraction (as _TableStep._compile)
            linked = compile_linked(run, lanes[1], flags=(*DEFAULT_FLAGS, "-ffp-contract=off"))
            if linked is not None:
                run = linked
        call = _NetworkRun(run, chunk, nc, nc * (1 + m))
        self._network_runs[(substeps, chunk)] = call
        return call

    def _step_tables(self, state: CurrentModelState, dt: Any, voltages: Any, gaps: Any,
                     gap_rates: Any) -> tuple[CurrentModelState, CurrentOutputs] | None:
        """:meth:`step` on the compiled table kernel, or None (the caller then takes the
        B-spline path, which validates, raises or warns): inputs other than finite
        float arrays of the right shape are converted first; a step the kernel flags
        (out of the maps, not finite) or gaps that are or become <= 0 give None.

        The hot path of a stepping loop: the checks are ordered by cost and the common
        case (a float ``dt`` seen before, float64 arrays of the right shape) takes only
        identity and shape tests; every other input goes through the same converters as
        before, with the same messages.
        """
        e = state.eddy_currents_A
        if self._n_e:
            # the eddy-network branch currents (n_c, m): as they are when float64 of that
            # shape, else through the B-spline path's converter (its messages)
            if not (type(e) is _NDARRAY and e.dtype is _F64 and e.shape == self._eddy_dims):
                e = self._eddy_state(state)
        elif e is not None:
            return None                        # not a state of this model: say so there
        if type(dt) is float and 0.0 < dt < math.inf:
            call = self._table_steps.get(dt)
        else:
            dt = check_step(dt)
            call = None
        shape_c, shape_g = self._input_shapes
        # ``dtype is`` float64's (native) singleton; an equal dtype that is not it (or any
        # other input) takes the converter, which returns a float64 array as it is
        u = (voltages if type(voltages) is _NDARRAY and voltages.dtype is _F64
             and voltages.shape == shape_c
             else per_name_values(voltages, self.circuit_names, "voltages", "V"))
        if gaps is None:
            g = state.gaps_m
        elif type(gaps) is _NDARRAY and gaps.dtype is _F64 and gaps.shape == shape_g:
            g = gaps
        else:
            g = _per_gap(gaps, self.gap_names, positive=True)
        if type(gap_rates) is _NDARRAY and gap_rates.dtype is _F64 and \
                gap_rates.shape == shape_g:
            gd = gap_rates
        elif type(gap_rates) is float:
            gd = np.full(shape_g, gap_rates)
        else:
            gd = _per_gap(gap_rates, self.gap_names, positive=False)
        if call is None:
            call = self._table_step(dt)
            if call is None:
                return None
        done = call(state.inductor_currents_A, g, u, gd, state.time_s + dt, e)
        if done is None:
            self._diagnose_table_step(call, state, g, u, gd, dt)
        return done            # None: the B-spline path raises, warns or integrates

    def _table_step(self, dt: float) -> _TableStep | None:
        """The compiled step of length ``dt`` [s] (built, or loaded from the disk cache,
        on first use and kept per length), or None where the tables cannot hold the maps."""
        call = self._table_steps.get(dt)
        if call is None:
            bank = self._table_bank()
            if bank is None:
                return None
            lanes = bank.compiled_step_library(dt)
            call = (_TableStep(bank.step_kernel(dt), self._avg, self._share, dt,
                               n_eddy=self._n_e)
                    if lanes is None
                    else _TableStep(lanes[0], self._avg, self._share, dt, lanes[1],
                                    n_eddy=self._n_e))
            if len(self._table_steps) > 16:
                self._table_steps.clear()
            self._table_steps[dt] = call
        return call

    def _diagnose_table_step(self, call: _TableStep, state: CurrentModelState, g: np.ndarray,
                             u: np.ndarray, gd: np.ndarray, dt: float) -> None:
        """A flagged table step of :meth:`step`: :meth:`_raise_from_codes` on its kernel's
        reason codes, except for pole gaps that are or become <= 0 (the kernel sees only
        substitute gaps; the B-spline path gives the per-gap message)."""
        if (g <= 0.0).any() or (g + gd * dt <= 0.0).any():
            return
        self._raise_from_codes(call.codes, self._avg @ g, self._avg @ gd,
                               state.inductor_currents_A, u, call.current_min.copy(),
                               call.current_max.copy(), state.time_s, state.time_s + dt)

    def _raise_from_codes(self, codes: np.ndarray, s: np.ndarray, sd: np.ndarray,
                          i0: np.ndarray, u: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                          t0: float, t1: float) -> None:
        """A step the table kernel flagged: its reason codes (:class:`StepFlag`) turned into
        the error by :func:`~maglevkit.reduced.core.diagnose_flags`, the one reading of
        them (no range check of its own).  Returns (for the B-spline path to take the
        step or run) where that path does more than raise: extrapolating, and a non-finite
        result (its step-wise integration)."""
        codes = np.asarray(codes, dtype=float).astype(int)
        first = int(np.bitwise_or.reduce(codes))
        if (self.extrapolate or not first
                or (first & StepFlag.RESULT_NOT_FINITE
                    and not first & (StepFlag.INPUT_NOT_FINITE | StepFlag.GAP_OUT_OF_RANGE))):
            return
        tol_s, tol_i = self._tol_s, self._tol_i
        (lo_s, _), (lo_i, hi_i) = self.gap_range, self.current_range
        nc = self.n_circuits
        diagnose_flags(codes, self.circuit_names, gaps_m=s, gap_rates_m_per_s=sd,
                       currents_A=i0, voltages_V=u, substep_min_A=lo, substep_max_A=hi,
                       current_min_A=np.full(nc, lo_i - tol_i),
                       current_max_A=np.full(nc, hi_i + tol_i),
                       gap_min_m=np.full(nc, lo_s - tol_s), t0_s=t0, t1_s=t1,
                       out_of_maps=self._out_of_maps)

    def _integrate(self, t: np.ndarray, x0: np.ndarray, uu: np.ndarray
                   ) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray] | None]:
        """States (n_t, n_x) on the grid ``t`` (``n_x = 2 n_c``, plus ``n_c m`` with eddy
        modes); controls ``uu`` (2 n_c, n_t - 1).

        With RK4 also the outputs (coil currents, circuit forces), each (n_c, n_t - 1), at
        the ends of the intervals with their held voltages; else None.
        """
        outs = None
        extremes = None
        try:
            if self.method == "rk4":
                h = np.diff(t)
                n = substep_count(float(h.max()), self.max_step_s)
                xf, coil, force, lo, hi = self._rk4_run(n, x0, uu, h)
                if not np.isfinite(xf).all():
                    raise RuntimeError("non-finite state in the RK4 integration")
                outs = (coil, force)
                extremes = (lo, hi)
            else:
                f = self._integrator(tuple(float(v) for v in (t[1:] - t[0])))
                xf = np.asarray(f(x0=x0, u=uu)["xf"])
        except RuntimeError as exc:
            xf = self._integrate_stepwise(t, x0, uu, str(exc))
            outs = None
            extremes = None
        xs = np.concatenate([x0[:, None], xf], axis=1).T
        nc = self.n_circuits
        self._check_range(xs[:, self._sl], xs[:, :nc], t)
        self._check_force_current(xs, t)
        if extremes is not None:
            lo, hi = extremes
            bad = (lo < self._lower[:, None]) | (hi > self._upper[:, None])
            k = int(np.argmax(bad.any(axis=0))) if bad.any() else None
            if k is not None:
                self._check_substeps(lo[:, k], hi[:, k], float(t[k]), float(t[k + 1]))
        return xs, outs

    @renamed_keywords(t="times_s", gaps="gaps_m", voltages="voltages_V",
                      gap_rates="gap_rates_m_per_s", dt="dt_s",
                      initial_currents="initial_currents_A")
    def simulate(self, times_s: Any, *, gaps_m: Any, voltages_V: Any, gap_rates_m_per_s: Any = None,
                 dt_s: float | None = None, initial_currents_A: Any = None,
                 initial_state: CurrentModelState | None = None,
                 gap_rate_tolerance: float = 0.02) -> ReducedSimulation:
        """Simulate on a time grid; same inputs and conventions as :func:`maglevkit.simulate`.

        Gaps move linearly between samples, voltages are held from each sample to the
        next; the default initial state is the steady state ``I = U(t0) / R_el``.

        The old keyword names ``t``, ``gaps``, ``voltages``, ``gap_rates``, ``dt``,
        ``initial_currents`` still work as deprecated aliases (a ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        times_s : (t0, tf), [t0, tf] or array_like
            A time span [s] (sampled with ``dt``) or an explicit strictly increasing grid [s].
        gaps_m : float, sequence, mapping, Signal, callable or array
            Pole gaps [m], > 0 at every sample (constant, per gap, gap name -> value, a
            function of time [s] or an array (n_t, n_gaps) on the grid).
        voltages_V : same forms as ``gaps``
            Circuit voltages [V], one per circuit; zero-order hold on each interval.
        gap_rates_m_per_s : same forms as ``gaps``, optional
            Gap rates [m/s]; only checked against the secants of the sampled gaps (the
            secants drive the model). None: no check.
        dt_s : float, optional
            Grid step [s] of a time span (None: 1e-4 s, or ``tf - t0`` if shorter); must
            be None with an explicit grid.
        initial_currents_A : float, array_like (n_circuits,) or mapping, optional
            Start from the steady state with these coil currents [A] instead of
            ``U(t0) / R_el``. Not together with ``initial_state``.
        initial_state : CurrentModelState, optional
            Start from this state (e.g. a previous run's ``final_state``); its gaps are not
            used (the ``gaps`` input gives them). Not together with ``initial_currents``.
        gap_rate_tolerance : float, default 0.02
            Allowed disagreement of ``gap_rates`` with the gap secants [-], relative to the
            largest rate (plus 1 um/s), >= 0.

        Returns
        -------
        ReducedSimulation

        Raises
        ------
        InputError
            Bad grid (or ``dt`` with an explicit grid), inputs of the wrong shape or
            names, non-finite values, gaps <= 0, gap rates that disagree with the gaps, or
            both initial choices given.
        OutOfRangeError
            Substitute gaps or currents leave the maps during the run (see ``extrapolate``).
        """
        gaps, voltages, gap_rates, dt = gaps_m, voltages_V, gap_rates_m_per_s, dt_s
        initial_currents = initial_currents_A
        times, g, u, secant = simulation_inputs(
            times_s, dt, gaps=gaps, voltages=voltages, gap_rates=gap_rates, gap_names=self.gap_names,
            circuit_names=self.circuit_names, gap_rate_tolerance=gap_rate_tolerance)
        check_initial_choice(initial_state, initial_currents, CurrentModelState)
        if initial_state is not None:
            i0 = initial_state.inductor_currents_A
            e0 = self._eddy_state(initial_state)
        else:
            i0 = per_name_values(u[0] / self.resistance_ohm if initial_currents is None
                                 else initial_currents, self.circuit_names, "initial_currents",
                                 "A")
            e0 = np.zeros(self.n_circuits * self._n_e)    # steady state: I_k = 0
        s = np.asarray(g) @ self._avg.T                 # substitute gaps (substitute_gaps)
        sd = np.asarray(secant) @ self._avg.T
        # the table kernel flags every step whose gap path or currents leave the maps (the
        # same bounds with the same allowances as the check below), so a run it finishes
        # needs no check of its own; a flagged run takes the checked B-spline path
        run = self._run_tables(times, s, u, sd, i0, e0) if self._use_tables else None
        if run is None:
            self._check_range(s, np.broadcast_to(i0, s.shape), times)
        else:
            il, coil_t, fc, ed = run
            final = _new(CurrentModelState, time_s=float(times[-1]),
                         inductor_currents_A=il[-1].copy(), gaps_m=g[-1].copy(),
                         eddy_currents_A=None if ed is None else ed[-1].copy())
            rates = np.empty(g.shape)
            rates[:-1] = secant
            rates[-1] = secant[-1]
            held = u.copy()
            held[-1] = u[-2]
            return _new(
                ReducedSimulation, time_s=times, gaps_m=g, gap_rates_m_per_s=rates,
                voltages_V=held, currents_A=coil_t, inductor_currents_A=il,
                circuit_force_N=fc, pole_force_N=self._pole_forces(fc), force_N=row_sums(fc),
                gap_names=self.gap_names, circuit_names=self.circuit_names,
                final_state=final, eddy_currents_A=ed)
        xs, outs = self._integrate(times, np.concatenate([i0, s[0], e0]),
                                   np.concatenate([u[:-1], sd], axis=1).T)
        nc = self.n_circuits
        il = xs[:, :nc]
        # outputs at t_k with the left-limit voltage (that of [t_k-1, t_k)); u[0] at t_0
        c0, f0, _ = self._outs(xs[0], u[0])
        if outs is None:
            held = u[:-1].T
            rest = [xs[1:, 2 * nc:].T] if self._n_e else []
            c1, f1, _ = self.outputs_fun.map(times.size - 1)(il[1:].T, held,
                                                             xs[1:, self._sl].T, *rest)
            outs = (np.asarray(c1), np.asarray(f1))
        coil = np.concatenate([np.asarray(c0), outs[0]], axis=1)
        fc = np.concatenate([np.asarray(f0), outs[1]], axis=1).T
        eddy = (xs[:, 2 * nc:].reshape(times.size, *self._eddy_shape()) if self._n_e
                else None)
        final = CurrentModelState(float(times[-1]), il[-1].copy(), g[-1].copy(),
                                  None if eddy is None else eddy[-1].copy())
        return ReducedSimulation(
            time_s=times, gaps_m=g, gap_rates_m_per_s=np.vstack((secant, secant[-1:])),
            voltages_V=np.vstack((u[:-1], u[-2:-1])), currents_A=coil.T,
            inductor_currents_A=il, circuit_force_N=fc, pole_force_N=fc @ self._share.T,
            force_N=fc.sum(axis=1), gap_names=self.gap_names, circuit_names=self.circuit_names,
            final_state=final, eddy_currents_A=eddy)


def row_sums(a: np.ndarray) -> np.ndarray:
    """``a.sum(axis=1)`` of a 2-D float array, bit for bit, without the cost of NumPy's
    reduction over a short last axis (~12 us for (1001, 2)): for fewer than 8 columns
    NumPy adds them in order from the first, which is what this does (more columns: NumPy
    itself, whose pairwise blocks differ).

    Parameters
    ----------
    a : numpy.ndarray (n, m)
        Any unit.

    Returns
    -------
    numpy.ndarray (n,)
        Row sums, in the unit of ``a``.
    """
    m = a.shape[1]
    if m == 0 or m >= 8:
        return a.sum(axis=1)
    out = a[:, 0].copy()
    for j in range(1, m):
        out += a[:, j]
    return out


def _jit_compile(f: ca.Function) -> ca.Function:
    """``f`` (SX) compiled to machine code by CasADi's JIT through the system C compiler."""
    xs = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    opts: dict[str, Any] = {"jit": True, "compiler": "shell",
                            "jit_options": {"flags": ["-O3"], "verbose": False}}
    try:
        return ca.Function(f.name() + "_jit", xs, list(f(*xs)), opts)
    except RuntimeError as exc:
        raise SolverError("JIT compilation of the current model failed (jit=True needs a C "
                          "compiler such as gcc on the PATH; use jit=False otherwise)",
                          reason=_last_line(str(exc))) from None


class _TableStep:
    """One step of one length on the bank's compiled table kernel with everything around
    it in one CasADi call through bound NumPy buffers: substitute gaps and rates from the
    pole values (``avg``), the end gaps, the pole forces (``share``), the total force and
    one flag (the kernel's, plus pole gaps that are or become <= 0).

    ``(I_L, pole gaps, U, pole gap rates, end time)`` -> the new
    :class:`CurrentModelState` and :class:`CurrentOutputs` (their arrays views of one
    new block), or None when the step is flagged.  The step length ``h_s`` [s] is an
    input of the function, written once: a ``_TableStep`` is kept per length.
    """

    def __init__(self, kernel: ca.Function, avg: np.ndarray, share: np.ndarray, h_s: float,
                 library: Path | None = None, n_eddy: int = 0) -> None:
        nc, ng = avg.shape
        x, u = ca.MX.sym("I_L", nc), ca.MX.sym("U", nc)
        g, gd, h = ca.MX.sym("gaps", ng), ca.MX.sym("gap_rates", ng), ca.MX.sym("h")
        ins = {"I_L": x, "s": ca.mtimes(ca.DM(avg), g), "U": u,
               "sdot": ca.mtimes(ca.DM(avg), gd), "h": h}
        # eddy-network branch currents (n_eddy per circuit): an (m, n_c) input and output
        # here, whose column-major nonzeros are the row-major (n_c, m) array of
        # CurrentModelState.eddy_currents_A; the bank's kernel takes them as (n_c, m)
        e = ca.MX.sym("I_e", n_eddy, nc) if n_eddy else None
        if e is not None:
            ins["I_e"] = ca.reshape(e.T, kernel.size_in("I_e"))   # (n_c, m), or its vec
        res = kernel.call(ins)
        g1 = g + gd * h
        flag = res["n_bad"] + ca.sum1(g <= 0) + ca.sum1(g1 <= 0)
        force = res["F"]
        # the block of results, the flag, and for a flagged step the kernel's reason codes
        # and sub-step current extremes
        block = [res["I_L_next"], res["I"], force, ca.mtimes(ca.DM(share), force),
                 res["member_F"], g1, res["I_L_next"]]
        if e is not None:
            block.append(ca.reshape(res["I_e_next"], nc, n_eddy).T)
        outs = block + [flag, res["flags"], res["I_L_min"], res["I_L_max"]]
        f = ca.Function(f"maglevkit_cm_{kernel.name()}", [x, g, u, gd, h]
                        + ([e] if e is not None else []), outs)
        self.function, self.library, self.h_s = f, library, h_s
        self.n_eddy = n_eddy
        sizes = [f.nnz_out(i) for i in range(len(block))]
        self.block = np.zeros(sum(sizes))
        ends = np.cumsum([0, *sizes])
        self.slices = [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:], strict=True)]
        #: where in the block the total force is (one value)
        self.total_at = int(ends[4])
        self.flag = np.zeros(1)
        #: the kernel's reason codes (StepFlag bits) and the smallest and largest ``I_L``
        #: over the sub-steps of the last call, per circuit
        self.codes, self.current_min, self.current_max = (np.zeros(nc) for _ in range(3))
        self._bind(f)
        if library is not None:
            # compiled at once, on the first step of this length: that call builds (or
            # loads) the lane library anyway, so no later step pauses for the compiler
            self._compile()

    def _bind(self, f: ca.Function) -> None:
        bind = {i: self.block[sl] for i, sl in enumerate(self.slices)}
        n = len(self.slices)
        bind[n], bind[n + 1], bind[n + 2], bind[n + 3] = (self.flag, self.codes,
                                                          self.current_min, self.current_max)
        self.bound = BoundCall(f, res=bind)
        self.args = self.bound.args
        self.args[4][0] = self.h_s               # the step length: once per binding
        self.inputs = tuple(self.args[:4])
        self.eddy_input = self.args[5] if self.n_eddy else None
        self.eval = self.bound.eval

    def _compile(self) -> None:
        """This function as generated C linked against the lane library that holds the
        kernel (CasADi's virtual machine spends three times the kernel's own time calling
        it); the same operations, no contraction (bit-identical, tested)."""
        assert self.library is not None
        f = compile_linked(self.function, self.library,
                           flags=(*DEFAULT_FLAGS, "-ffp-contract=off"))
        if f is not None:                  # else (e.g. a linker without these options) as it is
            self._bind(f)

    def __call__(self, i: np.ndarray, g: np.ndarray, u: np.ndarray, gd: np.ndarray,
                 t1_s: float, eddy: np.ndarray | None = None
                 ) -> tuple[CurrentModelState, CurrentOutputs] | None:
        a0, a1, a2, a3 = self.inputs
        a0[:] = i
        a1[:] = g
        a2[:] = u
        a3[:] = gd
        if self.eddy_input is not None:
            self.eddy_input[:] = eddy.ravel()        # type: ignore[union-attr]
        self.eval()
        if self.flag[0]:
            return None
        b = self.block.copy()
        s0, s1, s2, s3, _, s5, s6 = self.slices[:7]
        # both frozen dataclasses filled without their generated __init__ (one
        # object.__setattr__ per field): equal to CurrentModelState(t1_s, ...) and as frozen
        state = _new_object(CurrentModelState)
        d = state.__dict__
        d["time_s"] = t1_s
        d["inductor_currents_A"] = b[s0]
        d["gaps_m"] = b[s5]
        d["eddy_currents_A"] = (b[self.slices[7]].reshape(-1, self.n_eddy) if self.n_eddy
                                else None)
        out = _new_object(CurrentOutputs)
        d = out.__dict__
        d["time_s"] = t1_s
        d["currents_A"] = b[s1]
        d["inductor_currents_A"] = b[s6]
        d["circuit_force_N"] = b[s2]
        d["pole_force_N"] = b[s3]
        d["force_N"] = b.item(self.total_at)
        return state, out


class _NetworkRun:
    """The eddy-network time loop of :meth:`CurrentModel._run_network` (``chunk`` steps)
    through bound NumPy buffers: the state ``x0`` (``I_L``, then the branch currents
    column-major), the step inputs ``s``, ``u``, ``sd`` (chunk, n_c) and ``h`` (chunk,);
    after :attr:`eval` the states ``x`` (chunk, n_x), coil currents ``coil`` and circuit
    forces ``force`` (chunk, n_c) after each step and the kernel's flag count ``bad``
    per step.  The (n_c, chunk) matrices of the loop are the row-major (chunk, n_c)
    arrays (CasADi's column-major nonzeros)."""

    def __init__(self, f: ca.Function, chunk: int, nc: int, nx: int) -> None:
        self.bound = BoundCall(f)
        self.eval = self.bound.eval
        a, r = self.bound.args, self.bound.res
        self.x0, self.h, self.bad = a[0], a[4], r[3]
        self.s, self.u, self.sd = (a[i].reshape(chunk, nc) for i in (1, 2, 3))
        self.x = r[0].reshape(chunk, nx)
        self.coil, self.force = (r[i].reshape(chunk, nc) for i in (1, 2))


#: steps of the short eddy-network loop (runs of at most this many steps; longer ones
#: take the bank's RUN_CHUNK)
_NETWORK_SHORT = 64
#: the most RK4 sub-steps per step that the eddy network's compiled time loop takes (more:
#: the B-spline path; each sub-step is unrolled in the loop's C source)
_NETWORK_MAX_SUBSTEPS = 16
_T = TypeVar("_T")
_F64 = np.dtype(np.float64)
_NDARRAY = np.ndarray
_new_object = object.__new__


def _new(cls: type[_T], **fields: Any) -> _T:
    """A frozen dataclass instance with every field given, without the per-field
    ``object.__setattr__`` of its generated ``__init__``; equal to ``cls(**fields)`` and
    as frozen."""
    obj = object.__new__(cls)
    obj.__dict__.update(fields)
    return obj


class _PlainCall:
    """``f(*args)`` with the results as flat float arrays."""

    def __init__(self, f: ca.Function) -> None:
        self.f = f

    def __call__(self, *args: Any) -> list[np.ndarray]:
        return [np.asarray(r, dtype=float).ravel() for r in self.f(*args)]


def eq8_rhs(i_l: Any, u: Any, gap_rate: Any, ltilde: Any, dl_ds: Any, r_el: Any, a: Any) -> Any:
    """Eq. 8: ``dI_L/dt = [(U - R_el I_L)/a - dL/ds I_L ds/dt] / L~`` with ``a = 1 + R_el/R_ec``.

    Works element-wise on floats, NumPy arrays and CasADi expressions; the one expression
    of eq. 8 that :class:`CurrentModel` and :class:`~maglevkit.reduced.bank.MagnetBank` use.
    """
    return ((u - r_el * i_l) / a - dl_ds * i_l * gap_rate) / ltilde


def eq8_coil_current(i_l: Any, u: Any, r_el: Any, a: Any) -> Any:
    """Coil current of Fig. 8: ``I = (U - U_L)/R_el`` with ``U_L = (U - R_el I_L)/a``."""
    return (u - (u - r_el * i_l) / a) / r_el


def eq8_freewheel_voltage(i_l: Any, u: Any, r_el: Any, a: Any) -> Any:
    """Eq. 8's terminal voltage behind a two-quadrant chopper with freewheeling diodes.

    The chopper drives the coil current ``I = (U/R_ec + I_L)/a`` (Fig. 8) but cannot
    reverse it: where the commanded ``U`` would make ``I < 0`` the diodes block and the
    terminal voltage is the one that gives ``I = 0``, ``U = -R_ec I_L``, so that
    ``U_eff = max(U, -R_ec I_L)`` with ``R_ec = R_el/(a - 1)``.  With ``I = 0`` the flux
    then decays through the eddy-current path alone (``L~ dI_L/dt = -R_ec I_L`` at a fixed
    gap), and ``I_L`` never crosses zero.  Without an eddy path (``a = 1``, ``I = I_L``)
    the diodes hold ``I_L`` at zero once it is there (``U_eff = max(U, 0)`` for
    ``I_L <= 0``).  Evaluated inside every RK4 stage, the limit holds within a step, not
    only at the sample instants.

    Parameters
    ----------
    i_l : float or CasADi
        Inductor current ``I_L`` [A].
    u : float or CasADi
        Commanded terminal voltage ``U`` [V].
    r_el : float or CasADi
        Coil resistance ``R_el`` [ohm].
    a : float or CasADi
        ``1 + R_el/R_ec`` [-] (1: no eddy path).

    Returns
    -------
    CasADi expression (or float for float inputs)
        The applied voltage ``U_eff`` [V] (CasADi ``fmax``/``if_else``).
    """
    floor = ca.if_else(a > 1, -r_el * i_l / ca.fmax(a - 1, 1e-300),
                       ca.if_else(i_l > 0, -ca.inf, 0.0))
    return ca.fmax(u, floor)


def eq8_eddy_branch_rhs(i_k: Any, u_l: Any, r_k: Any, l_k: Any) -> Any:
    """An RL branch of the eddy network in parallel with ``L~`` (Fig. 8 extended):
    ``dI_k/dt = (U_L - R_k I_k)/L_k``, ``U_L`` the inductor voltage."""
    return (u_l - r_k * i_k) / l_k


def eq8_shielded_gap_rhs(i_l: Any, i_e: Any, u: Any, gap_rate: Any, ltilde: Any, dl_ds: Any,
                         r_el: Any, a: Any, r_2: Any, l_u: Any, share: Any) -> tuple[Any, Any]:
    """Eq. 8 with a shielded gap section (``CurrentModel(maps, motion_eddy=True)``).

    The ladder ``R_el``, shunt ``R_a``, series ``L_u``, shunt ``R_2 || L(s, I_L)``
    (:mod:`maglevkit.reduction.motion_eddy`), with ``a = 1 + R_el/R_a`` and the
    motion-induced voltage ``e = dL/ds I_L ds/dt`` shared between the gap section
    (``1 - beta``) and the unshielded ``L_u`` (``beta``, ``share``)::

        V_A = (U - R_el (I_L + I_e))/a,   V_m = R_2 I_e
        dI_L/dt = (V_m - (1 - beta) e)/(L~ - L_u)
        dI_e/dt = (V_A - V_m - beta e)/L_u - dI_L/dt

    ``I_L`` [A] is the gap section's current (the force's), ``I_e`` [A] the shielding eddy
    current through ``R_2``; the coil current is ``eq8_coil_current(I_L + I_e, U, R_el, a)``.
    ``beta = 0`` is the ladder without an unshielded motion term.  Element-wise on floats,
    NumPy arrays and CasADi expressions.

    Returns
    -------
    (dI_L/dt, dI_e/dt) [A/s]
    """
    v_a = (u - r_el * (i_l + i_e)) / a
    v_m = r_2 * i_e
    emf = dl_ds * i_l * gap_rate
    d_il = (v_m - (1.0 - share) * emf) / (ltilde - l_u)
    return d_il, (v_a - v_m - share * emf) / l_u - d_il


def eq8_shielded_gap3_rhs(i_l: Any, i_e1: Any, i_e2: Any, u: Any, gap_rate: Any,
                          ltilde: Any, dl_ds: Any, r_el: Any, a: Any, r_2: Any, l_u: Any,
                          r_3: Any, l_2: Any, share: Any, inner_share: Any
                          ) -> tuple[Any, Any, Any]:
    """Eq. 8 with two shielded sections, the three-state ladder
    (``CurrentModel(maps, motion_eddy=True, eddy_branches=2)``; docs/equations.md section 8).

    ``R_el``, shunt ``R_a``, series ``L_u``, shunt ``R_2``, series ``L_2``, shunt
    ``R_3 || L(s, I_L)`` with the gap section's inductance ``L~ - L_u - L_2``; the currents
    ``I_2 = I_L + I_e1`` (through ``L_2``) and ``I_u = I_2 + I_e2`` (through ``L_u``), and
    the motion voltage ``e = dL/ds I_L ds/dt`` shared as ``beta e``, ``beta_2 e`` and
    ``(1 - beta - beta_2) e``::

        V_A = (U - R_el I_u)/a,   V_B = R_2 I_e2,   V_C = R_3 I_e1
        dI_L/dt = (V_C - (1 - beta - beta_2) e)/(L~ - L_u - L_2)
        dI_2/dt = (V_B - V_C - beta_2 e)/L_2
        dI_u/dt = (V_A - V_B - beta e)/L_u

    The coil current is ``eq8_coil_current(I_u, U, R_el, a)``.  ``L_2 -> 0`` is
    :func:`eq8_shielded_gap_rhs` with ``R_2 || R_3`` on its slow manifold.  Element-wise on
    floats, NumPy arrays and CasADi expressions.

    Returns
    -------
    (dI_L/dt, dI_e1/dt, dI_e2/dt) [A/s]
    """
    i_2 = i_l + i_e1
    i_u = i_2 + i_e2
    v_a = (u - r_el * i_u) / a
    v_b, v_c = r_2 * i_e2, r_3 * i_e1
    emf = dl_ds * i_l * gap_rate
    d_il = (v_c - (1.0 - share - inner_share) * emf) / (ltilde - l_u - l_2)
    d_i2 = (v_b - v_c - inner_share * emf) / l_2
    d_iu = (v_a - v_b - share * emf) / l_u
    return d_il, d_i2 - d_il, d_iu - d_i2


def motion_eddy3_parameters(maps: CharacteristicMaps, resistance_ohm: np.ndarray, *,
                            what: str = "") -> tuple[dict[str, np.ndarray], float]:
    """The three-state ladder of ``maps`` (``motion_eddy3_*`` variables of ``build_maps``),
    checked: its elements per circuit by the short names ``r_a, l_u, r_2, l_2, r_3, beta,
    beta_2, c_1, c_2`` and ``a``, and the longest stable RK4 sub-step [s] (``1.5`` over the
    Gershgorin bound of the rates in ``(I_u, I_2, I_L)`` with the maps' smallest ``L~``).
    ``what`` prefixes the error messages (e.g. ``"member 'm1': "``).  Both
    :class:`CurrentModel` and :class:`~maglevkit.reduced.bank.MagnetBank` read the ladder here.

    Raises
    ------
    InputError
        Maps without the variables (built before them, or from a table), of a magnet
        without eddy currents, or whose smallest ``L~`` is not above ``L_u + L_2``.
    """
    from ..reduction.maps import MOTION_EDDY3_VARIABLES

    ds = maps.dataset
    names = [v[0] for v in MOTION_EDDY3_VARIABLES[:9]]
    missing = [n for n in names if n not in ds]
    if missing:
        raise InputError(f"{what}eddy_branches=2: these maps have no three-state ladder "
                         f"({', '.join(missing[:2])}, ...); rebuild them with this version "
                         "(build_maps), or use eddy_branches=1")
    vals = [np.array(ds[n].values, dtype=float) for n in names]
    par = dict(zip(("r_a", "l_u", "r_2", "l_2", "r_3", "beta", "beta_2", "c_1", "c_2"),
                   vals, strict=True))
    if not (all(np.all(np.isfinite(v)) for v in vals)
            and all(np.all(par[k] > 0) for k in ("r_a", "l_u", "r_2", "l_2", "r_3"))):
        if _no_current_jump(ds):
            # the fit needs the exact current jump (build_maps); an eddy network that
            # diffuses (eddy_model = "ladder") has none, so the fit was skipped
            raise InputError(f"{what}eddy_branches=2: these maps have no three-state ladder: "
                             "its fit starts from the current jump on a voltage step, and "
                             "this magnet's eddy network has none (R_ec of the jump is inf: "
                             "its eddy currents diffuse, e.g. eddy_model = 'ladder'); use "
                             "eddy_modes=2 (the fitted RL eddy network, without motion_eddy), "
                             "or eddy_branches=1")
        raise InputError(f"{what}eddy_branches=2: these maps have no three-state ladder to use (the "
                         "magnet has no eddy currents); use motion_eddy=False")
    lt_min = np.array([float(np.min(maps.variable("inductance_H", c))) for c in maps.circuits])
    l_3 = lt_min - par["l_u"] - par["l_2"]
    if np.any(l_3 <= 0):
        raise InputError(f"{what}eddy_branches=2: the maps' smallest L~ ({lt_min.min():.4g} H) is "
                         "not above the ladder's L_u + L_2 (the gap section would have no "
                         "inductance left); use eddy_branches=1")
    r_el = np.asarray(resistance_ohm, dtype=float)
    par["a"] = eq8_a(r_el, par["r_a"])
    rate = float(np.max(np.maximum.reduce([
        (r_el / par["a"] + 2.0 * par["r_2"]) / par["l_u"],
        2.0 * (par["r_2"] + par["r_3"]) / par["l_2"], 2.0 * par["r_3"] / l_3])))
    return par, 1.5 / rate


def _no_current_jump(ds: Any) -> bool:
    """Whether maps (their dataset) have eddy currents but no current jump on a voltage
    step: the jump's ``R_ec`` (``eddy_resistance_ohm``) inf in some circuit while the
    step-fitted one (``eddy_resistance_fit_ohm``) is finite there."""
    if "eddy_resistance_ohm" not in ds or "eddy_resistance_fit_ohm" not in ds:
        return False
    jump = np.asarray(ds["eddy_resistance_ohm"].values, dtype=float)
    fit = np.asarray(ds["eddy_resistance_fit_ohm"].values, dtype=float)
    return bool(np.any(np.isinf(jump) & np.isfinite(fit)))


def shielded_gap_freewheel_voltage(i_l: Any, i_e: Any, u: Any, r_el: Any, a: Any) -> Any:
    """The shielded-gap ladder's terminal voltage behind a two-quadrant chopper with
    freewheeling diodes (``CurrentModel(maps, motion_eddy=True, freewheel=True)`` and
    ``MagnetBank(..., motion_eddy=True, freewheel=True)``).

    The ladder's coil current ``I = (U/R_a + I_L + I_e)/a`` is eq. 8's
    ``(U/R_ec + I_L)/a`` with ``I_L + I_e`` in place of ``I_L`` and the shunt ``R_a`` in
    place of ``R_ec`` (``a = 1 + R_el/R_a``), so the diode law is
    :func:`eq8_freewheel_voltage` of ``I_L + I_e``: ``U_eff = max(U, -R_a (I_L + I_e))``.
    With ``I_e = 0`` (eq. 8 circuits of a bank) it is eq. 8's own limit.

    Parameters
    ----------
    i_l : float or CasADi
        The gap section's current ``I_L`` [A].
    i_e : float or CasADi
        The shielding eddy current ``I_e`` [A].
    u : float or CasADi
        Commanded terminal voltage ``U`` [V].
    r_el : float or CasADi
        Coil resistance ``R_el`` [ohm].
    a : float or CasADi
        ``1 + R_el/R_a`` [-].

    Returns
    -------
    CasADi expression (or float for float inputs)
        The applied voltage ``U_eff`` [V].
    """
    return eq8_freewheel_voltage(i_l + i_e, u, r_el, a)


def shielded_gap_force_current(i_l: Any, i_e: Any, force_share: Any) -> Any:
    """The current at which the shielded-gap ladder reads eq. 8's force map:
    ``F = F(s, I_L + gamma I_e)``.

    ``gamma`` (``force_share``) is the share of the shielding eddy current's MMF that acts
    on the gap (identified from the detailed model's held-flux stiffness,
    :func:`~maglevkit.reduction.motion_eddy.force_share`; docs/equations.md section 8);
    ``gamma = 0`` is eq. 8's ``F(s, I_L)``.  In a steady state ``I_e = 0``: the statics'
    force.  Element-wise on floats, NumPy arrays and CasADi expressions.

    Parameters
    ----------
    i_l : float, ndarray or CasADi expression
        ``I_L`` [A].
    i_e : float, ndarray or CasADi expression
        ``I_e`` [A].
    force_share : float, ndarray or CasADi expression
        ``gamma`` [-].

    Returns
    -------
    same type as ``i_l``
        The force current [A].
    """
    return i_l + force_share * i_e


#: Whether the eddy branches' ``L_k`` scale with ``L~(s, I_L)/L~_ref`` (True) or stay at
#: their fitted values (decided by measurement: docs/decisions.md, "Reduction").
_EDDY_INDUCTANCE_SCALES = True


def check_eddy_modes(value: Any) -> int:
    from ..reduction.eddy_network import EDDY_NETWORK_MODES

    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or \
            (int(value) != 0 and int(value) not in EDDY_NETWORK_MODES):
        raise InputError(f"eddy_modes = {value!r}; use 0 (eq. 8, one R_ec) or one of "
                         f"{list(EDDY_NETWORK_MODES)} (RL branches of the eddy network)")
    return int(value)


def _no_eddy_network_message(maps: CharacteristicMaps, missing: Sequence[str]) -> str:
    """Why ``eddy_modes > 0`` is refused on ``maps`` without an eddy network, and what the
    user can do instead: the one text of :class:`CurrentModel` and
    :class:`~maglevkit.reduced.bank.MagnetBank` (through :func:`eddy_network_parameters`).

    Maps imported from a table (``maps_from_table``) cannot be rebuilt with ``build_maps``:
    the network is fitted to the detailed model's voltage step, which a table does not
    have; the table's own ``R_ec`` (eq. 8, ``eddy_modes=0``) is what they hold.  Other maps
    without the variables were built before them.

    Parameters
    ----------
    maps : CharacteristicMaps
        The maps that lack the network.
    missing : sequence of str
        The ``eddy_network_*`` variables they lack.
    """
    if "table_report" in maps.dataset.attrs:
        source = maps.dataset.attrs.get("table_source")
        table = f"the table {source!r}" if source else "a table"
        return (f"these maps were imported from {table} (maps_from_table) and hold no eddy "
                "network (it is fitted to the detailed flux model's voltage step, which a "
                "table does not have): use eddy_modes=0 (the paper's eq. 8 with the table's "
                "R_ec, maps_from_table(eddy_resistance_ohm=...)), or build maps from a magnet "
                "file (mk.build_maps / maglevkit maps build MAGNET) to use eddy_modes > 0")
    return (f"these maps have no eddy network ({', '.join(missing)}; built by an earlier "
            "version): rebuild them with this version from their magnet (mk.build_maps / "
            "maglevkit maps build MAGNET) to use eddy_modes > 0, or use eddy_modes=0 (eq. 8)")


def eddy_network_parameters(maps: CharacteristicMaps, m: int, resistance_ohm: np.ndarray, *,
                            what: str = "") -> tuple[dict[str, np.ndarray], float]:
    """The maps' fitted eddy network with ``m`` branches (``eddy_network_*`` variables of
    ``build_maps``), checked: per circuit ``r_0`` (``R_0`` [ohm], inf: no current jump),
    ``a = 1 + R_el/R_0``, ``l_ref`` (``L~_ref`` [H]) and per branch ``r_k`` [ohm], ``l_k`` [H]
    (arrays ``(n_circuits, m)``), and the longest stable RK4 sub-step [s].

    The sub-step: the eigenvalues of ``M^-1 S`` (``network_step_response``) lie within the
    Gershgorin discs of its rows, ``|lambda| <= (R_k + (m + 1) R_el/a)/L_k``, with the
    smallest ``L_k`` over the maps (``L_k`` scales with ``L~``); 1.5 over the largest rate.
    ``what`` prefixes the error messages (e.g. ``"member 'm1': "``).  Both
    :class:`CurrentModel` and :class:`~maglevkit.reduced.bank.MagnetBank` read the network
    here.

    Raises
    ------
    InputError
        Maps without the variables (built before them), without a network of ``m``
        branches, or of a magnet without eddy currents (or a failed fit).
    """
    ds = maps.dataset
    names = ("eddy_network_r0_ohm", "eddy_network_resistance_ohm",
             "eddy_network_inductance_H", "eddy_network_reference_inductance_H")
    missing = [n for n in names if n not in ds]
    if missing:
        raise InputError(what + _no_eddy_network_message(maps, missing))
    have = [int(v) for v in ds["eddy_modes"].values] if "eddy_modes" in ds.coords else []
    if m not in have:
        raise InputError(f"{what}eddy_modes = {m}: these maps hold eddy networks with {have} "
                         "branches; use one of those or 0")
    r0 = np.asarray(ds["eddy_network_r0_ohm"].sel(eddy_modes=m).values, dtype=float)
    r_k = np.asarray(ds["eddy_network_resistance_ohm"].sel(eddy_modes=m).values,
                     dtype=float)[:, :m]
    l_k = np.asarray(ds["eddy_network_inductance_H"].sel(eddy_modes=m).values,
                     dtype=float)[:, :m]
    l_ref = np.asarray(ds["eddy_network_reference_inductance_H"].values, dtype=float)
    if not (np.all(np.isfinite(r_k)) and np.all(np.isfinite(l_k)) and np.all(r_k > 0)
            and np.all(l_k > 0) and np.all(l_ref > 0) and not np.any(np.isnan(r0))):
        raise InputError(f"{what}these maps have no eddy network to use (the magnet has no "
                         "eddy currents, or the fit failed); use eddy_modes=0")
    r_el = np.asarray(resistance_ohm, dtype=float)
    a = eq8_a(r_el, r0)
    lt_min = np.array([float(np.min(maps.variable("inductance_H", c))) for c in maps.circuits])
    scale = lt_min / l_ref if _EDDY_INDUCTANCE_SCALES else np.ones(r_el.size)
    step = math.inf
    if np.all(scale > 0):
        rate = float(np.max((r_k + ((m + 1) * r_el / a)[:, None]) / (l_k * scale[:, None])))
        step = 1.5 / rate
    return {"r_0": r0, "a": a, "r_k": r_k, "l_k": l_k, "l_ref": l_ref}, step


def eddy_network_freewheel_voltage(i_l: Any, i_k: Sequence[Any], u: Any, r_el: Any,
                                   a: Any) -> Any:
    """The eddy network's terminal voltage behind a two-quadrant chopper with freewheeling
    diodes (``CurrentModel(maps, eddy_modes=m, freewheel=True)``, ``MagnetBank(...,
    eddy_modes=m, freewheel=True)``; docs/bank.md, "Eddy-network members").

    The network's coil current (:func:`eddy_network_coil_current`) is
    ``I = (U - U_L)/R_el = (U/R_0 + I_L + sum_k I_k)/a`` with ``a = 1 + R_el/R_0``: eq. 8's
    ``(U/R_ec + I_L)/a`` with the terminal current ``I_L + sum_k I_k`` in place of ``I_L``
    and ``R_0`` in place of ``R_ec``.  So the diode law is :func:`eq8_freewheel_voltage` of
    that sum, ``U_eff = max(U, -R_0 (I_L + sum_k I_k))``, exact for a finite ``R_0``.  With
    ``R_0 = inf`` (``a = 1``) ``I = I_L + sum_k I_k`` does not depend on ``U`` and blocking
    is a constraint on the states, not a clamp of ``U``: refused by
    :func:`check_network_freewheel`.  The sum runs left to right, as the ladders' terminal
    currents (unused branches of a bank hold exact zeros).

    Parameters
    ----------
    i_l : float or CasADi
        Inductor current ``I_L`` [A].
    i_k : sequence of float or CasADi
        Branch currents ``I_k`` [A].
    u : float or CasADi
        Commanded terminal voltage ``U`` [V].
    r_el : float or CasADi
        Coil resistance ``R_el`` [ohm].
    a : float or CasADi
        ``1 + R_el/R_0`` [-] (> 1: finite ``R_0``).

    Returns
    -------
    CasADi expression (or float for float inputs)
        The applied voltage ``U_eff`` [V].
    """
    total = i_l
    for v in i_k:
        total = total + v
    return eq8_freewheel_voltage(total, u, r_el, a)


def check_network_freewheel(r_0_ohm: Any, names: Sequence[str], what: str = "") -> None:
    """Refuse freewheeling diodes on eddy-network circuits whose fitted ``R_0`` is infinite
    (``names`` the circuits, ``what`` prefixes the message).

    Raises
    ------
    InputError
        Naming the circuits: with ``R_0 = inf`` the coil current ``I_L + sum_k I_k`` does not
        depend on ``U``, so a blocking diode is a constraint on the states (the branches keep
        relaxing while their sum is held at 0), which :func:`eddy_network_freewheel_voltage`
        cannot express.
    """
    r0 = np.atleast_1d(np.asarray(r_0_ohm, dtype=float))
    bad = [str(n) for n, r in zip(names, r0, strict=True) if not np.isfinite(r)]
    if bad:
        raise InputError(f"{what}freewheel=True on eddy-network circuits {bad} whose fitted "
                         "R_0 is inf (no current jump): there the coil current I_L + sum I_k "
                         "does not depend on U and a blocking diode is a constraint on the "
                         "states, not a clamp of U (docs/bank.md); allowed: circuits with a "
                         "finite R_0, or freewheel=False")


def eddy_network_rhs(i_l: Any, i_k: Sequence[Any], u: Any, gap_rate: Any, ltilde: Any,
                     dl_ds: Any, r_el: Any, a: Any, r_k: Sequence[Any], l_k: Sequence[Any],
                     l_ref: Any) -> tuple[Any, tuple[Any, ...]]:
    """Eq. 8 with the eddy network (``CurrentModel(maps, eddy_modes=m)``, ``MagnetBank(...,
    eddy_modes=m)``): ``R_ec`` replaced by ``1/R_0 + sum_k 1/(R_k + p L_k)``, one state
    ``I_k`` per branch (docs/equations.md, "The eddy network")::

        U_L = (U - R_el (I_L + sum_k I_k))/a,        a = 1 + R_el/R_0
        dI_L/dt = (U_L - dL/ds I_L ds/dt)/L~
        dI_k/dt = (U_L - R_k I_k)/(L_k L~/L~_ref)

    eq. 8 (:func:`eq8_rhs`) with ``U - R_el sum_k I_k`` as the voltage behind ``R_el``, and
    the branches of :func:`eq8_eddy_branch_rhs` (their ``L_k`` scaled with ``L~``).

    Parameters
    ----------
    i_l : float or CasADi
        Inductor current ``I_L`` [A].
    i_k : sequence of float or CasADi, length m
        Branch currents ``I_k`` [A].
    u : float or CasADi
        Terminal voltage ``U`` [V].
    gap_rate : float or CasADi
        ``ds/dt`` [m/s].
    ltilde, dl_ds : float or CasADi
        ``L~(s, I_L)`` [H] and ``dL/ds(s, I_L)`` [H/m] from the maps.
    r_el : float or CasADi
        Coil resistance ``R_el`` [ohm].
    a : float or CasADi
        ``1 + R_el/R_0`` [-] (1 with ``R_0 = inf``: no current jump).
    r_k, l_k : sequence of float or CasADi, length m
        The branches' ``R_k`` [ohm] and ``L_k`` [H] (at ``L~_ref``).
    l_ref : float or CasADi
        ``L~_ref`` [H], the ``L~`` at which ``L_k`` were fitted.

    Returns
    -------
    (dI_L/dt, (dI_k/dt, ...)) [A/s]
    """
    i_sum = i_k[0]
    for v in i_k[1:]:
        i_sum = i_sum + v
    u_eff = u - r_el * i_sum
    u_l = (u_eff - r_el * i_l) / a
    scale = ltilde / l_ref if _EDDY_INDUCTANCE_SCALES else 1.0
    return (eq8_rhs(i_l, u_eff, gap_rate, ltilde, dl_ds, r_el, a),
            tuple(eq8_eddy_branch_rhs(i, u_l, r, ll * scale)
                  for i, r, ll in zip(i_k, r_k, l_k, strict=True)))


def eddy_network_coil_current(i_l: Any, i_k: Sequence[Any], u: Any, r_el: Any, a: Any) -> Any:
    """The eddy network's coil current ``I = (U - U_L)/R_el``: eq. 8's
    (:func:`eq8_coil_current`) with ``U - R_el sum_k I_k`` behind ``R_el``, plus the
    branch currents [A]."""
    i_sum = i_k[0]
    for v in i_k[1:]:
        i_sum = i_sum + v
    return eq8_coil_current(i_l, u - r_el * i_sum, r_el, a) + i_sum


def _last_line(text: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    return lines[-1] if lines else text


def _per_gap(value: Any, names: tuple[str, ...], *, positive: bool) -> np.ndarray:
    """Pole gaps [m] (> 0) or gap rates [m/s] per gap (the same converter)."""
    return (per_name_values(value, names, "gaps", "m", kind="gap", positive=True) if positive
            else per_name_values(value, names, "gap_rates", "m/s", kind="gap"))
