"""Many magnets advanced together: one compiled call per step for every reduced circuit.

A vehicle carries on the order of 100 levitation and guidance circuits.  A
:class:`MagnetBank` holds magnets of mixed kinds (standard, bow, guidance, U-magnet; each
with its own characteristic maps, stored once when several magnets share them) and
advances all of them by one call with arrays over circuits.  For the reduced members the
whole step, eq. 8 integrated by RK4 for every circuit, is one CasADi function mapped over
the circuits, generated as C, compiled by the system compiler and cached on disk
(:mod:`maglevkit.models.compiled`); no Python runs per circuit.  Detailed flux-based
members (:class:`~maglevkit.models.flux.FluxModel`) can join the bank too; each is
advanced by its own integrator (correct, not fast: for studies of the per-pole force
distribution).

Per reduced circuit ``j`` (paper eq. 8, Fig. 8; the same expression as
:class:`~maglevkit.reduced.current.CurrentModel`)::

    dI_L/dt = [ (U - R_el I_L) / a  -  dL/ds(s, I_L) I_L ds/dt ] / L~(s, I_L),   a = 1 + R_el/R_ec
    I       = (U - U_L) / R_el,   U_L = (U - R_el I_L) / a                (coil current)
    F       = F(s, I_L)

with ``L~``, ``dL/ds`` and ``F`` from per-cell polynomial tables of the maps
(:mod:`maglevkit.reduced.tables`; ``"bicubic"`` reproduces the single model's B-spline to
rounding).  The same expressions are available as CasADi functions
(:attr:`MagnetBank.ode_function`, :attr:`MagnetBank.output_function`) for vehicle
models, linearisation and MPC.
"""

from __future__ import annotations

import hashlib
import math
import subprocess
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, TypeVar

import casadi as ca
import numpy as np

from ..errors import InputError, OutOfRangeError
from ..models.compiled import (
    COMPILE_MODES,
    BoundCall,
    build_source,
    cache_directory,
    compile_function,
    find_compiler,
)
from ..models.flux import FluxModel, FluxState
from ..models.inputs import (
    check_initial_choice,
    check_step,
    per_name_values,
    reject_bools,
    simulation_inputs,
)
from ..models.statics import circuit_pole_groups
from ..reduction.motion_eddy import ladder3_force_current
from ..validation import describe, external_stacklevel, flag, renamed_keywords
from .core import (
    EXTRA_CELLS,
    STEP_FLAG_MESSAGES,
    MotionEddyLadder,
    ReducedCore,
    StepFlag,
    circuit_label,
    diagnose_flags,
    extend_values,
    rk4_substep,
    substep_count,
    substep_counts,
)
from .current import (
    CurrentModel,
    check_eddy_modes,
    check_network_freewheel,
    eddy_network_coil_current,
    eddy_network_freewheel_voltage,
    eddy_network_parameters,
    eddy_network_rhs,
    eq8_coil_current,
    eq8_freewheel_voltage,
    eq8_rhs,
    eq8_shielded_gap3_rhs,
    eq8_shielded_gap_rhs,
    motion_eddy3_parameters,
    shielded_gap_force_current,
    shielded_gap_freewheel_voltage,
)
from .lanes import LaneInput, external_source, lane_source, lane_target
from .stepper import BankStepper
from .tables import INTERPOLATION_METHODS, cell_lookup, cell_table, gap_cell_part

if TYPE_CHECKING:
    from ..reduction.maps import CharacteristicMaps

__all__ = ["EDDY_NETWORK_PARAMETERS", "KERNEL_PARAMETERS", "MOTION_EDDY3_PARAMETERS",
           "MOTION_EDDY_PARAMETERS", "RUN_CHUNK",
           "STEP_FLAG_MESSAGES", "BankOutputs", "BankRun", "BankSimulation", "BankState",
           "MagnetBank", "StepFlag", "circuit_label"]

_MAP_VARIABLES = ("inductance_H", "dL_ds_H_per_m", "force_N")
KERNEL_PARAMETERS = ("s0_m", "inv_ds_per_m", "cells_s", "i0_A", "inv_di_per_A", "cells_i",
                     "table_offset", "resistance_ohm", "a", "gap_lower_m", "gap_upper_m",
                     "current_lower_A", "current_upper_A")
"""Rows of :attr:`MagnetBank.circuit_parameters`: the circuit's grid, its table offset,
``R_el``, ``a = 1 + R_el/R_ec`` and the range bounds (with rounding allowances)."""
_N_PAR = len(KERNEL_PARAMETERS)
MOTION_EDDY_PARAMETERS = ("motion_eddy", "shielding_resistance_ohm", "unshielded_inductance_H",
                          "unshielded_share", "force_share")
"""Rows appended to :attr:`MagnetBank.circuit_parameters` in a bank with shielded-gap
ladder members (:attr:`MagnetBank.motion_eddy`): 1 for a ladder circuit, 0 for an eq. 8
one; the ladder's ``R_2`` [ohm], ``L_u`` [H] (1 H for eq. 8 circuits, unused), the
unshielded share ``beta`` of the motion term [-] and the force share ``gamma`` of ``I_e``
[-] (force ``F(s, I_L + gamma I_e)``; both 0 for eq. 8 circuits).  In ladder circuits the
row ``a`` holds ``1 + R_el/R_a``.  In a bank with three-state ladder members
(:attr:`MagnetBank.n_eddy_states` 2) the flag is 2 for their circuits, the rows ``R_2``,
``L_u``, ``beta`` hold the outer section's ``R_2``, ``L_u``, ``beta`` and ``force_share``
holds ``c_1`` (the share of the first eddy state ``I_e1``)."""
MOTION_EDDY3_PARAMETERS = ("inner_shielding_resistance_ohm", "inner_inductance_H",
                           "inner_share", "force_share_2")
"""Rows appended after :data:`MOTION_EDDY_PARAMETERS` in a bank with three-state ladder
members (``MagnetBank.n_eddy_states == 2``): the inner shield ``R_3`` [ohm], the inner
series ``L_2`` [H], the inner share ``beta_2`` of the motion term [-] and the share
``c_2`` of the second eddy state ``I_e2`` in the force current [-] (docs/equations.md
section 8, "Three states"); ``0, 1 H, 0, 0`` in two-state ladder and eq. 8 circuits."""
EDDY_NETWORK_PARAMETERS = ("eddy_network_modes", "eddy_network_reference_inductance_H")
"""Rows appended after :data:`MOTION_EDDY_PARAMETERS` (and :data:`MOTION_EDDY3_PARAMETERS`
where present) in a bank with eddy-network members (``eddy_modes > 0``;
:attr:`MagnetBank.eddy_modes`): the circuit's branch count ``m`` (0 in other circuits) and
``L~_ref`` [H] (1 H elsewhere), then ``n_e`` rows of branch resistances ``R_k`` [ohm] and
``n_e`` rows of branch inductances ``L_k`` [H] (``n_e`` = :attr:`MagnetBank.n_eddy_states`;
``0, 1 H`` for absent branches).  Their circuits have the flag 3 in row ``motion_eddy`` and
``a = 1 + R_el/R_0`` in row ``a``."""
RUN_CHUNK = 1024
"""Steps per call of the compiled time loop of :meth:`MagnetBank.run_steps` (longer runs
take several calls)."""
_LANE_INTERLEAVE = 2
# blocks of SIMD lanes per iteration of the lanes' loop (lane_source's interleave; the
# same bits either way, docs/decisions.md "netperf")
_T = TypeVar("_T")


@dataclass(frozen=True)
class BankState:
    """State of a magnet bank at one instant.

    Attributes
    ----------
    time_s : float
        Time [s].
    inductor_currents_A : ndarray (n_circuits,)
        ``I_L`` of every reduced circuit [A] (NaN for circuits of detailed members).
    gaps_m : ndarray (n_gaps,)
        The bank's gap inputs [m] (one per circuit or one per pole, see
        :attr:`MagnetBank.gap_names`).
    member_states : tuple of FluxState
        States of the detailed members, in member order.
    eddy_currents_A : ndarray (n_circuits,), (n_circuits, n_e) or None
        The shielding eddy current ``I_e`` [A] of every circuit in a bank with
        shielded-gap ladder members (:attr:`MagnetBank.motion_eddy`; 0 for eq. 8
        circuits, NaN for detailed members); ``(I_e1, I_e2)`` per circuit in a bank with
        three-state members (:attr:`MagnetBank.n_eddy_states` 2); the branch currents
        ``I_k`` of eddy-network members (``eddy_modes``) in their first ``m`` columns;
        ``n_e`` = :attr:`MagnetBank.n_eddy_states` columns when it is 2 or 3; None in
        banks without ladder or eddy-network members.
    """

    time_s: float
    inductor_currents_A: np.ndarray
    gaps_m: np.ndarray
    member_states: tuple[FluxState, ...] = ()
    eddy_currents_A: np.ndarray | None = None


@dataclass(frozen=True)
class BankOutputs:
    """Outputs of a bank at the end of a step.

    Attributes
    ----------
    time_s : float
    currents_A : ndarray (n_circuits,)
        Coil currents [A] (with the voltages of the step just taken).
    inductor_currents_A : ndarray (n_circuits,)
        ``I_L`` [A] (NaN for detailed members).
    circuit_force_N : ndarray (n_circuits,)
        Force of each circuit's poles [N], attraction positive.
    member_force_N : ndarray (n_members,)
        Total force of each magnet [N].
    pole_force_N : ndarray (n_poles,) or None
        Force per pole [N] (:attr:`MagnetBank.pole_names`) when asked for: a reduced
        circuit's force shared equally by its poles, a detailed member's own pole forces.
    """

    time_s: float
    currents_A: np.ndarray
    inductor_currents_A: np.ndarray
    circuit_force_N: np.ndarray
    member_force_N: np.ndarray
    pole_force_N: np.ndarray | None = None


@dataclass(frozen=True)
class BankSimulation:
    """Time series of a bank simulation (SI units, axis 0 is time; conventions as
    :class:`~maglevkit.reduced.current.ReducedSimulation`: outputs at ``t_k`` are left
    limits, with the voltages held on ``[t_k-1, t_k)``).

    Attributes
    ----------
    time_s : ndarray (n_t,)
        Sample times [s].
    gaps_m : ndarray (n_t, n_gaps)
        Gap inputs [m] (one per circuit or per pole, ``gap_names``).
    voltages_V : ndarray (n_t, n_circuits)
        Voltages [V] held on ``[t_k, t_k+1)`` (the last row repeats the previous one).
    currents_A, inductor_currents_A, circuit_force_N : ndarray (n_t, n_circuits)
        Coil currents [A], inductor currents ``I_L`` [A] (NaN for detailed members) and
        circuit forces [N].
    member_force_N : ndarray (n_t, n_members)
        Total force of each magnet [N].
    pole_force_N : ndarray (n_t, n_poles)
        Force per pole [N].
    circuit_names, gap_names, pole_names, member_names : tuple of str
        Column orders of the arrays.
    final_state : BankState
        State at ``time_s[-1]`` (to continue with :meth:`MagnetBank.step` or a new
        ``simulate``).
    eddy_currents_A : ndarray (n_t, n_circuits), (n_t, n_circuits, 2) or None
        The shielding eddy currents ``I_e`` [A] in a bank with ladder members (the shape
        of :attr:`BankState.eddy_currents_A` with time in front), else None.
    """

    time_s: np.ndarray
    gaps_m: np.ndarray
    voltages_V: np.ndarray
    currents_A: np.ndarray
    inductor_currents_A: np.ndarray
    circuit_force_N: np.ndarray
    member_force_N: np.ndarray
    pole_force_N: np.ndarray
    circuit_names: tuple[str, ...]
    gap_names: tuple[str, ...]
    pole_names: tuple[str, ...]
    member_names: tuple[str, ...]
    final_state: BankState
    eddy_currents_A: np.ndarray | None = None


@dataclass(frozen=True)
class BankRun:
    """The reduced circuits of a bank over a sequence of steps (:meth:`MagnetBank.run_steps`).

    Row ``k`` holds the values at the end of step ``k`` (coil currents with that step's
    voltages), as :meth:`MagnetBank.step` returns them.

    Attributes
    ----------
    inductor_currents_A, currents_A, circuit_force_N : ndarray (n_steps, n_circuits)
        ``I_L`` [A], coil currents [A] and circuit forces [N]; rows from ``n_good`` on are
        NaN when the run stopped at a flagged step.
    n_good : int
        Steps completed (``n_steps`` unless ``stop_at_flag`` stopped the run at step
        ``n_good``, which the kernel flagged: out of the maps or not finite).
    """

    inductor_currents_A: np.ndarray
    currents_A: np.ndarray
    circuit_force_N: np.ndarray
    n_good: int


@dataclass(frozen=True)
class _Member:
    name: str
    kind: str                         # "reduced" or "detailed"
    circuits: tuple[str, ...]         # the member's own circuit names
    poles: tuple[str, ...]            # its pole (gap input) names
    pole_groups: dict[str, tuple[str, ...]]
    maps: CharacteristicMaps | None = None
    core: ReducedCore | None = None   # reduced members: the facts of their maps
    resistance_ohm: np.ndarray | None = None
    eddy_resistance_ohm: np.ndarray | None = None
    model: FluxModel | None = None
    ladder: MotionEddyLadder | None = None   # the shielded-gap ladder (motion_eddy)
    ladder3: dict[str, np.ndarray] | None = None   # the three-state ladder (eddy_branches=2)
    ladder_step_s: float = math.inf          # the ladder's stable RK4 sub-step [s]
    network: dict[str, np.ndarray] | None = None   # the eddy network (eddy_modes > 0)

    @property
    def eddy_states(self) -> int:
        """Eddy states per circuit: 0 (eq. 8), 1 or 2 (ladders), m (eddy network)."""
        if self.network is not None:
            return int(self.network["r_k"].shape[1])
        return 2 if self.ladder3 is not None else int(self.ladder is not None)

    @property
    def law(self) -> int:
        """The circuits' law (row ``motion_eddy``): 0 eq. 8, 1 two-state ladder, 2
        three-state ladder, 3 eddy network."""
        return 3 if self.network is not None else self.eddy_states


class MagnetBank:
    """Magnets of mixed kinds advanced together (``initial_state`` / ``step`` / ``simulate``).

    Parameters
    ----------
    members : mapping or sequence of (name, model)
        The magnets, each named; a model is a
        :class:`~maglevkit.reduction.CharacteristicMaps` or a
        :class:`~maglevkit.reduced.current.CurrentModel` (reduced member: its maps and
        resistances) or a :class:`~maglevkit.models.flux.FluxModel` (detailed member).
        A single magnet is a bank of one.
    gap_inputs : {"circuit", "pole"}
        ``"circuit"`` (default): one gap input per circuit, the substitute gap of the
        reduced model (a detailed member's poles all get their circuit's gap);
        ``"pole"``: one gap input per pole, as for the single models (a reduced circuit
        uses the mean of its poles' gaps).
    interpolation : {"bicubic", "monotone", "bilinear"}
        How the maps are interpolated (:mod:`maglevkit.reduced.tables`); ``"bicubic"``
        equals the single :class:`CurrentModel`.
    compiled : {"auto", "always", "never"}
        ``"auto"`` (default): generated C compiled by the system C compiler and cached on
        disk, falling back with a warning to CasADi's virtual machine; ``"never"``: the
        virtual machine; ``"always"``: a :class:`SolverError` if compiling fails.
    eddy_resistance : {"fit", "jump"}
        Which ``R_ec`` of the maps reduced members given as maps use (as
        :class:`CurrentModel`); a member given as a ``CurrentModel`` keeps its own.
    max_step_s : float
        Largest RK4 sub-step [s] (default 1e-3 s, as :class:`CurrentModel`).
    extrapolate : bool
        Leaving a map's range raises :class:`OutOfRangeError` (default); ``True`` continues
        the maps linearly for up to three grid cells with a warning.
    cache_dir : path, optional
        Where compiled kernels are cached (default :func:`maglevkit.models.compiled.cache_directory`).
    codegen : {"lanes", "casadi"}
        How the compiled step is generated from the same CasADi function: ``"lanes"``
        (default) evaluates several circuits at once in SIMD lanes
        (:mod:`maglevkit.reduced.lanes`: 4 with AVX2, else 2), ``"casadi"`` is CasADi's
        own code generation of the mapped function (one circuit after the other).  Both
        give the same numbers; ``"lanes"`` is ~3-5x faster at 100-1000 circuits
        (BENCHMARKS.md).  Where the lanes cannot be compiled or loaded, the bank uses
        the ``"casadi"`` code without a warning.
    freewheel : bool
        ``False`` (default): the reduced circuits take the voltages as given (eq. 8);
        ``True``: behind a two-quadrant chopper with freewheeling diodes, the coil
        current cannot go below zero within a step (every RK4 stage applies
        :func:`~maglevkit.reduced.current.eq8_freewheel_voltage`, ``U_eff = max(U,
        -R_ec I_L)``; the outputs' coil currents too; in ladder circuits with ``I_L + I_e``
        and ``R_a`` in place of ``I_L`` and ``R_ec``, the same coil-current law; in
        eddy-network circuits with ``I_L + sum_k I_k`` and ``R_0``).  The vehicle runs
        turn it on.
    motion_eddy : bool
        ``False`` (default): members given as maps follow eq. 8; ``True``: they carry the
        shielded-gap ladder (as ``CurrentModel(maps, motion_eddy=True)``; a member given
        as a ``CurrentModel`` keeps its own choice).  Ladder circuits carry a second state,
        the shielding eddy current ``I_e`` (:attr:`BankState.eddy_currents_A`); the RK4
        sub-step is limited to the ladder's stable step
        (:class:`~maglevkit.reduced.core.MotionEddyLadder`).  With ``freewheel`` the diodes
        act on the ladder's coil current ``I = (U/R_a + I_L + I_e)/a`` (docs/bank.md).
    eddy_branches : {1, 2}
        With ``motion_eddy=True``: the shielded sections of the ladder of members given as
        maps, 1 (default; the two-state ladder, one eddy state ``I_e`` per circuit) or 2
        (the three-state ladder of ``CurrentModel(maps, motion_eddy=True,
        eddy_branches=2)``, eddy states ``I_e1``, ``I_e2`` per circuit; a member given as
        a ``CurrentModel`` keeps its own).  A bank with three-state members carries two
        eddy states in every circuit (:attr:`n_eddy_states`; ``eddy_currents_A`` of shape
        ``(n_circuits, 2)``, the second 0 in two-state ladder circuits, both 0 in eq. 8
        circuits).
    eddy_modes : {0, 1, 2, 3}
        ``0`` (default): members given as maps follow eq. 8 (or the ladder); ``m > 0``: they
        carry the maps' fitted eddy network with ``m`` RL branches (as
        ``CurrentModel(maps, eddy_modes=m)``; a member given as a ``CurrentModel`` keeps
        its own), ``m`` eddy states ``I_k`` per circuit (:attr:`n_eddy_states`, the
        bank-wide maximum; absent branches stay 0).  Not with ``motion_eddy=True`` (two
        different extensions for members given as maps; members given as
        ``CurrentModel`` may mix).  With ``freewheel=True`` the diodes act on the terminal
        current ``I_L + sum_k I_k`` (:func:`~maglevkit.reduced.current.
        eddy_network_freewheel_voltage`); a network whose fitted ``R_0`` is inf is then
        refused (docs/bank.md, "Eddy-network members").

    Examples
    --------
    >>> import numpy as np
    >>> import maglevkit as mk
    >>> magnet = mk.load_magnet("u-magnet")
    >>> maps = mk.build_maps(magnet, gaps_m=np.linspace(0.006, 0.016, 6),
    ...                      currents_A=np.linspace(0, 60, 13), progress=False)
    >>> bank = mk.MagnetBank({f"m{k}": maps for k in range(4)}, compiled="never")
    >>> state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
    >>> state, out = bank.step(state, 1e-3, voltages_V=bank.resistance_ohm * 20.0)
    >>> out.circuit_force_N.shape
    (4,)
    """

    def __init__(self, members: Mapping[str, Any] | Sequence[tuple[str, Any]], *,
                 gap_inputs: str = "circuit", interpolation: str = "bicubic",
                 compiled: str = "auto", eddy_resistance: str = "fit", max_step_s: float = 1e-3,
                 extrapolate: bool = False, cache_dir: Any = None,
                 codegen: str = "lanes", freewheel: bool = False,
                 motion_eddy: bool = False, eddy_branches: int = 1,
                 eddy_modes: int = 0) -> None:
        if compiled not in COMPILE_MODES:
            raise InputError(f"compiled = {compiled!r}; use one of {list(COMPILE_MODES)}")
        if codegen not in ("lanes", "casadi"):
            raise InputError(f"codegen = {codegen!r}; use 'lanes' or 'casadi'")
        if gap_inputs not in ("circuit", "pole"):
            raise InputError(f"gap_inputs = {gap_inputs!r}; use 'circuit' or 'pole'")
        if interpolation not in INTERPOLATION_METHODS:
            raise InputError(f"interpolation = {interpolation!r}; use one of "
                             f"{list(INTERPOLATION_METHODS)}")
        if eddy_resistance not in ("fit", "jump"):
            raise InputError(f"eddy_resistance = {eddy_resistance!r}; use 'fit' or 'jump'")
        reject_bools(max_step_s, "max_step_s")
        if not (isinstance(max_step_s, (int, float)) and math.isfinite(max_step_s)
                and max_step_s > 0):
            raise InputError(f"max_step_s = {max_step_s!r} must be a finite number > 0")
        flag(extrapolate, "extrapolate")
        self.freewheel = flag(freewheel, "freewheel")
        self.gap_inputs = gap_inputs
        self.interpolation = interpolation
        self.compiled_mode = compiled
        self.codegen = codegen
        self.max_step_s = float(max_step_s)
        self.extrapolate = extrapolate
        self._cache_dir = cache_dir
        if not isinstance(members, (Mapping, Sequence)) or isinstance(members, (str, bytes)):
            raise InputError(f"members = {describe(members)}: expected a mapping of names to "
                             "magnets or maps, or a list of (name, magnet or maps) pairs")
        pairs = list(members.items()) if isinstance(members, Mapping) else list(members)
        if not pairs:
            raise InputError("a magnet bank needs at least one member")
        flag(motion_eddy, "motion_eddy")
        if isinstance(eddy_branches, bool) or eddy_branches not in (1, 2):
            raise InputError(f"eddy_branches = {eddy_branches!r}; use 1 (the two-state ladder) "
                             "or 2 (the three-state ladder), with motion_eddy=True")
        if eddy_branches == 2 and not motion_eddy:
            raise InputError("eddy_branches = 2 needs motion_eddy=True (it is the shielded-gap "
                             "ladder's second shielded section)")
        modes = check_eddy_modes(eddy_modes)
        if modes and motion_eddy:
            raise InputError(f"motion_eddy=True with eddy_modes={modes}: these are two "
                             "different eddy extensions of eq. 8 for the members given as "
                             "maps; use one of them (give CurrentModel members to mix them)")
        self._members = tuple(self._member(p, eddy_resistance, bool(motion_eddy),
                                           int(eddy_branches), modes) for p in pairs)
        ladders = [m for m in self._members if m.eddy_states]
        self.motion_eddy = any(m.law in (1, 2) for m in self._members)
        """Whether some member carries the shielded-gap ladder (two or three states per
        circuit)."""
        self.eddy_modes = max([m.eddy_states for m in self._members if m.network is not None],
                              default=0)
        """The most eddy-network branches of a member (``eddy_modes``; 0: no eddy-network
        members)."""
        self.n_eddy_states = max([m.eddy_states for m in self._members])
        """Eddy states per circuit: 0 (eq. 8 members only), 1 (two-state ladders: ``I_e``;
        or eddy networks of one branch), 2 (some three-state ladder member: ``I_e1``,
        ``I_e2``; or an eddy network of two branches) or 3 (an eddy network of three)."""
        self._has_eddy = self.n_eddy_states > 0
        # which laws the bank's circuits follow (0 eq. 8, 1 two-state, 2 three-state, 3 eddy
        # network): the kernel selects only among those present
        self._laws = tuple(sorted({m.law for m in self._members if m.kind == "reduced"}))
        # eddy-network circuits with fewer branches than n_eddy_states (their last
        # branches are switched off per circuit)
        self._mixed_modes = any(m.network is not None and m.eddy_states < self.n_eddy_states
                                for m in self._members)
        if self.freewheel:
            # the diodes on eddy-network circuits need a finite fitted R_0
            # (eddy_network_freewheel_voltage)
            for m in self._members:
                if m.network is not None:
                    check_network_freewheel(m.network["r_0"], m.circuits,
                                            f"member {m.name!r}: ")
        diodes = [m.name for m, (_, model) in zip(self._members, pairs, strict=True)
                  if isinstance(model, CurrentModel) and model.freewheel]
        if diodes and not self.freewheel:
            # a member's freewheeling diodes would be dropped without a word
            raise InputError(f"members {diodes} are CurrentModel(freewheel=True) but the bank "
                             "has freewheel=False: give MagnetBank(..., freewheel=True) (the "
                             "diodes are a bank-wide option)")
        self.eddy_step_s = min([m.ladder_step_s for m in ladders], default=math.inf)
        """The longest stable RK4 sub-step of the members' eddy laws [s] (the shielded-gap
        ladders', the eddy networks'; inf with eq. 8 members only): a stability limit, not
        an accuracy one (``max_step_s`` is at most this; the MPC's prediction models take
        it, :meth:`~maglevkit.control.model.MagnetHeaveModel.rk4_substeps`)."""
        if ladders:
            # the ladder's stable RK4 sub-step (CurrentModel limits its own the same way)
            self.max_step_s = min(self.max_step_s, self.eddy_step_s)
        names = [m.name for m in self._members]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InputError(f"member names must be unique; repeated: {dup}")
        self.member_names: tuple[str, ...] = tuple(names)
        self._layout()
        self._build_reduced()
        self._kernels: dict[int, _StepCall] = {}
        self._lanes: dict[int, tuple[ca.Function, Path]] = {}   # sub-steps -> (f, library)
        self._lane_runs: dict[int, ca.Function] = {}    # sub-steps -> the compiled time loop
        self._runs: dict[int, _RunCall] = {}
        self._inlined_outputs: ca.Function | None = None    # built by _outputs_at
        self._outputs_calls = 0
        self._last_dt: float = math.nan             # the last step length and its kernel
        self._last_call: _StepCall | None = None
        self.compiled: bool | None = None       # known after the first step
        self._extrapolation_warned: set[int] = set()   # circuits already reported

    # ------------------------------------------------------------------ construction
    @staticmethod
    def _member(pair: Any, eddy_resistance: str, motion_eddy: bool = False,
                eddy_branches: int = 1, eddy_modes: int = 0) -> _Member:
        try:
            name, model = pair
        except (TypeError, ValueError):
            raise InputError("members: give a mapping name -> model or (name, model) pairs, "
                             f"got {pair!r}") from None
        if not isinstance(name, str) or not name or "/" in name:
            raise InputError(f"member name {name!r} must be a non-empty string without '/'")
        if isinstance(model, FluxModel):
            net = model.network
            groups = (circuit_pole_groups(net, gap_m=0.01, current_A=10.0)
                      if len(net.circuit_names) > 1 else {net.circuit_names[0]: net.gap_names})
            return _Member(name, "detailed", tuple(model.circuit_names), tuple(model.gap_names),
                           groups, model=model)
        if isinstance(model, CurrentModel):
            core = model.core
            motion_eddy = bool(getattr(model, "motion_eddy", False))
            eddy_branches = int(getattr(model, "eddy_branches", 1))
            eddy_modes = int(model.eddy_modes)
        elif hasattr(model, "dataset") and hasattr(model, "variable"):
            core = ReducedCore.from_maps(model, eddy_resistance=eddy_resistance,
                                         what=f"member {name!r}: ")
        else:
            raise InputError(f"member {name!r}: a model must be CharacteristicMaps, a "
                             f"CurrentModel or a FluxModel, got {type(model).__name__}")
        ladder, ladder3, network, step_s = None, None, None, math.inf
        if eddy_modes:
            network, step_s = eddy_network_parameters(core.maps, eddy_modes,
                                                      core.resistance_ohm,
                                                      what=f"member {name!r}: ")
            r_ec = network["r_0"]
        elif motion_eddy and eddy_branches == 2:
            ladder3, step_s = motion_eddy3_parameters(core.maps, core.resistance_ohm,
                                                      what=f"member {name!r}: ")
            r_ec = ladder3["r_a"]
        elif motion_eddy:
            ladder = MotionEddyLadder.from_maps(core.maps, resistance_ohm=core.resistance_ohm,
                                                what=f"member {name!r}: ")
            r_ec, step_s = ladder.jump_resistance_ohm, ladder.max_step_s
        else:
            r_ec = core.eddy_resistance_ohm
        return _Member(name, "reduced", core.circuit_names, core.gap_names,
                       dict(core.pole_groups), maps=core.maps, core=core,
                       resistance_ohm=core.resistance_ohm, eddy_resistance_ohm=r_ec,
                       ladder=ladder, ladder3=ladder3, ladder_step_s=step_s,
                       network=network)

    def _layout(self) -> None:
        circuits: list[str] = []
        poles: list[str] = []
        member_of: list[int] = []
        self._circuit_slices: list[slice] = []
        self._pole_slices: list[slice] = []
        for k, m in enumerate(self._members):
            c0, p0 = len(circuits), len(poles)
            circuits += [f"{m.name}/{c}" for c in m.circuits]
            poles += [f"{m.name}/{p}" for p in m.poles]
            member_of += [k] * len(m.circuits)
            self._circuit_slices.append(slice(c0, len(circuits)))
            self._pole_slices.append(slice(p0, len(poles)))
        self.circuit_names: tuple[str, ...] = tuple(circuits)
        self.pole_names: tuple[str, ...] = tuple(poles)
        self.gap_names: tuple[str, ...] = (self.circuit_names if self.gap_inputs == "circuit"
                                           else self.pole_names)
        nc, npl = len(circuits), len(poles)
        self._member_of = np.array(member_of)
        self._member_starts = np.array([s.start for s in self._circuit_slices])
        # share: circuit force -> pole forces (equal shares); avg: pole gaps -> circuit gap
        share = np.zeros((npl, nc))
        for m, cs, ps in zip(self._members, self._circuit_slices, self._pole_slices, strict=True):
            if m.core is not None:              # a reduced member: its core's share matrix
                share[ps, cs] = m.core.share
                continue
            pi = {p: ps.start + j for j, p in enumerate(m.poles)}
            for j, c in enumerate(m.circuits):
                for p in m.pole_groups[c]:
                    share[pi[p], cs.start + j] = 1.0 / len(m.pole_groups[c])
        self._share = share
        nonzero = share != 0
        self._pole_gather = ((np.argmax(nonzero, axis=1), share.max(axis=1))
                             if np.all(nonzero.sum(axis=1) == 1) else None)
        self._avg = (share > 0).T / np.maximum((share > 0).sum(axis=0), 1)[:, None]
        self._reduced_idx = np.array([j for m, cs in zip(self._members, self._circuit_slices,
                                                         strict=True)
                                      if m.kind == "reduced" for j in range(cs.start, cs.stop)],
                                     dtype=int)
        self._all_reduced = all(m.kind == "reduced" for m in self._members)
        self._n_detailed = sum(m.kind == "detailed" for m in self._members)
        self._fast = self._all_reduced and self.gap_inputs == "circuit"
        r = np.full(nc, np.nan)
        for m, cs in zip(self._members, self._circuit_slices, strict=True):
            if m.kind == "reduced":
                r[cs] = m.resistance_ohm
            else:
                assert m.model is not None
                r[cs] = m.model.network.resistances
        self.resistance_ohm = r
        """Ohmic resistance R_el of every circuit [ohm]."""
        r_ec = np.full(nc, np.nan)
        for m, cs in zip(self._members, self._circuit_slices, strict=True):
            if m.kind == "reduced":
                r_ec[cs] = m.eddy_resistance_ohm
        self.eddy_resistance_ohm = r_ec
        """Eddy-current resistance R_ec of every reduced circuit [ohm] (inf: none; NaN for
        detailed members, whose eddy currents are part of their network)."""

    def _build_reduced(self) -> None:
        """Per-cell tables (one per distinct map), kernel parameters and range bounds."""
        idx = self._reduced_idx
        n = idx.size
        ne = self.n_eddy_states
        n3 = _N_PAR + (len(MOTION_EDDY_PARAMETERS) if self._has_eddy else 0)
        # the eddy network's rows (EDDY_NETWORK_PARAMETERS, then R_k and L_k of n_e branches)
        self._net_row = n3 + (len(MOTION_EDDY3_PARAMETERS) if 2 in self._laws else 0)
        n_par = self._net_row + ((len(EDDY_NETWORK_PARAMETERS) + 2 * ne) if 3 in self._laws
                                 else 0)
        self._par = np.zeros((n_par, n))
        self._bounds = np.zeros((4, n))            # s_lo, s_hi, i_lo, i_hi (map ranges)
        self._spline_bounds = np.zeros((4, n))     # the same extended by EXTRA_CELLS cells
        tol = np.zeros((2, n))                     # rounding allowances: gap, current
        tables: list[np.ndarray] = []
        known: dict[tuple, tuple[int, tuple[float, float, float, float], tuple[int, int]]] = {}
        by_object: dict[tuple[int, str], list[np.ndarray]] = {}
        size = 0
        k = 0
        self._degree = 1 if self.interpolation == "bilinear" else 3
        for m in self._members:
            if m.kind != "reduced":
                continue
            maps = m.maps
            assert maps is not None and m.core is not None
            gs, gi = m.core.extended_gaps_m, m.core.extended_currents_A
            for j, c in enumerate(m.circuits):
                if (id(maps), c) not in by_object:       # xarray access is ~1 ms a map
                    by_object[(id(maps), c)] = [maps.variable(v, c) for v in _MAP_VARIABLES]
                values = by_object[(id(maps), c)]
                # maps are stored once however many circuits use them
                key = (m.core.gaps_m.tobytes(), m.core.currents_A.tobytes(),
                       *(v.tobytes() for v in values))
                if key not in known:
                    for v, arr in zip(_MAP_VARIABLES, values, strict=True):
                        if not np.all(np.isfinite(arr)):
                            raise InputError(f"member {m.name!r}: map {v!r} of circuit {c!r} has "
                                             "non-finite values; rebuild the maps")
                    ext = np.stack([extend_values(extend_values(a, axis=0), axis=1)
                                    for a in values])
                    tab = cell_table(gs, gi, ext, method=self.interpolation)
                    # layout per cell: map-major, then the (d+1)^2 coefficients t^p w^q
                    tables.append(tab.coefficients.reshape(-1))
                    known[key] = (size, (tab.s0_m, tab.ds_m, tab.i0_A, tab.di_A), tab.n_cells)
                    size += tab.coefficients.size
                offset, (s0, ds_, i0, di_), (cs_, ci_) = known[key]
                assert m.resistance_ohm is not None
                core = m.core
                r_el = float(m.resistance_ohm[j])
                lad, lad3, net = m.ladder, m.ladder3, m.network
                a = float(net["a"][j] if net is not None else
                          lad3["a"][j] if lad3 is not None else
                          core.a[j] if lad is None else lad.a[j])
                self._par[:9, k] = (s0, 1.0 / ds_, cs_, i0, 1.0 / di_, ci_, offset, r_el, a)
                if self._has_eddy:
                    self._par[_N_PAR:n3, k] = (
                        (2.0, *(float(lad3[q][j]) for q in ("r_2", "l_u", "beta", "c_1")))
                        if lad3 is not None else
                        (3.0, 0.0, 1.0, 0.0, 0.0) if net is not None else
                        (0.0, 0.0, 1.0, 0.0, 0.0) if lad is None else
                        (1.0, float(lad.shielding_resistance_ohm[j]),
                         float(lad.unshielded_inductance_H[j]), float(lad.unshielded_share[j]),
                         float(lad.force_share[j])))
                    if 2 in self._laws:
                        self._par[n3:self._net_row, k] = (
                            tuple(float(lad3[q][j]) for q in ("r_3", "l_2", "beta_2", "c_2"))
                            if lad3 is not None else (0.0, 1.0, 0.0, 0.0))
                    if 3 in self._laws:
                        # the branches' R_k, L_k (absent ones 0, 1 H: never advanced)
                        rk, lk = np.zeros(ne), np.ones(ne)
                        mk_ = 0
                        if net is not None:
                            mk_ = net["r_k"].shape[1]
                            rk[:mk_], lk[:mk_] = net["r_k"][j], net["l_k"][j]
                        self._par[self._net_row:, k] = (
                            float(mk_), float(net["l_ref"][j]) if net is not None else 1.0,
                            *rk, *lk)
                self._bounds[:, k] = (*core.gap_range_m, *core.current_range_A)
                tol[:, k] = (core.gap_tolerance_m, core.current_tolerance_A)
                self._spline_bounds[:, k] = (gs[0], gs[-1], gi[0], gi[-1])
                k += 1
        self._table = np.concatenate(tables) if tables else np.zeros(1)
        self.n_distinct_maps = len(tables)
        """How many distinct circuit maps the bank stores (shared when equal)."""
        b = self._bounds
        # rounding allowances of the range checks (the cores', as CurrentModel's)
        tol_s, tol_i = tol
        self._lo_s, self._hi_s = b[0] - tol_s, b[1] + tol_s
        self._lo_i, self._hi_i = b[2] - tol_i, b[3] + tol_i
        self._par[9:13] = (self._lo_s, self._hi_s, self._lo_i, self._hi_i)
        self._circuit_kernel = self._make_circuit_kernel()

    # ------------------------------------------------------------------ CasADi kernels
    def _gap_cell(self, s: Any, p: Any) -> tuple[Any, Any]:
        """The gap half of a table lookup at gap ``s`` (MX expressions): the table offset
        of the gap cell's row and the powers of the local coordinate ``t``
        (:func:`~maglevkit.reduced.tables.gap_cell_part`)."""
        return gap_cell_part(s, p, self._degree)

    def _lookup(self, cell: tuple[Any, Any], i: Any, p: Any, table: Any,
                maps: tuple[int, ...] = (0, 1, 2)) -> list[Any]:
        """Maps ``maps`` of ``(L~, dL/ds, F)`` of one circuit at the gap cell ``cell``
        (:meth:`_gap_cell`) and current ``i`` from the per-cell table (MX expressions;
        :func:`~maglevkit.reduced.tables.cell_lookup`)."""
        return cell_lookup(cell, i, p, table, self._degree, maps)[0]

    def _circuit_expressions(self, i: Any, s: Any, u: Any, sd: Any, p: Any, table: Any,
                             cell: tuple[Any, Any] | None = None) -> tuple[Any, Any, Any, Any]:
        """Eq. 8 of one circuit as MX expressions: ``(dI_L/dt, I, F, L~)``."""
        lt, dl, f = self._lookup(self._gap_cell(s, p) if cell is None else cell, i, p, table)
        r_el, a = p[7], p[8]
        if self.freewheel:
            u = eq8_freewheel_voltage(i, u, r_el, a)
        return eq8_rhs(i, u, sd, lt, dl, r_el, a), eq8_coil_current(i, u, r_el, a), f, lt

    def _ladder_rhs(self, i: Any, ie: Any, u: Any, sd: Any, lt: Any, dl: Any,
                    p: Any) -> tuple[Any, Any]:
        """``(dI_L/dt, dI_e/dt)`` of one circuit of a bank with ladder members: the
        shielded-gap ladder (:func:`eq8_shielded_gap_rhs`) where ``p``'s row
        ``motion_eddy`` is 1, else eq. 8 with ``dI_e/dt = 0`` (CasADi ``if_else``
        selects one of the two exactly)."""
        r_el, a = p[7], p[8]
        me, r_2, l_u, beta = p[_N_PAR], p[_N_PAR + 1], p[_N_PAR + 2], p[_N_PAR + 3]
        u = self._ladder_voltage(i, ie, u, p)
        d_il, d_ie = eq8_shielded_gap_rhs(i, ie, u, sd, lt, dl, r_el, a, r_2, l_u, beta)
        return (ca.if_else(me > 0, d_il, eq8_rhs(i, u, sd, lt, dl, r_el, a)),
                ca.if_else(me > 0, d_ie, 0.0))

    def _ladder_voltage(self, i: Any, ie: Any, u: Any, p: Any) -> Any:
        """The voltage a circuit of a bank with ladder members applies: ``U`` as given, or
        behind the chopper's freewheeling diodes (``freewheel``,
        :func:`shielded_gap_freewheel_voltage`: eq. 8's diode law of the current
        ``I_L + I_e`` through ``R_a``'s node, with ``R_a`` from row ``a``; ``I_e = 0`` in
        eq. 8 circuits: eq. 8's own limit)."""
        return shielded_gap_freewheel_voltage(i, ie, u, p[7], p[8]) if self.freewheel else u

    def _eddy_tuple(self, ie: Any) -> tuple[Any, ...]:
        """A circuit's ladder eddy states as scalars, ``(I_e,)`` or ``(I_e1, I_e2)``, from
        the MX of :attr:`n_eddy_states` elements."""
        return (ie,) if self.n_eddy_states == 1 else tuple(ie[k] for k in
                                                            range(self.n_eddy_states))

    def _select(self, me: Any, laws: dict[int, tuple[Any, ...]]) -> tuple[Any, ...]:
        """The law of the circuit's kind ``me`` (row ``motion_eddy``: 0, 1, 2) among the
        ``laws`` present in the bank (CasADi ``if_else`` picks one exactly; a bank with
        one kind evaluates that one alone)."""
        kinds = sorted(laws)
        out = laws[kinds[0]]
        for k in kinds[1:]:
            out = tuple(ca.if_else(me > k - 0.5, a, b)
                        for a, b in zip(laws[k], out, strict=True))
        return out

    def _eddy_law(self, i: Any, e: tuple[Any, ...], u: Any, sd: Any, lt: Any, dl: Any,
                  p: Any) -> tuple[Any, ...]:
        """``(dI_L/dt, dI_e/dt)`` (:meth:`_ladder_rhs`) or, in a bank with three-state
        members, ``(dI_L/dt, dI_e1/dt, dI_e2/dt)`` of one circuit: the three-state ladder
        (:func:`eq8_shielded_gap3_rhs`) where row ``motion_eddy`` is 2, the two-state one
        (``I_e1`` its ``I_e``, ``dI_e2/dt = 0``) where it is 1, eq. 8 where it is 0."""
        if 3 in self._laws:
            return self._network_law(i, e, u, sd, lt, dl, p)
        if self.n_eddy_states == 1:
            return self._ladder_rhs(i, e[0], u, sd, lt, dl, p)
        e1, e2 = e
        r_el, a = p[7], p[8]
        me, r_2, l_u, beta = p[_N_PAR], p[_N_PAR + 1], p[_N_PAR + 2], p[_N_PAR + 3]
        n3 = _N_PAR + len(MOTION_EDDY_PARAMETERS)
        r_3, l_2, beta_2 = p[n3], p[n3 + 1], p[n3 + 2]
        u = self._eddy_voltage(i, e, u, p)
        laws: dict[int, tuple[Any, ...]] = {}
        if 0 in self._laws:
            laws[0] = (eq8_rhs(i, u, sd, lt, dl, r_el, a), 0.0, 0.0)
        if 1 in self._laws:
            laws[1] = (*eq8_shielded_gap_rhs(i, e1, u, sd, lt, dl, r_el, a, r_2, l_u, beta),
                       0.0)
        laws[2] = eq8_shielded_gap3_rhs(i, e1, e2, u, sd, lt, dl, r_el, a, r_2, l_u, r_3, l_2,
                                        beta, beta_2)
        return self._select(me, laws)

    def _network_law(self, i: Any, e: tuple[Any, ...], u: Any, sd: Any, lt: Any, dl: Any,
                     p: Any) -> tuple[Any, ...]:
        """``(dI_L/dt, dI_1/dt, ..., dI_ne/dt)`` of one circuit of a bank with eddy-network
        members: the eddy network (:func:`eddy_network_rhs`, its first ``m`` states; the
        others' rates 0 where the circuit has fewer branches) where row ``motion_eddy`` is
        3, the ladders and eq. 8 elsewhere (their unused states' rates 0).  Behind the
        chopper's diodes (``freewheel``) every law sees :meth:`_network_voltage`."""
        ne = self.n_eddy_states
        r_el, a = p[7], p[8]
        u = self._network_voltage(i, e, u, p)
        me, r_2, l_u, beta = p[_N_PAR], p[_N_PAR + 1], p[_N_PAR + 2], p[_N_PAR + 3]
        zeros = (0.0,) * ne
        laws: dict[int, tuple[Any, ...]] = {}
        if 0 in self._laws:
            laws[0] = (eq8_rhs(i, u, sd, lt, dl, r_el, a), *zeros)
        if 1 in self._laws:
            laws[1] = (*eq8_shielded_gap_rhs(i, e[0], u, sd, lt, dl, r_el, a, r_2, l_u, beta),
                       *zeros[1:])
        if 2 in self._laws:
            n3 = _N_PAR + len(MOTION_EDDY_PARAMETERS)
            laws[2] = (*eq8_shielded_gap3_rhs(i, e[0], e[1], u, sd, lt, dl, r_el, a, r_2, l_u,
                                              p[n3], p[n3 + 1], beta, p[n3 + 2]), *zeros[2:])
        q = self._net_row
        modes, l_ref = p[q], p[q + 1]
        r_k = [p[q + 2 + k] for k in range(ne)]
        l_k = [p[q + 2 + ne + k] for k in range(ne)]
        d_il, d_k = eddy_network_rhs(i, e, u, sd, lt, dl, r_el, a, r_k, l_k, l_ref)
        if self._mixed_modes:
            # a circuit with m < n_e branches: the last ones switched off (their currents
            # start at 0 and stay there, so that the sums above add exact zeros)
            d_k = tuple(ca.if_else(modes > k + 0.5, d, 0.0) if k else d
                        for k, d in enumerate(d_k))
        laws[3] = (d_il, *d_k)
        return self._select(me, laws)

    def _network_voltage(self, i: Any, e: tuple[Any, ...], u: Any, p: Any) -> Any:
        """The voltage a circuit of a bank with eddy-network members applies: ``U`` as
        given, or behind the chopper's diodes (``freewheel``) eq. 8's diode law of the
        terminal current ``I_L + sum_k e_k`` (:func:`eddy_network_freewheel_voltage`).  The
        same expression as the ladders' (:meth:`_eddy_voltage`) and eq. 8's in their
        circuits, whose unused eddy states hold exact zeros."""
        return eddy_network_freewheel_voltage(i, e, u, p[7], p[8]) if self.freewheel else u

    def _terminal_current(self, i: Any, e: tuple[Any, ...]) -> Any:
        """The current through ``R_a``'s node, ``I_L + I_e`` (``I_u = I_L + I_e1 + I_e2``
        with three states; ``I_L + sum_k I_k`` of the eddy network), whose coil current
        and diode law are eq. 8's."""
        out = i + e[0]
        for v in e[1:]:
            out = out + v
        return out

    def _eddy_voltage(self, i: Any, e: tuple[Any, ...], u: Any, p: Any) -> Any:
        """:meth:`_ladder_voltage` with the terminal current of :meth:`_terminal_current`
        (the diode law of :func:`shielded_gap_freewheel_voltage` for both ladders)."""
        if len(e) == 1:
            return self._ladder_voltage(i, e[0], u, p)
        return (shielded_gap_freewheel_voltage(self._terminal_current(i, e[:-1]), e[-1], u,
                                               p[7], p[8])
                if self.freewheel else u)

    def _eddy_coil(self, i: Any, e: tuple[Any, ...], u: Any, p: Any) -> Any:
        """The coil current of Fig. 8 with the terminal current through ``R_a``'s node
        (:func:`eddy_network_coil_current` in eddy-network circuits, selected per circuit
        as the law)."""
        if 3 in self._laws:
            u_eff = self._network_voltage(i, e, u, p)
            laws: dict[int, tuple[Any, ...]] = {3: (eddy_network_coil_current(i, e, u_eff, p[7],
                                                                                p[8]),)}
            if set(self._laws) - {3}:
                laws[0] = (eq8_coil_current(self._terminal_current(i, e), u_eff, p[7], p[8]),)
            return self._select(p[_N_PAR], laws)[0]
        return eq8_coil_current(self._terminal_current(i, e), self._eddy_voltage(i, e, u, p),
                                p[7], p[8])

    def _force_current(self, i: Any, e: tuple[Any, ...], p: Any) -> Any:
        """The current at which a circuit of a ladder bank reads its force map: ``I_L +
        gamma I_e`` (:func:`shielded_gap_force_current`; ``gamma`` 0 in eq. 8 circuits,
        whose eddy states stay 0), with three states ``I_L + c_1 I_e1 + c_2 I_e2``
        (:func:`~maglevkit.reduction.motion_eddy.ladder3_force_current`)."""
        if 3 in self._laws:
            # the eddy network reads the force map at I_L (CurrentModel's F(s, I_L))
            laws: dict[int, tuple[Any, ...]] = {3: (i,)}
            if 0 in self._laws or 1 in self._laws:
                laws[1] = (shielded_gap_force_current(i, e[0], p[_N_PAR + 4]),)
            if 2 in self._laws:
                laws[2] = (ladder3_force_current(
                    i + e[0] + e[1], i + e[0], i,
                    (p[_N_PAR + 4], p[_N_PAR + len(MOTION_EDDY_PARAMETERS) + 3])),)
            return self._select(p[_N_PAR], laws)[0]
        if len(e) == 1:
            return shielded_gap_force_current(i, e[0], p[_N_PAR + 4])
        e1, e2 = e
        c_2 = p[_N_PAR + len(MOTION_EDDY_PARAMETERS) + 3]
        laws = {}
        if 0 in self._laws or 1 in self._laws:
            laws[1] = (shielded_gap_force_current(i, e1, p[_N_PAR + 4]),)
        laws[2] = (ladder3_force_current(i + e1 + e2, i + e1, i, (p[_N_PAR + 4], c_2)),)
        return self._select(p[_N_PAR], laws)[0]

    def _eddy_force(self, cell: tuple[Any, Any], i_f: Any, p: Any, table: Any) -> Any:
        """The force of one circuit at the gap cell ``cell`` and the force current
        ``i_f`` (:meth:`_force_current`)."""
        return self._lookup(cell, i_f, p, table, maps=(2,))[0]

    def _make_circuit_kernel(self) -> dict[str, ca.Function]:
        """Single-circuit functions: right-hand side, outputs (MX, table embedded)."""
        table = ca.MX(ca.DM(self._table))
        i, s, u, sd = (ca.MX.sym(n) for n in ("I_L", "s", "U", "sdot"))
        if self._has_eddy:
            ne = self.n_eddy_states
            p = ca.MX.sym("p", self._par.shape[0])
            ie = ca.MX.sym("I_e", ne) if ne > 1 else ca.MX.sym("I_e")
            e = self._eddy_tuple(ie)
            cell = self._gap_cell(s, p)
            lt, dl = self._lookup(cell, i, p, table, maps=(0, 1))
            d = self._eddy_law(i, e, u, sd, lt, dl, p)
            # the coil current of Fig. 8 with the terminal current I_L + I_e (I_L + I_e1 +
            # I_e2) through R_a's node (the eddy states are 0 in eq. 8 circuits)
            coil = self._eddy_coil(i, e, u, p)
            f = self._eddy_force(cell, self._force_current(i, e, p), p, table)
            d_e = d[1] if ne == 1 else ca.vertcat(*d[1:])
            return {"rhs": ca.Function("bank_circuit_rhs", [i, s, u, sd, p, ie], [d[0], d_e]),
                    "out": ca.Function("bank_circuit_out", [i, s, u, p, ie], [coil, f, lt])}
        p = ca.MX.sym("p", _N_PAR)
        rhs, coil, f, lt = self._circuit_expressions(i, s, u, sd, p, table)
        return {"rhs": ca.Function("bank_circuit_rhs", [i, s, u, sd, p], [rhs]),
                "out": ca.Function("bank_circuit_out", [i, s, u, p], [coil, f, lt])}

    def circuit_step_function(self, substeps: int = 1) -> ca.Function:
        """The bank's RK4 step of one reduced circuit, with its parameters as an input.

        ``(I_L, s, U, sdot, h, p) -> (I_L', I, F, I_min, I_max, bad)``: ``substeps``
        classical RK4 sub-steps of eq. 8 over ``h`` [s] with the gap moving linearly from
        ``s`` at ``sdot``; ``I``, ``F`` at the end (gap ``s + sdot h``); ``I_min``/``I_max``
        the extremes of ``I_L`` over the sub-step ends; ``bad`` is the circuit's reason
        code, a sum of :class:`StepFlag` bits (0: a good step; the gap path or a sub-step
        current leaving the map range, an input or the result not finite).  ``p`` is one
        column of :attr:`circuit_parameters` (rows :data:`KERNEL_PARAMETERS`; change
        ``R_el`` and ``a`` there to tune the resistances).  The table of every distinct map
        is embedded as a constant.  :meth:`step` maps this function over the circuits.

        Parameters
        ----------
        substeps : int, default 1
            Number of equal RK4 sub-steps over ``h``, a whole number >= 1 (no bools).

        Returns
        -------
        casadi.Function

        Raises
        ------
        InputError
            ``substeps`` not a whole number >= 1.
        """
        if not (isinstance(substeps, int) and not isinstance(substeps, bool) and substeps >= 1):
            raise InputError(f"substeps = {substeps!r} must be a whole number >= 1")
        if self._has_eddy:
            return self._ladder_step_function(substeps)
        table = ca.MX(ca.DM(self._table))
        i, s, u, sd, h = (ca.MX.sym(n) for n in ("I_L", "s", "U", "sdot", "h"))
        p = ca.MX.sym("p", _N_PAR)
        hs = h / substeps

        r_el, a = p[7], p[8]
        # the current's cell of the first stage is the guess of every later lookup's
        # (cell_lookup's hint: the same values, a shorter chain in the lanes' C)
        hint: list[Any] = []

        def f(x: Any, cell: tuple[Any, Any]) -> Any:
            # the stages need L~ and dL/ds only (the gather of F would be wasted)
            (lt, dl), k = cell_lookup(cell, x, p, table, self._degree, (0, 1),
                                      hint=hint[0] if hint else None)
            hint[:] = hint or [k]
            return eq8_rhs(x, eq8_freewheel_voltage(x, u, r_el, a) if self.freewheel else u,
                           sd, lt, dl, r_el, a)

        x, lo, hi = self._rk4_substeps(i, lambda v: v, f, s, sd, hs, substeps, p)
        se = s + sd * h
        coil = eq8_coil_current(x, eq8_freewheel_voltage(x, u, r_el, a) if self.freewheel
                                else u, r_el, a)
        force = cell_lookup(self._gap_cell(se, p), x, p, table, self._degree, (2,),
                            hint=hint[0])[0][0]
        bad = _reason_code(s, se, sd, u, lo, hi, (x,), p)
        return ca.Function("bank_circuit_step", [i, s, u, sd, h, p],
                           [x, coil, force, lo, hi, bad],
                           ["I_L", "s", "U", "sdot", "h", "p"],
                           ["I_L_next", "I", "F", "I_L_min", "I_L_max", "bad"])

    def _rk4_substeps(self, x: Any, current: Callable[[Any], Any], f: Callable[..., Any],
                  s: Any, sd: Any, hs: Any, substeps: int, p: Any) -> tuple[Any, Any, Any]:
        """The RK4 sub-steps of one circuit step, for eq. 8 and the ladder alike: the
        state ``x`` after ``substeps`` steps of ``hs`` with the one RK4, ``f(x, cell=)``
        evaluated at the stage gaps of each sub-step (start, middle (k2 and k3 share it),
        end; the end of one sub-step is the start of the next), and the extremes of the
        inductor current ``current(x)`` over the sub-step ends (the range flags)."""
        lo: Any = current(x)
        hi: Any = current(x)
        cell_start = self._gap_cell(s, p)
        for k in range(substeps):
            sk = s + sd * (k * hs)
            cell_mid = self._gap_cell(sk + sd * (hs / 2), p)
            cell_end = self._gap_cell(sk + sd * hs, p)
            x = rk4_substep(x, hs, partial(f, cell=cell_start), partial(f, cell=cell_mid),
                            partial(f, cell=cell_end))
            lo = ca.fmin(lo, current(x))
            hi = ca.fmax(hi, current(x))
            cell_start = cell_end
        return x, lo, hi

    def _ladder_step_function(self, substeps: int) -> ca.Function:
        """:meth:`circuit_step_function` of a bank with ladder members: the state
        ``[I_L; I_e]`` of every circuit (``I_e`` stays 0 in eq. 8 circuits), one more
        input ``I_e`` and output ``I_e_next`` after the others; with three-state members
        (:attr:`n_eddy_states` 2) the input ``I_e`` has two elements ``(I_e1, I_e2)`` and
        the outputs are ``I_e1_next``, ``I_e2_next`` (scalars, for the SIMD lanes).  The
        force current is read from the force map at the end: it is range-checked with
        ``I_L`` (folded into ``I_L_min``/``I_L_max``, equal to ``I_L``'s extremes where
        the force current is ``I_L``)."""
        table = ca.MX(ca.DM(self._table))
        i, s, u, sd, h = (ca.MX.sym(n) for n in ("I_L", "s", "U", "sdot", "h"))
        ne = self.n_eddy_states
        ie = ca.MX.sym("I_e", ne) if ne > 1 else ca.MX.sym("I_e")
        p = ca.MX.sym("p", self._par.shape[0])
        hs = h / substeps

        def f(x: Any, cell: tuple[Any, Any]) -> Any:
            lt, dl = self._lookup(cell, x[0], p, table, maps=(0, 1))
            return _Pair(*self._eddy_law(x[0], x.v[1:], u, sd, lt, dl, p))

        # the state as scalars (not a vertcat), so that the graph stays scalar and the
        # SIMD lanes translate it; the arithmetic per component is the same
        x, lo, hi = self._rk4_substeps(_Pair(i, *self._eddy_tuple(ie)), lambda v: v[0], f, s,
                                       sd, hs, substeps, p)
        se = s + sd * h
        e = x.v[1:]
        coil = self._eddy_coil(x[0], e, u, p)
        i_f = self._force_current(x[0], e, p)
        force = self._eddy_force(self._gap_cell(se, p), i_f, p, table)
        lo, hi = ca.fmin(lo, i_f), ca.fmax(hi, i_f)
        bad = _reason_code(s, se, sd, u, lo, hi, x.v, p)
        return ca.Function("bank_circuit_step", [i, s, u, sd, h, p, ie],
                           [x[0], coil, force, lo, hi, bad, *e],
                           ["I_L", "s", "U", "sdot", "h", "p", "I_e"],
                           ["I_L_next", "I", "F", "I_L_min", "I_L_max", "bad"]
                           + (["I_e_next"] if ne == 1 else
                              [f"I_e{k + 1}_next" for k in range(ne)]))

    def _step_kernel(self, substeps: int) -> ca.Function:
        """One RK4 step of every reduced circuit: ``(I_L, s, U, sdot, h) -> (I_L', I, F,
        I_min, I_max, n_bad)``.

        :meth:`circuit_step_function` mapped over the circuits (a serial loop); the
        gap moves linearly (exact); ``I_min``/``I_max`` are the extremes of the
        current over the sub-step ends; ``n_bad`` counts circuits with a gap or current
        outside their map's range (start, end and every sub-step) or a non-finite value,
        so that the caller checks one number (and diagnoses only when it is > 0);
        ``flags``: the reason code of every circuit (:class:`StepFlag` bits).
        Everything is inlined into one expression graph (no nested calls).  ``s_next``:
        the gaps at the end of the step, ``s + sdot h``.
        """
        one = self.circuit_step_function(substeps)
        n = self._reduced_idx.size
        mapped = one.map(n, "serial")
        vi, vs, vu, vsd = (ca.MX.sym(nm, n) for nm in ("I_L", "s", "U", "sdot"))
        vh = ca.MX.sym("h")
        if self._has_eddy:
            ve = ca.MX.sym("I_e", n, self.n_eddy_states)
            res = mapped(vi.T, vs.T, vu.T, vsd.T, vh, ca.DM(self._par), ve.T)
        else:
            res = mapped(vi.T, vs.T, vu.T, vsd.T, vh, ca.DM(self._par))
        # member totals of the reduced circuits' forces (sparse 0/1 matrix)
        rows = self._member_of[self._reduced_idx]
        summ = ca.DM(ca.Sparsity.triplet(len(self._members), n, rows.tolist(), list(range(n))),
                     1.0)
        outs = ([r.T for r in res[:3]]
                + [ca.densify(ca.mtimes(summ, res[2].T)), ca.sum2(res[5] > 0)]
                + [res[3].T, res[4].T, vs + vsd * vh, res[5].T])
        names = ["I_L_next", "I", "F", "member_F", "n_bad", "I_L_min", "I_L_max", "s_next",
                 "flags"]
        if self._has_eddy:
            # the ladder's eddy states after the others (the layout of eq. 8 banks stays):
            # (n, n_e), column-major as CasADi stores it (I_e1 of every circuit, then I_e2)
            e_next = res[6].T if self.n_eddy_states == 1 else ca.horzcat(*(r.T for r in res[6:]))
            return ca.Function(f"maglevkit_bank_step{substeps}", [vi, vs, vu, vsd, vh, ve],
                               outs + [e_next], ["I_L", "s", "U", "sdot", "h", "I_e"],
                               names + ["I_e_next"])
        return ca.Function(f"maglevkit_bank_step{substeps}", [vi, vs, vu, vsd, vh],
                           outs, ["I_L", "s", "U", "sdot", "h"], names)

    # ------------------------------------------------------------------ public model pieces
    @property
    def table(self) -> np.ndarray:
        """The per-cell coefficients of every distinct map, one flat array (read-only)."""
        view = self._table.view()
        view.flags.writeable = False
        return view

    @property
    def circuit_parameters(self) -> np.ndarray:
        """(13, n_reduced) parameter column ``p`` of every reduced circuit for
        :meth:`circuit_step_function` and :attr:`circuit_output_function` (rows
        :data:`KERNEL_PARAMETERS`: grid, table offset, ``R_el`` [ohm], ``a = 1 + R_el/R_ec``
        and the range bounds with their rounding allowances; in a bank with ladder members
        18 rows, :data:`MOTION_EDDY_PARAMETERS` appended, then
        :data:`MOTION_EDDY3_PARAMETERS` with three-state members and
        :data:`EDDY_NETWORK_PARAMETERS` with ``R_k``, ``L_k`` rows with eddy-network
        members)."""
        return self._par.copy()

    @property
    def circuit_output_function(self) -> ca.Function:
        """Outputs of one reduced circuit ``(I_L, s, U, p) -> (I, F, L~)`` (CasADi, table
        embedded; ``p`` a column of :attr:`circuit_parameters`)."""
        return self._circuit_kernel["out"]

    @property
    def map_ranges(self) -> np.ndarray:
        """(4, n_reduced) gap and current ranges of each reduced circuit's maps:
        rows ``s_min, s_max`` [m], ``I_min, I_max`` [A]."""
        return self._bounds.copy()

    @property
    def members(self) -> tuple[tuple[str, str, Any], ...]:
        """``(name, kind, model)`` per member: kind ``"reduced"`` (model: its maps) or
        ``"detailed"`` (model: its FluxModel)."""
        return tuple((m.name, m.kind, m.maps if m.kind == "reduced" else m.model)
                     for m in self._members)

    def ladder_expressions(self, k: int, i_l: Any, i_e: Any, s: Any, u: Any, gap_rate: Any,
                           table: Any) -> tuple[Any, Any, Any, Any, Any]:
        """The law of reduced circuit ``k`` of a bank with ladder members (``motion_eddy``)
        as CasADi expressions ``(dI_L/dt, dI_e/dt, I, F, L~)``: the shielded-gap ladder in
        ladder circuits, eq. 8 with ``dI_e/dt = 0`` in the others (the kernel's own
        expressions; :meth:`circuit_expressions` is eq. 8's).  In a bank with three-state
        members (:attr:`n_eddy_states` 2) ``i_e`` and ``dI_e/dt`` have two elements,
        ``(I_e1, I_e2)``: the three-state ladder in its circuits, the two-state one (with
        ``I_e1`` as its ``I_e``, ``dI_e2/dt = 0``) and eq. 8 in the others.  In a bank
        with eddy-network members (``eddy_modes``) ``i_e`` has :attr:`n_eddy_states`
        elements, the branch currents ``I_k`` (:func:`eddy_network_rhs` in their circuits).

        Parameters
        ----------
        k : int
            Column of the reduced circuit in :attr:`circuit_parameters`.
        i_l : casadi.MX
            Inductor current ``I_L`` [A].
        i_e : casadi.MX
            Shielding eddy current ``I_e`` [A] (:attr:`n_eddy_states` elements).
        s : casadi.MX
            Substitute gap [m].
        u : casadi.MX
            Circuit voltage [V].
        gap_rate : casadi.MX
            Substitute gap rate ``ds/dt`` [m/s].
        table : casadi.MX or DM
            The bank's map table (:attr:`table`), symbolic or constant.

        Returns
        -------
        tuple of casadi.MX
            ``dI_L/dt`` [A/s], ``dI_e/dt`` [A/s] (as ``i_e``), coil current ``I`` [A],
            force ``F`` [N] and ``L~`` [H].

        Raises
        ------
        InputError
            A bank without ladder members (use :meth:`circuit_expressions`).
        """
        if not self._has_eddy:
            raise InputError("ladder_expressions needs a bank with shielded-gap ladder "
                             "members (motion_eddy) or eddy-network members (eddy_modes); "
                             "this bank is eq. 8's: use circuit_expressions")
        p = ca.DM(self._par[:, k])
        cell = self._gap_cell(s, p)
        lt, dl = self._lookup(cell, i_l, p, table, maps=(0, 1))
        e = self._eddy_tuple(i_e)
        d = self._eddy_law(i_l, e, u, gap_rate, lt, dl, p)
        return (d[0], d[1] if len(e) == 1 else ca.vertcat(*d[1:]),
                self._eddy_coil(i_l, e, u, p),
                self._eddy_force(cell, self._force_current(i_l, e, p), p, table), lt)

    def circuit_expressions(self, k: int, i_l: Any, s: Any, u: Any, gap_rate: Any,
                            table: Any) -> tuple[Any, Any, Any, Any]:
        """Eq. 8 of reduced circuit ``k`` as CasADi expressions ``(dI_L/dt, I, F, L~)``.

        ``table`` is :attr:`table` as a CasADi symbol (a function input, so that CasADi's
        virtual machine does not copy the constant on every call) or as a constant.  The
        same expressions as :attr:`ode_function` and the compiled step.

        Parameters
        ----------
        k : int
            Column of the reduced circuit in :attr:`circuit_parameters` (0-based index over
            the bank's reduced circuits, not checked beyond NumPy's indexing).
        i_l : casadi.MX
            Inductor current ``I_L`` [A].
        s : casadi.MX
            Substitute gap [m].
        u : casadi.MX
            Circuit voltage [V].
        gap_rate : casadi.MX
            Substitute gap rate ``ds/dt`` [m/s].
        table : casadi.MX or DM
            The bank's map table (:attr:`table`), symbolic or constant.

        Returns
        -------
        tuple of casadi.MX
            ``dI_L/dt`` [A/s], coil current ``I`` [A], force ``F`` [N] and ``L~`` [H].
        """
        if self._has_eddy:
            raise InputError("circuit_expressions is eq. 8's one state per circuit; this bank "
                             "has shielded-gap ladder members (motion_eddy) or eddy-network "
                             "members (eddy_modes) with eddy states: use ladder_expressions")
        p = ca.DM(self._par[:, k])
        return self._circuit_expressions(i_l, s, u, gap_rate, p, table)

    @property
    def ode_function(self) -> ca.Function:
        """Eq. 8 of every reduced circuit: ``(I_L, U, s, sdot) -> dI_L/dt`` (CasADi, arrays
        over the reduced circuits, ``s`` the substitute gaps); differentiable (AD) and
        code-generatable, for vehicle models, linearisation and MPC."""
        n = self._reduced_idx.size
        vi, vu, vs, vsd = (ca.MX.sym(nm, n) for nm in ("I_L", "U", "s", "sdot"))
        f = self._circuit_kernel["rhs"].map(n, "serial")
        if self._has_eddy:
            ve = ca.MX.sym("I_e", n, self.n_eddy_states)
            d_il, d_ie = f(vi.T, vs.T, vu.T, vsd.T, ca.DM(self._par), ve.T)
            return ca.Function("maglevkit_bank_ode", [vi, vu, vs, vsd, ve], [d_il.T, d_ie.T],
                               ["I_L", "U", "s", "sdot", "I_e"], ["dI_L", "dI_e"])
        return ca.Function("maglevkit_bank_ode", [vi, vu, vs, vsd],
                           [f(vi.T, vs.T, vu.T, vsd.T, ca.DM(self._par)).T],
                           ["I_L", "U", "s", "sdot"], ["dI_L"])

    @property
    def output_function(self) -> ca.Function:
        """Outputs of every reduced circuit: ``(I_L, U, s) -> (I, F, L~)`` (CasADi)."""
        n = self._reduced_idx.size
        vi, vu, vs = (ca.MX.sym(nm, n) for nm in ("I_L", "U", "s"))
        if self._has_eddy:
            ve = ca.MX.sym("I_e", n, self.n_eddy_states)
            res = self._circuit_kernel["out"].map(n, "serial")(vi.T, vs.T, vu.T,
                                                                ca.DM(self._par), ve.T)
            return ca.Function("maglevkit_bank_outputs", [vi, vu, vs, ve], [r.T for r in res],
                               ["I_L", "U", "s", "I_e"], ["I", "F", "Ltilde"])
        res = self._circuit_kernel["out"].map(n, "serial")(vi.T, vs.T, vu.T, ca.DM(self._par))
        return ca.Function("maglevkit_bank_outputs", [vi, vu, vs], [r.T for r in res],
                           ["I_L", "U", "s"], ["I", "F", "Ltilde"])

    def _outputs_inlined(self) -> ca.Function:
        """:attr:`output_function` with every circuit's outputs inlined into one graph and
        the parameters an input (``(I_L, U, s[, I_e], p) -> (I, F, L~)``, ``p`` the
        :attr:`circuit_parameters`), built once: what :meth:`outputs` evaluates on CasADi's
        virtual machine.  The machine copies a function's constants into its work vector at
        every call, so the mapped circuit function copied the table once per circuit (11 ms
        per call for the 50 circuits of the TR09 vehicle, whose table holds 349 440
        coefficients; every vehicle run with eddy states made this call); inlined, the
        table is one node, copied once (0.7 ms).  The instructions per circuit are the
        mapped function's, so the results are the same bits.  Building it costs about as
        much as one or two mapped calls of the vehicle's bank (16 ms; 0.3 ms per circuit,
        0.2 s for 1000), so :meth:`outputs` maps on its first call and takes this from
        the second on (a vehicle's later runs, a stepper built again)."""
        if self._inlined_outputs is None:
            n = self._reduced_idx.size
            vi, vu, vs = (ca.MX.sym(nm, n) for nm in ("I_L", "U", "s"))
            par = ca.MX.sym("p", *self._par.shape)
            ins = [vi, vu, vs]
            ve = ca.MX.sym("I_e", n, self.n_eddy_states) if self._has_eddy else None
            if ve is not None:
                ins.append(ve)
            out = self._circuit_kernel["out"]
            cols: list[list[Any]] = [[], [], []]
            for k in range(n):
                args = [vi[k], vs[k], vu[k], par[:, k]] + ([] if ve is None else [ve[k, :].T])
                for col, r in zip(cols, out.call(args, True, False), strict=True):
                    col.append(r)
            self._inlined_outputs = ca.Function("maglevkit_bank_outputs_inlined", [*ins, par],
                                                [ca.vertcat(*c) for c in cols])
        return self._inlined_outputs

    @renamed_keywords(dt="dt_s")
    def step_function(self, dt_s: float) -> ca.Function:
        """The step of every reduced circuit over ``dt`` [s] as an uncompiled CasADi
        function, for composing larger compiled models (the vehicle step).

        The same function the compiled :meth:`step` runs, with inputs ``I_L``, ``s``,
        ``U``, ``sdot`` (arrays over the circuits), ``h`` (= ``dt``) and outputs named
        ``I_L_next``, ``I``, ``F``, ``member_F``, ``n_bad`` (count of circuits out of
        range or not finite; diagnose with :meth:`step`) and more; address them by
        name.  Only for banks of reduced members with one gap input per circuit.  A bank
        with ladder members (:attr:`motion_eddy`) has one more input, ``I_e``, and one
        more output, ``I_e_next``, after the others.

        Old keyword names (``dt``) are deprecated aliases for one release.

        Parameters
        ----------
        dt_s : float
            Step length [s], finite and > 0; it sets the RK4 sub-step count
            (``ceil(dt / max_step_s)``), while the function's ``h`` input is the step used.

        Returns
        -------
        casadi.Function

        Raises
        ------
        InputError
            A bad ``dt``, or a bank with detailed members or ``gap_inputs="pole"``.
        """
        return self._step_kernel(self._composable_substeps(dt_s, "step_function"))

    @renamed_keywords(dt="dt_s")
    def step_kernel(self, dt_s: float) -> ca.Function:
        """The compiled step that :meth:`step` calls for steps of ``dt`` [s] (lanes or
        CasADi code, or CasADi's virtual machine, by ``compiled`` and ``codegen``).

        Inputs and outputs as :meth:`step_function` (``n_bad`` > 0: a circuit left its
        maps or a value was not finite, ``flags`` says why per circuit; diagnose with
        :meth:`step`).  Banks of reduced members with one gap input per circuit only.

        Old keyword names (``dt``) are deprecated aliases for one release.

        Parameters
        ----------
        dt_s : float
            Step length [s] (> 0); steps with the same RK4 sub-step count share a kernel.

        Returns
        -------
        casadi.Function
        """
        self._composable_substeps(dt_s, "step_kernel")
        return self._kernel(float(dt_s)).f

    def run_steps(self, inductor_currents_A: Any, gaps_m: Any, voltages_V: Any,
                  gap_rates_m_per_s: Any, dt_s: Any, *, time_s: float = 0.0,
                  stop_at_flag: bool = False) -> BankRun:
        """Advance every circuit over ``n_steps`` steps in one compiled time loop.

        The same compiled step as :meth:`step` (bit-identical results) with the loop over
        the steps in C (:mod:`.lanes`; without a compiler or with ``codegen="casadi"`` a
        CasADi ``mapaccum`` of the step), :data:`RUN_CHUNK` steps per call.  Banks of
        reduced members with one gap input per circuit only, on eq. 8: the loop carries
        ``I_L`` alone, so a bank with more states per circuit (shielded-gap ladder or
        eddy-network members) is refused rather than run without them; its
        :meth:`step` and :meth:`stepper` carry them, and ``CurrentModel(maps,
        eddy_modes=m)`` runs its own compiled loop that does (docs/bank.md).

        Parameters
        ----------
        inductor_currents_A : array (n_circuits,)
            ``I_L`` at the start [A].
        gaps_m, voltages_V, gap_rates_m_per_s : array (n_steps, n_circuits)
            Gap at the start of each step [m], voltage held over it [V] and gap rate over it
            [m/s] (the gap moves linearly); the caller keeps the gaps consistent
            (``gaps_m[k + 1] = gaps_m[k] + gap_rates_m_per_s[k] dt_s[k]`` for a
            continuous path).
        dt_s : array (n_steps,)
            Step lengths [s] (>= 0; a step of 0 s gives the outputs at its start).  Runs
            of steps with the same RK4 sub-step count share one compiled loop.
        time_s : float
            Time at the start [s] (for messages).
        stop_at_flag : bool
            False (default): a step the kernel flags (out of the maps, non-finite) is
            diagnosed as :meth:`step` diagnoses it (raises, or warns with
            ``extrapolate``); True: the run stops there (``n_good``) for the caller to
            handle.

        Returns
        -------
        BankRun

        Raises
        ------
        InputError
            Not a bank of reduced members with circuit gap inputs, members with eddy
            states (``motion_eddy``, ``eddy_modes``), bad shapes or step lengths.
        OutOfRangeError, SolverError
            As :meth:`step`.
        """
        if not self._fast:
            raise InputError("run_steps needs a bank of reduced members only with "
                             "gap_inputs='circuit'")
        if self._has_eddy:
            raise InputError("run_steps carries eq. 8's one state per circuit; this bank has "
                             "shielded-gap ladder members (motion_eddy) or eddy-network "
                             "members (eddy_modes): use step or stepper")
        nc = self.n_circuits
        x0 = np.asarray(inductor_currents_A, dtype=float)
        s, u, sd = (np.ascontiguousarray(v, dtype=float) for v in (gaps_m, voltages_V,
                                                                     gap_rates_m_per_s))
        h = np.ascontiguousarray(dt_s, dtype=float).ravel()
        n = h.size
        if x0.shape != (nc,) or any(v.shape != (n, nc) for v in (s, u, sd)):
            raise InputError(f"run_steps: expected I_L ({nc},) and gaps, voltages and gap "
                             f"rates of shape ({n}, {nc}) for {n} steps")
        if n and not (h.min() >= 0.0 and h.max() < math.inf):      # (NaN fails the first)
            raise InputError("run_steps: dt_s must be finite and >= 0 s")
        if 0 < n <= RUN_CHUNK and substep_count(float(h.max()), self.max_step_s) == 1:
            # one chunk of one sub-step per step (the rule is monotone in the step length,
            # so the longest step decides): the loop below with nothing to split
            res = self._run_call(1)(x0, s, u, sd, h)
            if res.n_done == n:
                return BankRun(res.rows[0].copy(), res.rows[1].copy(), res.rows[2].copy(),
                               n_good=n)
        # the sub-step count of every step (a step of 0 s takes one: it changes nothing)
        per = self._substep_counts(h)
        out = [np.full((n, nc), np.nan) for _ in range(3)]
        k, x, t = 0, x0, float(time_s)
        while k < n:
            run = self._run_call(int(per[k]))
            same = np.flatnonzero(per[k:k + RUN_CHUNK] != per[k])
            m = int(same[0]) if same.size else min(RUN_CHUNK, n - k)
            res = run(x, s[k:k + m], u[k:k + m], sd[k:k + m], h[k:k + m])
            done = res.n_done
            for o, r in zip(out, res.rows, strict=True):
                o[k:k + done] = r[:done]
            t_k = t + float(np.sum(h[k:k + done]))
            if done < m:                 # step k + done was flagged
                if stop_at_flag:
                    return BankRun(out[0], out[1], out[2], n_good=k + done)
                j = k + done
                self._diagnose(s[j], sd[j], x if done == 0 else out[0][j - 1], u[j],
                               res.rows[0][done],
                               SimpleNamespace(res=res.extremes),  # type: ignore[arg-type]
                               t_k, t_k + h[j])
                for o, r in zip(out, res.rows, strict=True):    # warned only: accept it
                    o[j] = r[done]
                done += 1
                t_k += float(h[j])
            k += done
            t = t_k
            x = out[0][k - 1]
        return BankRun(out[0], out[1], out[2], n_good=n)

    def _run_call(self, substeps: int) -> _RunCall:
        call = self._runs.get(substeps)
        if call is None:
            self._kernel(self.max_step_s * substeps)         # compiles (lanes or CasADi)
            loop = self._lane_runs.get(substeps)
            call = _RunCall(loop, self._kernels[substeps].f, self._reduced_idx.size)
            self._runs[substeps] = call
        return call

    def _substep_counts(self, dt: np.ndarray) -> np.ndarray:
        """RK4 sub-steps of steps of ``dt`` [s] (at most ``max_step_s`` each; the rule)."""
        return substep_counts(dt, self.max_step_s)

    def _substeps(self, dt: float) -> int:
        """RK4 sub-steps of one step of ``dt`` [s] (:meth:`_substep_counts`)."""
        return int(self._substep_counts(np.array([dt]))[0])

    def _composable_substeps(self, dt: float, what: str) -> int:
        """Sub-steps of ``dt`` for the step functions other models compose (banks of
        reduced members with one gap input per circuit only)."""
        if not self._fast:
            raise InputError(f"{what} needs a bank of reduced members only with "
                             "gap_inputs='circuit'")
        return self._substeps(check_step(dt))

    def _kernel(self, dt: float) -> _StepCall:
        n = self._substeps(dt)
        call = self._kernels.get(n)
        if call is None:
            f = self._lanes_kernel(n) if self.codegen == "lanes" else None
            if f is None:
                f, is_compiled = compile_function(self._step_kernel(n), mode=self.compiled_mode,
                                                  cache_dir=self._cache_dir)
                self.compiled = is_compiled
            call = _StepCall(f, self.n_eddy_states)
            self._kernels[n] = call
        self._last_dt, self._last_call = dt, call
        return call

    def _lanes_kernel(self, substeps: int) -> ca.Function | None:
        """The step of :meth:`_step_kernel` compiled through :mod:`.lanes` (SIMD lanes over
        the circuits), or None where that is not possible (compiled = "never", or no
        working compiler: then the CasADi path decides about warnings and errors)."""
        hit = self._lanes.get(substeps)
        if hit is not None:
            return hit[0]
        if self.compiled_mode == "never" or find_compiler() is None:
            return None
        n = int(self._reduced_idx.size)
        nm = len(self._members)
        width, avx2, flags = lane_target()
        # the C names carry a hash of the source (written with a placeholder name first),
        # so that libraries of different banks never share a symbol
        name = "MAGLEVKIT_LANES_NAME"
        me = int(self._has_eddy)
        ne = self.n_eddy_states
        try:
            kernel = lane_source(self.circuit_step_function(substeps), name=f"{name}_k", n=n,
                                 inputs=[LaneInput("instance")] * 4
                                 + [LaneInput("shared"), LaneInput("baked", self._par)]
                                 + [LaneInput("instance")] * me,
                                 width=width, avx2=avx2, interleave=_LANE_INTERLEAVE)
        except (NotImplementedError, ValueError, KeyError, IndexError):  # pragma: no cover
            return None                  # a graph the generator does not translate
        members = self._member_of[self._reduced_idx]
        # a ladder bank (motion_eddy): input 5 I_e, n_e rows of n (zeros at w + 10n + 1
        # when absent) and output 9 I_e_next, the same layout (the kernel's outputs 7,
        # 8; scratch at w + (10 + n_e) n + 1)
        ladder = (f"  a[5] = arg[5];\n  if (!a[5]) {{ double *z = w + {10 * n + 1}; "
                  f"for (c = 0; c < {ne * n}; ++c) z[c] = 0.0; a[5] = z; }}\n"
                  + "".join(f"  r[{6 + q}] = res[9] ? res[9]{f' + {q * n}' if q else ''} : "
                            f"w + {(10 + ne + q) * n + 1};\n" for q in range(ne))) if me else ""
        body = (f"  static const int member[{n}] = {{{','.join(str(int(m)) for m in members)}}};\n"
                f"  const double *a[{5 + me}];\n  double *r[{6 + ne}];\n  long c;\n  int k;\n"
                f"  for (k = 0; k < 4; ++k) {{ a[k] = arg[k]; if (!a[k]) {{ double *z = w + "
                f"{6 * n} + k * {n}; for (c = 0; c < {n}; ++c) z[c] = 0.0; a[k] = z; }} }}\n"
                f"  a[4] = arg[4] ? arg[4] : w + {10 * n};\n  w[{10 * n}] = 0.0;\n"
                + "".join(f"  r[{j}] = res[{o}] ? res[{o}] : w + {j * n};\n"
                          for j, o in enumerate((0, 1, 2, 5, 6)))
                + f"  r[5] = w + {5 * n};\n" + ladder
                + f"  {name}_k(a, r);\n"
                + f"  if (res[3]) {{ for (k = 0; k < {nm}; ++k) res[3][k] = 0.0;\n"
                + f"    for (c = 0; c < {n}; ++c) res[3][member[c]] += r[2][c]; }}\n"
                + f"  if (res[4]) {{ double nb = 0.0; for (c = 0; c < {n}; ++c) nb += r[5][c] != 0.0; "
                  "res[4][0] = nb; }\n"
                + f"  if (res[7]) for (c = 0; c < {n}; ++c) res[7][c] = a[1][c] + a[3][c] * a[4][0];\n"
                + f"  if (res[8]) for (c = 0; c < {n}; ++c) res[8][c] = r[5][c];\n")
        # the time loop around the same step (MagnetBank.run_steps): up to RUN_CHUNK steps,
        # step k reads the state row k - 1 of its own output and writes row k; it stops
        # after the first flagged step (n_done = the good steps before it; that step's
        # rows, extremes and flags stay in the outputs for the diagnosis)
        ch = RUN_CHUNK
        loop = (f"  const double *a[5];\n  double *r[6];\n  long k, c, ns;\n"
                f"  for (k = 0; k < 7; ++k) if (!res[k]) return 1;\n"
                f"  ns = arg[5][0] > 0 ? (long) arg[5][0] : 0;\n  if (ns > {ch}) ns = {ch};\n"
                f"  r[3] = res[4]; r[4] = res[5]; r[5] = res[6];\n"
                f"  for (c = 0; c < {n}; ++c) r[5][c] = 0.0;\n"
                f"  for (k = 0; k < ns; ++k) {{\n"
                f"    double nb = 0.0;\n"
                f"    a[0] = k ? res[0] + (k - 1) * {n} : arg[0];\n"
                f"    for (c = 1; c < 4; ++c) a[c] = arg[c] + k * {n};\n"
                f"    a[4] = arg[4] + k;\n"
                f"    for (c = 0; c < 3; ++c) r[c] = res[c] + k * {n};\n"
                f"    {name}_k(a, r);\n"
                f"    for (c = 0; c < {n}; ++c) nb += r[5][c] != 0.0;\n"
                f"    if (nb != 0.0) break;\n  }}\n"
                f"  res[3][0] = (double) k;\n")
        code = ("#include <math.h>\n" + kernel
                + external_source(name, inputs=[("I_L", n), ("s", n), ("U", n), ("sdot", n),
                                                ("h", 1)] + [("I_e", ne * n)] * me,
                                  outputs=[("I_L_next", n), ("I", n), ("F", n), ("member_F", nm),
                                           ("n_bad", 1), ("I_L_min", n), ("I_L_max", n),
                                           ("s_next", n), ("flags", n)]
                                  + [("I_e_next", ne * n)] * me,
                                  body=body, work=(10 + 2 * ne) * n + 1))
        if not me:                       # (run_steps refuses ladder banks)
            code += external_source(f"{name}_run", inputs=[("I_L0", n), ("s", n * ch),
                                                           ("U", n * ch), ("sdot", n * ch),
                                                           ("h", ch), ("n_steps", 1)],
                                    outputs=[("I_L", n * ch), ("I", n * ch), ("F", n * ch),
                                             ("n_done", 1), ("I_L_min", n), ("I_L_max", n),
                                             ("bad", n)],
                                    body=loop)
        digest = hashlib.sha256(code.encode()).hexdigest()[:16]
        name = f"maglevkit_bank_lanes{substeps}_{digest}"
        code = code.replace("MAGLEVKIT_LANES_NAME", name)
        cache = Path(self._cache_dir) if self._cache_dir is not None else cache_directory()
        try:
            lib = build_source(name, code.encode(), cache=cache,
                               flags=("-O3", "-shared", "-fPIC", "-ffp-contract=off", *flags))
            f = ca.external(name, str(lib))
            if not me:
                self._lane_runs[substeps] = ca.external(f"{name}_run", str(lib))
        except (OSError, RuntimeError, subprocess.SubprocessError):
            return None                  # the CasADi path reports (or raises) the failure
        self.compiled = True
        self._lanes[substeps] = (f, lib)
        return f

    @renamed_keywords(dt="dt_s")
    def compiled_step_library(self, dt_s: float) -> tuple[ca.Function, Path] | None:
        """The compiled (lanes) step over ``dt`` [s] as a CasADi external function and the
        path of its shared library, or None (no compiler, ``compiled="never"`` or
        ``codegen="casadi"``).

        The function has the inputs and outputs of :meth:`step_function`; a larger
        CasADi function that calls it can be generated as C and compiled when linked
        against the library (the vehicle's compiled step does this).

        Old keyword names (``dt``) are deprecated aliases for one release.

        Parameters
        ----------
        dt_s : float
            Step length [s], finite and > 0 (sets the RK4 sub-step count as in
            :meth:`step_function`).

        Returns
        -------
        (casadi.Function, pathlib.Path) or None

        Raises
        ------
        InputError
            A bad ``dt``, or a bank with detailed members or ``gap_inputs="pole"``.
        """
        n = self._composable_substeps(dt_s, "compiled_step_library")
        if self.codegen != "lanes":
            return None
        f = self._lanes_kernel(n)
        return None if f is None else (f, self._lanes[n][1])

    # ------------------------------------------------------------------ properties
    @property
    def n_circuits(self) -> int:
        return len(self.circuit_names)

    @property
    def n_gaps(self) -> int:
        return len(self.gap_names)

    @property
    def circuit_slices(self) -> dict[str, slice]:
        """Member name -> its slice of the circuit arrays."""
        return dict(zip(self.member_names, self._circuit_slices, strict=True))

    @property
    def gap_slices(self) -> dict[str, slice]:
        """Member name -> its slice of the gap-input arrays."""
        return dict(zip(self.member_names, self._circuit_slices if self.gap_inputs == "circuit"
                        else self._pole_slices, strict=True))

    @renamed_keywords(gaps="gaps_m")
    def circuit_gaps(self, gaps_m: np.ndarray) -> np.ndarray:
        """Substitute gap of every circuit [m] from the gap inputs.

        Old keyword names (``gaps``) are deprecated aliases for one release.

        Parameters
        ----------
        gaps_m : ndarray (n_gaps,)
            The bank's gap inputs [m] (:attr:`gap_names`); not checked.

        Returns
        -------
        ndarray (n_circuits,)
            ``gaps`` itself with ``gap_inputs="circuit"``, else the mean of every circuit's
            pole gaps.
        """
        return gaps_m if self.gap_inputs == "circuit" else self._avg @ gaps_m

    @renamed_keywords(gaps="gaps_m")
    def pole_gaps(self, gaps_m: np.ndarray) -> np.ndarray:
        """Gap of every pole [m] from the gap inputs.

        Old keyword names (``gaps``) are deprecated aliases for one release.

        Parameters
        ----------
        gaps_m : ndarray (n_gaps,)
            The bank's gap inputs [m] (:attr:`gap_names`); not checked.

        Returns
        -------
        ndarray (n_poles,)
            With ``gap_inputs="circuit"`` every pole gets its circuit's gap; with
            ``"pole"`` ``gaps`` itself.
        """
        return (self._share > 0).astype(float) @ gaps_m if self.gap_inputs == "circuit" else gaps_m

    # ------------------------------------------------------------------ input handling
    def _range_error(self, k: int, s: float, i: float, where: str) -> None:
        j = int(self._reduced_idx[k])
        b = self._bounds[:, k]
        text = STEP_FLAG_MESSAGES
        msg = text["out_of_maps"] % (circuit_label(self.circuit_names[j]), where, s, i, *b)
        if self.extrapolate:
            e = self._spline_bounds[:, k]
            if e[0] <= s <= e[1] and e[2] <= i <= e[3]:
                # once per circuit and bank: a run that stays near a map's edge would
                # otherwise warn at every step (each message names its own time)
                if k not in self._extrapolation_warned:
                    self._extrapolation_warned.add(k)
                    warnings.warn("extrapolating the characteristic maps: "
                                  + msg.removeprefix("outside the characteristic maps: ")
                                  + " (reported once per circuit)", stacklevel=external_stacklevel())
                return
            msg += f"; linear extrapolation reaches only {EXTRA_CELLS} grid cells beyond the maps"
            advice = text["advice_extrapolating"]
        else:
            advice = text["advice"]
        raise OutOfRangeError(msg + advice)

    def _check_range(self, s_lo: np.ndarray, s_hi: np.ndarray, i_lo: np.ndarray,
                     i_hi: np.ndarray, where: str) -> None:
        """Vectorised range check of the reduced circuits (two comparisons when fine)."""
        bad = (s_lo < self._lo_s) | (s_hi > self._hi_s) | (i_lo < self._lo_i) | (i_hi > self._hi_i)
        if not bad.any():
            return
        for k in np.flatnonzero(bad):
            s = s_lo[k] if s_lo[k] < self._lo_s[k] else s_hi[k]
            i = i_lo[k] if i_lo[k] < self._lo_i[k] else i_hi[k]
            self._range_error(int(k), float(s), float(i), where)

    def _diagnose(self, s: np.ndarray, sd: np.ndarray, i0: np.ndarray, u: np.ndarray,
                  x: np.ndarray, call: _StepCall, t0: float, t1: float) -> None:
        """The kernel flagged circuits (inputs of the reduced circuits): their reason codes
        read by :func:`~maglevkit.reduced.core.diagnose_flags`, the one reading of them."""
        self._raise_reduced(call.res[8], s, sd, i0, u, call.res[5], call.res[6], t0, t1)

    def _raise_reduced(self, flags: Any, s: np.ndarray, sd: np.ndarray, i0: np.ndarray,
                       u: np.ndarray, lo: Any, hi: Any, t0: float, t1: float) -> None:
        ri = self._reduced_idx
        diagnose_flags(flags, [self.circuit_names[int(j)] for j in ri], gaps_m=s,
                       gap_rates_m_per_s=sd, currents_A=i0, voltages_V=u,
                       substep_min_A=np.array(lo, dtype=float).ravel(),
                       substep_max_A=np.array(hi, dtype=float).ravel(),
                       current_min_A=self._lo_i, current_max_A=self._hi_i, gap_min_m=self._lo_s,
                       t0_s=t0, t1_s=t1, out_of_maps=self._range_error)

    def raise_step_flags(self, flags: Any, *, gaps_m: Any, gap_rates_m_per_s: Any,
                         inductor_currents_A: Any, voltages_V: Any, current_min_A: Any,
                         current_max_A: Any, start_s: float, end_s: float) -> None:
        """The error of a step that a compiled step flagged elsewhere (e.g. inside a
        vehicle's compiled step, :meth:`step_function`, or a loop around
        :meth:`step_kernel` such as the stepper): its reason codes (:class:`StepFlag`, the
        step's ``flags``) turned into the same message :meth:`step` gives, without
        stepping again (:func:`~maglevkit.reduced.core.diagnose_flags`).  Extrapolating
        banks warn instead, as :meth:`step`.

        Parameters
        ----------
        flags : array (n_circuits,)
            The step's ``flags`` output (reason codes, 0 for a good circuit).
        gaps_m, gap_rates_m_per_s, inductor_currents_A, voltages_V : array (n_circuits,)
            The step's inputs ``s`` [m], ``sdot`` [m/s], ``I_L`` [A], ``U`` [V].
        current_min_A, current_max_A : array (n_circuits,)
            The step's outputs ``I_L_min``, ``I_L_max`` [A] (extremes over the sub-steps).
        start_s, end_s : float
            Times of the step's start and end [s] (for the message).

        Raises
        ------
        OutOfRangeError, InputError, SolverError
            As :meth:`step` for the same step; nothing when no flag is set.
        """
        ri = self._reduced_idx

        def arr(a: Any) -> np.ndarray:
            return np.asarray(a, dtype=float).ravel()[ri]

        self._raise_reduced(arr(flags), arr(gaps_m), arr(gap_rates_m_per_s),
                            arr(inductor_currents_A), arr(voltages_V), arr(current_min_A),
                            arr(current_max_A), float(start_s), float(end_s))

    # ------------------------------------------------------------------ stepping interface
    @renamed_keywords(gaps="gaps_m", currents="currents_A", time="time_s")
    def initial_state(self, *, gaps_m: Any, currents_A: Any, time_s: float = 0.0) -> BankState:
        """The steady state at ``gaps`` [m] (per gap input, or a scalar) with coil currents
        ``currents`` [A] (per circuit, or a scalar).

        The old keyword names ``gaps``, ``currents``, ``time`` still work as deprecated aliases (a
        ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        gaps_m : float, array_like (n_gaps,) or mapping
            Gap inputs [m], each > 0: one value for all, one per gap input
            (:attr:`gap_names`), or a mapping naming every gap input exactly once.
        currents_A : float, array_like (n_circuits,) or mapping
            Coil currents [A], same forms per circuit (:attr:`circuit_names`); detailed
            members start at their static operating point with these currents.
        time_s : float, default 0.0
            Time of the state [s], finite (no bools).

        Returns
        -------
        BankState
            ``inductor_currents_A`` is NaN for the circuits of detailed members.

        Raises
        ------
        InputError
            Wrong count, unknown or missing names, non-finite values, a gap <= 0, or a bad
            ``time``.
        OutOfRangeError
            A reduced circuit's substitute gap or current outside its maps (without
            ``extrapolate``).
        """
        gaps, currents, time = gaps_m, currents_A, time_s
        g = per_name_values(gaps, self.gap_names, "gaps", "m", kind="gap input")
        if (g <= 0).any():
            j = int(np.argmax(g <= 0))
            raise InputError(f"gaps must be > 0 m: {self.gap_names[j]!r} = {float(g[j])!r} m")
        i = per_name_values(currents, self.circuit_names, "currents", "A").copy()
        reject_bools(time, "time")
        if not (isinstance(time, (int, float, np.floating)) and math.isfinite(time)):
            raise InputError(f"time = {time!r} must be a finite number of seconds")
        s = self.circuit_gaps(g)
        ri = self._reduced_idx
        self._check_range(s[ri], s[ri], i[ri], i[ri], f" at t = {float(time):.6g} s")
        states = []
        pg = self.pole_gaps(g)
        for m, cs, ps in zip(self._members, self._circuit_slices, self._pole_slices, strict=True):
            if m.kind == "detailed":
                assert m.model is not None
                states.append(m.model.initial_state(gaps_m=pg[ps], currents_A=i[cs], time_s=float(time)))
                i[cs] = np.nan
        # the steady state of the ladder has no shielding current (I_e = V_m/R_2 = 0)
        eddy = np.where(np.isnan(i), np.nan, 0.0) if self._has_eddy else None
        if self.n_eddy_states >= 2:
            assert eddy is not None
            eddy = np.repeat(eddy[:, None], self.n_eddy_states, axis=1)
        return BankState(float(time), i, g.copy(), tuple(states), eddy)

    def check_state(self, state: Any) -> None:
        """Refuse a state that is not a :class:`BankState` of this bank.

        Parameters
        ----------
        state : object
            The state to check (type, array shapes, detailed members, eddy currents).

        Raises
        ------
        InputError
            ``state`` is not a BankState of this bank; the message says how to make one.
        """
        if (type(state) is not BankState or state.gaps_m.shape != (self.n_gaps,)
                or state.inductor_currents_A.shape != (self.n_circuits,)
                or len(state.member_states) != self._n_detailed):
            raise InputError("state must be a BankState of this bank (from initial_state, step "
                             "or a stepper's state)")
        e = state.eddy_currents_A
        shape = self._eddy_shape()
        if self._has_eddy != (e is not None) or (e is not None and e.shape != shape):
            raise InputError("state must be a BankState of this bank: "
                             + ("its ladder or eddy-network members (motion_eddy, eddy_modes) "
                                f"need eddy_currents_A of shape {shape}" if self._has_eddy else
                                "this bank has no ladder or eddy-network members, so "
                                "eddy_currents_A must be None")
                             + " (make it with initial_state, step or a stepper's state)")

    def _eddy_shape(self) -> tuple[int, ...]:
        """Shape of :attr:`BankState.eddy_currents_A`: ``(n_circuits,)`` with one ladder
        eddy state per circuit, ``(n_circuits, 2)`` with two (:attr:`n_eddy_states`)."""
        nc = self.n_circuits
        return (nc,) if self.n_eddy_states < 2 else (nc, self.n_eddy_states)

    @renamed_keywords(dt="dt_s", voltages="voltages_V", gaps="gaps_m", gap_rates="gap_rates_m_per_s")
    def step(self, state: BankState, dt_s: float, voltages_V: Any, gaps_m: Any = None,
             gap_rates_m_per_s: Any = 0.0, *, pole_forces: bool = False) -> tuple[BankState, BankOutputs]:
        """Advance every member by ``dt`` [s] with constant voltages and linearly moving gaps.

        The old keyword names ``dt``, ``voltages``, ``gaps``, ``gap_rates`` still work as
        deprecated aliases (a ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        state : BankState
            From :meth:`initial_state` or a previous step.
        dt_s : float
            Step length [s] (> 0).
        voltages_V : float or array (n_circuits,)
            Circuit voltages [V], held over the step.
        gaps_m : float, array (n_gaps,) or None
            Gap inputs [m] at the start of the step (None keeps the state's).
        gap_rates_m_per_s : float or array (n_gaps,)
            Gap rates [m/s] over the step.
        pole_forces : bool
            Also return the per-pole force distribution.

        Returns
        -------
        (BankState, BankOutputs)

        Raises
        ------
        InputError
            Bad shapes, non-finite values (naming the member and circuit), gaps that are or
            become <= 0.
        OutOfRangeError
            A reduced circuit leaves its maps (checked before integrating for the gaps and
            over every RK4 sub-step for the currents), naming member, circuit, gap, current
            and the map's range.
        SolverError
            Non-finite results (with time, state and reason) or a detailed member's
            integrator failing.
        """
        dt, voltages, gaps, gap_rates = dt_s, voltages_V, gaps_m, gap_rates_m_per_s
        self.check_state(state)
        if not (type(dt) is float and 0.0 < dt < math.inf):
            dt = check_step(dt)
        # fast path (all reduced, one gap per circuit): the kernel flags non-finite
        # inputs, gaps outside the maps (which start above 0) and currents leaving them;
        # only a flagged step is diagnosed in Python
        checked = not self._fast
        u = per_name_values(voltages, self.circuit_names, "voltages", "V", finite=checked)
        g = state.gaps_m if gaps is None else per_name_values(
            gaps, self.gap_names, "gaps", "m", finite=checked, kind="gap input")
        gd = per_name_values(gap_rates, self.gap_names, "gap_rates", "m/s", finite=checked,
                             kind="gap input")
        t0, t1 = state.time_s, state.time_s + dt
        if self._fast:
            # all reduced, one gap per circuit: one kernel call and two objects (the kernel
            # also returns the end gaps g + gd dt)
            last = self._last_call
            call = last if last is not None and dt == self._last_dt else self._kernel(dt)
            x, coil, force, member_force, n_bad, g1 = call(state.inductor_currents_A, g, u, gd,
                                                           dt, state.eddy_currents_A)
            if n_bad:
                self._diagnose(g, gd, state.inductor_currents_A, u, x, call, t0, t1)
            pf = self._share @ force if pole_forces else None
            return (_new(BankState, time_s=t1, inductor_currents_A=x, gaps_m=g1,
                         member_states=(), eddy_currents_A=call.eddy_next()),
                    _new(BankOutputs, time_s=t1, currents_A=coil, inductor_currents_A=x.copy(),
                         circuit_force_N=force, member_force_N=member_force, pole_force_N=pf))
        g1 = g + gd * dt
        if checked and ((g <= 0).any() or (g1 <= 0).any()):
            j = int(np.argmax((g <= 0) | (g1 <= 0)))
            raise InputError(f"gaps must stay > 0 m over the step: {self.gap_names[j]!r} from "
                             f"{float(g[j])!r} m to {float(g1[j])!r} m")
        nc = self.n_circuits
        coil = np.empty(nc)
        force = np.empty(nc)
        i_next = np.full(nc, np.nan)
        member_force = np.zeros(len(self._members))
        ri = self._reduced_idx
        e_next = None if state.eddy_currents_A is None else state.eddy_currents_A.copy()
        if ri.size:
            s, sd = self.circuit_gaps(g)[ri], self.circuit_gaps(gd)[ri]
            ur, ir = u[ri], state.inductor_currents_A[ri]
            call = self._kernel(dt)
            x, c, f, member_force, n_bad, _ = call(
                ir, s, ur, sd, dt, None if e_next is None else e_next[ri])
            if n_bad:
                self._diagnose(s, sd, ir, ur, x, call, t0, t1)
            i_next[ri], coil[ri], force[ri] = x, c, f
            if e_next is not None:
                e_next[ri] = call.eddy_next()
        states = list(state.member_states)
        pf_detailed: dict[int, np.ndarray] = {}
        pg, pgd = self.pole_gaps(g), self.pole_gaps(gd)
        k = 0
        for mi, (m, cs, ps) in enumerate(zip(self._members, self._circuit_slices,
                                             self._pole_slices, strict=True)):
            if m.kind != "detailed":
                continue
            assert m.model is not None
            new, out = m.model.step(states[k], dt, u[cs], pg[ps], pgd[ps])
            states[k] = new
            coil[cs] = out.currents_A
            force[cs] = _circuit_forces(out.pole_force_N, m)
            member_force[mi] = out.force_N
            pf_detailed[mi] = out.pole_force_N
            k += 1
        pf = None
        if pole_forces:
            pf = self._share @ force
            for mi, v in pf_detailed.items():
                pf[self._pole_slices[mi]] = v
        new_state = BankState(t1, i_next, g1, tuple(states), e_next)
        return new_state, BankOutputs(t1, coil, i_next.copy(), force, member_force, pf)

    @renamed_keywords(dt="dt_s")
    def stepper(self, state: BankState, dt_s: float) -> BankStepper:
        """A :class:`~maglevkit.reduced.stepper.BankStepper` that advances the bank from
        ``state`` in steps of ``dt`` [s] in place: the co-simulation loop of a vehicle
        model or controller without the per-step objects and copies of :meth:`step`
        (the same compiled function and checks, bit-identical results).

        The old keyword name ``dt`` still works as a deprecated alias (a
        ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        state : BankState
            Start state of this bank (from :meth:`initial_state`, :meth:`step` or another
            stepper's ``state``).
        dt_s : float
            Step length [s], finite and > 0.

        Returns
        -------
        BankStepper

        Raises
        ------
        InputError
            ``state`` not a state of this bank, or a bad ``dt``.

        Examples
        --------
        >>> import numpy as np
        >>> import maglevkit as mk
        >>> maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.006, 0.016, 6),
        ...                      currents_A=np.linspace(0, 60, 13), progress=False)
        >>> bank = mk.MagnetBank({"a": maps, "b": maps}, compiled="never")
        >>> stepper = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), dt_s=1e-3)
        >>> stepper.advance(voltages_V=45.0, gap_rates_m_per_s=0.0)
        >>> bool(stepper.inductor_currents_A[0] > 20.0)
        True
        """
        dt = dt_s
        return BankStepper(self, state, dt)

    @renamed_keywords(t="times_s", gaps="gaps_m", voltages="voltages_V",
                      gap_rates="gap_rates_m_per_s", dt="dt_s",
                      initial_currents="initial_currents_A")
    def simulate(self, times_s: Any, *, gaps_m: Any, voltages_V: Any, gap_rates_m_per_s: Any = None,
                 dt_s: float | None = None, initial_currents_A: Any = None,
                 initial_state: BankState | None = None,
                 gap_rate_tolerance: float = 0.02) -> BankSimulation:
        """Simulate on a time grid (inputs and conventions as :func:`maglevkit.simulate`).

        Gaps move linearly between samples, voltages are held from each sample to the
        next; the default initial state is the steady state ``I = U(t0) / R_el`` at the
        first gaps.  Every interval is one :meth:`step` (for banks of reduced members
        with one gap per circuit, through :meth:`stepper`: the same compiled function,
        without the per-step objects).

        The old keyword names ``t``, ``gaps``, ``voltages``, ``gap_rates``, ``dt``,
        ``initial_currents`` still work as deprecated aliases (a ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        times_s : (t0, tf), [t0, tf] or array_like
            A time span [s] (sampled with ``dt``) or an explicit strictly increasing grid [s].
        gaps_m : float, sequence, mapping, Signal, callable or array
            Gap inputs [m] (one per circuit or per pole, :attr:`gap_names`), > 0 at every
            sample: constant, per gap, gap name -> value, a function of time [s] or an
            array (n_t, n_gaps) on the grid.
        voltages_V : same forms as ``gaps``
            Circuit voltages [V] (:attr:`circuit_names`); zero-order hold on each interval.
        gap_rates_m_per_s : same forms as ``gaps``, optional
            Gap rates [m/s]; only checked against the secants of the sampled gaps (the
            secants drive the model). None: no check.
        dt_s : float, optional
            Grid step [s] of a time span (None: 1e-4 s, or ``tf - t0`` if shorter); must
            be None with an explicit grid.
        initial_currents_A : float, array_like (n_circuits,) or mapping, optional
            Start from the steady state at the first gaps with these coil currents [A]
            instead of ``U(t0) / R_el``. Not together with ``initial_state``.
        initial_state : BankState, optional
            Start from this state of the bank (e.g. a previous run's ``final_state``); the
            steps take their gaps from ``gaps``. Not together with ``initial_currents``.
        gap_rate_tolerance : float, default 0.02
            Allowed disagreement of ``gap_rates`` with the gap secants [-], relative to the
            largest rate (plus 1 um/s), >= 0.

        Returns
        -------
        BankSimulation

        Raises
        ------
        InputError
            Bad grid (or ``dt`` with an explicit grid), inputs of the wrong shape or
            names, non-finite values, gaps <= 0, gap rates that disagree with the gaps, or
            both initial choices given.
        OutOfRangeError
            A reduced circuit leaves its maps (see ``extrapolate``).
        SolverError
            Non-finite results or a detailed member's integrator failing.
        """
        gaps, voltages, gap_rates, dt = gaps_m, voltages_V, gap_rates_m_per_s, dt_s
        initial_currents = initial_currents_A
        times, g, u, rates = simulation_inputs(
            times_s, dt, gaps=gaps, voltages=voltages, gap_rates=gap_rates, gap_names=self.gap_names,
            circuit_names=self.circuit_names, gap_rate_tolerance=gap_rate_tolerance)
        check_initial_choice(initial_state, initial_currents, BankState)
        if initial_state is not None:
            state = initial_state
        else:
            i0 = u[0] / self.resistance_ohm if initial_currents is None else initial_currents
            state = self.initial_state(gaps_m=g[0], currents_A=i0, time_s=float(times[0]))
        nt, nc = times.size, self.n_circuits
        cur, il, fc = (np.empty((nt, nc)) for _ in range(3))
        pf = np.empty((nt, len(self.pole_names)))
        o = self._outputs_at(state, u[0])
        cur[0], il[0], fc[0], pf[0] = o.currents_A, o.inductor_currents_A, o.circuit_force_N, \
            o.pole_force_N
        ie = None
        if state.eddy_currents_A is not None:
            ie = np.empty((nt, *self._eddy_shape()))
            ie[0] = state.eddy_currents_A
        steps = np.diff(times)
        if self._fast and nt > 1 and len({self._substeps(float(h))
                                          for h in np.unique(steps)}) == 1:
            # every interval runs the same compiled kernel: step in place (the same
            # function and inputs as step(), so the same numbers), pole forces at the end
            # (each pole takes one share of one circuit's force: exact in any order)
            stepper = self.stepper(state, float(steps[0]))
            for k in range(nt - 1):
                stepper.set_step_length(float(steps[k]))
                stepper.advance(u[k], g[k], rates[k])
                cur[k + 1] = stepper.currents_A
                il[k + 1] = stepper.inductor_currents_A
                fc[k + 1] = stepper.circuit_force_N
                if ie is not None:
                    ie[k + 1] = stepper.eddy_currents_A
            pf[1:] = self._pole_forces_of(fc[1:])
            state = stepper.state
        else:
            for k in range(nt - 1):
                state, o = self.step(state, float(steps[k]), u[k], g[k], rates[k],
                                     pole_forces=True)
                cur[k + 1], il[k + 1], fc[k + 1] = (o.currents_A, o.inductor_currents_A,
                                                    o.circuit_force_N)
                assert o.pole_force_N is not None
                pf[k + 1] = o.pole_force_N
                if ie is not None:
                    ie[k + 1] = state.eddy_currents_A
        return BankSimulation(
            time_s=times, gaps_m=g, voltages_V=np.vstack((u[:-1], u[-2:-1])), currents_A=cur,
            inductor_currents_A=il, circuit_force_N=fc,
            member_force_N=np.add.reduceat(fc, self._member_starts, axis=1), pole_force_N=pf,
            circuit_names=self.circuit_names, gap_names=self.gap_names,
            pole_names=self.pole_names, member_names=self.member_names, final_state=state,
            eddy_currents_A=ie)

    @property
    def compiled_fast_path(self) -> bool:
        """Whether a step of the whole bank is one compiled call (every member reduced, one
        gap input per circuit): :meth:`step`'s and the stepper's fast path, where the
        kernel's reason codes (:class:`StepFlag`) are the only checks of a step."""
        return self._fast

    def pole_forces(self, circuit_force_N: np.ndarray) -> np.ndarray:
        """Force per pole [N] from the circuit forces of the reduced circuits: each pole
        takes an equal share of its circuit's force.

        Parameters
        ----------
        circuit_force_N : ndarray (n_circuits,) or (n_t, n_circuits)
            Circuit forces [N], one row per time.

        Returns
        -------
        ndarray (n_poles,) or (n_t, n_poles)
            Pole forces [N] in the order of :attr:`pole_names`.
        """
        f = np.asarray(circuit_force_N, dtype=float)
        return self._pole_forces_of(f[None, :])[0] if f.ndim == 1 else self._pole_forces_of(f)

    def _pole_forces_of(self, circuit_forces: np.ndarray) -> np.ndarray:
        """Per-pole forces of a time series of reduced circuit forces (n_t, n_circuits),
        equal to ``self._share @ f`` row by row: where every pole takes a share of one
        circuit (the bundled magnets) a gather and a product, exact as the matrix product
        (its other terms are exact zeros), else the product itself."""
        if self._pole_gather is None:
            return circuit_forces @ self._share.T
        col, w = self._pole_gather
        return circuit_forces[:, col] * w

    @renamed_keywords(voltages="voltages_V")
    def outputs(self, state: BankState, voltages_V: Any = None) -> BankOutputs:
        """Outputs at ``state`` with ``voltages`` [V] (default: the steady-state voltages
        ``R_el I_L``; for detailed members their state's own currents).

        Old keyword names (``voltages``) are deprecated aliases for one release.

        Parameters
        ----------
        state : BankState
            State of this bank; not checked against the bank here.
        voltages_V : float, array_like (n_circuits,), mapping or None, default None
            Circuit voltages [V], finite: one for all, one per circuit, or circuit name ->
            value.  They set the reduced circuits' coil currents ``I = (U - U_L) / R_el``;
            detailed members ignore them (their outputs come from their state).

        Returns
        -------
        BankOutputs
            With ``pole_force_N`` filled in.

        Raises
        ------
        InputError
            Voltages of the wrong count or names, or not finite.
        """
        # (steady state: I_e = 0 in the ladder circuits, so R_el I_L there too)
        u = (self.resistance_ohm * np.where(np.isnan(state.inductor_currents_A), 0.0,
                                            state.inductor_currents_A)
             if voltages_V is None else per_name_values(voltages_V, self.circuit_names, "voltages", "V"))
        return self._outputs_at(state, u)

    def _outputs_at(self, state: BankState, u: np.ndarray) -> BankOutputs:
        nc = self.n_circuits
        coil, force = np.empty(nc), np.empty(nc)
        ri = self._reduced_idx
        s = self.circuit_gaps(state.gaps_m)
        if ri.size:
            e = state.eddy_currents_A
            args = [state.inductor_currents_A[ri], u[ri], s[ri]]
            if e is not None:
                args.append(e[ri])
            # the first call maps the circuit function (no build); later calls take the
            # inlined graph, built once (_outputs_inlined: the same bits)
            self._outputs_calls += 1
            c, f, _ = (self.output_function(*args) if self._outputs_calls == 1 else
                       self._outputs_inlined()(*args, self._par))
            coil[ri], force[ri] = np.asarray(c).ravel(), np.asarray(f).ravel()
        pf_detailed = {}
        k = 0
        for mi, (m, cs) in enumerate(zip(self._members, self._circuit_slices, strict=True)):
            if m.kind == "detailed":
                assert m.model is not None
                out = m.model.outputs(state.member_states[k])
                coil[cs] = out.currents_A
                force[cs] = _circuit_forces(out.pole_force_N, m)
                pf_detailed[mi] = out.pole_force_N
                k += 1
        pf = self._share @ force
        for mi, v in pf_detailed.items():
            pf[self._pole_slices[mi]] = v
        return BankOutputs(state.time_s, coil, state.inductor_currents_A.copy(), force,
                           np.bincount(self._member_of, weights=force,
                                       minlength=len(self._members)), pf)


def _reason_code(s: Any, se: Any, sd: Any, u: Any, lo: Any, hi: Any, finals: tuple[Any, ...],
                 p: Any) -> Any:
    """A circuit step's reason code (:class:`StepFlag`, one bit per reason, 0 for a good
    step), written once for eq. 8 and the ladder: gaps ``s`` (start) and ``se`` (end)
    against ``p[9:11]``, the current's extremes ``lo``/``hi`` against ``p[11:13]`` (the
    bounds incl. rounding allowances), non-finite inputs, non-finite results ``finals``.
    ``|v| <= DBL_MAX`` is false for NaN and inf (``x - x`` would be simplified to 0)."""
    big = float(np.finfo(float).max)

    def non_finite(v: Any) -> Any:
        return 1 - (ca.fabs(v) <= big)

    def any_of(*conditions: Any) -> Any:
        return sum(conditions[1:], conditions[0]) > 0

    return (float(StepFlag.GAP_OUT_OF_RANGE) * any_of(ca.fmin(s, se) < p[9], ca.fmax(s, se) > p[10])
            + float(StepFlag.CURRENT_OUT_OF_RANGE) * any_of(lo < p[11], hi > p[12])
            + float(StepFlag.INPUT_NOT_FINITE) * any_of(non_finite(u), non_finite(s),
                                                 non_finite(sd))
            + float(StepFlag.RESULT_NOT_FINITE) * (non_finite(finals[0]) if len(finals) == 1
                                                   else any_of(*map(non_finite, finals))))


class _Pair:
    """Two scalar expressions added and scaled component by component: the ladder's state
    ``(I_L, I_e)`` for :func:`rk4_substep` without a vertcat (a scalar graph)."""

    __slots__ = ("v",)

    def __init__(self, *v: Any) -> None:
        self.v = v

    def __add__(self, other: _Pair) -> _Pair:
        return _Pair(*(a + b for a, b in zip(self.v, other.v, strict=True)))

    def __rmul__(self, c: Any) -> _Pair:
        return _Pair(*(c * a for a in self.v))

    def __getitem__(self, k: int) -> Any:
        return self.v[k]


def _new(cls: type[_T], **fields: Any) -> _T:
    """A frozen dataclass instance with every field given, without the per-field
    ``object.__setattr__`` of its generated ``__init__`` (~1 us each on the bank's hot
    path); equal to ``cls(**fields)``, and as frozen."""
    obj = object.__new__(cls)
    obj.__dict__.update(fields)
    return obj


def _circuit_forces(pole_force: np.ndarray, member: _Member) -> np.ndarray:
    """Sum of a detailed member's pole forces over each circuit's poles."""
    pi = {p: k for k, p in enumerate(member.poles)}
    return np.array([sum(pole_force[pi[p]] for p in member.pole_groups[c])
                     for c in member.circuits])


@dataclass
class _RunResult:
    rows: tuple[np.ndarray, np.ndarray, np.ndarray]    # I_L, I, F (m, n_circuits)
    n_done: int
    extremes: list[Any]          # as _StepCall.res: [5], [6] the flagged step's I_L extremes,
                                 # [8] its reason codes


class _RunCall:
    """Up to :data:`RUN_CHUNK` steps of the compiled step in one call: the lanes' C loop
    through bound buffers, else a CasADi ``mapaccum`` of the step (padded with steps of
    length 0, which change nothing)."""

    def __init__(self, loop: ca.Function | None, step: ca.Function, n: int) -> None:
        self.n = n
        ch = RUN_CHUNK
        if loop is not None:
            # the blocks (steps, circuits) are bound row-major: the loop's layout
            blocks = [np.zeros((ch, n)), np.zeros((ch, n)), np.zeros((ch, n))]
            bound = BoundCall(loop, args={1: blocks[0], 2: blocks[1], 3: blocks[2]},
                              res={0: np.zeros((ch, n)), 1: np.zeros((ch, n)),
                                   2: np.zeros((ch, n))})
            self.bound = bound
            self.eval = bound.eval
            self.args, self.res = bound.args, bound.res
            self.acc = None
        else:
            self.acc = step.mapaccum("maglevkit_bank_run", ch)

    def __call__(self, x0: np.ndarray, s: np.ndarray, u: np.ndarray, sd: np.ndarray,
                 h: np.ndarray) -> _RunResult:
        m = h.size
        if self.acc is None:
            a = self.args
            a[0][:] = x0
            a[1][:m] = s
            a[2][:m] = u
            a[3][:m] = sd
            a[4][:m] = h
            a[5][0] = m
            self.eval()
            r = self.res
            done = int(r[3][0])
            return _RunResult((r[0][:m], r[1][:m], r[2][:m]), done,
                              [None] * 5 + [r[4].copy(), r[5].copy(), None, r[6].copy()])
        ch = RUN_CHUNK
        pad = ch - m
        end = s[-1] + sd[-1] * h[-1]

        def padded(v: np.ndarray, fill: np.ndarray) -> np.ndarray:
            return np.vstack([v, np.broadcast_to(fill, (pad, self.n))]).T if pad else v.T

        res = self.acc(x0, padded(s, end), padded(u, u[-1]), padded(sd, np.zeros(self.n)),
                       np.concatenate([h, np.zeros(pad)])[None, :])
        x, coil, force = (np.asarray(res[j]).T[:m] for j in range(3))
        flags = np.asarray(res[4]).ravel()[:m]
        done = int(np.argmax(flags != 0)) if (flags != 0).any() else m
        lo, hi, flagged = (np.asarray(res[j])[:, min(done, m - 1)] for j in (5, 6, 8))
        return _RunResult((x, coil, force), done, [None] * 5 + [lo, hi, None, flagged])


class _StepCall:
    """The compiled step through bound NumPy buffers (no per-call conversion).

    Returns copies of the currents, coil currents, circuit and member forces, and the
    flag count; the sub-step extremes stay in ``res[5]``, ``res[6]`` for a diagnosis.
    """

    def __init__(self, f: ca.Function, n_eddy: int = 0) -> None:
        self.f = f
        self.n_eddy = n_eddy         # ladder eddy states per circuit (input 5, output 9)
        self.bound = BoundCall(f)
        self.eval = self.bound.eval
        self.args, self.res = self.bound.args, self.bound.res

    def __call__(self, i: np.ndarray, s: np.ndarray, u: np.ndarray, sd: np.ndarray, h: float,
                 eddy: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
        a = self.args
        a[0][:] = i
        a[1][:] = s
        a[2][:] = u
        a[3][:] = sd
        a[4][0] = h
        if eddy is not None:                 # a ladder bank's I_e (input 5, column-major)
            a[5][:] = eddy if eddy.ndim == 1 else eddy.ravel(order="F")
        self.eval()
        r = self.res
        return (r[0].copy(), r[1].copy(), r[2].copy(), r[3].copy(), float(r[4][0]),
                r[7].copy())

    def eddy_next(self) -> np.ndarray | None:
        """A ladder bank's ``I_e`` after the last call (output 9; None in eq. 8 banks):
        ``(n,)``, or ``(n, 2)`` with two eddy states per circuit."""
        if len(self.res) <= 9:
            return None
        r = self.res[9]
        return r.copy() if self.n_eddy < 2 else r.reshape(self.n_eddy, -1).T.copy()
