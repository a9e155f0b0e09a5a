"""One validation path for the numbers and switches of every public entry point.

Every public function that takes a number, an array of numbers or a physics switch checks
it here, so that the same input gets the same answer everywhere:

* a **number** is a real, finite int, float or numpy scalar (or an array of them); bools
  (``True`` would silently become 1.0), strings (``"0.01"`` would be parsed by numpy),
  complex numbers, ``None`` and other objects are refused;
* a **whole number** (counts such as ``max_num_steps``) is a real number without a
  fractional part, not a bool;
* a **flag** (``saturation``, ``grid``, ...) is ``True`` or ``False`` (or a numpy bool);
  ``"no"``, ``0`` or ``None`` are refused (a non-empty string is truthy: ``"no"`` would
  switch the option *on*).

All failures raise :class:`~maglevkit.errors.InputError` naming the argument, what it got
and what is allowed.  The module sits below every other layer (it needs only numpy and
:mod:`maglevkit.errors`).
"""

from __future__ import annotations

import functools
import math
import numbers
import os
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar, cast

import numpy as np

from .errors import InputError, MaglevkitError, PlausibilityWarning

_F = TypeVar("_F", bound=Callable[..., Any])

__all__ = ["renamed_keywords", "external_stacklevel", "real_number", "real_array", "whole_number", "flag",
           "optional_flag", "describe", "Plausible", "check_plausible"]


def describe(value: Any) -> str:
    """A short description of ``value`` for error messages: its repr and type.

    Parameters
    ----------
    value : object
        Anything.

    Returns
    -------
    str
        ``"<repr, at most 80 characters> (<type name>)"``.
    """
    text = repr(value)
    if len(text) > 80:
        text = text[:77] + "..."
    return f"{text} ({type(value).__name__})"


def _what(what: str, unit: str) -> str:
    return f"{what} [{unit}]" if unit else what


def _is_bool(value: Any) -> bool:
    return isinstance(value, (bool, np.bool_))


def real_number(value: Any, what: str, unit: str = "", *, positive: bool = False,
                nonnegative: bool = False, error: type[MaglevkitError] = InputError) -> float:
    """A finite real number as a float (ints, floats and numpy scalars; 0-d arrays too).

    Parameters
    ----------
    value : Any
        The argument to check.
    what : str
        Its name in error messages (e.g. ``"dt"``).
    unit : str
        Its unit in error messages (e.g. ``"s"``).
    positive, nonnegative : bool
        Also require ``> 0`` / ``>= 0``.
    error : MaglevkitError subclass
        The class raised (default :class:`InputError`; e.g. :class:`ParameterError` for
        model parameters).

    Raises
    ------
    InputError
        A bool, string, complex, non-number, array of several values, NaN/inf, or a
        value failing the sign check.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if _is_bool(value) or isinstance(value, (str, bytes)) \
            or not isinstance(value, numbers.Real):
        raise error(f"{_what(what, unit)} = {describe(value)}: expected a real number "
                         "(an int, float or numpy scalar; not a bool, string or array)")
    v = float(value)
    if not math.isfinite(v):
        raise error(f"{_what(what, unit)} = {value!r}: must be finite")
    if positive and not v > 0.0:
        raise error(f"{_what(what, unit)} = {value!r}: must be > 0")
    if nonnegative and not v >= 0.0:
        raise error(f"{_what(what, unit)} = {value!r}: must be >= 0")
    return v


_OK = object()   # sentinel of _bad_element: every part is a real number
# exact types that are real numbers (bool is a subclass of int, so exact types exclude it);
# the fast path of long lists of plain floats (sampled inputs of callables)
_PLAIN = frozenset({float, int, np.float64, np.float32, np.int64, np.int32})


def _bad_element(value: Any) -> Any:
    """The first part of ``value`` that is not a real number (``_OK`` if all are).

    Sequences (lists, tuples, ranges) are searched element by element; arrays and
    array-likes (anything with ``__array__``: numpy, pandas, xarray) by their dtype.
    """
    tp = type(value)
    if tp in _PLAIN:
        return _OK
    if tp is np.ndarray:
        if value.dtype.kind in "iuf":
            return _OK
        if value.dtype != object:
            return value
        return _first_bad(value.ravel().tolist())
    if tp is list or tp is tuple:
        if _PLAIN.issuperset(map(type, value)):
            return _OK
        return _first_bad(value)
    if isinstance(value, (str, bytes)) or _is_bool(value):
        return value
    if isinstance(value, numbers.Real):
        return _OK
    if isinstance(value, Sequence):
        return _first_bad(value)
    if isinstance(value, np.ndarray) or hasattr(value, "__array__"):
        return _bad_element(np.asarray(value))
    return value


def _first_bad(items: Any) -> Any:
    for v in items:
        bad = _bad_element(v)
        if bad is not _OK:
            return bad
    return _OK


def real_array(value: Any, what: str, unit: str = "", *, finite: bool = True) -> np.ndarray:
    """Real numbers (a scalar or a nested sequence/array of any shape) as a float array.

    Raises
    ------
    InputError
        The value is or contains a bool, string, complex number, None or another
        non-number; a ragged nesting; or (``finite=True``) NaN/inf.

    Parameters
    ----------
    value : object
        The argument to check.
    what : str
        Its name in error messages.
    unit : str, optional
        Its unit in error messages.
    finite : bool, default True
        Also reject NaN and inf (keyword only).

    Returns
    -------
    ndarray of float
        Same shape as ``value``.
    """
    bad = _bad_element(value)
    if bad is not _OK:
        kind = ("a bool" if _is_bool(bad) else "a string" if isinstance(bad, (str, bytes))
                else f"an array of {bad.dtype} values" if isinstance(bad, np.ndarray)
                else f"a {type(bad).__name__}")
        got = (f"is {kind}" if bad is value
               else f"contains {kind} ({bad!r})" if not isinstance(bad, np.ndarray)
               else f"contains {kind}")
        raise InputError(f"{_what(what, unit)} = {describe(value)} {got}; {what} must be "
                         "numbers (real ints, floats or numpy numbers; not bools or strings)")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{_what(what, unit)} = {describe(value)}: {what} must be numbers "
                         f"(a scalar or a regular array): {exc}") from None
    if finite and not np.all(np.isfinite(arr)):
        raise InputError(f"{_what(what, unit)} must be finite numbers, got {describe(value)}")
    return arr


def whole_number(value: Any, what: str, *, minimum: int | None = None) -> int:
    """A whole number as an int (ints, numpy ints, or floats without a fractional part).

    Raises
    ------
    InputError
        Not a real number, a bool, a fractional value, or below ``minimum``.

    Parameters
    ----------
    value : object
        The argument to check.
    what : str
        Its name in error messages.
    minimum : int, optional
        Smallest allowed value (keyword only).

    Returns
    -------
    int
    """
    v = real_number(value, what)
    if not v.is_integer():
        raise InputError(f"{what} = {value!r}: must be a whole number")
    n = int(v)
    if minimum is not None and n < minimum:
        raise InputError(f"{what} = {value!r}: must be a whole number >= {minimum}")
    return n


def flag(value: Any, what: str) -> bool:
    """A switch: ``True`` or ``False`` (numpy bools allowed), nothing else.

    Raises
    ------
    InputError
        Any other value (``"no"``, ``0``, ``None``, ...).

    Parameters
    ----------
    value : object
        The argument to check.
    what : str
        Its name in error messages.

    Returns
    -------
    bool
    """
    if not _is_bool(value):
        raise InputError(f"{what} = {describe(value)}: expected True or False")
    return bool(value)


def optional_flag(value: Any, what: str) -> bool | None:
    """Like :func:`flag`, but ``None`` (meaning "unchanged" or "default") is allowed.

    Parameters
    ----------
    value : object
        ``True``, ``False`` or ``None``.
    what : str
        Its name in error messages.

    Returns
    -------
    bool or None
    """
    return None if value is None else flag(value, what)


# ---------------------------------------------------------------- plausible file values
@dataclass(frozen=True)
class Plausible:
    """The plausible magnitudes of one dimensional key of a parameter file.

    A value outside ``low ... high`` (its magnitude; zero is always plausible, a unit
    slip cannot produce it) is almost always a unit slip (mm typed into a metre key,
    tonnes into a kilogram key) and raises a :class:`PlausibilityWarning` from
    :func:`check_plausible`.  The ranges are chosen so that every bundled file lies
    inside and the same file with any one value multiplied by 1000 or by 1/1000 lies
    outside (docs/decisions.md, "Plausible ranges of file values").

    ``physical_low`` / ``physical_high`` (optional) bound what the key can mean at all (a
    gap of metres, a flux density in iron of thousands of tesla, a force reserve below 1):
    a positive value outside them is refused by :func:`check_plausible` instead of warned
    (values <= 0 are left to the file's own checks); ``physical_note`` says why, in the
    refusal.
    """

    low: float
    high: float
    unit: str
    physical_low: float | None = None
    physical_high: float | None = None
    physical_note: str = ""

    def __post_init__(self) -> None:
        if not 0.0 < self.low < self.high:
            raise ValueError(f"Plausible range {self.low} ... {self.high}: need 0 < low < high")
        if (self.physical_low is not None and self.physical_low > self.low) or (
                self.physical_high is not None and self.physical_high < self.high):
            raise ValueError(f"Plausible range {self.low} ... {self.high}: the physical "
                             f"limits {self.physical_low} ... {self.physical_high} must "
                             "enclose it")

    def allowed(self) -> str:
        """The physical limits in words, for a refusal (``"<= 1 m"``, ``">= 1 -"``)."""
        parts = ([f">= {self.physical_low:g}"] if self.physical_low is not None else []) + (
            [f"<= {self.physical_high:g}"] if self.physical_high is not None else [])
        return f"{' and '.join(parts) or 'any value'} {self.unit}"


#: The unit a value 1000 times too large / too small was most likely typed in, per SI unit.
_SLIP_UNITS = {
    "m": ("mm", "km"), "kg": ("g", "t (tonnes)"), "A": ("mA", "kA"), "ohm": ("mohm", "kohm"),
    "s": ("ms", "ks"), "Hz": ("mHz", "kHz"), "V": ("mV", "kV"), "N/m": ("N/km", "kN/m or N/mm"),
    "N s/m": ("N s/km", "kN s/m or N s/mm"), "kg/m": ("g/m or kg/km", "t/m or kg/mm"),
    "kg m^2": ("g m^2", "t m^2"), "N m^2": ("N mm^2 / 1000", "kN m^2"),
    "ohm m": ("mohm m", "kohm m"), "m/s": ("mm/s", "km/s"),
}


def _slip(value: float, rng: Plausible) -> str:
    """The likely unit slip of a magnitude outside ``rng`` (empty if none is likely)."""
    big, small = _SLIP_UNITS.get(rng.unit, (f"milli-{rng.unit}", f"kilo-{rng.unit}"))
    # a vehicle speed (a range reaching beyond 50 m/s): km/h typed in, not mm/s
    if rng.unit == "m/s" and rng.high > 50.0 and value > rng.high and value / 3.6 <= rng.high:
        return (f"typed in km/h instead of m/s? ({value:g} m/s is {value * 3.6:g} km/h; "
                f"{value:g} km/h is {value / 3.6:.4g} m/s)")
    if rng.unit == "T" and value > rng.high and rng.low <= value / 1e4 <= rng.high:
        return f"typed in gauss instead of tesla? ({value:g} G is {value / 1e4:g} T)"
    if value > rng.high and rng.low <= value / 1000.0 <= rng.high:
        return f"1000 times too large: typed in {big} instead of {rng.unit}?"
    if value < rng.low and rng.low <= value * 1000.0 <= rng.high:
        return f"1000 times too small: typed in {small} instead of {rng.unit}?"
    return f"check its unit ({rng.unit})"


def check_plausible(values: Mapping[str, Any], ranges: Mapping[str, Plausible],
                    source: str = "", *, stacklevel: int = 3,
                    error: Callable[[str], Exception] = InputError) -> list[str]:
    """Warn about every file value outside its plausible range, refuse one outside its
    physical limits; the one such check.

    Parameters
    ----------
    values : mapping
        The parsed file: ``{table: {key: value}}``.  Keys of ``ranges`` missing from it,
        and values that are not numbers (checked elsewhere), are skipped; a list is
        checked element by element.
    ranges : mapping
        ``"table.key" -> Plausible``: the one table of ranges of a file kind.
    source : str
        The file's label for the message.
    error : callable, default InputError
        The exception (class) raised for a value outside :attr:`Plausible.physical_low`
        ... :attr:`Plausible.physical_high` (e.g. the file kind's own error).

    Returns
    -------
    list of str
        The ``"table.key"`` names warned about (for tests and callers).

    Raises
    ------
    Exception
        ``error(message)`` for the first positive value outside its physical limits,
        naming the key, the value, the unit, the allowed values and the likely slip.

    Warns
    -----
    PlausibilityWarning
        One per implausible key, naming the key, the value, the unit the key expects, the
        plausible range and the likely slip.
    """
    flagged: list[str] = []
    prefix = f"{source}: " if source else ""
    for name, rng in ranges.items():
        table, _, key = name.partition(".")
        tab = values.get(table)
        if not isinstance(tab, Mapping) or key not in tab:
            continue
        raw = tab[key]
        items = raw if isinstance(raw, list) else [raw]
        for item in items:
            if _is_bool(item) or not isinstance(item, numbers.Real):
                continue
            try:
                mag = abs(float(item))
            except OverflowError:   # an integer beyond float: the file's own check refuses it
                continue
            if mag == 0.0 or not math.isfinite(mag) or rng.low <= mag <= rng.high:
                continue
            val = float(item)
            if val > 0.0 and ((rng.physical_low is not None and val < rng.physical_low) or (
                    rng.physical_high is not None and val > rng.physical_high)):
                raise error(f"{prefix}[{table}] {key} = {item!r} {rng.unit} cannot be "
                            f"physical ({key} is in {rng.unit}): allowed are "
                            f"{rng.allowed()} ("
                            + (f"{rng.physical_note}; " if rng.physical_note else "")
                            + f"plausible {rng.low:g} ... {rng.high:g} {rng.unit}); "
                            f"{_slip(mag, rng)}")
            side = "above" if mag > rng.high else "below"
            warnings.warn(
                f"{prefix}[{table}] {key} = {item!r} {rng.unit} is {side} the plausible range "
                f"{rng.low:g} ... {rng.high:g} {rng.unit} ({key} is in {rng.unit}); "
                f"{_slip(mag, rng)}", PlausibilityWarning, stacklevel=stacklevel)
            flagged.append(name)
            break
    return flagged


_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep


def external_stacklevel() -> int:
    """The ``stacklevel`` that points a warning at the first caller outside maglevkit.

    Call it in the function that calls :func:`warnings.warn`: it counts that function's
    frame and every maglevkit frame above it (models, wrappers such as
    :func:`renamed_keywords`'s, which add a frame of their own), so the warning names the
    user's line however deep inside maglevkit it is raised.

    Returns
    -------
    int
        A value for ``warnings.warn(..., stacklevel=...)``, >= 1.
    """
    frame = sys._getframe(1)
    level = 1
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level


def renamed_keywords(**renames: str) -> Callable[[_F], _F]:
    """Decorator: keep old (unit-less) keyword names of a function as deprecated aliases.

    ``@renamed_keywords(dt="dt_s", gaps="gaps_m")`` lets callers still write ``dt=...``:
    the value is passed on as ``dt_s`` with a :class:`DeprecationWarning` that names the
    new keyword.  Giving both names is an :class:`~maglevkit.errors.InputError`.  Calls
    without an old name pay one set test.

    On a class (e.g. a dataclass whose fields were renamed) it wraps the constructor the
    same way and adds each old name as a read-only property that returns the new
    attribute with the same warning, so ``obj.gaps`` still reads ``obj.gaps_m``.  The
    wrapped function (or class) has the attribute ``renamed_keywords``, the old -> new
    mapping, for tools that migrate callers (``tools/rename_element_fields.py``).

    Parameters
    ----------
    **renames : str
        Old keyword name -> new keyword name.

    Returns
    -------
    callable
        The decorator (it keeps the function's name, docstring and signature; a class
        is returned itself, changed in place).
    """
    old_names = frozenset(renames)

    def wrap(fn: _F, where: str) -> _F:
        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if kwargs and not old_names.isdisjoint(kwargs):
                found = [old for old in renames if old in kwargs]
                for old in found:
                    new = renames[old]
                    if new in kwargs:
                        raise InputError(f"{where}: give {new}= only ({old}= is its "
                                         "deprecated name)")
                    kwargs[new] = kwargs.pop(old)
                # one warning per call, naming every old keyword and its new name
                warnings.warn(f"{where}: " + "; ".join(f"{old}= is deprecated, use "
                                                       f"{renames[old]}=" for old in found)
                              + " (same values and units)", DeprecationWarning, stacklevel=2)
            return fn(*args, **kwargs)

        wrapper.renamed_keywords = dict(renames)    # type: ignore[attr-defined]
        return cast(_F, wrapper)

    def alias(where: str, old: str, new: str) -> property:
        def read(self: Any) -> Any:
            warnings.warn(f"{where}: .{old} is deprecated, use .{new} (same values and "
                          "units)", DeprecationWarning, stacklevel=2)
            return getattr(self, new)

        return property(read, doc=f"Deprecated alias of ``{new}`` (read only).")

    def decorate(fn: _F) -> _F:
        if isinstance(fn, type):
            cls: Any = fn
            where = cls.__qualname__
            taken = [old for old in renames if old in vars(cls)]
            if taken:
                raise TypeError(f"{where} already defines {taken}")
            cls.__init__ = wrap(cls.__init__, where)
            for old, new in renames.items():
                setattr(cls, old, alias(where, old, new))
            cls.renamed_keywords = dict(renames)        # read by tools that migrate callers
            return fn
        return wrap(fn, fn.__qualname__)

    return decorate
