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
* :class:`TabulatedBH` -- measured (H, B) pairs, monotone cubic (PCHIP)
  interpolation of H(B), continued with slope ``mu0`` beyond the last point.
* :class:`ConstantPermeability` -- linear iron, ``H = B / (mu0 mu_r)``.
* :class:`IdealIron` -- ``mu -> inf`` (``H = 0``), for closed-form limit checks.

Built-in records are looked up with :func:`get_material`; names are compared
case- and punctuation-insensitively (``"AISI 1008" == "aisi_1008"``).
"""

from __future__ import annotations

import math
import re
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from scipy import integrate
from scipy.interpolate import PchipInterpolator

from .errors import MaterialError

MU0: float = 4e-7 * math.pi
"""Permeability of free space [H/m] (the classical value; the 2019 SI value differs by 1e-10)."""

__all__ = [
    "MU0",
    "Material",
    "SoftMagneticMaterial",
    "TabulatedBH",
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
    resistivity: float | None

    @abstractmethod
    def field_strength(self, B: Any) -> Any:
        """Magnetic field strength H [A/m] for flux density B [T] (NumPy or CasADi)."""

    def relative_permeability(self, B: Any) -> Any:
        """Relative permeability ``B / (mu0 H)`` (NumPy input only; ``mu_r(0)`` at B = 0)."""
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
            return IdealIron(name=self.name, resistivity=self.resistivity)
        return ConstantPermeability(mu_r=mu, name=f"{self.name} (linear)", resistivity=self.resistivity)

    def energy_density(self, B: Any) -> np.ndarray:
        """Stored magnetic energy density ``w(B) = integral_0^B H dB`` [J/m^3] (NumPy)."""
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


@dataclass(frozen=True)
class SoftMagneticMaterial(Material):
    """Roschke/Modelica approximation of a soft-magnetic B-H curve.

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
    resistivity : float or None
        Electrical resistivity [ohm m] for eddy-current estimates, if known.
    """

    mu_i: float
    B_mymax: float
    c_a: float
    c_b: float
    n: float
    name: str = "soft-magnetic"
    resistivity: float | None = None

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
        if self.resistivity is not None and not self.resistivity > 0.0:
            raise MaterialError(f"material {self.name!r}: resistivity must be > 0 ohm m")
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

    def field_strength(self, B: Any) -> Any:
        if not _is_symbolic(B):
            B = np.asarray(B, dtype=float)
        return B / (MU0 * self._mu_r(B))

    @property
    def initial_relative_permeability(self) -> float:
        return float(self.mu_i)


@dataclass(frozen=True)
class ConstantPermeability(Material):
    """Linear material ``H = B / (mu0 mu_r)``.

    Parameters
    ----------
    mu_r : float
        Relative permeability [-], >= 1.
    """

    mu_r: float
    name: str = "linear"
    resistivity: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mu_r) and self.mu_r >= 1.0):
            raise MaterialError(
                f"material {self.name!r}: mu_r = {self.mu_r} must be finite and >= 1 "
                "(use IdealIron for mu -> inf)"
            )

    def field_strength(self, B: Any) -> Any:
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
        b = np.asarray(B, dtype=float)
        return b * b / (2.0 * MU0 * self.mu_r)


@dataclass(frozen=True)
class IdealIron(Material):
    """Infinitely permeable iron (``H = 0``): the reluctance of the part vanishes."""

    name: str = "ideal"
    resistivity: float | None = None

    def field_strength(self, B: Any) -> Any:
        return 0.0 * B if _is_symbolic(B) else np.zeros_like(np.asarray(B, dtype=float))

    @property
    def initial_relative_permeability(self) -> float:
        return math.inf

    @property
    def saturates(self) -> bool:
        return False

    def energy_density(self, B: Any) -> np.ndarray:
        return np.zeros_like(np.asarray(B, dtype=float))


@dataclass(frozen=True)
class TabulatedBH(Material):
    """Material from measured (H, B) pairs of the first-magnetisation curve.

    H(B) is interpolated with a monotone piecewise cubic (PCHIP, Fritsch-Carlson)
    through the points and continued above the last point with slope ``mu0``
    (``H = H_n + (B - B_n)/mu0``); the curve is odd in B.

    Parameters
    ----------
    H : sequence of float
        Field strength [A/m], starting at 0, strictly increasing.
    B : sequence of float
        Flux density [T], starting at 0, strictly increasing, ``dB/dH >= mu0``
        between points and ``mu_r(0) = B_1 / (mu0 H_1) >= 1``.
    """

    H: tuple[float, ...]
    B: tuple[float, ...]
    name: str = "tabulated"
    resistivity: float | None = None
    _pp: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            h = np.asarray(self.H, dtype=float)
            b = np.asarray(self.B, dtype=float)
        except (TypeError, ValueError) as exc:
            raise MaterialError(f"material {self.name!r}: H and B must be lists of numbers") from exc
        if h.ndim != 1 or b.ndim != 1:
            raise MaterialError(f"material {self.name!r}: H and B must be flat lists of numbers, "
                                f"got arrays of shape {h.shape} and {b.shape}")
        object.__setattr__(self, "H", tuple(float(v) for v in h))
        object.__setattr__(self, "B", tuple(float(v) for v in b))
        who = f"B-H table {self.name!r}"
        if h.size != b.size:
            raise MaterialError(f"{who}: H has {h.size} values but B has {b.size}; they must pair up")
        if h.size < 3:
            raise MaterialError(f"{who}: needs at least 3 points including the origin, got {h.size}")
        if not (np.all(np.isfinite(h)) and np.all(np.isfinite(b))):
            raise MaterialError(f"{who}: values must be finite numbers")
        if h[0] != 0.0 or b[0] != 0.0:
            raise MaterialError(f"{who}: the curve must start at the origin (H[0] = B[0] = 0), "
                                f"got H[0] = {h[0]}, B[0] = {b[0]}")
        if np.any(np.diff(h) <= 0.0) or np.any(np.diff(b) <= 0.0):
            raise MaterialError(f"{who}: H and B must both be strictly increasing "
                                "(a first-magnetisation curve is monotone)")
        slopes = np.diff(b) / np.diff(h)
        if slopes[0] < MU0:
            raise MaterialError(f"{who}: mu_r(0) = {slopes[0] / MU0:.4g} < 1; the first point "
                                "must satisfy B_1 >= mu0 H_1")
        # Allow 0.1 % below mu0 for rounding in published tables.
        bad = np.nonzero(slopes < MU0 * (1.0 - 1e-3))[0]
        if bad.size:
            i = int(bad[0])
            raise MaterialError(
                f"{who}: between points {i} and {i + 1} dB/dH = {slopes[i]:.4g} H/m is below mu0; "
                "physical curves have dB/dH >= mu0"
            )
        if self.resistivity is not None and not self.resistivity > 0.0:
            raise MaterialError(f"{who}: resistivity must be > 0 ohm m")
        pp = PchipInterpolator(b, h, extrapolate=False)
        # The interpolant, not only the chords, must keep dB/dH >= mu0 (mu_r >= 1): a cubic
        # segment's slope can exceed its end slopes.  Checked on a dense sampling of every
        # segment (the slope is a quadratic per segment; 65 samples resolve its maximum to
        # well below the 0.1 % allowance).
        bs = np.concatenate([np.linspace(b[i], b[i + 1], 65) for i in range(b.size - 1)])
        dh_db = pp.derivative()(bs)
        worst = int(np.argmax(dh_db))
        if dh_db[worst] * MU0 > 1.0 + 1e-3:
            raise MaterialError(
                f"{who}: the monotone interpolation through the points has mu_r = "
                f"{1.0 / (MU0 * dh_db[worst]):.4g} < 1 at B = {bs[worst]:.4g} T (dB/dH below mu0); "
                "add points where the curve bends, or check the units (H in A/m, B in T)"
            )
        object.__setattr__(self, "_pp", pp)

    @property
    def initial_relative_permeability(self) -> float:
        # Slope of the PCHIP interpolant at the origin.
        dh_db = float(self._pp.derivative()(0.0))
        return 1.0 / (MU0 * dh_db)

    def _segments(self) -> tuple[np.ndarray, np.ndarray]:
        """Break points and local polynomial coefficients (highest power first)."""
        return np.asarray(self._pp.x), np.asarray(self._pp.c)

    def field_strength(self, B: Any) -> Any:
        x, c = self._segments()
        b_end, h_end = x[-1], float(self.H[-1])
        if _is_symbolic(B):
            bb = ca.fabs(B)
            # Tail above the table, continued with slope mu0.
            mag = h_end + (bb - b_end) / MU0
            for i in range(x.size - 2, 0, -1):
                d = bb - x[i]
                poly = ((c[0, i] * d + c[1, i]) * d + c[2, i]) * d + c[3, i]
                mag = ca.if_else(bb < x[i + 1], poly, mag)
            tail = ca.sign(B) * mag
            # First segment written as B * q(|B|) so that dH/dB is exact at B = 0.
            first = B * ((c[0, 0] * bb + c[1, 0]) * bb + c[2, 0])
            return ca.if_else(bb < x[1], first, tail)
        b = np.asarray(B, dtype=float)
        bb = np.abs(b)
        inside = bb <= b_end
        mag = np.where(inside, self._pp(np.where(inside, bb, 0.0)), h_end + (bb - b_end) / MU0)
        return np.sign(b) * mag

    def energy_density(self, B: Any) -> np.ndarray:
        b = np.abs(np.asarray(B, dtype=float))
        anti = self._pp.antiderivative()
        b_end, h_end = float(self._pp.x[-1]), float(self.H[-1])
        inside = b <= b_end
        w_in = anti(np.where(inside, b, 0.0))
        w_end = float(anti(b_end))
        d = b - b_end
        w_out = w_end + h_end * d + d * d / (2.0 * MU0)
        return np.where(inside, w_in, w_out)


# --------------------------------------------------------------------------- records
# Modelica Standard Library, Magnetic.FluxTubes.Material.SoftMagnetic (Roschke fits).
# Resistivities: pure iron 0.098e-6 ohm m [P]; solid structural/free-cutting steels
# 1.5e-7 ohm m [E] (typically 1e-7 to 2e-7; docs/sources.md sec. 4); none given for electrical sheet grades.
_ROSCHKE: dict[str, tuple[float, float, float, float, float, float | None]] = {
    # name: (mu_i, B_mymax, c_a, c_b, n, resistivity)
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
    """Case- and punctuation-insensitive key: ``"AISI 1008" -> "aisi1008"``."""
    return re.sub(r"[^0-9a-z]", "", name.lower())


_REGISTRY: dict[str, SoftMagneticMaterial] = {
    normalise_name(k): SoftMagneticMaterial(*v[:5], name=k, resistivity=v[5])
    for k, v in _ROSCHKE.items()
}


def material_names() -> list[str]:
    """Names of the built-in material records."""
    return sorted(_ROSCHKE)


def get_material(name: str | Material) -> Material:
    """Look up a built-in material by name (case/punctuation-insensitive).

    ``"ideal"`` gives :class:`IdealIron`.  A :class:`Material` is returned unchanged.

    Raises
    ------
    MaterialError
        If the name is unknown; the message lists the known names.
    """
    if isinstance(name, Material):
        return name
    if not isinstance(name, str):
        raise MaterialError(f"material must be a name or a Material, got {type(name).__name__}")
    key = normalise_name(name)
    if key == "ideal":
        return IdealIron()
    try:
        return _REGISTRY[key]
    except KeyError:
        raise MaterialError(
            f"unknown material {name!r}; built-in records are: {', '.join(material_names())}, "
            "or 'ideal' (or define a tabulated curve)"
        ) from None
