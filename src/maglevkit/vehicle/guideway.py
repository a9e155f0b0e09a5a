"""Elastic guideway: simply supported Euler-Bernoulli spans in modal form.

A Transrapid guideway is a chain of single-span girders, each simply supported on its own
piers, so the spans are mechanically independent.  Each span is described by its first
``n`` sine modes (the exact eigenfunctions of a simply supported Euler-Bernoulli beam)::

    w(x, t) = sum_j q_j(t) sin(j pi xi / L),        xi = x - x_pier   (0 <= xi <= L)
    M q_j'' + 2 zeta_j omega_j M q_j' + omega_j^2 M q_j = sum_k F_k sin(j pi xi_k / L)
    M = m L / 2,   omega_j = (j pi / L)^2 sqrt(EI / m)

with point loads ``F_k`` [N] (positive downward, like ``w``) at ``xi_k``.  The modal
equations are linear; :meth:`BeamSpan.discretize` gives their exact discretisation for
forces held over a step (zero-order hold), :meth:`BeamSpan.modal_rhs` the right-hand side
for NumPy or CasADi.

:class:`Guideway` chains the spans.  With ``moving_boundary=True`` only a window of
``n_spans`` consecutive spans is integrated (a ring buffer of span states): when every load
has left the rearmost span, that span is reset to rest and reused as the next span ahead.
This is exact for the loads, because the spans are independent and a span ahead of the
train is at rest until the train reaches it (the paper's "moving system boundary").
Equations and sources: ``docs/vehicle.md``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from ..errors import InputError, OutOfRangeError, ParameterError
from ..plant import STANDARD_GRAVITY
from ..validation import (
    Plausible,
    check_plausible,
    flag,
    real_array,
    real_number,
    renamed_keywords,
    whole_number,
)
from .zoh import exact_zoh_step

__all__ = ["BeamSpan", "Guideway", "GuidewayState", "GuidewayDeflection", "GUIDEWAY_PLAUSIBLE"]

#: The plausible magnitudes of every dimensional key of a guideway file
#: (:func:`~maglevkit.validation.check_plausible`; docs/decisions.md); :class:`BeamSpan`
#: checks its arguments against the same ranges.
GUIDEWAY_PLAUSIBLE: dict[str, Plausible] = {
    "guideway.span_length": Plausible(2.0, 200.0, "m"),
    "guideway.mass_per_length": Plausible(100.0, 1e5, "kg/m"),
    "guideway.bending_stiffness": Plausible(1e8, 1e13, "N m^2"),
    # built-in camber: mm on real spans (2.7 mm bundled); 0 (none) is always plausible
    "guideway.precamber": Plausible(1e-4, 0.05, "m"),
}
#: BeamSpan argument -> its guideway-file key (the one table of ranges above)
_SPAN_KEYS = {"length_m": "span_length", "mass_per_length_kg_per_m": "mass_per_length",
              "bending_stiffness_N_m2": "bending_stiffness", "precamber_m": "precamber"}


def _positive(name: str, value: float, unit: str) -> float:
    return real_number(value, name, unit, positive=True, error=ParameterError)


def _count(name: str, value: Any, minimum: int) -> int:
    try:
        return whole_number(value, name, minimum=minimum)
    except InputError as exc:
        raise ParameterError(str(exc)) from None


@dataclass(frozen=True)
class BeamSpan:
    """One simply supported Euler-Bernoulli span, described by its first sine modes.

    Parameters
    ----------
    length_m : float
        Span length ``L`` between the supports [m] (> 0).
    bending_stiffness_N_m2 : float
        Bending stiffness ``EI`` [N m^2] (> 0).
    mass_per_length_kg_per_m : float
        Mass per unit length ``m`` [kg/m] (> 0).
    n_modes : int
        Number of sine modes (>= 1).
    damping_ratio : float or sequence of float
        Modal damping ratio ``zeta_j`` [-], one value for all modes or one per mode
        (each >= 0; 0 = undamped).
    precamber_m : float
        Built-in upward camber of the unloaded girder at midspan [m] (finite; 0: a
        straight girder), along the uniform-load deflection line, so that a uniform load
        ``q`` with ``5 q L^4 / (384 EI) = precamber_m`` leaves the girder straight
        (:meth:`uniform_load_midspan_deflection_m`, :attr:`Guideway.built_in_profile`).
    """

    length_m: float
    bending_stiffness_N_m2: float
    mass_per_length_kg_per_m: float
    n_modes: int = 5
    damping_ratio: float | tuple[float, ...] = 0.01
    precamber_m: float = 0.0
    _zeta: np.ndarray = field(init=False, repr=False, compare=False)
    _k: np.ndarray = field(init=False, repr=False, compare=False)
    _omega: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name, unit in (("length_m", "m"), ("bending_stiffness_N_m2", "N m^2"),
                           ("mass_per_length_kg_per_m", "kg/m")):
            object.__setattr__(self, name, _positive(name, getattr(self, name), unit))
        object.__setattr__(self, "n_modes", _count("n_modes", self.n_modes, 1))
        # as the guideway file: a negative camber is refused, an implausible value warns
        object.__setattr__(self, "precamber_m", real_number(self.precamber_m, "precamber_m",
                                                            "m", nonnegative=True,
                                                            error=ParameterError))
        check_plausible({"BeamSpan": {arg: getattr(self, arg) for arg in _SPAN_KEYS}},
                        {f"BeamSpan.{arg}": GUIDEWAY_PLAUSIBLE[f"guideway.{key}"]
                         for arg, key in _SPAN_KEYS.items()}, stacklevel=4)
        d = self.damping_ratio
        if isinstance(d, Sequence) and not isinstance(d, str):
            if len(d) != self.n_modes:
                raise ParameterError(f"damping_ratio must be one number or {self.n_modes} numbers "
                                     f"(one per mode), got {d!r}")
            vals = tuple(real_number(v, "damping_ratio", nonnegative=True, error=ParameterError)
                         for v in d)
            zeta = np.array(vals)
            object.__setattr__(self, "damping_ratio", vals)
        else:
            z = real_number(d, "damping_ratio", nonnegative=True, error=ParameterError)
            zeta = np.full(self.n_modes, z)
            object.__setattr__(self, "damping_ratio", z)
        k = np.arange(1, self.n_modes + 1) * math.pi / self.length_m
        omega = k ** 2 * math.sqrt(self.bending_stiffness_N_m2 / self.mass_per_length_kg_per_m)
        for name, v in (("_zeta", zeta), ("_k", k), ("_omega", omega)):
            v.setflags(write=False)
            object.__setattr__(self, name, v)

    # ------------------------------------------------------------------ modal data
    @property
    def damping_ratios(self) -> np.ndarray:
        """Modal damping ratios ``zeta_j`` (n_modes,) [-]."""
        return self._zeta

    @property
    def wavenumbers_rad_per_m(self) -> np.ndarray:
        """``k_j = j pi / L`` (n_modes,) [rad/m]."""
        return self._k

    @property
    def natural_frequencies_rad_per_s(self) -> np.ndarray:
        """``omega_j = k_j^2 sqrt(EI/m)`` (n_modes,) [rad/s]."""
        return self._omega

    @property
    def natural_frequencies_Hz(self) -> np.ndarray:
        """``f_j = omega_j / (2 pi)`` (n_modes,) [Hz]."""
        return self.natural_frequencies_rad_per_s / (2 * math.pi)

    @property
    def modal_mass_kg(self) -> float:
        """Generalised mass of every sine mode, ``m L / 2`` [kg]."""
        return 0.5 * self.mass_per_length_kg_per_m * self.length_m

    def speed_parameter(self, speed_m_per_s: float) -> float:
        """Fryba's speed parameter ``alpha = v / (2 f_1 L)`` [-] (1 = critical speed).

        Parameters
        ----------
        speed_m_per_s : float
            Speed of the moving load [m/s] (not checked).

        Returns
        -------
        float
            ``alpha`` [-], with ``f_1`` the first natural frequency [Hz].
        """
        return float(speed_m_per_s) / (2.0 * float(self.natural_frequencies_Hz[0]) * self.length_m)

    def static_midspan_deflection_m(self, force_N: float) -> float:
        """Exact static midspan deflection under a midspan point force, ``F L^3 / (48 EI)``.

        Parameters
        ----------
        force_N : float
            Point force at midspan [N], positive downward (not checked).

        Returns
        -------
        float
            Midspan deflection [m], positive downward.
        """
        return float(force_N) * self.length_m ** 3 / (48.0 * self.bending_stiffness_N_m2)

    def uniform_load_midspan_deflection_m(self, load_N_per_m: float) -> float:
        """Exact static midspan deflection under a uniform load, ``5 q L^4 / (384 EI)`` [m].

        Parameters
        ----------
        load_N_per_m : float
            Uniform load ``q`` over the whole span [N/m], positive downward (not checked).

        Returns
        -------
        float
            Midspan deflection [m], positive downward.
        """
        return 5.0 * float(load_N_per_m) * self.length_m ** 4 / (
            384.0 * self.bending_stiffness_N_m2)

    @renamed_keywords(gravity="gravity_m_per_s2")
    def self_weight_sag_m(self, gravity_m_per_s2: float = STANDARD_GRAVITY) -> float:
        """Exact static midspan sag under the span's own weight, ``5 m g L^4 / (384 EI)`` [m].

        Old keyword names (``gravity``) are deprecated aliases for one release.

        Parameters
        ----------
        gravity_m_per_s2 : float, default STANDARD_GRAVITY
            Gravitational acceleration g [m/s^2] (9.80665; not checked).

        Returns
        -------
        float
            Midspan sag [m], positive downward.
        """
        return self.uniform_load_midspan_deflection_m(self.mass_per_length_kg_per_m * gravity_m_per_s2)

    def mode_shapes(self, local_x_m: Any) -> tuple[np.ndarray, np.ndarray]:
        """Mode shapes ``sin(k_j xi)`` and their slopes ``k_j cos(k_j xi)`` [1/m].

        Parameters
        ----------
        local_x_m : array_like
            Positions ``xi`` from the span's left support [m] (0 <= xi <= L).

        Returns
        -------
        (phi, dphi_dx) : ndarray (..., n_modes) each
        """
        arg = np.multiply.outer(np.asarray(local_x_m, dtype=float), self._k)
        return np.sin(arg), self._k * np.cos(arg)

    def static_modal_displacement(self, modal_force_N: Any) -> np.ndarray:
        """Static modal response ``q_j = Q_j / (M omega_j^2)`` [m] to generalised forces [N].

        Parameters
        ----------
        modal_force_N : array_like (..., n_modes)
            Generalised forces ``Q_j`` [N], modes on the last axis (not checked).

        Returns
        -------
        ndarray (..., n_modes)
            Modal displacements ``q_j`` [m].
        """
        return np.asarray(modal_force_N, dtype=float) / (
            self.modal_mass_kg * self.natural_frequencies_rad_per_s ** 2)

    # ------------------------------------------------------------------ equations of motion
    def state_space(self) -> tuple[np.ndarray, np.ndarray]:
        """``dx/dt = A x + B Q`` with ``x = [q; q']`` (2 n) and generalised forces ``Q`` (n) [N]."""
        n = self.n_modes
        om = self.natural_frequencies_rad_per_s
        a = np.zeros((2 * n, 2 * n))
        a[:n, n:] = np.eye(n)
        a[n:, :n] = -np.diag(om ** 2)
        a[n:, n:] = -np.diag(2.0 * self._zeta * om)
        b = np.zeros((2 * n, n))
        b[n:, :] = np.eye(n) / self.modal_mass_kg
        return a, b

    def modal_rhs(self, q: Any, q_dot: Any, modal_force_N: Any) -> tuple[Any, Any]:
        """Right-hand side of the modal equations: ``(dq/dt, d2q/dt2)``.

        Works elementwise on NumPy arrays (any leading batch axes, modes last) and on
        CasADi column vectors (``SX``/``MX``/``DM`` of length n_modes), so the same
        function builds the guideway part of a CasADi vehicle model.

        Parameters
        ----------
        q, q_dot : array_like or CasADi
            Modal displacements [m] and velocities [m/s].
        modal_force_N : array_like or CasADi
            Generalised forces ``Q_j = sum_k F_k sin(k_j xi_k)`` [N].
        """
        om = self.natural_frequencies_rad_per_s
        c, k, inv_m = 2.0 * self._zeta * om, om ** 2, 1.0 / self.modal_mass_kg
        if _is_casadi(q) or _is_casadi(q_dot) or _is_casadi(modal_force_N):
            import casadi as ca

            cd, kd = ca.DM(c), ca.DM(k)
            return q_dot, inv_m * modal_force_N - cd * q_dot - kd * q
        q_dot = np.asarray(q_dot, dtype=float)
        return q_dot, inv_m * np.asarray(modal_force_N, dtype=float) - c * q_dot - k * np.asarray(q)

    def discretize(self, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Exact discretisation for forces held over a step: ``x+ = Ad x + Bd Q``.

        ``Ad = exp(A dt)``, ``Bd = int_0^dt exp(A s) ds B`` (zero-order hold), computed
        from the matrix exponential of the augmented matrix ``[[A, B], [0, 0]] dt``.

        Parameters
        ----------
        dt_s : float
            Step [s], finite and > 0 (``InputError`` otherwise).

        Returns
        -------
        (Ad, Bd) : ndarray (2 n_modes, 2 n_modes) and (2 n_modes, n_modes)
            Read-only matrices for the state ``x = [q; q']`` ([m], [m/s]) and generalised
            forces ``Q`` [N]; cached per span and step.
        """
        dt = _check_dt(dt_s)
        return _discretize_cached(self.length_m, self.bending_stiffness_N_m2,
                                  self.mass_per_length_kg_per_m, tuple(self._zeta.tolist()), dt)


def _is_casadi(v: Any) -> bool:
    mod = type(v).__module__
    return mod.startswith("casadi")


def _check_dt(dt: Any) -> float:
    return real_number(dt, "dt", "s", positive=True)


@lru_cache(maxsize=64)
def _discretize_cached(length: float, ei: float, m: float, zeta: tuple[float, ...],
                       dt: float) -> tuple[np.ndarray, np.ndarray]:
    span = BeamSpan(length, ei, m, n_modes=len(zeta), damping_ratio=zeta)
    a, b = span.state_space()
    ad, bd = exact_zoh_step(a, b, dt)
    ad.setflags(write=False)
    bd.setflags(write=False)
    return ad, bd


@dataclass(frozen=True)
class GuidewayState:
    """State of the integrated spans at one instant.

    The window holds spans ``first_span ... first_span + n_spans - 1``; span ``k`` lives
    in row ``k mod n_spans`` of the arrays (a ring buffer: a recycled span keeps its row).

    Attributes
    ----------
    time_s : float
        Time [s].
    first_span : int
        Index of the rearmost integrated span (span ``k`` lies on
        ``[x0 + k L, x0 + (k + 1) L]``).
    modal_displacement_m : ndarray (n_spans, n_modes)
        ``q_j`` per ring-buffer row [m].
    modal_velocity_m_per_s : ndarray (n_spans, n_modes)
        ``q_j'`` per ring-buffer row [m/s].
    """

    time_s: float
    first_span: int
    modal_displacement_m: np.ndarray
    modal_velocity_m_per_s: np.ndarray


@dataclass(frozen=True)
class GuidewayDeflection:
    """Guideway deflection at given positions (positive downward).

    Attributes
    ----------
    position_m : ndarray
        Positions along the guideway [m].
    deflection_m : ndarray
        ``w(x, t)`` [m].
    slope : ndarray
        ``dw/dx`` [m/m].
    rate_m_per_s : ndarray
        ``dw/dt`` at fixed ``x`` [m/s].
    """

    position_m: np.ndarray
    deflection_m: np.ndarray
    slope: np.ndarray
    rate_m_per_s: np.ndarray

    def moving_rate_m_per_s(self, speed_m_per_s: Any) -> np.ndarray:
        """Rate seen by a point moving at ``v``: ``dw/dt + v dw/dx`` [m/s].

        Parameters
        ----------
        speed_m_per_s : float or array_like
            Speed ``v`` of the moving point [m/s] (broadcast against the positions).

        Returns
        -------
        ndarray
            ``dw/dt + v dw/dx`` [m/s] at each position.
        """
        return self.rate_m_per_s + np.asarray(speed_m_per_s, dtype=float) * self.slope


class Guideway:
    """A periodically pillared guideway of independent simply supported spans.

    Parameters
    ----------
    span : BeamSpan
        The (identical) spans.
    n_spans : int
        Number of integrated spans: the window of the moving system boundary, or the
        whole guideway with ``moving_boundary=False``.  The window must cover every span
        that carries a load at once (see :meth:`spans_needed`).
    moving_boundary : bool
        True: the window follows the loads; a span every load has left is reset to rest
        and reused ahead (an infinitely long guideway).  False: a guideway of exactly
        ``n_spans`` spans, ``first_span ... first_span + n_spans - 1`` of the initial state.
    rigid : bool
        A rigid guideway (no deflection, no states; loads are accepted and ignored).
    origin_m : float
        Position of pier 0 [m]; pier ``k`` stands at ``origin_m + k L``.
    """

    def __init__(self, span: BeamSpan, *, n_spans: int = 3, moving_boundary: bool = True,
                 rigid: bool = False, origin_m: float = 0.0) -> None:
        if not isinstance(span, BeamSpan):
            raise ParameterError(f"span must be a BeamSpan, got {type(span).__name__}")
        self.span = span
        self.n_spans = _count("n_spans", n_spans, 1)
        self.moving_boundary = flag(moving_boundary, "moving_boundary")
        self.rigid = flag(rigid, "rigid")
        self.origin_m = real_number(origin_m, "origin_m", "m", error=ParameterError)
        self.n_modes = 0 if rigid else span.n_modes

    def __repr__(self) -> str:
        kind = "rigid" if self.rigid else f"{self.n_modes} modes"
        mode = "moving boundary" if self.moving_boundary else "fixed"
        return (f"Guideway(L={self.span.length_m} m, {kind}, {self.n_spans} spans, {mode})")

    @property
    def built_in_profile(self) -> Any:
        """The girders' built-in shape as a guideway profile, or None.

        The precamber of :attr:`BeamSpan.precamber_m` as a camber of every span along the
        uniform-load deflection line (:class:`~maglevkit.vehicle.irregularities.SpanSag`
        with amplitude ``-precamber_m``, positive downward like an irregularity ``r``):
        in the gap ``s = s_0 + u - w - r`` a built-in camber and an irregularity are the
        same term, so a vehicle run adds this profile to its irregularity once, where it
        evaluates the profile along the paths of the force points.  None for a straight
        girder or a rigid guideway (an ideal, even track).
        """
        if self.rigid or self.span.precamber_m == 0.0:
            return None
        from .irregularities import SpanSag

        return SpanSag(-self.span.precamber_m, self.span.length_m, origin_m=self.origin_m)

    def spans_needed(self, load_extent_m: float) -> int:
        """Smallest window that always covers loads spread over ``load_extent_m`` [m].

        Parameters
        ----------
        load_extent_m : float
            Distance from the rearmost to the foremost load [m], >= 0
            (``InputError`` otherwise).

        Returns
        -------
        int
            ``floor(extent / L) + 2`` spans (1 for a single point load).
        """
        load_extent_m = real_number(load_extent_m, "load_extent_m", "m", nonnegative=True)
        return int(math.floor(load_extent_m / self.span.length_m)) + 2 if load_extent_m > 0 else 1

    # ------------------------------------------------------------------ state
    def initial_state(self, *, first_span: int = 0, time_s: float = 0.0) -> GuidewayState:
        """All spans at rest; the window starts at span ``first_span``.

        With the moving boundary start it at the rearmost load,
        ``first_span=int(guideway.span_index(x_rear))``; the window then follows the loads.

        Parameters
        ----------
        first_span : int, default 0
            Index of the rearmost integrated span (span ``k`` starts at
            ``origin_m + k L``); keyword only.
        time_s : float, default 0.0
            Time of the state [s].

        Returns
        -------
        GuidewayState
            Zero modal displacements and velocities (shape ``(n_spans, n_modes)``; no
            modes for a rigid guideway).

        Raises
        ------
        InputError
            ``first_span`` not a whole number or ``time_s`` not a finite real number.
        """
        first_span = whole_number(first_span, "first_span")
        time_s = real_number(time_s, "time_s", "s")
        z = np.zeros((self.n_spans, self.n_modes))
        return GuidewayState(time_s, first_span, z, z.copy())

    def span_index(self, position_m: Any) -> np.ndarray:
        """Index ``k`` of the span each position lies on (a pier belongs to the span ahead).

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m] (not checked: NaN gives a meaningless index).

        Returns
        -------
        ndarray of int
            ``floor((x - origin_m) / L)``, same shape as ``position_m``.
        """
        x = np.asarray(position_m, dtype=float)
        return np.floor((x - self.origin_m) / self.span.length_m).astype(int)

    def _locate(self, state: GuidewayState, x: np.ndarray, *, for_loads: bool
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Span indices, ring rows and local coordinates; checks that x is covered."""
        k = self.span_index(x)
        lo, hi = state.first_span, state.first_span + self.n_spans - 1
        behind = k < lo
        ahead = k > hi
        if behind.any():
            what = ("recycled by the moving system boundary" if self.moving_boundary
                    else "not part of this guideway")
            raise OutOfRangeError(
                f"position {float(x[behind].min()):.6g} m lies on span {int(k[behind].min())}, "
                f"which is {what}; integrated spans are {lo} ... {hi} "
                f"({self.origin_m + lo * self.span.length_m:.6g} ... "
                f"{self.origin_m + (hi + 1) * self.span.length_m:.6g} m)")
        if ahead.any() and (for_loads or not self.moving_boundary):
            need = int(k.max() - k.min()) + 1
            hint = (f"; the loads cover {need} spans, use n_spans >= {need}"
                    if self.moving_boundary else "")
            raise OutOfRangeError(
                f"position {float(x[ahead].max()):.6g} m lies on span {int(k[ahead].max())}, "
                f"beyond the integrated spans {lo} ... {hi}{hint}")
        xi = x - (self.origin_m + k * self.span.length_m)
        return k, np.mod(k, self.n_spans), xi

    def advance(self, state: GuidewayState, rear_position_m: float) -> GuidewayState:
        """Move the window so that it starts at the span under ``rear_position_m``.

        Spans behind it are reset to rest and reused ahead (moving boundary only; a
        window never moves backwards).

        Parameters
        ----------
        state : GuidewayState
            The current state.
        rear_position_m : float
            Position of the rearmost load [m].

        Returns
        -------
        GuidewayState
            The state with the moved window; ``state`` itself when the window does not
            move, without the moving boundary, or for a rigid guideway.
        """
        if not self.moving_boundary or self.rigid:
            return state
        rear_position_m = real_number(rear_position_m, "rear_position_m", "m")
        k_new = int(self.span_index(rear_position_m))
        shift = k_new - state.first_span
        if shift <= 0:
            return state
        q = state.modal_displacement_m.copy()
        qd = state.modal_velocity_m_per_s.copy()
        rows = np.mod(np.arange(state.first_span, state.first_span + min(shift, self.n_spans)),
                      self.n_spans)
        q[rows] = 0.0
        qd[rows] = 0.0
        return GuidewayState(state.time_s, k_new, q, qd)

    def window_schedule(self, rear_m: Any, front_m: Any, *, first_span: int
                        ) -> tuple[np.ndarray, np.ndarray, int]:
        """The moving system boundary over a whole run, computed once (both vehicle loops).

        At every step the window starts at the span under the rearmost load (never moving
        back; fixed without the moving boundary); the ring rows of the spans it leaves
        are reset to rest at that step, the rule of :meth:`advance`.

        Parameters
        ----------
        rear_m, front_m : array_like (n_steps,)
            Rearmost and foremost load position [m] of every step (the foremost including
            the half-step advance the modal update uses).
        first_span : int
            First span of the window at the first step.

        Returns
        -------
        (first_k, keep, k_out) : ndarray (n_steps,) of int, ndarray (n_steps, n_spans), int
            The window's first span per step; 1.0 for a ring row kept, 0.0 for one reset
            at that step; the first step whose loads leave the window (-1: none).
        """
        lo = self.span_index(rear_m)
        hi = self.span_index(front_m)
        first_k = (np.maximum.accumulate(np.maximum(lo, int(first_span)))
                   if self.moving_boundary else np.full(lo.shape, int(first_span)))
        out = (lo < first_k) | (hi > first_k + self.n_spans - 1)
        keep = np.ones((lo.size, self.n_spans))
        for kr in (np.flatnonzero(np.diff(first_k) > 0) + 1).tolist():
            old = int(first_k[kr - 1])
            keep[kr, np.arange(old, min(int(first_k[kr]), old + self.n_spans)) % self.n_spans] = 0.0
        return first_k, keep, int(np.argmax(out)) if out.any() else -1

    # ------------------------------------------------------------------ loads and outputs
    def _positions(self, positions_m: Any) -> np.ndarray:
        x = np.atleast_1d(real_array(positions_m, "positions_m", "m"))
        if x.ndim != 1:
            raise InputError("positions_m must be a scalar or a 1-D sequence [m]")
        return x

    def influence(self, state: GuidewayState, positions_m: Any) -> tuple[np.ndarray, np.ndarray]:
        """Modal influence matrices of point loads at ``positions_m``.

        Parameters
        ----------
        state : GuidewayState
            Gives the window of integrated spans.
        positions_m : float or array_like (n_points,)
            Load positions [m]; each must lie on an integrated span.

        Returns
        -------
        (phi, dphi_dx) : ndarray (n_spans, n_modes, n_points) each
            ``phi[r, j, p] = sin(k_j xi_p)`` if point ``p`` lies on the span in ring row
            ``r``, else 0; so ``Q = phi @ F`` are the generalised forces of point forces
            ``F`` and ``w = einsum('rj,rjp->p', q, phi)`` the deflections.  Constant over a
            step for loads held in place; the CasADi vehicle model takes them as inputs.

        Raises
        ------
        InputError
            Positions not finite real numbers, or not a scalar or 1-D sequence.
        OutOfRangeError
            A position on a span behind the window (recycled, or not part of the guideway)
            or ahead of it.
        """
        x = self._positions(positions_m)
        nm = self.n_modes
        phi = np.zeros((self.n_spans, nm, x.size))
        dphi = np.zeros_like(phi)
        if nm == 0 or x.size == 0:
            return phi, dphi
        _, rows, xi = self._locate(state, x, for_loads=True)
        s, ds = self.span.mode_shapes(xi)          # (n_points, n_modes)
        cols = np.arange(x.size)
        phi[rows, :, cols] = s
        dphi[rows, :, cols] = ds
        return phi, dphi

    def modal_forces(self, state: GuidewayState, positions_m: Any, forces_N: Any) -> np.ndarray:
        """Generalised forces (n_spans, n_modes) [N] of point forces (positive downward).

        Parameters
        ----------
        state : GuidewayState
            Gives the window of integrated spans.
        positions_m : float or array_like (n_points,)
            Load positions [m]; each must lie on an integrated span.
        forces_N : float or array_like (n_points,)
            Point forces [N], positive downward: one for all positions or one per position.

        Returns
        -------
        ndarray (n_spans, n_modes)
            ``Q_j = sum_k F_k sin(k_j xi_k)`` [N] per ring-buffer row.

        Raises
        ------
        InputError
            Non-finite or wrongly shaped positions or forces.
        OutOfRangeError
            A position outside the integrated spans.
        """
        x = self._positions(positions_m)
        f = real_array(forces_N, "forces_N", "N")
        if f.ndim > 1 or f.size not in (1, x.size):
            raise InputError(f"forces_N: one force or one per position ({x.size}), got shape "
                             f"{f.shape}")
        f = np.broadcast_to(f, x.shape)
        out = np.zeros((self.n_spans, self.n_modes))
        if self.n_modes == 0 or x.size == 0:
            return out
        _, rows, xi = self._locate(state, x, for_loads=True)
        s, _ = self.span.mode_shapes(xi)
        np.add.at(out, rows, s * f[:, None])
        return out

    def deflection(self, state: GuidewayState, positions_m: Any) -> GuidewayDeflection:
        """Deflection, slope and rate at ``positions_m`` (on integrated spans, or ahead of
        the window with the moving boundary, where the spans are at rest).

        Parameters
        ----------
        state : GuidewayState
            The state to evaluate.
        positions_m : float or array_like (n_points,)
            Positions [m].

        Returns
        -------
        GuidewayDeflection
            Deflection [m] (positive downward), slope [m/m] and rate [m/s]; zeros for a
            rigid guideway.

        Raises
        ------
        InputError
            Positions not finite real numbers, or not a scalar or 1-D sequence.
        OutOfRangeError
            A position behind the window, or ahead of it without the moving boundary.
        """
        x = self._positions(positions_m)
        zero = np.zeros_like(x)
        if self.n_modes == 0:
            return GuidewayDeflection(x, zero, zero.copy(), zero.copy())
        k, rows, xi = self._locate(state, x, for_loads=False)
        inside = k <= state.first_span + self.n_spans - 1
        s, ds = self.span.mode_shapes(np.where(inside, xi, 0.0))
        q = state.modal_displacement_m[rows] * inside[:, None]
        qd = state.modal_velocity_m_per_s[rows] * inside[:, None]
        return GuidewayDeflection(x, (q * s).sum(axis=1), (q * ds).sum(axis=1),
                                  (qd * s).sum(axis=1))

    def midspan_deflection_m(self, state: GuidewayState) -> np.ndarray:
        """Midspan deflection of every integrated span, ordered from the rearmost [m].

        Parameters
        ----------
        state : GuidewayState
            The state to evaluate.

        Returns
        -------
        ndarray (n_spans,)
            Midspan deflections [m], positive downward (zeros for a rigid guideway).
        """
        spans = state.first_span + np.arange(self.n_spans)
        if self.n_modes == 0:
            return np.zeros(self.n_spans)
        s, _ = self.span.mode_shapes(0.5 * self.span.length_m)
        q = state.modal_displacement_m[np.mod(spans, self.n_spans)]
        return q @ s

    # ------------------------------------------------------------------ time stepping
    def step(self, state: GuidewayState, dt_s: float, positions_m: Any = (),
             forces_N: Any = 0.0) -> GuidewayState:
        """Advance by ``dt_s`` [s] with point forces held over the step (exact for them).

        Parameters
        ----------
        state : GuidewayState
            The state at the start of the step.
        dt_s : float
            Step [s] (> 0).
        positions_m : array_like
            Load positions [m], held over the step.  For loads moving at ``v``, passing
            the mid-step positions ``x(t) + v dt / 2`` makes the step second-order
            accurate in the moving load.
        forces_N : array_like
            Point forces on the guideway [N], positive downward (the magnets' attraction
            pulls the guideway towards the vehicle); one per position or one for all.

        Returns
        -------
        GuidewayState
            With the moving boundary, the window is first moved to the rearmost load.
        """
        dt = _check_dt(dt_s)
        if not isinstance(state, GuidewayState):
            raise InputError("state must be a GuidewayState (from Guideway.initial_state)")
        if state.modal_displacement_m.shape != (self.n_spans, self.n_modes):
            raise InputError(f"state has shape {state.modal_displacement_m.shape}, this guideway "
                             f"needs ({self.n_spans}, {self.n_modes})")
        x = self._positions(positions_m)
        if self.n_modes == 0:
            return GuidewayState(state.time_s + dt, state.first_span,
                                 state.modal_displacement_m, state.modal_velocity_m_per_s)
        if x.size:
            state = self.advance(state, float(x.min()))
        qf = self.modal_forces(state, x, forces_N)
        ad, bd = self.span.discretize(dt)
        xs = np.concatenate([state.modal_displacement_m, state.modal_velocity_m_per_s], axis=1)
        xs = xs @ ad.T + qf @ bd.T
        n = self.n_modes
        return GuidewayState(state.time_s + dt, state.first_span, xs[:, :n], xs[:, n:])
