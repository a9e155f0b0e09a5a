"""Magnetic materials: the constitutive law H(B) of the iron parts.

Every material gives the magnetic field strength ``H`` [A/m] as an explicit, odd,
monotone function of the flux density ``B`` [T].  The same method works on NumPy
arrays and on CasADi symbols (``SX``/``MX``), so the equivalent magnetic circuit can
be assembled symbolically and differentiated exactly.

Available laws
--------------
* :class:`SoftMagneticMaterial` -- the Roschke approximation used by the Modelica
  ``Magnetic.FluxTubes`` library, ``mu_r(B) = 1 + (mu_i - 1 + c_a B_N) /
  (1 + c_b B_N + B_N^n)`` with ``B_N = |B| / B_mymax``.
* :class:`TabulatedBH` -- measured (H, B) pairs (lists or a two-column CSV file,
  :func:`read_bh_csv`), interpolated so that ``0 < dH/dB <= 1/mu0`` holds everywhere by
  construction (C1 ``"smooth"`` law, or ``"linear"`` as FEM tools), continued with slope
  ``mu0`` beyond the last point.
* :class:`ConstantPermeability` -- linear iron, ``H = B / (mu0 mu_r)``.
* :class:`IdealIron` -- ``mu -> inf`` (``H = 0``), for closed-form limit checks.

Built-in records are looked up with :func:`get_material`; names are compared
case- and punctuation-insensitively (``"AISI 1008" == "aisi_1008"``).
"""

from __future__ import annotations

import math
import os
import re
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from .errors import MaterialError
from .validation import real_number, renamed_keywords

MU0: float = 4e-7 * math.pi
"""Permeability of free space [H/m] (the classical value; the 2019 SI value differs by 1e-10)."""

__all__ = [
    "MU0",
    "Material",
    "SoftMagneticMaterial",
    "TabulatedBH",
    "INTERPOLATIONS",
    "CHORD_TOLERANCE",
    "MAX_POLARISATION_T",
    "read_bh_csv",
    "ConstantPermeability",
    "IdealIron",
    "get_material",
    "material_names",
    "normalise_name",
]


def _is_symbolic(x: Any) -> bool:
    return isinstance(x, (ca.SX, ca.MX, ca.DM))


class Material(ABC):
    """Constitutive law of a soft-magnetic material.

    Subclasses implement :meth:`field_strength`; the base derives the rest.
    """

    name: str
    resistivity_ohm_m: float | None

    @abstractmethod
    def field_strength(self, B: Any) -> Any:
        """Magnetic field strength H [A/m] for flux density B [T] (NumPy or CasADi).

        Parameters
        ----------
        B : float, array_like or CasADi
            Flux density [T] (any sign: the law is odd in B).

        Returns
        -------
        ndarray or CasADi
            H [A/m], the shape of ``B``.
        """

    def relative_permeability(self, B: Any) -> Any:
        """Relative permeability ``B / (mu0 H)`` (NumPy input only; ``mu_r(0)`` at B = 0).

        Parameters
        ----------
        B : float or array_like
            Flux density [T].

        Returns
        -------
        ndarray
            Secant relative permeability ``mu_r`` [-], the shape of ``B`` (``inf`` for
            ideal iron).
        """
        b = np.asarray(B, dtype=float)
        h = np.asarray(self.field_strength(b), dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = np.where(b == 0.0, self.initial_relative_permeability, b / (MU0 * h))
        return mu

    @property
    @abstractmethod
    def initial_relative_permeability(self) -> float:
        """``mu_r`` at B -> 0 [-] (``inf`` for ideal iron)."""

    @property
    def saturates(self) -> bool:
        """Whether the law is nonlinear."""
        return True

    def linearized(self) -> Material:
        """The same material without saturation: constant ``mu_r = mu_r(0)``."""
        mu = self.initial_relative_permeability
        if math.isinf(mu):
            return IdealIron(name=self.name, resistivity_ohm_m=self.resistivity_ohm_m)
        return ConstantPermeability(mu_r=mu, name=f"{self.name} (linear)",
                                    resistivity_ohm_m=self.resistivity_ohm_m)

    def energy_density(self, B: Any) -> np.ndarray:
        """Stored magnetic energy density ``w(B) = integral_0^B H dB`` [J/m^3] (NumPy).

        This general form integrates :meth:`field_strength` numerically (adaptive
        quadrature, relative tolerance 1e-13) point by point; subclasses with a closed
        form override it.

        Parameters
        ----------
        B : float or array_like
            Flux density [T], any shape (NumPy only, no CasADi symbols).

        Returns
        -------
        ndarray
            ``w(B)`` [J/m^3], the shape of ``B`` (even in B, 0 at ``B = 0``).
        """
        from scipy import integrate  # lazily: importing it takes ~0.2 s

        b = np.asarray(B, dtype=float)

        def one(bb: float) -> float:
            if bb == 0.0:
                return 0.0
            val, _ = integrate.quad(
                lambda t: float(self.field_strength(np.float64(t))), 0.0, bb,
                epsabs=0.0, epsrel=1e-13, limit=200,
            )
            return float(val)

        return np.vectorize(one, otypes=[float])(b)


@renamed_keywords(resistivity="resistivity_ohm_m")
@dataclass(frozen=True)
class SoftMagneticMaterial(Material):
    """Roschke/Modelica approximation of a soft-magnetic B-H curve.

    The formula's polarisation ``J = B - mu0 H`` peaks at some ``B*`` (1.79-3.57 T for the
    bundled records, :attr:`tail_from_T`) and falls beyond it (``mu_r,diff < 1``), which is
    unphysical: a saturated ferromagnet keeps its polarisation.  Beyond ``B*`` the law is
    therefore continued along its tangent of slope ``1/mu0``, ``H = H(B*) + (|B| - B*) / mu0``
    (``J = J(B*)`` constant, C1 at ``B*``), so ``0 < dH/dB <= 1/mu0`` holds everywhere.

    Parameters
    ----------
    mu_i : float
        Initial relative permeability [-], must be >= 1.
    B_mymax : float
        Flux density at which the curve parameters are normalised [T] (> 0).
    c_a, c_b : float
        Shape coefficients [-] (>= 0).
    n : float
        Saturation exponent [-] (> 1 so that H(B) is twice differentiable at 0).
    name : str
        Display name.
    resistivity_ohm_m : float or None
        Electrical resistivity [ohm m] for eddy-current estimates, if known.
    """

    mu_i: float
    B_mymax: float
    c_a: float
    c_b: float
    n: float
    name: str = "soft-magnetic"
    resistivity_ohm_m: float | None = None
    #: Flux density [T] above which ``H`` continues with slope ``1/mu0`` (inf: never).
    tail_from_T: float = field(init=False, default=math.inf)

    def __post_init__(self) -> None:
        vals = {"mu_i": self.mu_i, "B_mymax": self.B_mymax, "c_a": self.c_a,
                "c_b": self.c_b, "n": self.n}
        for key, v in vals.items():
            if not math.isfinite(v):
                raise MaterialError(f"material {self.name!r}: {key} = {v} is not finite")
        if self.mu_i < 1.0:
            raise MaterialError(
                f"material {self.name!r}: mu_i = {self.mu_i} < 1; the initial relative "
                "permeability must be >= 1 (mu_i < 1 makes H(B) jump at B = 0 and the "
                "network Jacobian singular at zero flux)"
            )
        if self.B_mymax <= 0.0:
            raise MaterialError(f"material {self.name!r}: B_mymax = {self.B_mymax} T must be > 0")
        if self.c_a < 0.0 or self.c_b < 0.0:
            raise MaterialError(f"material {self.name!r}: c_a and c_b must be >= 0")
        if self.n <= 1.0:
            raise MaterialError(f"material {self.name!r}: exponent n = {self.n} must be > 1")
        _check_resistivity(self)
        object.__setattr__(self, "tail_from_T", self._polarisation_peak())
        # H(B) must be strictly increasing, otherwise the network has no unique solution.
        b = np.linspace(0.0, 6.0 * max(self.B_mymax, 1.0), 4001)
        h = self.field_strength(b)
        if np.any(np.diff(h) <= 0.0):
            raise MaterialError(
                f"material {self.name!r}: these coefficients give a non-monotone H(B); "
                "choose c_a, c_b, n so that B / mu_r(B) increases with B"
            )

    def _mu_r(self, B: Any) -> Any:
        sym = _is_symbolic(B)
        bn = (ca.fabs(B) if sym else np.abs(B)) / self.B_mymax
        return 1.0 + (self.mu_i - 1.0 + self.c_a * bn) / (1.0 + self.c_b * bn + bn**self.n)

    def _fit_slope(self, b: np.ndarray) -> np.ndarray:
        """``mu0 dH/dB`` of the plain Roschke formula at ``b >= 0`` (= 1 / mu_r,diff)."""
        bm, a, n = self.B_mymax, self.mu_i - 1.0, self.n
        bn = b / bm
        num = a + self.c_a * bn
        den = 1.0 + self.c_b * bn + bn**n
        mu = 1.0 + num / den
        dmu = (self.c_a * den - num * (self.c_b + n * bn ** (n - 1.0))) / (bm * den**2)
        return np.asarray((mu - b * dmu) / mu**2)

    def _polarisation_peak(self) -> float:
        """Smallest ``B > 0`` where the fit's ``mu_r,diff`` falls to 1 (inf if nowhere).

        There the polarisation ``J = B - mu0 H`` of the formula peaks; beyond it the
        formula has ``dJ/dB < 0`` (``mu_r,diff < 1``: incrementally less permeable than
        air), which no ferromagnet shows.
        """
        b = np.geomspace(1e-6, 1e3, 6001) * self.B_mymax
        g = self._fit_slope(b) - 1.0
        up = np.nonzero((g[:-1] < 0.0) & (g[1:] >= 0.0))[0]
        if up.size == 0:
            return math.inf
        from scipy.optimize import brentq

        k = int(up[0])
        return float(brentq(lambda x: float(self._fit_slope(np.array(x))) - 1.0, b[k], b[k + 1],
                            xtol=1e-14, rtol=1e-14))

    def field_strength(self, B: Any) -> Any:
        """Magnetic field strength H [A/m] for flux density B [T] (NumPy or CasADi).

        The Roschke fit ``H = B / (mu0 mu_r(B))`` up to :attr:`tail_from_T`, then the tangent
        of slope ``1/mu0``.

        Parameters
        ----------
        B : float, array_like or CasADi
            Flux density [T] (any sign: the law is odd in B).

        Returns
        -------
        ndarray or CasADi
            H [A/m], the shape of ``B``.
        """
        bs = self.tail_from_T
        if _is_symbolic(B):
            h_fit = B / (MU0 * self._mu_r(B))
            if not math.isfinite(bs):
                return h_fit
            h_s = bs / (MU0 * float(self._mu_r(np.float64(bs))))
            tail = ca.sign(B) * (h_s + (ca.fabs(B) - bs) / MU0)
            return ca.if_else(ca.fabs(B) <= bs, h_fit, tail)
        B = np.asarray(B, dtype=float)
        h_fit = B / (MU0 * self._mu_r(B))
        if not math.isfinite(bs):
            return h_fit
        h_s = bs / (MU0 * float(self._mu_r(np.float64(bs))))
        return np.where(np.abs(B) <= bs, h_fit,
                        np.sign(B) * (h_s + (np.abs(B) - bs) / MU0))

    @property
    def initial_relative_permeability(self) -> float:
        return float(self.mu_i)


def _check_resistivity(material: Material) -> None:
    """The one check of every material's optional ``resistivity`` (finite, > 0 ohm m)."""
    rho = getattr(material, "resistivity_ohm_m", None)
    if rho is not None:
        real_number(rho, f"material {getattr(material, 'name', '?')!r}: resistivity_ohm_m",
                    "ohm m", positive=True, error=MaterialError)


@renamed_keywords(resistivity="resistivity_ohm_m")
@dataclass(frozen=True)
class ConstantPermeability(Material):
    """Linear material ``H = B / (mu0 mu_r)``.

    Parameters
    ----------
    mu_r : float
        Relative permeability [-], finite and >= 1.
    name : str, default "linear"
        Display name.
    resistivity_ohm_m : float or None
        Electrical resistivity [ohm m] for eddy-current estimates, if known (finite,
        > 0).

    Raises
    ------
    MaterialError
        ``mu_r`` not finite or < 1 (use :class:`IdealIron` for ``mu_r -> inf``); a
        ``resistivity_ohm_m`` that is not a finite number > 0.
    """

    mu_r: float
    name: str = "linear"
    resistivity_ohm_m: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mu_r) and self.mu_r >= 1.0):
            raise MaterialError(
                f"material {self.name!r}: mu_r = {self.mu_r} must be finite and >= 1 "
                "(use IdealIron for mu -> inf)"
            )
        _check_resistivity(self)

    def field_strength(self, B: Any) -> Any:
        """Magnetic field strength H [A/m] for flux density B [T] (NumPy or CasADi).

        ``H = B / (mu0 mu_r)``.

        Parameters
        ----------
        B : float, array_like or CasADi
            Flux density [T] (any sign: the law is odd in B).

        Returns
        -------
        ndarray or CasADi
            H [A/m], the shape of ``B``.
        """
        if not _is_symbolic(B):
            B = np.asarray(B, dtype=float)
        return B / (MU0 * self.mu_r)

    @property
    def initial_relative_permeability(self) -> float:
        return float(self.mu_r)

    @property
    def saturates(self) -> bool:
        return False

    def energy_density(self, B: Any) -> np.ndarray:
        """Energy density ``B^2 / (2 mu0 mu_r)`` [J/m^3] (closed form).

        Parameters
        ----------
        B : float or array_like
            Flux density [T] (NumPy only).

        Returns
        -------
        ndarray
            ``w(B)`` [J/m^3], the shape of ``B`` (even in B).
        """
        b = np.asarray(B, dtype=float)
        return b * b / (2.0 * MU0 * self.mu_r)


@renamed_keywords(resistivity="resistivity_ohm_m")
@dataclass(frozen=True)
class IdealIron(Material):
    """Infinitely permeable iron (``H = 0``): the reluctance of the part vanishes.

    Parameters
    ----------
    name : str, default "ideal"
        Display name.
    resistivity_ohm_m : float or None
        Electrical resistivity [ohm m] for eddy-current estimates, if known (finite,
        > 0).

    Raises
    ------
    MaterialError
        A ``resistivity_ohm_m`` that is not a finite number > 0.
    """

    name: str = "ideal"
    resistivity_ohm_m: float | None = None

    def __post_init__(self) -> None:
        _check_resistivity(self)

    def field_strength(self, B: Any) -> Any:
        """Magnetic field strength H [A/m] for flux density B [T] (NumPy or CasADi).

        Zero for every B.

        Parameters
        ----------
        B : float, array_like or CasADi
            Flux density [T] (any sign: the law is odd in B).

        Returns
        -------
        ndarray or CasADi
            H [A/m], the shape of ``B``.
        """
        return 0.0 * B if _is_symbolic(B) else np.zeros_like(np.asarray(B, dtype=float))

    @property
    def initial_relative_permeability(self) -> float:
        return math.inf

    @property
    def saturates(self) -> bool:
        return False

    def energy_density(self, B: Any) -> np.ndarray:
        """Energy density: zero (ideal iron stores no energy) [J/m^3].

        Parameters
        ----------
        B : float or array_like
            Flux density [T] (NumPy only).

        Returns
        -------
        ndarray
            ``w(B)`` [J/m^3], the shape of ``B`` (even in B).
        """
        return np.zeros_like(np.asarray(B, dtype=float))


INTERPOLATIONS: tuple[str, ...] = ("smooth", "linear")
"""Interpolation laws of :class:`TabulatedBH`: ``"smooth"`` (C1) and ``"linear"`` (as FEM tools)."""

CHORD_TOLERANCE: float = 1e-3
"""Relative allowance below ``mu0`` for a table's chords ``dB/dH`` (rounding in published tables)."""

MAX_POLARISATION_T: float = 3.0
"""Upper bound for the polarisation ``J = B - mu0 H`` of table points [T] (iron-cobalt: 2.4 T)."""

# A chord whose magnetisation rises by less than this many ulps of B_n (times 1/mu0) is a
# saturated chord that rounding made barely steeper than mu0; it is interpolated with slope
# exactly mu0 (later points move by at most 64 ulp(B_n)/mu0, 2.2e-8 A/m at 2.4 T), because
# the bends of H' it would need could not be placed in floating point.
_FLAT_ULPS = 64.0
# Smallest fraction of an interval for a bend of H' (if the chord leaves room), and how far
# the knot slope may move from the chord slope to make that room (fraction of the room
# between the chord slope and 0 or 1/mu0).
_BEND = 0.05
_BEND_DIP = 0.05


def read_bh_csv(path: str | os.PathLike[str]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Read a B-H table from a two-column text file: ``H`` [A/m], then ``B`` [T].

    Format: one point per line, the two numbers separated by a comma, a semicolon or
    white space; blank lines and lines starting with ``#`` are ignored; the first other
    line may be a header (e.g. ``H [A/m], B [T]``).  A unit in brackets or parentheses in
    the header must be ``A/m`` and ``T``; a header naming the columns ``B, H`` is refused
    (the order is H, B).  The points must be a first-magnetisation curve from the origin
    (see :class:`TabulatedBH`).

    Parameters
    ----------
    path : str or os.PathLike
        The text file.

    Returns
    -------
    H, B : tuple of float
        Field strength [A/m] and flux density [T] of the points, in file order.

    Raises
    ------
    MaterialError
        Missing or unreadable file, a line without exactly two numbers, swapped or
        wrongly labelled columns, fewer than two points.
    """
    p = Path(path)
    if not p.is_file():
        raise MaterialError(f"B-H file {str(p)!r} does not exist")
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise MaterialError(f"B-H file {str(p)!r} cannot be read as text: {exc}") from None
    h: list[float] = []
    b: list[float] = []
    seen_line = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = _csv_fields(line)
        where = f"B-H file {str(p)!r}, line {lineno}"
        try:
            values = [float(f) for f in fields]
        except ValueError:
            values = []
        if not values:
            if seen_line:
                raise MaterialError(f"{where}: {line!r} is not two numbers "
                                    "(H [A/m], B [T]); only the first line may be a header")
            # No space around brackets, so that "H [A/m]  B [T]" is two column names.
            tight = re.sub(r"\s+(?=[\[(])|(?<=[\[(])\s+|\s+(?=[\])])", "", line)
            _check_header(_csv_fields(tight), where)
            seen_line = True
            continue
        seen_line = True
        if len(values) != 2:
            raise MaterialError(f"{where}: expected 2 numbers (H [A/m], B [T]), "
                                f"got {len(values)} in {line!r}")
        if not all(math.isfinite(v) for v in values):
            raise MaterialError(f"{where}: values must be finite numbers, got {line!r}")
        h.append(values[0])
        b.append(values[1])
    if len(h) < 2:
        raise MaterialError(f"B-H file {str(p)!r}: needs at least 2 points (the origin and one "
                            f"more), found {len(h)}")
    return tuple(h), tuple(b)


def _csv_fields(line: str) -> list[str]:
    """Fields of one line: comma- or semicolon-separated, else white-space-separated."""
    if "," in line or ";" in line:
        fields = [f.strip() for f in re.split(r"[,;]", line)]
        while len(fields) > 2 and not fields[-1]:  # trailing separators (spreadsheets)
            fields.pop()
        return fields
    return line.split()


def _check_header(fields: list[str], where: str) -> None:
    if len(fields) != 2:
        raise MaterialError(f"{where}: a header must name 2 columns (H [A/m], B [T]), "
                            f"got {len(fields)}: {fields}")
    names = [re.sub(r"[\[(].*", "", f).strip().lower() for f in fields]
    if names[0].startswith("b") and names[1].startswith("h"):
        raise MaterialError(f"{where}: the header {fields} names the columns B, H; the file "
                            "must list H [A/m] first, then B [T]")
    for f, unit in zip(fields, ("a/m", "t"), strict=True):
        m = re.search(r"[\[(]\s*([^\])]*?)\s*[\])]", f)
        if m and m.group(1).replace(" ", "").lower() != unit:
            want = "A/m" if unit == "a/m" else "T"
            raise MaterialError(f"{where}: column {f!r} has unit {m.group(1)!r}; "
                                f"H must be in A/m and B in T (this column: {want})")


def _physical_points(h: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Field strengths with the magnetisation ``M = B/mu0 - H`` made non-decreasing.

    Where rounding made a chord slightly flatter than ``mu0`` (M falls), M is held at its
    running maximum, i.e. the point's H is lowered by the deficit; elsewhere H is unchanged.
    """
    m = b / MU0 - h
    m_up = np.maximum.accumulate(m)
    return np.where(m_up > m, h - (m_up - m), h)


def _smooth_knot_slopes(hb: np.ndarray, d: np.ndarray, dm: np.ndarray) -> np.ndarray:
    """Slopes ``dH/dB`` at the table points for the smooth interpolant (all in (0, 1/mu0]).

    ``hb``: B increments, ``d``: chord slopes dH/dB, ``dm``: magnetisation increments [A/m].
    """
    U = 1.0 / MU0
    n = d.size
    s = np.empty(n + 1)
    if n == 1:
        s[0] = d[0]
    else:
        # PCHIP's end formula (one-sided parabola through the first three points), limited
        # to [d0/2, min(2 d0, U)].
        s0 = ((2.0 * hb[0] + hb[1]) * d[0] - hb[0] * d[1]) / (hb[0] + hb[1])
        s[0] = min(max(s0, 0.5 * d[0]), min(2.0 * d[0], U))
        # PCHIP's interior slope (Fritsch-Butland weighted harmonic mean of the two chords,
        # weights as in scipy's PchipInterpolator), taken for H' or for M' = U - H'.  Each
        # chord leaves a B-width mu0 dH for bends of H' towards 0 and mu0 dM for bends
        # towards U; the chord with less room decides: its small side gets the harmonic
        # mean (below twice its chord), so the bends go into the roomier neighbour.
        w1 = 2.0 * hb[1:] + hb[:-1]
        w2 = hb[1:] + 2.0 * hb[:-1]
        e = U - d
        dh = d * hb
        room = np.minimum(dh, dm)
        k = np.where(room[:-1] <= room[1:], 0, 1)  # 0: the left chord decides
        h_side = np.where(k == 0, dh[:-1] <= dm[:-1], dh[1:] <= dm[1:])
        with np.errstate(divide="ignore", invalid="ignore"):
            h_mean = (w1 + w2) / (w1 / d[:-1] + w2 / d[1:])
            m_mean = np.where((e[:-1] > 0.0) & (e[1:] > 0.0),
                              (w1 + w2) / (w1 / e[:-1] + w2 / e[1:]), 0.0)
        si = np.where(h_side, h_mean, U - m_mean)
        s[1:n] = np.clip(si, np.minimum(d[:-1], d[1:]), np.maximum(d[:-1], d[1:]))
    s[n] = U  # the tail above the table has slope mu0: C1 there too
    flat = d >= U  # M constant on the chord: H' = U on all of it, so at both of its ends
    s[:-1][flat] = U
    s[1:][flat] = U
    return s


def _interval_knots(sl: float, sr: float, d: float) -> list[tuple[float, float]]:
    """Interior knots ``(fraction, slope)`` of one interval's continuous piecewise-linear H'.

    The end slopes are ``sl``, ``sr`` and the mean must be the chord slope ``d``; every
    interior slope lies in ``[d/2, d + (U - d)/2]``, inside ``(0, U]``.
    """
    U = 1.0 / MU0
    lo, hi = 0.5 * d, d + 0.5 * (U - d)
    if sl == d and sr == d:
        return []
    if (sl - d) * (sr - d) <= 0.0:
        # d between the end slopes: one knot whose slope is d keeps H' monotone (convexity
        # of the data is preserved).  A knot closer than _BEND to an end is moved inwards,
        # as far as the knot slope a = d + (lam - lam*) (sr - sl) stays within
        # _BEND_DIP of the room below (d) or above (U - d) the chord slope.
        lam_star = (sr - d) / (sr - sl)
        down, up = _BEND_DIP * d, _BEND_DIP * (U - d)
        rise = sr > sl
        eps_r = min(_BEND, (down if rise else up) / abs(sr - sl))  # knot moved left
        eps_l = min(_BEND, (up if rise else down) / abs(sr - sl))  # knot moved right
        lam = min(max(lam_star, eps_l), 1.0 - eps_r)
        if 0.0 < lam < 1.0:
            a = 2.0 * d - lam * sl - (1.0 - lam) * sr
            if lo <= a <= hi:
                return [(lam, a)]
    m = 0.5 * (sl + sr)
    a = 2.0 * d - m
    if lo <= a <= hi:
        return [(0.5, a)]
    # Both end slopes far on one side of d: ramps of width r to a plateau at the bound.
    a = lo if a < lo else hi
    r = (d - a) / (m - a)
    return [(r, a), (1.0 - r, a)]


def _bh_pieces(h: np.ndarray, b: np.ndarray, interpolation: str
               ) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints ``x`` and local coefficients ``c`` (rows: t^2, t, 1) of H(B) on [0, B_n]."""
    U = 1.0 / MU0
    hb = np.diff(b)
    d = np.minimum(np.diff(h) / hb, U)
    if interpolation == "linear":
        return b.copy(), np.vstack([np.zeros_like(d), d, h[:-1]])
    # Magnetisation increments (>= 0 after _physical_points); one whose B-equivalent is
    # below _FLAT_ULPS ulps of B_n is rounding and counts as zero (the chord as mu0).
    dm = np.maximum(np.diff(b / MU0 - h), 0.0)
    flat = MU0 * dm <= _FLAT_ULPS * np.spacing(b[-1])
    d = np.where(flat, U, d)
    dm = np.where(flat, 0.0, dm)
    s = _smooth_knot_slopes(hb, d, dm)
    xs: list[float] = []
    gs: list[float] = []
    for i in range(d.size):
        knots = [(0.0, float(s[i])), *_interval_knots(float(s[i]), float(s[i + 1]), float(d[i]))]
        for f, gk in knots:
            xs.append(float(b[i] + f * hb[i]) if f else float(b[i]))
            gs.append(gk)
    xs.append(float(b[-1]))
    gs.append(float(s[-1]))
    x, g = np.asarray(xs), np.asarray(gs)
    dx = np.diff(x)
    if np.any(dx <= 0.0):  # only if a chord leaves no room above rounding for a bend
        j = int(np.argmin(dx))
        raise MaterialError(f"near B = {x[j]:.9g} T the points are too close for floating "
                            "point: the curve must bend within less than rounding there; "
                            "merge or drop points whose H or B - mu0 H barely differ")
    c1 = g[:-1]
    c2 = np.diff(g) / (2.0 * dx)
    # H accumulated along the pieces, each start value computed exactly as the previous
    # piece evaluates at its end, so that H is continuous to rounding; the table points are
    # met to the rounding of the sub-knot positions (|H'| * ulp(B) per knot, < 1e-9 A/m).
    c0 = np.empty_like(c1)
    hv = 0.0
    for j in range(c1.size):
        c0[j] = hv
        hv = (c2[j] * dx[j] + c1[j]) * dx[j] + hv
    return x, np.array([c2, c1, c0])


@renamed_keywords(resistivity="resistivity_ohm_m")
@dataclass(frozen=True)
class TabulatedBH(Material):
    """Material from measured (H, B) pairs of the first-magnetisation curve.

    ``interpolation="smooth"`` (default): H(B) is a C1 piecewise quadratic through the
    points whose slope ``dH/dB`` is continuous, piecewise linear and, by construction,
    in ``(0, 1/mu0]`` everywhere: ``mu_r >= 1``, the magnetisation ``M = B/mu0 - H`` is
    non-decreasing and H is strictly increasing (docs/equations.md, "Tabulated B-H
    curves").  ``interpolation="linear"``: straight lines between the points, as FEM
    tools do (kinks at the points).  Both continue above the last point with slope
    ``mu0`` (``H = H_n + (B - B_n)/mu0``, C1 for ``"smooth"``); the curve is odd in B.

    A chord with ``dB/dH`` below ``mu0`` by at most :data:`CHORD_TOLERANCE` (rounding in
    published saturated tails) is accepted: the magnetisation is held constant there, which
    lowers the later point's H by at most that fraction of the chord's H increment
    (:attr:`max_adjustment_A_per_m`).

    Parameters
    ----------
    H : sequence of float
        Field strength [A/m], starting at 0, strictly increasing.
    B : sequence of float
        Flux density [T], starting at 0, strictly increasing, chords ``dB/dH >= mu0``
        (within :data:`CHORD_TOLERANCE`), polarisation ``B - mu0 H`` at most
        :data:`MAX_POLARISATION_T`.
    name : str
        Display name.
    resistivity_ohm_m : float or None
        Electrical resistivity [ohm m] for eddy-current estimates, if known.
    interpolation : {"smooth", "linear"}
        Interpolation law between the points (keyword-only).
    """

    H: tuple[float, ...]
    B: tuple[float, ...]
    name: str = "tabulated"
    resistivity_ohm_m: float | None = None
    interpolation: str = field(default="smooth", kw_only=True)
    _x: Any = field(init=False, repr=False, compare=False)
    _c: Any = field(init=False, repr=False, compare=False)
    _w: Any = field(init=False, repr=False, compare=False)
    _h_used: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            h = np.asarray(self.H, dtype=float)
            b = np.asarray(self.B, dtype=float)
        except (TypeError, ValueError) as exc:
            raise MaterialError(f"material {self.name!r}: H and B must be lists of numbers") from exc
        for key, seq in (("H", self.H), ("B", self.B)):
            flat = np.asarray(seq, dtype=object).ravel()
            if any(isinstance(v, (bool, np.bool_, str, bytes)) for v in flat):
                raise MaterialError(f"material {self.name!r}: {key} must be a list of numbers "
                                    "(got a string or true/false)")
        if h.ndim != 1 or b.ndim != 1:
            raise MaterialError(f"material {self.name!r}: H and B must be flat lists of numbers, "
                                f"got arrays of shape {h.shape} and {b.shape}")
        object.__setattr__(self, "H", tuple(float(v) for v in h))
        object.__setattr__(self, "B", tuple(float(v) for v in b))
        who = f"B-H table {self.name!r}"
        if not isinstance(self.interpolation, str) or self.interpolation not in INTERPOLATIONS:
            raise MaterialError(f"{who}: interpolation = {self.interpolation!r} is unknown; "
                                f"choose one of {', '.join(map(repr, INTERPOLATIONS))}")
        if h.size != b.size:
            raise MaterialError(f"{who}: H has {h.size} values but B has {b.size}; they must pair up")
        if h.size < 2:
            raise MaterialError(f"{who}: needs at least 2 points (the origin and one more), "
                                f"got {h.size}")
        if not (np.all(np.isfinite(h)) and np.all(np.isfinite(b))):
            raise MaterialError(f"{who}: values must be finite numbers")
        if h[0] != 0.0 or b[0] != 0.0:
            raise MaterialError(f"{who}: the curve must start at the origin (H[0] = B[0] = 0), "
                                f"got H[0] = {h[0]}, B[0] = {b[0]}")
        if np.any(np.diff(h) <= 0.0) or np.any(np.diff(b) <= 0.0):
            raise MaterialError(f"{who}: H and B must both be strictly increasing "
                                "(a first-magnetisation curve is monotone)")
        polarisation = b - MU0 * h
        if polarisation.max() > MAX_POLARISATION_T:
            i = int(np.argmax(polarisation))
            raise MaterialError(
                f"{who}: the polarisation B - mu0 H = {polarisation[i]:.4g} T at point {i} "
                f"exceeds {MAX_POLARISATION_T} T (no material saturates above ~2.4 T); check the "
                "units and the column order (H in A/m, B in T)")
        slopes = np.diff(b) / np.diff(h)
        allowed = MU0 * (1.0 - CHORD_TOLERANCE)
        if slopes[0] < allowed:
            raise MaterialError(f"{who}: mu_r(0) = {slopes[0] / MU0:.4g} < 1; the first point "
                                "must satisfy B_1 >= mu0 H_1")
        bad = np.nonzero(slopes < allowed)[0]
        if bad.size:
            i = int(bad[0])
            raise MaterialError(
                f"{who}: between points {i} and {i + 1} dB/dH = {slopes[i] / MU0:.6g} mu0 is "
                f"below mu0 by more than the rounding allowance {CHORD_TOLERANCE:g}; physical "
                "curves have dB/dH >= mu0 (check the units: H in A/m, B in T)"
            )
        _check_resistivity(self)
        h_used = _physical_points(h, b)
        try:
            x, c = _bh_pieces(h_used, b, self.interpolation)
        except MaterialError as exc:
            raise MaterialError(f"{who}: {exc}") from None
        dx = np.diff(x)
        w = np.concatenate([[0.0], np.cumsum(((c[0] * dx / 3.0 + c[1] / 2.0) * dx + c[2]) * dx)])
        object.__setattr__(self, "_x", x)
        object.__setattr__(self, "_c", c)
        object.__setattr__(self, "_w", w)
        object.__setattr__(self, "_h_used", h_used)

    @classmethod
    @renamed_keywords(resistivity="resistivity_ohm_m")
    def from_csv(cls, path: str | os.PathLike[str], *, name: str | None = None,
                 resistivity_ohm_m: float | None = None, interpolation: str = "smooth") -> TabulatedBH:
        """A table read by :func:`read_bh_csv` (H [A/m], B [T]); ``name`` defaults to the file stem.

        Parameters
        ----------
        path : str or os.PathLike
            Two-column text file, H [A/m] then B [T] (format: :func:`read_bh_csv`).
        name : str, optional
            Display name (default: the file name without its suffix).
        resistivity_ohm_m : float or None
            Electrical resistivity [ohm m], > 0, for eddy-current estimates, if known.
        interpolation : {"smooth", "linear"}
            Interpolation law between the points (default ``"smooth"``).

        Returns
        -------
        TabulatedBH

        Raises
        ------
        MaterialError
            An unreadable file or a table that is not a physical first-magnetisation curve
            (see the class docstring).
        """
        h, b = read_bh_csv(path)
        return cls(h, b, name=Path(path).stem if name is None else name,
                   resistivity_ohm_m=resistivity_ohm_m, interpolation=interpolation)

    @property
    def _h_end(self) -> float:
        """H at the last point as the interpolant reaches it (start of the mu0 tail)."""
        c, dx = self._c, float(self._x[-1] - self._x[-2])
        return float((c[0, -1] * dx + c[1, -1]) * dx + c[2, -1])

    @property
    def max_adjustment_A_per_m(self) -> float:
        """Largest change of a table point's H by the rounding allowance [A/m] (0: none)."""
        return float(np.max(np.abs(np.asarray(self.H) - self._h_used)))

    @property
    def initial_relative_permeability(self) -> float:
        # Slope of the interpolant at the origin; positive by construction (inf guards
        # against a zero slope, which ideal iron would have).
        dh_db = float(self._c[1, 0])
        return 1.0 / (MU0 * dh_db) if dh_db > 0.0 else math.inf

    def field_strength(self, B: Any) -> Any:
        """Magnetic field strength H [A/m] for flux density B [T] (NumPy or CasADi).

        The interpolant through the table points, continued above the last point with
        slope ``1/mu0``.

        Parameters
        ----------
        B : float, array_like or CasADi
            Flux density [T] (any sign: the law is odd in B).

        Returns
        -------
        ndarray or CasADi
            H [A/m], the shape of ``B``.
        """
        x, c = self._x, self._c
        b_end, h_end = float(x[-1]), self._h_end
        if _is_symbolic(B):
            bb = ca.fabs(B)
            # Tail above the table, continued with slope mu0.
            mag = h_end + (bb - b_end) / MU0
            for i in range(x.size - 2, 0, -1):
                d = bb - x[i]
                poly = (c[0, i] * d + c[1, i]) * d + c[2, i]
                mag = ca.if_else(bb < x[i + 1], poly, mag)
            tail = ca.sign(B) * mag
            # First piece written as B * q(|B|) so that dH/dB is exact at B = 0.
            first = B * (c[0, 0] * bb + c[1, 0])
            return ca.if_else(bb < x[1], first, tail)
        b = np.asarray(B, dtype=float)
        bb = np.abs(b)
        i = np.clip(np.searchsorted(x, bb, side="right") - 1, 0, x.size - 2)
        t = bb - x[i]
        mag = np.where(bb <= b_end, (c[0, i] * t + c[1, i]) * t + c[2, i],
                       h_end + (bb - b_end) / MU0)
        return np.sign(b) * mag

    def energy_density(self, B: Any) -> np.ndarray:
        """Energy density ``w(B) = integral_0^B H dB`` [J/m^3], exact for the interpolant.

        Parameters
        ----------
        B : float or array_like
            Flux density [T] (NumPy only).

        Returns
        -------
        ndarray
            ``w(B)`` [J/m^3], the shape of ``B`` (even in B).
        """
        x, c, w = self._x, self._c, self._w
        b = np.abs(np.asarray(B, dtype=float))
        b_end, h_end = float(x[-1]), self._h_end
        i = np.clip(np.searchsorted(x, b, side="right") - 1, 0, x.size - 2)
        t = b - x[i]
        w_in = w[i] + ((c[0, i] * t / 3.0 + c[1, i] / 2.0) * t + c[2, i]) * t
        e = b - b_end
        w_out = w[-1] + h_end * e + e * e / (2.0 * MU0)
        return np.where(b <= b_end, w_in, w_out)


# --------------------------------------------------------------------------- records
# Modelica Standard Library, Magnetic.FluxTubes.Material.SoftMagnetic (Roschke fits).
# Resistivities: pure iron 0.098e-6 ohm m [P]; solid structural/free-cutting steels
# 1.5e-7 ohm m [E] (typically 1e-7 to 2e-7; docs/sources.md sec. 4); none given for electrical sheet grades.
_ROSCHKE: dict[str, tuple[float, float, float, float, float, float | None]] = {
    # name: (mu_i, B_mymax, c_a, c_b, n, resistivity_ohm_m)
    "M330-50A": (500, 0.7, 24000, 9.38, 9.6, None),
    "M350-50A": (1210, 1.16, 24630, 2.44, 14, None),
    "M530-50A": (2120, 1.25, 12400, 1.6, 13.5, None),
    "M700-100A": (1120, 1.2, 20750, 3.55, 13.15, None),
    "M940-100A": (680, 1.26, 17760, 3.13, 13.9, None),
    "AISI 1008": (200, 1.17, 8100, 2.59, 10, 1.5e-7),
    "AISI 12L14": (10, 0.94, 5900, 4.19, 6.4, 1.5e-7),
    "DC01": (5, 1.1, 6450, 3.65, 7.7, 1.5e-7),
    "9SMnPb28": (400, 1.488, 1200, 3, 12.5, 1.5e-7),
    "X6Cr17": (274, 1.1, 970, 1.2, 8.3, None),
    "RFe80": (123, 1.27, 44410, 6.4, 10, 0.098e-6),
    "VACOFER S2": (2666, 1.15, 187000, 4.24, 19, None),
    "VACOFLUX 50": (3850, 1.75, 11790, 2.63, 15.02, None),
}


def normalise_name(name: str) -> str:
    """Case- and punctuation-insensitive key: ``"AISI 1008" -> "aisi1008"``.

    Parameters
    ----------
    name : str
        A material name.

    Returns
    -------
    str
        Lower-case letters and digits of ``name`` only.
    """
    return re.sub(r"[^0-9a-z]", "", name.lower())


_NAMES: dict[str, str] = {normalise_name(k): k for k in _ROSCHKE}
_REGISTRY: dict[str, SoftMagneticMaterial] = {}
"""The built-in records by normalised name, each built on its first use (building one
finds its polarisation peak with scipy's ``brentq``; importing scipy.optimize with this
module took ~0.4 s of every ``import maglevkit.vehicle``)."""


def material_names() -> list[str]:
    """Names of the built-in material records."""
    return sorted(_ROSCHKE)


def get_material(name: str | Material) -> Material:
    """Look up a built-in material by name (case/punctuation-insensitive).

    ``"ideal"`` gives :class:`IdealIron`.  A :class:`Material` is returned unchanged.

    Parameters
    ----------
    name : str or Material
        A built-in record name (:func:`material_names`, e.g. ``"AISI 1008"``), ``"ideal"``,
        or a material.

    Returns
    -------
    Material

    Raises
    ------
    MaterialError
        If the name is unknown (the message lists the known names), or ``name`` is
        neither a string nor a :class:`Material`.
    """
    if isinstance(name, Material):
        return name
    if not isinstance(name, str):
        raise MaterialError(f"material must be a name or a Material, got {type(name).__name__}")
    key = normalise_name(name)
    if key == "ideal":
        return IdealIron()
    try:
        canonical = _NAMES[key]
    except KeyError:
        raise MaterialError(
            f"unknown material {name!r}; built-in records are: {', '.join(material_names())}, "
            "or 'ideal' (or define a tabulated curve)"
        ) from None
    mat = _REGISTRY.get(key)
    if mat is None:
        v = _ROSCHKE[canonical]
        mat = _REGISTRY[key] = SoftMagneticMaterial(*v[:5], name=canonical, resistivity_ohm_m=v[5])
    return mat
