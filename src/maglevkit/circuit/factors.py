"""Calibration factors on a network's elements: the one law (issue 25, part 2).

The documented set of uncertain network factors (:data:`PARAMETERS`) and the element
wrappers that apply them, with numbers (a calibrated magnet: the loader applies a
parameter file's ``[calibration]`` table with :func:`with_factors`) or with CasADi symbols
(the exact parameter derivatives of :mod:`maglevkit.calibration`, which fits them).
See docs/magnets.md, "Calibration".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import renamed_keywords
from .elements import (
    AirGap,
    EddyCurrent,
    Element,
    FringePermeance,
    GapLeakage,
    IronPath,
    LeakagePermeance,
    LinearElement,
)
from .network import Network

__all__ = ["PARAMETERS", "DYNAMIC_PARAMETERS", "ParameterSpec", "CalibratedLinear", "CalibratedIron",
           "with_factors", "has_factors"]


@dataclass(frozen=True)
class ParameterSpec:
    """A calibratable parameter.

    Attributes
    ----------
    nominal : float
        The value that leaves the network unchanged [unit].
    lower, upper : float
        Bounds of the fit and of a parameter file's value [unit].
    scale : float
        Typical size, for identifiability (the Jacobian's columns are scaled by it) and
        finite-difference steps [unit].
    unit : str
        ``"1"`` or ``"m"``.
    description : str
        What it does.
    """

    nominal: float
    lower: float
    upper: float
    scale: float
    unit: str
    description: str


PARAMETERS: dict[str, ParameterSpec] = {
    "leakage_factor": ParameterSpec(1.0, 0.2, 5.0, 1.0, "1", "scales every leakage permeance"),
    "fringing_factor": ParameterSpec(1.0, 0.0, 5.0, 1.0, "1",
                                     "scales the air gaps' fringing permeance"),
    "gap_offset_m": ParameterSpec(0.0, -2e-3, 2e-3, 1e-3, "m", "added to every gap"),
    "iron_field_scale": ParameterSpec(1.0, 0.1, 10.0, 1.0, "1",
                                      "scales H(B) of the iron (permeability / k)"),
    "iron_saturation_scale": ParameterSpec(1.0, 0.5, 1.5, 0.1, "1",
                                           "scales the B axis of the iron's B-H curve"),
    "eddy_conductance_scale": ParameterSpec(1.0, 0.05, 20.0, 1.0, "1",
                                            "scales every eddy conductance G_ec (dynamics "
                                            "only)"),
    "resistance_scale": ParameterSpec(1.0, 0.5, 2.0, 0.1, "1",
                                      "scales every circuit's R_el (dynamics only)"),
}
"""The documented parameter set (docs/magnets.md, "Calibration")."""

DYNAMIC_PARAMETERS = ("eddy_conductance_scale", "resistance_scale")
"""Parameters that do not enter the statics (static data cannot determine them): with
numbers :func:`with_factors` scales the eddy elements' conductances and the circuits'
``R_el``; with CasADi symbols they enter the flux DAE's rows
(:class:`~maglevkit.reduction.maps.StepRun`, ``eddy_scale``/``resistance_scale``)."""


@dataclass(frozen=True)
class CalibratedLinear(LinearElement):
    """A linear element with calibration factors (numbers or CasADi symbols).

    ``G = k_leak G_inner(s + delta)`` for leakage, ``k_fringe G_inner(s + delta)`` for
    fringe elements, and for an air gap ``G_inner(s + delta) + (k_fringe - 1) G_fringe``.

    Attributes
    ----------
    inner : LinearElement
        The wrapped element.
    leakage : float or casadi.SX
        ``leakage_factor`` [1].
    fringing : float or casadi.SX
        ``fringing_factor`` [1].
    offset : float or casadi.SX
        ``gap_offset_m`` [m].
    """

    inner: LinearElement = field(default=None)  # type: ignore[assignment]
    leakage: Any = 1.0
    fringing: Any = 1.0
    offset: Any = 0.0

    @property
    def gap(self) -> str | None:
        return self.inner.gap

    @property
    def area(self) -> float | None:
        return self.inner.area

    @renamed_keywords(gap="gap_m")
    def permeance(self, gap_m: Any = None) -> Any:
        """Permeance [Wb/A] at the gap ``gap_m`` [m] (before the offset)."""
        el = self.inner
        g = None if gap_m is None or el.gap is None else gap_m + self.offset
        base = el.permeance(g)
        if isinstance(el, (LeakagePermeance, GapLeakage)):
            return self.leakage * base
        if isinstance(el, FringePermeance):
            return self.fringing * base
        if isinstance(el, AirGap) and el.fringe_edges:
            return base + (self.fringing - 1.0) * el.fringe_permeance(g)
        return base


@dataclass(frozen=True)
class CalibratedIron(Element):
    """An iron path with calibration factors: ``V_m = k_H l H(phi/(A k_B))``.

    Attributes
    ----------
    inner : IronPath
        The wrapped iron path.
    field_scale : float or casadi.SX
        ``iron_field_scale`` ``k_H`` [1].
    saturation_scale : float or casadi.SX
        ``iron_saturation_scale`` ``k_B`` [1].
    """

    inner: IronPath = field(default=None)  # type: ignore[assignment]
    field_scale: Any = 1.0
    saturation_scale: Any = 1.0

    @property
    def area(self) -> float | None:
        return self.inner.area

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def mmf_drop(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Magnetic voltage [A] at the branch flux ``flux_Wb`` [Wb] (``gap_m`` unused)."""
        return self.field_scale * self.inner.mmf_drop(flux_Wb / self.saturation_scale)

    @renamed_keywords(flux="flux_Wb", gap="gap_m")
    def energy(self, flux_Wb: Any, gap_m: Any = None) -> Any:
        """Stored energy [J] at the flux ``flux_Wb`` [Wb] (``gap_m`` unused)."""
        # int_0^phi k_H V(phi'/k_B) dphi' = k_H k_B W_inner(phi/k_B)
        return (self.field_scale * self.saturation_scale
                * self.inner.energy(np.asarray(flux_Wb, dtype=float) / self.saturation_scale))

    def linearized(self) -> CalibratedIron:
        """The same factors on the iron's initial permeability (``saturation=False``)."""
        return replace(self, inner=replace(self.inner,
                                           material=self.inner.material.linearized()))


def has_factors(network: Network) -> bool:
    """Whether ``network`` already carries calibration factors.

    Parameters
    ----------
    network : Network
        The network to inspect.
    """
    return any(isinstance(e, (CalibratedLinear, CalibratedIron))
               for b in network.branches for e in b.elements)


def with_factors(network: Network, values: Mapping[str, Any], *, where: str = "") -> Network:
    """``network`` with the calibration factors ``values`` applied to its elements.

    Parameters
    ----------
    network : Network
        An uncalibrated network (factors do not compose: a network that already carries
        them is refused).
    values : mapping
        Parameter names of :data:`PARAMETERS` to numbers (unit of the parameter: ``1`` or
        ``m``) or CasADi symbols; missing ones stay nominal.  With nominal values the
        statics equal the original's bit for bit.  :data:`DYNAMIC_PARAMETERS` given as
        numbers scale the eddy elements' ``G_ec`` and the circuits' ``R_el``; as CasADi
        symbols they are left out here (they do not enter the statics; the step DAE takes
        them, :class:`~maglevkit.reduction.maps.StepRun`).
    where : str
        Prefix of error messages (e.g. the file's ``[calibration]`` table).

    Raises
    ------
    InputError
        An unknown name, or a network that already carries factors.
    """
    prefix = f"{where}: " if where else ""
    unknown = sorted(set(values) - set(PARAMETERS))
    if unknown:
        raise InputError(f"{prefix}unknown calibration parameter(s) {unknown}; the "
                         f"documented set: {list(PARAMETERS)}")
    if has_factors(network):
        raise InputError(f"{prefix}the network {network.name!r} already carries calibration "
                         "factors (a calibrated magnet); they do not compose: calibrate the "
                         "magnet without its [calibration] table")
    v = {k: values.get(k, spec.nominal) for k, spec in PARAMETERS.items()}
    k_eddy, k_res = v["eddy_conductance_scale"], v["resistance_scale"]
    numeric_eddy = isinstance(k_eddy, (int, float)) and k_eddy != 1.0
    numeric_res = isinstance(k_res, (int, float)) and k_res != 1.0

    def wrap(el: Element) -> Element:
        if isinstance(el, LinearElement):
            return CalibratedLinear(el.name, inner=el, leakage=v["leakage_factor"],
                                    fringing=v["fringing_factor"], offset=v["gap_offset_m"])
        if isinstance(el, IronPath):
            return CalibratedIron(el.name, inner=el, field_scale=v["iron_field_scale"],
                                  saturation_scale=v["iron_saturation_scale"])
        if isinstance(el, EddyCurrent) and numeric_eddy:
            return replace(el, conductance_S=float(k_eddy) * el.conductance_S)
        return el

    branches = tuple(replace(b, elements=tuple(wrap(e) for e in b.elements))
                     for b in network.branches)
    circuits = (tuple(replace(c, resistance_ohm=float(k_res) * c.resistance_ohm)
                      for c in network.circuits) if numeric_res else network.circuits)
    return Network(branches, circuits, name=network.name)
