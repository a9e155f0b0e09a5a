"""Input signals of the dynamic models: time grids and sampling of gaps and voltages.

Shared by the flux-based and the current-based model so that both accept the same inputs:
constants, per-name mappings, :class:`~maglevkit.models.signals.Signal` objects, callables
of time, or sampled arrays.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import describe, real_array, real_number
from .signals import Signal

__all__ = ["time_grid", "sample_input", "gap_secants", "check_step", "check_span",
           "reject_bools", "simulation_inputs", "check_initial_choice", "per_name_values"]


def check_step(dt: Any, what: str = "dt") -> float:
    """A time step [s] as a float: a finite real number > 0 (numpy scalars allowed, bools not).

    Parameters
    ----------
    dt : float
        The step [s].
    what : str, default "dt"
        Name of the argument in error messages.

    Returns
    -------
    float

    Raises
    ------
    InputError
        ``dt`` is a bool, not a real number, not finite, or <= 0.
    """
    return real_number(dt, what, "s", positive=True)


def reject_bools(value: Any, what: str) -> None:
    """Raise InputError if ``value`` is or contains a bool, a string or another non-number
    (a mapping: its values; NaN/inf are left to the caller).

    Parameters
    ----------
    value : object
        A number, array_like or mapping of them.
    what : str
        Name of the value in error messages.

    Raises
    ------
    InputError
        A bool, string or other non-number anywhere in ``value``.
    """
    if isinstance(value, Mapping):
        for key, v in value.items():
            reject_bools(v, f"{what}[{key}]")
        return
    real_array(value, what, finite=False)


def check_span(t0: float, tf: float, dt: float) -> None:
    """The rule for a time span and its step, shared by :func:`time_grid` and scenario files.

    ``tf > t0`` and ``dt <= tf - t0`` (a rounding allowance of 1e-9 dt): a step longer
    than the span would silently give a two-sample "grid" ``[t0, tf]``.

    Parameters
    ----------
    t0, tf : float
        Start and end of the span [s] (finiteness is not checked here).
    dt : float
        Step [s] (its sign and finiteness are not checked here: see :func:`check_step`).

    Raises
    ------
    InputError
        ``tf <= t0`` or ``dt`` longer than the span.
    """
    if not tf > t0:
        raise InputError(f"t_span = ({t0:g}, {tf:g}) s: tf must be > t0")
    if dt > (tf - t0) * (1.0 + 1e-9):
        raise InputError(f"dt = {dt:g} s exceeds the simulated span tf - t0 = {tf - t0:g} s; "
                         "give a step no longer than the span (e.g. dt = 1e-4 s)")


def time_grid(t: Any, dt: Any) -> np.ndarray:
    """The simulation time grid [s] from ``t`` and ``dt``.

    The rule (the type of ``t`` decides, never its length alone):

    * a **tuple or list of exactly two numbers** ``(t0, tf)`` / ``[t0, tf]`` is a time
      *span*: the grid is ``t0 + k dt`` (``dt`` default 1e-4 s, at most ``tf - t0``,
      see :func:`check_span`), ending exactly at ``tf`` (like
      ``scipy.integrate.solve_ivp``'s ``t_span``);
    * a **numpy array** (any length >= 2) or a sequence of three or more times is an
      explicit, strictly increasing *grid*; ``dt`` must then be None.  A two-point grid
      is ``np.array([t0, t1])`` (or the span ``(t0, t1)`` with ``dt = t1 - t0``).

    Parameters
    ----------
    t : tuple, list or ndarray
        A span ``(t0, tf)`` [s] or an explicit grid [s] (see above).
    dt : float or None
        Step [s] of a span (None: 1e-4 s, or ``tf - t0`` if shorter); must be None
        with an explicit grid.

    Returns
    -------
    ndarray (n,)
        Times [s].  For a span that is not a whole number of steps, the last interval
        is shorter than ``dt`` (the grid still ends at ``tf``).

    Raises
    ------
    InputError
        Non-numeric (bools, strings), non-finite or non-increasing times, ``tf <= t0``,
        a bad ``dt`` or one longer than the span, or ``dt`` given together with an
        explicit grid.
    """
    span = (type(t) is tuple and len(t) == 2 and type(t[0]) in (int, float)
            and type(t[1]) in (int, float) and math.isfinite(t[0]) and math.isfinite(t[1]))
    if not span:                    # (a span of two plain finite numbers: the common case)
        arr = real_array(t, "t", "s", finite=False)
        if arr.ndim != 1 or arr.size < 2 or not np.all(np.isfinite(arr)):
            raise InputError("t must be (t0, tf) or a 1-D array of at least 2 finite times [s]")
        span = arr.size == 2 and isinstance(t, (tuple, list))
    if span:
        t0, tf = float(t[0]), float(t[1])
        step = 1e-4 if dt is None else check_step(dt)
        if dt is None and tf > t0:
            step = min(step, tf - t0)
        check_span(t0, tf, step)
        n = int(math.floor((tf - t0) / step * (1.0 + 1e-12)))
        grid = np.arange(n + 1, dtype=float)
        grid *= step
        grid += t0                      # t0 + step k, as t0 + step * np.arange(n + 1)
        if tf - grid[-1] > 1e-9 * step:
            grid = np.append(grid, tf)
        else:
            grid[-1] = tf
        return grid
    if dt is not None:
        raise InputError("give either dt with t = (t0, tf), or an explicit time grid, not both")
    if np.any(np.diff(arr) <= 0.0):
        raise InputError("the time grid must be strictly increasing")
    return arr


def sample_input(value: Any, times: np.ndarray, names: tuple[str, ...], what: str,
            unit: str) -> np.ndarray:
    """Sample an input (scalar, vector, mapping, Signal, callable, array) on ``times``.

    Parameters
    ----------
    value : float, array_like, mapping, Signal or callable
        The input: a scalar (every name, every time), one value per name ``(k,)``,
        samples ``(n, k)`` (or ``(n,)`` for one name), a mapping ``{name: input}``
        with every name, a :class:`Signal` (every name), or a callable ``f(t)``
        returning a scalar or ``k`` values for a time t [s].
    times : ndarray (n,)
        Sample times [s].
    names : tuple of str
        Names of the input's components (gap or circuit names).
    what : str
        Name of the input in error messages (e.g. ``"gaps"``).
    unit : str
        Unit of the input in error messages (e.g. ``"m"``).

    Returns
    -------
    ndarray (n, k)
        The samples, in the input's unit.

    Raises
    ------
    InputError
        Unknown or missing names, non-numbers, wrong shapes, a callable that raises or
        returns non-numbers, or non-finite samples.
    """
    n, k = times.size, len(names)
    if isinstance(value, Mapping):
        _check_names(value, names, what, unit, "name")
        # every column is sampled and checked (finite) on its own, into one (n, k) array
        out = np.empty((n, k))
        for j, nm in enumerate(names):
            v = value[nm]
            col = _signal_column(v, times) if isinstance(v, Signal) else None
            out[:, j] = (col if col is not None
                         else sample_input(v, times, (nm,), f"{what}[{nm}]", unit)[:, 0])
        return out
    if isinstance(value, Signal):
        col = _signal_column(value, times)
        if col is not None:
            # the same value for every name: checked once, before the copies
            out = np.empty((n, k))
            out[:] = col[:, None]
            return out
        arr = np.repeat(np.asarray(value(times), dtype=float)[:, None], k, axis=1)
    elif callable(value):
        arr = _sample_callable(value, times, k, names, what, unit)
    elif type(value) is np.ndarray and value.dtype == np.float64 and value.shape == (k,) \
            and not (k == 1 and n == 1) and np.isfinite(value).all():
        # one finite value per name (the common constant input): checked before the copies
        out = np.empty((n, k))
        out[:] = value
        return out
    else:
        try:
            a = real_array(value, what, unit, finite=False)
        except InputError as exc:
            raise InputError(f"{exc}; {what} may also be a Signal, a callable of t or a "
                             "mapping per name") from None
        if a.ndim == 0:
            arr = np.full((n, k), float(a))
        elif a.shape == (k,) and not (k == 1 and n == 1):
            arr = np.broadcast_to(a, (n, k)).copy()
        elif a.shape == (n,) and k == 1:
            arr = a[:, None].copy()
        elif a.shape == (n, k):
            arr = a.copy()
        else:
            raise InputError(f"{what} array has shape {a.shape}; expected a scalar, ({k},) "
                             f"(one per {list(names)}), or samples ({n}, {k}) on the "
                             f"{n}-point time grid")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argmax(~np.all(np.isfinite(arr), axis=1)))
        raise InputError(f"{what} is not finite at t = {times[bad]:.6g} s: {arr[bad].tolist()}")
    return arr


def _signal_column(value: Signal, times: np.ndarray) -> np.ndarray | None:
    """A Signal's samples at ``times`` as a float array (n,), or None where they are not
    finite numbers of that shape (the caller then reports them)."""
    col = np.asarray(value(times), dtype=float)
    return col if col.shape == times.shape and np.isfinite(col).all() else None


def _sample_callable(value: Any, times: np.ndarray, k: int, names: tuple[str, ...], what: str,
                     unit: str) -> np.ndarray:
    """Evaluate ``value(t)`` at every time; scalars apply to every name.

    Fast path: one array conversion of all returned values. If that fails (mixed
    shapes, non-numbers), the samples are checked one by one for a precise error.
    """
    raw = []
    for t in times.tolist():
        try:
            raw.append(value(t))
        except Exception as exc:  # any failure of user code is an input error, chained
            raise InputError(f"{what}: the callable raised {type(exc).__name__} at t = {t} s: "
                             f"{exc}; it must return numbers [{unit}] for every time t [s] of "
                             "the grid") from exc
    try:
        arr = real_array(raw, what, unit, finite=False)
    except InputError:
        arr = np.empty(0)
    if arr.ndim == 1 and arr.size == times.size:
        return np.repeat(arr[:, None], k, axis=1)
    if arr.shape == (times.size, k):
        return arr
    rows = []
    for t, r in zip(times, raw, strict=True):
        try:
            v = real_array(r, what, unit, finite=False)
        except InputError as exc:
            raise InputError(f"{what}: the callable must return numbers [{unit}] for a "
                             f"time t [s]; it returned {r!r} at t = {t}: {exc}") from None
        if v.ndim == 0:
            v = np.full(k, float(v))
        if v.shape != (k,):
            raise InputError(f"{what}: the callable returned shape {v.shape} at t = {t}; "
                             f"expected a scalar or {k} values ({list(names)})")
        rows.append(v)
    return np.array(rows)


def gap_secants(times: np.ndarray, gaps: np.ndarray, gap_rates: Any, names: tuple[str, ...],
                tolerance: float) -> np.ndarray:
    """Gap rates per interval [m/s] (secants of the sampled gaps), checked against ``gap_rates``.

    If ``gap_rates`` is given, the trapezoidal mean of the rates over each interval may
    differ from the secant by at most ``tolerance`` times the largest rate (plus 1 um/s);
    otherwise :class:`InputError`.

    Parameters
    ----------
    times : ndarray (n,)
        Sample times [s], strictly increasing.
    gaps : ndarray (n, n_gaps)
        Sampled gaps [m].
    gap_rates : input or None
        Gap rates [m/s] in any form :func:`sample_input` takes, or None (no check).
    names : tuple of str
        Gap names.
    tolerance : float
        Relative tolerance [-], >= 0.

    Returns
    -------
    ndarray (n - 1, n_gaps)
        Secant gap rate of every interval [m/s].
    """
    tolerance = real_number(tolerance, "gap_rate_tolerance", nonnegative=True)
    h = np.diff(times)
    secant = np.diff(gaps, axis=0) / h[:, None]
    if gap_rates is not None:
        r = sample_input(gap_rates, times, names, "gap_rates", "m/s")
        mean = 0.5 * (r[1:] + r[:-1])
        tol = tolerance * max(float(np.abs(r).max()), float(np.abs(secant).max())) + 1e-6
        err = np.abs(mean - secant)
        if np.any(err > tol):
            j = int(np.argmax(np.max(err - tol, axis=1)))
            raise InputError(
                f"gaps and gap_rates disagree on [{times[j]:.6g}, {times[j + 1]:.6g}] s: the "
                f"gaps change at {secant[j].tolist()} m/s but the rates average "
                f"{mean[j].tolist()} m/s (tolerance {tol:.3g} m/s); pass consistent signals "
                "or only the gaps")
    return secant


def simulation_inputs(t: Any, dt: Any, *, gaps: Any, voltages: Any, gap_rates: Any,
                      gap_names: tuple[str, ...], circuit_names: tuple[str, ...],
                      gap_rate_tolerance: float
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The sampled inputs of a ``simulate`` call: ``(times, gaps, voltages, gap_rates)``.

    Times from :func:`time_grid`; gaps [m] (all > 0) and voltages [V] sampled at the
    times (:func:`sample_input`); the gap rate of every interval [m/s] from
    :func:`gap_secants` (the gaps move linearly between samples).

    Parameters
    ----------
    t, dt
        Time span or grid [s] and step [s] (see :func:`time_grid`).
    gaps : input
        Gaps [m], > 0 (any form of :func:`sample_input`; keyword only, like all that
        follow).
    voltages : input
        Circuit voltages [V].
    gap_rates : input or None
        Gap rates [m/s] to check the gaps against (None: no check).
    gap_names, circuit_names : tuple of str
        The model's gap and circuit names.
    gap_rate_tolerance : float
        Relative tolerance of the check [-] (see :func:`gap_secants`).

    Returns
    -------
    (times, gaps, voltages, gap_rates) : ndarray (n,), (n, n_gaps), (n, n_circuits), (n - 1, n_gaps)

    Raises
    ------
    InputError
        Any bad input (see the functions above), or a gap <= 0.
    """
    times = time_grid(t, dt)
    g = sample_input(gaps, times, gap_names, "gaps", "m")
    if g.size and g.min() <= 0.0:                 # (finite: sample_input checked them)
        raise InputError("gaps must be > 0 m")
    u = sample_input(voltages, times, circuit_names, "voltages", "V")
    rates = gap_secants(times, g, gap_rates, gap_names, gap_rate_tolerance)
    return times, g, u, rates


def check_initial_choice(initial_state: Any, initial_currents: Any, state_type: type) -> None:
    """At most one of ``initial_state`` / ``initial_currents``; the state of the right type.

    Parameters
    ----------
    initial_state : object or None
        The initial state given to ``simulate``.
    initial_currents : object or None
        The initial currents [A] given to ``simulate``.
    state_type : type
        The model's state class.

    Raises
    ------
    InputError
        Both given, or a state of another type.
    """
    if initial_state is None:
        return
    if initial_currents is not None:
        raise InputError("give initial_currents or initial_state, not both")
    if not isinstance(initial_state, state_type):
        raise InputError(f"initial_state must be a {state_type.__name__}")


def _check_names(value: Mapping, names: tuple[str, ...], what: str, unit: str,
                 kind: str) -> None:
    """The name check of a mapping input, one message for every converter: every name of
    ``names`` and no other key."""
    missing = [k for k in names if k not in value]
    unknown = sorted(str(k) for k in set(value) - set(names))
    if missing or unknown:
        raise InputError(f"{what}: unknown names {_listed(unknown)}, missing "
                         f"{_listed(missing)}; give one value [{unit}] per {kind}: "
                         f"{_listed(names)}")


def _listed(names: Any, limit: int = 8) -> str:
    """``names`` as a list for a message, the first ``limit`` of a long one."""
    names = list(names)
    return str(names) if len(names) <= limit else f"{names[:limit]} and {len(names) - limit} more"


def per_name_values(value: Any, names: tuple[str, ...], what: str, unit: str, *,
                    kind: str = "circuit", finite: bool = True, positive: bool = False,
                    allow_inf: bool = False, leading: bool = False) -> np.ndarray:
    """One value per name (circuit, gap, ...) as a float array: the one converter of
    per-circuit and per-gap inputs (the reduced models, the bank, the table import).

    Parameters
    ----------
    value : float, array_like (n,) or mapping
        One value for every name, one per name in the order of ``names``, or
        name -> value (every name, no other key).
    names : tuple of str
        The names, in order.
    what : str
        The user's name of the input (keyword or option) in error messages.
    unit : str
        Its unit in error messages (e.g. ``"V"``).
    kind : str, default "circuit"
        What a name is, in error messages (``"circuit"``, ``"gap"``, ``"gap input"``).
    finite : bool, default True
        Refuse NaN and inf (False: leave them to the caller, e.g. a kernel that flags
        them; numbers are still checked).
    positive : bool, default False
        Refuse values <= 0.
    allow_inf : bool, default False
        Allow +inf (with ``finite``), e.g. "no eddy currents".
    leading : bool, default False
        Also take values with leading axes: an array ``(..., n)`` (one value per name
        along the last axis, e.g. a grid of operating points), or a mapping whose values
        are arrays of one common shape (stacked along a new last axis).

    Returns
    -------
    numpy.ndarray (n,), or (..., n) with ``leading``
        The values [``unit``]; a float64 array of the right shape is returned as it is.

    Raises
    ------
    InputError
        Missing or unknown names, non-numbers (bools, strings), a wrong count, and with
        the options above NaN/inf or values <= 0; each message names ``what``, the
        value and what is allowed.
    """
    n = len(names)
    if leading:
        arr = _with_leading_axes(value, names, what, unit, kind)
    elif type(value) is np.ndarray and value.dtype == np.float64 and value.shape == (n,):
        arr = value
        if not (finite or positive):
            return arr
    elif type(value) is float and (not finite or math.isfinite(value)) and \
            not (positive and not value > 0.0):
        return np.full(n, value)              # one plain float for all (e.g. 0.0 m/s)
    else:
        if isinstance(value, Mapping):
            _check_names(value, names, what, unit, kind)
            value = [value[k] for k in names]
        arr = real_array(value, what, unit, finite=False)       # no bools or strings
        if arr.ndim == 0:
            arr = np.full(n, float(arr))
        elif arr.shape != (n,):
            raise InputError(f"{what}: expected {n} values [{unit}] (one per {kind} of "
                             f"{_listed(names)}, or one for all), got shape {arr.shape}: "
                             f"{describe(value)}")
    if finite:
        ok = np.isfinite(arr) | ((arr == math.inf) if allow_inf else False)
        if not ok.all():
            j = int(np.argmax(~ok.reshape(-1)))
            allowed = " (or inf)" if allow_inf else ""
            raise InputError(f"{what} must be finite{allowed}: {kind} {names[j % n]!r} = "
                             f"{float(arr.reshape(-1)[j])!r} {unit}")
    if positive and not (arr > 0.0).all():
        j = int(np.argmax(~(arr > 0.0).reshape(-1)))
        raise InputError(f"{what} must be > 0 {unit}: {kind} {names[j % n]!r} = "
                         f"{float(arr.reshape(-1)[j])!r} {unit}")
    return arr


def _with_leading_axes(value: Any, names: tuple[str, ...], what: str, unit: str,
                       kind: str) -> np.ndarray:
    """:func:`per_name_values`' conversion with ``leading``: (..., n) float array, numbers
    only (finiteness and sign are the caller's checks)."""
    n = len(names)
    if isinstance(value, Mapping):
        _check_names(value, names, what, unit, kind)
        cols = [real_array(value[k], f"{kind} {k!r}", unit, finite=False) for k in names]
        if len({c.shape for c in cols}) > 1:
            raise InputError(f"{what}: the values per {kind} must have one shape, got "
                             f"{dict(zip(names, (c.shape for c in cols), strict=True))}")
        return np.stack(cols, axis=-1)
    arr = real_array(value, what, unit, finite=False)
    if arr.ndim == 0:
        return np.full(n, float(arr))
    if arr.shape[-1] != n:
        raise InputError(f"{what}: expected {n} values [{unit}] along the last axis (one per "
                         f"{kind} of {_listed(names)}, or one for all), got shape "
                         f"{arr.shape}: {describe(value)}")
    return arr
