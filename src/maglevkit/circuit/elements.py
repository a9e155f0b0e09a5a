"""Elements of the equivalent magnetic circuit (EMC).

Each element is a small frozen dataclass: the leaf class holds the geometry, the
base class owns the law the element contributes to its branch.

* :class:`IronPath` -- saturable iron, ``V_m = l H(phi / A)`` (paper eq. 1 with mu(phi)).
* :class:`AirGap` -- pole air gap with optional fringing and Carter factor,
  ``V_m = phi / G(s)``.
* :class:`LeakagePermeance` -- constant leakage permeance (Roters shapes as constructors).
* :class:`GapLeakage` -- gap-dependent leakage/fringe permeance ``mu0 w/pi ln(1 + pi r/s)``.
* :class:`FringePermeance` -- fringing from a pole flank to a flat rail on its own branch,
  ``2 mu0 w/pi ln(1 + pi r/(2 s))`` (Roters) or the conformal map of a pole edge over a
  plane, ``mu0 w/pi ln(1 + v^2)``.
* :class:`EdgeCornerPermeance` -- the face's corner flux of pole edges with the coil beside the flank
  and a window's centre plane, 0.195 mu0 w per edge for a free flank, growing with the gap.
* :class:`GapLayerPermeance` -- air along a cell layer filling the gap, ``mu0 w s/l``.
* :class:`EddyCurrent` -- the paper's "magnetic inductance", ``V_m = G_ec dphi/dt``.

Sign convention: a branch flux ``phi`` flows from the branch's start node to its end
node; an element's magnetic voltage drop ``V_m`` is measured in the same direction.
All quantities are SI: lengths in m, areas in m^2, flux in Wb, MMF in A (ampere-turns).
The fields and the factories' arguments carry their unit in the name (``length_m``,
``pole_area_m2``, ``value_H``, ``conductance_S``); the old names (``length``, ``pole_area``,
``value``, ``conductance``, ...) are deprecated aliases for one release, as keywords and
as attributes (``tools/rename_element_fields.py`` migrates callers).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ..errors import InputError, ParameterError
from ..materials import MU0, Material, get_material
from ..validation import real_array, renamed_keywords

__all__ = [
    "symbolic",
    "Element",
    "LinearElement",
    "IronPath",
    "AirGap",
    "LeakagePermeance",
    "GapLeakage",
    "FringePermeance",
    "GapLayerPermeance",
    "EddyCurrent",
    "carter_coefficient",
    "carter_slot_loss",
    "edge_flank_per_mu0",
    "edge_corner_per_mu0",
    "EdgeCornerPermeance",
    "rectangle_torsion_constant",
]


def symbolic(value: Any) -> bool:
    """Whether ``value`` is a CasADi symbolic expression (``SX`` or ``MX``).

    Element geometry may be symbolic when a builder is evaluated with CasADi symbols (the
    design optimisation's exact geometry derivatives, :mod:`maglevkit.design`); the range
    checks then apply to the numbers the symbols later take (the optimiser's bounds and
    constraints), not here.

    Parameters
    ----------
    value : object
        Any value (a geometry number [m, m^2, H] or a CasADi expression).

    Returns
    -------
    bool
    """
    return isinstance(value, (ca.SX, ca.MX))


def _positive(owner: str, **values: float) -> None:
    for key, v in values.items():
        if symbolic(v):
            continue
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            raise ParameterError(f"{owner}: {key} must be a number, got {v!r}")
        if not (math.isfinite(v) and v > 0.0):
            raise ParameterError(f"{owner}: {key} = {v!r} must be a finite number > 0")


def _nonnegative(owner: str, **values: float) -> None:
    for key, v in values.items():
        if symbolic(v):
            continue
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            raise ParameterError(f"{owner}: {key} must be a number, got {v!r}")
        if not (math.isfinite(v) and v >= 0.0):
            raise ParameterError(f"{owner}: {key} = {v!r} must be a finite number >= 0")


def _log(x: Any) -> Any:
    return ca.log(x) if isinstance(x, (ca.SX, ca.MX, ca.DM)) else np.log(x)


def _atan(x: Any) -> Any:
    return ca.atan(x) if isinstance(x, (ca.SX, ca.MX, ca.DM)) else np.arctan(x)


_EDGE_NEWTON_STEPS = 4


def edge_flank_parameter(r: Any, s: Any) -> Any:
    """The conformal map's parameter ``v`` of the flank point at height ``r`` above the face
    of a right-angled pole edge at distance ``s`` from a plane: ``v - atan(v) = pi r/(2 s)``.

    Solved by 4 Newton steps from ``min(q + pi/2, w (1 + w^2/4))``, ``q = pi r/(2 s)``, ``w =
    (3 q)^(1/3)`` (the root's bound for large ``q`` and its series ``v^3/3 - v^5/5 = q`` for
    small ``q``): relative error below 1e-11 for every ``q`` from 1e-8 to 1e6 (3 steps
    already reach 1e-11; the floor is the round-off of ``v - atan v`` at small ``v``).
    NumPy or CasADi input (a fixed expression, so it differentiates exactly).

    Parameters
    ----------
    r : float, array_like or CasADi
        Flank height above the face [m], >= 0.
    s : float, array_like or CasADi
        Distance from the face to the plane [m], > 0.

    Returns
    -------
    float, ndarray or CasADi
        ``v`` [-] (0 at the edge, ``~ pi (r + s)/(2 s)`` far up the flank).
    """
    q = math.pi * r / (2.0 * s)
    w = (3.0 * q) ** (1.0 / 3.0)
    small = w * (1.0 + 0.25 * w * w)
    large = q + 0.5 * math.pi
    # (kept off 0 so that r = 0 gives v ~ 1e-100 and a zero permeance, not 0/0)
    if isinstance(q, (ca.SX, ca.MX, ca.DM)):
        v = ca.fmax(ca.fmin(large, small), 1e-100)
    else:
        v = np.maximum(np.minimum(large, small), 1e-100)
    for _ in range(_EDGE_NEWTON_STEPS):
        v = v - (v - _atan(v) - q) * (1.0 + v * v) / (v * v)
    return v


def edge_flank_per_mu0(w: Any, r: Any, s: Any) -> Any:
    """Permeance divided by mu0 [m] of the flank ``[0, r]`` of a right-angled pole edge of
    length ``w`` at distance ``s`` from a plane (2-D conformal map, flank and face at one
    potential, the plane at another): ``(w/pi) ln(1 + v^2)``, ``v`` from
    :func:`edge_flank_parameter`.

    Roters' quarter circles give ``(2 w/pi) ln(1 + pi r/(2 s))``: the same for ``r >> s``
    to ``O(s/r)``; nearer the edge they carry less flux and fall faster with the gap
    (at ``r = 0.75 s``: 0.496 against 0.596 ``w``, ``s dG/ds`` -0.344 against -0.320
    ``w``; docs/equations.md sec. 1).  NumPy or CasADi input.

    Parameters
    ----------
    w : float or CasADi
        Edge length [m].
    r : float, array_like or CasADi
        Flank height above the face [m], >= 0.
    s : float, array_like or CasADi
        Distance from the face to the plane [m], > 0 (Carter's ``k_C s`` over a slotted
        stator).

    Returns
    -------
    float, ndarray or CasADi
        The permeance divided by mu0 [m].
    """
    v = edge_flank_parameter(r, s)
    return w / math.pi * _log(1.0 + v * v)


_CORNER_NEWTON_STEPS = 8
_CORNER_NODES, _CORNER_WEIGHTS = np.polynomial.legendre.leggauss(20)


def _numlib(*x: Any) -> Any:
    return ca if any(isinstance(v, (ca.SX, ca.MX, ca.DM)) for v in x) else np


def _free_edge(a: Any) -> bool:
    return a is None or (not symbolic(a) and math.isinf(a))


def edge_window_height(v: Any, s: Any, a: Any = None) -> Any:
    """Flank height [m] above the face of the point with map parameter ``v`` of a
    right-angled pole edge at distance ``s`` from a plane, with a second plane (at the
    plane's potential) parallel to the flank at distance ``a`` (the window's centre plane;
    ``None`` or ``inf``: none, :func:`edge_flank_parameter`'s ``(2s/pi)(v - atan v)``).

    The air between face, plane, centre plane and flank is the image of the upper half
    ``t``-plane under ``dz/dt = (a/pi) sqrt((t + 1)/(alpha - t))/t``, ``alpha = (a/s)^2``
    (corner ``t = -1``, the flank ``t = -(1 + v^2)``, the plane's corner with the centre
    plane ``t = alpha``), so ``y = (2/pi)[a asinh(v s/sqrt(a^2 + s^2)) - s atan(v a/sqrt(a^2
    + s^2 + v^2 s^2))]`` (docs/equations.md sec. 1).  NumPy or CasADi input.
    """
    if _free_edge(a):
        return 2.0 * s / math.pi * (v - _atan(v))
    f = _numlib(v, s, a)
    q = a * a + s * s
    asinh = np.arcsinh if f is np else ca.asinh
    return 2.0 / math.pi * (a * asinh(v * s / f.sqrt(q))
                            - s * _atan(v * a / f.sqrt(q + v * v * s * s)))


def _edge_window_slope(v: Any, s: Any, a: Any) -> Any:
    """``d y/d v`` of :func:`edge_window_height` [m]."""
    if _free_edge(a):
        return 2.0 * s / math.pi * v * v / (1.0 + v * v)
    f = _numlib(v, s, a)
    return 2.0 * a * s / math.pi * v * v / ((1.0 + v * v) * f.sqrt(a * a + s * s + v * v * s * s))


def edge_window_parameter(y: Any, s: Any, a: Any = None) -> Any:
    """The map parameter ``v`` of the flank point at height ``y`` [m] above the face
    (inverse of :func:`edge_window_height`; without a centre plane
    :func:`edge_flank_parameter`).  8 Newton steps in ``ln v`` from the free edge's root
    (which lies below it; ``y(e^u)`` is convex and increasing in ``u``): relative error
    below 1e-14 for ``s`` from 0.1 to 200 mm, ``a`` from 5 mm to 1 m, ``y`` from ``0.01 s``
    to ``15 a``.  NumPy or CasADi input.
    """
    v = edge_flank_parameter(y, s)
    if _free_edge(a):
        return v
    f = _numlib(y, s, a)
    for _ in range(_CORNER_NEWTON_STEPS):
        v = v * f.exp(-(edge_window_height(v, s, a) - y) / (v * _edge_window_slope(v, s, a)))
    return v


def edge_corner_per_mu0(w: Any, s: Any, r: Any, h: Any, a: Any = None) -> Any:
    """The face's corner flux of a right-angled pole edge over a plane, divided by ``mu0
    V`` [m]: what the face carries beyond the uniform field ``V w X/s`` (``X`` the face's
    width), for a flank at the pole's potential ``V`` from the face to the coil's lower
    end ``r`` above it, the coil's MMF falling linearly to 0 along its height ``h``, and
    the flank at 0 above (the yoke's side of the coil); ``a``: a centre plane at 0 at
    that distance from the flank (the window's, by antisymmetry; ``None``: none).

    ``w [c_0(s, a) + d(s, a, r, h)]`` with the flank and face at one potential
    ``c_0 = (2/pi)[(a/s) atan(s/a) - ln 2 + ln(1 + s^2/a^2)/2]`` (``(2 - 2 ln 2)/pi =
    0.195`` without a centre plane, :func:`edge_flank_per_mu0`'s map) and the coil's share
    ``d = (1/(pi h)) int_r^{r+h} ln(1 + 1/v(y)^2) dy`` (the flank's potential deficit
    against the Poisson kernel of the mapped half-plane; ``v`` from
    :func:`edge_window_parameter`), by 20-point Gauss-Legendre in ``ln v`` (absolute error
    below 1e-6 for ``r`` from 0.1 mm, ``s`` 0.5-100 mm; docs/equations.md sec. 1).  It
    grows with the gap as the coil and the centre plane come nearer in units of ``s``.
    NumPy (scalar or array ``s``) or CasADi input.

    Parameters
    ----------
    w : float
        Edge length [m].
    s : float, array_like or CasADi
        Distance from the face to the plane [m], > 0.
    r : float
        Flank height of the coil's lower end above the face [m], > 0.
    h : float
        Coil height [m], > 0.
    a : float, optional
        Distance of the centre plane from the flank [m], > 0 (``None`` or ``inf``: none).

    Returns
    -------
    float, ndarray or CasADi
        The permeance divided by mu0 [m].
    """
    f = _numlib(s, r, h, a)
    if _free_edge(a):
        c0: Any = (2.0 - 2.0 * math.log(2.0)) / math.pi
    else:
        c0 = 2.0 / math.pi * (a / s * _atan(s / a) - math.log(2.0)
                              + 0.5 * _log(1.0 + s * s / (a * a)))
    lo_y, hi_y = r, r + h
    if not _free_edge(a):
        # above 15 a the deficit's weight ln(1 + 1/v^2) ~ exp(-pi y/a) is below 1e-20 (and
        # v overflows): the integral ends there
        lo_y, hi_y = f.fmin(lo_y, 15.0 * a), f.fmin(hi_y, 15.0 * a)
    lo = _log(edge_window_parameter(lo_y, s, a))
    hi = _log(edge_window_parameter(hi_y, s, a))
    mid, half = 0.5 * (hi + lo), 0.5 * (hi - lo)
    total: Any = 0.0
    for x, wt in zip(_CORNER_NODES, _CORNER_WEIGHTS, strict=True):
        v = f.exp(mid + half * float(x))
        total = total + float(wt) * _log(1.0 + 1.0 / (v * v)) * _edge_window_slope(v, s, a) * v
    return w * (c0 + half * total / (math.pi * h))


@renamed_keywords(gap="gap_m", slot_pitch="slot_pitch_m", slot_opening="slot_opening_m")
def carter_coefficient(gap_m: Any, slot_pitch_m: float, slot_opening_m: float) -> Any:
    """Carter's coefficient ``k_C = tau / (tau - gamma s)`` of a slotted surface.

    ``gamma = (4/pi) [x atan(x) - ln sqrt(1 + x^2)]`` with ``x = b / (2 s)``
    (slot pitch ``tau``, slot opening ``b``, gap ``s``; all in m).  Works on NumPy and
    CasADi inputs.

    Parameters
    ----------
    gap_m : float, array_like or CasADi
        Air gap s [m], > 0 (numeric gaps are checked; CasADi expressions are not).
    slot_pitch_m : float
        Slot pitch tau [m], > 0.
    slot_opening_m : float
        Slot opening b [m], ``0 <= b < tau``.

    Returns
    -------
    float, ndarray or CasADi
        ``k_C`` [-] (>= 1), the shape of ``gap_m``.

    Raises
    ------
    ParameterError
        ``slot_pitch_m`` not a number > 0, ``slot_opening_m`` not in ``[0, slot_pitch_m)``.
    InputError
        A numeric ``gap_m`` that is not real numbers > 0 (bools and strings included).
    """
    _positive("carter_coefficient", slot_pitch_m=slot_pitch_m)
    _nonnegative("carter_coefficient", slot_opening_m=slot_opening_m)
    if slot_opening_m >= slot_pitch_m:
        raise ParameterError(f"carter_coefficient: slot_opening_m = {slot_opening_m!r} m must be "
                             f"smaller than slot_pitch_m = {slot_pitch_m!r} m")
    if not isinstance(gap_m, (ca.SX, ca.MX, ca.DM)):
        gap_m = real_array(gap_m, "gap_m", "m")
        if np.any(gap_m <= 0.0):
            raise InputError(f"carter_coefficient: gap_m = {gap_m.tolist()!r} m must be > 0")
    return slot_pitch_m / (slot_pitch_m - carter_slot_loss(gap_m, slot_opening_m))


def carter_slot_loss(gap: Any, slot_opening: float) -> Any:
    """Face width [m] that one slot of opening ``b`` removes from a pole face at gap ``s``.

    ``gamma s`` with ``gamma = (4/pi) [x atan(x) - ln sqrt(1 + x^2)]``, ``x = b / (2 s)``
    (Carter): the flux through a face of width ``l`` with slots is that of a smooth face
    of width ``l - gamma s`` per slot.  Exact for slots deeper than about half their
    opening; ``0 < gamma s < b``.  Works on NumPy and CasADi inputs (no checks here).
    """
    x = slot_opening / (2.0 * gap)
    gamma = (4.0 / math.pi) * (x * _atan(x) - 0.5 * _log(1.0 + x * x))
    return gamma * gap


@dataclass(frozen=True)
class Element(ABC):
    """Base of all EMC elements: one law on one branch.

    Attributes
    ----------
    name : str
        Unique name within the network.
    """

    name: str

    #: name of the gap input this element depends on (None: gap-independent)
    @property
    def gap(self) -> str | None:
        return None

    @property
    def area(self) -> float | None:
        """Cross-section [m^2] used to report a flux density, if meaningful."""
        return None

    @property
    def eddy_conductance(self) -> float:
        """``G_ec`` [S] of the ``V_m = G_ec dphi/dt`` law (0 for static elements)."""
        return 0.0

    @abstractmethod
    def mmf_drop(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Static magnetic voltage drop ``V_m`` [A] for branch flux ``flux_Wb`` [Wb].

        Parameters
        ----------
        flux_Wb : float, array_like or CasADi
            Branch flux phi [Wb], in the branch's direction.
        gap_m : float, array_like or CasADi, optional
            Value of the element's gap input [m] (ignored by gap-independent elements).

        Returns
        -------
        float, ndarray or CasADi
            ``V_m`` [A] (ampere-turns), the shape of ``flux_Wb``.
        """

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def energy(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Stored energy ``integral_0^phi V_m dphi`` [J] (NumPy input).

        Parameters
        ----------
        flux_Wb : float or array_like
            Branch flux phi [Wb].
        gap_m : float or array_like, optional
            Value of the element's gap input [m] (gap-dependent elements only).

        Returns
        -------
        float or ndarray
            Energy [J].

        Raises
        ------
        NotImplementedError
            For elements without a stored-energy law (the base class).
        """
        raise NotImplementedError(f"{type(self).__name__} has no stored energy law")


@dataclass(frozen=True)
class LinearElement(Element):
    """An element with a flux-independent permeance ``G`` [H]: ``V_m = phi / G``.

    The stored energy is ``phi^2 / (2 G)``.  Gap-dependent elements must be linear,
    so that the pole force is exactly ``dW/ds`` at constant flux.

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    """

    @abstractmethod
    def permeance(self, gap_m: Any = None) -> Any:
        """Permeance ``G`` [H] (= Wb/A); ``gap_m`` [m] for gap-dependent elements.

        Parameters
        ----------
        gap_m : float, array_like or CasADi, optional
            Value of the element's gap input [m]; required by gap-dependent elements
            (``ParameterError`` when missing), ignored by the others.

        Returns
        -------
        float, ndarray or CasADi
            ``G`` [H].
        """

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def mmf_drop(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """``V_m = phi / G`` [A].

        Parameters
        ----------
        flux_Wb : float, array_like or CasADi
            Branch flux phi [Wb].
        gap_m : float, array_like or CasADi, optional
            Value of the element's gap input [m] (required by gap-dependent elements).

        Returns
        -------
        float, ndarray or CasADi
            ``V_m`` [A].
        """
        return flux_Wb / self.permeance(gap_m)

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def energy(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Stored energy ``phi^2 / (2 G)`` [J] (NumPy or CasADi input).

        Parameters
        ----------
        flux_Wb : float, array_like or CasADi
            Branch flux phi [Wb].
        gap_m : float, array_like or CasADi, optional
            Value of the element's gap input [m] (required by gap-dependent elements).

        Returns
        -------
        float, ndarray or CasADi
            Energy [J].
        """
        return flux_Wb * flux_Wb / (2.0 * self.permeance(gap_m))


class _GapElement(LinearElement):
    """A linear element whose permeance depends on one gap input: the boilerplate of
    :class:`AirGap`, :class:`GapLeakage`, :class:`FringePermeance`,
    :class:`EdgeCornerPermeance` and :class:`GapLayerPermeance` in one place.

    Not a dataclass and without fields of its own: each subclass keeps its ``gap_input``
    field where it was, so the elements' fields, reprs and thus the networks' hashes
    (:func:`~maglevkit.reduction.maps.network_hash`) are those of the classes before.
    """

    #: The element's name in messages ("air gap", "gap leakage", ...).
    _label: ClassVar[str] = "gap element"
    gap_input: str

    @property
    def gap(self) -> str:
        return self.gap_input

    @property
    def _owner(self) -> str:
        """The element in messages: its ``_label`` and name."""
        return f"{self._label} {self.name!r}"

    def _check_gap_input(self) -> None:
        """Refuse an empty or non-string ``gap_input`` (``ParameterError``)."""
        if not isinstance(self.gap_input, str) or not self.gap_input:
            raise ParameterError(f"{self._owner}: gap_input must be a non-empty name")

    @renamed_keywords(gap="gap_m")
    def permeance(self, gap_m: Any = None) -> Any:
        """Permeance ``G(s)`` [H] at the gap ``gap_m``: the law of the class docstring.

        Parameters
        ----------
        gap_m : float, array_like or CasADi
            Air gap s [m], > 0 (checked only where a law needs it, e.g. Carter's
            coefficient); required (``ParameterError`` when None).

        Returns
        -------
        float, ndarray or CasADi
            ``G`` [H].
        """
        if gap_m is None:
            raise ParameterError(f"{self._owner}: needs a gap value")
        return self._permeance(gap_m)

    @abstractmethod
    def _permeance(self, gap_m: Any) -> Any:
        """The law ``G(s)`` [H] at a given gap ``gap_m`` [m] (NumPy or CasADi)."""


@renamed_keywords(length="length_m", cross_section="cross_section_m2")
@dataclass(frozen=True)
class IronPath(Element):
    """A homogeneous iron part: ``V_m = l H(phi/A)`` (paper eq. 1 with mu = mu(phi)).

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    length_m : float
        Mean flux path length [m], > 0 (deprecated keyword: ``length``).
    cross_section_m2 : float
        Cross-section area [m^2], > 0 (deprecated keyword: ``cross_section``).
    material : Material or str
        Constitutive law, or the name of a built-in record (default ``"ideal"``:
        infinitely permeable iron).

    Raises
    ------
    ParameterError
        ``length_m`` or ``cross_section_m2`` not a finite number > 0; an unknown material.
    """

    length_m: float
    cross_section_m2: float
    material: Material = field(default_factory=lambda: get_material("ideal"))

    def __post_init__(self) -> None:
        _positive(f"iron path {self.name!r}", length_m=self.length_m,
                  cross_section_m2=self.cross_section_m2)
        object.__setattr__(self, "material", get_material(self.material))

    @property
    def area(self) -> float:
        return self.cross_section_m2

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def mmf_drop(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """``V_m = l H(phi / A)`` [A].

        Parameters
        ----------
        flux_Wb : float, array_like or CasADi
            Branch flux phi [Wb].
        gap_m : optional
            Ignored (an iron path does not depend on a gap).

        Returns
        -------
        float, ndarray or CasADi
            ``V_m`` [A].
        """
        return self.length_m * self.material.field_strength(flux_Wb / self.cross_section_m2)

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def energy(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Stored energy ``l A w(phi / A)`` [J], with the material's energy density ``w(B)``.

        Parameters
        ----------
        flux_Wb : float or array_like
            Branch flux phi [Wb].
        gap_m : optional
            Ignored.

        Returns
        -------
        float or ndarray
            Energy [J].
        """
        b = np.asarray(flux_Wb, dtype=float) / self.cross_section_m2
        return self.length_m * self.cross_section_m2 * self.material.energy_density(b)


@renamed_keywords(pole_area="pole_area_m2", slot_pitch="slot_pitch_m", slot_opening="slot_opening_m")
@dataclass(frozen=True)
class AirGap(_GapElement):
    """Air gap between a pole face and the rail/stator.

    ``G(s) = mu0 [A / s' + sum_e (2 w_e / pi) ln(1 + pi r_e / (2 s')) + sum_j A_j / (s' + d_j)]``
    with ``s' = k_C s``.

    The first term is the homogeneous field under the pole face, the first sum the
    fringing flux from the pole flanks to the flat rail (Roters' quarter-circle-and-
    straight-line tubes: the line leaving the flank at height ``x`` has length
    ``s' + pi x / 2``, so ``dG = mu0 w dx / (s' + pi x / 2)``; one term per edge of length
    ``w_e`` whose flank of height ``r_e`` sees the rail).  This is the image of the
    pole-to-pole tube :class:`GapLeakage` at distance ``2 s'``, doubled.  The second sum
    is the flux from recessed parts of the pole face (e.g. the grooves of a
    linear-generator winding) of area ``A_j`` and depth ``d_j``, which cross the groove
    and then the gap in series.  ``k_C`` is Carter's coefficient of a slotted stator
    (1 when ``slot_pitch_m`` is 0).  Slots in the pole face itself (``face_slots``, narrow
    grooves deeper than half their opening, whose flux enters through the side walls)
    are counted by Carter's slot loss instead: ``A`` is then the whole face and each
    slot of length ``w_k`` and opening ``b_k`` subtracts ``w_k gamma(b_k/(2s)) s / s'``
    (:func:`carter_slot_loss` at the true gap, so that with a slotted stator the two
    slottings multiply as the product of their Carter factors).

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    gap_input : str
        Name of the gap input (one per pole), non-empty.
    pole_area_m2 : float
        Pole face area [m^2], > 0 (deprecated keyword: ``pole_area``).
    fringe_edges : tuple of (float, float)
        ``(edge length w_e [m], flank height r_e [m])`` per fringing edge, each > 0
        (empty: none).
    slot_pitch_m, slot_opening_m : float
        Stator slot pitch and slot opening [m] for Carter's coefficient (0: smooth);
        with a pitch > 0 the opening must lie in ``(0, slot_pitch_m)`` (deprecated
        keywords: ``slot_pitch``, ``slot_opening``).
    recesses : tuple of (float, float)
        ``(area A_j [m^2], depth d_j [m])`` of recessed pole-face parts, each > 0
        (empty: none).
    face_slots : tuple of (float, float)
        ``(slot length w_k [m], opening b_k [m])`` of slots in the pole face counted by
        Carter's slot loss (their area is part of ``pole_area_m2``; empty: none).

    Raises
    ------
    ParameterError
        An empty ``gap_input`` or any of the above out of range.
    """

    _label: ClassVar[str] = "air gap"
    gap_input: str = "s"
    pole_area_m2: float = 1.0
    fringe_edges: tuple[tuple[float, float], ...] = ()
    slot_pitch_m: float = 0.0
    slot_opening_m: float = 0.0
    recesses: tuple[tuple[float, float], ...] = ()
    face_slots: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        owner = self._owner
        self._check_gap_input()
        _positive(owner, pole_area_m2=self.pole_area_m2)
        edges = tuple((w if symbolic(w) else float(w), r if symbolic(r) else float(r))
                      for w, r in self.fringe_edges)
        object.__setattr__(self, "fringe_edges", edges)
        for w, r in edges:
            _positive(owner, fringe_edge_length=w, fringe_radius=r)
        recesses = tuple((a if symbolic(a) else float(a), float(d)) for a, d in self.recesses)
        object.__setattr__(self, "recesses", recesses)
        for a, d in recesses:
            _positive(owner, recess_area=a, recess_depth=d)
        slots = tuple((w if symbolic(w) else float(w), float(b)) for w, b in self.face_slots)
        object.__setattr__(self, "face_slots", slots)
        for w, b in slots:
            _positive(owner, face_slot_length=w, face_slot_opening=b)
        covered = sum(w * b for w, b in slots)
        if slots and not (symbolic(covered) or symbolic(self.pole_area_m2)) \
                and covered >= self.pole_area_m2:
            raise ParameterError(f"{owner}: the face slots (length x opening) cover the "
                                 "whole pole area; pole_area_m2 must include them")
        _nonnegative(owner, slot_pitch_m=self.slot_pitch_m, slot_opening_m=self.slot_opening_m)
        if self.slot_pitch_m > 0.0 and not 0.0 < self.slot_opening_m < self.slot_pitch_m:
            raise ParameterError(f"{owner}: slot_opening_m must lie in (0, slot_pitch_m) when a "
                                 "slot pitch is given")

    @property
    def area(self) -> float:
        return self.pole_area_m2

    @renamed_keywords(gap="gap_m")
    def effective_gap(self, gap_m: Any) -> Any:
        """Gap enlarged by Carter's coefficient [m].

        Parameters
        ----------
        gap_m : float, array_like or CasADi
            Mechanical air gap s [m], > 0 (checked only with a slot pitch, by
            :func:`carter_coefficient`).

        Returns
        -------
        float, ndarray or CasADi
            ``k_C s`` [m] (``s`` itself for a smooth stator).
        """
        if self.slot_pitch_m > 0.0:
            return carter_coefficient(gap_m, self.slot_pitch_m, self.slot_opening_m) * gap_m
        return gap_m

    @renamed_keywords(gap="gap_m")
    def fringe_permeance(self, gap_m: Any) -> Any:
        """The fringe edges' share of :meth:`permeance` [H]: ``mu0 sum fringe_per_mu0(w, r,
        k_C s)`` over ``fringe_edges`` (0 without).

        Parameters
        ----------
        gap_m : float, array_like or CasADi
            Mechanical air gap s [m], > 0.

        Returns
        -------
        float, ndarray or CasADi
            The fringe permeance [H].
        """
        return MU0 * self._add_fringe(0.0, self.effective_gap(gap_m))

    def _add_fringe(self, g: Any, s: Any) -> Any:
        """``g + sum fringe_per_mu0(w, r, s)`` over the fringe edges (``s`` effective)."""
        for w, r in self.fringe_edges:
            g = g + fringe_per_mu0(w, r, s)
        return g

    def _permeance(self, gap_m: Any) -> Any:
        """Permeance ``G(s)`` [H] of the gap (see the class docstring)."""
        s = self.effective_gap(gap_m)
        g = self._add_fringe(self.pole_area_m2 / s, s)
        for a, d in self.recesses:
            g = g + a / (s + d)
        for w, b in self.face_slots:
            g = g - w * carter_slot_loss(gap_m, b) / s
        return MU0 * g


@renamed_keywords(value="value_H")
@dataclass(frozen=True)
class LeakagePermeance(LinearElement):
    """A constant leakage permeance ``G`` [H] (flux that does not cross the air gap).

    Use the constructors for the standard Roters flux-tube shapes (their dimensions carry
    the unit in the name, ``length_m``, ``radius_m``, ...; the old names ``length=``,
    ``radius=``, ... are deprecated aliases for one release).

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    value_H : float
        Permeance G [H], > 0 (required, although it has a default for the dataclass;
        deprecated keyword: ``value``).

    Raises
    ------
    ParameterError
        ``value_H`` not a finite number > 0.
    """

    value_H: float = 0.0

    def __post_init__(self) -> None:
        _positive(f"leakage permeance {self.name!r}", value_H=self.value_H)

    @renamed_keywords(gap="gap_m")
    def permeance(self, gap_m: Any = None) -> Any:
        """The constant permeance ``G`` [H].

        Parameters
        ----------
        gap_m : optional
            Ignored (gap-independent).

        Returns
        -------
        float
            :attr:`value_H` [H].
        """
        return self.value_H

    @classmethod
    @renamed_keywords(area="area_m2", distance="distance_m")
    def parallel_plates(cls, name: str, area_m2: float, distance_m: float) -> LeakagePermeance:
        """Homogeneous field between two parallel faces: ``mu0 A / d``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        area_m2 : float
            Face area A [m^2], > 0.
        distance_m : float
            Distance d between the faces [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", area_m2=area_m2, distance_m=distance_m)
        return cls(name, MU0 * area_m2 / distance_m)

    @classmethod
    @renamed_keywords(length="length_m")
    def half_cylinder(cls, name: str, length_m: float) -> LeakagePermeance:
        """Half cylinder of axial length l: ``0.26 mu0 l``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        length_m : float
            Axial length l [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", length_m=length_m)
        return cls(name, 0.26 * MU0 * length_m)

    @classmethod
    @renamed_keywords(length="length_m")
    def quarter_cylinder(cls, name: str, length_m: float) -> LeakagePermeance:
        """Quarter cylinder of axial length l: ``0.52 mu0 l``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        length_m : float
            Axial length l [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", length_m=length_m)
        return cls(name, 0.52 * MU0 * length_m)

    @classmethod
    @renamed_keywords(length="length_m", inner_radius="inner_radius_m", thickness="thickness_m")
    def half_hollow_cylinder(cls, name: str, length_m: float, inner_radius_m: float,
                             thickness_m: float) -> LeakagePermeance:
        """Half hollow cylinder: ``mu0 l ln(1 + t/r_i) / pi``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        length_m : float
            Axial length l [m], > 0.
        inner_radius_m : float
            Inner radius r_i [m], > 0 (half the distance between the faces).
        thickness_m : float
            Shell thickness t [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", length_m=length_m, inner_radius_m=inner_radius_m,
                  thickness_m=thickness_m)
        ratio = 1.0 + thickness_m / inner_radius_m
        log = ca.log(ratio) if symbolic(ratio) else math.log(ratio)
        return cls(name, MU0 * length_m * log / math.pi)

    @classmethod
    @renamed_keywords(length="length_m", inner_radius="inner_radius_m", thickness="thickness_m")
    def quarter_hollow_cylinder(cls, name: str, length_m: float, inner_radius_m: float,
                                thickness_m: float) -> LeakagePermeance:
        """Quarter hollow cylinder: twice the half hollow cylinder.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        length_m : float
            Axial length l [m], > 0.
        inner_radius_m : float
            Inner radius r_i [m], > 0.
        thickness_m : float
            Shell thickness t [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        half = cls.half_hollow_cylinder(name, length_m, inner_radius_m, thickness_m)
        return cls(name, 2.0 * half.value_H)

    @classmethod
    @renamed_keywords(radius="radius_m")
    def quarter_sphere(cls, name: str, radius_m: float) -> LeakagePermeance:
        """Quarter sphere: ``0.077 mu0 2 r``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        radius_m : float
            Radius r [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", radius_m=radius_m)
        return cls(name, 0.077 * MU0 * 2.0 * radius_m)

    @classmethod
    @renamed_keywords(radius="radius_m")
    def eighth_sphere(cls, name: str, radius_m: float) -> LeakagePermeance:
        """Eighth sphere: ``0.308 mu0 r``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        radius_m : float
            Radius r [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", radius_m=radius_m)
        return cls(name, 0.308 * MU0 * radius_m)

    @classmethod
    @renamed_keywords(thickness="thickness_m")
    def quarter_hollow_sphere(cls, name: str, thickness_m: float) -> LeakagePermeance:
        """Quarter hollow sphere of shell thickness t: ``0.25 mu0 t``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        thickness_m : float
            Shell thickness t [m], > 0.

        Returns
        -------
        LeakagePermeance

        Raises
        ------
        ParameterError
            A dimension that is not a finite number > 0.
        """
        _positive(f"leakage {name!r}", thickness_m=thickness_m)
        return cls(name, 0.25 * MU0 * thickness_m)


@renamed_keywords(width="width_m", radius="radius_m")
@dataclass(frozen=True)
class GapLeakage(_GapElement):
    """Gap-dependent leakage around a pole: ``G = mu0 w / pi ln(1 + pi r / s)``.

    Modelica's ``LeakageAroundPoles``: half-circle-and-straight-line tubes between two
    facing poles at distance ``s`` (line length ``s + pi x``).  For a pole facing a flat
    rail use the fringe edges of :class:`AirGap` (quarter circles).

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    gap_input : str
        Name of the gap input.
    width_m : float
        Edge length w [m], > 0 (deprecated keyword: ``width``).
    radius_m : float
        Leakage radius r [m], > 0 (deprecated keyword: ``radius``).

    Raises
    ------
    ParameterError
        An empty ``gap_input``, or ``width_m`` or ``radius_m`` not a finite number > 0.
    """

    _label: ClassVar[str] = "gap leakage"
    gap_input: str = "s"
    width_m: float = 1.0
    radius_m: float = 1.0

    def __post_init__(self) -> None:
        self._check_gap_input()
        _positive(self._owner, width_m=self.width_m, radius_m=self.radius_m)

    def _permeance(self, gap_m: Any) -> Any:
        """Permeance ``G = mu0 w / pi ln(1 + pi r / s)`` [H]."""
        return MU0 * self.width_m / math.pi * _log(1.0 + math.pi * self.radius_m / gap_m)


@renamed_keywords(width="width_m", radius="radius_m", inner_radius="inner_radius_m",
                  slot_pitch="slot_pitch_m", slot_opening="slot_opening_m")
@dataclass(frozen=True)
class FringePermeance(_GapElement):
    """Fringing from a pole flank to a flat rail: ``G = (2 mu0 w/pi) ln(1 + pi r/(2 s))``.

    The fringe term of :class:`AirGap` (Roters' quarter circle from the flank at height
    ``x`` plus the straight line across the gap, length ``s + pi x/2``, integrated over
    ``x`` in ``[0, r]``) as an element of its own, so that a network can let the fringe
    flux leave the flank and land on the rail beside the pole instead of sharing the
    pole face's branch.

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    gap_input : str
        Name of the gap input, non-empty.
    width_m : float
        Edge length w [m], > 0 (deprecated keyword: ``width``).
    radius_m : float
        Flank height r [m] whose tubes reach the rail, > 0 (deprecated keyword:
        ``radius``).
    inner_radius_m : float
        Flank height [m] where the tubes start (0: at the pole face): a strip
        ``[inner_radius_m, radius_m]`` of the flank, ``(2 mu0 w/pi) ln((s + pi r/2) /
        (s + pi r_i/2))`` (deprecated keyword: ``inner_radius``).
    slot_pitch_m, slot_opening_m : float
        Stator slot pitch and opening [m]: the gap is then Carter's ``k_C s``, as in
        :class:`AirGap` (0: the true gap; deprecated keywords: ``slot_pitch``,
        ``slot_opening``).
    law : str
        ``"roters"`` (default): the quarter circles above.  ``"conformal"``: the field of a
        right-angled pole edge over a plane (:func:`edge_flank_per_mu0`), ``(mu0 w/pi)
        [ln(1 + v(r)^2) - ln(1 + v(r_i)^2)]``.

    Raises
    ------
    ParameterError
        An empty ``gap_input``, ``width_m`` or ``radius_m`` not a finite number > 0, or an
        unknown ``law``.
    """

    _label: ClassVar[str] = "fringe permeance"
    gap_input: str = "s"
    width_m: float = 1.0
    radius_m: float = 1.0
    inner_radius_m: float = 0.0
    slot_pitch_m: float = 0.0
    slot_opening_m: float = 0.0
    law: str = "roters"

    def __post_init__(self) -> None:
        owner = self._owner
        self._check_gap_input()
        _positive(owner, width_m=self.width_m, radius_m=self.radius_m)
        _nonnegative(owner, inner_radius_m=self.inner_radius_m, slot_pitch_m=self.slot_pitch_m,
                     slot_opening_m=self.slot_opening_m)
        if not (symbolic(self.inner_radius_m) or symbolic(self.radius_m)) \
                and self.inner_radius_m >= self.radius_m:
            raise ParameterError(f"{owner}: inner_radius_m = {self.inner_radius_m!r} m must be "
                                 f"smaller than radius_m = {self.radius_m!r} m")
        if self.slot_pitch_m > 0.0 and not 0.0 < self.slot_opening_m < self.slot_pitch_m:
            raise ParameterError(f"{owner}: slot_opening_m must lie in (0, slot_pitch_m) when a "
                                 "slot pitch is given")
        if self.law not in FRINGE_LAWS:
            raise ParameterError(f"{owner}: law = {self.law!r} is not one of "
                                 f"{', '.join(map(repr, FRINGE_LAWS))}")

    def _permeance(self, gap_m: Any) -> Any:
        """Permeance [H]: ``(2 mu0 w / pi) ln(1 + pi r / (2 s))`` (Roters) or the
        conformal map's strip (see the class docstring)."""
        if self.slot_pitch_m > 0.0:
            gap_m = carter_coefficient(gap_m, self.slot_pitch_m, self.slot_opening_m) * gap_m
        law = edge_flank_per_mu0 if self.law == "conformal" else fringe_per_mu0
        g = law(self.width_m, self.radius_m, gap_m)
        if symbolic(self.inner_radius_m) or self.inner_radius_m > 0.0:
            g = g - law(self.width_m, self.inner_radius_m, gap_m)
        return MU0 * g


FRINGE_LAWS = ("roters", "conformal")
"""The laws of :class:`FringePermeance`."""


@dataclass(frozen=True)
class EdgeCornerPermeance(_GapElement):
    """The face's corner flux of a pole's edges (gap-dependent): ``mu0 sum_k``
    :func:`edge_corner_per_mu0` ``(w, s, r, h, a_k)`` over its edges ``k``.

    What the face carries beyond the uniform field ``mu0 w X/s`` near its edges, with the
    coil's MMF falling along the flank from ``r`` up and, on a window's side, the window's
    centre plane at ``a_k`` (docs/equations.md sec. 1): 0.195 ``mu0 w`` per edge for a flank
    free to infinity, growing with the gap as coil and centre plane come nearer in units
    of ``s``.  In parallel with a face permeance ``mu0 w X/s`` it replaces a
    gap-independent edge term (Roters' quarter cylinders).

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    gap_input : str
        Name of the gap input, non-empty.
    width_m : float
        Edge length w [m], > 0.
    coil_from_m : float
        Flank height of the coil's lower end above the face r [m], > 0.
    coil_height_m : float
        Coil height h [m], > 0.
    window_halves_m : tuple of float
        One entry per edge: the distance [m] from the flank to a centre plane at the
        plane's potential, > 0 (``inf``: none).

    Raises
    ------
    ParameterError
        An empty ``gap_input``, ``width_m``, ``coil_from_m`` or ``coil_height_m`` not a
        finite number > 0, no edge, or an edge's entry not a number > 0.
    """

    _label: ClassVar[str] = "edge corner permeance"
    gap_input: str = "s"
    width_m: float = 1.0
    coil_from_m: float = 1.0
    coil_height_m: float = 1.0
    window_halves_m: tuple[float, ...] = (math.inf,)

    def __post_init__(self) -> None:
        owner = self._owner
        self._check_gap_input()
        _positive(owner, width_m=self.width_m, coil_from_m=self.coil_from_m,
                  coil_height_m=self.coil_height_m)
        if not isinstance(self.window_halves_m, tuple) or not self.window_halves_m:
            raise ParameterError(f"{owner}: window_halves_m must be a non-empty tuple (one "
                                 f"entry per edge), got {self.window_halves_m!r}")
        for a in self.window_halves_m:
            if symbolic(a):
                continue
            if not isinstance(a, (int, float)) or isinstance(a, bool) or not a > 0.0:
                raise ParameterError(f"{owner}: window_halves_m entry {a!r} must be a number "
                                     "> 0 [m] (inf: no centre plane)")

    def _permeance(self, gap_m: Any) -> Any:
        """Permeance [H] of the edges' corner flux (see the class docstring)."""
        g: Any = 0.0
        for a in self.window_halves_m:
            g = g + edge_corner_per_mu0(self.width_m, gap_m, self.coil_from_m,
                                        self.coil_height_m, a)
        return MU0 * g


@renamed_keywords(width="width_m", length="length_m")
@dataclass(frozen=True)
class GapLayerPermeance(_GapElement):
    """Air inside the gap layer between two neighbouring cells: ``G = mu0 w s / l``.

    The lateral link of a cell network whose row of cells fills the air gap (height
    ``s``, the gap): flux along the layer, cross-section ``w x s`` (``w`` the depth),
    length ``l`` between the cell centres.  Its permeance grows with the gap, so its
    share of the force ``phi^2/2 dR/ds`` is repulsive: the ``-B_x^2/(2 mu0)`` part of the
    Maxwell stress on the rail.

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    gap_input : str
        Name of the gap input, non-empty.
    width_m : float
        Extent across the flux and the gap [m] (the depth), > 0 (deprecated keyword:
        ``width``).
    length_m : float
        Path length along the layer [m], > 0 (deprecated keyword: ``length``).

    Raises
    ------
    ParameterError
        An empty ``gap_input``, or ``width_m`` or ``length_m`` not a finite number > 0.
    """

    _label: ClassVar[str] = "gap layer permeance"
    gap_input: str = "s"
    width_m: float = 1.0
    length_m: float = 1.0

    def __post_init__(self) -> None:
        owner = self._owner
        self._check_gap_input()
        _positive(owner, width_m=self.width_m, length_m=self.length_m)

    def _permeance(self, gap_m: Any) -> Any:
        """Permeance ``G = mu0 w s / l`` [H]."""
        return MU0 * self.width_m * gap_m / self.length_m


def fringe_per_mu0(w: float, r: float, s: Any) -> Any:
    """Roters' quarter-circle fringe of an edge of length ``w`` and flank height ``r`` to a
    plane at distance ``s``, divided by mu0: ``(2 w/pi) ln(1 + pi r/(2 s))`` [m]."""
    return 2.0 * w / math.pi * _log(1.0 + math.pi * r / (2.0 * s))


def rectangle_torsion_constant(a: float, b: float) -> float:
    """Saint-Venant torsion constant of an a x b rectangle (exact series) [m^4]."""
    a, b = max(a, b), min(a, b)
    series = sum(math.tanh(k * math.pi * a / (2.0 * b)) / k**5 for k in range(1, 200, 2))
    return a * b**3 / 3.0 * (1.0 - 192.0 / math.pi**5 * (b / a) * series)


@renamed_keywords(conductance="conductance_S")
@dataclass(frozen=True)
class EddyCurrent(Element):
    """Eddy currents as a "magnetic inductance": ``V_m = G_ec dphi/dt``.

    Equivalent to a short-circuited winding of conductance ``G_ec`` [S] around the
    flux tube (low-frequency, resistance-limited eddy currents).  It carries no
    static drop; the flux-based dynamic model uses :attr:`eddy_conductance`.

    Parameters
    ----------
    name : str
        Unique name of the element within its network.
    conductance_S : float
        ``G_ec`` [S] (> 0; required, although it has a default for the dataclass;
        deprecated keyword: ``conductance``).

    Raises
    ------
    ParameterError
        ``conductance_S`` not a finite number > 0.
    """

    conductance_S: float = 0.0

    def __post_init__(self) -> None:
        _positive(f"eddy-current element {self.name!r}", conductance_S=self.conductance_S)

    @property
    def eddy_conductance(self) -> float:
        return self.conductance_S

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def mmf_drop(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Static drop: zero (the element acts through :attr:`eddy_conductance` only).

        Parameters
        ----------
        flux_Wb : float, array_like or CasADi
            Branch flux phi [Wb].
        gap_m : optional
            Ignored.

        Returns
        -------
        float, ndarray or CasADi
            ``0 * flux`` [A].
        """
        return 0.0 * flux_Wb

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def energy(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Stored energy: zero (eddy currents dissipate, they store nothing).

        Parameters
        ----------
        flux_Wb : float or array_like
            Branch flux phi [Wb].
        gap_m : optional
            Ignored.

        Returns
        -------
        ndarray
            Zeros [J] of the shape of ``flux_Wb``.
        """
        return np.zeros_like(np.asarray(flux_Wb, dtype=float))

    @classmethod
    @renamed_keywords(path_area="path_area_m2", path_length="path_length_m",
                      resistivity="resistivity_ohm_m")
    def one_turn(cls, name: str, path_area_m2: float, path_length_m: float,
                 resistivity_ohm_m: float) -> EddyCurrent:
        """Modelica's ``G = A / (rho l)``: a one-turn short circuit of wire area A, length l.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        path_area_m2 : float
            Cross-section A of the current path [m^2], > 0.
        path_length_m : float
            Length l of the current path (once around the flux) [m], > 0.
        resistivity_ohm_m : float
            Electrical resistivity rho of the conductor [ohm m], > 0 (deprecated keyword:
            ``resistivity``).

        Returns
        -------
        EddyCurrent

        Raises
        ------
        ParameterError
            A dimension or the resistivity not a finite number > 0.
        """
        _positive(f"eddy-current element {name!r}", path_area_m2=path_area_m2,
                  path_length_m=path_length_m, resistivity_ohm_m=resistivity_ohm_m)
        return cls(name, path_area_m2 / (resistivity_ohm_m * path_length_m))

    @classmethod
    @renamed_keywords(width="width_m", height="height_m", length="length_m",
                      resistivity="resistivity_ohm_m")
    def solid_rectangular(cls, name: str, width_m: float, height_m: float, length_m: float,
                          resistivity_ohm_m: float) -> EddyCurrent:
        """Solid bar of cross-section width x height and length l, flux along l.

        Low-frequency eddy loss under a uniform ``dB/dt`` is ``P = J l (dB/dt)^2/(4 rho)``
        with the Saint-Venant torsion constant J of the cross-section (the stream
        function of the eddy currents solves the same Poisson problem), so
        ``G_ec = P / (dphi/dt)^2 = J l / (4 rho A^2)``.  Thin-sheet limit: ``b^2 l/(12 rho A)``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        width_m, height_m : float
            Sides of the cross-section [m], > 0.
        length_m : float
            Length l of the bar along the flux [m], > 0.
        resistivity_ohm_m : float
            Electrical resistivity rho of the conductor [ohm m], > 0 (deprecated keyword:
            ``resistivity``).

        Returns
        -------
        EddyCurrent

        Raises
        ------
        ParameterError
            A dimension or the resistivity not a finite number > 0.
        """
        _positive(f"eddy-current element {name!r}", width_m=width_m, height_m=height_m,
                  length_m=length_m, resistivity_ohm_m=resistivity_ohm_m)
        area = width_m * height_m
        torsion = rectangle_torsion_constant(width_m, height_m)
        return cls(name, torsion * length_m / (4.0 * resistivity_ohm_m * area * area))

    @classmethod
    @renamed_keywords(area="area_m2", length="length_m", sheet_thickness="sheet_thickness_m",
                      resistivity="resistivity_ohm_m")
    def laminated(cls, name: str, area_m2: float, length_m: float, resistivity_ohm_m: float,
                  sheet_thickness_m: float) -> EddyCurrent:
        """Laminated stack of sheets of thickness d: ``G_ec = d^2 l / (12 rho A)``.

        Parameters
        ----------
        name : str
            Unique name of the element within its network.
        area_m2 : float
            Cross-section A of the stack (across the flux) [m^2], > 0.
        length_m : float
            Length l of the stack along the flux [m], > 0.
        resistivity_ohm_m : float
            Electrical resistivity rho of the sheets [ohm m], > 0 (deprecated keyword:
            ``resistivity``).
        sheet_thickness_m : float
            Sheet thickness d [m], > 0.

        Returns
        -------
        EddyCurrent

        Raises
        ------
        ParameterError
            A dimension or the resistivity not a finite number > 0.
        """
        _positive(f"eddy-current element {name!r}", area_m2=area_m2, length_m=length_m,
                  resistivity_ohm_m=resistivity_ohm_m, sheet_thickness_m=sheet_thickness_m)
        return cls(name, sheet_thickness_m**2 * length_m / (12.0 * resistivity_ohm_m * area_m2))
