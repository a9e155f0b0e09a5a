"""Time signals for model inputs (voltages, gaps): constant, step, ramp, sine, tabulated.

A :class:`Signal` maps times ``t`` [s] (array) to values of one scalar input.  The
simulators sample signals on their time grid (zero-order hold for voltages, piecewise
linear for gaps).  :func:`parse_signal` reads the TOML form used by scenario files::

    {type = "constant", value = 40.0}
    {type = "step", initial = 20.0, final = 40.0, time = 0.01}
    {type = "ramp", initial = 0.010, final = 0.008, start = 0.0, stop = 0.05}
    {type = "sine", offset = 0.010, amplitude = 0.001, frequency = 5.0, phase = 0.0}
    {type = "tabulated", times = [0.0, 0.1], values = [0.0, 40.0]}

A bare number is a constant.  Values are in the unit of the input (V for voltages, m for
gaps); times in s, frequencies in Hz, phases in rad.  In Python the classes' times,
frequency and phase carry their unit in their names (``Step(time_s=...)``,
``Sine(frequency_Hz=..., phase_rad=...)``); the unit-less keyword and attribute names of
earlier releases still work for one release with a ``DeprecationWarning``.  The file keys
above are the scenario format's own (whose ``[scenario]`` keys are unit-less too) and are
unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, ParameterFileError
from ..validation import real_array, renamed_keywords

__all__ = [
    "Signal",
    "Constant",
    "Step",
    "Ramp",
    "Sine",
    "Tabulated",
    "parse_signal",
]


class Signal:
    """Base class: a scalar input as a function of time (callable on arrays)."""

    def __call__(self, t: Any) -> np.ndarray:
        raise NotImplementedError

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Times [s] where the signal or its slope jumps (for choosing time grids)."""
        return ()


def _finite(owner: str, **values: float) -> None:
    for k, v in values.items():
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)):
            raise InputError(f"{owner}: {k} = {v!r} must be a finite number")


@dataclass(frozen=True)
class Constant(Signal):
    """``u(t) = value``.

    Parameters
    ----------
    value : float
        The value, finite, in the unit of the input (V for voltages, m for gaps).

    Raises
    ------
    InputError
        A value that is not a finite number.
    """

    value: float

    def __post_init__(self) -> None:
        _finite("constant signal", value=self.value)

    def __call__(self, t: Any) -> np.ndarray:
        return np.full(np.shape(t), float(self.value))


@renamed_keywords(time="time_s")
@dataclass(frozen=True)
class Step(Signal):
    """``u(t) = initial`` for ``t < time_s``, ``final`` for ``t >= time_s``.

    Parameters
    ----------
    initial, final : float
        Values before and from the step, in the unit of the input (V or m).
    time_s : float, default 0.0
        Time of the step [s] (``time`` is its deprecated name).

    Raises
    ------
    InputError
        A value that is not a finite number.
    """

    initial: float
    final: float
    time_s: float = 0.0

    def __post_init__(self) -> None:
        _finite("step signal", initial=self.initial, final=self.final, time_s=self.time_s)

    def __call__(self, t: Any) -> np.ndarray:
        return np.where(np.asarray(t, dtype=float) < self.time_s, self.initial, self.final)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.time_s,)


@renamed_keywords(start="start_s", stop="stop_s")
@dataclass(frozen=True)
class Ramp(Signal):
    """Linear from ``initial`` at ``start_s`` to ``final`` at ``stop_s``; constant outside.

    Parameters
    ----------
    initial, final : float
        Values before ``start_s`` and after ``stop_s``, in the unit of the input (V or m).
    start_s, stop_s : float
        Start and end of the ramp [s], ``stop_s > start_s`` (``start``, ``stop`` are their
        deprecated names).

    Raises
    ------
    InputError
        A value that is not a finite number, or ``stop_s <= start_s``.
    """

    initial: float
    final: float
    start_s: float
    stop_s: float

    def __post_init__(self) -> None:
        _finite("ramp signal", initial=self.initial, final=self.final, start_s=self.start_s,
                stop_s=self.stop_s)
        if not self.stop_s > self.start_s:
            raise InputError(f"ramp signal: stop_s = {self.stop_s} s must be > start_s = "
                             f"{self.start_s} s")

    def __call__(self, t: Any) -> np.ndarray:
        frac = np.clip((np.asarray(t, dtype=float) - self.start_s) / (self.stop_s - self.start_s),
                       0.0, 1.0)
        return self.initial + frac * (self.final - self.initial)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.start_s, self.stop_s)


@renamed_keywords(frequency="frequency_Hz", phase="phase_rad")
@dataclass(frozen=True)
class Sine(Signal):
    """``u(t) = offset + amplitude sin(2 pi frequency_Hz t + phase_rad)``.

    Parameters
    ----------
    offset, amplitude : float
        Mean value and amplitude, in the unit of the input (V or m).
    frequency_Hz : float
        Frequency [Hz], >= 0 (``frequency`` is its deprecated name).
    phase_rad : float, default 0.0
        Phase at t = 0 [rad] (``phase`` is its deprecated name).

    Raises
    ------
    InputError
        A value that is not a finite number, or a negative frequency.
    """

    offset: float
    amplitude: float
    frequency_Hz: float
    phase_rad: float = 0.0

    def __post_init__(self) -> None:
        _finite("sine signal", offset=self.offset, amplitude=self.amplitude,
                frequency_Hz=self.frequency_Hz, phase_rad=self.phase_rad)
        if self.frequency_Hz < 0.0:
            raise InputError(f"sine signal: frequency_Hz = {self.frequency_Hz} Hz must be >= 0")

    def __call__(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        arg = 2.0 * math.pi * self.frequency_Hz * t + self.phase_rad
        return self.offset + self.amplitude * np.sin(arg)


@renamed_keywords(times="times_s")
@dataclass(frozen=True)
class Tabulated(Signal):
    """Piecewise-linear interpolation of ``(times_s, values)``; constant beyond the ends.

    ``times_s`` must be strictly increasing.

    Parameters
    ----------
    times_s : sequence of float
        Sample times [s], finite, strictly increasing, at least one (``times`` is its
        deprecated name).
    values : sequence of float
        Values at the sample times, in the unit of the input (V or m), as many as
        ``times_s``.

    Raises
    ------
    InputError
        Non-numeric (strings, bools, ...) or non-finite entries, lists that are not 1-D and equally long
        (>= 1), or times that are not strictly increasing.
    """

    times_s: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        # bools are refused (True was taken as 1 s / 1 V), like every number of the API
        t = real_array(self.times_s, "tabulated signal times_s", "s", finite=False)
        v = real_array(self.values, "tabulated signal values", finite=False)
        if t.ndim != 1 or v.ndim != 1 or t.size != v.size or t.size < 1:
            raise InputError(f"tabulated signal: times_s ({t.size}) and values ({v.size}) must "
                             "be 1-D lists of equal, non-zero length")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise InputError("tabulated signal: times_s and values must be finite")
        if np.any(np.diff(t) <= 0.0):
            raise InputError("tabulated signal: times_s must be strictly increasing")
        object.__setattr__(self, "times_s", tuple(float(a) for a in t))
        object.__setattr__(self, "values", tuple(float(a) for a in v))

    def __call__(self, t: Any) -> np.ndarray:
        return np.interp(np.asarray(t, dtype=float), self.times_s, self.values)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return self.times_s


_SIGNAL_KEYS: dict[str, tuple[type[Signal], dict[str, bool]]] = {
    # type -> (class, {key: required})
    "constant": (Constant, {"value": True}),
    "step": (Step, {"initial": True, "final": True, "time": False}),
    "ramp": (Ramp, {"initial": True, "final": True, "start": True, "stop": True}),
    "sine": (Sine, {"offset": True, "amplitude": True, "frequency": True, "phase": False}),
    "tabulated": (Tabulated, {"times": True, "values": True}),
}
#: file key -> the class field it sets, where the two differ (the fields carry units)
_FIELD_OF_KEY = {"time": "time_s", "start": "start_s", "stop": "stop_s",
                 "frequency": "frequency_Hz", "phase": "phase_rad", "times": "times_s"}


def parse_signal(spec: Any, where: str = "signal") -> Signal:
    """Build a :class:`Signal` from its scenario-file form (a number or a table).

    Parameters
    ----------
    spec : float or mapping
        A number (a :class:`Constant`) or a table with ``type`` (``"constant"``,
        ``"step"``, ``"ramp"``, ``"sine"``, ``"tabulated"``) and that type's keys (see
        the module docstring); values in the unit of the input, times in s.
    where : str, default "signal"
        Where the signal was found, for error messages (e.g. ``"[voltages] all"``).

    Returns
    -------
    Signal

    Raises
    ------
    ParameterFileError
        Unknown ``type``, unknown or missing keys, or invalid values (the message names
        ``where`` and lists the allowed keys).
    """
    if isinstance(spec, bool):
        raise ParameterFileError(f"{where}: expected a number or a signal table, got {spec!r}")
    if isinstance(spec, (int, float)):
        try:
            return Constant(float(spec))
        except InputError as exc:
            raise ParameterFileError(f"{where}: {exc}") from None
    if not isinstance(spec, Mapping):
        raise ParameterFileError(f"{where}: expected a number or a table like "
                                 "{type = \"step\", initial = ..., final = ..., time = ...}")
    kind = spec.get("type")
    if kind not in _SIGNAL_KEYS:
        raise ParameterFileError(f"{where}: 'type' = {kind!r} is not a signal type; use one of "
                                 f"{', '.join(_SIGNAL_KEYS)}")
    cls, keys = _SIGNAL_KEYS[kind]
    given = {k: v for k, v in spec.items() if k != "type"}
    unknown = sorted(set(given) - set(keys))
    if unknown:
        raise ParameterFileError(f"{where}: unknown key(s) {unknown} for a {kind!r} signal; "
                                 f"allowed: type, {', '.join(keys)}")
    missing = [k for k, req in keys.items() if req and k not in given]
    if missing:
        raise ParameterFileError(f"{where}: a {kind!r} signal needs key(s) {missing}")
    kwargs: dict[str, Any] = {}
    for k, v in given.items():
        if kind == "tabulated":
            if not isinstance(v, list):
                raise ParameterFileError(f"{where}: {k} must be a list of numbers")
            kwargs[_FIELD_OF_KEY.get(k, k)] = tuple(v)
        else:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ParameterFileError(f"{where}: {k} = {v!r} must be a number")
            kwargs[_FIELD_OF_KEY.get(k, k)] = float(v)
    try:
        return cls(**kwargs)
    except InputError as exc:
        raise ParameterFileError(f"{where}: {exc}") from None
