"""The reduced circuits of one set of maps, derived once: :class:`ReducedCore`.

Every consumer of the reduced model (:class:`~maglevkit.reduced.current.CurrentModel`,
:class:`~maglevkit.reduced.bank.MagnetBank` and its stepper, the control model of
:mod:`maglevkit.control.model`, the FMU export) needs the same facts of the maps: the
circuit and gap names, which poles a circuit drives, the averaging matrix (pole gaps ->
the circuit's substitute gap) and the share matrix (circuit force -> equal pole shares),
``R_el``, the chosen ``R_ec`` (``"fit"`` or ``"jump"``), ``a = 1 + R_el/R_ec`` of eq. 8,
the grids continued by :data:`EXTRA_CELLS` cells, the map ranges with their rounding
allowances, and the RK4 sub-step rule.  :meth:`ReducedCore.from_maps` derives them once;
nobody else re-derives them.

The one RK4 step (:func:`rk4_substep`) is written here too: every RK4 of the reduced
model (the B-spline interval of ``CurrentModel``, the bank's table kernel, the control
model's discretisation and the MPC's reference formulation) advances its right-hand side
with it, so a change of the scheme lands in one place.  Eq. 8 itself is
:func:`~maglevkit.reduced.current.eq8_rhs`.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError

if TYPE_CHECKING:
    from ..reduction.maps import CharacteristicMaps

__all__ = ["EDDY_RESISTANCE_CHOICES", "EXTRA_CELLS", "STEP_FLAG_MESSAGES", "SUBSTEP_ALLOWANCE",
           "MotionEddyLadder", "ReducedCore", "StepFlag", "circuit_label", "diagnose_flags",
           "eq8_a", "extend_axis", "extend_values", "rk4_substep", "substep_count",
           "substep_counts", "substep_rule_c"]

EXTRA_CELLS = 3
"""Grid cells by which the maps are continued linearly beyond their range."""

#: ``eddy_resistance`` option -> the maps' variable holding that ``R_ec``
EDDY_RESISTANCE_CHOICES = {"fit": "eddy_resistance_fit_ohm", "jump": "eddy_resistance_ohm"}

#: relative rounding allowance of the gap range checks (times the largest gap)
GAP_TOLERANCE = 1e-12
#: relative rounding allowance of the current range checks (times max(1 A, largest current))
CURRENT_TOLERANCE = 1e-9


def extend_axis(axis: np.ndarray) -> np.ndarray:
    """A grid axis continued by :data:`EXTRA_CELLS` cells of its first/last spacing.

    Parameters
    ----------
    axis : numpy.ndarray
        Increasing grid values (gaps [m] or currents [A]), at least two.

    Returns
    -------
    numpy.ndarray
        ``2 * EXTRA_CELLS`` values longer, in the unit of ``axis``.
    """
    d = axis[1] - axis[0]
    k = np.arange(1, EXTRA_CELLS + 1)
    return np.concatenate([axis[0] - d * k[::-1], axis, axis[-1] + d * k])


def extend_values(values: np.ndarray, *, axis: int) -> np.ndarray:
    """Map values continued linearly (edge slope) by :data:`EXTRA_CELLS` cells along ``axis``.

    Parameters
    ----------
    values : numpy.ndarray
        A map on the grid (any unit).
    axis : int
        The axis to extend.

    Returns
    -------
    numpy.ndarray
        ``values`` with ``EXTRA_CELLS`` more entries on both ends of ``axis``.
    """
    v = np.moveaxis(values, axis, 0)
    k = np.arange(1, EXTRA_CELLS + 1)[:, None]
    lo = v[0] - (v[1] - v[0]) * k[::-1]
    hi = v[-1] + (v[-1] - v[-2]) * k
    return np.moveaxis(np.concatenate([lo, v, hi], axis=0), 0, axis)


class StepFlag(enum.IntFlag):
    """Why the compiled step flagged a circuit: the bits of the kernel's reason code.

    The step (:meth:`~maglevkit.reduced.bank.MagnetBank.circuit_step_function`) returns,
    per circuit, the sum of the reasons that hold (0: a good step);
    :func:`diagnose_flags` turns the codes into the one message of each reason for
    :meth:`~maglevkit.reduced.bank.MagnetBank.step`, its stepper and
    :meth:`~maglevkit.reduced.current.CurrentModel.step`, the FMU's C wrapper likewise.
    """

    GAP_OUT_OF_RANGE = 1
    """The gap path of the step leaves the map's gap range (or a gap is <= 0)."""
    CURRENT_OUT_OF_RANGE = 2
    """The current at the start or at a sub-step end leaves the map's current range."""
    INPUT_NOT_FINITE = 4
    """A voltage, gap or gap rate is NaN or infinite."""
    RESULT_NOT_FINITE = 8
    """The RK4 step gave a NaN or infinite current."""

    @classmethod
    def by_priority(cls) -> tuple[StepFlag, ...]:
        """The order in which reasons are reported: inputs, gap path, result, currents."""
        return (cls.INPUT_NOT_FINITE, cls.GAP_OUT_OF_RANGE, cls.RESULT_NOT_FINITE,
                cls.CURRENT_OUT_OF_RANGE)


#: The message of each reason code (:class:`StepFlag`), written once as printf-style
#: templates: Python's ``%`` formatting and C's ``printf`` agree on ``%s`` and ``%g``, so
#: ``MagnetBank.step`` (and the stepper, ``run_steps``), ``CurrentModel`` (its table step
#: and the range checks of its B-spline path) and the FMU's C wrapper
#: (:mod:`maglevkit.export.fmu` writes them into its ``config.h``) say the same.
#: ``out_of_maps`` takes the circuit's label (:func:`circuit_label` in a bank,
#: ``circuit 'c'`` in a ``CurrentModel``), where (``step`` or ``substep`` with the step's
#: start and end times [s], or ``time`` [s]), the gap [m] and current [A] that left the
#: maps, and the maps' gap [m] and current [A] ranges; the advice follows it
#: (``advice_cli`` where the command line passes the option on).
STEP_FLAG_MESSAGES: dict[str, str] = {
    # what, name, value, unit: the words of models.inputs.per_name_values
    "input_not_finite": "%s must be finite: circuit '%s' = %g %s",
    "gap_not_positive": "gaps must stay > 0 m over the step: circuit '%s' from %.9g m to %.9g m",
    "out_of_maps": ("outside the characteristic maps: %s%s: substitute gap %.6g m and current "
                    "%.6g A; its maps cover gaps %g..%g m and currents %g..%g A"),
    "result_not_finite": "non-finite value in circuit '%s'",
    "step": " over the step t = %.6g..%.6g s",
    "substep": " in an RK4 sub-step within t = %.6g..%.6g s",
    "time": " at t = %.6g s",
    # a shielded-gap ladder's force current (I_L + gamma I_e, I_L + c_1 I_e1 + c_2 I_e2),
    # read from the force map like I_L from the others, left the maps
    "force_current": " (the ladder's force current)",
    "advice": " (rebuild the maps on a larger grid, or pass extrapolate=True)",
    "advice_cli": (" (rebuild the maps on a larger grid, or pass extrapolate=True; on the "
                   "command line: --extrapolate)"),
    "advice_extrapolating": " (rebuild the maps on a larger grid)",
    "advice_fmu": " (rebuild the maps on a larger grid; the FMU does not extrapolate or clamp)",
}


def circuit_label(name: str) -> str:
    """A bank circuit's name as the range messages give it: ``member 'm', circuit 'c'``.

    Parameters
    ----------
    name : str
        The bank's circuit name ``"member/circuit"``.

    Returns
    -------
    str
    """
    member, circuit = name.split("/", 1)
    return f"member {member!r}, circuit {circuit!r}"


def diagnose_flags(flags: np.ndarray, names: Sequence[str], *, gaps_m: np.ndarray,
                   gap_rates_m_per_s: np.ndarray, currents_A: np.ndarray, voltages_V: np.ndarray,
                   substep_min_A: np.ndarray, substep_max_A: np.ndarray,
                   current_min_A: np.ndarray, current_max_A: np.ndarray, gap_min_m: np.ndarray,
                   t0_s: float, t1_s: float,
                   out_of_maps: Callable[[int, float, float, str], None]) -> None:
    """Turn the kernel's reason codes of one flagged step into the error: the one reading
    of :class:`StepFlag` for every Python caller (the FMU's C wrapper reads them the same
    way, in C).

    Reasons are taken in the order of :meth:`StepFlag.by_priority` (inputs first, then the
    gap path, the result, the currents), each for every circuit that has it, with the
    messages of :data:`STEP_FLAG_MESSAGES`.

    Parameters
    ----------
    flags : ndarray (n,)
        The kernel's reason code of every circuit (:class:`StepFlag` bits, 0: good).
    names : sequence of str
        The circuits' names as the messages give them.
    gaps_m, gap_rates_m_per_s, currents_A, voltages_V : ndarray (n,)
        The step's substitute gaps [m] at its start, their rates [m/s], the currents
        ``I_L`` [A] at its start and the held voltages [V].
    substep_min_A, substep_max_A : ndarray (n,)
        The smallest and largest ``I_L`` [A] over the step's RK4 sub-step ends (the
        kernel's ``I_L_min``, ``I_L_max``).
    current_min_A, current_max_A, gap_min_m : ndarray (n,)
        The checked bounds: the kernel's current range [A] and lower gap bound [m] (each
        with its rounding allowance).
    t0_s, t1_s : float
        The step's start and end [s].
    out_of_maps : callable ``(k, gap_m, current_A, where)``
        Reports circuit ``k`` outside its maps (raises, or warns and returns where the
        caller extrapolates); ``where`` is ``STEP_FLAG_MESSAGES["step"]`` or
        ``["substep"]`` with the step's times.

    Raises
    ------
    InputError
        A non-finite input, or gaps that are or become <= 0.
    SolverError
        A non-finite result (with time, state and reason).
    """
    from ..errors import SolverError

    text = STEP_FLAG_MESSAGES
    s, sd, i0, u = gaps_m, gap_rates_m_per_s, currents_A, voltages_V
    se = s + sd * (t1_s - t0_s)
    codes = np.asarray(flags, dtype=float).astype(int)
    step = text["step"] % (t0_s, t1_s)
    for reason in StepFlag.by_priority():
        for k in (int(v) for v in np.flatnonzero(codes & reason)):
            name = names[k]
            if reason is StepFlag.INPUT_NOT_FINITE:
                for what, arr, unit in (("voltages", u, "V"), ("gaps", s, "m"),
                                        ("gap_rates", sd, "m/s")):
                    if not math.isfinite(float(arr[k])):
                        raise InputError(text["input_not_finite"] % (what, name, float(arr[k]),
                                                                     unit))
            elif reason is StepFlag.GAP_OUT_OF_RANGE:
                if s[k] <= 0 or se[k] <= 0:
                    raise InputError(text["gap_not_positive"] % (name, float(s[k]), float(se[k])))
                low, high = min(s[k], se[k]), max(s[k], se[k])
                out_of_maps(k, float(low if low < gap_min_m[k] else high), float(i0[k]), step)
            elif reason is StepFlag.RESULT_NOT_FINITE:
                raise SolverError(text["result_not_finite"] % name, time_s=t0_s,
                                  state={"I_L_A": float(i0[k]), "gap_m": float(s[k]),
                                         "gap_rate_m_per_s": float(sd[k]),
                                         "voltage_V": float(u[k])},
                                  reason="the RK4 step gave a non-finite current")
            elif not current_min_A[k] <= i0[k] <= current_max_A[k]:   # at the start
                out_of_maps(k, float(s[k]), float(i0[k]), step)
            else:                                                      # in a sub-step
                lo, hi = substep_min_A[k], substep_max_A[k]
                out_of_maps(k, float(se[k]), float(lo if lo < current_min_A[k] else hi),
                            text["substep"] % (t0_s, t1_s))


#: relative allowance of the sub-step rule: a step this much longer than a whole multiple
#: of the longest sub-step gets no extra sub-step
SUBSTEP_ALLOWANCE = 1e-12


def substep_rule_c(step: str, max_step: str) -> str:
    """The sub-step rule of :func:`substep_counts` as a C expression (a ``long``), for
    generated C that must count sub-steps the same way (the FMU's wrapper).

    Parameters
    ----------
    step : str
        C expression of the step length [s].
    max_step : str
        C expression of the longest sub-step [s].

    Returns
    -------
    str
        ``max(1, ceil(step / max_step * (1 - SUBSTEP_ALLOWANCE)))`` in C (needs ``math.h``).
    """
    count = f"(long)ceil(({step}) / ({max_step}) * (1.0 - {SUBSTEP_ALLOWANCE!r}))"
    return f"({count} > 1 ? {count} : 1L)"


def substep_counts(dt_s: Any, max_step_s: float) -> np.ndarray:
    """The RK4 sub-step rule: ``max(1, ceil(dt / max_step_s))`` sub-steps per step.

    A step a few rounding units longer than a whole multiple of ``max_step_s`` does not
    get an extra sub-step (the relative allowance 1e-12).

    Parameters
    ----------
    dt_s : float or array_like
        Step lengths [s].
    max_step_s : float
        Longest RK4 sub-step [s].

    Returns
    -------
    numpy.ndarray of int
        Sub-steps per step (the shape of ``dt_s``).
    """
    return np.maximum(1, np.ceil(np.asarray(dt_s, dtype=float) / max_step_s
                                 * (1 - SUBSTEP_ALLOWANCE))).astype(int)


def substep_count(dt_s: float, max_step_s: float) -> int:
    """:func:`substep_counts` of one step length.

    Parameters
    ----------
    dt_s : float
        Step length [s].
    max_step_s : float
        Longest RK4 sub-step [s].

    Returns
    -------
    int
        Sub-steps of the step.
    """
    return max(1, math.ceil(dt_s / max_step_s * (1 - SUBSTEP_ALLOWANCE)))


def rk4_substep(x: Any, hs: Any, rhs_start: Callable[[Any], Any],
                rhs_mid: Callable[[Any], Any] | None = None,
                rhs_end: Callable[[Any], Any] | None = None) -> Any:
    """One classical Runge-Kutta (RK4) step of ``dx/dt = rhs(x)``: the one RK4 of the
    reduced model.

    ``k1 = rhs_start(x)``, ``k2 = rhs_mid(x + hs/2 k1)``, ``k3 = rhs_mid(x + hs/2 k2)``,
    ``k4 = rhs_end(x + hs k3)``, ``x + hs/6 (k1 + 2 k2 + 2 k3 + k4)``.  Inputs that move
    over the step (the bank's gaps ``s + sdot t``) enter through the three stage
    functions (start, middle, end); for held inputs give ``rhs_start`` only.

    Parameters
    ----------
    x : CasADi expression, float or numpy.ndarray
        State at the start of the step (its unit; e.g. ``I_L`` [A]).
    hs : CasADi expression or float
        Step length [s].
    rhs_start : callable
        ``x -> dx/dt`` with the inputs at the start of the step (unit of ``x`` per s).
    rhs_mid, rhs_end : callable, optional
        The same at the middle and at the end of the step (default ``rhs_start``).

    Returns
    -------
    same type as ``x``
        The state after ``hs``.
    """
    mid = rhs_start if rhs_mid is None else rhs_mid
    end = rhs_start if rhs_end is None else rhs_end
    k1 = rhs_start(x)
    k2 = mid(x + hs / 2 * k1)
    k3 = mid(x + hs / 2 * k2)
    k4 = end(x + hs * k3)
    return x + hs / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


@dataclass(frozen=True, eq=False)
class ReducedCore:
    """The facts of eq. 8's reduced circuits of one set of maps, derived once.

    Build it with :meth:`from_maps`.  Arrays are read-only.

    Parameters
    ----------
    maps : CharacteristicMaps
        The maps.
    eddy_resistance : {"fit", "jump"}
        Which ``R_ec`` of the maps eq. 8 uses.
    circuit_names : tuple of str
        Circuits (the maps' order).
    gap_names : tuple of str
        Gap inputs (poles) in input order.
    pole_groups : mapping str -> tuple of str
        Circuit -> the poles it drives.
    averaging : numpy.ndarray (n_circuits, n_gaps)
        Pole gaps [m] -> the circuit's substitute gap [m] (the mean of its poles).
    share : numpy.ndarray (n_gaps, n_circuits)
        Circuit force [N] -> pole forces [N] (equal shares).
    resistance_ohm : numpy.ndarray (n_circuits,)
        ``R_el`` [ohm].
    eddy_resistance_ohm : numpy.ndarray (n_circuits,)
        The chosen ``R_ec`` [ohm] (inf: no eddy branch).
    a : numpy.ndarray (n_circuits,)
        ``1 + R_el/R_ec`` of eq. 8 (1 where ``R_ec`` is infinite) [-].
    gaps_m, currents_A : numpy.ndarray
        The maps' grids [m], [A].
    extended_gaps_m, extended_currents_A : numpy.ndarray
        The grids continued by :data:`EXTRA_CELLS` cells (:func:`extend_axis`) [m], [A].
    gap_range_m, current_range_A : (float, float)
        The maps' ranges [m], [A].
    gap_tolerance_m, current_tolerance_A : float
        Rounding allowances of the range checks [m], [A].
    """

    maps: CharacteristicMaps
    eddy_resistance: str
    circuit_names: tuple[str, ...]
    gap_names: tuple[str, ...]
    pole_groups: Mapping[str, tuple[str, ...]]
    averaging: np.ndarray
    share: np.ndarray
    resistance_ohm: np.ndarray
    eddy_resistance_ohm: np.ndarray
    a: np.ndarray
    gaps_m: np.ndarray
    currents_A: np.ndarray
    extended_gaps_m: np.ndarray
    extended_currents_A: np.ndarray
    gap_range_m: tuple[float, float]
    current_range_A: tuple[float, float]
    gap_tolerance_m: float
    current_tolerance_A: float

    @classmethod
    def from_maps(cls, maps: CharacteristicMaps, *, eddy_resistance: str | None = "fit",
                  what: str = "") -> ReducedCore:
        """Derive the core of ``maps``.

        Parameters
        ----------
        maps : CharacteristicMaps
            The maps.
        eddy_resistance : {"fit", "jump"} or None
            Which ``R_ec`` eq. 8 uses (None: ``"fit"``).
        what : str, optional
            Prefix of error messages (e.g. ``"member 'm1': "``).

        Returns
        -------
        ReducedCore

        Raises
        ------
        InputError
            An unknown ``eddy_resistance``, or maps without that ``R_ec``.
        """
        choice = "fit" if eddy_resistance is None else eddy_resistance
        var = EDDY_RESISTANCE_CHOICES.get(choice) if isinstance(choice, str) else None
        if var is None:
            raise InputError(f"{what}eddy_resistance = {eddy_resistance!r}; use 'fit' or "
                             "'jump' (or None: the fit)")
        circuits = tuple(maps.circuits)
        groups = maps.pole_groups
        attr = maps.dataset.attrs.get("gap_names")
        gap_names = (tuple(str(attr).split(",")) if attr
                     else tuple(g for c in circuits for g in groups[c]))
        gi = {g: k for k, g in enumerate(gap_names)}
        nc, ng = len(circuits), len(gap_names)
        avg = np.zeros((nc, ng))
        for j, c in enumerate(circuits):
            for g in groups[c]:
                avg[j, gi[g]] = 1.0 / len(groups[c])
        share = (avg > 0).T / np.maximum((avg > 0).sum(axis=1), 1)
        r_el = np.asarray(maps.dataset["resistance_ohm"].values, dtype=float)
        if var not in maps.dataset:
            raise InputError(f"{what}these maps have no {var!r}; rebuild them with this version")
        r_ec = np.asarray(maps.dataset[var].values, dtype=float)
        gs, gi_ = maps.gaps_m, maps.currents_A
        gap_range = (float(gs[0]), float(gs[-1]))
        current_range = (float(gi_[0]), float(gi_[-1]))
        arrays = dict(averaging=avg, share=share, resistance_ohm=r_el, eddy_resistance_ohm=r_ec,
                      a=eq8_a(r_el, r_ec), gaps_m=gs, currents_A=gi_,
                      extended_gaps_m=extend_axis(gs), extended_currents_A=extend_axis(gi_))
        for v in arrays.values():
            v.flags.writeable = False
        return cls(maps=maps, eddy_resistance=choice, circuit_names=circuits,
                   gap_names=gap_names, pole_groups=groups,
                   gap_range_m=gap_range, current_range_A=current_range,
                   gap_tolerance_m=GAP_TOLERANCE * gap_range[1],
                   current_tolerance_A=CURRENT_TOLERANCE * max(1.0, current_range[1]),
                   **arrays)

    @property
    def n_circuits(self) -> int:
        """Number of circuits."""
        return len(self.circuit_names)

    @property
    def n_gaps(self) -> int:
        """Number of gap inputs (poles)."""
        return len(self.gap_names)

    def state_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the state ``[I_L [A]; s [m]]`` with the rounding
        allowances (the range check of every RK4 sub-step).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            Each ``2 n_circuits`` long: currents [A] then gaps [m].
        """
        nc = self.n_circuits
        ti, ts = self.current_tolerance_A, self.gap_tolerance_m
        lo = np.concatenate([np.full(nc, self.current_range_A[0] - ti),
                             np.full(nc, self.gap_range_m[0] - ts)])
        hi = np.concatenate([np.full(nc, self.current_range_A[1] + ti),
                             np.full(nc, self.gap_range_m[1] + ts)])
        return lo, hi


def eq8_a(r_el: Any, r_ec: Any) -> Any:
    """``a = 1 + R_el/R_ec`` of eq. 8 (1 where ``R_ec`` is infinite: no eddy branch).

    Parameters
    ----------
    r_el : float or numpy.ndarray
        ``R_el`` [ohm].
    r_ec : float or numpy.ndarray
        ``R_ec`` [ohm].

    Returns
    -------
    float or numpy.ndarray
        ``a`` [-] (a float for float inputs).
    """
    if np.ndim(r_el) == 0 and np.ndim(r_ec) == 0:
        return 1.0 if math.isinf(float(r_ec)) else 1.0 + float(r_el) / float(r_ec)
    r_el, r_ec = np.asarray(r_el, dtype=float), np.asarray(r_ec, dtype=float)
    return 1.0 + np.where(np.isinf(r_ec), 0.0, r_el / np.where(np.isinf(r_ec), 1.0, r_ec))


@dataclass(frozen=True, eq=False)
class MotionEddyLadder:
    """The shielded-gap ladder of a set of maps (``motion_eddy=True``), read and checked once.

    The ladder ``R_el`` -- shunt ``R_a`` -- series ``L_u`` -- shunt ``R_2 || L(s, I_L)``
    (:mod:`maglevkit.reduction.motion_eddy`; the law is
    :func:`~maglevkit.reduced.current.eq8_shielded_gap_rhs`).  Both
    :class:`~maglevkit.reduced.current.CurrentModel` and
    :class:`~maglevkit.reduced.bank.MagnetBank` take its parameters, its ``a`` and its RK4
    sub-step limit from here.  Build it with :meth:`from_maps`.  Arrays are read-only.

    Parameters
    ----------
    jump_resistance_ohm : numpy.ndarray (n_circuits,)
        The shunt ``R_a`` [ohm] (takes eq. 8's ``R_ec`` place).
    shielding_resistance_ohm : numpy.ndarray (n_circuits,)
        ``R_2`` [ohm], the shielding eddy path of the gap section.
    unshielded_inductance_H : numpy.ndarray (n_circuits,)
        The series ``L_u`` [H].
    unshielded_share : numpy.ndarray (n_circuits,)
        ``beta`` [-], the share of the motion-induced voltage in ``L_u`` (0 in maps built
        before it was identified: the ladder as it was fitted then).
    force_share : numpy.ndarray (n_circuits,)
        ``gamma`` [-], the share of ``I_e`` in the force current ``I_L + gamma I_e``
        (:func:`~maglevkit.reduced.current.shielded_gap_force_current`; 0 in maps built
        before it was identified: the force ``F(s, I_L)`` of those maps).
    a : numpy.ndarray (n_circuits,)
        ``1 + R_el/R_a`` [-].
    max_step_s : float
        The longest stable RK4 sub-step [s]: ``1.5/lambda`` with ``lambda`` the Gershgorin
        bound of the ladder's rates with the maps' smallest ``L~ - L_u``.
    """

    jump_resistance_ohm: np.ndarray
    shielding_resistance_ohm: np.ndarray
    unshielded_inductance_H: np.ndarray
    unshielded_share: np.ndarray
    force_share: np.ndarray
    a: np.ndarray
    max_step_s: float

    @classmethod
    def from_maps(cls, maps: CharacteristicMaps, *, resistance_ohm: np.ndarray,
                  what: str = "") -> MotionEddyLadder:
        """Read the ladder of ``maps`` and check it.

        Parameters
        ----------
        maps : CharacteristicMaps
            The maps (with the ``motion_eddy_*`` variables of ``build_maps``).
        resistance_ohm : numpy.ndarray (n_circuits,)
            ``R_el`` of the maps' circuits [ohm].
        what : str, optional
            Prefix of error messages (e.g. ``"member 'm1': "``).

        Returns
        -------
        MotionEddyLadder

        Raises
        ------
        InputError
            Maps without a ladder (imported from a table, built by an older version, or
            of a magnet without eddy currents), or maps whose smallest ``L~`` is not above
            ``L_u``.
        """
        from ..reduction.motion_eddy import FORCE_SHARE_VARIABLE, SHARE_VARIABLE

        ds = maps.dataset
        names = ("motion_eddy_jump_resistance_ohm", "motion_eddy_shielding_resistance_ohm",
                 "motion_eddy_unshielded_inductance_H")
        missing = [n for n in names if n not in ds]
        if missing:
            raise InputError(what + (
                "maps imported from a table (maps_from_table) cannot carry the shielded-gap "
                "ladder (it is fitted to the detailed flux model's frequency response, which "
                "a table does not have); use motion_eddy=False" if "table_report" in ds.attrs
                else f"these maps have no shielded-gap ladder ({', '.join(missing)}); rebuild "
                "them with this version (build_maps) to use motion_eddy=True"))
        r_a, r_2, l_u = (np.array(ds[n].values, dtype=float) for n in names)
        # the unshielded share of the motion term (docs/reduction.md, "Gap motion"); maps
        # built before it was identified had their ladder fitted without it: 0
        beta = (np.array(ds[SHARE_VARIABLE].values, dtype=float) if SHARE_VARIABLE in ds
                else np.zeros_like(r_a))
        # the force share of I_e (docs/equations.md section 8); maps built before it was
        # identified: 0, the force F(s, I_L)
        gamma = (np.array(ds[FORCE_SHARE_VARIABLE].values, dtype=float)
                 if FORCE_SHARE_VARIABLE in ds else np.zeros_like(r_a))
        if not (np.all(np.isfinite(r_a)) and np.all(np.isfinite(r_2))
                and np.all(np.isfinite(l_u)) and np.all(r_a > 0) and np.all(r_2 > 0)
                and np.all(l_u > 0) and np.all(np.isfinite(beta))
                and np.all(np.isfinite(gamma))):
            raise InputError(f"{what}these maps have no shielded-gap ladder to use (the magnet "
                             "has no eddy currents); use motion_eddy=False")
        circuits = tuple(maps.circuits)
        lt_min = np.array([float(np.min(maps.variable("inductance_H", c))) for c in circuits])
        if np.any(lt_min <= l_u):
            j = int(np.argmax(lt_min <= l_u))
            raise InputError(f"{what}motion_eddy=True: the maps' smallest L~ of circuit "
                             f"{circuits[j]!r}, {lt_min[j]:.4g} H, is not above "
                             f"the ladder's L_u = {l_u[j]:.4g} H (the gap section would "
                             "have no inductance left); use motion_eddy=False or maps "
                             "that stay out of such deep saturation")
        r_el = np.asarray(resistance_ohm, dtype=float)
        a = eq8_a(r_el, r_a)
        # RK4 stability: Gershgorin bound of the ladder's rates in (I_u, I_L) with the
        # smallest L~ - L_u over the maps (module reduction.motion_eddy; the share of the
        # motion term is an input term and does not move them)
        rate = float(np.max(np.maximum((r_el / a + 2.0 * r_2) / l_u,
                                       2.0 * r_2 / (lt_min - l_u))))
        for v in (r_a, r_2, l_u, beta, gamma, a):
            v.flags.writeable = False
        return cls(jump_resistance_ohm=r_a, shielding_resistance_ohm=r_2,
                   unshielded_inductance_H=l_u, unshielded_share=beta, force_share=gamma, a=a,
                   max_step_s=1.5 / rate)
