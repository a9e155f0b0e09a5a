"""Exceptions and warnings raised by maglevkit.

Every error says what is wrong and what is allowed.  All derive from
:class:`MaglevkitError`; the input-validation ones also derive from
:class:`ValueError` so that generic callers can catch them as such.  Warnings derive
from :class:`MaglevkitWarning` (a :class:`UserWarning`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np


class MaglevkitError(Exception):
    """Base class of all maglevkit errors."""


class ParameterError(MaglevkitError, ValueError):
    """A model parameter (geometry, turns, resistance, ...) is invalid."""


class MaterialError(MaglevkitError, ValueError):
    """An unknown material name or an invalid B-H description."""


class TopologyError(MaglevkitError, ValueError):
    """The equivalent magnetic circuit or its electric circuits are malformed."""


class InputError(MaglevkitError, ValueError):
    """A run-time input (gap, current, voltage, time grid) is invalid."""


class OutOfRangeError(InputError):
    """An input lies outside the range a characteristic map was built for."""


class ParameterFileError(MaglevkitError, ValueError):
    """A parameter or scenario file is malformed (syntax, unknown or missing keys)."""


class MaglevkitWarning(UserWarning):
    """Base class of all maglevkit warnings."""


class PlausibilityWarning(MaglevkitWarning):
    """An input lies far outside the magnet's physical range (likely a unit mistake).

    Examples: a gap larger than the magnet's pole (``10`` typed for 10 mm into a metre
    option), or a current whose density in the winding no coil carries.  The
    computation still runs; silence it with ``warnings.filterwarnings("ignore",
    category=maglevkit.PlausibilityWarning)`` when such values are intended.
    """


class ProvenanceWarning(MaglevkitWarning):
    """A parameter file lacks provenance tags (``[provenance]`` table or entries)."""


class SolverError(MaglevkitError, RuntimeError):
    """A numerical solver failed.

    The old keyword and attribute name ``time`` is a deprecated alias of ``time_s`` (a
    ``DeprecationWarning`` names the new one).

    Parameters
    ----------
    message : str
        What failed.
    time_s : float or None, keyword only
        Simulation time [s] at which the failure happened (None for statics).
    state : mapping, keyword only
        The operating point or state at the failure (names to values).
    reason : str, keyword only
        What the solver reported.

    Attributes
    ----------
    time_s : float or None
        Simulation time [s] at which the failure happened (None for statics).
    state : dict
        The operating point or state at the failure (names to values).
    reason : str
        What the solver reported.
    """

    def __init__(
        self,
        message: str,
        *,
        time_s: float | None = None,
        state: Mapping[str, Any] | None = None,
        reason: str = "",
        **renamed: Any,
    ) -> None:
        if renamed:                 # the deprecated keyword time= (see _renamed_time)
            time_s = _renamed_time(renamed, time_s)
        self.time_s = time_s
        self.state = dict(state or {})
        self.reason = reason
        parts = [message]
        if time_s is not None:
            parts.append(f"at t = {time_s:.9g} s")
        if self.state:
            parts.append("state: " + ", ".join(f"{k}={_fmt(v)}" for k, v in self.state.items()))
        if reason:
            parts.append(f"reason: {reason}")
        super().__init__("; ".join(parts))

    @property
    def time(self) -> float | None:
        """Deprecated alias of ``time_s`` (read only)."""
        warnings.warn("SolverError: .time is deprecated, use .time_s (same values and units)",
                      DeprecationWarning, stacklevel=2)
        return self.time_s


def _renamed_time(renamed: dict[str, Any], time_s: float | None) -> float | None:
    """``SolverError(time=...)``: the old keyword of ``time_s``, with a DeprecationWarning.

    The same behaviour as :func:`maglevkit.validation.renamed_keywords` (which this module
    cannot import: validation imports the errors), for the one renamed keyword here.
    """
    unknown = sorted(set(renamed) - {"time"})
    if unknown:
        raise TypeError(f"SolverError() got an unexpected keyword argument {unknown[0]!r}")
    if time_s is not None:
        raise InputError("SolverError: give time_s= only (time= is its deprecated name)")
    warnings.warn("SolverError: time= is deprecated, use time_s= (same values and units)",
                  DeprecationWarning, stacklevel=3)
    return renamed["time"]


def _fmt(value: Any) -> str:
    if isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, str):
        arr = np.asarray(value, dtype=float).ravel()
        return "[" + ", ".join(f"{v:.6g}" for v in arr) + "]"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


class CompilationWarning(UserWarning):
    """Compiling a model to machine code failed; the slower interpreted path is used."""


class DataError(MaglevkitError, ValueError):
    """Tabulated or measured data (a table of F(s, I) / psi(s, I), a measured step) is
    malformed or inconsistent; the message names the column, the row or grid point and
    what is allowed."""


class DataWarning(MaglevkitWarning):
    """Tabulated data is usable but questionable (e.g. force not monotone in the gap, or
    co-energy reciprocity met only loosely); the message names where."""
